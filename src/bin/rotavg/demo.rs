//! `rotavg demo`.

use crate::Outcome;
use crate::common::not_implemented;
use clap::Args as ClapArgs;

/// Arguments of `rotavg demo`.
#[derive(ClapArgs, Debug)]
pub struct Args {}

/// Run the subcommand.
pub fn run(_args: &Args) -> rotavg::Result<Outcome> {
    Err(not_implemented("demo"))
}
