//! The dual certificate of the `conv(SO(3))` relaxation at an estimate, for graphs of any size
//! (`paper-notes/anisotropic.md` `[A11]`): the `O(3)` dual certificate of a *surrogate*
//! problem whose edges are penalised against reflections.
//!
//! For every edge `e` (with `X_e = R_j R_i^T` at the estimate, `N_e = R_ij (2 tr(H) I - 4 H)`,
//! the edge's term `f_e(X) = 2 tr H - <N_e, X>`), a symmetric `P_e` in the cone
//! `C = { P : tr(P) I - P PSD }` gives the surrogate term with `N'_e = N_e - X_e P_e`, which is
//! stored as an ordinary anisotropic edge (`R'_e`, `H'_e` from the polar decomposition of
//! `X_e^T N'_e`). Whatever the surrogate's data, for every rotation `X`:
//! `f_e(X) >= f'_e(X) - delta_e` with `delta_e = max over SO(3) of (f'_e - f_e)
//! = 2 tr H'_e - 2 tr H_e + h(N_e - N'_e)`, `h(D) = max_{R in SO(3)} <D, R> = s_1 + s_2 +
//! sign(det D) s_3` ([`special_support`]); so a verified bound `L'` of the surrogate gives
//! `L' - sum delta_e` for the problem. With `P_e` in `C` the maximum is attained at the estimate
//! (the bound loses nothing there), and the surrogate's certificate matrix is
//! `S' = S - 1/2 sum_e B_e^T P_e B_e` with `B_e x = x_i - X_e^T x_j`: the `conv(SO(3))`
//! relaxation's dual with its multipliers in the estimate's frame. `P_e` starts at the edge's own
//! reflection price and is improved by cutting planes from the Lanczos vectors of negative
//! Ritz value ([`search_penalties`]); the bound itself is checked by the `O(3)` ladder of
//! [`super::verify`] on the surrogate and by the verified offsets, never by the search.

use super::check::Scope;
use super::conv_frames::{Frame, Inverse, anisotropic, frames};
use super::conv_offset::edge_offset;
pub use super::conv_offset::special_support;
use super::multipliers::{certificate_matrix, multipliers};
use super::state::{Best, State};
use super::verified::VerifiedBound;
use crate::certify::budget::Deadline;
use crate::certify::budget::{Budget, PREDICTED_FLOP_RATE};
use crate::certify::log::Point;
use crate::certify::log::{Prediction, Refusal};
use crate::certify::proof::{BoundMethod, Proof};
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifyMode;
pub use crate::certify::settings::ConvDualSettings;
use crate::error::{Error, Result};
use crate::linalg::cholesky::sparse_matvec;
use crate::linalg::compensated::Accumulator;
use crate::linalg::{Extreme, LanczosSettings, UNIT_ROUNDOFF, lanczos};
use crate::multiple::anisotropic::Information;
use crate::multiple::{Edge, MultipleProblem};
use crate::so3::{DEFAULT_ROTATION_TOLERANCE, Rotation, rotation_from_matrix};
use faer::sparse::SparseColMat;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Instant;

/// Why the search stopped.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum ConvSearchStop {
    /// The Lanczos run found no Ritz value below `-threshold` (an estimate, converged or not:
    /// the proof decides).
    NoNegativeRitzValue {
        /// Smallest Ritz value on the complement of the estimate's null space.
        smallest: f64,
        /// The resolution's threshold (`1e-9`, refined `1e-13`) times the search's scale.
        threshold: f64,
        /// Lanczos met its residual tolerance.
        converged: bool,
    },
    /// `max_rounds` rounds done.
    RoundLimit,
    /// `stall_rounds` rounds without progress.
    Stalled,
    /// Its share of the time budget spent.
    TimeLimit,
}

impl fmt::Display for ConvSearchStop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ConvSearchStop::NoNegativeRitzValue {
                smallest,
                threshold,
                converged,
            } => write!(
                f,
                "no Ritz value below -{threshold:.1e} (smallest {smallest:.3e}{})",
                if *converged { "" } else { ", not converged" }
            ),
            ConvSearchStop::RoundLimit => f.write_str("round limit"),
            ConvSearchStop::Stalled => f.write_str("stalled"),
            ConvSearchStop::TimeLimit => f.write_str("its share of the time budget spent"),
        }
    }
}

/// What the search did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConvSearch {
    /// One `P_e` per edge (in the estimate's frame of the edge, in the cone `C`): those of
    /// the round with the largest estimated bound (`kept_round`), else the initial ones.
    pub penalties: Vec<Matrix3<f64>>,
    /// The round whose penalties are returned (1-based; 0: no round ran).
    #[serde(default)]
    pub kept_round: usize,
    /// Their estimated bound: the surrogate's cost at the estimate, plus `3n` times the
    /// round's smallest Ritz value when negative, minus the offsets (not verified).
    #[serde(default)]
    pub estimated_bound: Option<f64>,
    /// Rounds run (0: the initial prices were not improved).
    pub rounds: usize,
    /// The rounds ran shift-invert Lanczos on a factorisation of `S' + sigma I`.
    pub shift_invert: bool,
    /// Cuts added.
    pub cuts: usize,
    /// The smallest Ritz value of the last round (an estimate of `lambda_min(S')` on the
    /// complement of the estimate's null space), if a round ran.
    pub smallest_ritz_value: Option<f64>,
    /// Why it stopped.
    pub stop: ConvSearchStop,
    /// Wall time, seconds.
    pub seconds: f64,
    /// The rounds ran at the fine resolution ([`refine_penalties`]), from the multipliers of a
    /// search at the coarse one whose surrogate did not certify.
    #[serde(default)]
    pub refined: bool,
}

/// The surrogate problem and the verified offsets of its edges.
#[derive(Debug, Clone, PartialEq)]
pub struct Surrogate {
    /// The penalised problem (same nodes and edges; data `R'_e`, `H'_e`).
    pub problem: MultipleProblem,
    /// A verified upper bound on `sum_e max over SO(3) of (f'_e - f_e)`.
    pub offset: f64,
}

