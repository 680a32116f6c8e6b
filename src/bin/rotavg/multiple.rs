//! `rotavg multiple INPUT [--format auto|g2o|1dsfm|json] [--loss ...] [--certify ...] [--json]
//! [--output FILE]`: multiple rotation averaging with a certificate
//! (`rotavg::multiple::average::average_multiple`).
//!
//! `--json` prints one object (SPEC section 5): `problem` = "multiple", `num_rotations`,
//! `num_measurements`, `loss`, `cost` (the chosen loss), `chordal_cost`, `estimate` (row-major,
//! `R_0 = I`), `solver`, `certificate` (or null), plus `node_ids` (file ids of the estimate's
//! nodes), `pipeline` (methods run, times), `accuracy` (with `--ground-truth`) and
//! `other_components` (with `--largest-component`).

use crate::Outcome;
use crate::common::{Common, WeightSource, read_input};
use clap::{Args as ClapArgs, ValueEnum};
use rotavg::io::detect::{GraphFormat, LoadedGraph, ReadOptions, WeightSource as IoWeights};
use rotavg::io::detect::{load_graph, read_graph};
use rotavg::io::json::read_rotations_estimate;
use rotavg::io::sfm::{read_bundler, read_rotation_list, truth_for_nodes};
use rotavg::multiple::accuracy::{AccuracyReport, align_and_compare};
use rotavg::multiple::average::{AverageMultipleSettings, CertifyMode, average_multiple};
use rotavg::multiple::{Initialisation, Loss, MultipleProblem, MultipleSettings};
use rotavg::so3::{Rotation, rotation_to_rows};
use rotavg::{Error, Result};
use std::path::Path;

/// Input format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum FormatArg {
    /// From the extension, then the content.
    #[default]
    Auto,
    /// g2o / TORO pose graph.
    G2o,
    /// 1DSfM `EGs.txt`.
    #[value(name = "1dsfm")]
    OneDsfm,
    /// JSON problem (SPEC section 5).
    Json,
}

impl From<FormatArg> for GraphFormat {
    fn from(f: FormatArg) -> GraphFormat {
        match f {
            FormatArg::Auto => GraphFormat::Auto,
            FormatArg::G2o => GraphFormat::G2o,
            FormatArg::OneDsfm => GraphFormat::OneDsfm,
            FormatArg::Json => GraphFormat::Json,
        }
    }
}

/// Loss.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum LossArg {
    /// Chordal L2 (certifiable).
    #[default]
    Chordal,
    /// Geodesic L2.
    Geodesic,
    /// Geodesic L1.
    L1,
    /// Huber on the residual angle (threshold `--loss-threshold`).
    Huber,
    /// Cauchy on the residual angle (scale `--loss-threshold`).
    Cauchy,
}

/// Initialisation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum InitArg {
    /// Spectral (connection Laplacian eigenvectors).
    #[default]
    Spectral,
    /// Maximum-weight spanning tree.
    Tree,
}

/// Certification.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum CertifyArg {
    /// Dual; then SDP (small graphs) or staircase (large).
    #[default]
    Auto,
    /// Dual certificate only.
    Dual,
    /// Dual, then the SDP.
    Sdp,
    /// Dual, then the Riemannian staircase.
    Staircase,
    /// None.
    None,
}

impl From<CertifyArg> for CertifyMode {
    fn from(c: CertifyArg) -> CertifyMode {
        match c {
            CertifyArg::Auto => CertifyMode::Auto,
            CertifyArg::Dual => CertifyMode::Dual,
            CertifyArg::Sdp => CertifyMode::Sdp,
            CertifyArg::Staircase => CertifyMode::Staircase,
            CertifyArg::None => CertifyMode::None,
        }
    }
}

