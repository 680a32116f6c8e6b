//! `rotavg single INPUT`: the L^p mean of the JSON file of contract section 5, certified
//! (`rotavg::pipeline::average_single`, printed as `rotavg::report::SingleReport`).

use crate::Outcome;
use crate::common::{Common, InitArgs, RotationOutputArgs, choice};
use rotavg::certify::CertifyMode;
use rotavg::io::input::{read_input, read_single_problem};
use rotavg::io::names::Choice;
use rotavg::pipeline::{AverageSettings, average_single};
use rotavg::report::SingleReport;
use rotavg::single::SingleSettings;
use rotavg::{Loss, Metric, Objective};

/// Arguments of `rotavg single`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input file, or `-` for standard input.
    pub input: String,
    /// The distance d(R_i, R).
    #[arg(long, value_parser = choice(Metric::choices()), default_value_t = Metric::Chordal)]
    pub metric: Metric,
    /// The exponent p of the cost sum_i w_i d(R_i, R)^p (1 or 2).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=2))]
    pub p: u32,
    /// Certification.
    #[arg(long, value_parser = choice(vec![CertifyMode::Auto, CertifyMode::Theory, CertifyMode::BranchAndBound, CertifyMode::None]), default_value_t = CertifyMode::Auto)]
    pub certify: CertifyMode,
    #[command(flatten)]
    pub init: InitArgs,
    #[command(flatten)]
    pub output: RotationOutputArgs,
    #[command(flatten)]
    pub common: Common,
}

/// Run the subcommand.
pub fn run(args: &Args) -> rotavg::Result<Outcome> {
    let report = args
        .output
        .around(|| solve(args), |r| r.result.solution.estimate)?;
    args.common.finish(&report, report.verdict())
}

/// Read, solve and certify.
fn solve(args: &Args) -> rotavg::Result<SingleReport> {
    let options = args.common.read_options();
    let input = read_input(&args.input)?;
    let problem = read_single_problem(&input.text, &input.name, &options)?;
    let init = args.init.rotation(&options)?;
    let loss = if args.p == 1 { Loss::L1 } else { Loss::L2 };
    let problem = problem.with_objective(Objective::new(args.metric, loss))?;
    let settings = AverageSettings {
        solve: SingleSettings {
            init,
            max_seconds: args.common.solve_seconds(),
            ..Default::default()
        },
        certify: args.common.settings(args.certify),
    };
    Ok(SingleReport::new(average_single(&problem, &settings)?))
}
