//! The state of one certification of the simultaneous problem: the joint estimate, its cost,
//! the best verified bound, the improvement (a cheaper SDP rounding) and the one log.

use crate::certify::budget::Deadline;
use crate::certify::certificate::nonnegative_bound_at_most;
use crate::certify::certification::SdpSummary;
use crate::certify::log::Attempt;
use crate::certify::proof::Proof;
use crate::certify::rung::climb_by_best_bound;
use crate::certify::settings::CertifySettings;
use crate::multiple::MultipleProblem;
use crate::relax::simultaneous::JointRotations;
use crate::so3::Rotation;

/// The best verified bound so far.
pub(crate) struct Best {
    pub lower_bound: f64,
    pub proof: Proof,
    pub verified_min_eigenvalue: f64,
    pub note: String,
}

/// One certification's state.
pub(crate) struct SimState<'a> {
    pub right: &'a MultipleProblem,
    pub left: &'a MultipleProblem,
    pub rotations: &'a [Rotation],
    pub s: &'a Rotation,
    pub settings: &'a CertifySettings,
    pub deadline: Deadline,
    /// The joint estimate's cost and the gap the verdict allows there.
    pub cost: f64,
    pub allowed_gap: f64,
    pub best: Option<Best>,
    pub improvement: Option<JointRotations>,
    pub sdp: Option<SdpSummary>,
    pub log: Vec<Attempt>,
}

impl SimState<'_> {
    /// `lower_bound` certifies the estimate.
    pub fn certifies(&self, lower_bound: f64) -> bool {
        self.cost - lower_bound <= self.allowed_gap
    }

    /// Keep `lower_bound` (capped: at least 0, at most the cost, the joint cost being a sum of
    /// nonnegative terms) when it is the best so far; the capped value.
    pub fn offer(
        &mut self,
        lower_bound: f64,
        proof: Proof,
        verified_min_eigenvalue: f64,
        note: &str,
    ) -> f64 {
        let lb = nonnegative_bound_at_most(lower_bound, self.cost);
        if self.best.as_ref().is_none_or(|b| lb > b.lower_bound) {
            self.best = Some(Best {
                lower_bound: lb,
                proof,
                verified_min_eigenvalue,
                note: note.to_string(),
            });
        }
        lb
    }
}

climb_by_best_bound!(SimState);
