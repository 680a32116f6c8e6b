//! The SO(2) dual certificate `[G3]` as a rung of the gravity ladder: on large graphs its
//! `lambda_min(S)` is proven first by the scalar comparison `[G9]` (`scalar.rs`), else (or when
//! that does not certify) by the shifted Cholesky of `S`'s real form (`planar.rs`), and when
//! that charges too much, with `S`'s null space deflated by a ground `[G17]` (`grounded.rs`).

use super::grounded::verify_planar_grounded;
use super::planar::{PlanarForm, verify_planar};
use super::scalar::verify_planar_scalar;
use super::state::GravityState;
use crate::certify::log::{Prediction, Refusal};
use crate::certify::multiple::multipliers::data_defect;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifyMode;
use crate::error::Result;

/// The planar dual certificate as a rung (full gravity only; modes `auto` and `dual`).
#[derive(Default)]
pub(crate) struct PlanarRung {
    done: bool,
}

impl<'a> Rung<GravityState<'a>> for PlanarRung {
    fn proof(&self) -> Proof {
        Proof::GravityDual
    }

    fn plan(&mut self, cx: &GravityState<'a>) -> Result<Plan> {
        if self.done {
            return Ok(Plan::Done);
        }
        if !cx.problem.priors().is_full() {
            let reason = "some images have no gravity prior (the mixed problem has no SO(2) form)";
            return Ok(Plan::Refuse(
                Refusal::NotApplicable {
                    reason: reason.into(),
                },
                None,
            ));
        }
        if !matches!(
            cx.tally.settings.mode,
            CertifyMode::Auto | CertifyMode::Dual
        ) {
            let reason = format!(
                "the gravity problem is certified by its SO(2) dual certificate (modes auto \
                 and dual), not {}",
                cx.tally.settings.mode.name()
            );
            return Ok(Plan::Refuse(Refusal::NotApplicable { reason }, None));
        }
        // a sparse factorisation of 2n x 2n: about what the multiple problem's dual costs
        let n = cx.problem.problem().num_rotations() as f64;
        let m = cx.problem.problem().num_edges() as f64;
        Ok(Plan::Run(Prediction::new(2e-7 * (n + m), 400.0 * (n + m))))
    }

    fn attempt(&mut self, cx: &mut GravityState<'a>) -> Result<Found> {
        self.done = true;
        let Some(form) = PlanarForm::new(cx.problem) else {
            return Ok(Found::failed("some image has no gravity prior"));
        };
        let standard = cx.problem.to_standard(cx.rotations);
        let x = PlanarForm::phases(cx.problem, &standard);
        // on large graphs the scalar comparison [G9] first: one n x n factor
        let graph_defect = data_defect(cx.problem.problem());
        let gaps = (cx.tally.allowed_gap, graph_defect);
        let first = verify_planar_scalar(&form, &x, gaps, cx.tally.settings, &cx.tally.deadline)?;
        let mut tried = String::new();
        match first {
            Some(Ok(b)) => {
                let note = format!(
                    "SO(2) multipliers at the estimate verified by the scalar comparison [G9], \
                     lambda_min(S) >= {:.3e}",
                    b.verified_min_eigenvalue
                );
                let mu = Some(b.verified_min_eigenvalue);
                let lb = cx.offer(b.lower_bound, Proof::GravityDual, mu, &note);
                if cx.tally.certifies(lb) {
                    return Ok(Found::proved(lb, true, note));
                }
                tried = format!("{note}, not enough; ");
            }
            Some(Err(why)) => tried = format!("scalar comparison [G9]: {why}; "),
            None => {}
        }
        let (settings, deadline, gap) =
            (cx.tally.settings, &cx.tally.deadline, cx.tally.allowed_gap);
        let found = verify_planar(cx.problem, &form, &x, gap, &settings.budget, deadline)?;
        match found {
            Ok(b) => {
                let note = format!(
                    "SO(2) multipliers at the estimate verified, lambda_min(S) >= {:.3e}",
                    b.verified_min_eigenvalue
                );
                let mu = Some(b.verified_min_eigenvalue);
                let lb = cx.offer(b.lower_bound, Proof::GravityDual, mu, &note);
                if cx.tally.certifies(lb) {
                    return Ok(Found::proved(lb, true, format!("{tried}{note}")));
                }
                tried = format!("{tried}{note}, not enough; ");
            }
            Err(reason) => tried = format!("{tried}{reason}; "),
        }
        // the null space deflated [G17]: no n x margin at a critical estimate
        let (budget, deadline) = (&cx.tally.settings.budget, &cx.tally.deadline);
        let found = verify_planar_grounded(&form, &x, gaps, budget, deadline)?;
        Ok(match found {
            Ok(b) => {
                let note = format!(
                    "{tried}SO(2) multipliers at the estimate verified with the null space \
                     deflated [G17], lambda_min(S) >= {:.3e}",
                    b.verified_min_eigenvalue
                );
                let mu = Some(b.verified_min_eigenvalue);
                let lb = cx.offer(b.lower_bound, Proof::GravityDual, mu, &note);
                Found::proved(lb, cx.tally.certifies(lb), note)
            }
            Err(reason) => Found::failed(format!("{tried}grounded [G17]: {reason}")),
        })
    }
}
