//! Graph statistics for `rotavg info`: sizes, duplicate and contradictory edges, components,
//! degrees, weights, residuals of an initial estimate, and the spectral gap.
//!
//! Spectral gap `[F10]` (`paper-notes/formats.md`): `lambda_2(L) / d_max`, where `L = D - W`
//! is the weighted scalar graph Laplacian (`W_ab` = sum of the weights of all edges joining
//! `a` and `b`, multi-edges summed) and `d_max` the largest weighted degree. It is 0 exactly
//! when the graph is disconnected, and at most `n / (n - 1)`; small values mean a weakly
//! connected graph (long cycles, bottlenecks), where rotation averaging is poorly conditioned.
//! Computed with dense eigenvalues for `n <= dense_max_nodes`, otherwise by Lanczos with full
//! reorthogonalisation on `L` restricted to the complement of the all-ones vector: the smallest
//! Ritz value is then an upper bound on `lambda_2` (Cauchy interlacing), reported with its
//! residual `|beta_k s_k|`, which bounds its distance to an eigenvalue of `L`.

use crate::linalg::{Extreme, LanczosSettings, LanczosStop, lanczos};
use crate::multiple::MultipleProblem;
use crate::so3::{Rotation, angle_between};
use crate::warning::Warning;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Settings of [`graph_stats`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StatsSettings {
    /// Two measurements of the same pair that disagree by more than this angle (degrees) are
    /// reported as contradictory.
    pub contradiction_deg: f64,
    /// Largest `n` for which dense eigenvalues are computed; above it, Lanczos.
    pub dense_max_nodes: usize,
    /// Number of Lanczos steps (above `dense_max_nodes`).
    pub lanczos_steps: usize,
}

impl Default for StatsSettings {
    fn default() -> Self {
        StatsSettings {
            contradiction_deg: 5.0,
            dense_max_nodes: 2000,
            lanczos_steps: 300,
        }
    }
}

/// Summary statistics of a set of numbers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// Smallest value.
    pub min: f64,
    /// Mean.
    pub mean: f64,
    /// Median.
    pub median: f64,
    /// Largest value.
    pub max: f64,
}

impl Summary {
    /// Summary of a non-empty slice (`None` when empty).
    pub fn of(values: &[f64]) -> Option<Summary> {
        if values.is_empty() {
            return None;
        }
        let mut v = values.to_vec();
        v.sort_by(f64::total_cmp);
        let k = v.len();
        let median = if k % 2 == 1 {
            v[k / 2]
        } else {
            0.5 * (v[k / 2 - 1] + v[k / 2])
        };
        Some(Summary {
            min: v[0],
            mean: v.iter().sum::<f64>() / k as f64,
            median,
            max: v[k - 1],
        })
    }
}

impl fmt::Display for Summary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // fixed notation for ordinary magnitudes, scientific for tiny or huge ones
        let num = |x: f64| {
            if x == 0.0 || (1e-3..1e6).contains(&x.abs()) {
                format!("{x:.4}")
            } else {
                format!("{x:.4e}")
            }
        };
        write!(
            f,
            "min {}, mean {}, median {}, max {}",
            num(self.min),
            num(self.mean),
            num(self.median),
            num(self.max)
        )
    }
}

/// How the spectral gap was obtained.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case")]
pub enum SpectralGap {
    /// Dense symmetric eigenvalues of `L` (exact up to rounding).
    Dense {
        /// `lambda_2(L)`.
        lambda2: f64,
        /// `lambda_2(L) / d_max`.
        normalized: f64,
    },
    /// Lanczos estimate (an upper bound on `lambda_2`, see the module docs).
    Lanczos {
        /// Smallest Ritz value on the complement of the ones vector.
        lambda2: f64,
        /// `lambda2 / d_max`.
        normalized: f64,
        /// Residual norm of the Ritz pair (distance bound to an eigenvalue of `L`).
        residual: f64,
        /// Lanczos steps taken.
        steps: usize,
        /// Why the iteration stopped: converged when the relative residual is below `1e-8`
        /// (otherwise `lambda2` is only an upper bound, possibly a loose one).
        stop: LanczosStop,
    },
    /// The graph is disconnected: `lambda_2 = 0`.
    Disconnected,
    /// Not computed.
    Skipped {
        /// Why.
        reason: String,
    },
}