/// The eigenvalues of a symmetric 3x3 matrix in ascending order, with their vectors.
fn sorted_eigen(m: &Matrix3<f64>) -> ([f64; 3], [Vector3<f64>; 3]) {
    let e = SymmetricEigen::new((m + m.transpose()) * 0.5);
    let mut idx = [0usize, 1, 2];
    idx.sort_by(|&a, &b| e.eigenvalues[a].total_cmp(&e.eigenvalues[b]));
    (
        idx.map(|k| e.eigenvalues[k]),
        idx.map(|k| e.eigenvectors.column(k).into_owned()),
    )
}

/// An edge's own reflection price: `P = beta (I - 2 u u^T)`, `kappa_1 <= kappa_2` the smallest
/// eigenvalues of `sym(K_e)` and `u` the first one's vector (the reflection across the plane
/// normal to `u` is what the edge alone would gain `2 kappa_1` from). `beta = -kappa_1` removes
/// that gain exactly and leaves the edge's `sym(K_e) - P` singular along `u`; the price is
/// [`REFLECTION_PRICE_MARGIN`] of `kappa_1 + kappa_2` above it, so that no such singular
/// direction survives in the surrogate's `S'` (on a 60-node graph the exact price left a fourth
/// zero eigenvalue, which its stationarity residual of 6.5e-5 turned into -6e-6, above the
/// tolerance's share). Edges with `kappa_1 >= 0` pay nothing.
fn initial_penalty(k: &Matrix3<f64>) -> Matrix3<f64> {
    let (values, vectors) = sorted_eigen(k);
    if values[0] >= 0.0 {
        return Matrix3::zeros();
    }
    let u = vectors[0];
    let beta = -values[0] + REFLECTION_PRICE_MARGIN * (values[0] + values[1]).max(0.0);
    (Matrix3::identity() - u * u.transpose() * 2.0) * beta
}

/// The initial reflection price's margin above the exact price, as a fraction of
/// `kappa_1 + kappa_2` (`(0, 1)`: the price stays at most `kappa_2`, where the edge's remaining
/// curvature would vanish).
pub const REFLECTION_PRICE_MARGIN: f64 = 0.25;

/// The Euclidean projection of a symmetric `P` onto the cone `C = { tr(P) I - P PSD }` (in
/// eigenvalues `p_1 <= p_2 <= p_3`: `p_1 + p_2 >= 0`).
///
/// ```
/// use rotavg::certify::multiple::conv_dual::project_to_cone;
/// use nalgebra::{Matrix3, Vector3};
/// let p = Matrix3::from_diagonal(&Vector3::new(-3.0, 1.0, 5.0));
/// let q = project_to_cone(&p);
/// let e = (Matrix3::identity() * q.trace() - q).symmetric_eigenvalues();
/// assert!(e.min() > -1e-12);
/// assert_eq!(project_to_cone(&Matrix3::identity()), Matrix3::identity());
/// ```
pub fn project_to_cone(p: &Matrix3<f64>) -> Matrix3<f64> {
    let (v, vectors) = sorted_eigen(p);
    if v[0] + v[1] >= 0.0 {
        return (p + p.transpose()) * 0.5;
    }
    // the projection of the eigenvalues onto the polyhedral cone {q_a + q_b >= 0}: the closest
    // feasible solution of the equality-constrained problems of the 7 nonempty active sets
    let pairs = [(0usize, 1usize), (0, 2), (1, 2)];
    let slack = 1e-12 * v.iter().map(|x| x.abs()).sum::<f64>();
    let mut best: Option<(f64, [f64; 3])> = None;
    for mask in 1u8..8 {
        let active = || {
            (pairs.iter().enumerate())
                .filter(move |(bit, _)| mask & (1 << bit) != 0)
                .map(|(_, &pair)| pair)
        };
        let k = mask.count_ones();
        // q = v - sum_c mu_c (e_a + e_b), with (e_a + e_b) . q = 0 for every active pair: the
        // Gram matrix of any k of the three pairs is I + 1 1^T (each pair has 2 indices and
        // shares exactly one with each other), whose inverse is I - 1 1^T / (1 + k)
        let share = active().map(|(a, b)| v[a] + v[b]).sum::<f64>() / f64::from(1 + k);
        let mut q = v;
        for (a, b) in active() {
            let mu = v[a] + v[b] - share;
            q[a] -= mu;
            q[b] -= mu;
        }
        let feasible = pairs.iter().all(|&(a, b)| q[a] + q[b] >= -slack);
        let distance: f64 = q.iter().zip(&v).map(|(x, y)| (x - y).powi(2)).sum();
        if feasible && best.is_none_or(|(d, _)| distance < d) {
            best = Some((distance, q));
        }
    }
    let q = best.map_or([0.0; 3], |(_, q)| q);
    let mut out = Matrix3::zeros();
    for (value, u) in q.iter().zip(&vectors) {
        out += u * u.transpose() * *value;
    }
    out
}

/// `B_e x = x_i - X_e^T x_j`.
fn apply_b(e: &Edge, x_e: &Matrix3<f64>, x: &[f64]) -> Vector3<f64> {
    let xi = Vector3::new(x[3 * e.i], x[3 * e.i + 1], x[3 * e.i + 2]);
    let xj = Vector3::new(x[3 * e.j], x[3 * e.j + 1], x[3 * e.j + 2]);
    xi - x_e.transpose() * xj
}

/// A violated constraint `v^T S'(P) v >= target`, linear in the `P_e`:
/// `v^T S v - 1/2 sum_e w_e^T P_e w_e`.
struct Cut {
    base: f64,
    w: Vec<Vector3<f64>>,
    norm_sq: f64,
}

impl Cut {
    fn value(&self, penalties: &[Matrix3<f64>]) -> f64 {
        let pen: f64 = self
            .w
            .iter()
            .zip(penalties)
            .map(|(w, p)| w.dot(&(p * w)))
            .sum();
        self.base - 0.5 * pen
    }
}

/// Rounds predicted for a search (searches that certify end within a few tens of rounds; the
/// others stop at their stall rule or their share of the time).
pub const TYPICAL_ROUNDS: f64 = 20.0;

