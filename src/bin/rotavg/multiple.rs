//! `rotavg multiple INPUT`: multiple rotation averaging with a certificate
//! (`rotavg::pipeline::average_multiple`, printed as `rotavg::report::MultipleReport`).

use crate::Outcome;
use crate::common::{Common, GraphArgs, GravityArgs, InitArgs, PlotArgs, choice};
use rotavg::Result;
use rotavg::certify::CertifyMode;
use rotavg::io::input::{MultipleInputOptions, load_multiple_input};
use rotavg::io::names::{Choice, MultipleLoss};
use rotavg::io::output::{MultipleOutputs, OutputFormat, OutputSource};
use rotavg::multiple::gravity::GravityProblem;
use rotavg::multiple::robust_scale::ScaleRule;
use rotavg::multiple::{Initialisation, MultipleSettings};
use rotavg::pipeline::{AverageSettings, average_multiple, average_with_gravity};
use rotavg::report::MultipleReport;

/// Arguments of `rotavg multiple`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Input file (or a folder holding a COLMAP database.db), or `-` for standard input.
    pub input: String,
    #[command(flatten)]
    pub graph: GraphArgs,
    /// Loss (`auto`: least squares unless its residuals show outliers; then cauchy, and the
    /// chordal L2 problem on its inlier graph is the one certified).
    #[arg(long, value_parser = choice(MultipleLoss::choices()), default_value_t = MultipleLoss::Auto)]
    pub loss: MultipleLoss,
    /// Huber / Cauchy threshold in degrees (default 5; for L1: the inlier threshold unless
    /// `--inlier-threshold` is given); when given, also `auto`'s Cauchy scale and inlier
    /// threshold, which are otherwise from the data (1.5 x and 3 x the median residual at the
    /// L1 solution, `[D20]`).
    #[arg(long, value_name = "DEG")]
    pub loss_threshold: Option<f64>,
    /// Robust losses (l1, huber, cauchy; auto when it chooses cauchy): an edge is an inlier iff its residual angle at the
    /// robust estimate is at most DEG (default: `--loss-threshold`; for `auto` without it, 3 x
    /// the median residual at the L1 solution). The inlier graph's
    /// chordal L2 problem is refined and certified unless `--certify none`.
    #[arg(long, value_name = "DEG")]
    pub inlier_threshold: Option<f64>,
    /// Robust losses (auto: when it chooses cauchy): write the per-edge residuals, one row per edge (`i j residual_deg weight
    /// inlier`, nodes by their file ids): JSON when FILE ends in `.json`, otherwise CSV.
    #[arg(long, value_name = "FILE")]
    pub edges_output: Option<String>,
    /// Robust losses (auto: when it chooses cauchy): write the inlier graph's refined (chordal L2) estimate as `--output` (which
    /// writes the robust one, as printed) in `--output-format` (or from its path).
    #[arg(long, value_name = "FILE")]
    pub inlier_output: Option<String>,
    /// Initialisation of the local solver (ignored with `--init FILE`; `spectral` starts from the
    /// spanning tree on long chains and large grids, whose Newton systems use [M6b]).
    #[arg(long, value_parser = choice(Initialisation::choices()), default_value_t = Initialisation::Spectral)]
    pub init_method: Initialisation,
    #[command(flatten)]
    pub init: InitArgs,
    #[command(flatten)]
    pub gravity: GravityArgs,
    /// Ground truth: g2o vertices, Bundler `.out`, a COLMAP model folder / `images.bin` /
    /// `images.txt` (by image name, or id), a JSON estimate (node order, or `node_ids`), or a
    /// rotation list (`R11 .. R33` per line: line k = file id k; or `id R11 .. R33`), matched to
    /// nodes by file id. An all-zero rotation means "no ground truth for this camera".
    #[arg(long, value_name = "FILE")]
    pub ground_truth: Option<String>,
    /// Solve the largest connected component of a disconnected graph (and report the others).
    #[arg(long)]
    pub largest_component: bool,
    /// Write the estimate: JSON `{"rotations": [...], "node_ids": [...]}`; g2o for `*.g2o` (a g2o
    /// input's lines with the vertex rotations replaced); a COLMAP sparse model for a folder
    /// (`.../`) or `*images.txt`, created before the solve (see `--output-format`).
    #[arg(long, value_name = "PATH")]
    pub output: Option<String>,
    /// Format of `--output` (`auto`: from the file name).
    #[arg(long, value_parser = choice(OutputFormat::choices()), default_value_t = OutputFormat::Auto)]
    pub output_format: OutputFormat,
    #[command(flatten)]
    pub plot: PlotArgs,
    #[command(flatten)]
    pub common: Common,
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<Outcome> {
    args.plot.check()?;
    // output folders are created (or refused) before anything is read or solved
    let outputs = MultipleOutputs::prepare(
        args.output.as_deref(),
        args.inlier_output.as_deref(),
        args.edges_output.as_deref(),
        args.output_format,
    )?;
    let outcome = solve_and_write(args, &outputs);
    // a failed run, or an output a run had nothing to write, leaves no folder behind
    outputs.remove_empty_folders();
    outcome
}

