//! `rotavg multiple INPUT [--format auto|g2o|1dsfm|json|colmap] [--loss ...] [--certify ...]
//! [--json] [--output FILE [--output-format auto|json|g2o|colmap]]`: multiple rotation averaging with a certificate
//! (`rotavg::pipeline::average_multiple`); input loading is `rotavg::io::input`, the printed
//! object `rotavg::report::MultipleReport`.

use crate::Outcome;
use crate::common::{Common, choice};
use clap::Args as ClapArgs;
use rotavg::Result;
use rotavg::certify::{CertifyMode, CertifySettings};
use rotavg::io::detect::GraphFormat;
use rotavg::io::input::{MultipleInputOptions, load_multiple_input};
use rotavg::io::names::{Choice, MultipleLoss};
use rotavg::io::output::{
    EstimateFile, OutputFormat, OutputSource, edges_file_text, prepare_output, write_text,
};
use rotavg::multiple::{Initialisation, MultipleSettings};
use rotavg::pipeline::{AverageSettings, average_multiple};
#[cfg(feature = "plot")]
use rotavg::plot::write_multiple_figure;
use rotavg::report::MultipleReport;

/// The certify modes of multiple averaging.
pub fn certify_modes() -> Vec<CertifyMode> {
    use CertifyMode::*;
    vec![Auto, Dual, Sdp, Staircase, None]
}

