//! `rotavg info INPUT [--format auto|g2o|1dsfm|json|colmap] [--weights file|unit] [--json]`: describe
//! a view-graph file (`rotavg::report::InfoReport`).

use crate::Outcome;
use crate::common::choice;
use rotavg::io::detect::{GraphFormat, ReadOptions, WeightSource};
use rotavg::io::names::Choice;
use rotavg::report::InfoReport;

/// Arguments of `rotavg info`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input file (or a folder holding a COLMAP database.db), or `-` for standard input.
    pub input: String,
    /// Input format.
    #[arg(long, value_parser = choice(GraphFormat::choices()), default_value_t = GraphFormat::Auto)]
    pub format: GraphFormat,
    /// Weights from the file (`file`, default) or all 1 (`unit`).
    #[arg(long, value_parser = choice(WeightSource::choices()), default_value_t = WeightSource::File)]
    pub weights: WeightSource,
    /// Print one JSON object instead of the readable summary.
    #[arg(long)]
    pub json: bool,
}

/// Run the subcommand.
pub fn run(args: &Args) -> rotavg::Result<Outcome> {
    let options = ReadOptions {
        weights: args.weights,
        ..Default::default()
    };
    let report = InfoReport::load(&args.input, args.format, &options)?;
    crate::common::print(&report, args.json, false, false)?;
    Ok(None)
}
