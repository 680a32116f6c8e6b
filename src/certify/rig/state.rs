//! The state of one rig certification: the estimate, its cost, the best bound, the one log.

use crate::certify::certificate::bound_at_most;
use crate::certify::proof::Proof;
use crate::certify::tally::{Tally, climb_by_tally};
use crate::rig::RigProblem;
use crate::so3::Rotation;
use crate::termination::SolverReport;

/// One certification's state.
pub(crate) struct RigState<'a> {
    pub problem: &'a RigProblem,
    pub frames: &'a [Rotation],
    pub sensors: &'a [Rotation],
    pub tally: Tally<'a>,
    /// A point of lower cost than the estimate found while bounding (the coupled bound's
    /// polish, `[H21]`), when one was.
    pub improvement: Option<crate::rig::RigSolution>,
}

impl RigState<'_> {
    /// Keep `lower_bound` (capped at the cost, at least 0 for scalar weights) when it is the
    /// best so far; the capped value.
    pub fn offer(&mut self, lower_bound: f64, proof: Proof, note: &str) -> f64 {
        // the trace form of data orthogonal only to rounding can be slightly negative (`[H24]`)
        let nonnegative = !self.problem.is_anisotropic();
        let lb = bound_at_most(lower_bound, self.tally.cost, nonnegative);
        self.tally.keep(lb, proof, None, note)
    }

    /// Keep `(frames, sensors)`, reached by `report`, when its cost is below the estimate's
    /// and any earlier improvement's.
    pub fn improve(&mut self, frames: Vec<Rotation>, sensors: Vec<Rotation>, report: SolverReport) {
        let cost = self.problem.cost(&frames, &sensors);
        let best = self
            .improvement
            .as_ref()
            .map_or(self.tally.cost, |s| s.cost);
        if cost < best {
            self.improvement = Some(crate::rig::RigSolution {
                frames,
                sensors,
                cost,
                report,
            });
        }
    }

    /// A lower bound on `J*` from a proven bound `lower` of one of `[H19]`'s reformulations
    /// of the rig's cost, less their rounding (`rounding.rs`): scalar weights or information.
    pub fn floor(&self, lower: f64) -> f64 {
        match self.problem.information() {
            Some(info) => super::rounding::information_floor(lower, info),
            None => super::rounding::rounding_floor(lower, self.total_weight()),
        }
    }

    /// The sum of the edges' weights.
    pub fn total_weight(&self) -> f64 {
        self.problem.edges().iter().map(|e| e.weight).sum()
    }
}

climb_by_tally!(RigState);