/// The predicted cost of the search: [`TYPICAL_ROUNDS`] rounds of products with `S'` (at
/// most `time_fraction` of the time left, whatever the prediction), and its peak memory: the
/// Lanczos basis, the kept cuts and the multipliers.
pub fn predict_search(problem: &MultipleProblem, settings: &ConvDualSettings) -> Prediction {
    let dim = 3.0 * problem.num_rotations() as f64;
    let m = problem.num_edges() as f64;
    // a round: a Lanczos run of products with S' (36 values an edge, two flops each); a search
    // that certifies typically ends within TYPICAL_ROUNDS (it may spend up to
    // `time_fraction` of the time left)
    let round = settings.lanczos_iterations as f64 * 72.0 * m / PREDICTED_FLOP_RATE;
    Prediction::new(
        TYPICAL_ROUNDS * round,
        8.0 * (settings.lanczos_iterations as f64 + 8.0) * dim
            + 24.0 * m * settings.cuts_kept as f64
            // the multipliers, the frames' data, and the kept round's copy of the multipliers
            + 3.0 * 72.0 * m,
    )
}

/// The Ritz pairs of one round: `(lambda, vector)` estimates of the smallest eigenpairs of
/// `S'` on the complement of the null space, and whether Lanczos converged.
struct Ritz {
    pairs: Vec<(f64, Vec<f64>)>,
    converged: bool,
}

/// Search for multipliers `P_e` that make `S' = S - 1/2 sum B_e^T P_e B_e` positive
/// semidefinite at `rotations` (the estimate's own `S`): start at the edges' reflection prices,
/// then rounds of (a Lanczos run on `S'`, shift-inverted when its factor fits, deflated by the
/// estimate's null space `Y`; every Ritz vector of negative Ritz value becomes a cut; cyclic
/// projections onto the kept cuts, each followed by the projection onto `C`) until no negative
/// Ritz value is left (converged or not: the proof decides), `max_rounds`, a stall, or
/// `deadline` (checked before every factorisation: a round ends at most one factorisation past
/// it). The factor of the shift-invert rounds fits what `budget` leaves beside the search's own
/// memory ([`predict_search`]); above it the rounds use Lanczos on `S'` itself. Errors: an
/// isotropic problem, an estimate of the wrong size.
pub fn search_penalties(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &ConvDualSettings,
    deadline: Option<Instant>,
    budget: &Budget,
) -> Result<ConvSearch> {
    search_at(
        problem,
        rotations,
        settings,
        (deadline, budget),
        COARSE,
        None,
    )
}

/// [`search_penalties`] at the fine resolution, from the multipliers `start` (one per edge):
/// cuts ask for `1e-11` of the scale, Ritz values below `-1e-13` of it are cut and the
/// shift-invert shift goes down to `1e-13` of it, where the coarse search stops at `1e-9` and
/// shifts of `1e-6` (`[A11]` "Two resolutions"). For strongly anisotropic information, whose
/// multipliers' scale (`1.8e9` on a 5000-pose SLAM graph) is far above the eigenvalues of `S'`
/// that decide (about `-0.05` there). Errors: as [`search_penalties`], and `start` of the
/// wrong length.
pub fn refine_penalties(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &ConvDualSettings,
    (deadline, budget): (Option<Instant>, &Budget),
    start: &[Matrix3<f64>],
) -> Result<ConvSearch> {
    if start.len() != problem.num_edges() {
        return Err(Error::InvalidSettings {
            name: "penalties".into(),
            reason: format!(
                "{} multipliers for {} edges",
                start.len(),
                problem.num_edges()
            ),
        });
    }
    search_at(
        problem,
        rotations,
        settings,
        (deadline, budget),
        FINE,
        Some(start),
    )
}

/// The search's sizes relative to its scale (the largest of `||S||_inf` and the multipliers'
/// norms): cuts ask `v^T S' v >= target`, Ritz values below `-threshold` are cut (none left
/// ends the search), the shift-invert rounds' shift is at least `floor`.
#[derive(Debug, Clone, Copy)]
struct Resolution {
    target: f64,
    threshold: f64,
    floor: f64,
}

/// The first search's resolution.
const COARSE: Resolution = Resolution {
    target: 1e-6,
    threshold: 1e-9,
    floor: 1e-6,
};

/// The refinement's resolution ([`refine_penalties`]).
const FINE: Resolution = Resolution {
    target: 1e-11,
    threshold: 1e-13,
    floor: 1e-13,
};

/// The search at `resolution`, from `start` or the edges' reflection prices.
fn search_at(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &ConvDualSettings,
    (deadline, budget): (Option<Instant>, &Budget),
    resolution: Resolution,
    start: Option<&[Matrix3<f64>]>,
) -> Result<ConvSearch> {
    let clock = Instant::now();
    settings.validate()?;
    super::multipliers::check_rotations(problem, rotations)?;
    let frames = frames(problem, rotations)?;
    let initial: Vec<Matrix3<f64>> = frames
        .iter()
        .map(|f| match f.fixed {
            true => Matrix3::zeros(),
            false => initial_penalty(&f.k),
        })
        .collect();
    let lambdas = multipliers(problem, rotations)?;
    let s = certificate_matrix(problem, &lambdas)?;
    let s_scale = crate::linalg::cholesky::inf_norm(s.as_ref());
    let p_scale = initial.iter().map(|p| p.norm()).fold(0.0, f64::max);
    let scale = s_scale.max(p_scale).max(f64::MIN_POSITIVE);
    let mut penalties = start.map_or(initial, <[Matrix3<f64>]>::to_vec);
    let null = estimate_null_space(rotations);
    let edges = problem.edges();
    let max_values = shift_invert_max_values(problem, settings, &s, budget);
    let mut inverse = Inverse::new(&s, edges, max_values)?;
    let shift_invert = inverse.is_some();
    let rounds_of = Round {
        frames: &frames,
        null: &null,
        scale,
        resolution,
        settings,
        problem,
        rotations,
    };
    let (mut progress, stop) = rounds_of.run(&s, edges, inverse.as_mut(), &mut penalties, deadline);
    let (kept_round, estimated_bound) = match progress.kept.take() {
        Some(kept) => {
            penalties = kept.penalties;
            (kept.round, Some(kept.estimate))
        }
        None => (0, None),
    };
    Ok(ConvSearch {
        penalties,
        kept_round,
        estimated_bound,
        rounds: progress.rounds,
        shift_invert,
        cuts: progress.added,
        smallest_ritz_value: progress.smallest,
        stop,
        seconds: clock.elapsed().as_secs_f64(),
        refined: start.is_some(),
    })
}

