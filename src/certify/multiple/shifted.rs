//! The shifted Cholesky rung `[D5]`-`[D7]` (`paper-notes/certificates.md`): a successful
//! sparse Cholesky factorisation of `S + sigma I` proves `lambda_min(S) >= -sigma - margin`
//! (the floating-point margin `[D6]`). The first shift spends a tenth of the tolerance; when it
//! fails, Lanczos estimates `lambda_min(S)` (an estimate only: it picks the shifts, and its
//! negative eigenvector is the staircase's direction of descent) and shifts above it are tried.

use super::check::{
    Check, Notes, ThreeN, counted_factorisation_prediction, first_shift, ordering_refusal,
};
use crate::certify::log::{Prediction, Refusal};
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::error::Result;
use crate::linalg::cholesky::PositiveFactor;
use crate::linalg::{
    Extreme, LanczosResult, LanczosSettings, ShiftedCholesky, lanczos_extreme, rayleigh_quotient,
    smallest_eigenpair,
};

/// The shifted Cholesky rung: the analysis of `S` (made when planned, or by the attempt when
/// the prediction came from the scalar factor) and its prediction.
#[derive(Default)]
pub(super) struct ShiftedProof {
    analysed: Option<ShiftedCholesky>,
    predicted: Option<Prediction>,
    done: bool,
}

impl<'a> Rung<Check<'a>> for ShiftedProof {
    fn proof(&self) -> Proof {
        Proof::ShiftedCholesky
    }

    fn plan(&mut self, cx: &Check<'a>) -> Result<Plan> {
        if self.done {
            return Ok(Plan::Done);
        }
        if let Some(p) = self.predicted {
            if let Some(refusal) = cx.cut_by_not_critical(p.seconds) {
                return Ok(Plan::Refuse(refusal, Some(p)));
            }
            return Ok(Plan::Run(p));
        }
        let predicted = match cx.three_n_predicted(cx.dim(), 3.0) {
            ThreeN::Known(p) => p,
            ThreeN::Wait => return Ok(Plan::Wait),
            ThreeN::Unknown => match analyse(cx)? {
                Ok((ch, p)) => {
                    self.analysed = Some(ch);
                    Ok(p)
                }
                Err(refusal) => Err(refusal),
            },
        };
        self.predicted = predicted.as_ref().ok().copied();
        Ok(match predicted {
            Ok(p) => match cx.cut_by_not_critical(p.seconds) {
                Some(refusal) => Plan::Refuse(refusal, Some(p)),
                None => Plan::Run(p),
            },
            Err(refusal) => Plan::Refuse(refusal, None),
        })
    }

    fn attempt(&mut self, cx: &mut Check<'a>) -> Result<Found> {
        self.done = true;
        if self.analysed.is_none() {
            match analyse(cx)? {
                Ok((ch, _)) => self.analysed = Some(ch),
                Err(refusal) => return Ok(Found::refused(refusal)),
            }
        }
        let Some(ch) = self.analysed.as_mut() else {
            return Ok(Found::failed("no analysis of S"));
        };
        let (bound, reason) = verify_shifted(cx, ch);
        Ok(match bound {
            Some(b) => Found::new(cx.offer(b), ""),
            None => Found::failed(reason),
        })
    }
}

/// A shift that factorised, with its margins ([`PositiveFactor`]).
#[derive(Debug, Clone, Copy)]
struct Verified {
    shift: f64,
    margin: f64,
    margin_sum: f64,
}

impl Verified {
    fn of(f: &PositiveFactor<'_>) -> Self {
        Verified {
            shift: f.shift,
            margin: f.margin,
            margin_sum: f.margin_sum,
        }
    }
}

