//! The dual certificate of the simultaneous problem at the estimate `[H15]` as a rung: the
//! multipliers complementary slackness fixes at the estimate ([`super::multipliers`]), the
//! couplings of least norm, then a search over the others (`search.rs`), every
//! candidate verified by [`super::bound::verify_simultaneous_bound`].

use super::bound::{SimultaneousBound, verify_simultaneous_bound_at};
use super::multipliers::EstimateMultipliers;
use super::state::SimState;
use crate::certify::log::{Prediction, Refusal};
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifyMode;
use crate::error::Result;
/// The most nodes of a rig the dense dual certificate `[H15]` is tried on (six dense `3n x 3n`
/// matrices: 1.7 GB at 2000 nodes; its least-norm certificate took 2.9 s at 1000 nodes and
/// 12 s at 1500 with faer's eigensolver, measured 2026-12-01, where nalgebra's took 19.6 s at
/// 1000); larger rigs are bounded by the decoupled bound `[H16]`, and solved by the sparse
/// alternation `[H17]`.
pub const DENSE_MAX_NODES: usize = 2000;

/// Seconds per `(3n)^3` of the least-norm dense certificate (a dense `3n x 3n` Cholesky
/// factorisation, two dense symmetric eigenvalue problems and the forming of the matrices):
/// 1.07e-10 at `3n = 3000` and 1.32e-10 at 4500 on this 2-core machine (2026-12-01, idle),
/// with room for a loaded one. Since 2026-12-02 the eigenvalue problems run only where the
/// grounded bound `[H23]` fails or could be beaten (1.2e-10 at `3n = 3000` and 7.7e-11 at
/// 6000 on a loaded day, `rig_scale`); the prediction keeps them, for the rigs where they run.
pub const DENSE_SECONDS_PER_CUBE: f64 = 2e-10;

/// Time and memory of [`super::multipliers::multipliers_at_estimate`] and of its verification
/// on `n` nodes: [`DENSE_SECONDS_PER_CUBE`] `(3n)^3`, and six dense `3n x 3n` matrices alive at
/// once.
pub fn predict_multipliers_at_estimate(n: usize) -> Prediction {
    let d = 3.0 * n as f64;
    Prediction::new(DENSE_SECONDS_PER_CUBE * d * d * d, 6.0 * 8.0 * d * d)
}

/// The dual certificate at the estimate `[H15]` as the first rung of a simultaneous
/// certification (modes `auto` and `dual`), once: the couplings of least norm, then, when they
/// do not certify, a cutting-plane search over the couplings complementary slackness allows
/// (its rounds within half the time left, its cuts within the memory the prediction leaves);
/// every candidate verified by [`super::bound::verify_simultaneous_bound`].
#[derive(Default)]
pub(crate) struct DualRung {
    done: bool,
}

impl<'a> Rung<SimState<'a>> for DualRung {
    fn proof(&self) -> Proof {
        Proof::SimultaneousDual
    }

    fn plan(&mut self, cx: &SimState<'a>) -> Result<Plan> {
        let mode = cx.tally.settings.mode;
        if self.done || mode == CertifyMode::Sdp {
            return Ok(Plan::Done);
        }
        if !matches!(mode, CertifyMode::Auto | CertifyMode::Dual) {
            let reason = format!(
                "the simultaneous problem is certified by its dual certificate and its SDP \
                 (modes auto, dual and sdp), not {}",
                mode.name()
            );
            return Ok(Plan::Refuse(Refusal::NotApplicable { reason }, None));
        }
        if cx.conv_ran {
            let reason = "the conv(SO(3)) surrogate's dual certificate ran [H27] (its bound is \
                          kept; on every pair measured it was the higher one)"
                .into();
            return Ok(Plan::Refuse(Refusal::NotApplicable { reason }, None));
        }
        let n = cx.right.num_rotations();
        if n > DENSE_MAX_NODES {
            let reason = format!(
                "{n} nodes: the dense dual certificate is for rigs of at most {DENSE_MAX_NODES} \
                 (the decoupled bound [H16] applies)"
            );
            return Ok(Plan::Refuse(Refusal::NotApplicable { reason }, None));
        }
        Ok(Plan::Run(predict_multipliers_at_estimate(
            cx.right.num_rotations(),
        )))
    }

    fn attempt(&mut self, cx: &mut SimState<'a>) -> Result<Found> {
        self.done = true;
        let n = cx.right.num_rotations();
        let at = cx.point_terms().and_then(EstimateMultipliers::new);
        let point = Some((cx.rotations, cx.s));
        let mut bound = at.as_ref().and_then(|at| {
            let g = at.least_norm.clone();
            verify_simultaneous_bound_at(cx.right, cx.left, &at.lambdas(&g), &g, point)
        });
        let mut note = match bound {
            Some(b) => format!(
                "multipliers at the estimate (couplings of least norm) verified, lambda_min(Z) >= {:.3e}",
                b.verified_min_eigenvalue
            ),
            None => "multipliers at the estimate not finite (singular coupling system)".into(),
        };
        if let Some(at) = &at
            && !bound.is_some_and(|b| cx.tally.certifies(b.lower_bound))
        {
            let predicted = predict_multipliers_at_estimate(n);
            let (searched, words) = search(cx, at, &predicted, bound);
            note = match words {
                Some(w) if searched.is_some() => w,
                Some(w) => format!("{note}; {w}"),
                None => note,
            };
            bound = searched.or(bound);
        }
        Ok(match bound {
            Some(b) => {
                let lb = cx.offer(
                    b.lower_bound,
                    Proof::SimultaneousDual,
                    b.verified_min_eigenvalue,
                    &note,
                );
                Found::proved(lb, cx.tally.certifies(lb), note)
            }
            None => Found::failed(note),
        })
    }
}

/// Other couplings complementary slackness allows `[H15]`: a cutting-plane search (its rounds
/// within half the time left, its cuts within the memory the rung's prediction leaves). Returns
/// a better verified bound than `bound`, if found, and what the search did in words.
fn search(
    cx: &SimState<'_>,
    at: &EstimateMultipliers,
    predicted: &Prediction,
    bound: Option<SimultaneousBound>,
) -> (Option<SimultaneousBound>, Option<String>) {
    let n = cx.right.num_rotations();
    let target = 0.25 * cx.tally.allowed_gap / (3 * n) as f64;
    let seconds = cx.tally.deadline.left().map(|l| 0.5 * l.max(0.0));
    let cut_bytes = (cx.tally.settings.budget.max_memory_bytes as f64 - predicted.bytes).max(0.0);
    let Some(found) =
        super::search::search_couplings(cx.right, cx.left, at, target, seconds, cut_bytes)
    else {
        return (
            None,
            Some(
                "no search over the couplings: one round is predicted past half the time left"
                    .into(),
            ),
        );
    };
    let point = Some((cx.rotations, cx.s));
    let searched =
        verify_simultaneous_bound_at(cx.right, cx.left, &found.lambdas, &found.couplings, point);
    match searched {
        Some(b) if bound.is_none_or(|x| b.lower_bound > x.lower_bound) => (
            Some(b),
            Some(format!(
                "multipliers at the estimate, couplings from a search ({} rounds, {} cuts) from the least-norm ones, verified, lambda_min(Z) >= {:.3e}",
                found.rounds, found.cuts, b.verified_min_eigenvalue
            )),
        ),
        _ => (
            None,
            Some(format!(
                "a search over the couplings ({} rounds, {} cuts) found no better bound",
                found.rounds, found.cuts
            )),
        ),
    }
}
