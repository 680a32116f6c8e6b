//! The verified lower bound of the `conv(SO(3))`-strengthened SDP (`paper-notes/anisotropic.md`
//! `[A6]`): from any multipliers `Lambda_i` and `Z_e`, recomputed independently of the solver.
//!
//! For `X` PSD with `X_ii = I` and `A(X_ij)` PSD, and `Z_e` PSD:
//! `tr(Q X) >= sum tr(Lambda_i) - sum tr(Z_e) + tr(S X)` with
//! `S = Q - blkdiag(Lambda) - sum_e E_e(Z_e)` (`E_e` holds `G(Z_e) / 2` in block `(i, j)` and its
//! transpose in `(j, i)`, [`crate::relax::conv_so3::conv_adjoint`]), and `tr(S X) >= 3n
//! min(lambda_min(S), 0)`. Each `Z_e` is first made PSD by a verified diagonal shift; `S` is
//! dense (small graphs) and its smallest eigenvalue is taken with a backward-error margin.

use super::multipliers::{check_lambdas, data_defect, forming_margin, symmetrize};
use super::state::{Best, State};
use crate::certify::certification::ImprovementSource;
use crate::certify::log::{Point, Prediction, Refusal};
use crate::certify::proof::{BoundMethod, Proof};
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifyMode;
use crate::error::{Error, Result};
use crate::linalg::{UNIT_ROUNDOFF, gamma};
use crate::multiple::MultipleProblem;
use crate::multiple::laplacian::connection_laplacian;
use crate::relax::conv_so3::{ConvRelaxation, conv_adjoint};
use nalgebra::{DMatrix, Matrix4};
use serde::{Deserialize, Serialize};

/// A verified lower bound of the `conv(SO(3))` relaxation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ConvBound {
    /// The proven lower bound on the minimum of the chordal cost over `SO(3)^n`.
    pub lower_bound: f64,
    /// The proven `mu <= lambda_min(S)` (computed eigenvalue minus its margin).
    pub verified_min_eigenvalue: f64,
    /// The largest diagonal shift that made a `Z_e` PSD (0 when all were).
    pub largest_z_shift: f64,
}

/// Verify the multipliers of [`crate::relax::conv_so3::relax_multiple_conv`] (or any others
/// with the same shapes): the proven lower bound. Errors: multipliers of the wrong count or not
/// finite, or a pair that is not an edge's.
///
/// ```
/// use rotavg::certify::multiple::conv_bound;
/// use rotavg::relax::{SdpSettings, conv_so3::relax_multiple_conv};
/// use rotavg::multiple::synthetic::SyntheticAnisotropic;
/// let (p, truth) = SyntheticAnisotropic { num_rotations: 6, num_edges: 12, ..Default::default() }.generate();
/// let r = relax_multiple_conv(&p, &SdpSettings::default())?;
/// let b = conv_bound(&p, &r)?;
/// assert!(b.lower_bound <= p.chordal_cost(&truth));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn conv_bound(problem: &MultipleProblem, relaxation: &ConvRelaxation) -> Result<ConvBound> {
    let lambdas = &relaxation.multipliers;
    check_lambdas(problem, lambdas)?;
    let n = problem.num_rotations();
    let dim = 3 * n;
    let q = connection_laplacian(problem).to_dense();
    let mut s = DMatrix::<f64>::from_fn(dim, dim, |r, c| q[(r, c)]);
    for (i, l) in lambdas.iter().enumerate() {
        let l = symmetrize(l);
        for a in 0..3 {
            for b in 0..3 {
                s[(3 * i + a, 3 * i + b)] -= l[(a, b)];
            }
        }
    }
    let conv = subtract_conv_multipliers(problem, relaxation, &mut s)?;
    // margins: the eigensolver's backward error, forming S from the data (the anisotropic
    // blocks [A3], the sums of the isotropic ones, the multipliers and the E_e)
    let degree = max_degree(problem);
    let s_norm = s.norm();
    let l_norm: f64 = lambdas.iter().map(|l| l.norm()).sum();
    let forming = forming_margin(problem, lambdas)
        + 2.0 * gamma(degree + 16) * (q.norm_l2() + l_norm + conv.e_norm);
    let margin = 10.0 * dim as f64 * UNIT_ROUNDOFF * s_norm + forming;
    let computed = s.symmetric_eigenvalues().min();
    let mu = computed - margin;
    let trace: f64 = lambdas.iter().map(|l| l.trace()).sum();
    let abs_trace: f64 = lambdas
        .iter()
        .map(|l| l[(0, 0)].abs() + l[(1, 1)].abs() + l[(2, 2)].abs())
        .sum();
    let deficit = dim as f64 * (-mu).max(0.0);
    let terms = dim + 4 * relaxation.conv_multipliers.len() + 4;
    let lower_bound = trace
        - conv.trace
        - deficit
        - 2.0 * gamma(terms) * (abs_trace + conv.abs_trace + deficit)
        - data_defect(problem);
    Ok(ConvBound {
        lower_bound,
        verified_min_eigenvalue: mu,
        largest_z_shift: conv.largest_shift,
    })
}