/// Arguments of `rotavg multiple`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Input file (or a folder holding a COLMAP database.db), or `-` for standard input.
    pub input: String,
    /// Input format.
    #[arg(long, value_parser = choice(GraphFormat::choices()), default_value_t = GraphFormat::Auto)]
    pub format: GraphFormat,
    /// Loss.
    #[arg(long, value_parser = choice(MultipleLoss::choices()), default_value_t = MultipleLoss::Chordal)]
    pub loss: MultipleLoss,
    /// Huber / Cauchy threshold in degrees (for L1: the inlier threshold unless
    /// `--inlier-threshold` is given).
    #[arg(long, value_name = "DEG", default_value_t = 5.0)]
    pub loss_threshold: f64,
    /// Robust losses (l1, huber, cauchy): an edge is an inlier iff its residual angle at the
    /// robust estimate is at most DEG (default: `--loss-threshold`). The inlier graph's
    /// chordal L2 problem is refined and certified unless `--certify none`.
    #[arg(long, value_name = "DEG")]
    pub inlier_threshold: Option<f64>,
    /// Robust losses: write the per-edge residuals, one row per edge (`i j residual_deg weight
    /// inlier`, nodes by their file ids): JSON when FILE ends in `.json`, otherwise CSV.
    #[arg(long, value_name = "FILE")]
    pub edges_output: Option<String>,
    /// Robust losses: write the inlier graph's refined (chordal L2) estimate, in the format
    /// given by `--output-format` (or its path), as `--output` (the estimate printed and
    /// written by `--output` is the robust one).
    #[arg(long, value_name = "FILE")]
    pub inlier_output: Option<String>,
    /// Initialisation of the local solver (ignored with `--init FILE`; `spectral` on graphs
    /// whose Newton systems use the Laplacian preconditioner, long chains and large grids,
    /// starts from the spanning tree instead: paper-notes [M6b]).
    #[arg(long, value_parser = choice(Initialisation::choices()), default_value_t = Initialisation::Spectral)]
    pub init_method: Initialisation,
    /// Certification.
    #[arg(long, value_parser = choice(certify_modes()), default_value_t = CertifyMode::Auto)]
    pub certify: CertifyMode,
    /// Ground truth: g2o (vertex lines; `.g2o` or a first token that is a tag), Bundler `.out`,
    /// a COLMAP model folder / `images.bin` / `images.txt` (matched by image name, or id), JSON
    /// estimate (node order, or by `node_ids`), or a rotation list (`R11 .. R33` per line, line
    /// k = file id k, or `id R11 .. R33` per line); matched to nodes by file id. An all-zero
    /// rotation means "no ground truth for this camera".
    #[arg(long, value_name = "FILE")]
    pub ground_truth: Option<String>,
    /// Solve the largest connected component of a disconnected graph (and report the others).
    #[arg(long)]
    pub largest_component: bool,
    /// Write the estimate: JSON `{"rotations": [...], "node_ids": [...]}`; g2o when PATH ends
    /// in `.g2o` (a g2o input's lines with the vertex rotations replaced: translations and
    /// edges as read); a COLMAP sparse model (cameras.txt, images.txt, empty points3D.txt) when
    /// PATH is a folder (ends in `/`) or ends in `images.txt`. Folders are created before the
    /// solve (see `--output-format`).
    #[arg(long, value_name = "PATH")]
    pub output: Option<String>,
    /// Format of `--output` (`auto`: from the file name).
    #[arg(long, value_parser = choice(OutputFormat::choices()), default_value_t = OutputFormat::Auto)]
    pub output_format: OutputFormat,
    /// Write an SVG figure: histogram of the residual angles (degrees), the certificate, and
    /// the 10 smallest eigenvalues of the certificate matrix (estimates) with the proven bound.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<Outcome> {
    crate::common::check_plot(args.plot.as_ref())?;
    // output folders are created (or refused) before anything is read or solved
    let output = match &args.output {
        Some(p) => Some(prepare_output(p, args.output_format)?),
        None => None,
    };
    let inlier_output = match &args.inlier_output {
        Some(p) => Some(prepare_output(p, args.output_format)?),
        None => None,
    };
    if let Some(p) = &args.edges_output {
        prepare_output(p, OutputFormat::Json)?;
    }
    let input = load_multiple_input(
        &args.input,
        &MultipleInputOptions {
            format: args.format,
            read: args.common.read_options(),
            largest_component: args.largest_component,
            ground_truth: args.ground_truth.clone(),
            init: args.common.init.clone(),
        },
    )?;
    let graph = &input.graph;
    let source = OutputSource {
        input: &args.input,
        format: graph.format,
    };
    for plan in output.iter().chain(&inlier_output) {
        source.check(plan)?;
    }
    let objective = args.loss.objective(args.loss_threshold);
    let problem = graph.problem.clone().with_objective(objective)?;
    let robust_only = |flag: &str| rotavg::Error::InvalidSettings {
        name: flag.into(),
        reason: format!(
            "needs a robust loss (--loss l1, huber or cauchy), not {}",
            args.loss
        ),
    };
    let inlier_threshold_deg = match args.loss {
        MultipleLoss::L1 => Some(args.inlier_threshold.unwrap_or(args.loss_threshold)),
        MultipleLoss::Huber | MultipleLoss::Cauchy => args.inlier_threshold,
        MultipleLoss::Chordal | MultipleLoss::Geodesic => {
            for (flag, given) in [
                ("--inlier-threshold", args.inlier_threshold.is_some()),
                ("--edges-output", args.edges_output.is_some()),
                ("--inlier-output", args.inlier_output.is_some()),
            ] {
                if given {
                    return Err(robust_only(flag));
                }
            }
            None
        }
    };
    if args.inlier_output.is_some() && args.certify == CertifyMode::None {
        return Err(rotavg::Error::InvalidSettings {
            name: "--inlier-output".into(),
            reason:
                "the inlier graph is refined only when it is certified (not with --certify none)"
                    .into(),
        });
    }
    let settings = AverageSettings {
        solve: MultipleSettings {
            init: input
                .init
                .clone()
                .map_or_else(|| args.init_method.clone(), Initialisation::Given),
            inlier_threshold_deg,
            ..Default::default()
        },
        certify: CertifySettings {
            mode: args.certify,
            // the figure shows the smallest eigenvalues of the certificate matrix
            spectrum: args.plot.as_ref().map(|_| Default::default()),
            budget: args.common.budget(),
            dual: args.common.dual(),
            ..Default::default()
        },
    };
    args.common.progress(format_args!(
        "{} nodes, {} edges: solving ({} loss) and certifying ({})...",
        problem.num_rotations(),
        problem.num_edges(),
        args.loss,
        settings.certify.mode
    ));
    let mut report = MultipleReport::new(&input, average_multiple(&problem, &settings)?)?;
    let (rotations, certificate) = (
        &report.result.solution.rotations,
        report.result.certificate.as_ref(),
    );
    if let Some(plan) = &output {
        let file = EstimateFile {
            problem: &graph.problem,
            rotations,
            node_ids: &graph.node_ids,
            node_names: &graph.node_names,
        };
        file.write_planned(plan, &source)?;
    }
    if let (Some(path), Some(r)) = (&args.edges_output, &report.result.solution.residuals) {
        write_text(
            path,
            &edges_file_text(path, &graph.problem, r, &graph.node_ids),
        )?;
    }
    if let (Some(plan), Some(g)) = (&inlier_output, &report.result.details.inlier_graph) {
        let file = EstimateFile {
            problem: &graph.problem,
            rotations: &g.estimate,
            node_ids: &graph.node_ids,
            node_names: &graph.node_names,
        };
        file.write_planned(plan, &source)?;
        report.inlier_output = Some(plan.path.clone());
    }
    #[cfg(feature = "plot")]
    if let Some(path) = &args.plot {
        write_multiple_figure(path, &graph.problem, rotations, certificate, &args.input)?;
    }
    #[cfg(not(feature = "plot"))]
    let _ = certificate;
    report.output = args.output.clone();
    report.edges_output = args.edges_output.clone();
    report.figure = args.plot.clone();
    if let Some(w) = &report.result.details.outliers
        && !args.common.quiet
    {
        let warning = format!("rotavg: warning: {}: {w}", args.input);
        eprintln!(
            "{}",
            rotavg::report::wrap_lines(&warning, crate::common::TEXT_WIDTH)
        );
    }
    args.common.print(&report)?;
    Ok(Outcome {
        verdict: report.verdict(),
    })
}
