//! `rotavg certify INPUT --estimate FILE [--format ...] [--certify ...] [--json]`: certify an
//! estimate computed elsewhere, or report its proven gap, **without changing it**.
//!
//! The problem type comes from INPUT: a JSON object with `"pairs"` is a conjugate problem
//! (estimate `{"rotation": S}`, chordal L2, SDP certificate), one with `"num_rotations"` or
//! `"edges"` a multiple problem, one with `"rotations"` a single problem (estimate
//! `{"rotation": R}`, chordal L2); g2o / 1DSfM files are multiple problems (estimate
//! `{"rotations": [...]}` or `{"estimate": [...]}`, one rotation per node in node order,
//! `rotavg::multiple::average::certify_multiple_estimate`). `cost` is the chordal L2 cost of
//! the given estimate.

use crate::Outcome;
use crate::common::{Common, WeightSource, read_input};
use crate::multiple::{CertifyArg, FormatArg, read_options};
use clap::Args as ClapArgs;
use rotavg::io::detect::{GraphFormat, detect_format};
use rotavg::io::json::{Estimate, read_estimate};
use rotavg::multiple::average::{AverageMultipleSettings, CertifyMode, certify_multiple_estimate};
use rotavg::single::{SingleProblem, SingleSettings, certify_single};
use rotavg::so3::{Rotation, rotation_to_rows};
use rotavg::{Certificate, Error, Result};

/// Arguments of `rotavg certify`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Problem file, or `-` for standard input.
    pub input: String,
    /// The estimate to certify (JSON: `{"rotations": [...]}`, `{"estimate": ...}` or
    /// `{"rotation": R}`).
    #[arg(long, value_name = "FILE")]
    pub estimate: String,
    /// Input format (multiple problems).
    #[arg(long, value_enum, default_value_t = FormatArg::Auto)]
    pub format: FormatArg,
    /// Bounding methods for multiple problems when the dual certificate fails (`none` = dual).
    #[arg(long, value_enum, default_value_t = CertifyArg::Auto)]
    pub certify: CertifyArg,
    /// Write an SVG figure (multiple and conjugate problems): histogram of the residual angles
    /// (degrees), the certificate, and the smallest eigenvalues of the certificate matrix.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

enum Kind {
    Multiple,
    Single,
    Conjugate,
}

fn kind_of(name: &str, text: &str, format: FormatArg) -> Result<Kind> {
    let fmt = match format {
        FormatArg::Auto => detect_format(name, text)?,
        f => f.into(),
    };
    if fmt != GraphFormat::Json {
        return Ok(Kind::Multiple);
    }
    let v: serde_json::Value = serde_json::from_str(text)
        .map_err(|e| Error::parse(Some(name), Some(e.line()), e.to_string()))?;
    let has = |k: &str| v.get(k).is_some();
    if has("pairs") {
        Ok(Kind::Conjugate)
    } else if has("num_rotations") || has("edges") {
        Ok(Kind::Multiple)
    } else if has("rotations") {
        Ok(Kind::Single)
    } else {
        Err(Error::parse(
            Some(name),
            None,
            "cannot tell the problem type: expected \"edges\"/\"num_rotations\" (multiple), \
             \"rotations\" (single) or \"pairs\" (conjugate)",
        ))
    }
}

fn one_rotation(e: Estimate, file: &str) -> Result<Rotation> {
    match e {
        Estimate::Single(r) => Ok(r),
        Estimate::Multiple(_) => Err(Error::parse(
            Some(file),
            None,
            "expected one rotation ({\"rotation\": R}) for this problem, found a list",
        )),
    }
}

