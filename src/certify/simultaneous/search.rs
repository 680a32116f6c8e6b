//! A search over the couplings of the simultaneous dual certificate `[H15]`
//! (`paper-notes/conjugate.md`): when the couplings of least norm leave `Z_R` or `Z_C` with a
//! negative eigenvalue, other couplings in the same affine set (the ones complementary slackness
//! allows at the estimate) may not. Both `lambda_min(Z_R(gamma))` and `lambda_min(Z_C(gamma))`
//! are concave in `gamma` (the `Lambda_a` are affine in it): every negative eigenpair `(w, v)`
//! gives the cut `w + d . (gamma' - gamma) >= w / 4`-ish, `d` the gradient `v^T (dZ / dgamma) v`
//! projected onto the kernel of `A`, and cyclic projections onto the cuts (as `[A11]`'s search)
//! move `gamma`; a round recomputes both spectra. Nothing here is proved: the couplings found are
//! handed to [`super::verify_simultaneous_bound`] like any others.

use super::bound::certificate_matrix;
use super::multipliers::EstimateMultipliers;
use crate::multiple::MultipleProblem;
use nalgebra::{DMatrix, Matrix3};
use std::time::Instant;

/// Rounds at most (each two dense eigendecompositions with vectors, `3n x 3n`).
pub const MAX_SEARCH_ROUNDS: usize = 40;

/// Negative eigenpairs turned into cuts per side and round at most.
const CUTS_PER_SIDE: usize = 10;

/// Sweeps of cyclic projections over all cuts per round.
const SWEEPS: usize = 20;

/// Rounds over which the search must halve its most negative eigenvalue, or stop.
const STALL_WINDOW: usize = 10;

/// The search has stalled: the best (least negative) of the smaller `lambda_min` over the last
/// [`STALL_WINDOW`] rounds is not half the best before them. Measured (simultaneous_table, 3
/// seeds per row, 5-200 stations): every search that certified halved it within 2-3 rounds and
/// ended within 9; the ones that failed oscillated for all 40 rounds.
fn stalled(history: &[f64]) -> bool {
    let k = history.len();
    if k <= STALL_WINDOW {
        return false;
    }
    let best = |h: &[f64]| h.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let (before, recent) = history.split_at(k - STALL_WINDOW);
    best(recent).abs() > 0.5 * best(before).abs()
}

/// Rounds within which a search of expensive rounds ([`EXPENSIVE_ROUND_SECONDS`]) must halve
/// its first round's most negative eigenvalue, or stop ([`stalled_early`]).
const EARLY_WINDOW: usize = 4;

/// A round predicted at least this long (two `3n x 3n` eigendecompositions: from about 700
/// frames) makes [`STALL_WINDOW`] cost minutes.
const EXPENSIVE_ROUND_SECONDS: f64 = 1.0;

/// The search has not halved its first round's most negative eigenvalue within
/// [`EARLY_WINDOW`] rounds: every search that certified did within 2-3 (the measurement of
/// [`stalled`]); a two-graph rig of 1000 frames with strongly anisotropic information (`[H22]`
/// "Information") spent 115 s in the 10-round window without gaining (2026-12-06).
fn stalled_early(history: &[f64]) -> bool {
    let Some((&first, rest)) = history.split_first() else {
        return false;
    };
    let best = rest.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    rest.len() >= EARLY_WINDOW && first < 0.0 && best.abs() > 0.5 * first.abs()
}

/// What the search ended with (for the verification) and how long it ran (for the note).
pub(crate) struct SearchOutcome {
    /// The multipliers and couplings it ended with.
    pub lambdas: Vec<Matrix3<f64>>,
    pub couplings: Vec<f64>,
    /// Rounds of cuts and projections, and cuts made.
    pub rounds: usize,
    pub cuts: usize,
}

/// Seconds per `(3n)^3` of a dense symmetric eigendecomposition with vectors (faer: 1.5 s at
/// `3n = 3000`, 16.6 s at 6000 on this 2-core machine, 2026-12-01; with room).
const ROUND_SECONDS_PER_CUBE: f64 = 1.2e-10;

/// The time of one round on `n` nodes: two dense symmetric eigendecompositions of `3n x 3n`
/// with vectors. A round is started only when it fits.
fn predicted_round_seconds(n: usize) -> f64 {
    let d = 3.0 * n as f64;
    2.0 * ROUND_SECONDS_PER_CUBE * d * d * d
}