/// The first shift, and when it fails the search: a verified bound, or why not.
fn verify_shifted(
    cx: &Check<'_>,
    ch: &mut ShiftedCholesky,
) -> (Option<super::verified::VerifiedBound>, String) {
    let delta0 = first_shift(cx);
    // a floating-point margin below this costs at most 5 % of the gap budget: the tighter,
    // more expensive residual margin [D6] (2) is not needed then
    let margin_target = 0.05 * cx.gap / cx.dim().max(1) as f64;
    let mut best = None;
    let mut notes = cx.notes();
    // an estimate handed in that is clearly below -delta0: that shift would only fail
    let hinted_below = cx
        .hint
        .as_ref()
        .is_some_and(|h| h.high < -2.0 * delta0 && h.low.value + h.low.residual < -2.0 * delta0);
    let first = (!hinted_below).then(|| {
        notes.factorizations += 1;
        ch.factor(delta0, margin_target)
    });
    if let Some(f) = first.flatten() {
        best = Some(Verified::of(&f));
        if cx.settings.dual.estimate_when_verified {
            let mut r = shift_invert(&f, cx.dim(), None, &lanczos(cx, 40));
            notes.lanczos_iterations += r.iterations;
            (r.value, r.residual) = rayleigh_quotient(cx.s().as_ref(), &r.vector);
            notes.estimate = Some(r);
        }
    } else if !notes.not_critical {
        // far from a critical point the bound is weak whatever the shift: no search
        best = search(cx, ch, delta0, margin_target, &mut notes);
    }
    let bound = best.map(|v| {
        let margin = v.margin + cx.forming;
        let mut b = cx.bound_from_mu(-v.shift - margin, Proof::ShiftedCholesky);
        // [D6] (3): the margins by rows, S >= -shift I - D with tr(D) <= margin_sum + forming_sum
        let n3 = cx.dim() as f64;
        let by_rows = n3 * v.shift + v.margin_sum + cx.forming_sum;
        b.lower_bound = b.lower_bound.max(cx.trace_bound().with_deficit(by_rows));
        b.shift = Some(v.shift);
        b.fp_margin = margin;
        b.factor_nonzeros = ch.factor_len();
        b
    });
    let reason = match (&notes.skipped, &notes.estimate) {
        (Some(skipped), _) => skipped.clone(),
        (None, Some(e)) => format!(
            "no shift verified; Lanczos estimate lambda_min(S) ~ {:.3e}",
            e.value
        ),
        (None, None) => "the first shift did not verify".into(),
    };
    (bound, reason)
}

/// The symbolic analysis of `S` within the budget, and its prediction (the first shift, and when
/// it fails an estimate and a few more). Its refusal is noted for the grounded rung.
fn analyse(cx: &Check<'_>) -> Result<std::result::Result<(ShiftedCholesky, Prediction), Refusal>> {
    let dim = cx.dim();
    let cap = cx
        .settings
        .budget
        .max_factor_values(dim)
        .min(cx.settings.dual.max_factor_nonzeros);
    let ch = match ShiftedCholesky::new_within(cx.s().clone(), cx.terms, cap)? {
        Ok(ch) => ch,
        Err(predicted) => {
            let refusal = ordering_refusal(cx.settings, predicted, dim).unwrap_or_else(|| {
                Refusal::OverBudget {
                    reason: format!("the ordering predicts {predicted:.1e} factor values"),
                }
            });
            cx.note_three_n_refused(&refusal);
            return Ok(Err(refusal));
        }
    };
    let scratch = ch.scratch_bytes().div_ceil(8);
    match counted_factorisation_prediction(
        cx.settings,
        ch.factor_len(),
        scratch,
        ch.multiply_adds(),
        3.0,
    ) {
        Ok(p) => Ok(Ok((ch, p))),
        Err(refusal) => {
            cx.note_three_n_refused(&refusal);
            Ok(Err(refusal))
        }
    }
}

/// The Lanczos settings of the estimates, at most `iterations` (and the dimension).
fn lanczos(cx: &Check<'_>, iterations: usize) -> LanczosSettings {
    let mut lz = cx.settings.dual.lanczos;
    lz.max_iterations = lz.max_iterations.min(iterations).min(cx.dim().max(1));
    lz
}

/// Shift-invert estimate through a successful factor: the largest eigenvalue `theta` of
/// `(S + sigma I)^-1` gives `lambda_min(S) ~ 1 / theta - sigma` `[D7]`.
fn shift_invert(
    f: &PositiveFactor<'_>,
    n: usize,
    start: Option<&[f64]>,
    lz: &LanczosSettings,
) -> LanczosResult {
    let mut r = lanczos_extreme(
        n,
        |x, y| {
            y.copy_from_slice(x);
            f.solve_in_place(y);
        },
        Extreme::Largest,
        0.0,
        lz,
        start,
    );
    r.value = 1.0 / r.value - f.shift;
    r
}

