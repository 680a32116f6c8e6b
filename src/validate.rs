//! Input checks shared by the problem constructors and the readers: the weight window and the
//! rotation test (`paper-notes/conventions.md`, `[C6]`).

use crate::error::{Error, Result};
use crate::so3::{self, DEFAULT_ROTATION_TOLERANCE, Rotation};

/// Smallest weight accepted (see [`MAX_WEIGHT`]).
pub const MIN_WEIGHT: f64 = 1e-100;

/// Largest weight accepted. Weights are relative (scaling all of them scales every cost and
/// leaves the minimiser unchanged), but the solvers and certificates form squares of weighted
/// sums, which overflow or underflow in `f64` for extreme weights: fuzzing found NaN estimates
/// of `rotavg single` for weights of about `1e154` and above, and wrong "certified" answers for
/// weights `1e-200` and `1e308` (`tests/suite/fuzz_regressions.rs`). Constructors and readers
/// therefore reject a weight outside `[MIN_WEIGHT, MAX_WEIGHT]`; rescale such data.
pub const MAX_WEIGHT: f64 = 1e100;

/// Relative slack at the ends of `[MIN_WEIGHT, MAX_WEIGHT]`, for weights computed from a file
/// (g2o `kappa`): a problem written at a window end must read back (found by fuzzing).
const WEIGHT_SLACK: f64 = 1e-12;

/// `Some(message)` when a weight is not finite or outside `[MIN_WEIGHT, MAX_WEIGHT]` (up to a
/// relative rounding slack of `1e-12`).
pub(crate) fn weight_out_of_range(w: f64) -> Option<String> {
    if (MIN_WEIGHT * (1.0 - WEIGHT_SLACK)..=MAX_WEIGHT * (1.0 + WEIGHT_SLACK)).contains(&w) {
        None
    } else {
        Some(format!(
            "weight {w:e} is outside [{MIN_WEIGHT:e}, {MAX_WEIGHT:e}] (weights are relative: rescale them)"
        ))
    }
}

/// [`Error::InvalidWeight`] for `item` when `w` is outside the window.
pub(crate) fn check_weight(item: impl FnOnce() -> String, w: f64) -> Result<()> {
    match weight_out_of_range(w) {
        None => Ok(()),
        Some(_) => Err(Error::InvalidWeight {
            item: item(),
            weight: w,
        }),
    }
}

/// [`Error::NonFinite`] or [`Error::NotARotation`] for `item` unless `r` is a rotation within
/// [`DEFAULT_ROTATION_TOLERANCE`] (`[C6]`).
pub(crate) fn check_rotation(item: impl FnOnce() -> String, r: &Rotation) -> Result<()> {
    check_rotation_within(item, r, DEFAULT_ROTATION_TOLERANCE)
}

/// [`check_rotation`] with the tolerance `tol` on `||R^T R - I||_F` and `|det R - 1|`.
pub(crate) fn check_rotation_within(
    item: impl FnOnce() -> String,
    r: &Rotation,
    tol: f64,
) -> Result<()> {
    let m = r.matrix();
    if !m.iter().all(|x| x.is_finite()) {
        return Err(Error::NonFinite { item: item() });
    }
    let (orth, det) = so3::rotation_defect(m);
    if orth <= tol && (det - 1.0).abs() <= tol {
        Ok(())
    } else {
        Err(Error::NotARotation {
            item: item(),
            orthogonality_error: orth,
            determinant: det,
            tolerance: tol,
        })
    }
}

/// [`Error::InvalidSettings`] naming `name` unless `v` is finite and `> 0`.
pub(crate) fn positive(name: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidSettings {
            name: name.into(),
            reason: format!("must be finite and > 0, got {v}"),
        })
    }
}

/// [`Error::InvalidSettings`] naming `name` unless `v` is finite and `>= 0`.
pub(crate) fn non_negative(name: &str, v: f64) -> Result<()> {
    if v.is_finite() && v >= 0.0 {
        Ok(())
    } else {
        Err(Error::InvalidSettings {
            name: name.into(),
            reason: format!("must be finite and >= 0, got {v}"),
        })
    }
}

/// [`Error::InvalidSettings`] naming `name` unless `v >= 1`.
pub(crate) fn at_least_one(name: &str, v: usize) -> Result<()> {
    if v >= 1 {
        Ok(())
    } else {
        Err(Error::InvalidSettings {
            name: name.into(),
            reason: "must be at least 1".into(),
        })
    }
}

/// `q(p)` of ascending values, linear between ranks (rank `p (len - 1)`; so `p = 0.5` is the
/// median, the mean of the two middle values for an even count); `NaN` for none. The one
/// quantile of the crate's reports (residual and error summaries).
pub(crate) fn quantile_sorted(sorted: &[f64], p: f64) -> f64 {
    let Some(last) = sorted.len().checked_sub(1) else {
        return f64::NAN;
    };
    let pos = p.clamp(0.0, 1.0) * last as f64;
    let (lo, hi) = (pos.floor() as usize, pos.ceil() as usize);
    sorted[lo] + (sorted[hi] - sorted[lo]) * (pos - lo as f64)
}

/// The smallest positive weight (all finite; 0 for none): the scale of the absolute part of
/// every certificate tolerance (contract section 3). Adding measurements can only lower it, so no
/// set of measurements loosens a tolerance.
pub(crate) fn min_weight(weights: impl Iterator<Item = f64>) -> f64 {
    let min = weights.filter(|w| *w > 0.0).fold(f64::INFINITY, f64::min);
    if min.is_finite() { min } else { 0.0 }
}
