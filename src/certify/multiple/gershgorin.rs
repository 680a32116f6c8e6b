//! Gershgorin's discs `[D8]` as the last check of a verification: always available, usually
//! weak. Claimed only when no check was kept out by the budget (then the checks that ran say
//! `S` is not provably positive semidefinite); otherwise its bound is reported, unclaimed, and
//! the verdict is `inconclusive` with the budget's reasons (issue 15).

use super::check::Check;
use super::verified::VerifiedBound;
use crate::certify::log::{Outcome, Prediction};
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::error::Result;
use crate::linalg::{gamma, gershgorin_lower_bound};

/// The Gershgorin check: a fallback, run once when no other check proved a bound.
#[derive(Default)]
pub(super) struct GershgorinCheck {
    done: bool,
}

impl GershgorinCheck {
    /// Gershgorin's bound on `lambda_min(S)` with the forming errors `[D6]`(b), `[A3]`.
    fn bound(cx: &Check<'_>) -> VerifiedBound {
        let mu = gershgorin_lower_bound(cx.s().as_ref())
            - 2.0 * gamma(cx.terms + 1) * cx.norm()
            - cx.forming;
        cx.bound_from_mu(mu, Proof::Gershgorin)
    }

    /// Gershgorin's bound marked as not claimed (no check fitted the budget), with the reasons.
    pub(super) fn unclaimed(cx: &Check<'_>) -> VerifiedBound {
        let mut b = Self::bound(cx);
        b.factorization_skipped = true;
        let cut = cx.notes().cut;
        b.budget_exceeded = Some(if cut {
            "not a critical point: the checks gave way to its refinement".into()
        } else {
            cx.budget_limited()
                .unwrap_or_else(|| "no proof fits the budget".into())
        });
        b
    }
}

impl<'a> Rung<Check<'a>> for GershgorinCheck {
    fn proof(&self) -> Proof {
        Proof::Gershgorin
    }

    fn plan(&mut self, cx: &Check<'a>) -> Result<Plan> {
        Ok(if self.done || cx.best.is_some() {
            Plan::Done
        } else {
            Plan::Fallback(Prediction::new(0.0, 0.0))
        })
    }

    fn attempt(&mut self, cx: &mut Check<'a>) -> Result<Found> {
        self.done = true;
        if cx.budget_limited().is_some() {
            // not claimed, not logged: the budget's refusals say why
            cx.unclaimed = Some(Self::unclaimed(cx));
            return Ok(Found::logged(Outcome::Refused(
                crate::certify::log::Refusal::NotNeeded,
            )));
        }
        let outcome = cx.offer(Self::bound(cx));
        Ok(Found::new(outcome, ""))
    }
}
