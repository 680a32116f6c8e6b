//! The SDP relaxation as a rung of a certification of multiple averaging (`[D4]`, `[P6]`):
//! solved by Clarabel within the time left minus what its verification and polish need, its
//! multipliers verified (never its objective), its rounding polished and adopted when cheaper.

use super::check::Scope;
use super::staircase::polish;
use super::state::{Best, State};
use super::verified::VerifiedBound;
use super::verify::multipliers_bound;
use crate::certify::certification::{ImprovementSource, SdpSummary};
use crate::certify::log::{Outcome, Point, Prediction, Refusal};
use crate::certify::proof::{BoundMethod, Proof};
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifyMode;
use crate::error::Result;
use crate::multiple::MultipleSolution;
use crate::relax::{MultipleRelaxation, predict_relax_multiple, relax_multiple};

/// The share of the SDP's predicted time reserved after Clarabel stops (its last iteration past
/// the time limit, checked once per iteration, and the rounding) on top of the verification's
/// and the polish's own reserve ([`POST_SECONDS_PER_EDGE`]).
pub const SDP_RESERVE_FRACTION: f64 = 0.15;

/// Seconds per edge reserved for the verification of the SDP's multipliers and the polish of
/// its rounding (both `O(m)` to `O(m log m)` at the sizes an SDP runs).
pub const POST_SECONDS_PER_EDGE: f64 = 2e-4;

/// The SDP rung (mode `sdp`; mode `auto` when `n <= sdp_max_nodes` and the staircase stopped
/// short of a verified point), once.
#[derive(Default)]
pub(crate) struct SdpRung {
    done: bool,
}

impl SdpRung {
    /// The seconds kept after Clarabel stops, for `predicted` SDP seconds.
    fn reserve(cx: &State<'_>, predicted: f64) -> f64 {
        SDP_RESERVE_FRACTION * predicted + POST_SECONDS_PER_EDGE * cx.problem.num_edges() as f64
    }
}

impl<'a> Rung<State<'a>> for SdpRung {
    fn proof(&self) -> Proof {
        Proof::Sdp
    }

    fn plan(&mut self, cx: &State<'a>) -> Result<Plan> {
        let n = cx.problem.num_rotations();
        if self.done {
            return Ok(Plan::Done);
        }
        match cx.escalation() {
            Err(reason) => return Ok(Plan::Refuse(Refusal::NotApplicable { reason }, None)),
            Ok(false) => return Ok(Plan::Wait),
            Ok(true) => {}
        }
        if cx.settings.mode == CertifyMode::Auto && n > cx.settings.sdp_max_nodes {
            let reason = format!("{n} nodes > sdp_max_nodes {}", cx.settings.sdp_max_nodes);
            return Ok(Plan::Refuse(Refusal::NotApplicable { reason }, None));
        }
        if cx.settings.mode == CertifyMode::Auto {
            // the staircase first (it solves the same relaxation: on a 40-node graph with 20 %
            // outliers its verified bound matched the SDP's to 4e-9 relative in 0.07 s against
            // 10.3 s); the SDP only when it stopped short of a verified point
            match cx.staircase_verified {
                None => return Ok(Plan::Wait),
                Some(true) => return Ok(Plan::Done),
                Some(false) => {}
            }
        }
        let p = predict_relax_multiple(cx.problem)?;
        let seconds = p.seconds + Self::reserve(cx, p.seconds);
        Ok(Plan::Run(Prediction::new(seconds, p.bytes)))
    }

    fn attempt(&mut self, cx: &mut State<'a>) -> Result<Found> {
        self.done = true;
        cx.sdp_ran = true;
        crate::progress::phase(crate::progress::Phase::Sdp, || {
            format!("{} nodes", cx.problem.num_rotations())
        });
        let predicted = predict_relax_multiple(cx.problem)?.seconds;
        let reserve = Self::reserve(cx, predicted);
        let Some(sdp_settings) = cx.settings.sdp_until(&cx.deadline, reserve) else {
            return Ok(Found::refused(Refusal::OverBudget {
                reason: format!(
                    "{:.2} s left, {reserve:.2} s of it kept for the verification",
                    cx.deadline.left().unwrap_or(0.0).max(0.0)
                ),
            }));
        };
        let sdp = relax_multiple(cx.problem, &sdp_settings)?;
        let bound = verify_sdp(cx, &sdp)?;
        // the polish only while time is left (the bound holds without it)
        let polished = (!cx.deadline.passed())
            .then(|| polish(cx.problem, &sdp.rounded, &cx.deadline))
            .flatten();
        cx.sdp = Some(summary(&sdp, polished.as_ref()));
        let note = sdp_note(
            &sdp,
            bound.as_ref(),
            polished.as_ref(),
            cx.problem.num_rotations(),
        );
        let found = match &bound {
            Some(b) => {
                offer(cx, b, &sdp);
                Found::proved(b.lower_bound, cx.certifies(b.lower_bound), note)
            }
            None => Found::new(
                Outcome::Failed {
                    reason: format!("Clarabel {:?}: unusable multipliers", sdp.status),
                },
                note,
            ),
        };
        if let Some(p) = polished
            && p.chordal_cost < cx.current.cost
        {
            cx.adopt(p, ImprovementSource::SdpRounding, Point::Sdp);
        }
        Ok(found)
    }
}