/// Arguments of `rotavg multiple`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Input file, or `-` for standard input.
    pub input: String,
    /// Input format.
    #[arg(long, value_enum, default_value_t = FormatArg::Auto)]
    pub format: FormatArg,
    /// Loss.
    #[arg(long, value_enum, default_value_t = LossArg::Chordal)]
    pub loss: LossArg,
    /// Huber / Cauchy threshold in degrees.
    #[arg(long, value_name = "DEG", default_value_t = 5.0)]
    pub loss_threshold: f64,
    /// Initialisation of the local solver (ignored with `--init FILE`).
    #[arg(long, value_enum, default_value_t = InitArg::Spectral)]
    pub init_method: InitArg,
    /// Certification.
    #[arg(long, value_enum, default_value_t = CertifyArg::Auto)]
    pub certify: CertifyArg,
    /// Ground truth: g2o (vertex lines; `.g2o` or a first token that is a tag), Bundler `.out`,
    /// JSON estimate (node order), or a rotation list (9 numbers per line,
    /// line k = file id k); matched to
    /// nodes by file id.
    #[arg(long, value_name = "FILE")]
    pub ground_truth: Option<String>,
    /// Solve the largest connected component of a disconnected graph (and report the others).
    #[arg(long)]
    pub largest_component: bool,
    /// Write the estimate: JSON `{"rotations": [...], "node_ids": [...]}`, or g2o when FILE ends
    /// in `.g2o`.
    #[arg(long, value_name = "FILE")]
    pub output: Option<String>,
    /// Write an SVG figure: histogram of the residual angles (degrees), the certificate, and
    /// the 10 smallest eigenvalues of the certificate matrix (estimates) with the proven bound.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// Read options from the common flags.
pub fn read_options(common: &Common) -> ReadOptions {
    ReadOptions {
        weights: match common.weights {
            WeightSource::File => IoWeights::File,
            WeightSource::Unit => IoWeights::Unit,
        },
        ..Default::default()
    }
}

/// Load a view graph (`-` is standard input).
pub fn load(input: &str, format: GraphFormat, options: &ReadOptions) -> Result<LoadedGraph> {
    if input == "-" {
        let (name, text) = read_input(input)?;
        read_graph(&text, &name, format, options)
    } else {
        load_graph(Path::new(input), format, options)
    }
}

/// Ground truth for the nodes of `graph` (indexed like `graph.node_ids`).
fn read_truth(
    path: &str,
    graph: &LoadedGraph,
    options: &ReadOptions,
) -> Result<Vec<Option<Rotation>>> {
    let (name, text) = read_input(path)?;
    let lower = name.to_ascii_lowercase();
    let trimmed = text.trim_start();
    if lower.ends_with(".json") || trimmed.starts_with('{') {
        let rs = read_rotations_estimate(&text, &name, options)?;
        if rs.len() != graph.node_ids.len() {
            return Err(Error::parse(
                Some(&name),
                None,
                format!(
                    "ground truth has {} rotations, the graph has {} nodes",
                    rs.len(),
                    graph.node_ids.len()
                ),
            ));
        }
        return Ok(rs.into_iter().map(Some).collect());
    }
    let first_token = text
        .lines()
        .map(str::trim)
        .find(|l| !l.is_empty() && !l.starts_with('#'))
        .and_then(|l| l.split_whitespace().next())
        .unwrap_or("");
    if lower.ends_with(".g2o") || first_token.starts_with(|c: char| c.is_ascii_alphabetic()) {
        let gt = read_graph(&text, &name, GraphFormat::G2o, options)?;
        let init = gt.initial.as_ref();
        return Ok(graph
            .node_ids
            .iter()
            .map(|&id| {
                let k = gt.node_of_id(id)?;
                init.and_then(|v| v.get(k).copied())
            })
            .collect());
    }
    let by_id = if lower.ends_with(".out") || trimmed.starts_with("# Bundle") {
        read_bundler(&text, &name, options)?
    } else {
        read_rotation_list(&text, &name, options)?
    };
    Ok(truth_for_nodes(&by_id, &graph.node_ids))
}

