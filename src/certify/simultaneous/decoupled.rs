//! The decoupled bound of the simultaneous problem (`paper-notes/conjugate.md`, `[H16]`):
//! `J(R, S) = f_R(R) + f_L(S R_1, ..., S R_n)` with `f_R`, `f_L` the chordal costs of the two
//! view graphs, and `S R_i` is a tuple of rotations, so `J* >= min f_R + min f_L`. Each graph
//! is solved from the estimate (`R_i`, and `S R_i` for the left one) by the chordal Newton-LM
//! and certified by the view graph's own certification (handed in by the entry point:
//! `certify_multiple`), within the time left, each with half of it. No dense matrix: the bound
//! of rigs beyond the dense certificate's size; tight when the two graphs' optima agree up to
//! one `S` (noise-free rigs), a gap otherwise (the coupling's cost).

use super::state::SimState;
use crate::certify::log::Prediction;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, GraphCertifier, Plan, Rung};
use crate::certify::settings::CertifyMode;
use crate::error::Result;
use crate::multiple::MultipleProblem;
use crate::multiple::MultipleSettings;
use crate::multiple::chordal::solve_chordal;
use crate::so3::Rotation;

/// The decoupled bound as the last rung of a simultaneous certification (modes `auto` and
/// `dual`; mode `sdp` is the SDP alone).
pub(crate) struct DecoupledRung {
    done: bool,
    certify: GraphCertifier,
}

impl DecoupledRung {
    /// The rung, certifying each graph with `certify`.
    pub(crate) fn new(certify: GraphCertifier) -> Self {
        DecoupledRung {
            done: false,
            certify,
        }
    }

    /// A proven lower bound on `graph`'s chordal minimum: its local minimum from `start`,
    /// certified within `seconds`; `None` (with the reason) when no bound was proven.
    fn graph_bound(
        &self,
        graph: &MultipleProblem,
        start: Vec<Rotation>,
        cx: &SimState<'_>,
        seconds: Option<f64>,
    ) -> Result<std::result::Result<f64, String>> {
        let local = solve_chordal(graph, start, &MultipleSettings::default(), None)?;
        let mut settings = cx.tally.settings.clone();
        settings.budget.max_seconds = seconds;
        let c = (self.certify)(graph, &local.rotations, &settings)?;
        Ok(c.lower_bound.ok_or(c.explanation))
    }
}

impl<'a> Rung<SimState<'a>> for DecoupledRung {
    fn proof(&self) -> Proof {
        Proof::SimultaneousDecoupled
    }

    fn plan(&mut self, cx: &SimState<'a>) -> Result<Plan> {
        if self.done || cx.tally.settings.mode == CertifyMode::Sdp {
            return Ok(Plan::Done);
        }
        // two local solves and two certifications of sparse view graphs
        let size = (cx.right.num_rotations() + cx.right.num_edges() + cx.left.num_edges()) as f64;
        Ok(Plan::Fallback(Prediction::new(4e-6 * size, 4000.0 * size)))
    }

    fn attempt(&mut self, cx: &mut SimState<'a>) -> Result<Found> {
        self.done = true;
        let half = cx.tally.deadline.left().map(|l| 0.5 * l.max(0.0));
        let right = self.graph_bound(cx.right, cx.rotations.to_vec(), cx, half)?;
        let left_start = cx.rotations.iter().map(|r| cx.s * r).collect();
        let rest = cx.tally.left();
        let left = self.graph_bound(cx.left, left_start, cx, rest)?;
        let (lr, ll) = match (right, left) {
            (Ok(a), Ok(b)) => (a, b),
            (Err(why), _) | (_, Err(why)) => {
                return Ok(Found::failed(format!("a graph has no bound: {why}")));
            }
        };
        let note = format!(
            "the two graphs' certified minima, decoupled [H16]: {lr:.9e} (right) + {ll:.9e} (left)"
        );
        let lb = cx.offer(lr + ll, Proof::SimultaneousDecoupled, f64::NAN, &note);
        Ok(Found::proved(lb, cx.tally.certifies(lb), note))
    }
}
