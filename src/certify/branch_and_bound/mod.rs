//! Branch and bound over SO(3) (`paper-notes/branch_and_bound.md`, `[B1]`-`[B6]`): a proven
//! lower bound on the global minimum of every single- and conjugate-averaging cost (one unknown
//! rotation), whatever the metric and loss.
//!
//! - `profile.rs`: `h(theta) = rho(d(theta))` with bounds on `h'` and `h''`;
//! - `bound.rs`: the bound of a geodesic ball from its centre (`[B2]` Lipschitz per term, `[B3]`
//!   first order, `[B4]` samples at the centre, `[B6]` rounding);
//! - `search.rs`: best-first search over axis-angle cubes (`[B1]`), with a ball around each
//!   incumbent (`[B5]`);
//! - `terms.rs`: the samples / pairs of the two problems.
//!
//! The verdict comes from [`crate::Certificate::from_bounds`] like every other method.

pub(crate) mod bound;
pub(crate) mod profile;
pub(crate) mod search;
pub(crate) mod terms;

use crate::certify::certificate::{BoundMethod, nonnegative_bound_at_most};
use crate::certify::certification::{CertifyDetails, MethodRun};
use crate::error::Result;
use crate::validate::at_least_one;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Instant;

/// Settings of the branch and bound (`CertifySettings::branch_and_bound`); its time limit is
/// `CertifySettings::budget.max_seconds`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct BranchAndBoundSettings {
    /// Largest number of cells bounded (default 2 000 000; >= 1).
    pub max_cells: usize,
    /// The axis-angle cube `[-pi, pi]^3` is first split into `k^3` cells (default 4; >= 1; measured on 10^4 samples with outliers: k = 4 bounds 15 % fewer cells than k = 8).
    pub initial_divisions: usize,
    /// Largest number of local solves started from cell centres that beat the incumbent
    /// (default 16).
    pub max_local_solves: usize,
    /// Mode `auto` falls back to the branch and bound only for problems with at most this many
    /// samples / pairs (default 20 000: each cell costs one pass over the terms, ~0.1 us per
    /// term, and a search bounds a few thousand cells); mode `branch_and_bound` has no limit.
    pub auto_max_terms: usize,
}

impl Default for BranchAndBoundSettings {
    fn default() -> Self {
        BranchAndBoundSettings {
            max_cells: 2_000_000,
            initial_divisions: 4,
            max_local_solves: 16,
            auto_max_terms: 20_000,
        }
    }
}

impl BranchAndBoundSettings {
    /// Check every value; [`crate::Error::InvalidSettings`] names the first bad one.
    ///
    /// ```
    /// use rotavg::certify::BranchAndBoundSettings;
    /// assert!(BranchAndBoundSettings::default().validate().is_ok());
    /// let bad = BranchAndBoundSettings { max_cells: 0, ..Default::default() };
    /// assert!(bad.validate().unwrap_err().to_string().contains("max_cells"));
    /// ```
    pub fn validate(&self) -> Result<()> {
        at_least_one("branch_and_bound.max_cells", self.max_cells)?;
        at_least_one("branch_and_bound.initial_divisions", self.initial_divisions)
    }
}

/// Why the branch and bound stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BranchAndBoundStop {
    /// Every cell was bounded within the tolerance of the best cost found.
    #[default]
    Converged,
    /// `max_cells` cells were bounded.
    CellBudget,
    /// The time budget (`budget.max_seconds`) ran out.
    TimeBudget,
    /// A cell to split was below the resolution of the floating-point margins.
    Resolution,
    /// Not searched: the data margin `[B6]` has no proof (quaternion metric, samples that are
    /// rotations only to the validation tolerance); the bound is the trivial 0.
    UnprovenData,
}

impl fmt::Display for BranchAndBoundStop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BranchAndBoundStop::Converged => "converged",
            BranchAndBoundStop::CellBudget => "cell budget",
            BranchAndBoundStop::TimeBudget => "time budget",
            BranchAndBoundStop::Resolution => "resolution limit",
            BranchAndBoundStop::UnprovenData => "unproven data margin",
        })
    }
}

/// What a branch and bound did (in the certificate's JSON as `branch_and_bound`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct BranchAndBoundStats {
    /// Cells whose bound was computed.
    pub cells_explored: usize,
    /// Cells discarded because their bound reached the best cost minus half the tolerance.
    pub cells_pruned: usize,
    /// Cells discarded because they lie in a ball around an incumbent (`[B5]`).
    pub cells_in_balls: usize,
    /// Cells still open when the search stopped (0 when converged).
    pub live_cells: usize,
    /// Deepest level of subdivision reached (0: the initial cells).
    pub max_depth: u32,
    /// Radius (rad) of the ball around the estimate bounded at once (`[B5]`; 0 if none).
    pub ball_radius: f64,
    /// Local solves started from cell centres.
    pub local_solves: usize,
    /// The proven lower bound of the global minimum.
    pub lower_bound: f64,
    /// The best cost seen (estimate, cell centres, local solves).
    pub best_cost: f64,
    /// Why it stopped.
    pub stop: BranchAndBoundStop,
    /// Wall time, seconds.
    pub seconds: f64,
}

