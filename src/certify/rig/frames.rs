//! A rig with every sensor held (`[H19]`): `J(F, S)` is the frames' view graph's chordal cost
//! plus the within-frame edges' cost, which `F` does not change; the view graph's certified
//! bound plus that constant bounds `J*`, less the rounding `rounding.rs` charges.

use super::state::RigState;
use crate::certify::log::Prediction;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, GraphCertifier, Handed, Plan, Rung};
use crate::error::Result;

/// The frames' bound as a rung: first, when every sensor is held.
pub(crate) struct FramesRung(pub(crate) Handed<GraphCertifier>);

impl<'a> Rung<RigState<'a>> for FramesRung {
    fn proof(&self) -> Proof {
        Proof::RigFrames
    }

    fn plan(&mut self, cx: &RigState<'a>) -> Result<Plan> {
        if self.0.done || !cx.problem.all_held() {
            return Ok(Plan::Done);
        }
        // the view graph's certification: a few sparse factorisations
        let size = (cx.problem.num_frames() + cx.problem.edges().len()) as f64;
        Ok(Plan::Run(Prediction::new(2e-6 * size, 2000.0 * size)))
    }

    fn attempt(&mut self, cx: &mut RigState<'a>) -> Result<Found> {
        self.0.done = true;
        let (graph, constant) = cx.problem.frame_graph(cx.sensors)?;
        let mut settings = cx.settings.clone();
        settings.budget.max_seconds = cx.left();
        let inner = (self.0.certify)(&graph, cx.frames, &settings)?;
        let Some(lb) = inner.lower_bound else {
            return Ok(Found::failed(format!(
                "the frames' view graph has no bound: {}",
                inner.explanation
            )));
        };
        let bound = super::rounding::rounding_floor(lb + constant, cx.total_weight());
        let note = format!(
            "the frames' view graph ({} edges) bounded by {} at {lb:.9e}, plus the within-frame \
             edges' {constant:.9e}, less rounding [H19]",
            graph.num_edges(),
            inner.method
        );
        let bound = cx.offer(bound, Proof::RigFrames, &note);
        Ok(Found::proved(bound, cx.certifies(bound), note))
    }
}