/// Restrict a loaded graph to its largest component (problem, node ids, initial estimate);
/// returns the sizes of the other components.
fn restrict(graph: &mut LoadedGraph) -> Vec<usize> {
    let comps = graph.problem.components();
    if comps.len() <= 1 {
        return Vec::new();
    }
    let (sub, keep) = graph.problem.largest_component();
    graph.node_ids = keep.iter().map(|&k| graph.node_ids[k]).collect();
    graph.initial = graph
        .initial
        .as_ref()
        .map(|v| keep.iter().map(|&k| v[k]).collect());
    graph.problem = sub;
    comps.iter().skip(1).map(Vec::len).collect()
}

/// The `--output` text: g2o for a `.g2o` path, else estimate JSON with node ids.
pub fn output_text(
    path: &str,
    problem: &MultipleProblem,
    rotations: &[Rotation],
    node_ids: &[u64],
) -> String {
    if path.to_ascii_lowercase().ends_with(".g2o") {
        rotavg::io::g2o::write_g2o(problem, Some(rotations))
    } else {
        let rows: Vec<_> = rotations.iter().map(rotation_to_rows).collect();
        let mut s = serde_json::to_string(&serde_json::json!({
            "rotations": rows,
            "node_ids": node_ids,
        }))
        .unwrap_or_default();
        s.push('\n');
        s
    }
}

fn write_file(path: &str, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::Io {
        path: path.into(),
        message: e.to_string(),
    })
}

/// Write the `--plot` SVG: residual-angle histogram (degrees), the certificate facts and, when
/// the certificate carries them, the smallest eigenvalues of its certificate matrix.
pub fn write_plot(
    path: &str,
    problem: &MultipleProblem,
    rotations: &[Rotation],
    certificate: Option<&rotavg::Certificate>,
    input: &str,
) -> Result<()> {
    write_figure(
        path,
        &problem.residual_angles(rotations),
        "edges",
        certificate,
        3,
        input,
    )
}

