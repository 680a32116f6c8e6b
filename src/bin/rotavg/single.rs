//! `rotavg single`.

use crate::Outcome;
use crate::common::{Common, not_implemented};
use clap::Args as ClapArgs;

/// Arguments of `rotavg single`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Input file, or `-` for standard input.
    pub input: String,
    #[command(flatten)]
    pub common: Common,
}

/// Run the subcommand.
pub fn run(_args: &Args) -> rotavg::Result<Outcome> {
    Err(not_implemented("single"))
}