/// The estimate says `S` is indefinite by at least 100 times its Ritz residual plus the first
/// shift.
fn clearly_negative(r: &LanczosResult, delta0: f64) -> bool {
    r.value < -100.0 * (r.residual + delta0)
}

/// The first estimate of `lambda_min(S)`: the hint's, or Lanczos on `S`; `None` (with the
/// reason in `notes`) when no shift can prove a bound above the trivial 0.
fn first_estimate(
    cx: &Check<'_>,
    lz: &LanczosSettings,
    notes: &mut Notes,
) -> Option<LanczosResult> {
    let r = match &cx.hint {
        Some(h) => h.low.clone(),
        None => {
            let r = smallest_eigenpair(cx.s().as_ref(), cx.norm(), lz);
            notes.lanczos_iterations += r.iterations;
            r
        }
    };
    // a Ritz value is at least lambda_min: no shift can prove more than the bound at the
    // estimate, and below 0 (which every cost is above) that is worth no factorisation (at 10^4
    // nodes with outliers, 12 s for a bound of -4.7e3 at a local minimum the staircase then
    // bounds within 0.2 %)
    // (only at an estimate: bare multipliers get their bound, whatever its sign)
    let at_best = cx.trace_bound().at_mu(r.value);
    if cx.rotations.is_some() && at_best < 0.0 {
        notes.skipped = Some(format!(
            "the estimate lambda_min(S) ~ {:.3e} predicts a bound of at most {at_best:.3e} < 0, \
             below the trivial bound 0: no factorisation",
            r.value
        ));
        notes.estimate = Some(r);
        return None;
    }
    Some(r)
}

/// Estimate `lambda_min(S)` by Lanczos on `S`, then shifts above it `4^j` steps apart until one
/// factorisation succeeds (refining the estimate by shift-invert from there), then one tighter
/// shift just above the refined estimate. Returns the best verified shift with its margins.
fn search(
    cx: &Check<'_>,
    ch: &mut ShiftedCholesky,
    delta0: f64,
    margin_target: f64,
    notes: &mut Notes,
) -> Option<Verified> {
    let lz = lanczos(cx, usize::MAX);
    let hinted = cx.hint.is_some();
    let mut r = first_estimate(cx, &lz, notes)?;
    let mut tries = Tries {
        tried: 1,
        max: cx.settings.dual.max_factorizations,
    };
    let base = (-r.value).max(0.0);
    let step0 = delta0.max(r.residual).max(1e-12 * cx.norm());
    let gersh_shift = (-crate::linalg::gershgorin_lower_bound(cx.s().as_ref())).max(0.0);
    let mut best = None;
    let mut j = 0i32;
    while tries.next() {
        let sigma = base + step0 * 4f64.powi(j);
        j += 1;
        let Some(f) = ch.factor(sigma, margin_target) else {
            if sigma > gersh_shift {
                break;
            }
            continue;
        };
        best = Some(Verified::of(&f));
        if hinted || clearly_negative(&r, delta0) {
            // a hint is already the estimate a shift-invert run would refine, and the shift
            // above it the tight one; and when S is indefinite by far more than the estimate's
            // uncertainty, the bound is trace + 3n lambda_min whatever the shift: tightening or
            // refining (two more factorisations, a shift-invert run) changes it by the residual
            break;
        }
        let mut r2 = shift_invert(&f, cx.dim(), Some(&r.vector), &lz);
        notes.lanczos_iterations += r2.iterations;
        (r2.value, r2.residual) = rayleigh_quotient(cx.s().as_ref(), &r2.vector);
        if r2.value < r.value || r2.residual < r.residual {
            r = r2;
        }
        break;
    }
    if let Some(v) = best.filter(|_| !hinted && !clearly_negative(&r, delta0)) {
        best = tighten(ch, &r, v.shift, delta0, margin_target, &mut tries).or(best);
    }
    notes.factorizations += tries.tried - 1;
    notes.estimate = Some(r);
    best
}

/// The factorisations tried so far and the most allowed.
struct Tries {
    tried: usize,
    max: usize,
}

