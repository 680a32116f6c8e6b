//! Options shared by the problem subcommands (SPEC section 5, "Common options"), the parser
//! of the library's named choices, progress lines and printing a report.

use clap::Args as ClapArgs;
use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use rotavg::certify::{Budget, DualSettings};
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
    /// g2o / TORO edges with an information matrix: SE-Sync's scalar `kappa` (`kappa`,
    /// default) or their full 3x3 rotation information, which makes the problem anisotropic
    /// (`full`; docs/guides/anisotropic.md). COLMAP databases: weights 1 (default), or with
    /// `full` each pair's rotation information from its inlier correspondences and cameras.
    #[arg(long, value_name = "kappa|full", default_value = "kappa", value_parser = ["kappa", "full"])]
    pub information: String,
    /// Start the local solver from this estimate (JSON estimate file; `multiple` reads every
    /// estimate format of `rotavg certify --estimate`: g2o vertices, a COLMAP model folder /
    /// `images.bin` / `images.txt`, Bundler, rotation lists, matched by id or image name).
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
    /// Print the proof's details: every rung of the proof ladder that ran, the tolerance rule,
    /// the whole explanation with the labels of paper-notes/ (e.g. [D15]), long lines unbroken.
    #[arg(long, short = 'v')]
    pub verbose: bool,
    /// Time budget of the certificate, seconds (`none`: no limit). A proof step predicted or
    /// found to exceed it is not started; the verdict is then `inconclusive` with the reason.
    #[arg(long, value_name = "SECONDS", default_value = "600", value_parser = parse_seconds)]
    pub max_seconds: Seconds,
    /// Memory budget of one factorisation of the certificate: bytes, or with a suffix K, M, G,
    /// T (powers of 1024), e.g. `8G`. A proof whose factor would not fit is not started.
    #[arg(long, value_name = "SIZE", default_value = "4G", value_parser = parse_bytes)]
    pub max_memory: u64,
    /// Seed of the randomized Chebyshev test [D16] (multiple averaging, run when no proof fits
    /// the budget; its Monte Carlo bound is reported beside the `inconclusive` verdict). Default:
    /// a fresh seed per run, printed with the result.
    #[arg(long, value_name = "N")]
    pub randomized_seed: Option<u64>,
    /// Do not run the randomized Chebyshev test [D16].
    #[arg(long, conflicts_with = "randomized_seed")]
    pub no_randomized: bool,
}

/// A time limit in seconds, or none.
#[derive(Debug, Clone, Copy)]
pub struct Seconds(pub Option<f64>);

/// `none`, or a positive finite number of seconds.
fn parse_seconds(text: &str) -> Result<Seconds, String> {
    if text.eq_ignore_ascii_case("none") {
        return Ok(Seconds(None));
    }
    match text.parse::<f64>() {
        Ok(t) if t.is_finite() && t > 0.0 => Ok(Seconds(Some(t))),
        _ => Err(format!(
            "`{text}` is not a positive number of seconds or `none`"
        )),
    }
}

/// A positive size in bytes with an optional K, M, G or T suffix (powers of 1024; a trailing
/// `B` or `iB` is accepted).
pub fn parse_bytes(text: &str) -> Result<u64, String> {
    let t = text.trim();
    let upper = t.to_ascii_uppercase();
    let stem = upper
        .strip_suffix("IB")
        .or_else(|| upper.strip_suffix('B'))
        .unwrap_or(&upper);
    let (number, unit) = match stem.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => (&stem[..i], c),
        _ => (stem, ' '),
    };
    let shift = match unit {
        ' ' => 0,
        'K' => 10,
        'M' => 20,
        'G' => 30,
        'T' => 40,
        _ => return Err(format!("`{text}`: unknown unit (use K, M, G or T)")),
    };
    match number.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v >= 1.0 && v * ((1u64 << shift) as f64) < 2f64.powi(63) => {
            Ok((v * (1u64 << shift) as f64) as u64)
        }
        _ => Err(format!("`{text}` is not a size of at least 1 byte")),
    }
}

impl Common {
    /// The readers' options.
    pub fn read_options(&self) -> ReadOptions {
        ReadOptions {
            weights: self.weights,
            full_information: self.information == "full",
            ..Default::default()
        }
    }

    /// The certificate's budget from `--max-seconds` and `--max-memory`.
    pub fn budget(&self) -> Budget {
        Budget {
            max_memory_bytes: self.max_memory,
            max_seconds: self.max_seconds.0,
        }
    }

    /// The dual certificate's settings with `--randomized-seed` / `--no-randomized`.
    pub fn dual(&self) -> DualSettings {
        let mut d = DualSettings::default();
        d.randomized.seed = self.randomized_seed;
        d.randomized.enabled = !self.no_randomized;
        d
    }

    /// Show a progress message on the display line (a terminal's stderr only; never under
    /// `--quiet` or `--json`, see `progress.rs`).
    pub fn progress(&self, message: std::fmt::Arguments<'_>) {
        crate::progress::say(message);
    }

    /// Print a report: its JSON with `--json`, its text unless `--quiet`.
    pub fn print<R: Serialize + Display>(&self, report: &R) -> rotavg::Result<()> {
        print(report, self.json, self.quiet, self.verbose)
    }
}

/// The width of the default text output: longer lines are broken (`--verbose` does not).
pub const TEXT_WIDTH: usize = 100;

/// Print a report: `serde_json::to_string(report)` when `json`, else unless `quiet` its text:
/// the short form broken into lines of at most [`TEXT_WIDTH`] characters, or with `verbose`
/// the alternate form (`{:#}`: the proof's details).
pub fn print<R: Serialize + Display>(
    report: &R,
    json: bool,
    quiet: bool,
    verbose: bool,
) -> rotavg::Result<()> {
    crate::progress::finish();
    if json {
        let text = serde_json::to_string(report).map_err(|e| rotavg::Error::Io {
            path: "<stdout>".into(),
            message: e.to_string(),
        })?;
        println!("{text}");
    } else if verbose && !quiet {
        println!("{report:#}");
    } else if !quiet {
        println!(
            "{}",
            rotavg::report::wrap_lines(&report.to_string(), TEXT_WIDTH)
        );
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_and_seconds_parse() {
        assert_eq!(parse_bytes("4G"), Ok(4 << 30));
        assert_eq!(parse_bytes("512MiB"), Ok(512 << 20));
        assert_eq!(parse_bytes("1.5k"), Ok(1536));
        assert_eq!(parse_bytes("1000"), Ok(1000));
        assert!(parse_bytes("0").is_err());
        assert!(parse_bytes("-3G").is_err());
        assert!(parse_bytes("4X").is_err());
        assert!(parse_bytes("nan").is_err());
        assert!(parse_bytes("1e30T").is_err());
        assert_eq!(parse_seconds("none").map(|s| s.0), Ok(None));
        assert_eq!(parse_seconds("2.5").map(|s| s.0), Ok(Some(2.5)));
        assert!(parse_seconds("0").is_err());
        assert!(parse_seconds("inf").is_err());
    }
}
