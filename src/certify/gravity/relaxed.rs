//! The gravity problem's constraints dropped (`paper-notes/gravity.md`, `[G7]`): every
//! feasible point of the gravity problem is one of the view graph alone, so a proven lower
//! bound on the view graph's chordal minimum bounds the gravity problem's. The view graph is
//! solved from the estimate (the unconstrained chordal Newton-LM) and certified by the view
//! graph's own certification (the entry point hands it in: `certify_multiple`) within the time
//! left. The last fallback (the mixed problem is certified by the tilted surrogate `[G12]`,
//! full gravity by the SO(2) certificate).

use super::state::GravityState;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, GraphCertifier, Handed, Plan, Rung};
use crate::error::Result;
use crate::multiple::chordal::solve_chordal;
use crate::multiple::{MultipleSettings, fix_gauge};

/// The relaxed bound as a rung: run first for the mixed problem (beside the surrogate), as
/// the fallback for full gravity.
pub(crate) struct RelaxedRung(pub(crate) Handed<GraphCertifier>);

impl<'a> Rung<GravityState<'a>> for RelaxedRung {
    fn proof(&self) -> Proof {
        Proof::GravityRelaxed
    }

    fn plan(&mut self, cx: &GravityState<'a>) -> Result<Plan> {
        if self.0.done {
            return Ok(Plan::Done);
        }
        // a local solve and the view graph's certification
        Ok(cx.mixed_first(0))
    }

    fn attempt(&mut self, cx: &mut GravityState<'a>) -> Result<Found> {
        self.0.done = true;
        let graph = cx.problem.problem();
        // within the certification's time left (one clock)
        let local = MultipleSettings {
            max_seconds: cx.tally.left(),
            ..Default::default()
        };
        let mut free = solve_chordal(graph, cx.rotations.to_vec(), &local, None)?;
        fix_gauge(&mut free.rotations);
        let mut settings = cx.tally.settings.clone();
        settings.budget.max_seconds = cx.tally.left();
        let inner = (self.0.certify)(graph, &free.rotations, &settings)?;
        let Some(lb) = inner.lower_bound else {
            return Ok(Found::failed(format!(
                "the view graph alone has no bound: {}",
                inner.explanation
            )));
        };
        let note = format!(
            "the view graph without its priors: local minimum {:.9e} ({}), its bound by {}",
            free.cost, inner.verdict, inner.method
        );
        let lb = cx.offer(
            lb,
            Proof::GravityRelaxed,
            inner.verified_min_eigenvalue,
            &note,
        );
        cx.relaxed_method = Some(inner.method);
        Ok(Found::proved(lb, cx.tally.certifies(lb), note))
    }
}