/// Search from the least-norm couplings of `at` until both `lambda_min` are at least `-target`,
/// [`MAX_SEARCH_ROUNDS`] rounds, a stall ([`stalled`]), a round predicted past `seconds`, or
/// `max_cut_bytes` of stored cuts (`8 n (n - 1) / 2` bytes each). Memory besides the cuts: one
/// side's eigenvectors while the other's are computed (with `at`'s factor, at most five dense
/// `3n x 3n` matrices). `None` when not even one round fits the time.
pub(crate) fn search_couplings(
    right: &MultipleProblem,
    left: &MultipleProblem,
    at: &EstimateMultipliers,
    target: f64,
    seconds: Option<f64>,
    max_cut_bytes: f64,
) -> Option<SearchOutcome> {
    let start = Instant::now();
    let n = at.rs.len();
    let round_seconds = predicted_round_seconds(n);
    let fits = || seconds.is_none_or(|s| start.elapsed().as_secs_f64() + round_seconds <= s);
    if !fits() {
        return None;
    }
    let max_cuts = (max_cut_bytes / (8.0 * at.pairs.len().max(1) as f64)) as usize;
    let mut g = at.least_norm.clone();
    let mut cuts: Vec<(Vec<f64>, f64)> = Vec::new();
    let (mut rounds, mut history) = (0, Vec::new());
    loop {
        let lambdas = at.lambdas(&g);
        let before = cuts.len();
        let mut min = f64::INFINITY;
        // one side at a time: its spectrum, its cuts, then it is dropped
        for (p, side, sign, ys) in [
            (right, &lambdas[..n], -0.5, &at.rs),
            (left, &lambdas[n..], 0.5, &at.cs),
        ] {
            let (z, _) = certificate_matrix(p, side, &g, sign);
            let Some(eig) = crate::linalg::dense::symmetric_eigen(&z) else {
                min = f64::NEG_INFINITY;
                continue;
            };
            drop(z);
            min = min.min(eig.0.first().copied().unwrap_or(f64::INFINITY));
            let side = Side { at, ys, sign };
            side.cuts(&eig, &g, target, max_cuts, &mut cuts);
        }
        history.push(min);
        let done = min >= -target
            || rounds >= MAX_SEARCH_ROUNDS
            || cuts.len() == before
            || stalled(&history)
            || (round_seconds >= EXPENSIVE_ROUND_SECONDS && stalled_early(&history))
            || !fits();
        if done {
            return Some(SearchOutcome {
                lambdas,
                couplings: g,
                rounds,
                cuts: cuts.len(),
            });
        }
        rounds += 1;
        project_onto_cuts(&mut g, &cuts);
    }
}

/// One side of the certificate (`Z_R` or `Z_C`): the multipliers at the estimate, the side's
/// rotations `Y` and the sign of its couplings.
struct Side<'a> {
    at: &'a EstimateMultipliers,
    ys: &'a [Matrix3<f64>],
    sign: f64,
}

impl Side<'_> {
    /// The cuts of the side's [`CUTS_PER_SIDE`] most negative eigenpairs below `-target` at the
    /// couplings `g`, appended to `cuts` while they hold fewer than `max_cuts`.
    fn cuts(
        &self,
        (values, vectors): &(Vec<f64>, DMatrix<f64>),
        g: &[f64],
        target: f64,
        max_cuts: usize,
        cuts: &mut Vec<(Vec<f64>, f64)>,
    ) {
        let mut order: Vec<usize> = (0..values.len()).filter(|&k| values[k] < -target).collect();
        order.sort_by(|&a, &b| values[a].total_cmp(&values[b]));
        for &k in order.iter().take(CUTS_PER_SIDE) {
            if cuts.len() >= max_cuts {
                break;
            }
            let w = values[k];
            let mut d = self.gradient(vectors.column(k));
            self.at.project(&mut d);
            let dd: f64 = d.iter().map(|x| x * x).sum();
            if dd > 0.0 && dd.is_finite() {
                // aim a quarter of |w| above zero: w + d . (gamma' - gamma) >= |w| / 4
                let dg: f64 = d.iter().zip(g).map(|(a, b)| a * b).sum();
                cuts.push((d, 0.25 * w.abs() - w + dg));
            }
        }
    }

    /// The gradient of `v^T Z(gamma) v` in the couplings:
    /// `v^T (dZ / dgamma_ij) v = -2 sign (v_i^T M v_i / 2 + v_j^T M v_j / 2 - v_i . v_j)`,
    /// `M = sym(Y_j Y_i^T)` (R on the right, C on the left).
    fn gradient(&self, v: nalgebra::DVectorView<'_, f64>) -> Vec<f64> {
        let (ys, sign) = (self.ys, self.sign);
        let vb = |i: usize| nalgebra::Vector3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
        self.at
            .pairs
            .iter()
            .map(|&(i, j)| {
                let m = ys[j] * ys[i].transpose();
                let m = (m + m.transpose()) * 0.5;
                let (vi, vj) = (vb(i), vb(j));
                -2.0 * sign * (0.5 * vi.dot(&(m * vi)) + 0.5 * vj.dot(&(m * vj)) - vi.dot(&vj))
            })
            .collect()
    }
}

