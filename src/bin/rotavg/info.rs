//! `rotavg info`.

use crate::Outcome;
use crate::common::not_implemented;
use clap::Args as ClapArgs;

/// Arguments of `rotavg info`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Input file, or `-` for standard input.
    pub input: String,
}

/// Run the subcommand.
pub fn run(_args: &Args) -> rotavg::Result<Outcome> {
    Err(not_implemented("info"))
}
