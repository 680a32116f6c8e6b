//! The verified lower bound of conjugate averaging from the multipliers of its SDP relaxation
//! `[H8]`, and [`certify_conjugate`] (SPEC section 3, `paper-notes/conjugate.md`).

use super::branch_and_bound;
use super::branch_and_bound::terms::ConjugateTerms;
use super::certificate::{BoundMethod, Certificate};
use super::certification::{
    Certification, CertifyDetails, Improvement, ImprovementSource, MethodRun, SdpSummary,
};
use super::settings::{CertifyMode, CertifySettings};
use super::spectrum::{SpectrumEstimate, SpectrumMethod};
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
use std::time::Instant;

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

/// Certify a rotation `s` (never changed) for conjugate averaging. For the chordal L2 objective
/// (modes `auto` and `sdp`): solve the SDP relaxation `[H3]`, verify lower bounds from Clarabel's
/// multipliers and from the multipliers refined at `s` and at the polished extraction `[H8]`
/// (each is a bound on the global minimum; the largest is kept), and polish the rank-one
/// extraction with the local solver: when that has a lower cost than `s` it is returned as the
/// [`Certification::improvement`]. In mode `auto`, when the SDP does not certify, and for every
/// other objective, the branch and bound over SO(3) `[B1]`-`[B6]` bounds the global minimum
/// (mode `branch_and_bound`: only it); a better solution it finds is the improvement. Mode
/// `sdp` with another objective than chordal L2 gives an `inconclusive` certificate.
///
/// ```
/// use rotavg::certify::{certify_conjugate, CertifySettings};
/// use rotavg::conjugate::ConjugateProblem;
/// use rotavg::so3::exp;
/// use nalgebra::Vector3;
/// let s = exp(&Vector3::new(0.4, -0.1, 0.7));
/// let rs = [exp(&Vector3::new(0.5, 0.0, 0.1)), exp(&Vector3::new(0.0, 0.8, -0.3))];
/// let ls: Vec<_> = rs.iter().map(|r| s * r * s.inverse()).collect();
/// let p = ConjugateProblem::from_rotations(&ls, &rs)?;
/// let c = certify_conjugate(&p, &s, &CertifySettings::default())?;
/// assert!(c.certificate.is_certified());
/// assert!(c.improvement.is_none());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn certify_conjugate(
    problem: &ConjugateProblem,
    s: &Rotation,
    settings: &CertifySettings,
) -> Result<Certification<ConjugateSolution>> {
    settings.check_one_rotation("conjugate", CertifyMode::Sdp, s)?;
    let start = Instant::now();
    let objective = problem.objective();
    let cost = problem.cost(s);
    let mut details = CertifyDetails {
        mode: settings.mode,
        ..Default::default()
    };
    let tolerance = settings.tolerance.resolve(problem.min_weight());
    let small = problem.num_pairs() <= settings.branch_and_bound.auto_max_terms;
    if settings.mode == CertifyMode::BranchAndBound
        || (settings.mode == CertifyMode::Auto && !objective.is_chordal_l2() && small)
    {
        return Ok(with_branch_and_bound(
            problem, s, cost, settings, None, details, start,
        ));
    }
    if !objective.is_chordal_l2() {
        details.skipped_reason = Some(if small {
            format!(
                "no lower bound for the {objective} cost: the SDP relaxation bounds chordal L2 only"
            )
        } else {
            format!(
                "no lower bound for the {objective} cost: the SDP relaxation bounds chordal L2 only, and {} pairs > branch_and_bound.auto_max_terms = {} (use mode branch_and_bound)",
                problem.num_pairs(),
                settings.branch_and_bound.auto_max_terms
            )
        });
        details.seconds = start.elapsed().as_secs_f64();
        let certificate = Certificate::from_bounds(
            cost,
            None,
            BoundMethod::Sdp,
            None,
            tolerance,
            format!(
                "no lower bound: the SDP relaxation bounds the chordal L2 cost, not {objective}"
            ),
            details.seconds,
        );
        return Ok(Certification {
            certificate,
            details,
            improvement: None,
        });
    }
    crate::progress::phase(crate::progress::Phase::Sdp, || {
        format!("10 x 10 relaxation of {} pairs", problem.num_pairs())
    });
    let relax = relax_conjugate(problem, &settings.sdp)?;
    // The extraction polished by the chordal local solver: a candidate better estimate.
    let rounded = extract_rotation(&relax.z);
    let polished = rounded.and_then(|s0| {
        let local = ConjugateSettings {
            init: Some(s0),
            ..Default::default()
        };
        solve_conjugate(problem, &local).ok()
    });
    // the bound is verified on the computed M; lowered below by its forming error (n terms)
    let (m, forming_error) = cost_matrix_with_error(problem);
    let cons = constraint_matrices();
    let mut bound = verify_lower_bound(&m, &cons, &relax.multipliers);
    let mut at = vec![*s];
    at.extend(polished.as_ref().map(|p| p.estimate));
    for point in &at {
        if let Some(nu) = refine_multipliers(&m, &cons, &relax.multipliers, point)
            && let Some(b) = verify_lower_bound(&m, &cons, &nu)
            && bound.is_none_or(|x| b.lower_bound > x.lower_bound)
        {
            bound = Some(b);
        }
    }
    let bound = bound.map(|mut b| {
        b.lower_bound -= 4.0 * forming_error;
        b.margin += 4.0 * forming_error;
        b
    });
    let lam = bound.map(|b| b.min_eigenvalue);
    let seconds = start.elapsed().as_secs_f64();
    let mut certificate = Certificate::from_bounds(
        cost,
        bound.map(|b| b.lower_bound),
        BoundMethod::Sdp,
        lam,
        settings.tolerance.resolve(problem.min_weight()),
        explain(bound.as_ref(), &relax),
        seconds,
    );
    attach_spectrum(&mut certificate, bound.as_ref());
    let run = MethodRun {
        method: BoundMethod::Sdp,
        lower_bound: bound.map(|b| b.lower_bound),
        seconds,
        note: format!(
            "Clarabel SDP ({:?}, {} iterations, {:.3} s); multipliers verified by a dense \
             eigenvalue check",
            relax.status, relax.iterations, relax.seconds
        ),
    };
    details.record(run, certificate.is_certified());
    details.sdp = Some(SdpSummary {
        status: relax.status,
        iterations: relax.iterations,
        seconds: relax.seconds,
        eigenvalue_ratio: relax.eigenvalue_ratio,
        rounded_cost: rounded.map(|r| problem.chordal_cost(&r)),
        polished_cost: polished.as_ref().map(|p| p.cost),
    });
    details.seconds = seconds;
    // An improvement must be better beyond rounding (a tie is no improvement).
    let improvement = polished.filter(|p| cost - p.cost > 1e-12 * cost.abs().max(1e-300));
    details.improvement = improvement.as_ref().map(|p| Improvement {
        source: ImprovementSource::SdpRounding,
        cost: p.cost,
    });
    if settings.mode == CertifyMode::Auto && !certificate.is_certified() && small {
        // The SDP bound was not tight enough (or its rounding beat the estimate): the branch
        // and bound decides, starting from the SDP's bound.
        let prior = Some((certificate, improvement));
        return Ok(with_branch_and_bound(
            problem, s, cost, settings, prior, details, start,
        ));
    }
    Ok(Certification {
        certificate,
        details,
        improvement,
    })
}

