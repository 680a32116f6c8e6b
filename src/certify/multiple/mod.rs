//! Certificates of chordal L2 multiple rotation averaging (SPEC section 3,
//! `paper-notes/certificates.md`, `[D3]`-`[D14]`).
//!
//! - [`certify_multiple`]: the whole method for an estimate: the dual certificate `[D3]`-`[D9]`
//!   (at the estimate, or at its refinement when the estimate is not an accurate critical
//!   point), then, when that fails and the mode allows, the SDP relaxation (multipliers verified
//!   `[D4]`, rounding polished) or the Riemannian staircase `[D11]`. The largest verified bound
//!   wins `[D12]`.
//! - [`dual`]: the dual certificate of an estimate and why it has its verdict.
//! - [`mod@multipliers`]: `Q Y`, the multipliers, `S`, the residuals and the bound's rounding
//!   (the numbers every certificate is made of, in double-double where they cancel).
//! - [`verify`]: the ladder of proofs that `S` is (nearly) positive semidefinite
//!   ([`crate::certify::ladder`]): [`grounded`] `[D15]`, the shifted Cholesky of `S` `[D5]`,
//!   [`scalar`] `[D13]` (one factorisation of an `n x n` scalar matrix, a subgraph's, or a
//!   split's), Gershgorin `[D8]`; [`randomized`] `[D16]` (a Monte Carlo bound reported beside an
//!   `inconclusive` verdict when no deterministic proof fits the budget).
//! - [`staircase`]: the Riemannian staircase (rank-lifted Burer-Monteiro descent).

mod climb;
pub mod conv;
pub mod conv_dual;
pub mod dual;
pub mod grounded;
pub mod multipliers;
pub mod randomized;
pub mod scalar;
mod shifted;
pub mod staircase;
pub mod verify;

pub use conv::{ConvBound, certify_conv, conv_bound};
pub use dual::{DualCertificate, DualDiagnosis, certify_with_multipliers, dual_certificate};
pub use grounded::GroundedBound;
pub use multipliers::{certificate_matrix, laplacian_times, multipliers, stationarity_residual};
pub use randomized::{ComplementEstimate, RandomizedBound};
pub use verify::{Verification, VerifiedBound, lower_bound_from_multipliers};

use super::certificate::{BoundMethod, Certificate};
use super::certification::{Certification, CertifyDetails};
use super::settings::{CertifyMode, CertifySettings};
use crate::error::Result;
use crate::multiple::{MultipleProblem, MultipleSolution};
use crate::so3::Rotation;
use climb::Climb;
pub use climb::REFINE_FACTOR;
use multipliers::check_rotations;
use std::time::Instant;

/// The given estimate is not refined (nor its refinement certified) when its certificate
/// matrix's negative eigenvalue estimate is at least this many times its stationarity residual
/// (both in units of the edge weights): refining moves the point, and `S`, by about the
/// residual. On a 10^4-node graph with 20 % outliers (`lambda_min ~ -1.6`, residual 1.4e-4)
/// the refinement's certificate took 15 s and found the same.
pub const REFINE_INDEFINITE_RATIO: f64 = 1e3;

const MARGIN_LIMITED: &str = "SDP / staircase skipped: the estimate is a critical point whose \
certificate matrix is PSD up to the floating-point precision of the verification; the gap is that \
precision, which other multipliers cannot improve (mode sdp or staircase runs them anyway)";

