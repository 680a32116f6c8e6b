//! The state of one certification of the gravity problem: the estimate, its cost, the best
//! verified bound and the one log.

use crate::certify::budget::Deadline;
use crate::certify::log::Attempt;
use crate::certify::proof::{BoundMethod, Proof};
use crate::certify::rung::climb_by_best_bound;
use crate::certify::settings::CertifySettings;
use crate::multiple::gravity::GravityProblem;
use crate::so3::Rotation;

/// The best verified bound so far.
pub(crate) struct Best {
    pub lower_bound: f64,
    pub proof: Proof,
    pub verified_min_eigenvalue: Option<f64>,
    pub note: String,
}

/// One certification's state.
pub(crate) struct GravityState<'a> {
    pub problem: &'a GravityProblem,
    /// The estimate, as given (never changed).
    pub rotations: &'a [Rotation],
    pub settings: &'a CertifySettings,
    pub deadline: Deadline,
    /// The estimate's cost and the gap the verdict allows there.
    pub cost: f64,
    pub allowed_gap: f64,
    pub best: Option<Best>,
    pub log: Vec<Attempt>,
    /// The family of the view graph's bound, when [`Proof::GravityRelaxed`] gave one.
    pub relaxed_method: Option<BoundMethod>,
}

impl GravityState<'_> {
    /// `lower_bound` certifies the estimate.
    pub fn certifies(&self, lower_bound: f64) -> bool {
        self.cost - lower_bound <= self.allowed_gap
    }

    /// Keep `lower_bound` (capped at the cost: `f* <= f(estimate)`) when it is the best so
    /// far; the capped value. A bound that is not finite is not kept.
    pub fn offer(&mut self, lower_bound: f64, proof: Proof, mu: Option<f64>, note: &str) -> f64 {
        if !lower_bound.is_finite() {
            return lower_bound;
        }
        let lb = lower_bound.min(self.cost);
        if self.best.as_ref().is_none_or(|b| lb > b.lower_bound) {
            self.best = Some(Best {
                lower_bound: lb,
                proof,
                verified_min_eigenvalue: mu,
                note: note.to_string(),
            });
        }
        lb
    }
}

climb_by_best_bound!(GravityState);
