//! Typed reports: what the `rotavg` command prints, as values. Each report is built from a
//! pipeline's result ([`crate::pipeline::Averaged`]) or a certification, plus the context of
//! its input (file name, format, node ids, ground-truth accuracy, other components,
//! diagnostics). Its `Serialize` is the `--json` object of the subcommand (contract section 5) and
//! its `Display` is the text the subcommand prints; the command line prints nothing else.
//!
//! | subcommand | report | JSON `problem` |
//! |---|---|---|
//! | `rotavg single` | [`SingleReport`] | `single` |
//! | `rotavg multiple` | [`MultipleReport`] | `multiple` |
//! | `rotavg conjugate` | [`ConjugateReport`] | `conjugate` |
//! | `rotavg certify` | [`CertifyReport`] (`solver: null`) | any of the three |
//! | `rotavg info` | [`InfoReport`] | — (a file description) |
//! | `rotavg demo` | [`DemoReport`] (text only) | — |
//!
//! Every problem report has the contract's keys first, in its order: `problem`, `num_rotations`,
//! `num_measurements`, the objective (`metric`, `p`, `loss` where the subcommand prints them),
//! `cost`, `estimate`, `solver`, `certificate`; then the keys of its subcommand.
//!
//! ```
//! use rotavg::pipeline::{average_single, AverageSettings};
//! use rotavg::report::SingleReport;
//! use rotavg::single::SingleProblem;
//! use rotavg::so3::exp;
//! let samples = vec![exp(&nalgebra::Vector3::new(0.1, 0.0, 0.0)), exp(&nalgebra::Vector3::new(-0.1, 0.0, 0.0))];
//! let result = average_single(&SingleProblem::new(samples, None)?, &AverageSettings::default())?;
//! let report = SingleReport::new(result);
//! let json: serde_json::Value = serde_json::to_value(&report).unwrap();
//! assert_eq!(json["problem"], "single");
//! assert_eq!(json["certificate"]["verdict"], "certified");
//! assert!(report.to_string().starts_with("single rotation average: chordal l2 mean of 2 samples"));
//! # Ok::<(), rotavg::Error>(())
//! ```

pub mod certify;
pub mod conjugate;
pub mod demo;
mod errors;
pub mod info;
pub mod multiple;
pub mod rig;
pub mod rig_file;
mod rig_robust;
pub mod rig_two_graphs;
pub mod single;

pub use crate::io::input::ProblemKind;
pub use certify::CertifyReport;
pub use conjugate::ConjugateReport;
pub use demo::DemoReport;
pub use errors::error_text;
pub use info::InfoReport;
pub use multiple::{CertifiedEstimate, MultipleReport, VerdictOf};
pub use rig::{RigReport, rig_problem};
pub use rig_file::RigFileReport;
pub use single::SingleReport;

use crate::certify::MethodRun;
use crate::so3::Rotation;
use crate::warning::Warning;
use serde::Serialize;
use std::fmt;

pub(crate) use crate::pipeline::nested;

/// The command line's width of text lines (reports, warnings, help).
pub const TEXT_WIDTH: usize = 100;

/// A report as the command line prints it: its JSON (`json`), or its text broken into lines of
/// at most [`TEXT_WIDTH`] characters ([`wrap_lines`]), or with `verbose` its alternate form
/// (`{:#}`: the proof's details, long lines as they are).
///
/// ```
/// use rotavg::{Verdict, report::render};
/// assert_eq!(render(&Verdict::Certified, true, false)?, "\"certified\"");
/// assert_eq!(render(&Verdict::Certified, false, false)?, "certified");
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn render<R: Serialize + fmt::Display>(
    report: &R,
    json: bool,
    verbose: bool,
) -> crate::Result<String> {
    Ok(if json {
        serde_json::to_string(report).map_err(|e| crate::Error::Io {
            path: "<stdout>".into(),
            message: e.to_string(),
        })?
    } else {
        text(report, verbose)
    })
}

/// A report's text: broken into lines of at most [`TEXT_WIDTH`] characters, or with `verbose`
/// its alternate form (`{:#}`).
pub fn text(report: &impl fmt::Display, verbose: bool) -> String {
    if verbose {
        format!("{report:#}")
    } else {
        wrap_lines(&report.to_string(), TEXT_WIDTH)
    }
}

/// `text` with every line longer than `width` characters broken after a `; ` or `, ` (or else a
/// space) before the limit, the continuation indented two spaces more than the line: the
/// command line's default text output (`--verbose` prints the long lines as they are).
pub fn wrap_lines(text: &str, width: usize) -> String {
    let mut out = String::with_capacity(text.len() + 64);
    for (k, line) in text.split('\n').enumerate() {
        if k > 0 {
            out.push('\n');
        }
        let indent = line.len() - line.trim_start().len();
        let pad = " ".repeat(indent + 2);
        let mut rest = line;
        let mut first = true;
        loop {
            let limit = if first { width } else { width - pad.len() };
            if rest.chars().count() <= limit {
                out.push_str(rest);
                break;
            }
            let cut = rest
                .char_indices()
                .nth(limit)
                .map_or(rest.len(), |(i, _)| i);
            let head = &rest[..cut];
            let at = ["; ", ", ", " "].iter().find_map(|sep| {
                head.rfind(sep)
                    .filter(|&i| i > indent + 8)
                    .map(|i| i + sep.len())
            });
            let Some(at) = at else {
                out.push_str(rest);
                break;
            };
            out.push_str(rest[..at].trim_end());
            out.push('\n');
            out.push_str(&pad);
            rest = rest[at..].trim_start();
            first = false;
        }
    }
    out
}