/// The SDP's multipliers verified independently (`None` when they are not usable); the checks
/// are logged.
fn verify_sdp(cx: &mut State<'_>, sdp: &MultipleRelaxation) -> Result<Option<VerifiedBound>> {
    let n = cx.problem.num_rotations();
    let usable = sdp.multipliers.len() == n
        && sdp
            .multipliers
            .iter()
            .all(|l| l.iter().all(|x| x.is_finite()));
    if !usable {
        return Ok(None);
    }
    let scope = Scope {
        point: Point::Sdp,
        within: Proof::Sdp,
        deadline: cx.deadline,
        refinement_follows: None,
    };
    let b = multipliers_bound(cx.problem, &sdp.multipliers, cx.settings, scope, None)?;
    cx.log.extend(b.ladder.iter().cloned());
    Ok(Some(b))
}

/// Offer the SDP's verified bound.
fn offer(cx: &mut State<'_>, b: &VerifiedBound, sdp: &MultipleRelaxation) {
    cx.offer(Best {
        lower_bound: b.lower_bound,
        method: BoundMethod::Sdp,
        point: Point::Sdp,
        min_eigenvalue: b
            .min_eigenvalue_estimate
            .or(Some(b.verified_min_eigenvalue)),
        explanation: format!(
            "bound from the SDP relaxation's multipliers (Clarabel {:?}), verified \
             independently: lambda_min(Q - blkdiag(Lambda)) >= {:.3e}",
            sdp.status, b.verified_min_eigenvalue
        ),
        verified_min_eigenvalue: b.verified_min_eigenvalue,
        shift: b.shift,
        lambdas: Some(sdp.multipliers.clone()),
    });
}

/// The SDP's statistics for the report.
fn summary(sdp: &MultipleRelaxation, polished: Option<&MultipleSolution>) -> SdpSummary {
    SdpSummary {
        status: sdp.status,
        iterations: sdp.iterations,
        seconds: sdp.seconds,
        eigenvalue_ratio: match sdp.x_top_eigenvalues.as_slice() {
            [_, _, l3, l4, ..] if *l3 > 0.0 => l4.max(0.0) / l3,
            _ => f64::NAN,
        },
        rounded_cost: Some(sdp.rounded_cost),
        polished_cost: polished.map(|p| p.chordal_cost),
    }
}

/// What the SDP did, in words.
fn sdp_note(
    sdp: &MultipleRelaxation,
    bound: Option<&VerifiedBound>,
    polished: Option<&MultipleSolution>,
    n: usize,
) -> String {
    let reflections = (sdp.reflected_blocks > 0).then(|| {
        format!(
            "; {} of {n} blocks of the SDP's rank-3 factor are reflections (det < 0): the O(3) \
             relaxation prefers them, so its bound can lie below every rotation estimate",
            sdp.reflected_blocks
        )
    });
    format!(
        "Clarabel SDP ({:?}, {} iterations, {:.3} s); multipliers verified{}; rounding cost {:.9e}{}{}",
        sdp.status,
        sdp.iterations,
        sdp.solver_seconds,
        bound
            .map(|b| format!(
                ": lambda_min(Q - blkdiag(Lambda)) >= {:.3e}",
                b.verified_min_eigenvalue
            ))
            .unwrap_or_else(|| " (unusable multipliers)".into()),
        sdp.rounded_cost,
        polished
            .map(|p| format!(", polished {:.9e}", p.chordal_cost))
            .unwrap_or_default(),
        reflections.unwrap_or_default()
    )
}
