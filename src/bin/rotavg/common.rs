//! Options shared by the problem subcommands (SPEC section 5, "Common options"), the parser
//! of the library's named choices, progress lines and printing a report.

use clap::Args as ClapArgs;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use rotavg::io::detect::{ReadOptions, WeightSource};
use rotavg::io::names::Choice;
use serde::Serialize;
use std::fmt::Display;

/// Common options.
#[derive(ClapArgs, Debug, Clone)]
pub struct Common {
    /// Weights from the file (`file`, default) or all 1 (`unit`).
    #[arg(long, value_parser = choice(WeightSource::choices()), default_value_t = WeightSource::File)]
    pub weights: WeightSource,
    /// Start the local solver from this estimate (JSON estimate file).
    #[arg(long, value_name = "FILE")]
    pub init: Option<String>,
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

impl Common {
    /// The readers' options.
    pub fn read_options(&self) -> ReadOptions {
        ReadOptions {
            weights: self.weights,
            ..Default::default()
        }
    }

    /// Print a progress line on stderr, only when it can help a person watching: not under
    /// `--quiet` or `--json`, and only when stderr is a terminal (never into logs or pipes).
    pub fn progress(&self, message: std::fmt::Arguments<'_>) {
        use std::io::IsTerminal;
        if !self.quiet && !self.json && std::io::stderr().is_terminal() {
            eprintln!("rotavg: {message}");
        }
    }

    /// Print a report: its JSON with `--json`, its text unless `--quiet`.
    pub fn print<R: Serialize + Display>(&self, report: &R) -> rotavg::Result<()> {
        print(report, self.json, self.quiet)
    }
}

/// Print a report: `serde_json::to_string(report)` when `json`, else `report.to_string()`
/// unless `quiet`.
pub fn print<R: Serialize + Display>(report: &R, json: bool, quiet: bool) -> rotavg::Result<()> {
    if json {
        let text = serde_json::to_string(report).map_err(|e| rotavg::Error::Io {
            path: "<stdout>".into(),
            message: e.to_string(),
        })?;
        println!("{text}");
    } else if !quiet {
        println!("{report}");
    }
    Ok(())
}

/// A parser of the named values `values` of a library choice (help lists their names and
/// descriptions; other names are a usage error).
pub fn choice<T: Choice>(values: Vec<T>) -> impl TypedValueParser<Value = T> {
    let possible: Vec<PossibleValue> = values
        .iter()
        .map(|v| PossibleValue::new(v.name()).help(v.help()))
        .collect();
    PossibleValuesParser::new(possible)
        .try_map(|name| T::from_name(&name).ok_or_else(|| format!("unknown value `{name}`")))
}

/// `--plot` needs the `plot` feature (on by default): without it, fail before doing any work.
pub fn check_plot(plot: Option<&String>) -> rotavg::Result<()> {
    match plot {
        Some(_) if !cfg!(feature = "plot") => Err(rotavg::report::certify::no_plot_feature()),
        _ => Ok(()),
    }
}