/// Certify an estimate of chordal L2 multiple rotation averaging **without changing it** (modes
/// `auto`, `dual`, `sdp`, `staircase`). Upper bound: its chordal cost. Lower bound: the largest
/// verified bound among
///
/// 1. the dual certificate `[D3]`-`[D9]`, `[D15]` at the estimate, and, when that does not
///    certify, at its refinement by the local solver (when a cheap test shows that the
///    estimate is not a critical point, its own multipliers are not verified: the refined
///    point's bound holds for it too);
/// 2. when that does not certify and the mode allows: the Riemannian staircase `[D11]`
///    (`auto`, `staircase`) and the SDP's verified multipliers (always in `sdp`; in `auto` only
///    when the staircase stopped short of a verified point, `n <= sdp_max_nodes` and it fits
///    the budget).
///
/// Each is a bound on the global minimum whatever point produced it. A refined point or a
/// polished SDP rounding of lower cost than the estimate is returned as the
/// [`Certification::improvement`] (the pipeline [`crate::pipeline::average_multiple`] adopts
/// it). The gap tolerance follows `settings.tolerance` with the smallest edge weight (`[D12]`).
/// Every rung tried at every point is listed in [`CertifyDetails::ladder`].
/// Objectives other than chordal L2 get an `inconclusive` certificate.
///
/// ```
/// use rotavg::certify::{certify_multiple, CertifySettings};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, gt) = SyntheticGraph { num_rotations: 20, num_edges: 40, noise_sigma: 0.0, ..Default::default() }.generate();
/// let c = certify_multiple(&p, &gt, &CertifySettings::default())?;
/// assert!(c.certificate.is_certified());
/// assert!(c.improvement.is_none()); // the ground truth of noise-free data is optimal
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn certify_multiple(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
) -> Result<Certification<MultipleSolution>> {
    let start = Instant::now();
    settings.validate()?;
    settings.mode.require(
        "multiple",
        &[
            CertifyMode::Auto,
            CertifyMode::Dual,
            CertifyMode::Sdp,
            CertifyMode::Staircase,
        ],
    )?;
    check_rotations(problem, rotations)?;
    if !problem.objective().is_chordal_l2() {
        return Ok(no_bound(problem, rotations, settings, start));
    }
    let mut climb = Climb::new(
        problem,
        rotations,
        problem.chordal_cost(rotations),
        settings,
        start,
    );
    // anisotropic data with an indefinite M on some edge, whose O(3) relaxation can prefer
    // reflections [A5]: the conv(SO(3)) dual certificate at the given estimate first [A11]
    // (a no-op on other data)
    climb.conv_dual()?;
    let (first, last) = if climb.best_certifies() {
        // the O(3) dual certificate of the given estimate is not needed (nor run): its
        // diagnosis is the conv(SO(3)) certificate's
        let certified = climb::DualRun {
            diagnosis: DualDiagnosis::Certified,
            randomized: None,
        };
        (DualDiagnosis::Certified, certified)
    } else {
        let steps = dual_steps(&mut climb)?;
        // then at the refined point (a no-op when the point did not move)
        climb.conv_dual()?;
        steps
    };
    let escalate = match &last.diagnosis {
        _ if climb.best_certifies() => false,
        DualDiagnosis::Certified => {
            if matches!(settings.mode, CertifyMode::Sdp | CertifyMode::Staircase) {
                climb.details.skipped_reason = Some(format!(
                    "{} not run: the dual certificate at {} already certified it",
                    settings.mode, climb.current.label
                ));
            }
            false
        }
        DualDiagnosis::PrecisionLimited { .. }
            if !matches!(settings.mode, CertifyMode::Sdp | CertifyMode::Staircase) =>
        {
            climb.details.skipped_reason = Some(MARGIN_LIMITED.into());
            false
        }
        DualDiagnosis::OverBudget { .. } => false,
        _ => !climb.over_time("SDP / staircase"),
    };
    if escalate {
        match climb.wants_sdp() {
            Some(true) if settings.mode == CertifyMode::Auto => climb.staircase_then_sdp()?,
            Some(true) => climb.sdp()?,
            Some(false) => {
                climb.staircase()?;
            }
            None if settings.mode == CertifyMode::Auto => {
                climb.details.skipped_reason = Some(format!(
                    "SDP not run: {} nodes > sdp_max_nodes {}",
                    problem.num_rotations(),
                    settings.sdp_max_nodes
                ));
            }
            None => {}
        }
        // a better point found on the way (staircase or SDP rounding): its conv(SO(3)) dual
        // certificate [A11]
        climb.conv_dual()?;
        // anisotropic data: where the O(3) relaxation leaves a gap (reflections, [A5]), the
        // conv(SO(3)) relaxation of small graphs [A6]
        if matches!(settings.mode, CertifyMode::Auto | CertifyMode::Sdp) {
            climb.conv_sdp()?;
        }
    }
    let certificate = climb.certificate(&first, Some(&last));
    climb.details.seconds = start.elapsed().as_secs_f64();
    let improvement = climb.improvement();
    Ok(Certification {
        certificate,
        details: climb.details,
        improvement,
    })
}

/// The dual certificates: at the given estimate (unless it is cheaply shown not to be a critical
/// point), then, when that does not certify (and precision or the budget is not what limits
/// it), at its refinement. Returns the given estimate's diagnosis and the last run.
fn dual_steps(climb: &mut Climb<'_>) -> Result<(DualDiagnosis, climb::DualRun)> {
    let first = climb.given()?;
    let settled = first.as_ref().is_some_and(|r| {
        matches!(
            r.diagnosis,
            DualDiagnosis::Certified
                | DualDiagnosis::PrecisionLimited { .. }
                | DualDiagnosis::OverBudget { .. }
        )
    });
    let mut last = first.clone();
    // a critical point whose S is clearly indefinite stays so when refined: the staircase (or
    // the SDP) is what can help, not a second dual certificate at nearly the same point
    let hopeless_to_refine = first.as_ref().is_some_and(|r| {
        matches!(r.diagnosis, DualDiagnosis::Indefinite { min_eigenvalue }
            if -min_eigenvalue >= REFINE_INDEFINITE_RATIO
                * climb.details.given_stationarity_residual.unwrap_or(f64::INFINITY))
    });
    if !settled && !hopeless_to_refine && !climb.over_time("refinement") && climb.refine() {
        last = Some(climb.dual()?);
    }
    let last = match last {
        Some(l) => l,
        // not a critical point, and the refinement found nothing cheaper: its own ladder after all
        None => climb.dual()?,
    };
    let given = match first {
        Some(r) => r.diagnosis,
        None => DualDiagnosis::NotCritical {
            residual: climb
                .details
                .given_stationarity_residual
                .unwrap_or(f64::NAN),
        },
    };
    Ok((given, last))
}

/// Objectives other than chordal L2: no lower bound, and why.
fn no_bound(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
    start: Instant,
) -> Certification<MultipleSolution> {
    let objective = problem.objective();
    let why =
        format!("no lower bound for the {objective} cost: the certificates bound chordal L2 only");
    let seconds = start.elapsed().as_secs_f64();
    let details = CertifyDetails {
        mode: settings.mode,
        skipped_reason: Some(why.clone()),
        seconds,
        ..Default::default()
    };
    let certificate = Certificate::from_bounds(
        problem.cost(rotations),
        None,
        BoundMethod::Dual,
        None,
        settings.tolerance.resolve(problem.min_weight()),
        why,
        seconds,
    );
    Certification {
        certificate,
        details,
        improvement: None,
    }
}
