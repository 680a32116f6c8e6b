//! Node groups for the grouped subgraphs of large view graphs (`paper-notes/certificates.md`
//! `[D13]`, "Grouped subgraphs"): `k` connected regions of about `n / k` nodes each, with few
//! edges between them. Which nodes go where decides only whether the grouped comparison proves
//! and what its factors cost, never what it proves.

use crate::multiple::MultipleProblem;
use crate::multiple::union_find::UnionFind;
use std::cmp::Reverse;
use std::collections::{BinaryHeap, VecDeque};

/// Refinement passes of [`partition`] (each moves a node to the group holding most of its
/// neighbours; on a 3x10^4-node random graph of 10 edges per node and 4 groups the cut fell
/// from 177k to 170k edges in six, the later passes moving under 1 % of the nodes).
const REFINE_PASSES: usize = 6;

/// How far a group may grow past, or shrink below, `n / k` while it is refined (a fraction).
const BALANCE: f64 = 0.05;

/// `k` groups of the nodes (`group[i]` in `0..k`): regions grown together from `k` seeds spread
/// along a breadth-first order (the smallest region grows next, so they stay balanced), then
/// refined by moving nodes to the group that holds most of their neighbours, within
/// [`BALANCE`] of `n / k`, and finally every node outside its group's largest connected part
/// moved to the neighbouring group it has most edges into (a group must be connected: each
/// further component of its subgraph is one more negative pivot the proof expects, and a
/// small one makes the coarse bound weak). `k` is clamped to `1..=n`.
pub(super) fn partition(problem: &MultipleProblem, k: usize) -> Vec<usize> {
    partition_weighted(problem, k, &|_| 1.0)
}

/// [`partition`] whose refinement counts each edge `e` as `weight(e)` (`>= 0`) instead of 1:
/// a node goes to the group holding most of its edges' weight (the block comparison's
/// regions weigh edges by their strength, so that a node keeps its strong edges).
pub(in crate::certify::multiple) fn partition_weighted(
    problem: &MultipleProblem,
    k: usize,
    weight: &dyn Fn(usize) -> f64,
) -> Vec<usize> {
    let n = problem.num_rotations();
    let k = k.clamp(1, n.max(1));
    if k == 1 {
        return vec![0; n];
    }
    let mut group = grow(problem, k);
    let mut sizes = vec![0usize; k];
    group.iter().for_each(|&g| sizes[g] += 1);
    refine(problem, &mut group, &mut sizes, weight);
    for _ in 0..3 {
        if !reattach(problem, &mut group, k) {
            break;
        }
    }
    group
}

/// Regions grown breadth-first from `k` seeds at evenly spaced places of a breadth-first order
/// of the whole graph, the smallest region taking the next node.
fn grow(problem: &MultipleProblem, k: usize) -> Vec<usize> {
    let n = problem.num_rotations();
    let adjacency = problem.adjacency();
    let order = breadth_first_order(problem);
    let mut group = vec![usize::MAX; n];
    let mut queues: Vec<VecDeque<usize>> =
        (0..k).map(|g| VecDeque::from([order[g * n / k]])).collect();
    let mut heap: BinaryHeap<Reverse<(usize, usize)>> = (0..k).map(|g| Reverse((0, g))).collect();
    while let Some(Reverse((size, g))) = heap.pop() {
        // the region's next unassigned node, if it has one left to reach
        while let Some(v) = queues[g].pop_front() {
            if group[v] != usize::MAX {
                continue;
            }
            group[v] = g;
            let reach = adjacency.neighbours(v).iter().map(|&(w, _)| w);
            queues[g].extend(reach.filter(|&w| group[w] == usize::MAX));
            heap.push(Reverse((size + 1, g)));
            break;
        }
    }
    // nodes no region reached (other components of the graph): the first group
    group
        .iter_mut()
        .filter(|g| **g == usize::MAX)
        .for_each(|g| *g = 0);
    group
}

/// The nodes in breadth-first order from node 0 (every component, one after the other).
fn breadth_first_order(problem: &MultipleProblem) -> Vec<usize> {
    let n = problem.num_rotations();
    let adjacency = problem.adjacency();
    let mut seen = vec![false; n];
    let mut order = Vec::with_capacity(n);
    for start in 0..n {
        if seen[start] {
            continue;
        }
        seen[start] = true;
        let mut at = order.len();
        order.push(start);
        while at < order.len() {
            let v = order[at];
            at += 1;
            for &(w, _) in adjacency.neighbours(v) {
                if !seen[w] {
                    seen[w] = true;
                    order.push(w);
                }
            }
        }
    }
    order
}

