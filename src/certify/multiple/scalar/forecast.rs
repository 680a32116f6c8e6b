//! The scalar comparison's chance of proving, forecast before its factorisation (issue 35: on a
//! 10^5-node SLAM grid it was predicted cheapest, failed in 0.35 s with 13 negative pivots, and
//! the grounded bound then proved in 0.70 s).
//!
//! The comparison `[D13]` needs `L' - diag(w)` (the kept weights' Laplacian less the charges)
//! to have at most one negative eigenvalue. With the second-order charges of small residuals,
//! an edge of residual angle `theta` keeps `w (cos theta - 1/2)` and charges `w sin^2 theta` to
//! each end (the charges' other terms only add). When the quadratic form of that matrix is
//! negative definite on the plane of the constant vector and a smooth one (the breadth-first
//! distance from a peripheral node, centred), the matrix has two negative eigenvalues
//! (Courant-Fischer) and the comparison fails. The model is the comparison's (first-order
//! charges for outliers aside): a forecast that orders the ladder, never part of a proof.

use super::ScalarFailure;
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;

/// The chance of proving given to a comparison forecast to fail (the rungs forecast to work
/// run first; it still runs when they do not prove).
pub(crate) const FORECAST_FAILURE_SUCCESS: f64 = 0.05;

/// Whether the comparison at `rotations` is forecast to fail (see the module documentation):
/// `O(n + m)`, two breadth-first searches and one pass over the edges.
pub(crate) fn forecast_fails(problem: &MultipleProblem, rotations: &[Rotation]) -> bool {
    let n = problem.num_rotations();
    if n < 3 || rotations.len() != n {
        return false;
    }
    let adjacency = problem.adjacency();
    let far = adjacency.breadth_first(0).last;
    let depth = adjacency.breadth_first(far).depth;
    // hop counts from a peripheral node (unreached nodes at 0), centred
    let mut x: Vec<f64> = depth
        .iter()
        .map(|&d| if d == usize::MAX { 0.0 } else { d as f64 })
        .collect();
    let mean = x.iter().sum::<f64>() / n as f64;
    x.iter_mut().for_each(|v| *v -= mean);
    // a = 1^T M 1, b = 1^T M x, c = x^T M x for M = L' - diag(charges)
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for (e, theta) in problem
        .edges()
        .iter()
        .zip(problem.residual_angles(rotations))
    {
        let cos = theta.cos();
        let charge = e.weight * theta.sin().powi(2);
        let kept = e.weight * (cos - 0.5);
        let (xi, xj) = (x[e.i], x[e.j]);
        a -= 2.0 * charge;
        b -= charge * (xi + xj);
        c += kept * (xi - xj) * (xi - xj) - charge * (xi * xi + xj * xj);
    }
    a < 0.0 && c < 0.0 && a * c > b * b
}

/// The mean charge ratio (see [`sparsest_regions_forecast`]) above which the sparsest subgraph
/// in regions is forecast to fail. Measured (2026-12-05/06, `gen_graph.py expander` graphs of
/// 3x10^4 to 10^5 nodes, 3 and 10 edges per node, 0.02 to 0.1 rad; `docs/benchmarks.md` "A
/// forecast for the sparsest regions"): every such subgraph that proved had a mean of 0.0066 or
/// less, every one from 0.0169 failed.
pub(super) const SPARSEST_FAILING_RATIO: f64 = 0.03;

/// Negative pivots per node forecast per unit of the mean charge ratio: measured 0.53-0.63
/// where the mean was 0.066 or more (0.15-0.33 below, where the rule does not apply); taken
/// high, since a count too low jumps to a subgraph that fails again and one too high to a
/// denser one that proves.
const PIVOTS_PER_RATIO: f64 = 0.6;

/// The failure forecast for the sparsest subgraph in regions from its charges, before its
/// factorisation: `reduced` each edge's kept weight (0 for a dropped one) and `delta` each
/// node's charge (`EdgeCharges`). With `kept_i` the positive kept weight at node `i`, the mean of
/// `delta_i / kept_i` over the nodes with some is compared with [`SPARSEST_FAILING_RATIO`]; the
/// forecast count is [`PIVOTS_PER_RATIO`] times the mean, per node. `None` below it. A forecast
/// orders the ladder, never part of a proof.
pub(super) fn sparsest_regions_forecast(
    problem: &MultipleProblem,
    reduced: &[f64],
    delta: &[f64],
) -> Option<ScalarFailure> {
    let n = problem.num_rotations();
    let mut kept = vec![0.0f64; n];
    for (e, &w) in problem
        .edges()
        .iter()
        .zip(reduced)
        .filter(|(_, w)| **w > 0.0)
    {
        kept[e.i] += w;
        kept[e.j] += w;
    }
    let (sum, nodes) = kept
        .iter()
        .zip(delta)
        .filter(|(k, _)| **k > 0.0)
        .fold((0.0, 0usize), |(s, c), (k, d)| (s + d / k, c + 1));
    let mean_ratio = sum / nodes.max(1) as f64;
    (mean_ratio > SPARSEST_FAILING_RATIO).then(|| ScalarFailure::Forecast {
        negative_pivots: (PIVOTS_PER_RATIO * mean_ratio * n as f64).ceil() as usize,
        mean_ratio,
    })
}
