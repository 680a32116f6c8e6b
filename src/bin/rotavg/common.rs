//! Options shared by the problem subcommands (SPEC section 5, "Common options").

use clap::{Args as ClapArgs, ValueEnum};
use std::path::PathBuf;

/// Where edge/sample weights come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum WeightSource {
    /// Weights from the file where the format has them (g2o: SE-Sync's kappa).
    #[default]
    File,
    /// All weights 1.
    Unit,
}

/// Common options.
#[derive(ClapArgs, Debug, Clone)]
pub struct Common {
    /// Weights from the file (`file`, default) or all 1 (`unit`).
    #[arg(long, value_enum, default_value_t = WeightSource::File)]
    pub weights: WeightSource,
    /// Start the local solver from this estimate (JSON estimate file).
    #[arg(long, value_name = "FILE")]
    pub init: Option<PathBuf>,
    /// Exit with status 3 unless the verdict is `certified`.
    #[arg(long)]
    pub require_certified: bool,
    /// Print nothing on stdout/stderr except errors and `--json` output.
    #[arg(long)]
    pub quiet: bool,
    /// Print one JSON object on stdout (SPEC section 5) instead of the readable summary.
    #[arg(long)]
    pub json: bool,
}

/// Read an input argument: a path, or `-` for standard input. Returns (display name, text).
pub fn read_input(path: &str) -> rotavg::Result<(String, String)> {
    use std::io::Read;
    if path == "-" {
        let mut s = String::new();
        std::io::stdin()
            .read_to_string(&mut s)
            .map_err(|e| rotavg::Error::Io {
                path: "-".into(),
                message: e.to_string(),
            })?;
        Ok(("-".into(), s))
    } else {
        let s = std::fs::read_to_string(path).map_err(|e| rotavg::Error::Io {
            path: path.into(),
            message: e.to_string(),
        })?;
        Ok((path.into(), s))
    }
}

/// Print a progress line on stderr, only when it can help a person watching: not under
/// `--quiet` or `--json`, and only when stderr is a terminal (never into logs or pipes).
pub fn progress(common: &Common, message: std::fmt::Arguments<'_>) {
    use std::io::IsTerminal;
    if !common.quiet && !common.json && std::io::stderr().is_terminal() {
        eprintln!("rotavg: {message}");
    }
}
