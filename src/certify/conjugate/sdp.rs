//! The verified lower bound of conjugate averaging from the multipliers of its SDP relaxation
//! `[H8]` (contract section 3, `paper-notes/conjugate.md`), and the SDP as a rung of a conjugate
//! certification (`SdpRung`).

use crate::certify::certification::{ImprovementSource, SdpSummary};
use crate::certify::log::{Prediction, Refusal};
use crate::certify::one_rotation::{Bound, RotationState};
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifyMode;
use crate::certify::spectrum::{SpectrumEstimate, SpectrumMethod};
use crate::conjugate::{ConjugateProblem, ConjugateSettings, ConjugateSolution, solve_conjugate};
use crate::error::Result;
use crate::relax::conjugate::{
    Mat9, Mat10, QcqpConstraint, constraint_matrices, cost_matrix_with_error, extract_rotation,
    lift,
};
use crate::relax::{ConjugateRelaxation, relax_conjugate};
use crate::so3::Rotation;
use nalgebra::{DMatrix, DVector, SymmetricEigen};
use serde::{Deserialize, Serialize};

/// A lower bound on `min_{S in SO(3)} g(S)` verified from multipliers `[H8]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ConjugateBound {
    /// The bound `sum_k nu_k b_k + 4 min(lambda_min, 0) - margin`.
    pub lower_bound: f64,
    /// `lambda_min(C(nu))` from nalgebra's dense symmetric eigen-decomposition.
    pub min_eigenvalue: f64,
    /// The floating-point safety margin subtracted.
    pub margin: f64,
    /// Proven lower bound on `lambda_min` of the exact `C(nu)`: `min_eigenvalue` minus the
    /// eigenvalue part `100 eps ||(|M| + sum |nu_k| |A_k|)||_F` of `margin`.
    pub verified_min_eigenvalue: f64,
    /// All 10 eigenvalues of `C(nu)`, ascending (dense, as computed: estimates).
    pub eigenvalues: [f64; 10],
    /// Residuals `||C x - lambda x||` of the computed eigenpairs, same order.
    pub eigen_residuals: [f64; 10],
}

/// The certificate matrix `C(nu) = blkdiag(M, 0) - sum_k nu_k A_k` `[H8]`.
pub fn certificate_matrix(m: &Mat9, constraints: &[QcqpConstraint], nu: &[f64]) -> Mat10 {
    let mut c = Mat10::zeros();
    c.fixed_view_mut::<9, 9>(0, 0).copy_from(m);
    for (con, &n) in constraints.iter().zip(nu) {
        c -= con.matrix * n;
    }
    c
}

/// Verify a lower bound from any multipliers `nu` `[H8]`: for every feasible `z = [vec S; 1]`
/// (`S` in SO(3)), `g(S) = z^T C(nu) z + sum_k nu_k b_k >= sum_k nu_k b_k + lambda_min ||z||^2`
/// and `||z||^2 = ||S||_F^2 + 1 = 4`. `lambda_min` comes from nalgebra's dense eigen solver
/// (independent of Clarabel); the margin `4 * 100 eps ||(|M| + sum |nu_k| |A_k|)||_F` covers
/// rounding in forming `C(nu)` and in the eigenvalues. Returns `None` for non-finite input.
pub fn verify_lower_bound(
    m: &Mat9,
    constraints: &[QcqpConstraint],
    nu: &[f64],
) -> Option<ConjugateBound> {
    if nu.len() != constraints.len() || !nu.iter().all(|x| x.is_finite()) {
        return None;
    }
    let c = certificate_matrix(m, constraints, nu);
    let mut mag = Mat10::zeros();
    mag.fixed_view_mut::<9, 9>(0, 0).copy_from(&m.abs());
    for (con, &n) in constraints.iter().zip(nu) {
        mag += con.matrix.abs() * n.abs();
    }
    let eig = SymmetricEigen::new(c);
    let lam = eig.eigenvalues.min();
    let mut order: Vec<usize> = (0..10).collect();
    order.sort_by(|&p, &q| eig.eigenvalues[p].total_cmp(&eig.eigenvalues[q]));
    let mut eigenvalues = [0.0; 10];
    let mut eigen_residuals = [0.0; 10];
    for (slot, &i) in order.iter().enumerate() {
        let x = eig.eigenvectors.column(i);
        eigenvalues[slot] = eig.eigenvalues[i];
        eigen_residuals[slot] = (c * x - x * eig.eigenvalues[i]).norm();
    }
    let dual: f64 = constraints.iter().zip(nu).map(|(k, n)| k.rhs * n).sum();
    let eigen_margin = 100.0 * f64::EPSILON * mag.norm();
    let margin = 4.0 * eigen_margin + 4.0 * f64::EPSILON * dual.abs();
    let lb = dual + 4.0 * lam.min(0.0) - margin;
    lb.is_finite().then_some(ConjugateBound {
        lower_bound: lb,
        min_eigenvalue: lam,
        margin,
        verified_min_eigenvalue: lam - eigen_margin,
        eigenvalues,
        eigen_residuals,
    })
}

