//! The state of one certification of the simultaneous problem: the joint estimate, its cost,
//! the best verified bound, the improvement (a cheaper SDP rounding) and the one log.

use crate::certify::certificate::bound_at_most;
use crate::certify::certification::SdpSummary;
use crate::certify::proof::Proof;
use crate::certify::simultaneous::multipliers::PointTerms;
use crate::certify::tally::{Tally, climb_by_tally};
use crate::multiple::MultipleProblem;
use crate::relax::simultaneous::JointRotations;
use crate::so3::Rotation;

/// One certification's state.
pub(crate) struct SimState<'a> {
    pub right: &'a MultipleProblem,
    pub left: &'a MultipleProblem,
    pub rotations: &'a [Rotation],
    pub s: &'a Rotation,
    pub tally: Tally<'a>,
    pub improvement: Option<JointRotations>,
    pub sdp: Option<SdpSummary>,
    /// The `conv(SO(3))` surrogate's certificate ran (`[H27]`): the dual certificate of the
    /// problem itself is then not tried.
    pub conv_ran: bool,
}

impl SimState<'_> {
    /// What complementary slackness reads off the estimate; `None` when it does not fit the
    /// graphs.
    pub fn point_terms(&self) -> Option<PointTerms> {
        PointTerms::new(self.right, self.left, self.rotations, self.s)
    }

    /// Keep `lower_bound` (capped at the cost; at least 0 with scalar weights, where the joint
    /// cost is a sum of nonnegative terms, not with information: `[A1]`'s trace form can be
    /// negative, [`bound_at_most`]) when it is the best so far; the capped value.
    pub fn offer(&mut self, lower_bound: f64, proof: Proof, mu: f64, note: &str) -> f64 {
        let nonnegative = !(self.right.is_anisotropic() || self.left.is_anisotropic());
        let lb = bound_at_most(lower_bound, self.tally.cost, nonnegative);
        self.tally.keep(lb, proof, Some(mu), note)
    }
}

climb_by_tally!(SimState);
