//! `rotavg demo`: the three problems on built-in, seeded synthetic instances (no files needed;
//! `rotavg::report::DemoReport`).

use crate::Outcome;

/// Arguments of `rotavg demo`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Seed of the synthetic instances.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of nodes of the multiple-averaging instance.
    #[arg(long, default_value_t = 1000)]
    pub nodes: usize,
    /// Print the proof's details (the certificates' whole explanations).
    #[arg(long, short = 'v')]
    pub verbose: bool,
}

/// Run the demo. The verdict returned is the worst of the certificates.
pub fn run(args: &Args) -> rotavg::Result<Outcome> {
    let report = rotavg::report::DemoReport::run(args.seed, args.nodes)?;
    println!("{}", rotavg::report::text(&report, args.verbose));
    Ok(Some(report.worst_verdict()))
}
