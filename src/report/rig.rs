//! `rotavg rig RIGHT LEFT`: a two-sensor rig calibrated and its frames averaged jointly (the
//! simultaneous problem, [`crate::pipeline::simultaneous`]), as text and JSON.

use super::Rows;
use crate::io::detect::{GraphFormat, LoadedGraph};
use crate::multiple::MultipleSettings;
use crate::pipeline::simultaneous::{
    SimultaneousProblem, SimultaneousSettings, SimultaneousSolution, average_simultaneous,
    average_with_sensor_held,
};
use crate::pipeline::{AverageSettings, Averaged};
use crate::so3::{Rotation, angle, log};
use crate::warning::Warning;
use crate::{Error, Result};
use serde::{Serialize, Serializer};
use std::fmt;

/// A rig's report: the two view graphs as read, and the joint estimate with its certificate.
#[derive(Debug, Clone, PartialEq)]
pub struct RigReport {
    /// The right (reference sensor's) and left view graphs' files, as given.
    pub inputs: [String; 2],
    /// Their formats.
    pub formats: [GraphFormat; 2],
    /// The frames' file ids (the two graphs' common node ids).
    pub node_ids: Vec<u64>,
    /// Edges of each graph.
    pub num_edges: [usize; 2],
    /// The readers' warnings.
    pub warnings: Vec<Warning>,
    /// The joint estimate: the frames (the reference sensor's rotations, `R_0 = I`) and
    /// `S = sensor_from_rig` of the left sensor.
    pub result: Averaged<SimultaneousSolution>,
    /// `S` was given and held (`rotavg rig --sensor-from-rig`, `[H18]`), not estimated.
    pub sensor_from_rig_held: bool,
    /// What a robust solve did (`--loss auto` when it turned robust, or `cauchy`): the result is
    /// then the inlier problem's, certified (`[H20]`, `[H22]`).
    pub robust: Option<crate::pipeline::rig::RigRobustDetails>,
}

/// The simultaneous problem of two view graphs read from files: the right graph is the
/// reference sensor's (its rotations are the frames'), the left one the other sensor's,
/// `L_ij ~ S R_ij S^T` with `S` its `sensor_from_rig`. Frames are paired by file id; the two
/// graphs must have the same ids. Errors: different ids, anisotropic information (the
/// simultaneous problem takes scalar weights; such graphs are
/// [`super::rig_two_graphs::two_graph_rig`]'s).
pub fn rig_problem(right: &LoadedGraph, left: &LoadedGraph) -> Result<SimultaneousProblem> {
    super::rig_two_graphs::same_frames(right, left)?;
    if super::rig_two_graphs::needs_rig_form(right, left) {
        return Err(Error::InvalidSettings {
            name: "rig".into(),
            reason: "the simultaneous problem takes scalar weights; two view graphs with \
                     information matrices are the rig of two sensors they describe \
                     (`report::rig_two_graphs::two_graph_rig`, [H24])"
                .into(),
        });
    }
    Ok(SimultaneousProblem {
        num_nodes: right.problem.num_rotations(),
        right: right.problem.edges().to_vec(),
        left: left.problem.edges().to_vec(),
    })
}

impl RigReport {
    /// Write the estimate to `path` (`rotavg rig --output`): JSON `{"rotations": [...],
    /// "node_ids": [...], "sensor_from_rig": S}`.
    pub fn write_output(&self, path: &str) -> crate::Result<()> {
        let s = &self.result.solution;
        let text = crate::io::json::write_rig_json(&s.rotations, &self.node_ids, &s.s);
        crate::io::output::write_text(path, &text)
    }

    /// The report of `result`, the estimate of the rig of `right` and `left` (read from the
    /// files `inputs`).
    pub fn new(
        inputs: [String; 2],
        right: &LoadedGraph,
        left: &LoadedGraph,
        result: Averaged<SimultaneousSolution>,
    ) -> Self {
        RigReport {
            inputs,
            formats: [right.format, left.format],
            node_ids: right.node_ids.clone(),
            num_edges: [right.problem.num_edges(), left.problem.num_edges()],
            warnings: [super::input_warnings(right), super::input_warnings(left)].concat(),
            result,
            sensor_from_rig_held: false,
            robust: None,
        }
    }

    /// The report of `result` with the other sensor's `sensor_from_rig` held, not estimated
    /// (`rotavg rig --sensor-from-rig`): its verdict is about the frames' view graph `[H18]`.
    pub fn sensor_held(mut self) -> Self {
        self.sensor_from_rig_held = true;
        self
    }

    /// Average the rig of `right` and `left` (read from the files `inputs`) as `rotavg rig`
    /// does: jointly ([`average_simultaneous`]), or with `held` as the other sensor's
    /// `sensor_from_rig` ([`average_with_sensor_held`], `[H18]`); the solve within
    /// `max_seconds`, the certificate under `certify`.
    pub fn average(
        inputs: [String; 2],
        (right, left): (&LoadedGraph, &LoadedGraph),
        held: Option<Rotation>,
        certify: crate::certify::CertifySettings,
        max_seconds: Option<f64>,
    ) -> Result<Self> {
        let problem = rig_problem(right, left)?;
        let Some(s) = held else {
            let solve = SimultaneousSettings {
                max_memory_bytes: certify.budget.max_memory_bytes,
                max_seconds,
                ..Default::default()
            };
            let result = average_simultaneous(&problem, &AverageSettings { solve, certify })?;
            return Ok(RigReport::new(inputs, right, left, result));
        };
        let solve = MultipleSettings {
            max_seconds,
            ..Default::default()
        };
        let result = average_with_sensor_held(&problem, &s, &AverageSettings { solve, certify })?;
        Ok(RigReport::new(inputs, right, left, result).sensor_held())
    }

