//! `rotavg certify INPUT --estimate FILE [--format ...] [--certify ...] [--json]`: certify an
//! estimate computed elsewhere, or report its proven gap, **without changing it**.
//!
//! The problem kind comes from INPUT (`rotavg::io::input::detect_problem_kind`): g2o / 1DSfM
//! files, COLMAP databases and JSON with `"edges"` are multiple problems (estimate in any
//! format of `rotavg::io::input::load_estimate_for`: JSON, g2o vertices, COLMAP models, Bundler,
//! rotation lists, matched to the nodes by id or image name), JSON with `"rotations"` single
//! and with `"pairs"` conjugate problems (estimate `{"rotation": R}`), all under chordal L2.
//! Printed as `rotavg::report::CertifyReport`.

use crate::Outcome;
use crate::common::{Common, choice};
use crate::multiple::certify_modes;
use clap::Args as ClapArgs;
use rotavg::Result;
use rotavg::certify::{CertifyMode, CertifySettings};
use rotavg::io::detect::GraphFormat;
use rotavg::io::input::{LoadedProblem, load_estimate, load_estimate_for, load_problem};
use rotavg::io::names::Choice;
use rotavg::report::CertifyReport;

/// Arguments of `rotavg certify`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Problem file (or a COLMAP database, or the folder holding database.db), or `-` for
    /// standard input.
    pub input: String,
    /// The estimate to certify. View graphs: JSON (`{"rotations": [...]}` in node order, or
    /// rotavg's `--output` with `node_ids`), g2o / TORO vertex lines (e.g. GTSAM's or rotavg's
    /// g2o output), a COLMAP sparse model folder (e.g. GLOMAP's `sparse/0`), `images.bin` or
    /// `images.txt`, Bundler `.out`, a rotation list; matched to the nodes by id, or by image
    /// name when the problem has names (a COLMAP database). Single and conjugate problems:
    /// JSON `{"rotation": R}`.
    #[arg(long, value_name = "PATH")]
    pub estimate: String,
    /// Input format (multiple problems).
    #[arg(long, value_parser = choice(GraphFormat::choices()), default_value_t = GraphFormat::Auto)]
    pub format: GraphFormat,
    /// Bounding methods for multiple problems when the dual certificate fails (`none` = dual).
    #[arg(long, value_parser = choice(certify_modes()), default_value_t = CertifyMode::Auto)]
    pub certify: CertifyMode,
    /// Write an SVG figure (multiple and conjugate problems): histogram of the residual angles
    /// (degrees), the certificate, and the smallest eigenvalues of the certificate matrix.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<Outcome> {
    if args.common.init.is_some() {
        // a usage error (exit status 2): certify never starts a solve from a point of its own
        clap::Error::raw(
            clap::error::ErrorKind::ArgumentConflict,
            "--init does not apply to `rotavg certify`: it evaluates the estimate given by \
             --estimate and never changes it (--init starts the local solver of single, multiple \
             and conjugate)\n",
        )
        .exit();
    }
    let options = args.common.read_options();
    let problem = load_problem(&args.input, args.format, &options)?;
    let estimate = match &problem {
        LoadedProblem::Multiple(g) => {
            let e = load_estimate_for(&args.estimate, g, &options)?;
            if let Some(w) = &e.warning
                && !args.common.quiet
            {
                eprintln!("rotavg: warning: {w}");
            }
            e.into_loaded()
        }
        LoadedProblem::Single(_) | LoadedProblem::Conjugate(_) => {
            load_estimate(&args.estimate, &options)?
        }
    };
    if args.plot.is_some() {
        CertifyReport::require_figure(&problem)?;
    }
    // `--certify` chooses the bounds of multiple problems; the others have one certifier.
    let settings = match &problem {
        LoadedProblem::Multiple(g) => {
            args.common.progress(format_args!(
                "certifying an estimate of {} rotations...",
                g.problem.num_rotations()
            ));
            CertifySettings {
                mode: match args.certify {
                    CertifyMode::None => CertifyMode::Dual,
                    m => m,
                },
                spectrum: args.plot.as_ref().map(|_| Default::default()),
                budget: args.common.budget(),
                dual: args.common.dual(),
                ..Default::default()
            }
        }
        LoadedProblem::Single(_) | LoadedProblem::Conjugate(_) => CertifySettings {
            budget: args.common.budget(),
            ..Default::default()
        },
    };
    let report = CertifyReport::certify(&args.input, &problem, estimate, &settings)?;
    if let Some(path) = &args.plot {
        report.write_figure(path, &problem)?;
    }
    args.common.print(&report)?;
    Ok(Outcome {
        verdict: Some(report.verdict()),
    })
}
