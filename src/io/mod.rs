//! Readers and writers for the file formats: JSON (SPEC section 5), g2o (3-D and 2-D), TORO
//! `EDGE3`, 1DSfM `EGs.txt`, Bundler ground truth, hand-eye pose files. Each reader documents,
//! where it reads, how the format maps onto this crate's conventions.

pub mod detect;
pub mod g2o;
pub mod handeye;
pub mod json;
pub mod sfm;
pub mod single_json;

/// Smallest weight the readers accept (see [`MAX_WEIGHT`]).
pub const MIN_WEIGHT: f64 = 1e-100;

/// Largest weight the readers accept. Weights are relative (scaling all of them scales every
/// cost and leaves the minimiser unchanged), but the solvers and certificates form squares of
/// weighted sums, which overflow or underflow in `f64` for extreme weights: fuzzing found NaN
/// estimates of `rotavg single` for weights of about `1e154` and above, and wrong "certified"
/// answers for weights `1e-200` and `1e308` (`tests/fuzz_regressions.rs`). Readers therefore
/// reject a weight outside `[MIN_WEIGHT, MAX_WEIGHT]`; rescale such files.
pub const MAX_WEIGHT: f64 = 1e100;

/// Relative slack at the ends of `[MIN_WEIGHT, MAX_WEIGHT]`, for weights computed from a file
/// (g2o `kappa`): a problem written at a window end must read back (found by fuzzing).
const WEIGHT_SLACK: f64 = 1e-12;

/// `Some(message)` when a weight read from a file is not finite or outside
/// `[MIN_WEIGHT, MAX_WEIGHT]` (up to a relative rounding slack of `1e-12`).
pub(crate) fn weight_out_of_range(w: f64) -> Option<String> {
    if (MIN_WEIGHT * (1.0 - WEIGHT_SLACK)..=MAX_WEIGHT * (1.0 + WEIGHT_SLACK)).contains(&w) {
        None
    } else {
        Some(format!(
            "weight {w:e} is outside [{MIN_WEIGHT:e}, {MAX_WEIGHT:e}] (weights are relative: rescale them)"
        ))
    }
}