/// What the `Z_e` (made PSD) put into the bound: `sum tr(Z_e)` and `sum |tr(Z_e)|`, the sum of
/// the Frobenius norms of the `E_e(Z_e)`, and the largest PSD shift.
struct ConvTerms {
    trace: f64,
    abs_trace: f64,
    e_norm: f64,
    largest_shift: f64,
}

/// Subtract every `E_e(Z_e)` from `s`, each `Z_e` first made PSD by a diagonal shift. Errors: a
/// multiplier that is not finite or not an edge's.
fn subtract_conv_multipliers(
    problem: &MultipleProblem,
    relaxation: &ConvRelaxation,
    s: &mut DMatrix<f64>,
) -> Result<ConvTerms> {
    let mut terms = ConvTerms {
        trace: 0.0,
        abs_trace: 0.0,
        e_norm: 0.0,
        largest_shift: 0.0f64,
    };
    for &(i, j, z) in &relaxation.conv_multipliers {
        let is_edge = problem
            .edges()
            .iter()
            .any(|e| (e.i, e.j) == (i, j) || (e.j, e.i) == (i, j));
        if !is_edge || !z.iter().all(|x| x.is_finite()) {
            return Err(Error::InvalidSettings {
                name: "conv_multipliers".into(),
                reason: format!("the multiplier of pair ({i}, {j}) is not finite or not an edge's"),
            });
        }
        // Z made PSD: eigenvalues are computed to within 16 u ||Z||_F of the exact ones
        let zs = (z + z.transpose()) * 0.5;
        let lo = zs.symmetric_eigenvalues().min();
        let shift = (-lo).max(0.0) + 16.0 * UNIT_ROUNDOFF * zs.norm();
        terms.largest_shift = terms.largest_shift.max(shift);
        let zp: Matrix4<f64> = zs + Matrix4::identity() * shift;
        terms.trace += zp.trace();
        terms.abs_trace += zp.trace().abs();
        let g = conv_adjoint(&zp) * 0.5;
        terms.e_norm += 2.0 * g.norm();
        for a in 0..3 {
            for b in 0..3 {
                s[(3 * i + a, 3 * j + b)] -= g[(a, b)];
                s[(3 * j + b, 3 * i + a)] -= g[(a, b)];
            }
        }
    }
    Ok(terms)
}

/// The largest number of edges at a node.
fn max_degree(problem: &MultipleProblem) -> usize {
    (0..problem.num_rotations())
        .map(|v| {
            problem
                .edges()
                .iter()
                .filter(|e| e.i == v || e.j == v)
                .count()
        })
        .max()
        .unwrap_or(0)
}