impl SpectralGap {
    /// The normalised gap, when computed (0 for a disconnected graph).
    pub fn normalized(&self) -> Option<f64> {
        match self {
            SpectralGap::Dense { normalized, .. } | SpectralGap::Lanczos { normalized, .. } => {
                Some(*normalized)
            }
            SpectralGap::Disconnected => Some(0.0),
            SpectralGap::Skipped { .. } => None,
        }
    }
}

impl fmt::Display for SpectralGap {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SpectralGap::Dense {
                lambda2,
                normalized,
            } => write!(
                f,
                "{normalized:.6e} (lambda_2 = {lambda2:.6e}, dense eigenvalues)"
            ),
            SpectralGap::Lanczos {
                lambda2,
                normalized,
                residual,
                steps,
                stop,
            } => write!(
                f,
                "{normalized:.6e} (lambda_2 <= {lambda2:.6e}, Lanczos {steps} steps, residual {residual:.1e}{})",
                if stop.converged() {
                    ""
                } else {
                    ", NOT converged: upper bound only"
                }
            ),
            SpectralGap::Disconnected => write!(f, "0 (disconnected)"),
            SpectralGap::Skipped { reason } => write!(f, "skipped ({reason})"),
        }
    }
}

/// Residuals of an estimate (e.g. a file's vertex lines) on the graph.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResidualStats {
    /// Chordal cost `sum w_ij ||R_j - R_ij R_i||_F^2`.
    pub chordal_cost: f64,
    /// Residual angles `theta(R_ij R_i, R_j)` in degrees.
    pub angle_deg: Summary,
}

/// Statistics of a view graph.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GraphStats {
    /// Number of nodes.
    pub num_nodes: usize,
    /// Number of edges (multi-edges counted).
    pub num_edges: usize,
    /// Number of distinct unordered pairs `{i, j}`.
    pub num_pairs: usize,
    /// Edges whose pair occurred earlier (`num_edges - num_pairs`).
    pub duplicate_edges: usize,
    /// Pairs measured more than once whose measurements disagree by more than
    /// [`StatsSettings::contradiction_deg`] (each measurement compared with the pair's first).
    pub contradictory_pairs: usize,
    /// Largest disagreement between two measurements of one pair (degrees), if any duplicates.
    pub max_duplicate_disagreement_deg: Option<f64>,
    /// Component sizes, largest first.
    pub component_sizes: Vec<usize>,
    /// Node degrees (number of incident edges, multi-edges counted).
    pub degree: Summary,
    /// Edge weights.
    pub weight: Summary,
    /// Residuals of the given initial estimate, if one was given.
    pub initial_residuals: Option<ResidualStats>,
    /// Normalised algebraic connectivity `[F10]`.
    pub spectral_gap: SpectralGap,
}

/// The edges as `(a, b, k)`, `{a, b}` the unordered pair of edge `k` (`a < b`), sorted: the
/// measurements of one pair are adjacent, in file order. 24 bytes per edge, where a hash map of
/// the pairs takes several times that.
fn sorted_pairs(problem: &MultipleProblem) -> Vec<(usize, usize, usize)> {
    let mut pairs: Vec<(usize, usize, usize)> = problem
        .edges()
        .iter()
        .enumerate()
        .map(|(k, e)| (e.i.min(e.j), e.i.max(e.j), k))
        .collect();
    pairs.sort_unstable();
    pairs
}

/// Number of edges whose unordered pair occurred earlier in the edge list.
///
/// ```
/// use rotavg::multiple::{Edge, MultipleProblem, stats::duplicate_edge_count};
/// use rotavg::Rotation;
/// let e = |i, j| Edge { i, j, rotation: Rotation::identity(), weight: 1.0 };
/// let p = MultipleProblem::new(3, vec![e(0, 1), e(1, 0), e(1, 2), e(0, 1)])?;
/// assert_eq!(duplicate_edge_count(&p), 2);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn duplicate_edge_count(problem: &MultipleProblem) -> usize {
    let pairs = sorted_pairs(problem);
    pairs
        .windows(2)
        .filter(|w| (w[0].0, w[0].1) == (w[1].0, w[1].1))
        .count()
}

/// For each pair measured more than once: the largest angle (radians) between a later
/// measurement and the pair's first one, both expressed as `R_ab` with `a < b`; sorted by pair.
pub fn duplicate_disagreements(problem: &MultipleProblem) -> Vec<((usize, usize), f64)> {
    let edges = problem.edges();
    let oriented = |k: usize| {
        let e = &edges[k];
        if e.i < e.j {
            e.rotation
        } else {
            e.rotation.inverse()
        }
    };
    let pairs = sorted_pairs(problem);
    let mut out = Vec::new();
    for group in pairs.chunk_by(|x, y| (x.0, x.1) == (y.0, y.1)) {
        if let [(a, b, first), rest @ ..] = group
            && !rest.is_empty()
        {
            let r0 = oriented(*first);
            let worst = rest.iter().fold(0.0, |w: f64, &(_, _, k)| {
                w.max(angle_between(&r0, &oriented(k)))
            });
            out.push(((*a, *b), worst));
        }
    }
    out
}

