//! The dual certificate at the estimate `[H15]` without dense matrices, as a rung
//! (`paper-notes/conjugate.md` `[H25]`): the least-norm couplings in low-rank form
//! ([`super::low_rank`]), each side's grounded bound from a sparse bordered factorisation
//! ([`super::sparse_side`]). The same multipliers as the dense rung's least-norm ones; no
//! search over the couplings (the dense rung searches, up to its size).

use super::bound::joint_bound;
use super::grounded::Grounded;
use super::low_rank::LowRankCouplings;
use super::sparse_side::{compared_side_floor, sparse_side_floor};
use super::state::SimState;
use crate::certify::budget::Prediction;
use crate::certify::log::Refusal;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifyMode;
use crate::error::Result;
use crate::multiple::MultipleProblem;
use nalgebra::Matrix3;

/// The time and memory predicted for view graphs of `edges` edges each (the larger): a power
/// law through the measurements of each side's scalar comparison `[H26]` on random view graphs
/// of 4 edges per frame, whose factors fill the most (1000, 5000 and 10^4 frames: 0.10, 1.5 and
/// 6.6 s of certificate, 2026-12-03; 1.5 times that), where `[H25]`'s `3n` factors alone took
/// 0.38, 9.0 and 69 s (its fallback, started only while time is left); sparser graphs
/// (sequences) take far less. Only
/// for ordering the rungs and the time budget: the memory is bounded by the factor's own
/// refusal (`max_values`); the memory at least the factor's border (`18 x 3` dense columns of
/// `3n`) and the pattern of `A`, twice.
pub(super) fn predict(n: usize, edges: usize) -> Prediction {
    let scale = edges as f64 / 4000.0;
    let least = 16.0 * (162.0 * n as f64 + 9.0 * (n + 2 * edges) as f64);
    Prediction::new(
        0.15 * scale.powf(1.8),
        (8.0 * 2.5e6 * scale.powi(2)).max(least),
    )
}

/// One side: its graph, its `n` multipliers, its sign (-1 right, +1 left) and its point.
type Side<'s> = (
    &'s MultipleProblem,
    &'s [Matrix3<f64>],
    f64,
    &'s [Matrix3<f64>],
);

/// The low-rank dual certificate at the estimate, once (modes `auto` and `dual`; isotropic
/// graphs).
#[derive(Default)]
pub(crate) struct LowRankRung {
    done: bool,
}

impl<'a> Rung<SimState<'a>> for LowRankRung {
    fn proof(&self) -> Proof {
        Proof::SimultaneousLowRank
    }

    fn plan(&mut self, cx: &SimState<'a>) -> Result<Plan> {
        let mode = cx.tally.settings.mode;
        if self.done || !matches!(mode, CertifyMode::Auto | CertifyMode::Dual) {
            return Ok(Plan::Done);
        }
        if cx.right.is_anisotropic() || cx.left.is_anisotropic() {
            let reason = "the low-rank certificate is for view graphs with scalar weights".into();
            return Ok(Plan::Refuse(Refusal::NotApplicable { reason }, None));
        }
        let edges = cx.right.num_edges().max(cx.left.num_edges());
        Ok(Plan::Run(predict(cx.right.num_rotations(), edges)))
    }

    fn attempt(&mut self, cx: &mut SimState<'a>) -> Result<Found> {
        self.done = true;
        let Some(low) = cx.point_terms().and_then(LowRankCouplings::new) else {
            return Ok(Found::failed("the low-rank couplings are not finite"));
        };
        let lambdas = low.lambdas();
        let n = cx.right.num_rotations();
        // a factor's values (8 bytes) and its factorisation's workspace within the budget (one
        // side at a time; peak 8.7 bytes per value measured at 1.9e8 values)
        let max_values = (cx.tally.settings.budget.max_memory_bytes / 16) as usize;
        let sides: [Side<'_>; 2] = [
            (cx.right, &lambdas[..n], -1.0, &low.point.rs),
            (cx.left, &lambdas[n..], 1.0, &low.point.cs),
        ];
        let (mut floor, mut lam, mut verified) = (0.0, f64::INFINITY, f64::INFINITY);
        let mut compared = 0;
        let started = std::time::Instant::now();
        for (p, side_lambdas, sign, y) in sides {
            // the left side only while the time left exceeds what the right one took
            if sign > 0.0
                && cx
                    .tally
                    .deadline
                    .left()
                    .is_some_and(|l| l < started.elapsed().as_secs_f64())
            {
                return Ok(Found::failed(
                    "the right side was proven, no time left for the left side",
                ));
            }
            match side_floor(cx, (p, side_lambdas), &low, (sign, y), max_values) {
                Ok((g, by_comparison)) => {
                    compared += usize::from(by_comparison);
                    floor += g.floor;
                    lam = lam.min(g.rayleigh);
                    verified = verified.min(g.min_eigenvalue);
                }
                Err(why) => {
                    let side = if sign < 0.0 { "right" } else { "left" };
                    return Ok(Found::failed(format!(
                        "low-rank couplings ({} CG iterations, residual {:.1e}); the {side} side: {why}",
                        low.iterations, low.residual
                    )));
                }
            }
        }
        let Some(b) = joint_bound(cx.right, cx.left, &lambdas, floor, lam, verified) else {
            return Ok(Found::failed("the bound is not finite"));
        };
        let note = format!(
            "multipliers at the estimate (least-norm couplings of rank 18, {} CG iterations) verified by sparse bordered factorisations ({compared} of 2 sides by the scalar comparison [H26]), lambda_min(Z) >= {:.3e}",
            low.iterations, b.verified_min_eigenvalue
        );
        let lb = cx.offer(
            b.lower_bound,
            Proof::SimultaneousLowRank,
            b.verified_min_eigenvalue,
            &note,
        );
        Ok(Found::proved(lb, cx.tally.certifies(lb), note))
    }
}

/// One side's floor: the scalar comparison bordered by the couplings (`[H26]`) when it proves
/// within a quarter of the allowed gap (`3n min(mu, 0)`), else the `3n` bordered factor of
/// `[H25]`; `(floor, by the comparison)`.
fn side_floor(
    cx: &SimState<'_>,
    (p, lambdas): (&MultipleProblem, &[Matrix3<f64>]),
    low: &LowRankCouplings,
    (sign, y): (f64, &[Matrix3<f64>]),
    max_values: usize,
) -> std::result::Result<(Grounded, bool), String> {
    let dim = 3.0 * p.num_rotations() as f64;
    let target = 0.25 * cx.tally.allowed_gap / dim;
    let compared = compared_side_floor(p, lambdas, low, (sign, y), (target, max_values));
    if let Ok(g) = compared
        && g.floor >= -target * dim
    {
        return Ok((g, true));
    }
    let left = || cx.tally.deadline.left();
    sparse_side_floor(p, lambdas, low, (sign, y), max_values, &left).map(|g| (g, false))
}
