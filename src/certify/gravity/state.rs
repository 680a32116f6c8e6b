//! The state of one certification of the gravity problem: the estimate, its cost, the best
//! verified bound and the one log.

use crate::certify::log::Prediction;
use crate::certify::proof::{BoundMethod, Proof};
use crate::certify::rung::Plan;
use crate::certify::tally::{Tally, climb_by_tally};
use crate::multiple::gravity::GravityProblem;
use crate::so3::Rotation;

/// One certification's state.
pub(crate) struct GravityState<'a> {
    pub problem: &'a GravityProblem,
    /// The estimate, as given (never changed).
    pub rotations: &'a [Rotation],
    pub tally: Tally<'a>,
    /// The family of the view graph's bound, when [`Proof::GravityRelaxed`] gave one.
    pub relaxed_method: Option<BoundMethod>,
}

impl GravityState<'_> {
    /// Keep `lower_bound` (capped at the cost: `f* <= f(estimate)`) when it is the best so
    /// far; the capped value. A bound that is not finite is not kept.
    pub fn offer(&mut self, lower_bound: f64, proof: Proof, mu: Option<f64>, note: &str) -> f64 {
        if !lower_bound.is_finite() {
            return lower_bound;
        }
        let lb = lower_bound.min(self.tally.cost);
        self.tally.keep(lb, proof, mu, note)
    }

    /// The plan of a rung that certifies a view graph of the problem's images and edges and
    /// `extra` more edges (a few sparse factorisations): run first for the mixed problem, a
    /// fallback for full gravity (whose planar rung comes first).
    pub fn mixed_first(&self, extra: usize) -> Plan {
        let g = self.problem.problem();
        let size = (g.num_rotations() + g.num_edges() + extra) as f64;
        let predicted = Prediction::new(2e-6 * size, 2000.0 * size);
        if self.problem.priors().is_full() {
            Plan::Fallback(predicted)
        } else {
            Plan::Run(predicted)
        }
    }
}

climb_by_tally!(GravityState);
