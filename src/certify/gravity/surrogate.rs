//! The held priors' tilted soft surrogate (`paper-notes/gravity.md` `[G12]`): soft priors
//! turned so that the estimate is their critical point
//! ([`crate::multiple::gravity::GravityProblem::tilted_surrogate`]), certified as a soft
//! problem (the view graph with a world node, by the multiple-averaging ladder; the entry point
//! hands the certifier in), less the surrogate's constant on the held problem's feasible set.
//! The certificate of the mixed problem; for full gravity, a fallback of the SO(2) one.

use super::state::GravityState;
use crate::certify::certificate::Certificate;
use crate::certify::log::Outcome;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Handed, Plan, Rung};
use crate::certify::settings::CertifySettings;
use crate::error::Result;
use crate::multiple::gravity::{GravityProblem, Stiffness};
use crate::so3::Rotation;

/// Certifies an estimate of a soft gravity problem (`certify_gravity`'s soft path).
pub(crate) type SoftCertifier =
    fn(&GravityProblem, &[Rotation], &CertifySettings) -> Result<Certificate>;

/// The surrogate's bound as a rung: run first for the mixed problem, as a fallback for full
/// gravity.
pub(crate) struct SurrogateRung(pub(crate) Handed<SoftCertifier>);

impl<'a> Rung<GravityState<'a>> for SurrogateRung {
    fn proof(&self) -> Proof {
        Proof::GravitySurrogate
    }

    fn plan(&mut self, cx: &GravityState<'a>) -> Result<Plan> {
        if self.0.done {
            return Ok(Plan::Done);
        }
        // the augmented view graph's certificate (3(n + 1), one more node)
        Ok(cx.mixed_first(cx.problem.priors().num_known()))
    }

    fn attempt(&mut self, cx: &mut GravityState<'a>) -> Result<Found> {
        self.0.done = true;
        let mut notes = Vec::new();
        let mut best = None;
        for stiffness in [Stiffness::Light, Stiffness::Stiff] {
            let found = self.attempt_with(cx, stiffness)?;
            notes.push(found.note.clone());
            if let Outcome::Proved {
                lower_bound,
                sufficient,
            } = found.outcome
            {
                if sufficient {
                    return Ok(Found::proved(lower_bound, true, notes.join("; ")));
                }
                best = Some(best.map_or(lower_bound, |b: f64| b.max(lower_bound)));
            }
        }
        Ok(match best {
            Some(lb) => Found::proved(lb, cx.tally.certifies(lb), notes.join("; ")),
            None => Found::failed(notes.join("; ")),
        })
    }
}

impl SurrogateRung {
    /// The bound of the surrogate of `stiffness` at the estimate, offered to the tally.
    fn attempt_with(&self, cx: &mut GravityState<'_>, stiffness: Stiffness) -> Result<Found> {
        let (surrogate, constant) = cx.problem.tilted_surrogate(cx.rotations, stiffness)?;
        let mut settings = cx.tally.settings.clone();
        settings.budget.max_seconds = cx.tally.left();
        let inner = (self.0.certify)(&surrogate, cx.rotations, &settings)?;
        let Some(lb) = inner.lower_bound else {
            return Ok(Found::failed(format!(
                "the tilted surrogate has no bound: {}",
                inner.explanation
            )));
        };
        // lb - constant, rounded down (one subtraction)
        let bound = (lb - constant) - (lb - constant).abs() * f64::EPSILON;
        let weight = surrogate.priors().weight().unwrap_or(f64::NAN);
        let note = format!(
            "the priors' tilted soft surrogate ({}, weight {weight:.3e}): its bound {lb:.9e} \
             ({}, by {}) less its constant {constant:.3e} on the held problem",
            stiffness.name(),
            inner.verdict,
            inner.method
        );
        let lb = cx.offer(
            bound,
            Proof::GravitySurrogate,
            inner.verified_min_eigenvalue,
            &note,
        );
        Ok(Found::proved(lb, cx.tally.certifies(lb), note))
    }
}
