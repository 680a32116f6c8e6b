//! Robust averaging of anisotropic measurements with gravity priors, in two stages
//! (`paper-notes/gravity.md` `[G8]`, `[A14]` with the priors): a confidently wrong pair carries
//! large information, and the Cauchy factor of its Mahalanobis angle times its `tr(H) / 3` lets
//! it lead the reweighted solve. So the robust solve with the priors runs first with unit
//! weights and no information (every pair's pull bounded alike); the edges whose Mahalanobis
//! angle at that estimate exceeds the inlier threshold are set aside, and the reweighted solve
//! with the information of the others starts from it.

use super::GravityProblem;
use crate::error::Result;
use crate::multiple::problem::MultipleProblem;
use crate::multiple::robust::inlier_threshold_deg;
use crate::multiple::solve::{Initialisation, L1_START_DECREASE_TOLERANCE, MultipleSettings};
use crate::so3::Rotation;

/// The first stage's estimate (the file's convention), its iterations and the edges set aside,
/// or `None` where the two stages do not apply: scalar weights, a least-squares loss, a given
/// start (as `[A14]`, which starts from a given estimate in one stage).
pub(super) struct FirstStage {
    pub rotations: Vec<Rotation>,
    pub iterations: usize,
    pub aside: Vec<bool>,
}

/// Stage 1 of the robust solve of `problem` with its priors (`[G8]`): the same loss and priors
/// on the same edges with unit weights and no information (soft priors keep their weight
/// relative to a median edge: divided by the median `tr(H) / 3`), then the edges whose
/// Mahalanobis angle at that estimate exceeds the inlier threshold.
pub(super) fn first_stage(
    problem: &GravityProblem,
    settings: &MultipleSettings,
) -> Result<Option<FirstStage>> {
    let graph = problem.problem();
    let threshold = inlier_threshold_deg(&graph.objective(), settings);
    let (Some(threshold), Some(median)) = (threshold, median_information_weight(graph)) else {
        return Ok(None);
    };
    if matches!(settings.init, Initialisation::Given(_)) {
        return Ok(None);
    }
    let unit = crate::multiple::two_stage::unit_weights(graph)?;
    let priors = problem.priors().clone();
    let priors = match priors.weight() {
        Some(w) => priors.with_weight(w / median)?,
        None => priors,
    };
    // a start: its passes also stop at the L1 start's relative decrease (`[M9]`); waiting for
    // the weights to settle took 71 passes (23 s) on a 10^4-image scene at a 1.6-degree scale
    let start = MultipleSettings {
        irls_decrease_tolerance: settings
            .irls_decrease_tolerance
            .max(L1_START_DECREASE_TOLERANCE),
        ..settings.clone()
    };
    let first = super::solve_gravity(&GravityProblem::new(unit, priors)?, &start)?;
    let aside = (graph.objective_angles(&first.rotations).iter())
        .map(|t| t.to_degrees() > threshold)
        .collect();
    Ok(Some(FirstStage {
        rotations: first.rotations,
        iterations: first.report.iterations,
        aside,
    }))
}

/// The median of `tr(H) / 3` over the edges' information (a positive one: the weight of a
/// typical edge); `None` for scalar weights.
fn median_information_weight(graph: &MultipleProblem) -> Option<f64> {
    let mut w: Vec<f64> = (graph.information()?.iter())
        .map(|h| h.matrix().trace() / 3.0)
        .filter(|w| *w > 0.0)
        .collect();
    w.sort_by(f64::total_cmp);
    w.get(w.len() / 2).copied()
}
