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

use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use std::collections::VecDeque;

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
    let adjacency = adjacency(problem);
    let far = farthest(&adjacency, 0);
    let mut x = distances(&adjacency, far);
    let mean = x.iter().sum::<f64>() / n as f64;
    x.iter_mut().for_each(|v| *v -= mean);
    // a = 1^T M 1, b = 1^T M x, c = x^T M x for M = L' - diag(charges)
    let (mut a, mut b, mut c) = (0.0, 0.0, 0.0);
    for e in problem.edges() {
        let gram = rotations[e.j].matrix() * rotations[e.i].matrix().transpose();
        let cos = ((e.rotation.matrix().dot(&gram) - 1.0) / 2.0).clamp(-1.0, 1.0);
        let charge = e.weight * (1.0 - cos * cos);
        let kept = e.weight * (cos - 0.5);
        let (xi, xj) = (x[e.i], x[e.j]);
        a -= 2.0 * charge;
        b -= charge * (xi + xj);
        c += kept * (xi - xj) * (xi - xj) - charge * (xi * xi + xj * xj);
    }
    a < 0.0 && c < 0.0 && a * c > b * b
}

fn adjacency(problem: &MultipleProblem) -> Vec<Vec<usize>> {
    let mut adjacency = vec![Vec::new(); problem.num_rotations()];
    for e in problem.edges() {
        adjacency[e.i].push(e.j);
        adjacency[e.j].push(e.i);
    }
    adjacency
}

/// Breadth-first distances from `source` (unreached nodes: 0).
fn distances(adjacency: &[Vec<usize>], source: usize) -> Vec<f64> {
    let mut d = vec![f64::NAN; adjacency.len()];
    d[source] = 0.0;
    let mut queue = VecDeque::from([source]);
    while let Some(u) = queue.pop_front() {
        for &v in &adjacency[u] {
            if d[v].is_nan() {
                d[v] = d[u] + 1.0;
                queue.push_back(v);
            }
        }
    }
    d.iter()
        .map(|v| if v.is_nan() { 0.0 } else { *v })
        .collect()
}

/// The node farthest from `source` (a peripheral node, for a smooth distance vector).
fn farthest(adjacency: &[Vec<usize>], source: usize) -> usize {
    let d = distances(adjacency, source);
    (0..d.len())
        .max_by(|&p, &q| d[p].total_cmp(&d[q]))
        .unwrap_or(source)
}