/// Refine multipliers so that `z* = [vec S*; 1]` is an exact null vector of `C(nu)`: the
/// least-norm correction `nu + pinv(A(z*)) (C(nu) z*)` with `A(z*) = [A_1 z*, ..., A_K z*]`
/// `[H8]`. Then `sum nu_k b_k = g(S*)`, so the bound is `g(S*) + 4 lambda_min`: tight up to the
/// solver's PSD accuracy. Any multipliers give a valid bound, so this cannot make it unsound.
pub fn refine_multipliers(
    m: &Mat9,
    constraints: &[QcqpConstraint],
    nu: &[f64],
    s: &Rotation,
) -> Option<Vec<f64>> {
    let z = lift(s.matrix(), 1.0);
    let c = certificate_matrix(m, constraints, nu);
    let resid = c * z;
    let k = constraints.len();
    let a = DMatrix::from_fn(10, k, |i, j| (constraints[j].matrix * z)[i]);
    let rhs = DVector::from_column_slice(resid.as_slice());
    let delta = a.svd(true, true).solve(&rhs, 1e-12).ok()?;
    let out: Vec<f64> = nu.iter().zip(delta.iter()).map(|(n, d)| n + d).collect();
    out.iter().all(|x| x.is_finite()).then_some(out)
}

/// Seconds predicted for the 10 x 10 SDP of a conjugate problem (a few milliseconds measured)
/// and per pair (forming `M`, the multipliers' refinement).
pub const SDP_SECONDS: f64 = 0.02;

/// See [`SDP_SECONDS`].
pub const SDP_SECONDS_PER_PAIR: f64 = 1e-6;

/// The SDP relaxation `[H3]` as a rung of a conjugate certification (chordal L2; modes `auto`
/// and `sdp`), once: lower bounds verified from Clarabel's multipliers and from the multipliers
/// refined at the estimate and at the polished extraction `[H8]` (each a bound on the global
/// minimum; the largest is kept); the rank-one extraction polished by the local solver is an
/// improvement when cheaper.
pub(crate) struct SdpRung<'p> {
    problem: &'p ConjugateProblem,
    done: bool,
}

impl<'p> SdpRung<'p> {
    /// The rung for `problem`.
    pub fn new(problem: &'p ConjugateProblem) -> Self {
        SdpRung {
            problem,
            done: false,
        }
    }
}