/// The estimate's null space: the columns of `Y` (the stacked rotations), orthonormal after
/// `1 / sqrt(n)`.
fn estimate_null_space(rotations: &[Rotation]) -> Vec<Vec<f64>> {
    let n = rotations.len();
    let dim = 3 * n;
    (0..3)
        .map(|c| {
            let mut v = vec![0.0; dim];
            for (i, r) in rotations.iter().enumerate() {
                for a in 0..3 {
                    v[3 * i + a] = r.matrix()[(a, c)] / (n as f64).sqrt();
                }
            }
            v
        })
        .collect()
}

/// The shift-invert factor's size limit: within what the budget leaves beside the search's own
/// memory and the two copies of `S` it keeps (values and row indices: 16 bytes per stored
/// entry each), and at most [`ConvDualSettings::shift_invert_max_factor`].
pub(super) fn shift_invert_max_values(
    problem: &MultipleProblem,
    settings: &ConvDualSettings,
    s: &SparseColMat<usize, f64>,
    budget: &Budget,
) -> usize {
    let own = predict_search(problem, settings).bytes + 32.0 * s.val().len() as f64;
    let left = Budget {
        max_memory_bytes: (budget.max_memory_bytes as f64 - own).max(0.0) as u64,
        ..*budget
    };
    settings
        .shift_invert_max_factor
        .min(left.max_factor_values(3 * problem.num_rotations()))
}

/// The rounds of a search so far: their count, the last smallest Ritz value, the best one and
/// its round, the cuts added, and the penalties of the round with the largest estimated bound.
struct Progress {
    rounds: usize,
    smallest: Option<f64>,
    best: f64,
    best_round: usize,
    added: usize,
    kept: Option<Kept>,
}

/// The penalties a search returns: those of the round (1-based) whose estimated bound was the
/// largest ([`Round::estimated_bound`]), not the last round's, so that more rounds never return
/// worse penalties by that estimate.
struct Kept {
    round: usize,
    estimate: f64,
    penalties: Vec<Matrix3<f64>>,
}

impl Progress {
    fn new() -> Self {
        Progress {
            rounds: 0,
            smallest: None,
            best: f64::NEG_INFINITY,
            best_round: 0,
            added: 0,
            kept: None,
        }
    }

    /// Keep `penalties` (evaluated in the round just recorded) when their estimated bound is
    /// the largest so far.
    fn keep(&mut self, estimate: f64, penalties: &[Matrix3<f64>]) {
        if self.kept.as_ref().is_some_and(|k| k.estimate >= estimate) {
            return;
        }
        self.kept = Some(Kept {
            round: self.rounds,
            estimate,
            penalties: penalties.to_vec(),
        });
    }

    /// Count a round whose smallest Ritz value is `low`; `true` when the search has stalled:
    /// `stall_rounds` rounds without raising the best by `1e-3` of itself.
    fn record(&mut self, low: f64, stall_rounds: usize) -> bool {
        self.rounds += 1;
        self.smallest = Some(low);
        if self.best == f64::NEG_INFINITY || low > self.best + 1e-3 * self.best.abs() {
            self.best = low;
            self.best_round = self.rounds;
            false
        } else {
            self.rounds - self.best_round >= stall_rounds
        }
    }
}

/// Why the search stops after a round's Ritz pairs, if it does: none (no shift factored, or past
/// the deadline: no estimate to go on), or none below `-threshold` (converged or not: an
/// unconverged run would repeat itself, the multipliers being unchanged, so the proof decides).
fn ritz_stop(
    ritz: &Ritz,
    low: f64,
    threshold: f64,
    deadline: Option<Instant>,
) -> Option<ConvSearchStop> {
    if ritz.pairs.is_empty() {
        return Some(if deadline.is_some_and(|d| Instant::now() >= d) {
            ConvSearchStop::TimeLimit
        } else {
            ConvSearchStop::Stalled
        });
    }
    if !ritz.pairs.iter().any(|(v, _)| *v < -threshold) {
        return Some(ConvSearchStop::NoNegativeRitzValue {
            smallest: low,
            threshold,
            converged: ritz.converged,
        });
    }
    None
}

/// Cyclic projections onto the cuts `value >= target`, each pass followed by the projection of
/// every `P_e` onto `C`; at most `passes`, fewer when no cut is violated.
fn project_onto_cuts(penalties: &mut [Matrix3<f64>], cuts: &[Cut], target: f64, passes: usize) {
    for _ in 0..passes {
        let mut violated = false;
        for cut in cuts {
            let value = cut.value(penalties);
            if value >= target {
                continue;
            }
            violated = true;
            let alpha = 0.5 * (target - value) / cut.norm_sq;
            for (p, w) in penalties.iter_mut().zip(&cut.w) {
                *p -= w * w.transpose() * alpha;
            }
        }
        for p in penalties.iter_mut() {
            *p = project_to_cone(p);
        }
        if !violated {
            break;
        }
    }
}

fn lanczos_settings(settings: &ConvDualSettings) -> LanczosSettings {
    LanczosSettings {
        max_iterations: settings.lanczos_iterations,
        tolerance: 1e-6,
        block_size: 3,
        ..Default::default()
    }
}

/// What every round of the search reads: the edges' frames, the estimate's null space, the
/// scale and the settings.
struct Round<'a> {
    frames: &'a [Frame],
    null: &'a [Vec<f64>],
    scale: f64,
    resolution: Resolution,
    settings: &'a ConvDualSettings,
    problem: &'a MultipleProblem,
    rotations: &'a [Rotation],
}