/// The warning `duplicates_disagree` when pairs measured more than once disagree by more than
/// `threshold_deg` ([`duplicate_disagreements`]; every measurement is used, as given): the
/// count of such pairs and the worst, named by the file ids `node_ids` of its nodes.
///
/// ```
/// use rotavg::multiple::{Edge, MultipleProblem, stats::duplicates_disagree};
/// use rotavg::so3::exp;
/// use rotavg::Rotation;
/// let e = |i, j, r| Edge { i, j, rotation: r, weight: 1.0 };
/// let turn = exp(&nalgebra::Vector3::new(0.0, 0.0, 90f64.to_radians()));
/// let p = MultipleProblem::new(3, vec![e(0, 1, Rotation::identity()), e(1, 2, Rotation::identity()), e(1, 0, turn)])?;
/// let w = duplicates_disagree(&p, &[10, 20, 30], 5.0).unwrap();
/// assert_eq!(w.count, Some(1));
/// assert!(w.message.contains("90.0 deg") && w.message.contains("(10, 20)"), "{}", w.message);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn duplicates_disagree(
    problem: &MultipleProblem,
    node_ids: &[u64],
    threshold_deg: f64,
) -> Option<Warning> {
    let bad: Vec<((usize, usize), f64)> = duplicate_disagreements(problem)
        .into_iter()
        .filter(|(_, angle)| angle.to_degrees() > threshold_deg)
        .collect();
    let ((a, b), worst) = bad.iter().copied().max_by(|x, y| x.1.total_cmp(&y.1))?;
    let id = |k: usize| node_ids.get(k).copied().unwrap_or(k as u64);
    Some(
        Warning::new(
            "duplicates_disagree",
            format!(
                "{} pairs measured more than once disagree by more than {threshold_deg} deg \
                 (worst: pair ({}, {}), {:.1} deg); every measurement is used as given",
                bad.len(),
                id(a),
                id(b),
                worst.to_degrees()
            ),
        )
        .with_count(bad.len()),
    )
}

/// Weighted degrees and adjacency (multi-edges summed) of the scalar graph Laplacian.
fn laplacian_adjacency(problem: &MultipleProblem) -> (Vec<f64>, Vec<Vec<(usize, f64)>>) {
    let n = problem.num_rotations();
    let mut deg = vec![0.0; n];
    // exact capacities: the lists take 16 bytes per edge end, no growth slack
    let mut count = vec![0usize; n];
    for e in problem.edges() {
        count[e.i] += 1;
        count[e.j] += 1;
    }
    let mut adj: Vec<Vec<(usize, f64)>> = count.into_iter().map(Vec::with_capacity).collect();
    for e in problem.edges() {
        deg[e.i] += e.weight;
        deg[e.j] += e.weight;
        adj[e.i].push((e.j, e.weight));
        adj[e.j].push((e.i, e.weight));
    }
    (deg, adj)
}

/// `y = L x` for the weighted scalar Laplacian.
fn laplacian_apply(deg: &[f64], adj: &[Vec<(usize, f64)>], x: &[f64], y: &mut [f64]) {
    for a in 0..deg.len() {
        let mut s = deg[a] * x[a];
        for &(b, w) in &adj[a] {
            s -= w * x[b];
        }
        y[a] = s;
    }
}