impl Tries {
    /// Counts one more factorisation, if one is allowed.
    fn next(&mut self) -> bool {
        let allowed = self.tried < self.max;
        self.tried += usize::from(allowed);
        allowed
    }
}

/// Shifts just above the refined estimate `r`, below the verified `shift`, margins 10x apart:
/// the first that factors; then, when that margin was the estimate's residual and the residual
/// is large against the estimate (Lanczos not converged), margins 10x smaller while they
/// factor ([`descend`]).
fn tighten(
    ch: &mut ShiftedCholesky,
    r: &LanczosResult,
    shift: f64,
    delta0: f64,
    margin_target: f64,
    tries: &mut Tries,
) -> Option<Verified> {
    let floor = delta0.max(1e-9 * r.value.abs());
    let mut margin = floor.max(r.residual);
    loop {
        let sigma = (-r.value).max(0.0) + margin;
        if sigma >= shift || !tries.next() {
            return None;
        }
        if let Some(f) = ch.factor(sigma, margin_target) {
            let found = Verified::of(&f);
            if margin == r.residual && r.residual > 10.0 * (r.value.abs() + floor) {
                return Some(descend(
                    ch,
                    r,
                    found,
                    margin / 10.0,
                    floor,
                    margin_target,
                    tries,
                ));
            }
            return Some(found);
        }
        margin *= 10.0;
    }
}

/// Margins above the estimate `r`, 10x apart downwards from `margin` to `floor`, while they
/// factor: the residual of an unconverged Lanczos estimate (229 against an estimate of -0.003
/// on a 5000-pose strongly anisotropic SLAM surrogate whose `S + 0.1 I` factorises) is no
/// measure of how far above it the smallest eigenvalue lies. Every success tightens the bound;
/// one failure ends it.
fn descend(
    ch: &mut ShiftedCholesky,
    r: &LanczosResult,
    mut best: Verified,
    mut margin: f64,
    floor: f64,
    margin_target: f64,
    tries: &mut Tries,
) -> Verified {
    while margin >= floor && tries.next() {
        let Some(f) = ch.factor((-r.value).max(0.0) + margin, margin_target) else {
            break;
        };
        best = Verified::of(&f);
        margin /= 10.0;
    }
    best
}

#[cfg(test)]
mod tests {
    use super::{Tries, tighten};
    use crate::linalg::{LanczosResult, LanczosStop, ShiftedCholesky};
    use faer::sparse::{SparseColMat, Triplet};

    /// `tridiag(-1, 2, -1) - c I` of size `n` (smallest eigenvalue `2 - 2 cos(pi / (n + 1)) -
    /// c`, closed form) and an unconverged estimate of it: the Rayleigh quotient `-0.003` with
    /// residual `229` (the 5000-pose SLAM surrogate's numbers). The tightened shift is within
    /// 10x of the true distance below zero (it was the residual, 229, before the descent), and
    /// it proves a bound below the closed form.
    #[test]
    fn an_unconverged_estimate_is_tightened_downwards() {
        let n = 200;
        let exact_min = 2.0 - 2.0 * (std::f64::consts::PI / (n as f64 + 1.0)).cos();
        let c = exact_min + 0.05;
        let mut t = Vec::new();
        for i in 0..n {
            t.push(Triplet::new(i, i, 2.0 - c));
            if i + 1 < n {
                t.push(Triplet::new(i, i + 1, -1.0));
                t.push(Triplet::new(i + 1, i, -1.0));
            }
        }
        let s = SparseColMat::try_new_from_triplets(n, n, &t).unwrap();
        let mut ch = ShiftedCholesky::new(s, 3).unwrap();
        let r = LanczosResult {
            value: -0.003,
            vector: vec![0.0; n],
            residual: 229.0,
            iterations: 300,
            stop: LanczosStop::SubspaceLimit {
                dimension: 300,
                residual: 1.0,
                threshold: 1e-6,
            },
        };
        let mut tries = Tries { tried: 1, max: 24 };
        let v = tighten(&mut ch, &r, 369.0, 1e-9, 0.0, &mut tries).unwrap();
        assert!(v.shift >= 0.05 && v.shift <= 0.5, "{v:?}");
        assert!(-v.shift - v.margin <= -0.05 + 1e-12);
        assert!(tries.tried <= 7, "{} factorisations", tries.tried);
    }
}
