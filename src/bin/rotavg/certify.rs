//! `rotavg certify INPUT --estimate FILE`: certify an estimate computed elsewhere, or report
//! its proven gap, **without changing it**. The problem kind comes from INPUT (view graph,
//! single or conjugate problem: `rotavg::io::input::load_problem`), the estimate is matched to
//! it (`load_estimate_for`); printed as `rotavg::report::CertifyReport`.

use crate::Outcome;
use crate::common::{Common, GraphArgs, PlotArgs};
use rotavg::Result;
use rotavg::certify::CertifyMode;
use rotavg::io::input::{LoadedProblem, load_estimate, load_estimate_for, load_problem};
use rotavg::report::CertifyReport;

/// Arguments of `rotavg certify`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Problem file (or a COLMAP database, or the folder holding database.db), or `-` for
    /// standard input.
    pub input: String,
    /// The estimate to certify. View graphs: JSON (`{"rotations": [...]}` in node order, or with
    /// `node_ids`), g2o / TORO vertices, a COLMAP sparse model folder (e.g. GLOMAP's `sparse/0`),
    /// `images.bin` or `images.txt`, Bundler `.out`, a rotation list; matched to the nodes by id,
    /// or by image name (COLMAP). Single and conjugate problems: JSON `{"rotation": R}`.
    #[arg(long, value_name = "PATH")]
    pub estimate: String,
    #[command(flatten)]
    pub graph: GraphArgs,
    #[command(flatten)]
    pub plot: PlotArgs,
    #[command(flatten)]
    pub common: Common,
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<Outcome> {
    let options = args.graph.read_options(&args.common);
    let problem = load_problem(&args.input, args.graph.format, &options)?;
    let estimate = match &problem {
        LoadedProblem::Multiple(g) => load_estimate_for(&args.estimate, g, &options)?.into_loaded(),
        LoadedProblem::Single(_) | LoadedProblem::Conjugate(_) => {
            load_estimate(&args.estimate, &options)?
        }
    };
    if args.plot.plot.is_some() {
        CertifyReport::require_figure(&problem)?;
    }
    // `--certify` chooses the bounds of multiple problems (`none`: the dual certificate); the
    // others have one certifier.
    let settings = match &problem {
        LoadedProblem::Multiple(g) => {
            crate::progress::say(format_args!(
                "certifying an estimate of {} rotations...",
                g.problem.num_rotations()
            ));
            let mut settings = args.graph.settings(&args.common, &args.plot);
            if settings.mode == CertifyMode::None {
                settings.mode = CertifyMode::Dual;
            }
            settings
        }
        _ => args.common.settings(CertifyMode::Auto),
    };
    let report = CertifyReport::certify(&args.input, &problem, estimate, &settings)?;
    if let Some(path) = &args.plot.plot {
        report.write_figure(path, &problem)?;
    }
    args.common.finish(&report, Some(report.verdict()))
}