/// Certify `rotations` against the `conv(SO(3))` relaxation (graphs of at most
/// [`crate::relax::conv_so3::CONV_MAX_NODES`] nodes): the SDP of `settings.sdp` solved by
/// Clarabel, its multipliers verified by [`conv_bound`], the verdict under the tolerance of
/// contract section 3 (method `sdp`). Errors as [`crate::relax::conv_so3::relax_multiple_conv`]
/// and [`conv_bound`], or an estimate of the wrong size.
///
/// ```
/// use rotavg::certify::{CertifySettings, Verdict, multiple::certify_conv};
/// use rotavg::multiple::{Edge, MultipleProblem, anisotropic::Information};
/// use nalgebra::{Matrix3, Vector3};
/// // the O(3) relaxation cannot certify this exact answer (its bound is -8); conv(SO(3)) can
/// let edge = Edge { i: 0, j: 1, rotation: rotavg::Rotation::identity(), weight: 1.0 };
/// let h = Information::new(Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 4.0)))?;
/// let p = MultipleProblem::new(2, vec![edge])?.with_information(vec![h])?;
/// let c = certify_conv(&p, &[rotavg::Rotation::identity(); 2], &CertifySettings::default())?;
/// assert!(c.lower_bound.unwrap() > -1e-5);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn certify_conv(
    problem: &MultipleProblem,
    rotations: &[crate::so3::Rotation],
    settings: &crate::certify::settings::CertifySettings,
) -> Result<crate::certify::certificate::Certificate> {
    let start = std::time::Instant::now();
    settings.validate()?;
    super::multipliers::check_rotations(problem, rotations)?;
    let relaxation = crate::relax::conv_so3::relax_multiple_conv(problem, &settings.sdp)?;
    let bound = conv_bound(problem, &relaxation)?;
    let tolerance = settings.tolerance.resolve(problem.min_weight());
    Ok(crate::certify::certificate::Certificate::from_bounds(
        problem.chordal_cost(rotations),
        Some(bound.lower_bound),
        BoundMethod::Sdp,
        Some(bound.verified_min_eigenvalue),
        tolerance,
        format!(
            "bound from the conv(SO(3)) relaxation's multipliers (Clarabel {:?}, {} iterations), \
             verified independently: lambda_min(S) >= {:.3e}, largest shift of a Z_e {:.1e} \
             [A6]",
            relaxation.status,
            relaxation.iterations,
            bound.verified_min_eigenvalue,
            bound.largest_z_shift
        ),
        start.elapsed().as_secs_f64(),
    ))
}

/// The `conv(SO(3))` SDP `[A6]` as a rung of a certification (modes `auto` and `sdp`): for
/// anisotropic problems of at most [`crate::relax::conv_so3::CONV_MAX_NODES`] nodes, once,
/// after the dual certificates (the `O(3)` relaxation can prefer reflections, `[A5]`); solved
/// within the time left, its multipliers verified by [`conv_bound`].
#[derive(Default)]
pub(crate) struct ConvSdpRung {
    done: bool,
}

impl<'a> Rung<State<'a>> for ConvSdpRung {
    fn proof(&self) -> Proof {
        Proof::ConvSdp
    }

    fn plan(&mut self, cx: &State<'a>) -> Result<Plan> {
        let n = cx.problem.num_rotations();
        if self.done
            || !cx.problem.is_anisotropic()
            || n > crate::relax::conv_so3::CONV_MAX_NODES
            || !matches!(cx.settings.mode, CertifyMode::Auto | CertifyMode::Sdp)
        {
            return Ok(Plan::Done);
        }
        Ok(match cx.escalation() {
            Err(reason) => Plan::Refuse(Refusal::NotApplicable { reason }, None),
            Ok(false) => Plan::Wait,
            Ok(true) => {
                let p = crate::relax::conv_so3::predict_relax_multiple_conv(cx.problem);
                Plan::Run(Prediction::new(p.seconds, p.bytes))
            }
        })
    }

    fn attempt(&mut self, cx: &mut State<'a>) -> Result<Found> {
        self.done = true;
        let Some(sdp) = cx.settings.sdp_until(&cx.deadline, 0.0) else {
            return Ok(Found::refused(Refusal::OverBudget {
                reason: "the time budget is spent".into(),
            }));
        };
        let relaxation = crate::relax::conv_so3::relax_multiple_conv(cx.problem, &sdp)?;
        let bound = conv_bound(cx.problem, &relaxation)?;
        let note = format!(
            "bound from the conv(SO(3)) relaxation's multipliers [A6] (Clarabel {:?}, {} \
             iterations), verified independently: lambda_min(S) >= {:.3e}",
            relaxation.status, relaxation.iterations, bound.verified_min_eigenvalue
        );
        // the rounding, polished while time is left, is the answer when it beats the estimate
        // (the bound holds without it)
        if !cx.deadline.passed()
            && let Some(p) = super::staircase::polish(cx.problem, &relaxation.rounded, &cx.deadline)
            && p.chordal_cost < cx.current.cost
        {
            cx.adopt(p, ImprovementSource::ConvSdpRounding, Point::ConvSdp);
        }
        cx.offer(Best {
            lower_bound: bound.lower_bound,
            method: BoundMethod::Sdp,
            point: Point::ConvSdp,
            min_eigenvalue: Some(bound.verified_min_eigenvalue),
            explanation: note.clone(),
            verified_min_eigenvalue: bound.verified_min_eigenvalue,
            shift: None,
            lambdas: None,
        });
        Ok(Found::proved(
            bound.lower_bound,
            cx.certifies(bound.lower_bound),
            note,
        ))
    }
}
