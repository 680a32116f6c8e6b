//! The `rotavg` command-line tool. The contract is SPEC section 5 (see README.md):
//!
//! ```text
//! rotavg demo
//! rotavg single    INPUT [--metric chordal|quaternion|geodesic] [--p 1|2] [--json]
//! rotavg multiple  INPUT [--format auto|g2o|1dsfm|json] [--loss chordal|geodesic|l1|huber|cauchy]
//!                        [--certify auto|dual|sdp|none] [--json] [--output FILE]
//! rotavg conjugate INPUT [--format auto|json|...] [--certify auto|sdp|none] [--json]
//! rotavg certify   INPUT --estimate FILE [--json]
//! rotavg info      INPUT
//! ```
//!
//! Exit status: 0 success (whatever the verdict), 1 bad input or failure, 2 usage error,
//! 3 with `--require-certified` when the verdict is not `certified`.

mod certify;
mod common;
mod conjugate;
mod demo;
mod info;
mod multiple;
mod progress;
mod single;

use clap::{Parser, Subcommand};
use common::Common;
use rotavg::Verdict;
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(
    name = "rotavg",
    version,
    about = "Certifiably optimal rotation averaging"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run all problems on built-in synthetic instances (no files needed).
    Demo(demo::Args),
    /// Average many estimates of one rotation.
    Single(single::Args),
    /// Absolute rotations from relative ones on a view graph (R_ij R_i = R_j).
    Multiple(multiple::Args),
    /// Conjugate (hand-eye) averaging: S with R_i ~ S^-1 L_i S.
    Conjugate(conjugate::Args),
    /// Certify (or bound the gap of) an estimate computed elsewhere, without changing it.
    Certify(certify::Args),
    /// Describe an input file: sizes, components, degrees, spectral gap.
    Info(info::Args),
}

/// What a subcommand reports back for the exit status.
pub struct Outcome {
    /// The verdict of the certificate, if one was computed.
    pub verdict: Option<Verdict>,
}

/// Exit quietly (status 141, as a shell reports a process ended by SIGPIPE) when stdout is
/// closed by the reader, e.g. `rotavg demo | head`, instead of panicking in `println!`.
fn exit_quietly_on_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.contains("failed printing to stdout") && msg.contains("Broken pipe") {
            std::process::exit(141);
        }
        default(info);
    }));
}

fn main() -> ExitCode {
    exit_quietly_on_broken_pipe();
    let cli = Cli::parse();
    let common: Option<&Common> = match &cli.command {
        Command::Demo(_) | Command::Info(_) => None,
        Command::Single(a) => Some(&a.common),
        Command::Multiple(a) => Some(&a.common),
        Command::Conjugate(a) => Some(&a.common),
        Command::Certify(a) => Some(&a.common),
    };
    progress::Display::install(common.is_some_and(|c| !c.quiet && !c.json));
    let result = match &cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Single(a) => single::run(a),
        Command::Multiple(a) => multiple::run(a),
        Command::Conjugate(a) => conjugate::run(a),
        Command::Certify(a) => certify::run(a),
        Command::Info(a) => info::run(a),
    };
    progress::finish();
    match result {
        Ok(outcome) => {
            let require = common.is_some_and(|c| c.require_certified);
            if require && outcome.verdict != Some(Verdict::Certified) {
                if !common.is_some_and(|c| c.quiet) {
                    eprintln!(
                        "rotavg: --require-certified: verdict is {}",
                        outcome
                            .verdict
                            .map_or("none".to_string(), |v| v.to_string())
                    );
                }
                ExitCode::from(3)
            } else {
                ExitCode::SUCCESS
            }
        }
        Err(e) => {
            let text = folder_refused(named(e, input(&cli.command)), &cli.command);
            eprintln!("rotavg: error: {text}");
            ExitCode::from(1)
        }
    }
}

/// The input file of a subcommand, if it has one.
fn input(command: &Command) -> Option<&str> {
    match command {
        Command::Demo(_) => None,
        Command::Single(a) => Some(&a.input),
        Command::Multiple(a) => Some(&a.input),
        Command::Conjugate(a) => a.input.as_deref(),
        Command::Certify(a) => Some(&a.input),
        Command::Info(a) => Some(&a.input),
    }
}

/// A folder given as the input of a verb that cannot read it: the reader's error (the
/// operating system's "Is a directory", or the readers' general note on folders) becomes what
/// this verb reads instead. Other errors are unchanged.
fn folder_refused(text: String, command: &Command) -> String {
    let Some(path) = input(command) else {
        return text;
    };
    let is_folder = path != "-" && std::path::Path::new(path).is_dir();
    let Some(message) = text.strip_prefix(path).and_then(|t| t.strip_prefix(": ")) else {
        return text;
    };
    // the readers' general note on folders, or the operating system's; a specific diagnosis
    // (a database.db that is not SQLite, no hand-eye streams found) is kept
    let general = message.starts_with("is a folder, not a file") || message.contains("os error 21");
    if !is_folder || !general {
        return text;
    }
    let accepts = match command {
        Command::Single(_) => {
            "is a folder: `rotavg single` reads a file (JSON {\"rotations\": [R, ...]}), \
                     never a folder"
        }
        Command::Multiple(_) | Command::Info(_) => {
            "is a folder: as a folder, `rotavg multiple` and `rotavg info` read only a \
                     COLMAP project (a folder holding database.db); other view graphs are files \
                     (g2o, 1DSfM EGs.txt, JSON)"
        }
        Command::Conjugate(_) => {
            "is a folder: as a folder, `rotavg conjugate` reads a Tabb dataset \
                     (robot_cali.txt) or a hand and a camera pose stream (CSV files named \
                     *hand*/*base_link*/*vicon* and *camera*/*target*, or --hand/--camera)"
        }
        Command::Certify(_) => {
            "is a folder: `rotavg certify` reads the problem from a file (a view graph: \
                     g2o, 1DSfM EGs.txt, JSON; a single or conjugate JSON problem)"
        }
        Command::Demo(_) => return text,
    };
    format!("{path}: {accepts}")
}

/// The error as printed: an error about the data that does not name a file yet (a disconnected
/// graph, degenerate hand-eye pairs) names the input (issue 24).
fn named(e: rotavg::Error, input: Option<&str>) -> String {
    use rotavg::Error;
    match (e, input) {
        (
            e @ (Error::Disconnected { .. } | Error::Degenerate { .. } | Error::Empty { .. }),
            Some(file),
        ) if file != "-" => {
            format!("{file}: {e}")
        }
        (e, _) => e.to_string(),
    }
}