impl fmt::Display for BranchAndBoundStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "branch and bound ({}): {} cells bounded, {} pruned, {} in the incumbent balls, {} open, depth {}, ball radius {:.3e} rad, {} local solves, {:.3} s",
            self.stop,
            self.cells_explored,
            self.cells_pruned,
            self.cells_in_balls,
            self.live_cells,
            self.max_depth,
            self.ball_radius,
            self.local_solves,
            self.seconds
        )
    }
}

/// A branch and bound run for an estimate: the proven bound, what it did, a better local
/// solution if one was found, and a sentence for the certificate.
pub(crate) struct Run<S> {
    /// Proven lower bound of the global minimum.
    pub lower_bound: f64,
    /// Statistics.
    pub stats: BranchAndBoundStats,
    /// A local solution of lower cost than the estimate, with its cost.
    pub improvement: Option<(S, f64)>,
    /// What happened, in words.
    pub explanation: String,
}

/// The time left of `budget` after `elapsed` seconds.
fn remaining(settings: &crate::certify::CertifySettings, elapsed: f64) -> Option<f64> {
    settings.budget.max_seconds.map(|t| (t - elapsed).max(0.0))
}

/// Branch and bound over the terms of a single- or conjugate-averaging problem
/// ([`terms::SingleTerms`], [`terms::ConjugateTerms`]) from `estimate` (cost `cost`), as a
/// method of its certification, which started at `start`: the tolerance is resolved with the
/// problem's smallest weight `min_weight`, the time limit is what `settings.budget` leaves. The
/// bound (at least 0, at most `cost`: [`nonnegative_bound_at_most`]), the time and the note of
/// the run are recorded in `details` (certifying when within the tolerance), with its
/// statistics. Returns the run and that bound.
pub(crate) fn run<T: search::Terms>(
    terms: &T,
    estimate: &crate::so3::Rotation,
    cost: f64,
    min_weight: f64,
    settings: &crate::certify::CertifySettings,
    start: Instant,
    details: &mut CertifyDetails,
) -> (Run<T::Solution>, f64) {
    let t = Instant::now();
    let tolerance = settings.tolerance.resolve(min_weight);
    let run = if terms.data_slack().is_finite() {
        let out = search::search(
            terms,
            estimate,
            cost,
            tolerance,
            &settings.branch_and_bound,
            remaining(settings, start.elapsed().as_secs_f64()),
        );
        searched(out, cost)
    } else {
        unproven_data(cost)
    };
    let lb = nonnegative_bound_at_most(run.lower_bound, cost);
    let method = MethodRun {
        method: BoundMethod::BranchAndBound,
        lower_bound: Some(lb),
        seconds: t.elapsed().as_secs_f64(),
        note: run.explanation.clone(),
    };
    details.record(method, cost - lb <= tolerance.allowed_gap(cost));
    details.branch_and_bound = Some(run.stats);
    (run, lb)
}

/// The run not searched because the data margin `[B6]` has no proof (the estimate's cost is
/// `cost`): every term is >= 0, so 0 is the only bound claimed.
fn unproven_data<S>(cost: f64) -> Run<S> {
    Run {
        lower_bound: 0.0,
        stats: BranchAndBoundStats {
            best_cost: cost,
            stop: BranchAndBoundStop::UnprovenData,
            ..Default::default()
        },
        improvement: None,
        explanation: "branch and bound not run [B6]: some samples are rotations only to the validation tolerance, and the quaternion distance of such a matrix has no proven perturbation bound; the lower bound is the trivial 0 (project the data onto SO(3), or use another metric)".into(),
    }
}

/// The run of a search from an estimate of cost `cost`, with its sentence.
fn searched<S>(out: search::Outcome<S>, cost: f64) -> Run<S> {
    // An improvement must be better beyond rounding (a tie is no improvement).
    let improvement = out
        .best
        .filter(|(_, c)| cost - c > 1e-12 * cost.abs().max(1e-300));
    let explanation = format!(
        "branch and bound over SO(3) [B1]-[B6]: proven lower bound {:.9e} of the global minimum; {}{}",
        out.lower_bound,
        out.stats,
        match &improvement {
            Some((_, c)) => format!(
                "; a local solve from a cell centre reached cost {c:.9e}, below the estimate's"
            ),
            None => String::new(),
        }
    );
    Run {
        lower_bound: out.lower_bound,
        stats: out.stats,
        improvement,
        explanation,
    }
}

/// Every metric x loss (thresholds 20 and 15 degrees): the objectives the unit tests of the
/// bounds run over.
#[cfg(test)]
pub(crate) fn test_objectives() -> Vec<crate::objective::Objective> {
    use crate::objective::{Loss, Objective};
    use crate::so3::Metric;
    let mut v = Vec::new();
    for m in [Metric::Geodesic, Metric::Chordal, Metric::Quaternion] {
        for l in [
            Loss::L1,
            Loss::L2,
            Loss::Huber {
                threshold_deg: 20.0,
            },
            Loss::Cauchy { scale_deg: 15.0 },
        ] {
            v.push(Objective::new(m, l));
        }
    }
    v
}