/// [`SWEEPS`] sweeps of cyclic projections of the couplings `g` onto the cuts
/// `d . g >= rhs`.
fn project_onto_cuts(g: &mut [f64], cuts: &[(Vec<f64>, f64)]) {
    for _ in 0..SWEEPS {
        for (d, rhs) in cuts {
            let dg: f64 = d.iter().zip(g.iter()).map(|(a, b)| a * b).sum();
            let violation = rhs - dg;
            if violation > 0.0 {
                let dd: f64 = d.iter().map(|x| x * x).sum();
                g.iter_mut()
                    .zip(d)
                    .for_each(|(x, di)| *x += violation * di / dd);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certify::simultaneous::multipliers::PointTerms;

    /// The stall rule: a trajectory that halves within the window goes on, one that oscillates
    /// stops (trajectories from the simultaneous table's trace).
    #[test]
    fn stall_rule() {
        let certified = [
            -5.3e-1, -2.1e-1, -2.3e-1, -1.4e-1, -5.6e-2, -2.3e-2, -2.3e-2, -2.4e-3,
        ];
        for k in 1..=certified.len() {
            assert!(!stalled(&certified[..k]));
        }
        let oscillating: Vec<f64> = (0..12)
            .map(|k| if k % 2 == 0 { -2.0 } else { -1.5 })
            .collect();
        assert!(!stalled(&oscillating[..STALL_WINDOW]));
        assert!(stalled(&oscillating));
        let slow: Vec<f64> = (0..12).map(|k| -3.0 * 0.7f64.powi(k)).collect();
        assert!(!stalled(&slow));
    }
    /// The early stall of expensive searches: a trajectory that halves its first value
    /// within [`EARLY_WINDOW`] rounds goes on, one that does not stops, and nothing stops
    /// before the window is full.
    #[test]
    fn early_stall_rule() {
        let halving = [-1.0, -0.7, -0.45, -0.2, -0.1];
        assert!(!stalled_early(&halving));
        let flat = [-1.0, -0.9, -0.8, -0.7, -0.6];
        assert!(stalled_early(&flat));
        assert!(!stalled_early(&flat[..EARLY_WINDOW]));
        assert!(!stalled_early(&[]));
    }

    use crate::multiple::synthetic::SyntheticGraph;

    /// The cut's gradient is the derivative of `v^T Z(gamma) v` along a projected direction
    /// (finite differences on a 6-node rig), and projected directions keep the multipliers'
    /// complementary slackness (`Z_R Y_R` unchanged).
    #[test]
    fn gradient_matches_finite_differences() {
        // two unrelated noisy graphs and any point: the identities hold everywhere
        let graph = |seed| SyntheticGraph {
            num_rotations: 6,
            num_edges: 12,
            noise_sigma: 0.2,
            seed,
            ..Default::default()
        };
        let (right, truth) = graph(9).generate();
        let (left, _) = graph(10).generate();
        let s = crate::so3::exp(&nalgebra::Vector3::new(0.3, -0.2, 0.5));
        let at =
            EstimateMultipliers::new(PointTerms::new(&right, &left, &truth, &s).unwrap()).unwrap();
        let n = 6;
        let g0 = at.least_norm.clone();
        let mut dir: Vec<f64> = (0..g0.len())
            .map(|k| ((k * 37) % 11) as f64 - 5.0)
            .collect();
        at.project(&mut dir);
        let sym = |m: Matrix3<f64>| (m + m.transpose()) * 0.5;
        for (side, sign) in [(0usize, 1.0), (1, -1.0)] {
            let z = |g: &[f64]| {
                let l = at.lambdas(g);
                if side == 0 {
                    certificate_matrix(&right, &l[..n], g, -0.5).0
                } else {
                    certificate_matrix(&left, &l[n..], g, 0.5).0
                }
            };
            let v = nalgebra::DVector::<f64>::from_fn(3 * n, |k, _| ((k * 13) % 7) as f64 - 3.0);
            let h = 1e-6;
            let plus: Vec<f64> = g0.iter().zip(&dir).map(|(a, b)| a + h * b).collect();
            let minus: Vec<f64> = g0.iter().zip(&dir).map(|(a, b)| a - h * b).collect();
            let fd = ((v.transpose() * z(&plus) * &v)[0] - (v.transpose() * z(&minus) * &v)[0])
                / (2.0 * h);
            let ys = if side == 0 { &at.rs } else { &at.cs };
            let analytic: f64 = at
                .pairs
                .iter()
                .zip(&dir)
                .map(|(&(i, j), d)| {
                    let m = sym(ys[j] * ys[i].transpose());
                    let vb =
                        |a: usize| nalgebra::Vector3::new(v[3 * a], v[3 * a + 1], v[3 * a + 2]);
                    let (vi, vj) = (vb(i), vb(j));
                    d * sign * (0.5 * vi.dot(&(m * vi)) + 0.5 * vj.dot(&(m * vj)) - vi.dot(&vj))
                })
                .sum();
            assert!(
                (fd - analytic).abs() <= 1e-5 * (1.0 + fd.abs()),
                "side {side}: {fd} vs {analytic}"
            );
            // Z Y at the moved couplings equals Z Y at the least-norm ones (both ~ 0)
            let y = nalgebra::DMatrix::<f64>::from_fn(3 * n, 3, |r, c| ys[r / 3][(r % 3, c)]);
            let zy0 = (z(&g0) * &y).norm();
            let zy1 = (z(&plus) * &y).norm();
            assert!((zy1 - zy0).abs() < 1e-8, "side {side}: {zy0} -> {zy1}");
        }
    }
}
