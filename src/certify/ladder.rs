//! The one climb of every certification (single, multiple, conjugate, simultaneous) and of the
//! checks inside a proof (`paper-notes/certificates.md` `[D12]`).
//!
//! Every rung ([`Rung`]) plans: a predicted cost and chance of success ([`Prediction`]), or a
//! refusal. The climb runs the rung of least expected time to a proof, `seconds / success`
//! (times below [`crate::certify::log::FREE_SECONDS`] tied, the stronger first), plans again
//! (an attempt may change the state: a better point, a hint), and stops when the state says
//! its best bound is enough or nothing is left to run. A rung predicted past the time left is
//! refused (the first of a climb only when it is predicted above `FREE_SECONDS`), so a larger
//! budget can only add rungs: it never gives a weaker verdict. Every rung considered is in the
//! log, once: refused, not needed, or its outcome and note.

use super::log::{Attempt, Outcome, Prediction, Refusal};
use super::rung::{Climb, Plan, Rung};
use crate::error::Result;
use std::time::Instant;

/// The rungs of one climb over the state `C`.
pub type Rungs<'a, C> = Vec<Box<dyn Rung<C> + 'a>>;

/// Climb `rungs` on the state `cx` (see the module documentation).
pub fn climb<C: Climb + ?Sized>(cx: &mut C, mut rungs: Rungs<'_, C>) -> Result<()> {
    // the last plan of each rung (aligned with `rungs`), for the log of those not needed
    let mut last: Vec<Option<Prediction>> = Vec::new();
    let mut ran = false;
    // every attempt retires its rung or waits for a new point: the guard only bounds a rung
    // that would not (a bug, never an input)
    for _ in 0..MAX_ATTEMPTS {
        if cx.enough() {
            for (r, p) in rungs.iter().zip(&last) {
                if let Some(p) = p {
                    let refused = Outcome::Refused(Refusal::NotNeeded);
                    log(cx, r.proof(), Some(*p), refused, Instant::now());
                }
            }
            return Ok(());
        }
        let (chosen, plans) = next(cx, &mut rungs)?;
        last = plans;
        let Some((k, predicted)) = chosen else {
            return Ok(());
        };
        let since = Instant::now();
        if let Some(refusal) = over_budget(cx, &predicted, ran) {
            let r = rungs.remove(k);
            last.remove(k);
            log(
                cx,
                r.proof(),
                Some(predicted),
                Outcome::Refused(refusal),
                since,
            );
            continue;
        }
        ran = true;
        last[k] = None;
        let point = cx.point();
        // what runs now, and for how long it is predicted to (the progress line)
        crate::progress::phase(crate::progress::Phase::Certify, || {
            format!(
                "{} (predicted {:.2} s)",
                rungs[k].proof(),
                predicted.seconds
            )
        });
        let found = rungs[k].attempt(cx)?;
        if found.logged {
            continue;
        }
        let attempt = Attempt {
            rung: rungs[k].proof(),
            point: found.point.unwrap_or(point),
            predicted: Some(predicted),
            outcome: found.outcome,
            seconds: since.elapsed().as_secs_f64(),
            note: found.note,
            within: cx.within(),
        };
        cx.record(attempt);
    }
    Ok(())
}

/// More attempts than any climb makes (the multiple climb makes at most about 12).
const MAX_ATTEMPTS: usize = 1000;

/// Plan every rung (logging and dropping the refused ones, dropping the finished ones) and
/// return the one to run next (least expected time, the stronger first among ties; a fallback
/// only when nothing else can run) with the plans of the rungs kept.
#[allow(clippy::type_complexity)]
fn next<C: Climb + ?Sized>(
    cx: &mut C,
    rungs: &mut Rungs<'_, C>,
) -> Result<(Option<(usize, Prediction)>, Vec<Option<Prediction>>)> {
    let mut best: Option<(usize, Prediction)> = None;
    let mut fallback: Option<(usize, Prediction)> = None;
    let mut plans = Vec::with_capacity(rungs.len());
    let mut k = 0;
    while k < rungs.len() {
        let since = Instant::now();
        match rungs[k].plan(cx)? {
            Plan::Run(p) => {
                if before(rungs, k, &p, best.as_ref()) {
                    best = Some((k, p));
                }
                plans.push(Some(p));
                k += 1;
            }
            Plan::Fallback(p) => {
                if before(rungs, k, &p, fallback.as_ref()) {
                    fallback = Some((k, p));
                }
                plans.push(None);
                k += 1;
            }
            Plan::Wait => {
                plans.push(None);
                k += 1;
            }
            Plan::Refuse(refusal, p) => {
                let r = rungs.remove(k);
                log(cx, r.proof(), p, Outcome::Refused(refusal), since);
            }
            Plan::Skip(refusal) => {
                let proof = rungs[k].proof();
                log(cx, proof, None, Outcome::Refused(refusal), since);
                plans.push(None);
                k += 1;
            }
            Plan::Done => {
                rungs.remove(k);
            }
        }
    }
    Ok((best.or(fallback), plans))
}

/// Rung `k` with prediction `p` runs before `current` (least expected time, then strength).
fn before<C: ?Sized>(
    rungs: &Rungs<'_, C>,
    k: usize,
    p: &Prediction,
    current: Option<&(usize, Prediction)>,
) -> bool {
    current.is_none_or(|(b, q)| {
        p.order_key()
            .total_cmp(&q.order_key())
            .then(
                rungs[k]
                    .proof()
                    .strength()
                    .cmp(&rungs[*b].proof().strength()),
            )
            .is_lt()
    })
}

/// The refusal of a rung predicted past the memory budget or the time left: no time refusal
/// for the first rung of a climb when it is predicted free (below `FREE_SECONDS`: the timer
/// resolves no finer).
fn over_budget<C: Climb + ?Sized>(cx: &C, predicted: &Prediction, ran: bool) -> Option<Refusal> {
    let budget = cx.budget();
    if predicted.bytes > budget.max_memory_bytes as f64 {
        return Some(Refusal::OverBudget {
            reason: format!(
                "predicted {:.1} GB, memory budget {:.1} GB",
                predicted.bytes / 1e9,
                budget.max_memory_bytes as f64 / 1e9
            ),
        });
    }
    let left = cx.deadline().left()?;
    let free = !ran && predicted.seconds <= super::log::FREE_SECONDS;
    (predicted.seconds > left && !free).then(|| Refusal::OverBudget {
        reason: format!(
            "predicted {:.2} s, {:.2} s of the time budget left",
            predicted.seconds,
            left.max(0.0)
        ),
    })
}

fn log<C: Climb + ?Sized>(
    cx: &mut C,
    rung: super::proof::Proof,
    predicted: Option<Prediction>,
    outcome: Outcome,
    since: Instant,
) {
    let attempt = Attempt {
        rung,
        point: cx.point(),
        predicted,
        outcome,
        seconds: since.elapsed().as_secs_f64(),
        note: String::new(),
        within: cx.within(),
    };
    cx.record(attempt);
}