impl Round<'_> {
    /// The rounds of [`search_penalties`] from `penalties` (improved in place), with the
    /// shift-invert factor when there is one.
    fn run(
        &self,
        s: &SparseColMat<usize, f64>,
        edges: &[Edge],
        mut inverse: Option<&mut Inverse>,
        penalties: &mut [Matrix3<f64>],
        deadline: Option<Instant>,
    ) -> (Progress, ConvSearchStop) {
        let settings = self.settings;
        let target = self.resolution.target * self.scale;
        let threshold = self.resolution.threshold * self.scale;
        let mut progress = Progress::new();
        let mut cuts: Vec<Cut> = Vec::new();
        while progress.rounds < settings.max_rounds {
            if deadline.is_some_and(|d| Instant::now() >= d) {
                return (progress, ConvSearchStop::TimeLimit);
            }
            let ritz = match inverse.as_deref_mut() {
                Some(inv) => self.inverse(inv, penalties, deadline),
                None => self.direct(s, edges, penalties),
            };
            let low = ritz.pairs.first().map_or(0.0, |p| p.0);
            let stalled = progress.record(low, settings.stall_rounds);
            // a round that did not raise the best Ritz value is not kept (its offsets, grown
            // with the penalties, rarely make up for it), and costs no surrogate
            if !ritz.pairs.is_empty() && progress.best_round == progress.rounds {
                progress.keep(self.estimated_bound(penalties, low), penalties);
            }
            if stalled {
                return (progress, ConvSearchStop::Stalled);
            }
            if let Some(stop) = ritz_stop(&ritz, low, threshold, deadline) {
                return (progress, stop);
            }
            for (_, v) in ritz.pairs.iter().filter(|(v, _)| *v < -threshold) {
                if let Some(cut) = self.cut(s, edges, v) {
                    cuts.push(cut);
                    progress.added += 1;
                }
            }
            if cuts.len() > settings.cuts_kept {
                cuts.drain(..cuts.len() - settings.cuts_kept);
            }
            project_onto_cuts(penalties, &cuts, target, settings.passes);
        }
        (progress, ConvSearchStop::RoundLimit)
    }

    /// The bound the penalties `P` would give if `low` were `lambda_min(S'(P))` (`[D4]`, `[A11]`):
    /// the surrogate's cost at the estimate, plus `3n min(low, 0)`, minus its offsets. An
    /// estimate (a Ritz value lies above the smallest eigenvalue), used only to choose which
    /// round's penalties the search returns; the bound itself is verified afterwards.
    /// Computed edge by edge as [`surrogate`] forms the data, without building or validating
    /// the surrogate problem (an edge whose surrogate data would be refused counts as there).
    fn estimated_bound(&self, penalties: &[Matrix3<f64>], low: f64) -> f64 {
        let Some(info) = self.problem.information() else {
            return f64::NEG_INFINITY;
        };
        let r = self.rotations;
        let mut total = 3.0 * r.len() as f64 * low.min(0.0);
        for (((e, h), f), p) in self
            .problem
            .edges()
            .iter()
            .zip(info)
            .zip(self.frames)
            .zip(penalties)
        {
            let gram = r[e.j].matrix() * r[e.i].matrix().transpose();
            let (data, h2) = if p.iter().all(|x| *x == 0.0) {
                (*e.rotation.matrix(), *h.matrix())
            } else {
                let (data, h2) = surrogate_edge(f, p);
                total -= edge_offset(e.rotation.matrix(), h.matrix(), &data, &h2, &f.x);
                (data, h2)
            };
            let m2 = Matrix3::identity() * (0.5 * h2.trace()) - h2;
            total += 4.0 * (m2.trace() - (data * m2).dot(&gram));
        }
        total
    }

    /// The cut of a Ritz vector `v` (`v^T S'(P) v >= target`), unless it does not depend on the
    /// penalties.
    fn cut(&self, s: &SparseColMat<usize, f64>, edges: &[Edge], v: &[f64]) -> Option<Cut> {
        let mut sv = vec![0.0; v.len()];
        sparse_matvec(s.as_ref(), v, &mut sv);
        let base: f64 = v.iter().zip(&sv).map(|(a, b)| a * b).sum();
        let w: Vec<Vector3<f64>> = edges
            .iter()
            .zip(self.frames)
            .map(|(e, f)| match f.fixed {
                true => Vector3::zeros(),
                false => apply_b(e, &f.x, v),
            })
            .collect();
        let norm_sq = 0.25 * w.iter().map(|x| x.norm_squared().powi(2)).sum::<f64>();
        (norm_sq > 0.0).then_some(Cut { base, w, norm_sq })
    }

    /// One round of Lanczos on `S'` itself.
    fn direct(
        &self,
        s: &SparseColMat<usize, f64>,
        edges: &[Edge],
        penalties: &[Matrix3<f64>],
    ) -> Ritz {
        let (frames, null, scale, settings) = (self.frames, self.null, self.scale, self.settings);
        let op = |x: &[f64], y: &mut [f64]| {
            sparse_matvec(s.as_ref(), x, y);
            for ((e, f), p) in edges.iter().zip(frames).zip(penalties) {
                let z = p * apply_b(e, &f.x, x) * 0.5;
                let zj = f.x * z;
                for a in 0..3 {
                    y[3 * e.i + a] -= z[a];
                    y[3 * e.j + a] += zj[a];
                }
            }
        };
        let dim = s.nrows();
        let est = lanczos(
            dim,
            op,
            Extreme::Smallest,
            6,
            scale,
            &lanczos_settings(settings),
            null,
            None,
        );
        Ritz {
            pairs: est.values.into_iter().zip(est.vectors).collect(),
            converged: est.stop.converged(),
        }
    }

    /// One round of shift-invert Lanczos: `S'(P) + sigma I` factorised (sigma from a quarter of the
    /// last round's, at least the resolution's floor times the scale, raised fourfold until it
    /// factors), its 12 largest inverse eigenvalues `theta` giving `lambda = 1 / theta - sigma`.
    fn inverse(
        &self,
        inv: &mut Inverse,
        penalties: &[Matrix3<f64>],
        deadline: Option<Instant>,
    ) -> Ritz {
        let settings = LanczosSettings {
            max_iterations: self.settings.lanczos_iterations.min(60),
            ..lanczos_settings(self.settings)
        };
        inv.assemble(self.frames, penalties);
        let floor = self.resolution.floor * self.scale;
        match inv.smallest((12, floor), (&settings, self.null), (12, deadline)) {
            Some((pairs, converged)) => Ritz { pairs, converged },
            // not factorisable with any shift tried, or past the deadline: no estimate
            None => Ritz {
                pairs: Vec::new(),
                converged: false,
            },
        }
    }
}

/// How far inside the cone `C` the stored surrogate's multipliers are moved: `P_e + (m / 2)
/// ||P_e||_F I` with `m = 1e-10`, so every pairwise sum of `P_e`'s eigenvalues is at least
/// `m ||P_e||_F`. On `C`'s boundary (the reflection price `beta (I - 2 u u^T)` lies there) the
/// rounding of the stored `R'_e`, `H'_e` (about `1e-15 ||P_e||`) turns into a loss of the same
/// size in each offset (`h(Q) - tr Q` grows linearly off the boundary); inside by `m` it is
/// second order, `2 |q|^2 / mu` (the framed bound of `[A11]` Statement 3). The shift lowers `S'` by at most
/// `m ||P_e|| / 4` per edge and, `P_e` staying in `C`, costs nothing at the estimate
/// (`[A11]` Statement 2).
pub const CONE_MARGIN: f64 = 1e-10;

