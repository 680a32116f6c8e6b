//! The SDP of the simultaneous problem `[H14]` as a rung (modes `auto` and `sdp`), once:
//! predicted from its size and refused over the budget, solved within the time left, its
//! multipliers verified ([`super::bound`]); a cheaper rounding is the improvement (not
//! polished: the joint local solver lives in [`crate::pipeline::simultaneous`]).

use super::bound::verify_simultaneous_bound_at;
use super::state::SimState;
use crate::certify::certification::SdpSummary;
use crate::certify::log::{Prediction, Refusal};
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifyMode;
use crate::error::Result;
use crate::relax::simultaneous::{predict_relax_simultaneous, relax_simultaneous};

/// The SDP rung.
#[derive(Default)]
pub(crate) struct SdpRung {
    done: bool,
}

impl<'a> Rung<SimState<'a>> for SdpRung {
    fn proof(&self) -> Proof {
        Proof::Sdp
    }

    fn plan(&mut self, cx: &SimState<'a>) -> Result<Plan> {
        if self.done || !matches!(cx.tally.settings.mode, CertifyMode::Auto | CertifyMode::Sdp) {
            return Ok(Plan::Done);
        }
        let p = predict_relax_simultaneous(cx.right.num_rotations());
        Ok(Plan::Run(Prediction::new(p.seconds, p.bytes)))
    }

    fn attempt(&mut self, cx: &mut SimState<'a>) -> Result<Found> {
        self.done = true;
        let n = cx.right.num_rotations();
        let Some(sdp) = cx.tally.settings.sdp_until(&cx.tally.deadline, 0.0) else {
            return Ok(Found::refused(Refusal::OverBudget {
                reason: "the time budget is spent".into(),
            }));
        };
        let relaxation = relax_simultaneous(cx.right, cx.left, &sdp)?;
        let bound = verify_simultaneous_bound_at(
            cx.right,
            cx.left,
            &relaxation.lambdas,
            &relaxation.couplings,
            Some((cx.rotations, cx.s)),
        );
        let top = &relaxation.x_top_eigenvalues;
        cx.sdp = Some(SdpSummary {
            status: relaxation.status,
            iterations: relaxation.iterations,
            seconds: relaxation.seconds,
            eigenvalue_ratio: match (top.get(2), top.get(3)) {
                (Some(&l3), Some(&l4)) if l3 > 0.0 => l4.max(0.0) / l3,
                _ => f64::NAN,
            },
            rounded_cost: Some(relaxation.rounded.cost),
            polished_cost: None,
        });
        if relaxation.rounded.cost < cx.tally.cost {
            cx.improvement = Some(relaxation.rounded.clone());
        }
        Ok(match bound {
            Some(b) => {
                let note = format!(
                    "SDP of two cones of size {} ({:?}, {} iterations): multipliers verified, \
                     lambda_min(Z) >= {:.3e}",
                    3 * n,
                    relaxation.status,
                    relaxation.iterations,
                    b.verified_min_eigenvalue
                );
                let lb = cx.offer(b.lower_bound, Proof::Sdp, b.verified_min_eigenvalue, &note);
                Found::proved(lb, cx.tally.certifies(lb), note)
            }
            None => Found::failed(format!(
                "SDP ({:?}): multipliers not finite",
                relaxation.status
            )),
        })
    }
}
