//! Which edges the block comparison `[A15]` keeps in its factorised block Laplacian: at every
//! node, greedily, the incident edges that most raise the smallest eigenvalue of the node's
//! kept strength `sum_e S_e` (anisotropic edges are strong about one or two axes; a subgraph
//! chosen by residual alone leaves nodes weak about the others), then the edges that connect
//! the result. Only a choice: it decides whether the proof succeeds and how large its factor
//! is, never what it proves.

use super::edges::edge_strength;
use crate::certify::multiple::scalar::connect;
use crate::multiple::MultipleProblem;
use crate::multiple::anisotropic::Information;
use crate::so3::Rotation;
use nalgebra::Matrix3;

/// The kept edges: every node keeps `edges_per_node` (`>= 0`; the fractional part: a fixed
/// fraction of the nodes keeps one more) of its incident edges, chosen greedily by the
/// smallest eigenvalue of its kept strength (counting the edges its neighbours kept before
/// it); an edge is kept when either endpoint keeps it.
pub(super) fn strong_subgraph_edges(
    problem: &MultipleProblem,
    information: &[Information],
    rotations: &[Rotation],
    edges_per_node: f64,
) -> Vec<bool> {
    let n = problem.num_rotations();
    let strength: Vec<Matrix3<f64>> = problem
        .edges()
        .iter()
        .zip(information)
        .map(|(e, h)| edge_strength(h, &e.rotation, &rotations[e.i], &rotations[e.j]))
        .collect();
    let residual: Vec<f64> = strength.iter().map(|s| -smallest(s)).collect();
    let adjacency = problem.adjacency();
    let mut keep = vec![false; problem.num_edges()];
    let whole = edges_per_node.floor() as usize;
    let fraction = edges_per_node - edges_per_node.floor();
    for v in 0..n {
        let incident: Vec<usize> = adjacency.neighbours(v).iter().map(|&(_, k)| k).collect();
        let mut sum: Matrix3<f64> = incident
            .iter()
            .filter(|&&k| keep[k])
            .map(|&k| strength[k])
            .sum();
        // a fixed pseudo-random subset of the nodes (Knuth's multiplicative hash)
        let extra = ((v as u64).wrapping_mul(2_654_435_761) % 1000) as f64 / 1000.0 < fraction;
        for _ in 0..whole + usize::from(extra) {
            let best = incident
                .iter()
                .filter(|&&k| !keep[k])
                .map(|&k| (k, smallest(&(sum + strength[k])), strength[k].trace()))
                .max_by(|a, b| a.1.total_cmp(&b.1).then(a.2.total_cmp(&b.2)));
            let Some((k, _, _)) = best else { break };
            keep[k] = true;
            sum += strength[k];
        }
    }
    connect(problem, &residual, &mut keep);
    keep
}

/// The smallest eigenvalue (an estimate: only a choice).
fn smallest(m: &Matrix3<f64>) -> f64 {
    m.symmetric_eigenvalues().min()
}
