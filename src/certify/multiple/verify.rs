//! Verifying a lower bound from multipliers `Lambda`: the climb of the checks that
//! `S = Q - blkdiag(Lambda)` is (nearly) positive semidefinite (`paper-notes/certificates.md`
//! `[D4]`-`[D8]`, `[D12]`, `[D13]`, `[D15]`, `[D16]`), on the one ladder
//! ([`crate::certify::ladder`]).
//!
//! The checks are the grounded bound `[D15]` ([`super::grounded`]), the shifted Cholesky
//! factorisation of `S` `[D5]` (`shifted.rs`), the scalar comparison `[D13]` on the whole
//! graph, a subgraph or a split (`scalar/rungs.rs`), and, as fallbacks when none of them
//! proves anything, Gershgorin's discs `[D8]` (`gershgorin.rs`: claimed only when no check was
//! kept out by the budget) and the randomized test `[D16]` ([`super::randomized`]: a labelled
//! estimate beside an `inconclusive` verdict, when a check was kept out by the budget). The
//! first bound that leaves at least half of the tolerance for the rest of the gap ends the
//! climb.

use super::block::rungs::BlockFamily;
use super::check::{Check, CurvatureHint, Scope, first_shift};
use super::gershgorin::GershgorinCheck;
use super::grounded::GroundedProof;
use super::multipliers::FirstOrder;
use super::randomized::RandomizedCheck;
use super::scalar::rungs::ScalarFamily;
use super::shifted::ShiftedProof;
use super::verified::VerifiedBound;
use crate::certify::budget::Deadline;
use crate::certify::ladder::{Rungs, climb};
use crate::certify::log::Point;
use crate::certify::proof::Proof;
use crate::certify::settings::CertifySettings;
use crate::error::Result;
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use nalgebra::Matrix3;

/// A verified lower bound on the global minimum of the chordal cost from *any* multipliers
/// `Lambda` (symmetrised) `[D4]`: `sum tr(Lambda_i) + 3n min(mu, 0)`, where `mu` is a
/// verified lower bound on `lambda_min(Q - blkdiag(Lambda))` (sparse Cholesky `[D5]` with
/// the floating-point margin `[D6]`; Gershgorin `[D8]` as the fallback). Use this to verify
/// an SDP solver's multipliers: never its reported objective.
///
/// ```
/// use rotavg::certify::multiple::lower_bound_from_multipliers;
/// use rotavg::certify::CertifySettings;
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// use nalgebra::Matrix3;
/// let (p, _) = SyntheticGraph { num_rotations: 6, num_edges: 10, noise_sigma: 0.1, ..Default::default() }.generate();
/// // Lambda = 0 is dual feasible (Q is PSD): the bound is ~0 (below every cost).
/// let b = lower_bound_from_multipliers(&p, &vec![Matrix3::zeros(); 6], &CertifySettings::default()).unwrap();
/// assert!(b.lower_bound <= 0.0 && b.lower_bound > -1e-6);
/// ```
pub fn lower_bound_from_multipliers(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    settings: &CertifySettings,
) -> Result<VerifiedBound> {
    settings.validate()?;
    let scope = Scope {
        point: Point::Sdp,
        within: Proof::Sdp,
        deadline: Deadline::start(&settings.budget),
        refinement_follows: None,
    };
    multipliers_bound(problem, lambdas, settings, scope, None)
}

/// [`lower_bound_from_multipliers`] in `scope` and, when known, with an estimate of
/// `lambda_min(S)` for the shifts.
pub(crate) fn multipliers_bound(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    settings: &CertifySettings,
    scope: Scope,
    hint: Option<CurvatureHint>,
) -> Result<VerifiedBound> {
    let trace: f64 = lambdas.iter().map(|l| l.trace()).sum();
    verify(problem, lambdas, None, trace.abs(), settings, scope, hint)
}

/// Climb the checks for `lambdas` (and the estimate `rotations` they belong to, when known):
/// `scale` is the cost whose tolerance is the gap budget.
pub(crate) fn verify(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    rotations: Option<&[Rotation]>,
    scale: f64,
    settings: &CertifySettings,
    scope: Scope,
    hint: Option<CurvatureHint>,
) -> Result<VerifiedBound> {
    let mut cx = Check::new(problem, lambdas, rotations, scale, settings, scope)?;
    cx.hint = hint;
    climb_checks(cx)
}

/// [`verify`] of an estimate's own multipliers, with its first-order quantities `first`
/// (made once: the checks read its gauge terms).
pub(crate) fn verify_own(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    first: &FirstOrder,
    scale: f64,
    settings: &CertifySettings,
    scope: Scope,
) -> Result<VerifiedBound> {
    let mut cx = Check::new(
        problem,
        &first.lambdas,
        Some(rotations),
        scale,
        settings,
        scope,
    )?;
    cx.first = Some(first);
    climb_checks(cx)
}

/// The climb of the checks on `cx`, and its bound.
fn climb_checks(mut cx: Check<'_>) -> Result<VerifiedBound> {
    let settings = cx.settings;
    let mut rungs: Rungs<'_, Check<'_>> = Vec::new();
    // the block comparison is planned first: the `3n` rungs may wait for it
    // (`Check::three_n_waits`; it is done at once on isotropic problems); the order decides
    // only exact ties of time and strength
    let block_first = |p: &&Proof| matches!(p, Proof::BlockComparison);
    let (block, others): (Vec<&Proof>, Vec<&Proof>) =
        settings.dual.proofs.iter().partition(block_first);
    for proof in block.into_iter().chain(others) {
        match proof {
            Proof::Grounded => rungs.push(Box::new(GroundedProof::default())),
            Proof::ShiftedCholesky => rungs.push(Box::new(ShiftedProof::default())),
            Proof::ScalarComparison => rungs.push(Box::new(ScalarFamily::default())),
            Proof::BlockComparison => rungs.push(Box::new(BlockFamily::default())),
            _ => {}
        }
    }
    rungs.push(Box::new(GershgorinCheck::default()));
    rungs.push(Box::new(RandomizedCheck::default()));
    climb(&mut cx, rungs)?;
    Ok(finish(cx))
}

/// The verified bound (the best check's, or the fallback's) with the estimates of the climb
/// and its log.
fn finish(mut cx: Check<'_>) -> VerifiedBound {
    let mut bound = match cx.best.take().or_else(|| cx.unclaimed.take()) {
        Some(b) => b,
        // no check ran at all (every one disabled): Gershgorin's, unclaimed
        None => GershgorinCheck::unclaimed(&cx),
    };
    let first = first_shift(&cx);
    let notes = cx.take_notes();
    if let Some(e) = notes.estimate {
        if bound.min_eigenvalue_estimate.is_none() {
            bound.min_eigenvalue_estimate = Some(e.value);
            bound.estimate_residual = Some(e.residual);
        }
        bound.negative_eigenvector =
            (e.value < 0.0 && e.value < -first && !e.vector.is_empty()).then_some(e.vector);
    }
    bound.lanczos_iterations += notes.lanczos_iterations;
    bound.factorizations = bound.factorizations.max(notes.factorizations);
    bound.not_critical |= notes.not_critical;
    bound.ladder = cx.take_log();
    bound
}