/// The surrogate's data of one edge for multipliers `p` (`[A11]`, "The surrogate as stored"),
/// `p` first moved inside `C` by [`CONE_MARGIN`]: `(X_e U, tr(M') I - M')` from the polar
/// decomposition `K_e - P_e = U T`, `M' = T / 4` (the rotation before its validation).
fn surrogate_edge(f: &Frame, p: &Matrix3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let p = p + Matrix3::identity() * (0.5 * CONE_MARGIN * p.norm());
    let (u, t) = polar(&(f.k - p));
    let m = t * 0.25;
    let h2 = Matrix3::identity() * m.trace() - m;
    (f.x * u, (h2 + h2.transpose()) * 0.5)
}

/// The polar decomposition `J = U T` with `U` a rotation and `T` symmetric (indefinite when
/// `det J < 0`).
fn polar(j: &Matrix3<f64>) -> (Matrix3<f64>, Matrix3<f64>) {
    let svd = j.svd(true, true);
    let (mut u, v_t) = match (svd.u, svd.v_t) {
        (Some(u), Some(v_t)) => (u, v_t),
        _ => return (Matrix3::identity(), (j + j.transpose()) * 0.5),
    };
    let mut sigma = svd.singular_values;
    if (u * v_t).determinant() < 0.0 {
        let k = (0..3)
            .min_by(|&a, &b| sigma[a].total_cmp(&sigma[b]))
            .unwrap_or(2);
        for r in 0..3 {
            u[(r, k)] = -u[(r, k)];
        }
        sigma[k] = -sigma[k];
    }
    let t = v_t.transpose() * Matrix3::from_diagonal(&sigma) * v_t;
    (u * v_t, (t + t.transpose()) * 0.5)
}

/// Build the surrogate of `problem` at `rotations` for the multipliers `penalties` (one per
/// edge, in the estimate's frame), and the verified sum of its offsets. An edge whose
/// surrogate data are not valid (`H'_e` not positive semidefinite or a trace outside the
/// weight window, after rounding) keeps its own data (offset 0). Errors: an isotropic problem,
/// an estimate or multipliers of the wrong size.
pub fn surrogate(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    penalties: &[Matrix3<f64>],
) -> Result<Surrogate> {
    super::multipliers::check_rotations(problem, rotations)?;
    if penalties.len() != problem.num_edges() {
        return Err(Error::InvalidSettings {
            name: "penalties".into(),
            reason: format!(
                "{} multipliers for {} edges",
                penalties.len(),
                problem.num_edges()
            ),
        });
    }
    let info = anisotropic(problem)?;
    let frames = frames(problem, rotations)?;
    let mut edges = Vec::with_capacity(problem.num_edges());
    let mut infos = Vec::with_capacity(problem.num_edges());
    let mut offset = Accumulator::default();
    let mut magnitude = 0.0;
    for (((e, h), f), p) in problem.edges().iter().zip(info).zip(&frames).zip(penalties) {
        let keep = |edges: &mut Vec<Edge>, infos: &mut Vec<Information>| {
            edges.push(e.clone());
            infos.push(*h);
        };
        if p.iter().all(|x| *x == 0.0) {
            keep(&mut edges, &mut infos);
            continue;
        }
        let (data, hp) = surrogate_edge(f, p);
        let rotation = rotation_from_matrix(&data, DEFAULT_ROTATION_TOLERANCE, "surrogate");
        let (Ok(rotation), Ok(hp)) = (rotation, Information::new(hp)) else {
            keep(&mut edges, &mut infos);
            continue;
        };
        let edge = Edge {
            i: e.i,
            j: e.j,
            rotation,
            weight: e.weight,
        };
        let delta = edge_offset(
            e.rotation.matrix(),
            h.matrix(),
            edge.rotation.matrix(),
            hp.matrix(),
            &f.x,
        );
        offset.add_product(1.0, delta);
        magnitude += delta.abs();
        edges.push(edge);
        infos.push(hp);
    }
    let problem = MultipleProblem::new(problem.num_rotations(), edges)?.with_information(infos)?;
    let sum = offset.value() + offset.bound();
    Ok(Surrogate {
        problem,
        offset: sum + 4.0 * UNIT_ROUNDOFF * magnitude,
    })
}

/// The verified bound of the `conv(SO(3))` dual certificate at an estimate.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvDualBound {
    /// The proven lower bound on the minimum of the chordal cost over `SO(3)^n`: the
    /// surrogate's bound minus the verified offsets.
    pub lower_bound: f64,
    /// The surrogate's own verified bound (the `O(3)` ladder of [`super::verify`]).
    pub surrogate: VerifiedBound,
    /// The verified sum of the edges' offsets.
    pub offset: f64,
    /// The search that chose the multipliers.
    pub search: ConvSearch,
    /// The nodes' multipliers' shifts, where they gave the bound (`[A11]` "Node shifts").
    pub node_shifts: Option<NodeShifts>,
}

/// The spectral bundle over the edges' multipliers and shifts of the nodes' ones that ran
/// where the search did not certify (`[A11]` "Node shifts"; estimates, the bound verified).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NodeShifts {
    /// Rounds of the bundle.
    pub rounds: usize,
    /// Its estimate of the bound's gain over the search's multipliers
    /// (`sum tr(D_i) + 3n lambda_min`, from Ritz values, at the end less at the start).
    pub estimated_gain: f64,
}

