//! `rotavg single INPUT [--metric chordal|quaternion|geodesic] [--p 1|2] [--json]`.
//!
//! INPUT is the JSON file of SPEC section 5 (`{"rotations": [R, ...], "weights": [w, ...]}`,
//! read by `rotavg::io::single_json`). `--json` prints one object:
//! `problem` = "single", `num_rotations` = 1 (one rotation is estimated), `num_measurements` =
//! number of samples, `metric`, `p`, `cost`, `estimate` (row-major), `solver` (name,
//! iterations, termination as an object with `status` and the measured value and threshold,
//! seconds) and `certificate`.

use crate::Outcome;
use crate::common::{Common, WeightSource, read_input};
use clap::{Args as ClapArgs, ValueEnum};
use rotavg::io::single_json::{parse_single_estimate, parse_single_json};
use rotavg::single::{Norm, SingleProblem, SingleSettings, SingleSolution, average_single_from};
use rotavg::so3::{Metric, rotation_to_rows};

/// The distance, as a command-line value.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum MetricArg {
    /// Chordal distance ||R - S||_F.
    #[default]
    Chordal,
    /// Quaternion distance 2 sin(theta / 4).
    Quaternion,
    /// Angle (geodesic) distance theta.
    Geodesic,
}

impl From<MetricArg> for Metric {
    fn from(m: MetricArg) -> Metric {
        match m {
            MetricArg::Chordal => Metric::Chordal,
            MetricArg::Quaternion => Metric::Quaternion,
            MetricArg::Geodesic => Metric::Geodesic,
        }
    }
}

/// Arguments of `rotavg single`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Input file, or `-` for standard input.
    pub input: String,
    /// The distance d(R_i, R).
    #[arg(long, value_enum, default_value_t = MetricArg::Chordal)]
    pub metric: MetricArg,
    /// The exponent p of the cost sum_i w_i d(R_i, R)^p (1 or 2).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=2))]
    pub p: u32,
    #[command(flatten)]
    pub common: Common,
}

/// Run the subcommand.
pub fn run(args: &Args) -> rotavg::Result<Outcome> {
    let (name, text) = read_input(&args.input)?;
    let mut problem = parse_single_json(&text, &name)?;
    if args.common.weights == WeightSource::Unit {
        problem = SingleProblem::new(problem.rotations().to_vec(), None)?;
    }
    let init = match &args.common.init {
        Some(path) => {
            let (file, text) = read_input(&path.display().to_string())?;
            Some(parse_single_estimate(&text, &file)?)
        }
        None => None,
    };
    let norm = Norm::from_exponent(args.p).ok_or_else(|| rotavg::Error::InvalidSettings {
        name: "p".into(),
        reason: format!("{} is not 1 or 2", args.p),
    })?;
    let settings = SingleSettings::new(args.metric.into(), norm);
    let solution = average_single_from(&problem, &settings, init.as_ref())?;
    if args.common.json {
        println!("{}", json_report(&solution));
    } else if !args.common.quiet {
        println!("{solution}");
    }
    Ok(Outcome {
        verdict: Some(solution.certificate.verdict),
    })
}

/// The `--json` object (SPEC section 5).
fn json_report(s: &SingleSolution) -> serde_json::Value {
    serde_json::json!({
        "problem": "single",
        "num_rotations": 1,
        "num_measurements": s.num_samples,
        "metric": s.metric,
        "p": s.norm.exponent(),
        "cost": s.cost,
        "estimate": rotation_to_rows(&s.estimate),
        "solver": s.report,
        "certificate": s.certificate,
    })
}
