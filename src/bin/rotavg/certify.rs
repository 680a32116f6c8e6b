//! `rotavg certify INPUT --estimate FILE`: certify an estimate computed elsewhere, or report
//! its proven gap, **without changing it**. The problem kind comes from INPUT (view graph,
//! single or conjugate problem: `rotavg::io::input::load_problem`; a hand-eye dataset folder
//! or `--hand` / `--camera` pose streams: `load_conjugate_with`, as `rotavg conjugate` reads
//! them), the estimate is matched to it (`load_estimate_for`); printed as
//! `rotavg::report::CertifyReport`.

use crate::Outcome;
use crate::common::{Common, GraphArgs, GravityArgs, PlotArgs, choice};
use crate::conjugate::StreamArgs;
use rotavg::Result;
use rotavg::certify::CertifyMode;
use rotavg::io::detect::ReadOptions;
use rotavg::io::input::{
    LoadedEstimate, LoadedProblem, load_certify_problem, load_estimate, load_estimate_for,
};
use rotavg::io::names::{Choice, MultipleLoss};
use rotavg::io::nearest;
use rotavg::report::CertifyReport;
use rotavg::report::rig_two_graphs::{certify_two_graphs, needs_rig_form, two_graph_rig};
use std::path::Path;

/// Arguments of `rotavg certify`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// Problem file (or a COLMAP database, or the folder holding database.db; or a hand-eye
    /// dataset folder: Tabb, ETH, pose streams), or `-` for standard input. Optional when
    /// both `--hand` and `--camera` are given.
    #[arg(required_unless_present_all = ["hand", "camera"])]
    pub input: Option<String>,
    /// The estimate to certify. View graphs: JSON (`{"rotations": [...]}` in node order, or with
    /// `node_ids`), g2o / TORO vertices, a COLMAP sparse model folder (e.g. GLOMAP's `sparse/0`),
    /// `images.bin` or `images.txt`, Bundler `.out`, a rotation list, a NumPy `.npy` / `.npz`
    /// array (n, 3, 3) in node order; matched to the nodes by id, or by image name (COLMAP).
    /// Single and conjugate problems: JSON `{"rotation": R}`, or a NumPy (3, 3) array.
    #[arg(long, value_name = "PATH")]
    pub estimate: String,
    /// Certify the nearest rotations of an estimate whose matrices are rotations only
    /// approximately (beyond `--rotation-tolerance`), or all reflections (det -1, as a
    /// relaxation's rounding may return: negated first, the chordal cost unchanged); the
    /// report says so (warning `estimate_projected`). Without it such an estimate is an error.
    #[arg(long, conflicts_with = "left")]
    pub nearest_rotations: bool,
    /// View graphs: also judge the estimate on a robust loss's inlier set (l1, huber,
    /// cauchy): the chordal L2 problem on the edges whose residual at the estimate is at most
    /// the inlier threshold (their largest connected component), the estimate unchanged; the
    /// verdict is then that problem's. `chordal` (default): all edges only.
    #[arg(long, value_parser = choice(MultipleLoss::choices()), default_value_t = MultipleLoss::Chordal)]
    pub loss: MultipleLoss,
    /// `--loss l1|huber|cauchy`: the inlier threshold in degrees (an edge is an inlier iff its
    /// residual at the estimate is at most DEG; default `--loss-threshold`).
    #[arg(long, value_name = "DEG")]
    pub inlier_threshold: Option<f64>,
    /// `--loss huber|cauchy|l1`: the loss's threshold in degrees, the inlier threshold unless
    /// `--inlier-threshold` is given.
    #[arg(long, value_name = "DEG", default_value_t = 5.0)]
    pub loss_threshold: f64,
    #[command(flatten)]
    pub graph: GraphArgs,
    #[command(flatten)]
    pub gravity: GravityArgs,
    /// A two-sensor rig: INPUT is the reference sensor's view graph and FILE the other
    /// sensor's; the estimate (as `rotavg rig --output` writes it) holds the frames and
    /// `"sensor_from_rig": S`. The joint cost is certified, the estimate unchanged.
    /// With `--gravity`: the priors on the frames, keyed by the reference graph's nodes, the
    /// estimate's `S` held (paper-notes/gravity.md [G14]).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["hand", "camera"])]
    pub left: Option<String>,
    /// A rig of any number of sensors: INPUT is a rig file (the JSON rig format or a COLMAP
    /// database with a rig configuration, as `rotavg rig FILE` reads it) and the estimate the
    /// file `rotavg rig FILE --output` writes (`"frames"`, `"sensors_from_rig"`); the rig's cost
    /// is certified, the estimate unchanged (`--nearest-rotations`: its nearest rotations).
    /// With `--gravity`: the priors on the rig's images, keyed by image id or name, the
    /// estimate's sensors held (paper-notes/gravity.md [G14]).
    #[arg(long, conflicts_with_all = ["left", "hand", "camera"])]
    pub rig: bool,
    #[command(flatten)]
    pub plot: PlotArgs,
    /// Hand-eye pose streams and their pairing, as `rotavg conjugate` reads them.
    #[command(flatten)]
    pub streams: StreamArgs,
    #[command(flatten)]
    pub common: Common,
}

