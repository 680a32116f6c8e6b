//! The `rotavg` command line: the verbs `demo`, `single`, `multiple`, `conjugate`, `rig`,
//! `certify` and `info` (the contract: docs/reference/contract.md section 5, and docs/reference/cli.md). The option groups the
//! verbs share are in `common.rs`. Exit status: 0 success (whatever the verdict), 1 bad input
//! or failure, 2 usage error, 3 with `--require-certified` when the verdict is not `certified`.

mod certify;
mod common;
mod conjugate;
mod demo;
mod info;
mod multiple;
mod progress;
mod rig;
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
    /// A two-sensor rig: frames and sensor_from_rig from two view graphs, jointly.
    Rig(rig::Args),
    /// Certify (or bound the gap of) an estimate computed elsewhere, without changing it.
    Certify(certify::Args),
    /// Describe an input file: sizes, components, degrees, spectral gap.
    Info(info::Args),
}

/// What a subcommand reports back for the exit status: the verdict of the certificate, if one
/// was computed.
pub type Outcome = Option<Verdict>;

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
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage(e),
    };
    let (verb, input, common): (&str, Option<&str>, Option<&Common>) = match &cli.command {
        Command::Demo(_) => ("demo", None, None),
        Command::Single(a) => ("single", Some(&a.input), Some(&a.common)),
        Command::Multiple(a) => ("multiple", Some(&a.input), Some(&a.common)),
        Command::Conjugate(a) => ("conjugate", a.input.as_deref(), Some(&a.common)),
        Command::Certify(a) => ("certify", a.input.as_deref(), Some(&a.common)),
        Command::Rig(a) => ("rig", Some(&a.right), Some(&a.common)),
        Command::Info(a) => ("info", Some(&a.input), None),
    };
    progress::install(common.map(|c| (c.quiet, c.json)));
    let result = match &cli.command {
        Command::Demo(a) => demo::run(a),
        Command::Single(a) => single::run(a),
        Command::Multiple(a) => multiple::run(a),
        Command::Conjugate(a) => conjugate::run(a),
        Command::Certify(a) => certify::run(a),
        Command::Rig(a) => rig::run(a),
        Command::Info(a) => info::run(a),
    };
    progress::finish();
    match result {
        Ok(verdict) if common.is_some_and(|c| c.require_certified) => {
            if verdict == Some(Verdict::Certified) {
                return ExitCode::SUCCESS;
            }
            if !common.is_some_and(|c| c.quiet) {
                let v = verdict.map_or("none".to_string(), |v| v.to_string());
                eprintln!("rotavg: --require-certified: verdict is {v}");
            }
            ExitCode::from(3)
        }
        Ok(_) => ExitCode::SUCCESS,
        Err(e) => {
            let text = rotavg::report::error_text(e, input, verb);
            eprintln!("rotavg: error: {text}");
            ExitCode::from(1)
        }
    }
}

/// Help and version on stdout, the help in lines of [`common::TEXT_WIDTH`] (clap writes each
/// option's paragraph on one line); any other parse error as clap prints it (exit status 2).
fn usage(e: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    match e.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => {
            let text = e.render().to_string();
            print!("{}", rotavg::report::wrap_lines(&text, common::TEXT_WIDTH));
            ExitCode::SUCCESS
        }
        _ => e.exit(),
    }
}
