//! The hub comparison (`paper-notes/gravity.md` `[G13]`, [`super::hub`]) as a shape of the
//! scalar comparison's rung: offered on anisotropic problems of hub shape (soft gravity priors'
//! world node and an isotropic view graph), predicted from its two scalar factors.

use super::hub::HubGraph;
use super::{SECONDS_PER_EDGE, failure_text, proved_bound};
use crate::certify::log::{Outcome, Prediction, Refusal};
use crate::certify::multiple::check::{Check, counted_prediction};
use crate::certify::multiple::verified::VerifiedBound;
use crate::certify::proof::Proof;
use crate::error::Result;
use crate::so3::Rotation;
use std::time::Instant;

/// What the hub comparison is called in the log.
const SHAPE: &str = "view graph and hub (two scalar factors)";

/// A hub shape's plan: the shape analysed (`None` when its factors are over the budget) and
/// its prediction or refusal.
pub(super) type HubPlan = (Option<HubGraph>, std::result::Result<Prediction, Refusal>);

/// The hub shape of the check's problem and its prediction; `None` when it has none.
pub(super) fn plan_hub(cx: &Check<'_>) -> Result<Option<HubPlan>> {
    let max_values = cx.max_factor_values();
    Ok(match HubGraph::new(cx.problem, max_values)? {
        None => None,
        Some(Err(predicted)) => Some((
            None,
            Err(Refusal::OverBudget {
                reason: format!("the ordering predicts {predicted:.1e} factor values"),
            }),
        )),
        Some(Ok(hub)) => {
            let predicted = predict(cx, &hub);
            Some((Some(hub), predicted))
        }
    })
}

/// Both factors' prediction, as the scalar comparison's.
fn predict(cx: &Check<'_>, hub: &HubGraph) -> std::result::Result<Prediction, Refusal> {
    let [a, b] = hub.analyses();
    let scratch = a.scratch_bytes().max(b.scratch_bytes()).div_ceil(8);
    let largest = a.factor_len().max(b.factor_len()).saturating_add(scratch);
    let total = (a.factor_len() + b.factor_len()).saturating_add(2 * scratch);
    let other = SECONDS_PER_EDGE * (a.num_edges() + b.num_edges()) as f64;
    let multiply_adds = a.factor_multiply_adds() + b.factor_multiply_adds();
    counted_prediction(cx.settings, largest, total, multiply_adds, largest, other)
}

/// Run the hub comparison: a bound when it proves `lambda_min(S) >= -target`; logged either
/// way.
pub(super) fn run_hub(
    cx: &Check<'_>,
    hub: &HubGraph,
    rotations: &[Rotation],
    target: f64,
) -> Option<VerifiedBound> {
    let since = Instant::now();
    let predicted = predict(cx, hub).ok();
    cx.notes().factorizations += 2;
    let proof = match hub.compare(cx.problem, rotations, cx.lambdas, target) {
        Ok(p) if p.verified_min_eigenvalue >= -target => p,
        other => {
            let mu = other.map(|p| p.verified_min_eigenvalue);
            let reason = format!("{SHAPE}: {}", failure_text(target, mu, 1));
            let failed = Outcome::Failed { reason };
            cx.log(Proof::ScalarComparison, predicted, failed, since);
            return None;
        }
    };
    Some(proved_bound(cx, proof, predicted, since, SHAPE.into()))
}