/// Read, solve, certify, write the planned outputs and print the report.
fn solve_and_write(args: &Args, outputs: &MultipleOutputs) -> Result<Outcome> {
    let input = load_multiple_input(
        &args.input,
        &MultipleInputOptions {
            format: args.graph.format,
            read: args.graph.read_options(&args.common),
            largest_component: args.largest_component,
            ground_truth: args.ground_truth.clone(),
            init: args.init.init.clone(),
        },
    )?;
    let graph = &input.graph;
    let source = OutputSource {
        input: &args.input,
        format: graph.format,
    };
    outputs.check(&source)?;
    let (loss_threshold, robust_scale) = ScaleRule::of(args.loss_threshold);
    let objective = args.loss.objective(loss_threshold);
    let problem = graph.problem.clone().with_objective(objective)?;
    let flags = [
        ("--inlier-threshold", args.inlier_threshold.is_some()),
        ("--edges-output", args.edges_output.is_some()),
        ("--inlier-output", args.inlier_output.is_some()),
    ];
    let certify_none = args.graph.certify == CertifyMode::None;
    args.loss.check_robust_flags(&flags, certify_none)?;
    let settings = AverageSettings {
        solve: MultipleSettings {
            init: input
                .init
                .clone()
                .map_or_else(|| args.init_method.clone(), Initialisation::Given),
            inlier_threshold_deg: args
                .loss
                .inlier_threshold_deg(loss_threshold, args.inlier_threshold),
            robust_on_outliers: args.loss.robust_on_outliers(loss_threshold),
            robust_scale,
            // --max-seconds is one clock for the solve and the certificate
            max_seconds: args.common.solve_seconds(),
            ..Default::default()
        },
        certify: args.graph.settings(&args.common, &args.plot),
    };
    crate::progress::say(format_args!(
        "{} nodes, {} edges: solving ({} loss) and certifying ({})...",
        problem.num_rotations(),
        problem.num_edges(),
        args.loss,
        settings.certify.mode
    ));
    let (result, gravity_warnings) = match args.gravity.read(graph)? {
        Some((priors, warnings)) => {
            args.loss.check_gravity()?;
            let p = GravityProblem::new(graph.problem.clone(), priors)?;
            (average_with_gravity(&p, &settings)?, warnings)
        }
        None => (average_multiple(&problem, &settings)?, Vec::new()),
    };
    let mut report = MultipleReport::new(&input, result)?;
    report.run_warnings.extend(gravity_warnings);
    report.inlier_output = outputs.write(graph, &report.result, &source)?;
    #[cfg(feature = "plot")]
    if let Some(path) = &args.plot.plot {
        report.write_figure(path, &graph.problem)?;
    }
    report.output = args.output.clone();
    report.note_robust_outputs(args.edges_output.as_deref(), args.inlier_output.is_some());
    // the reader's warnings are lines of the report; these go to stderr
    for w in report.stderr_warnings() {
        args.common.warn(&w.message);
    }
    args.common.finish(&report, report.verdict())
}