/// The `conv(SO(3))` dual certificate's bound at `rotations` `[A11]`: the multipliers of
/// [`search_penalties`] (stopped at `deadline`), the [`surrogate`], its bound verified by the
/// `O(3)` ladder with `point` labelling the rungs, minus the verified offsets. Errors: an
/// isotropic problem, an estimate of the wrong size, invalid settings.
///
/// ```
/// use rotavg::certify::CertifySettings;
/// use rotavg::certify::log::Point;
/// use rotavg::certify::multiple::conv_dual::conv_dual_bound;
/// use rotavg::multiple::{Edge, MultipleProblem, anisotropic::Information};
/// use nalgebra::{Matrix3, Vector3};
/// // the O(3) relaxation's bound of this exact answer is -8 (a reflection); conv(SO(3)) proves 0
/// let edge = Edge { i: 0, j: 1, rotation: rotavg::Rotation::identity(), weight: 1.0 };
/// let h = Information::new(Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 4.0)))?;
/// let p = MultipleProblem::new(2, vec![edge])?.with_information(vec![h])?;
/// let r = [rotavg::Rotation::identity(); 2];
/// let b = conv_dual_bound(&p, &r, &CertifySettings::default(), Point::ConvDual, None)?;
/// assert!(b.lower_bound > -1e-9 && b.lower_bound <= 0.0);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn conv_dual_bound(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &crate::certify::settings::CertifySettings,
    point: crate::certify::log::Point,
    deadline: Option<Instant>,
) -> Result<ConvDualBound> {
    settings.validate()?;
    let clock = Deadline::start(&settings.budget);
    conv_dual_within(problem, rotations, settings, point, deadline, clock)
}

/// [`conv_dual_bound`] on a certification's clock `clock`, its search stopped at `deadline`.
pub(crate) fn conv_dual_within(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &crate::certify::settings::CertifySettings,
    point: crate::certify::log::Point,
    deadline: Option<Instant>,
    clock: Deadline,
) -> Result<ConvDualBound> {
    let within = (deadline, &settings.budget);
    let coarse = search_penalties(
        problem,
        rotations,
        &settings.dual.conv,
        deadline,
        &settings.budget,
    )?;
    let stopped_clean = matches!(coarse.stop, ConvSearchStop::NoNegativeRitzValue { .. });
    let cost = problem.chordal_cost(rotations).abs();
    let at = (rotations, cost);
    let first = verified_surrogate(problem, at, settings, (point, clock), coarse)?;
    let gap = settings
        .tolerance
        .resolve(problem.min_weight())
        .allowed_gap(cost);
    let past = || deadline.is_some_and(|d| Instant::now() >= d);
    if first.lower_bound >= cost - gap || past() {
        return Ok(first);
    }
    // the coarse search saw no negative Ritz value, yet its surrogate does not certify: the
    // eigenvalues that decide are below its resolution
    let best = if stopped_clean {
        let fine = refine_penalties(
            problem,
            rotations,
            &settings.dual.conv,
            within,
            &first.search.penalties,
        )?;
        let second = verified_surrogate(problem, at, settings, (point, clock), fine)?;
        if second.lower_bound > first.lower_bound {
            second
        } else {
            first
        }
    } else {
        first
    };
    if best.lower_bound >= cost - gap || past() {
        return Ok(best);
    }
    // still not certified: the nodes' multipliers join the search (`[A11]` "Node shifts")
    let shifted = with_node_shifts(
        problem,
        rotations,
        settings,
        (point, clock),
        (&best, deadline),
    )?;
    Ok(match shifted {
        Some(b) if b.lower_bound > best.lower_bound => b,
        _ => best,
    })
}

/// The surrogate of `search`'s multipliers at `rotations` (whose cost is `cost`, in absolute
/// value), its bound verified by the `O(3)` ladder, minus its verified offsets.
fn verified_surrogate(
    problem: &MultipleProblem,
    (rotations, cost): (&[Rotation], f64),
    settings: &crate::certify::settings::CertifySettings,
    (point, clock): (crate::certify::log::Point, Deadline),
    search: ConvSearch,
) -> Result<ConvDualBound> {
    let sur = surrogate(problem, rotations, &search.penalties)?;
    let lambdas = multipliers(&sur.problem, rotations)?;
    let scope = Scope {
        point,
        within: Proof::ConvDual,
        deadline: clock,
        refinement_follows: None,
    };
    let bound = super::verify::verify(
        &sur.problem,
        &lambdas,
        Some(rotations),
        cost,
        settings,
        scope,
        None,
    )?;
    Ok(less_offsets(bound, sur.offset, search, None))
}

/// The surrogate's verified `bound` less its verified `offset` (the subtraction's rounding
/// charged), with the search and the node shifts that chose the multipliers.
fn less_offsets(
    bound: VerifiedBound,
    offset: f64,
    search: ConvSearch,
    node_shifts: Option<NodeShifts>,
) -> ConvDualBound {
    let difference = bound.lower_bound - offset;
    ConvDualBound {
        lower_bound: difference - 2.0 * UNIT_ROUNDOFF * (bound.lower_bound.abs() + offset.abs()),
        surrogate: bound,
        offset,
        search,
        node_shifts,
    }
}

/// The bound of `search`'s multipliers with the nodes' `shifts` (`[A11]` "Node shifts"): the
/// surrogate of the search's multipliers, its bound verified from the surrogate's multipliers
/// at `rotations` plus the shifts (no estimate's null space: the shifts move it), minus the
/// verified offsets.
fn verified_shifted(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &crate::certify::settings::CertifySettings,
    (point, clock): (crate::certify::log::Point, Deadline),
    (search, shifts): (ConvSearch, super::conv_shifts::Shifts),
) -> Result<ConvDualBound> {
    let sur = surrogate(problem, rotations, &search.penalties)?;
    let lambdas: Vec<Matrix3<f64>> = multipliers(&sur.problem, rotations)?
        .iter()
        .zip(&shifts.shifts)
        .map(|(l, d)| l + d)
        .collect();
    let scope = Scope {
        point,
        within: Proof::ConvDual,
        deadline: clock,
        refinement_follows: None,
    };
    let bound = super::verify::multipliers_bound(&sur.problem, &lambdas, settings, scope, None)?;
    let node_shifts = NodeShifts {
        rounds: shifts.rounds,
        estimated_gain: shifts.value - shifts.start,
    };
    Ok(less_offsets(bound, sur.offset, search, Some(node_shifts)))
}