/// The estimate of `--estimate` for `problem`, at its nearest rotations with
/// `--nearest-rotations` (`rotavg::io::nearest`); otherwise a matrix that is not a rotation is
/// an error naming the option.
fn load_given(
    args: &Args,
    problem: &LoadedProblem,
    options: &ReadOptions,
) -> Result<LoadedEstimate> {
    let read = |options: &ReadOptions| match problem {
        LoadedProblem::Multiple(g) => {
            Ok(load_estimate_for(&args.estimate, g, options)?.into_loaded())
        }
        LoadedProblem::Single(_) | LoadedProblem::Conjugate(_) => {
            load_estimate(&args.estimate, options)
        }
    };
    if args.nearest_rotations {
        read(&nearest::permissive(options))?.into_nearest_rotations()
    } else {
        read(options).map_err(nearest::with_nearest_hint)
    }
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<Outcome> {
    if let Some(left) = &args.left {
        return certify_rig(args, left);
    }
    if args.rig {
        return certify_rig_file(args);
    }
    let inlier_threshold = args
        .loss
        .certify_inlier_threshold_deg(args.loss_threshold, args.inlier_threshold)?;
    let options = args.graph.read_options(&args.common).scalar_by_default();
    let (input, problem) = load_certify_problem(
        args.input.as_deref(),
        args.graph.format,
        &options,
        &args.streams.options(),
    )?;
    let estimate = load_given(args, &problem, &options)?;
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
            args.graph.certify_settings(&args.common, &args.plot)
        }
        _ => args.common.settings(CertifyMode::Auto),
    };
    let gravity = match &problem {
        LoadedProblem::Multiple(g) => args.gravity.read(g)?,
        _ if args.gravity.gravity.is_some() => {
            return Err(rotavg::Error::InvalidSettings {
                name: "--gravity".into(),
                reason: "gravity priors apply to view graphs only".into(),
            });
        }
        _ => None,
    };
    let report = match (inlier_threshold, gravity, &problem) {
        (None, Some((priors, unmatched)), LoadedProblem::Multiple(g)) => {
            let mut r =
                CertifyReport::certify_with_gravity(&input, g, estimate, priors, &settings)?;
            r.warnings.extend(unmatched);
            r
        }
        (Some(_), Some(_), _) => {
            return Err(rotavg::Error::InvalidSettings {
                name: "--gravity".into(),
                reason: "gravity priors are certified on all edges (least squares), not with \
                         --loss"
                    .into(),
            });
        }
        (None, _, _) => CertifyReport::certify(&input, &problem, estimate, &settings)?,
        (Some(threshold), None, _) => CertifyReport::certify_on_inliers(
            &input,
            &problem,
            estimate,
            &args.loss.to_string(),
            threshold,
            &settings,
        )?,
    };
    if let Some(path) = &args.plot.plot {
        report.write_figure(path, &problem)?;
    }
    args.common.finish(&report, Some(report.verdict()))
}

/// `--left`: certify a rig estimate (frames and `sensor_from_rig`) on the two view graphs.
fn certify_rig(args: &Args, left_path: &str) -> Result<Outcome> {
    let options = args.graph.read_options(&args.common).scalar_by_default();
    let right_path = args.input.clone().unwrap_or_else(|| "-".into());
    let right =
        rotavg::io::detect::load_graph(Path::new(&right_path), args.graph.format, &options)?;
    let left = rotavg::io::detect::load_graph(Path::new(left_path), args.graph.format, &options)?;
    let rotations = load_estimate_for(&args.estimate, &right, &options)?
        .into_loaded()
        .into_rotations()?;
    let s = rotavg::io::json::read_sensor_from_rig(&args.estimate, &options)?;
    let settings = args.graph.certify_settings(&args.common, &args.plot);
    if needs_rig_form(&right, &left) || args.gravity.gravity.is_some() {
        let input = format!("{right_path} and {left_path}");
        let rig = two_graph_rig(&right, &left, None, args.gravity.read(&right)?)?;
        let report = certify_two_graphs(input, rig, rotations, s, &settings)?;
        return args.common.finish(&report, report.verdict());
    }
    let report = rotavg::report::RigReport::certify(
        [right_path, left_path.to_string()],
        &right,
        &left,
        rotations,
        s,
        &settings,
    )?;
    args.common.finish(&report, report.verdict())
}

/// `--rig`: certify a rig file's estimate (frames and every sensor's `sensor_from_rig`).
fn certify_rig_file(args: &Args) -> Result<Outcome> {
    let options = args.graph.read_options(&args.common).scalar_by_default();
    let input = args.input.clone().unwrap_or_else(|| "-".into());
    let rig = rotavg::io::rig::load_rig(Path::new(&input), &options)?;
    let rig = args.gravity.apply_to_rig(rig)?;
    let text = rotavg::io::text::read_text(&args.estimate)?;
    let estimate = rotavg::io::rig::read_rig_estimate(
        &text,
        &args.estimate,
        &rig,
        &options,
        args.nearest_rotations,
    )?;
    let settings = args.graph.certify_settings(&args.common, &args.plot);
    let report = rotavg::report::RigFileReport::certify(input, rig, estimate, &settings)?;
    args.common.finish(&report, report.verdict())
}
