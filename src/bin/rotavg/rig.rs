//! `rotavg rig RIGHT LEFT`: a two-sensor rig (two sensors rigidly mounted, each with its own
//! view graph over the same frames) calibrated and averaged jointly (or, with
//! `--sensor-from-rig`, averaged with the calibration held), certified
//! (`rotavg::pipeline::simultaneous`, printed as `rotavg::report::RigReport`).
//! `rotavg rig FILE`: a rig of any number of sensors from a JSON rig file or a COLMAP
//! database's rig configuration (`rotavg::pipeline::average_rig`, printed as
//! `rotavg::report::RigFileReport`).

use crate::Outcome;
use crate::common::{Common, GraphArgs, GravityArgs};
use rotavg::Result;
use rotavg::io::detect::load_graph;
use rotavg::pipeline::rig::RigLoss;
use rotavg::report::rig_two_graphs::{needs_rig_form, two_graph_rig};
use rotavg::report::{RigFileReport, RigReport};
use std::path::Path;

/// Arguments of `rotavg rig`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The reference sensor's view graph (any format `multiple` reads): its rotations are the
    /// rig frames'. Alone: a rig of any number of sensors, as a JSON rig file or a COLMAP
    /// database with a rig configuration (tables rigs, rig_sensors, frames, frame_data).
    pub right: String,
    /// The other sensor's view graph over the same frames (node ids): `L_ij ~ S R_ij S^T`,
    /// `S` its `sensor_from_rig` rotation. Graphs with information matrices are the rig of two
    /// sensors they describe, reported as a rig file; so are two graphs with `--gravity`.
    pub left: Option<String>,
    #[command(flatten)]
    pub graph: GraphArgs,
    /// Write the estimate: JSON `{"rotations": [...], "node_ids": [...],
    /// "sensor_from_rig": S}` (two graphs), or `{"frames": [...], "frame_ids": [...],
    /// "sensors_from_rig": [...], "sensor_ids": [...]}` (a rig file).
    #[arg(long, value_name = "FILE")]
    pub output: Option<String>,
    /// Hold the other sensor's `sensor_from_rig` at the rotation `"sensor_from_rig"` of FILE
    /// (a JSON object, as `--output` writes): only the frames are estimated, on one view graph,
    /// and certified by the multiple-averaging ladder (paper-notes/conjugate.md [H18]).
    /// (Two view graphs only: a rig file gives each sensor's known `sensor_from_rig` itself.)
    #[arg(long, value_name = "FILE", requires = "left")]
    pub sensor_from_rig: Option<String>,
    /// The loss: `auto` (least squares, and the Cauchy loss instead when the residuals look like
    /// outliers), `chordal` (least squares on every edge) or `cauchy` (then the inlier edges'
    /// chordal L2 problem is solved and certified; paper-notes/conjugate.md [H20]). With
    /// `--sensor-from-rig`: least squares.
    #[arg(long, value_name = "auto|chordal|cauchy", default_value = "auto", value_parser = ["auto", "chordal", "cauchy"])]
    pub loss: String,
    /// Gravity priors on a rig file's images, keyed by image id or name, or on two view
    /// graphs' frames, keyed as `multiple` keys the reference graph's nodes; held or soft as
    /// for `multiple`; sensors to estimate are calibrated without them first, then held
    /// (paper-notes/gravity.md [G14]; scalar weights only).
    #[command(flatten)]
    pub gravity: GravityArgs,
    /// The Cauchy loss's scale and the inlier threshold, degrees. Not given: both from the
    /// data under `--loss auto` (1.5 and 3 times the median residual at the rig's Cauchy
    /// estimate after 3 reweightings at 5 degrees, paper-notes/conjugate.md [H20] "The
    /// scale"), 5 with `--loss cauchy`.
    #[arg(long, value_name = "DEG")]
    pub loss_threshold: Option<f64>,
    #[command(flatten)]
    pub common: Common,
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<Outcome> {
    let Some(left) = &args.left else {
        return run_file(args);
    };
    let rig_loss = loss(args)?;
    let input = format!("{} and {left}", args.right);
    let options = args.graph.read_options(&args.common).scalar_by_default();
    let right = load_graph(Path::new(&args.right), args.graph.format, &options)?;
    let left = load_graph(Path::new(left), args.graph.format, &options)?;
    let certify = args.graph.settings(&args.common, &Default::default());
    let held = (args.sensor_from_rig.as_ref())
        .map(|file| rotavg::io::json::read_sensor_from_rig(file, &options))
        .transpose()?;
    if needs_rig_form(&right, &left) || args.gravity.gravity.is_some() {
        let rig = two_graph_rig(&right, &left, held, args.gravity.read(&right)?)?;
        return run_rig(args, input, rig);
    }
    crate::progress::say(format_args!(
        "rig of {} frames, {} + {} edges{}: solving and certifying...",
        right.problem.num_rotations(),
        right.problem.num_edges(),
        left.problem.num_edges(),
        held.map_or("", |_| ", sensor_from_rig held")
    ));
    let inputs = [args.right.clone(), args.left.clone().unwrap_or_default()];
    let max_seconds = args.common.solve_seconds();
    let graphs = (&right, &left);
    let report = match held {
        Some(_) => RigReport::average(inputs, graphs, held, certify, max_seconds)?,
        None => RigReport::average_with_loss(inputs, graphs, rig_loss, certify, max_seconds)?,
    };
    if let Some(path) = &args.output {
        report.write_output(path)?;
    }
    args.common.finish(&report, report.verdict())
}

/// `rotavg rig FILE`: a rig of any number of sensors read from a rig file.
fn run_file(args: &Args) -> Result<Outcome> {
    let options = args.graph.read_options(&args.common);
    let rig = rotavg::io::rig::load_rig(Path::new(&args.right), &options)?;
    run_rig(args, args.right.clone(), args.gravity.apply_to_rig(rig)?)
}

/// Solve, certify and report the rig read from `input` (a rig file, or two view graphs).
fn run_rig(args: &Args, input: String, rig: rotavg::io::rig::LoadedRig) -> Result<Outcome> {
    let p = &rig.problem;
    crate::progress::say(format_args!(
        "rig of {} frames, {} sensors, {} images, {} edges: solving and certifying...",
        p.num_frames(),
        p.sensors().len(),
        p.images().len(),
        p.edges().len()
    ));
    let certify = args.graph.settings(&args.common, &Default::default());
    let max_seconds = args.common.solve_seconds();
    let report = RigFileReport::average(input, rig, loss(args)?, certify, max_seconds)?;
    if let Some(path) = &args.output {
        report.write_output(path)?;
    }
    args.common.finish(&report, report.verdict())
}

/// `--loss` and `--loss-threshold` (the Cauchy scale and the inlier threshold), least squares
/// with `--sensor-from-rig` ([`RigLoss::with_sensor_held`]).
fn loss(args: &Args) -> Result<(RigLoss, rotavg::rig::RigRobust)> {
    let (loss, robust) = RigLoss::named(&args.loss, args.loss_threshold)?;
    Ok((
        loss.with_sensor_held(args.sensor_from_rig.is_some())?,
        robust,
    ))
}
