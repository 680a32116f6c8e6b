//! Certificates of chordal L2 multiple rotation averaging (contract section 3,
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
//!   split's), [`block`] `[A15]` (its anisotropic form: a subgraph's `3n` block Laplacian),
//!   Gershgorin `[D8]`; [`randomized`] `[D16]` (a Monte Carlo bound reported beside an
//!   `inconclusive` verdict when no deterministic proof fits the budget).
//! - [`staircase`]: the Riemannian staircase (rank-lifted Burer-Monteiro descent).

pub mod block;
mod block_operator;
mod check;
mod coarse;
pub mod conv;
pub mod conv_dual;
mod conv_frames;
mod conv_offset;
mod conv_shifts;
mod deflated;
pub mod diagnosis;
pub mod dual;
mod gershgorin;
pub mod grounded;
pub mod multipliers;
pub mod randomized;
pub mod scalar;
pub mod scalar_weights;
mod sdp;
mod shifted;
pub mod staircase;
mod state;
mod verdict;
pub mod verified;
pub mod verify;

pub use conv::{ConvBound, certify_conv, conv_bound};
pub use diagnosis::DualDiagnosis;
pub use dual::{DualCertificate, REFINE_FACTOR, certify_with_multipliers, dual_certificate};
pub use multipliers::{certificate_matrix, laplacian_times, multipliers, stationarity_residual};
pub use state::REFINE_INDEFINITE_RATIO;
pub use verified::{ComplementEstimate, GroundedBound, RandomizedBound, VerifiedBound};
pub use verify::lower_bound_from_multipliers;

use crate::certify::budget::Deadline;
use crate::certify::certificate::Certificate;
use crate::certify::certification::{Certification, CertifyDetails};
use crate::certify::ladder::{Rungs, climb};
use crate::certify::proof::BoundMethod;
use crate::certify::settings::{CertifyMode, CertifySettings};
use crate::error::Result;
use crate::multiple::{MultipleProblem, MultipleSolution};
use crate::so3::Rotation;
use multipliers::check_rotations;
use state::State;

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
    let deadline = Deadline::start(&settings.budget);
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
        return Ok(no_bound(problem, rotations, settings, deadline));
    }
    let cost = problem.chordal_cost(rotations);
    let mut state = State::new(problem, rotations, cost, settings, deadline);
    climb(&mut state, rungs(settings.mode))?;
    let certificate = verdict::certificate(&mut state);
    let improvement = verdict::improvement(&mut state);
    let mut details = CertifyDetails::from_log(settings.mode, state.log, deadline.elapsed());
    details.stationarity_residual = state.stationarity_residual;
    details.given_stationarity_residual = state.given_stationarity_residual;
    details.sdp = state.sdp;
    details.staircase_steps = state.staircase_steps;
    details.refine_seconds = state.refine_seconds;
    details.improvement = improvement.as_ref().map(|(_, i)| *i);
    Ok(Certification {
        certificate,
        details,
        improvement: improvement.map(|(s, _)| s),
    })
}

/// The rungs of a certification in `mode`: the dual certificate (at the given estimate, its
/// refinement, every better point) and the `conv(SO(3))` dual certificate always; the
/// staircase in `auto` and `staircase` (in `sdp` in the place of an SDP refused over the
/// budget); the SDP and the `conv(SO(3))` SDP in `auto` and `sdp`.
fn rungs<'a>(mode: CertifyMode) -> Rungs<'a, State<'a>> {
    let mut rungs: Rungs<'a, State<'a>> = vec![
        Box::new(dual::DualRung),
        Box::new(conv_dual::ConvDualRung::default()),
        Box::new(scalar_weights::ScalarWeightsRung::default()),
    ];
    if matches!(
        mode,
        CertifyMode::Auto | CertifyMode::Staircase | CertifyMode::Sdp
    ) {
        rungs.push(Box::new(staircase::StaircaseRung::default()));
    }
    if matches!(mode, CertifyMode::Auto | CertifyMode::Sdp) {
        rungs.push(Box::new(sdp::SdpRung::default()));
        rungs.push(Box::new(conv::ConvSdpRung::default()));
    }
    rungs
}

/// Objectives other than chordal L2: no lower bound, and why.
fn no_bound(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
    deadline: Deadline,
) -> Certification<MultipleSolution> {
    let objective = problem.objective();
    let why =
        format!("no lower bound for the {objective} cost: the certificates bound chordal L2 only");
    let seconds = deadline.elapsed();
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

/// [`certify_multiple`]'s certificate alone: the view graph's certification that the gravity
/// and rig rungs are handed ([`crate::certify::rung::GraphCertifier`]).
pub(crate) fn graph_certificate(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
) -> Result<crate::certify::certificate::Certificate> {
    Ok(certify_multiple(problem, rotations, settings)?.certificate)
}
