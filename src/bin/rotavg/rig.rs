//! `rotavg rig RIGHT LEFT`: a two-sensor rig (two sensors rigidly mounted, each with its own
//! view graph over the same frames) calibrated and averaged jointly, certified
//! (`rotavg::pipeline::simultaneous`, printed as `rotavg::report::RigReport`).

use crate::Outcome;
use crate::common::{Common, GraphArgs};
use rotavg::Result;
use rotavg::io::detect::load_graph;
use rotavg::pipeline::AverageSettings;
use rotavg::pipeline::simultaneous::{SimultaneousSettings, average_simultaneous};
use rotavg::report::{RigReport, rig_problem};
use std::path::Path;

/// Arguments of `rotavg rig`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The reference sensor's view graph (any format `multiple` reads): its rotations are the
    /// rig frames'.
    pub right: String,
    /// The other sensor's view graph over the same frames (node ids): `L_ij ~ S R_ij S^T`,
    /// `S` its `sensor_from_rig` rotation.
    pub left: String,
    #[command(flatten)]
    pub graph: GraphArgs,
    /// Write the estimate: JSON `{"rotations": [...], "node_ids": [...],
    /// "sensor_from_rig": S}`.
    #[arg(long, value_name = "FILE")]
    pub output: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<Outcome> {
    let options = args.graph.read_options(&args.common);
    let right = load_graph(Path::new(&args.right), args.graph.format, &options)?;
    let left = load_graph(Path::new(&args.left), args.graph.format, &options)?;
    let problem = rig_problem(&right, &left)?;
    let certify = args.graph.settings(&args.common, &Default::default());
    let settings = AverageSettings {
        solve: SimultaneousSettings {
            max_memory_bytes: certify.budget.max_memory_bytes,
            max_seconds: args.common.solve_seconds(),
            ..Default::default()
        },
        certify,
    };
    crate::progress::say(format_args!(
        "rig of {} frames, {} + {} edges: solving and certifying...",
        problem.num_nodes,
        problem.right.len(),
        problem.left.len()
    ));
    let result = average_simultaneous(&problem, &settings)?;
    let report = RigReport::new(
        [args.right.clone(), args.left.clone()],
        &right,
        &left,
        result,
    );
    if let Some(path) = &args.output {
        let s = &report.result.solution;
        let text = rotavg::io::json::write_rig_json(&s.rotations, &report.node_ids, &s.s);
        rotavg::io::output::write_text(path, &text)?;
    }
    args.common.finish(&report, report.verdict())
}