/// The normalised spectral gap `[F10]`.
///
/// ```
/// use rotavg::multiple::stats::{spectral_gap, StatsSettings};
/// use rotavg::multiple::synthetic::z_cycle;
/// // A 6-cycle with unit weights: lambda_2 = 2 - 2 cos(2 pi / 6) = 1, d_max = 2.
/// let gap = spectral_gap(&z_cycle(6, 0.0), &StatsSettings::default());
/// assert!((gap.normalized().unwrap() - 0.5).abs() < 1e-12);
/// ```
pub fn spectral_gap(problem: &MultipleProblem, settings: &StatsSettings) -> SpectralGap {
    let n = problem.num_rotations();
    if problem.components().len() > 1 {
        return SpectralGap::Disconnected;
    }
    let (deg, adj) = laplacian_adjacency(problem);
    let dmax = deg.iter().cloned().fold(0.0, f64::max);
    if n < 2 || dmax <= 0.0 {
        return SpectralGap::Skipped {
            reason: "fewer than 2 nodes".into(),
        };
    }
    if n <= settings.dense_max_nodes {
        let mut l = faer::Mat::<f64>::zeros(n, n);
        for e in problem.edges() {
            l[(e.i, e.i)] += e.weight;
            l[(e.j, e.j)] += e.weight;
            l[(e.i, e.j)] -= e.weight;
            l[(e.j, e.i)] -= e.weight;
        }
        return match l.self_adjoint_eigenvalues(faer::Side::Lower) {
            Ok(ev) => SpectralGap::Dense {
                lambda2: ev[1],
                normalized: ev[1] / dmax,
            },
            Err(e) => SpectralGap::Skipped {
                reason: format!("dense eigenvalue solver failed: {e:?}"),
            },
        };
    }
    lanczos_lambda2(&deg, &adj, settings.lanczos_steps.max(2), dmax)
}

/// The smallest eigenvalue of `L` on `1^perp` by [`lanczos`] (the ones vector deflated, a
/// fixed seed: deterministic).
fn lanczos_lambda2(deg: &[f64], adj: &[Vec<(usize, f64)>], steps: usize, dmax: f64) -> SpectralGap {
    let n = deg.len();
    let ones = vec![1.0 / (n as f64).sqrt(); n];
    let settings = LanczosSettings {
        max_iterations: steps.min(n - 1),
        tolerance: 1e-8,
        ..Default::default()
    };
    let e = lanczos(
        n,
        |x, y| laplacian_apply(deg, adj, x, y),
        Extreme::Smallest,
        1,
        dmax,
        &settings,
        &[ones],
        None,
    );
    match (e.values.first(), e.residuals.first()) {
        (Some(&lambda2), Some(&residual)) => SpectralGap::Lanczos {
            lambda2,
            normalized: lambda2 / dmax,
            residual,
            steps: e.subspace_dim,
            stop: e.stop,
        },
        _ => SpectralGap::Skipped {
            reason: "Lanczos found no Ritz pair".into(),
        },
    }
}

/// All statistics of a graph; `initial` (one rotation per node) adds its residuals.
///
/// ```
/// use rotavg::multiple::stats::{graph_stats, StatsSettings};
/// use rotavg::multiple::synthetic::z_cycle;
/// let s = graph_stats(&z_cycle(4, 0.0), None, &StatsSettings::default());
/// // a 4-cycle with unit weights: lambda_2 = 2, d_max = 2
/// assert!((s.spectral_gap.normalized().unwrap() - 1.0).abs() < 1e-12);
/// ```
pub fn graph_stats(
    problem: &MultipleProblem,
    initial: Option<&[Rotation]>,
    settings: &StatsSettings,
) -> GraphStats {
    let n = problem.num_rotations();
    let m = problem.num_edges();
    let duplicate_edges = duplicate_edge_count(problem);
    let dis = duplicate_disagreements(problem);
    let thr = settings.contradiction_deg.to_radians();
    let mut degree = vec![0.0; n];
    for e in problem.edges() {
        degree[e.i] += 1.0;
        degree[e.j] += 1.0;
    }
    let weights: Vec<f64> = problem.edges().iter().map(|e| e.weight).collect();
    let zero = Summary {
        min: 0.0,
        mean: 0.0,
        median: 0.0,
        max: 0.0,
    };
    let initial_residuals = initial.filter(|r| r.len() == n).map(|r| ResidualStats {
        chordal_cost: problem.chordal_cost(r),
        angle_deg: Summary::of(
            &problem
                .residual_angles(r)
                .iter()
                .map(|a| a.to_degrees())
                .collect::<Vec<_>>(),
        )
        .unwrap_or(zero),
    });
    GraphStats {
        num_nodes: n,
        num_edges: m,
        num_pairs: m - duplicate_edges,
        duplicate_edges,
        contradictory_pairs: dis.iter().filter(|(_, a)| *a > thr).count(),
        max_duplicate_disagreement_deg: dis.iter().map(|(_, a)| a.to_degrees()).reduce(f64::max),
        component_sizes: problem.components().iter().map(Vec::len).collect(),
        degree: Summary::of(&degree).unwrap_or(zero),
        weight: Summary::of(&weights).unwrap_or(zero),
        initial_residuals,
        spectral_gap: spectral_gap(problem, settings),
    }
}

