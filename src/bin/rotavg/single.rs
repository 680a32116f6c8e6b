//! `rotavg single INPUT [--metric chordal|quaternion|geodesic] [--p 1|2]
//! [--certify auto|theory|branch_and_bound|none] [--json]`: the L^p mean of the JSON file of
//! SPEC section 5, certified (`rotavg::report::SingleReport`).

use crate::Outcome;
use crate::common::{Common, choice};
use clap::Args as ClapArgs;
use rotavg::certify::{CertifyMode, CertifySettings};
use rotavg::io::input::{load_estimate, read_input, read_single_problem};
use rotavg::io::names::Choice;
use rotavg::pipeline::{AverageSettings, average_single};
use rotavg::report::SingleReport;
use rotavg::single::SingleSettings;
use rotavg::{Loss, Metric, Objective};

/// Arguments of `rotavg single`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Input file, or `-` for standard input.
    pub input: String,
    /// The distance d(R_i, R).
    #[arg(long, value_parser = choice(Metric::choices()), default_value_t = Metric::Chordal)]
    pub metric: Metric,
    /// The exponent p of the cost sum_i w_i d(R_i, R)^p (1 or 2).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=2))]
    pub p: u32,
    /// Certification: `auto` (theorems, then branch and bound over SO(3) when they do not
    /// certify), `theory`, `branch_and_bound`, `none`.
    #[arg(long, value_parser = choice(vec![CertifyMode::Auto, CertifyMode::Theory, CertifyMode::BranchAndBound, CertifyMode::None]), default_value_t = CertifyMode::Auto)]
    pub certify: CertifyMode,
    #[command(flatten)]
    pub common: Common,
}

/// Run the subcommand.
pub fn run(args: &Args) -> rotavg::Result<Outcome> {
    let options = args.common.read_options();
    let input = read_input(&args.input)?;
    let problem = read_single_problem(&input.text, &input.name, &options)?;
    let init = match &args.common.init {
        Some(path) => Some(load_estimate(path, &options)?.into_rotation()?),
        None => None,
    };
    let loss = if args.p == 1 { Loss::L1 } else { Loss::L2 };
    let problem = problem.with_objective(Objective::new(args.metric, loss))?;
    let settings = AverageSettings {
        solve: SingleSettings {
            init,
            ..Default::default()
        },
        certify: CertifySettings {
            budget: args.common.budget(),
            ..CertifySettings::with_mode(args.certify)
        },
    };
    let report = SingleReport::new(average_single(&problem, &settings)?);
    args.common.print(&report)?;
    Ok(Outcome {
        verdict: report.verdict(),
    })
}