/// The branch and bound `[B1]`-`[B6]` for `s` (cost `cost`), after an SDP certificate `prior`
/// (whose bound and improvement are kept when better).
fn with_branch_and_bound(
    problem: &ConjugateProblem,
    s: &Rotation,
    cost: f64,
    settings: &CertifySettings,
    prior: Option<(Certificate, Option<ConjugateSolution>)>,
    mut details: CertifyDetails,
    start: Instant,
) -> Certification<ConjugateSolution> {
    crate::progress::phase(crate::progress::Phase::Certify, || {
        format!("branch and bound over SO(3), {} pairs", problem.num_pairs())
    });
    let (run, lb) = branch_and_bound::run(
        &ConjugateTerms::new(problem),
        s,
        cost,
        problem.min_weight(),
        settings,
        start,
        &mut details,
    );
    let seconds = start.elapsed().as_secs_f64();
    details.seconds = seconds;
    let (prior_cert, prior_improvement) = match prior {
        Some((c, i)) => (Some(c), i),
        None => (None, None),
    };
    let mut certificate = match prior_cert {
        Some(c) if c.lower_bound.is_some_and(|p| p >= lb) => c,
        _ => Certificate::from_bounds(
            cost,
            Some(lb),
            BoundMethod::BranchAndBound,
            None,
            settings.tolerance.resolve(problem.min_weight()),
            run.explanation,
            seconds,
        ),
    };
    certificate.seconds = seconds;
    certificate.branch_and_bound = Some(run.stats);
    // The better of the two improvements.
    let improvement = match (prior_improvement, run.improvement) {
        (Some(a), Some((b, c))) => {
            if c < a.cost {
                details.improvement = Some(Improvement {
                    source: ImprovementSource::BranchAndBound,
                    cost: c,
                });
                Some(b)
            } else {
                Some(a)
            }
        }
        (Some(a), None) => Some(a),
        (None, Some((b, c))) => {
            details.improvement = Some(Improvement {
                source: ImprovementSource::BranchAndBound,
                cost: c,
            });
            Some(b)
        }
        (None, None) => None,
    };
    Certification {
        certificate,
        details,
        improvement,
    }
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

/// The verified `lambda_min` bound and the 10 (dense, exact up to rounding) eigenvalues of the
/// certificate matrix `C(nu)` of the bound `[H8]`, `[D14]` (free: the verification computed them).
fn attach_spectrum(certificate: &mut Certificate, bound: Option<&ConjugateBound>) {
    if let Some(b) = bound {
        certificate.verified_min_eigenvalue = Some(b.verified_min_eigenvalue);
        certificate.smallest_eigenvalues = Some(SpectrumEstimate {
            values: b.eigenvalues.to_vec(),
            residuals: b.eigen_residuals.to_vec(),
            method: SpectrumMethod::Dense,
            shift: None,
            stop: None,
            subspace_dim: 10,
            seconds: 0.0,
        });
    }
}
