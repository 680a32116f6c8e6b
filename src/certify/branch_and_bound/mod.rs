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

use crate::certify::certification::ImprovementSource;
pub use crate::certify::evidence::{BranchAndBoundStats, BranchAndBoundStop};
use crate::certify::log::{Prediction, Refusal};
use crate::certify::one_rotation::{Bound, RotationState};
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
pub use crate::certify::settings::BranchAndBoundSettings;
use crate::certify::settings::CertifyMode;
use crate::error::Result;

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

/// Seconds predicted per term and cell (each cell costs one pass over the terms, about 0.1 us
/// per term) and the cells of a typical search (a few thousand).
pub const SECONDS_PER_TERM_CELL: f64 = 1e-7;

/// See [`SECONDS_PER_TERM_CELL`].
pub const TYPICAL_CELLS: f64 = 4000.0;

/// The branch and bound over SO(3) `[B1]`-`[B6]` as a rung of a single or conjugate
/// certification: mode `branch_and_bound` always, mode `auto` for problems of at most
/// `branch_and_bound.auto_max_terms` terms; once. Its search stops at the time left.
pub(crate) struct BranchAndBoundRung<'t, T> {
    terms: &'t T,
    /// Terms of the problem (samples, pairs).
    len: usize,
    done: bool,
}

impl<'t, T> BranchAndBoundRung<'t, T> {
    /// The rung over `terms`, `len` of them.
    pub fn new(terms: &'t T, len: usize) -> Self {
        BranchAndBoundRung {
            terms,
            len,
            done: false,
        }
    }
}

impl<'a, T: search::Terms> Rung<RotationState<'a, T::Solution>> for BranchAndBoundRung<'_, T> {
    fn proof(&self) -> Proof {
        Proof::BranchAndBound
    }

    fn plan(&mut self, cx: &RotationState<'a, T::Solution>) -> Result<Plan> {
        let settings = cx.settings;
        if self.done
            || !matches!(
                settings.mode,
                CertifyMode::Auto | CertifyMode::BranchAndBound
            )
        {
            return Ok(Plan::Done);
        }
        let max = settings.branch_and_bound.auto_max_terms;
        if settings.mode == CertifyMode::Auto && self.len > max {
            let reason = format!(
                "{} terms > branch_and_bound.auto_max_terms = {max} (use mode branch_and_bound)",
                self.len
            );
            return Ok(Plan::Refuse(Refusal::NotApplicable { reason }, None));
        }
        let seconds = SECONDS_PER_TERM_CELL * TYPICAL_CELLS * self.len as f64;
        Ok(Plan::Run(Prediction::new(seconds, 0.0)))
    }

    fn attempt(&mut self, cx: &mut RotationState<'a, T::Solution>) -> Result<Found> {
        self.done = true;
        crate::progress::phase(crate::progress::Phase::Certify, || {
            format!("branch and bound over SO(3), {} terms", self.len)
        });
        let run = if self.terms.data_slack().is_finite() {
            let out = search::search(
                self.terms,
                &cx.estimate,
                cx.cost,
                cx.tolerance,
                &cx.settings.branch_and_bound,
                cx.deadline.left().map(|l| l.max(0.0)),
            );
            searched(out, cx.cost)
        } else {
            unproven_data(cx.cost)
        };
        cx.branch_and_bound = Some(run.stats);
        if let Some((s, c)) = run.improvement {
            cx.improve(s, c, ImprovementSource::BranchAndBound);
        }
        let lb = cx.offer(Bound {
            lower_bound: run.lower_bound,
            proof: Proof::BranchAndBound,
            explanation: run.explanation.clone(),
            min_eigenvalue: None,
            verified_min_eigenvalue: None,
            spectrum: None,
        });
        Ok(Found::proved(lb, cx.certifies(lb), run.explanation))
    }
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