impl<'a> Rung<RotationState<'a, ConjugateSolution>> for SdpRung<'_> {
    fn proof(&self) -> Proof {
        Proof::Sdp
    }

    fn plan(&mut self, cx: &RotationState<'a, ConjugateSolution>) -> Result<Plan> {
        let objective = self.problem.objective();
        if self.done || !matches!(cx.settings.mode, CertifyMode::Auto | CertifyMode::Sdp) {
            return Ok(Plan::Done);
        }
        if !objective.is_chordal_l2() {
            let reason = format!("the SDP relaxation bounds the chordal L2 cost, not {objective}");
            let refusal = Refusal::NotApplicable { reason };
            return Ok(Plan::Refuse(refusal, None));
        }
        let seconds = SDP_SECONDS + SDP_SECONDS_PER_PAIR * self.problem.num_pairs() as f64;
        Ok(Plan::Run(Prediction::new(seconds, 0.0)))
    }

    fn attempt(&mut self, cx: &mut RotationState<'a, ConjugateSolution>) -> Result<Found> {
        self.done = true;
        let problem = self.problem;
        crate::progress::phase(crate::progress::Phase::Sdp, || {
            format!("10 x 10 relaxation of {} pairs", problem.num_pairs())
        });
        let Some(sdp) = cx.settings.sdp_until(&cx.deadline, 0.0) else {
            return Ok(Found::refused(Refusal::OverBudget {
                reason: "the time budget is spent".into(),
            }));
        };
        let relax = relax_conjugate(problem, &sdp)?;
        // the extraction polished by the chordal local solver: a candidate better estimate
        let rounded = extract_rotation(&relax.z);
        let polished = rounded.and_then(|s0| {
            let local = ConjugateSettings {
                init: Some(s0),
                ..Default::default()
            };
            solve_conjugate(problem, &local).ok()
        });
        let bound = sdp_bound(problem, &relax, &cx.estimate, polished.as_ref());
        cx.sdp = Some(SdpSummary {
            status: relax.status,
            iterations: relax.iterations,
            seconds: relax.seconds,
            eigenvalue_ratio: relax.eigenvalue_ratio,
            rounded_cost: rounded.map(|r| problem.chordal_cost(&r)),
            polished_cost: polished.as_ref().map(|p| p.cost),
        });
        if let Some(p) = polished {
            let cost = p.cost;
            cx.improve(p, cost, ImprovementSource::SdpRounding);
        }
        let note = format!(
            "Clarabel SDP ({:?}, {} iterations, {:.3} s); multipliers verified by a dense \
             eigenvalue check",
            relax.status, relax.iterations, relax.seconds
        );
        Ok(match bound {
            Some(b) => {
                let lb = cx.offer(Bound {
                    lower_bound: b.lower_bound,
                    proof: Proof::Sdp,
                    explanation: explain(Some(&b), &relax),
                    min_eigenvalue: Some(b.min_eigenvalue),
                    verified_min_eigenvalue: Some(b.verified_min_eigenvalue),
                    spectrum: Some(spectrum(&b)),
                });
                Found::proved(lb, cx.certifies(lb), note)
            }
            None => Found::failed(format!("{note}; {}", explain(None, &relax))),
        })
    }
}

/// The best verified bound from Clarabel's multipliers and from those refined at `s` and at
/// the polished extraction `[H8]`, lowered by the forming error of `M` (`n` terms).
fn sdp_bound(
    problem: &ConjugateProblem,
    relax: &ConjugateRelaxation,
    s: &Rotation,
    polished: Option<&ConjugateSolution>,
) -> Option<ConjugateBound> {
    let (m, forming_error) = cost_matrix_with_error(problem);
    let cons = constraint_matrices();
    let mut bound = verify_lower_bound(&m, &cons, &relax.multipliers);
    let mut at = vec![*s];
    at.extend(polished.map(|p| p.estimate));
    for point in &at {
        if let Some(nu) = refine_multipliers(&m, &cons, &relax.multipliers, point)
            && let Some(b) = verify_lower_bound(&m, &cons, &nu)
            && bound.is_none_or(|x| b.lower_bound > x.lower_bound)
        {
            bound = Some(b);
        }
    }
    bound.map(|mut b| {
        b.lower_bound -= 4.0 * forming_error;
        b.margin += 4.0 * forming_error;
        b
    })
}

fn explain(bound: Option<&ConjugateBound>, relax: &ConjugateRelaxation) -> String {
    match bound {
        Some(b) => format!(
            "lower bound from Clarabel's multipliers ({:?}, {} iterations), verified with a dense eigenvalue check (lambda_min of the certificate matrix {:.3e}); Z eigenvalue ratio {:.1e}",
            relax.status, relax.iterations, b.min_eigenvalue, relax.eigenvalue_ratio
        ),
        None => "no usable multipliers from the SDP".into(),
    }
}

/// The 10 (dense, exact up to rounding) eigenvalues of the certificate matrix `C(nu)` of the
/// bound `[H8]`, `[D14]` (free: the verification computed them).
fn spectrum(b: &ConjugateBound) -> SpectrumEstimate {
    SpectrumEstimate {
        values: b.eigenvalues.to_vec(),
        residuals: b.eigen_residuals.to_vec(),
        method: SpectrumMethod::Dense,
        shift: None,
        stop: None,
        subspace_dim: 10,
        seconds: 0.0,
    }
}