impl fmt::Display for GraphStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "nodes:          {}", self.num_nodes)?;
        writeln!(
            f,
            "edges:          {} ({} distinct pairs, {} duplicate edges)",
            self.num_edges, self.num_pairs, self.duplicate_edges
        )?;
        if let Some(d) = self.max_duplicate_disagreement_deg {
            writeln!(
                f,
                "duplicates:     {} contradictory pair(s); largest disagreement {:.4} deg",
                self.contradictory_pairs, d
            )?;
        }
        let comps = &self.component_sizes;
        if comps.len() == 1 {
            writeln!(f, "components:     1 (connected)")?;
        } else {
            let shown: Vec<String> = comps.iter().take(10).map(|c| c.to_string()).collect();
            writeln!(
                f,
                "components:     {} (sizes {}{})",
                comps.len(),
                shown.join(", "),
                if comps.len() > 10 { ", ..." } else { "" }
            )?;
        }
        writeln!(f, "degree:         {}", self.degree)?;
        writeln!(f, "weight:         {}", self.weight)?;
        if let Some(r) = &self.initial_residuals {
            writeln!(
                f,
                "initial guess:  chordal cost {:.6e}; residual angle (deg) {}",
                r.chordal_cost, r.angle_deg
            )?;
        }
        write!(f, "spectral gap:   {}", self.spectral_gap)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multiple::Edge;
    use crate::multiple::synthetic::{SyntheticGraph, z_cycle};

    /// Cycle C_n with unit weights: lambda_2 = 2 - 2 cos(2 pi / n), d_max = 2 (closed form).
    #[test]
    fn cycle_gap_dense_and_lanczos() {
        for n in [5usize, 40] {
            let p = z_cycle(n, 0.0);
            let exact = (2.0 - 2.0 * (2.0 * std::f64::consts::PI / n as f64).cos()) / 2.0;
            let dense = spectral_gap(&p, &StatsSettings::default());
            assert!(
                (dense.normalized().unwrap() - exact).abs() < 1e-12,
                "{dense}"
            );
            let lz = spectral_gap(
                &p,
                &StatsSettings {
                    dense_max_nodes: 0,
                    lanczos_steps: n,
                    ..Default::default()
                },
            );
            assert!((lz.normalized().unwrap() - exact).abs() < 1e-9, "{lz}");
        }
    }

    /// Lanczos (300 steps) against dense eigenvalues on a random graph.
    #[test]
    fn lanczos_matches_dense_on_random_graph() {
        let (p, _) = SyntheticGraph {
            num_rotations: 800,
            num_edges: 2400,
            ..Default::default()
        }
        .generate();
        let d = spectral_gap(&p, &StatsSettings::default())
            .normalized()
            .unwrap();
        let l = spectral_gap(
            &p,
            &StatsSettings {
                dense_max_nodes: 0,
                ..Default::default()
            },
        )
        .normalized()
        .unwrap();
        assert!(
            l >= d - 1e-9 && (l - d).abs() < 1e-6 * d.max(1e-3),
            "{l} vs {d}"
        );
    }

    #[test]
    fn duplicates_and_contradictions() {
        let rz = |a: f64| Rotation::from_axis_angle(&nalgebra::Vector3::z_axis(), a.to_radians());
        let e = |i, j, r| Edge {
            i,
            j,
            rotation: r,
            weight: 1.0,
        };
        // pair {0,1}: 10 deg, then its reverse given as (1,0) with -10 deg (agrees), then 30 deg.
        let p = MultipleProblem::new(
            3,
            vec![
                e(0, 1, rz(10.0)),
                e(1, 0, rz(-10.0)),
                e(0, 1, rz(30.0)),
                e(1, 2, rz(0.0)),
            ],
        )
        .unwrap();
        let s = graph_stats(&p, None, &StatsSettings::default());
        assert_eq!(
            (s.num_pairs, s.duplicate_edges, s.contradictory_pairs),
            (2, 2, 1)
        );
        assert!((s.max_duplicate_disagreement_deg.unwrap() - 20.0).abs() < 1e-9);
        // disconnected graph: gap 0
        let q = MultipleProblem::new(4, vec![e(0, 1, rz(1.0)), e(2, 3, rz(1.0))]).unwrap();
        let s = graph_stats(&q, None, &StatsSettings::default());
        assert_eq!(s.component_sizes, vec![2, 2]);
        assert_eq!(s.spectral_gap, SpectralGap::Disconnected);
    }
}