/// The bundle of `[A11]` "Node shifts" from the multipliers of `best`'s search, at most until
/// `deadline`: its verified bound, `None` when it could not run (its own memory over half the
/// budget, or no shift-invert factor within the rest) or gained nothing.
fn with_node_shifts(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &crate::certify::settings::CertifySettings,
    (point, clock): (crate::certify::log::Point, Deadline),
    (best, deadline): (&ConvDualBound, Option<Instant>),
) -> Result<Option<ConvDualBound>> {
    let conv = &settings.dual.conv;
    let frames = frames(problem, rotations)?;
    let s = certificate_matrix(problem, &multipliers(problem, rotations)?)?;
    // the bundle's own memory within half the budget, its factor within what is left
    let own = super::conv_shifts::predicted_bytes(problem.num_rotations(), s.val().len());
    if own > settings.budget.max_memory_bytes / 2 {
        return Ok(None);
    }
    let budget = Budget {
        max_memory_bytes: settings.budget.max_memory_bytes - own,
        ..settings.budget
    };
    let max_values = shift_invert_max_values(problem, conv, &s, &budget);
    let Some(inverse) = Inverse::new(&s, problem.edges(), max_values)? else {
        return Ok(None);
    };
    let floor = FINE.floor * crate::linalg::cholesky::inf_norm(s.as_ref());
    let start = &best.search.penalties;
    let Some(shifts) = super::conv_shifts::shift_nodes(
        inverse,
        (&frames, problem.edges()),
        start,
        floor,
        deadline,
    ) else {
        return Ok(None);
    };
    let search = best.search.clone();
    verified_shifted(
        problem,
        rotations,
        settings,
        (point, clock),
        (search, shifts),
    )
    .map(Some)
}

/// The `conv(SO(3))` dual certificate `[A11]` as a rung of a certification: at every point
/// once (the given estimate, its refinement, a better point found by another rung), modes
/// `auto` and `dual`, on anisotropic data with some indefinite `M` (on definite data a failed
/// `O(3)` certificate is outliers or noise far more often; the dense SDP of small graphs,
/// `[A6]`, is the rung there). The search for its multipliers may spend
/// `dual.conv.time_fraction` of the time left; the surrogate's bound is verified by the `O(3)`
/// checks, logged within it.
#[derive(Default)]
pub(crate) struct ConvDualRung {
    /// The points its search ran at, with their rotations.
    searched: Vec<(Point, Vec<Rotation>)>,
    /// The points it did not run at: within [`SAME_POINT`] of a searched one.
    skipped: Vec<Point>,
}

/// Two estimates are the same point for the search when every edge's relative rotation
/// `R_j R_i^T` differs by at most this much (Frobenius): a refinement's or a polished
/// rounding's few last digits, where the search would repeat itself (three searches of 4-7 s
/// each with the same bound on the 200-node graphs of `[A11]` "Node shifts"). The bound of any
/// point bounds the global minimum; skipping only saves the time.
pub const SAME_POINT: f64 = 1e-6;

/// `a` and `b` are the same point ([`SAME_POINT`]) on `problem`'s edges.
fn same_point(problem: &MultipleProblem, a: &[Rotation], b: &[Rotation]) -> bool {
    problem.edges().iter().all(|e| {
        let x = a[e.j].matrix() * a[e.i].matrix().transpose();
        let y = b[e.j].matrix() * b[e.i].matrix().transpose();
        (x - y).norm() <= SAME_POINT
    })
}

impl<'a> Rung<State<'a>> for ConvDualRung {
    fn proof(&self) -> Proof {
        Proof::ConvDual
    }

    fn plan(&mut self, cx: &State<'a>) -> Result<Plan> {
        let conv = &cx.settings.dual.conv;
        if !cx.reflective
            || !conv.enabled
            || !matches!(cx.settings.mode, CertifyMode::Auto | CertifyMode::Dual)
        {
            return Ok(Plan::Done);
        }
        let label = cx.current.label;
        if cx.conv_dual_at.contains(&label) || self.skipped.contains(&label) {
            return Ok(Plan::Wait);
        }
        let here = &cx.current.rotations;
        if let Some((at, _)) = (self.searched.iter()).find(|(_, r)| same_point(cx.problem, r, here))
        {
            self.skipped.push(label);
            return Ok(Plan::Skip(Refusal::NotApplicable {
                reason: format!(
                    "its search ran at {at}, the same point to {SAME_POINT:.0e} in every edge's \
                     relative rotation"
                ),
            }));
        }
        Ok(Plan::Run(predict_search(cx.problem, conv)))
    }

    fn attempt(&mut self, cx: &mut State<'a>) -> Result<Found> {
        let label = cx.current.label;
        cx.conv_dual_at.push(label);
        self.searched.push((label, cx.current.rotations.clone()));
        crate::progress::phase(crate::progress::Phase::Certify, || {
            format!(
                "conv(SO(3)) dual certificate at {label} ({} nodes)",
                cx.problem.num_rotations()
            )
        });
        let search = cx
            .deadline
            .share(cx.settings.dual.conv.time_fraction)
            .instant();
        let rotations = cx.current.rotations.clone();
        let b = conv_dual_within(
            cx.problem,
            &rotations,
            cx.settings,
            Point::ConvDual,
            search,
            cx.deadline,
        )?;
        cx.log.extend(b.surrogate.ladder.iter().cloned());
        let note = format!(
            "bound from the conv(SO(3)) multipliers recovered at {label} [A11] ({} rounds of their \
             search{}, those of round {} kept, {} cuts, stopped: {}): the O(3) certificate of the \
             penalised surrogate{}, lambda_min(S') >= {:.3e}, minus its verified offsets {:.6e}",
            b.search.rounds,
            if b.search.refined {
                " refined at the fine resolution"
            } else {
                ""
            },
            b.search.kept_round,
            b.search.cuts,
            b.search.stop,
            b.node_shifts.map_or(String::new(), |s| format!(
                " with its nodes' multipliers shifted ({} rounds of a spectral bundle, [A11] \
                 \"Node shifts\")",
                s.rounds
            )),
            b.surrogate.verified_min_eigenvalue,
            b.offset
        );
        cx.offer(Best {
            lower_bound: b.lower_bound,
            method: BoundMethod::Dual,
            point: Point::ConvDual,
            min_eigenvalue: b
                .surrogate
                .min_eigenvalue_estimate
                .or(Some(b.surrogate.verified_min_eigenvalue)),
            explanation: note.clone(),
            verified_min_eigenvalue: b.surrogate.verified_min_eigenvalue,
            shift: None,
            lambdas: None,
        });
        Ok(Found::proved(
            b.lower_bound,
            cx.certifies(b.lower_bound),
            note,
        ))
    }
}