/// The end of a report's text: a line break, the result (`{:#}` in the alternate form) and the
/// verdict with its problem, when there is one.
pub(crate) fn result_and_verdict(
    f: &mut fmt::Formatter<'_>,
    result: &dyn fmt::Display,
    verdict: Option<VerdictOf>,
) -> fmt::Result {
    writeln!(f)?;
    nested(f, result)?;
    if let Some(v) = verdict {
        write!(f, "\n{v}")?;
    }
    Ok(())
}

/// The solver report of an estimate computed elsewhere and certified unchanged.
pub(crate) fn given_report() -> crate::termination::SolverReport {
    crate::termination::SolverReport {
        name: "given (certified, not changed)".into(),
        iterations: 0,
        termination: crate::termination::Termination::ClosedForm,
        seconds: 0.0,
    }
}

/// A given `solution` with the certification `c` of it, as a pipeline's result (its time all
/// the certificate's).
pub(crate) fn given_result<S, T>(
    solution: S,
    c: crate::certify::Certification<T>,
) -> crate::pipeline::Averaged<S> {
    let details = crate::pipeline::PipelineDetails {
        certify_seconds: c.details.seconds,
        total_seconds: c.details.seconds,
        certify: Some(c.details),
        ..Default::default()
    };
    crate::pipeline::Averaged {
        solution,
        certificate: Some(c.certificate),
        details,
    }
}

/// An estimate in JSON: one row-major rotation, or a list of them.
#[derive(Serialize)]
#[serde(untagged)]
enum Rows<'a> {
    /// `R` as `[[r11, r12, r13], ...]`.
    One(#[serde(with = "crate::so3::serde_rows::rotation")] &'a Rotation),
    /// `[R, ...]`.
    Many(#[serde(with = "crate::so3::serde_rows::rotations")] &'a [Rotation]),
}

/// A problem report's JSON: the contract's keys every problem report starts with (`problem`,
/// `num_rotations`, `num_measurements`), then the report's own keys (`rest`, in its order).
#[derive(Serialize)]
struct ProblemJson<J> {
    problem: ProblemKind,
    num_rotations: usize,
    num_measurements: usize,
    /// Every warning the text prints ([`crate::warning`]), on every verb.
    warnings: Vec<crate::warning::Warning>,
    #[serde(flatten)]
    rest: J,
}

impl<J> ProblemJson<J> {
    /// The JSON of a `problem` report with `num_rotations` unknowns and `num_measurements`
    /// measurements (samples, edges or pairs), no warnings, followed by `rest`.
    fn new(problem: ProblemKind, num_rotations: usize, num_measurements: usize, rest: J) -> Self {
        ProblemJson {
            problem,
            num_rotations,
            num_measurements,
            warnings: Vec::new(),
            rest,
        }
    }

    /// The same with `warnings`.
    fn with_warnings(mut self, warnings: Vec<crate::warning::Warning>) -> Self {
        self.warnings = warnings;
        self
    }
}

/// The lines `  METHOD (T s): NOTE` of the bounding methods that ran (the rungs of the proof
/// ladder), in the alternate form only (`{:#}`, the command line's `--verbose`).
/// What a report's input was (`input` of the JSON): the path as given, its format and the
/// options it was read with (view graphs), and the estimate file (`certify`).
#[derive(Debug, Clone, Copy, Serialize)]
pub(crate) struct InputJson<'a> {
    pub path: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub format: Option<crate::io::detect::GraphFormat>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub read: Option<&'a crate::io::detect::ReadOptions>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimate: Option<&'a str>,
}

/// The warnings of a view graph as read: the reader's, and `duplicates_disagree` for pairs
/// measured more than once whose measurements disagree by more than
/// [`StatsSettings::contradiction_deg`](crate::multiple::stats::StatsSettings) (5 degrees).
pub(crate) fn input_warnings(graph: &crate::io::detect::LoadedGraph) -> Vec<Warning> {
    use crate::multiple::stats::{StatsSettings, duplicates_disagree};
    let threshold = StatsSettings::default().contradiction_deg;
    let disagree = duplicates_disagree(&graph.problem, &graph.node_ids, threshold);
    graph.warnings.iter().cloned().chain(disagree).collect()
}

fn write_methods(f: &mut fmt::Formatter<'_>, methods: &[MethodRun]) -> fmt::Result {
    if !f.alternate() {
        return Ok(());
    }
    for m in methods {
        write!(f, "\n  {} ({:.3} s): {}", m.method, m.seconds, m.note)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::wrap_lines;

    #[test]
    fn long_lines_break_after_separators() {
        let line = format!("head: {}; tail, end", "word ".repeat(20).trim_end());
        let wrapped = wrap_lines(&line, 40);
        assert!(
            wrapped.lines().all(|l| l.chars().count() <= 40),
            "{wrapped}"
        );
        assert!(
            wrapped.lines().skip(1).all(|l| l.starts_with("  ")),
            "{wrapped}"
        );
        let words = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
        assert_eq!(words(&wrapped), words(&line));
        assert_eq!(wrap_lines("short\n  also short", 40), "short\n  also short");
    }
}