    /// Certify a rig estimate computed elsewhere (`rotations` of the frames, `s` its
    /// `sensor_from_rig`), never changed: `rotavg certify RIGHT --left LEFT --estimate FILE`.
    pub fn certify(
        inputs: [String; 2],
        right: &LoadedGraph,
        left: &LoadedGraph,
        rotations: Vec<Rotation>,
        s: Rotation,
        settings: &crate::certify::CertifySettings,
    ) -> Result<Self> {
        let p = rig_problem(right, left)?;
        let c = crate::certify::certify_simultaneous(
            &right.problem,
            &left.problem,
            &rotations,
            &s,
            settings,
        )?;
        let solution = SimultaneousSolution {
            cost: p.cost(&rotations, &s),
            rotations,
            s,
            report: super::given_report(),
        };
        let result = super::given_result(solution, c);
        Ok(RigReport::new(inputs, right, left, result))
    }

    /// The verdict of the joint estimate's certificate, if one was computed.
    pub fn verdict(&self) -> Option<crate::Verdict> {
        self.result.certificate.as_ref().map(|c| c.verdict)
    }

    /// The verdict and what it is about (`verdict` of the JSON report, as `multiple`'s): the
    /// returned frames and `sensor_from_rig` on the rig's joint chordal problem.
    pub fn verdict_of(&self) -> Option<super::VerdictOf> {
        let c = self.result.certificate.as_ref()?;
        let frames = self.result.solution.rotations.len();
        let edges = self.num_edges[0] + self.num_edges[1];
        use crate::certify::CertifiedProblemKind as Kind;
        let kind = match (&self.robust, self.sensor_from_rig_held) {
            (Some(_), _) => Kind::ChordalL2RigImagesInliers,
            (None, true) => Kind::ChordalL2RigSensorHeld,
            (None, false) => Kind::ChordalL2Rig,
        };
        Some(super::VerdictOf {
            verdict: c.verdict,
            estimate: super::CertifiedEstimate::Returned,
            problem: crate::certify::CertifiedProblem {
                kind,
                num_nodes: frames,
                total_nodes: frames,
                num_edges: self.robust.as_ref().map_or(edges, |r| r.inlier_edges),
                total_edges: edges,
            },
        })
    }
}

impl fmt::Display for SimultaneousSolution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let axis = log(&self.s).try_normalize(0.0).unwrap_or_default();
        write!(
            f,
            "joint chordal cost {:.9e}; sensor_from_rig S: {:.6} deg about ({:.6}, {:.6}, {:.6}); {}",
            self.cost,
            angle(&self.s).to_degrees(),
            axis.x,
            axis.y,
            axis.z,
            self.report
        )
    }
}

impl fmt::Display for RigReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "rig: {} ({} format, {} edges) and {} ({} format, {} edges), {} frames",
            self.inputs[0],
            self.formats[0],
            self.num_edges[0],
            self.inputs[1],
            self.formats[1],
            self.num_edges[1],
            self.node_ids.len()
        )?;
        if self.sensor_from_rig_held {
            write!(f, ", sensor_from_rig held")?;
        }
        for w in &self.warnings {
            write!(f, "\nwarning: {w}")?;
        }
        if let Some(r) = &self.robust {
            write!(f, "\n{}", r.summary(false))?;
        }
        super::result_and_verdict(f, &self.result, self.verdict_of())
    }
}

#[derive(Serialize)]
struct Json<'a> {
    problem: &'static str,
    num_rotations: usize,
    num_measurements: usize,
    warnings: &'a [Warning],
    inputs: &'a [String; 2],
    formats: [GraphFormat; 2],
    cost: f64,
    estimate: Rows<'a>,
    #[serde(with = "crate::so3::serde_rows::rotation")]
    sensor_from_rig: &'a Rotation,
    sensor_from_rig_held: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    robust: Option<&'a crate::pipeline::rig::RigRobustDetails>,
    node_ids: &'a [u64],
    solver: &'a crate::termination::SolverReport,
    certificate: Option<&'a crate::certify::Certificate>,
    verdict: Option<super::VerdictOf>,
    pipeline: &'a crate::pipeline::PipelineDetails,
}

impl Serialize for RigReport {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        let s = &self.result.solution;
        // the contract's first keys; `problem` is "rig" (an extension of section 5's kinds)
        Json {
            problem: "rig",
            // the frames, and S unless it was held
            num_rotations: s.rotations.len() + usize::from(!self.sensor_from_rig_held),
            num_measurements: self.num_edges[0] + self.num_edges[1],
            warnings: &self.warnings,
            inputs: &self.inputs,
            formats: self.formats,
            cost: s.cost,
            estimate: Rows::Many(&s.rotations),
            sensor_from_rig: &s.s,
            sensor_from_rig_held: self.sensor_from_rig_held,
            robust: self.robust.as_ref(),
            node_ids: &self.node_ids,
            solver: &s.report,
            certificate: self.result.certificate.as_ref(),
            verdict: self.verdict_of(),
            pipeline: &self.result.details,
        }
        .serialize(serializer)
    }
}