/// [`REFINE_PASSES`] passes moving each node to the group holding strictly more of its
/// neighbours (by `weight`) than its own, while both groups stay within [`BALANCE`] of `n / k`.
fn refine(
    problem: &MultipleProblem,
    group: &mut [usize],
    sizes: &mut [usize],
    weight: &dyn Fn(usize) -> f64,
) {
    let k = sizes.len();
    let adjacency = problem.adjacency();
    let even = group.len() as f64 / k as f64;
    let (most, least) = (
        (even * (1.0 + BALANCE)).ceil(),
        (even * (1.0 - BALANCE)).floor(),
    );
    let mut count = vec![0.0f64; k];
    for _ in 0..REFINE_PASSES {
        let mut moved = 0;
        for v in 0..group.len() {
            count.iter_mut().for_each(|c| *c = 0.0);
            for &(w, e) in adjacency.neighbours(v) {
                count[group[w]] += weight(e);
            }
            let own = group[v];
            let best = (0..k)
                .max_by(|&a, &b| {
                    count[a]
                        .total_cmp(&count[b])
                        .then((a == own).cmp(&(b == own)))
                })
                .unwrap_or(own);
            let fits = (sizes[best] + 1) as f64 <= most && (sizes[own] - 1) as f64 >= least;
            if best != own && count[best] > count[own] && fits {
                sizes[own] -= 1;
                sizes[best] += 1;
                group[v] = best;
                moved += 1;
            }
        }
        if moved * 100 < group.len() {
            break;
        }
    }
}

/// Move every node outside its group's largest connected part (of the edges within groups)
/// to the neighbouring group it has most edges into; `true` when any node moved.
fn reattach(problem: &MultipleProblem, group: &mut [usize], k: usize) -> bool {
    let n = group.len();
    let mut parts = UnionFind::new(n);
    for e in problem.edges() {
        if group[e.i] == group[e.j] {
            parts.union(e.i, e.j);
        }
    }
    let roots: Vec<usize> = (0..n).map(|v| parts.find(v)).collect();
    let mut size = vec![0usize; n];
    roots.iter().for_each(|&r| size[r] += 1);
    // each group's largest part
    let mut largest = vec![usize::MAX; k];
    for v in 0..n {
        let (g, r) = (group[v], roots[v]);
        if largest[g] == usize::MAX || size[r] > size[largest[g]] {
            largest[g] = r;
        }
    }
    let adjacency = problem.adjacency();
    let mut count = vec![0usize; k];
    let mut moved = false;
    for v in 0..n {
        if roots[v] == largest[group[v]] {
            continue;
        }
        count.iter_mut().for_each(|c| *c = 0);
        for &(w, _) in adjacency.neighbours(v) {
            if roots[w] == largest[group[w]] {
                count[group[w]] += 1;
            }
        }
        if let Some(best) = (0..k).filter(|&g| count[g] > 0).max_by_key(|&g| count[g]) {
            group[v] = best;
            moved = true;
        }
    }
    moved
}

#[cfg(test)]
mod tests {
    use super::partition;
    use crate::multiple::synthetic::SyntheticGraph;

    /// Balanced, connected groups covering every node, and fewer edges between them than a
    /// partition by node index (the random graph's nodes are in no particular order).
    #[test]
    fn groups_are_balanced_connected_regions() {
        let (p, _) = SyntheticGraph {
            num_rotations: 2000,
            num_edges: 10_000,
            ..Default::default()
        }
        .generate();
        for k in [1, 2, 4, 7] {
            let group = partition(&p, k);
            assert_eq!(group.len(), 2000);
            let mut sizes = vec![0usize; k];
            group.iter().for_each(|&g| sizes[g] += 1);
            assert!(sizes.iter().all(|&s| s > 2000 / k / 2), "{k}: {sizes:?}");
            let mut parts = crate::multiple::union_find::UnionFind::new(2000);
            for e in p.edges().iter().filter(|e| group[e.i] == group[e.j]) {
                parts.union(e.i, e.j);
            }
            let mut roots: Vec<usize> = (0..2000).map(|v| parts.find(v)).collect();
            roots.sort_unstable();
            roots.dedup();
            assert_eq!(roots.len(), k, "{k} groups, each connected");
            let cut = p
                .edges()
                .iter()
                .filter(|e| group[e.i] != group[e.j])
                .count();
            let by_index = p
                .edges()
                .iter()
                .filter(|e| e.i * k / 2000 != e.j * k / 2000)
                .count();
            assert!(cut <= by_index, "{k}: cut {cut} against {by_index}");
        }
    }
}