fn print_summary(header: &str, cert: &Certificate, extra: &[String]) {
    println!("{header}");
    println!("cost of the given estimate: {:.9e}", cert.upper_bound);
    println!("certificate: {cert}");
    for e in extra {
        println!("  {e}");
    }
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<Outcome> {
    let options = read_options(&args.common);
    let (name, text) = read_input(&args.input)?;
    let (ename, etext) = read_input(&args.estimate)?;
    let estimate = read_estimate(&etext, &ename, &options)?;
    let kind = kind_of(&name, &text, args.format)?;
    if args.plot.is_some() && matches!(kind, Kind::Single) {
        return Err(Error::InvalidSettings {
            name: "plot".into(),
            reason: "--plot is available for multiple and conjugate problems only".into(),
        });
    }
    let cert: Certificate;
    let json;
    match kind {
        Kind::Multiple => {
            let graph = rotavg::io::detect::read_graph(&text, &name, args.format.into(), &options)?;
            let rotations = match estimate {
                Estimate::Multiple(rs) => rs,
                Estimate::Single(_) => {
                    return Err(Error::parse(
                        Some(&ename),
                        None,
                        "expected a list of rotations ({\"rotations\": [...]}) for a multiple problem",
                    ));
                }
            };
            let n = graph.problem.num_rotations();
            if rotations.len() != n {
                return Err(Error::parse(
                    Some(&ename),
                    None,
                    format!(
                        "the estimate has {} rotations, the problem has {n} nodes",
                        rotations.len()
                    ),
                ));
            }
            let settings = AverageMultipleSettings {
                certify_mode: match CertifyMode::from(args.certify) {
                    CertifyMode::None => CertifyMode::Dual,
                    m => m,
                },
                spectrum: args.plot.as_ref().map(|_| Default::default()),
                ..Default::default()
            };
            crate::common::progress(
                &args.common,
                format_args!("certifying an estimate of {n} rotations..."),
            );
            let c = certify_multiple_estimate(&graph.problem, &rotations, &settings)?;
            let cost = graph.problem.chordal_cost(&rotations);
            if let Some(path) = &args.plot {
                crate::multiple::write_plot(
                    path,
                    &graph.problem,
                    &rotations,
                    Some(&c.certificate),
                    &args.input,
                )?;
            }
            json = serde_json::json!({
                "problem": "multiple",
                "num_rotations": n,
                "num_measurements": graph.problem.num_edges(),
                "cost": cost,
                "estimate": rotations.iter().map(rotation_to_rows).collect::<Vec<_>>(),
                "node_ids": graph.node_ids,
                "solver": null,
                "certificate": c.certificate,
                "pipeline": c.details,
            });
            if !args.common.json && !args.common.quiet {
                let extra: Vec<String> = c
                    .details
                    .methods
                    .iter()
                    .map(|m| format!("{} ({:.3} s): {}", m.method, m.seconds, m.note))
                    .collect();
                print_summary(
                    &format!(
                        "{}: multiple problem, {n} nodes, {} edges; estimate {ename}",
                        args.input,
                        graph.problem.num_edges()
                    ),
                    &c.certificate,
                    &extra,
                );
            }
            cert = c.certificate;
        }
        Kind::Single => {
            let mut problem = rotavg::io::single_json::parse_single_json(&text, &name)?;
            if args.common.weights == WeightSource::Unit {
                problem = SingleProblem::new(problem.rotations().to_vec(), None)?;
            }
            let r = one_rotation(estimate, &ename)?;
            let c = certify_single(&problem, &r, &SingleSettings::default())?;
            json = serde_json::json!({
                "problem": "single",
                "num_rotations": 1,
                "num_measurements": problem.rotations().len(),
                "cost": c.upper_bound,
                "estimate": rotation_to_rows(&r),
                "solver": null,
                "certificate": c,
            });
            if !args.common.json && !args.common.quiet {
                print_summary(
                    &format!(
                        "{}: single problem (chordal L2), {} samples; estimate {ename}",
                        args.input,
                        problem.rotations().len()
                    ),
                    &c,
                    &[],
                );
            }
            cert = c;
        }
        Kind::Conjugate => {
            let mut problem = rotavg::io::handeye::read_conjugate_json(&text, &name)?;
            if args.common.weights == WeightSource::Unit {
                problem = rotavg::conjugate::ConjugateProblem::new(
                    problem
                        .pairs()
                        .iter()
                        .map(|p| rotavg::conjugate::ConjugatePair::new(p.left, p.right))
                        .collect(),
                )?;
            }
            let s = one_rotation(estimate, &ename)?;
            let c = rotavg::conjugate::certify_conjugate(
                &problem,
                &s,
                &Default::default(),
                Default::default(),
            )?;
            if let Some(path) = &args.plot {
                crate::multiple::write_figure(
                    path,
                    &problem.residual_angles(&s),
                    "pairs",
                    Some(&c),
                    1,
                    &args.input,
                )?;
            }
            json = serde_json::json!({
                "problem": "conjugate",
                "num_rotations": 1,
                "num_measurements": problem.num_pairs(),
                "cost": c.upper_bound,
                "estimate": rotation_to_rows(&s),
                "solver": null,
                "certificate": c,
            });
            if !args.common.json && !args.common.quiet {
                print_summary(
                    &format!(
                        "{}: conjugate problem (chordal L2), {} pairs; estimate {ename}",
                        args.input,
                        problem.num_pairs()
                    ),
                    &c,
                    &[],
                );
            }
            cert = c;
        }
    }
    if args.common.json {
        println!("{json}");
    }
    Ok(Outcome {
        verdict: Some(cert.verdict),
    })
}
