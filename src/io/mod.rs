//! Readers and writers for the file formats: JSON (SPEC section 5), g2o (3-D and 2-D), TORO
//! `EDGE3`, 1DSfM `EGs.txt`, Bundler ground truth, hand-eye pose files. Each reader documents,
//! where it reads, how the format maps onto this crate's conventions.
//!
//! | module | reads | writes |
//! |---|---|---|
//! | [`detect`] | any view graph: [`detect::load_graph`] (path), [`detect::read_graph`] (text), format auto-detection | — |
//! | [`g2o`] | g2o 3-D / 2-D and TORO `EDGE3` ([`g2o::read_g2o`]) | [`g2o::write_g2o`] |
//! | [`sfm`] | 1DSfM `EGs.txt` ([`sfm::read_egs`]), Bundler ground truth, rotation lists | — |
//! | [`json`] | multiple problems ([`json::read_problem_json`]) and estimates ([`json::read_estimate`]) | [`json::write_problem_json`], [`json::write_estimate_json`] |
//! | [`single_json`] | single problems ([`single_json::parse_single_json`]) and estimates | [`single_json::to_single_json`] |
//! | [`handeye`] | Tabb and ETH hand-eye data, conjugate JSON ([`handeye::read_conjugate_json`]) | [`handeye::write_conjugate_json`] |
//!
//! Readers take the text and a file name (used in error messages, with the line number), so
//! tests and examples can read from inline strings:
//!
//! ```
//! use rotavg::io::detect::{read_graph, GraphFormat, ReadOptions};
//! // 1DSfM: `i j R11 .. R33` per line, holding R_i R_j^T; read as R_ij = its transpose.
//! let text = "0 1 1 0 0 0 1 0 0 0 1\n1 2 1 0 0 0 1 0 0 0 1\n";
//! let g = read_graph(text, "EGs.txt", GraphFormat::Auto, &ReadOptions::default())?;
//! assert_eq!(g.format, GraphFormat::OneDsfm);
//! assert_eq!((g.problem.num_rotations(), g.problem.num_edges()), (3, 2));
//! let err = read_graph("0 1 2 3\n", "bad.txt", GraphFormat::OneDsfm, &ReadOptions::default());
//! assert!(err.unwrap_err().to_string().starts_with("bad.txt:1:"));
//! # Ok::<(), rotavg::Error>(())
//! ```

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

/// The content lines of a text file: `(1-based line number, trimmed line)` for every line that
/// is neither blank nor a `#` comment. Shared by the line-oriented readers.
pub(crate) fn content_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(k, l)| (k + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
}

/// The line to blame for "nothing found" errors: the last line of the file (1 when empty).
pub(crate) fn last_line(text: &str) -> usize {
    text.lines().count().max(1)
}