/// Write a `--plot` SVG from residual angles (radians) of `what` (e.g. "edges", "pairs"), the
/// certificate, and the null-space dimension expected at a certified solution (3 gauge
/// directions for multiple averaging, 1 for the conjugate SDP).
pub fn write_figure(
    path: &str,
    residuals_rad: &[f64],
    what: &str,
    certificate: Option<&rotavg::Certificate>,
    null_dimension: usize,
    input: &str,
) -> Result<()> {
    let deg: Vec<f64> = residuals_rad.iter().map(|a| a.to_degrees()).collect();
    let notes = certificate
        .map(rotavg::plot::certificate_annotations)
        .unwrap_or_default();
    let eigen = certificate.and_then(|c| rotavg::plot::eigenvalue_panel(c, null_dimension));
    // the file name only: a long path would not fit above the histogram
    let name = Path::new(input)
        .file_name()
        .map_or_else(|| input.to_string(), |f| f.to_string_lossy().into_owned());
    let title = format!("{name}: residual angles of {} {what}", deg.len());
    rotavg::plot::write_svg(
        path,
        &rotavg::plot::figure_svg(&deg, &title, &notes, eigen.as_ref()),
    )
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<Outcome> {
    let options = read_options(&args.common);
    let mut graph = load(&args.input, args.format.into(), &options)?;
    let full_n = graph.problem.num_rotations();
    let truth_full = match &args.ground_truth {
        Some(p) => Some(read_truth(p, &graph, &options)?),
        None => None,
    };
    let init_full = match &args.common.init {
        Some(p) => {
            let (name, text) = read_input(&p.display().to_string())?;
            let rs = read_rotations_estimate(&text, &name, &options)?;
            Some((name, rs))
        }
        None => None,
    };
    let ids_before = graph.node_ids.clone();
    let others = if args.largest_component {
        restrict(&mut graph)
    } else {
        graph.problem.require_connected()?;
        Vec::new()
    };
    // map full-graph node index -> kept index, for truth and init
    let kept: Vec<usize> = graph
        .node_ids
        .iter()
        .filter_map(|id| ids_before.binary_search(id).ok())
        .collect();
    let truth = truth_full.map(|t| kept.iter().map(|&k| t[k]).collect::<Vec<_>>());
    let n = graph.problem.num_rotations();
    let init = match init_full {
        Some((name, rs)) => {
            let rs = if rs.len() == n {
                rs
            } else if rs.len() == full_n {
                kept.iter().map(|&k| rs[k]).collect()
            } else {
                return Err(Error::parse(
                    Some(&name),
                    None,
                    format!(
                        "initial estimate has {} rotations, the graph has {n} nodes",
                        rs.len()
                    ),
                ));
            };
            Initialisation::Given(rs)
        }
        None => match args.init_method {
            InitArg::Spectral => Initialisation::Spectral,
            InitArg::Tree => Initialisation::SpanningTree,
        },
    };
    let loss = match args.loss {
        LossArg::Chordal => Loss::Chordal,
        LossArg::Geodesic => Loss::Geodesic,
        LossArg::L1 => Loss::L1,
        LossArg::Huber => Loss::Huber {
            threshold_deg: args.loss_threshold,
        },
        LossArg::Cauchy => Loss::Cauchy {
            threshold_deg: args.loss_threshold,
        },
    };
    let settings = AverageMultipleSettings {
        local: MultipleSettings {
            loss,
            init,
            ..Default::default()
        },
        certify_mode: args.certify.into(),
        // the figure shows the smallest eigenvalues of the certificate matrix
        spectrum: args.plot.as_ref().map(|_| Default::default()),
        ..Default::default()
    };
    crate::common::progress(
        &args.common,
        format_args!(
            "{} nodes, {} edges: solving ({} loss) and certifying ({})...",
            n,
            graph.problem.num_edges(),
            loss.name(),
            settings.certify_mode.name()
        ),
    );
    let est = average_multiple(&graph.problem, &settings)?;
    let sol = &est.solution;
    let accuracy: Option<AccuracyReport> = match &truth {
        Some(t) => Some(align_and_compare(&sol.rotations, t)?),
        None => None,
    };
    if let Some(path) = &args.output {
        write_file(
            path,
            &output_text(path, &graph.problem, &sol.rotations, &graph.node_ids),
        )?;
    }
    if let Some(path) = &args.plot {
        write_plot(
            path,
            &graph.problem,
            &sol.rotations,
            est.certificate.as_ref(),
            &args.input,
        )?;
    }
    let verdict = est.certificate.as_ref().map(|c| c.verdict);
    if args.common.json {
        let out = serde_json::json!({
            "problem": "multiple",
            "num_rotations": n,
            "num_measurements": graph.problem.num_edges(),
            "loss": loss,
            "cost": sol.cost,
            "chordal_cost": sol.chordal_cost,
            "estimate": sol.rotations.iter().map(rotation_to_rows).collect::<Vec<_>>(),
            "node_ids": graph.node_ids,
            "solver": sol.report,
            "certificate": est.certificate,
            "pipeline": est.details,
            "accuracy": accuracy,
            "other_components": others,
            "format": graph.format,
        });
        println!("{out}");
    } else if !args.common.quiet {
        println!(
            "{}: {} format, {} nodes, {} edges ({} duplicate, {} reversed){}",
            args.input,
            graph.format,
            n,
            graph.problem.num_edges(),
            graph.duplicates,
            graph.reversed,
            if others.is_empty() {
                String::new()
            } else {
                format!(
                    "; solved the largest component ({n} of {full_n} nodes); other components (sizes {others:?}) not solved"
                )
            }
        );
        for w in &graph.warnings {
            println!("warning: {w}");
        }
        println!("{est}");
        for m in &est.details.methods {
            println!("  {} ({:.3} s): {}", m.method, m.seconds, m.note);
        }
        if let Some(a) = &accuracy {
            println!("{a}");
        }
        if let Some(p) = &args.output {
            println!("estimate written to {p}");
        }
        if let Some(p) = &args.plot {
            println!("figure written to {p}");
        }
    }
    Ok(Outcome { verdict })
}
