//! `rotavg rig FILE`: a rig of any number of sensors read from a JSON rig file or a COLMAP
//! database's rig configuration ([`crate::io::rig`]), solved and certified
//! ([`crate::pipeline::average_rig`], `paper-notes/conjugate.md` `[H19]`), as text and JSON.

use super::Rows;
use crate::Result;
use crate::certify::{CertifiedProblem, CertifiedProblemKind, CertifySettings};
use crate::io::rig::LoadedRig;
use crate::multiple::anisotropic::InformationSummary;
use crate::pipeline::rig::{
    RigCalibration, RigGravityDetails, RigLoss, RigRobustDetails,
    average_rig_calibrated_with_gravity, average_rig_with_loss,
};
use crate::pipeline::{AverageSettings, Averaged};
use crate::rig::{RigRobust, RigSettings, RigSolution};
use crate::so3::{angle, log};
use crate::warning::Warning;
use serde::{Serialize, Serializer};
use std::fmt;

/// A rig file's report: the rig as read and its estimate with the certificate.
#[derive(Debug, Clone, PartialEq)]
pub struct RigFileReport {
    /// The file, as given.
    pub input: String,
    /// The rig as read (with the file's ids and the reader's warnings).
    pub rig: LoadedRig,
    /// The estimate: the frames (`F_0 = I`) and every sensor's `sensor_from_rig`.
    pub result: Averaged<RigSolution>,
    /// A robust solve's loss, inliers and diagnosis (`--loss cauchy`, or `auto` on outliers);
    /// then the estimate and its certificate are the inlier problem's.
    pub robust: Option<RigRobustDetails>,
    /// The gravity priors and their checks (`--gravity`, `[G14]`).
    pub gravity: Option<RigGravityDetails>,
    /// With gravity priors and sensors to estimate: the calibration without the priors whose
    /// sensors the result holds (`[G14]`; then `rig.problem` is the held rig).
    pub calibration: Option<RigCalibration>,
    /// The sensors the file leaves to estimate, as read (with gravity priors `rig.problem`
    /// then holds them: at the calibration, or at the estimate `certify` was given).
    pub estimated_sensors: Vec<usize>,
}

impl RigFileReport {
    /// Write the estimate to `path` (`rotavg rig FILE --output`): JSON `{"frames": [...],
    /// "frame_ids": [...], "sensors_from_rig": [...], "sensor_ids": [...]}`; of two view graphs
    /// ([`crate::io::rig::TWO_GRAPHS_FORMAT`]) as [`super::RigReport::write_output`] writes
    /// theirs, `{"rotations": [...], "node_ids": [...], "sensor_from_rig": S}`.
    pub fn write_output(&self, path: &str) -> crate::Result<()> {
        let s = &self.result.solution;
        let text = match (
            self.rig.format == crate::io::rig::TWO_GRAPHS_FORMAT,
            &s.sensors[..],
        ) {
            (true, [_, other]) => {
                crate::io::json::write_rig_json(&s.frames, &self.rig.frame_ids, other)
            }
            _ => crate::io::rig::write_rig_estimate_json(&s.frames, &s.sensors, &self.rig),
        };
        crate::io::output::write_text(path, &text)
    }

    /// Solve the rig read from `input` with `loss` (`robust`: the Cauchy loss's thresholds) and
    /// certify it: the solve within `max_seconds`, the certificate under `certify`
    /// ([`average_rig_with_loss`]).
    pub fn average(
        input: String,
        rig: LoadedRig,
        (loss, robust): (RigLoss, RigRobust),
        certify: CertifySettings,
        max_seconds: Option<f64>,
    ) -> Result<Self> {
        let solve = RigSettings {
            max_seconds,
            ..Default::default()
        };
        let settings = AverageSettings { solve, certify };
        let mut rig = rig;
        let estimated_sensors = rig.problem.estimated_sensors();
        let ((result, certified, robust), calibration) = match rig.pending_gravity.take() {
            Some(priors) => {
                let both = (loss, &robust);
                let (run, c) =
                    average_rig_calibrated_with_gravity(&rig.problem, priors, both, &settings)?;
                (run, Some(c))
            }
            None => (
                average_rig_with_loss(&rig.problem, loss, &robust, &settings)?,
                None,
            ),
        };
        if calibration.is_some() {
            // the rig certified: every sensor held at the calibration, with the priors
            rig.problem = certified.with_edges(rig.problem.edges().to_vec())?;
        }
        Ok(RigFileReport {
            gravity: RigGravityDetails::of(&rig.problem)?,
            input,
            rig,
            result,
            robust,
            calibration,
            estimated_sensors,
        })
    }

    /// Certify a rig estimate computed elsewhere (read by [`crate::io::rig::read_rig_estimate`]),
    /// never changed: `rotavg certify FILE --rig --estimate EST`. A projection of the estimate
    /// (`--nearest-rotations`) is a warning of the report.
    pub fn certify(
        input: String,
        mut rig: LoadedRig,
        estimate: crate::io::rig::RigEstimate,
        settings: &CertifySettings,
    ) -> Result<Self> {
        let (mut joint, start) = (None, std::time::Instant::now());
        let estimated_sensors = rig.problem.estimated_sensors();
        if let Some(priors) = rig.pending_gravity.take() {
            // soft priors with sensors to estimate: the joint problem first ([G16]; not on the
            // two-graph shape, where its couplings cannot prove it); when it does not certify,
            // and for held priors, the estimate's sensors held ([G14])
            if priors.weight().is_some() && !crate::certify::rig::is_two_graphs(&rig.problem) {
                let p = rig.problem.clone().with_gravity(priors.clone())?;
                let c =
                    crate::certify::certify_rig(&p, &estimate.frames, &estimate.sensors, settings)?;
                joint = Some(c);
            }
            let held = rig.problem.with_sensors_held(&estimate.sensors)?;
            rig.problem = held.with_gravity(priors)?;
        }
        let frames = estimate.frames;
        let c = match joint.as_ref().filter(|j| j.certificate.is_certified()) {
            Some(j) => j.clone(),
            None => {
                // one budget for both certifications
                let mut left = settings.clone();
                left.budget = settings.budget.after(start);
                crate::certify::certify_rig(&rig.problem, &frames, &estimate.sensors, &left)?
            }
        };
        // the held sensors as held, as certified (the estimate's are within 1e-9 rad of them)
        let sensors = rig.problem.at_held(&estimate.sensors);
        if let Some(p) = &estimate.projection {
            rig.warnings.push(p.warning());
        }
        let solution = RigSolution {
            cost: rig.problem.cost(&frames, &sensors),
            frames,
            sensors,
            report: super::given_report(),
        };
        let mut result = super::given_result(solution, c);
        result.details.rig_joint = joint.map(|j| j.certificate);
        Ok(RigFileReport {
            gravity: RigGravityDetails::of(&rig.problem)?,
            input,
            rig,
            result,
            robust: None,
            calibration: None,
            estimated_sensors,
        })
    }

    /// The verdict of the certificate, if one was computed.
    pub fn verdict(&self) -> Option<crate::Verdict> {
        self.result.certificate.as_ref().map(|c| c.verdict)
    }

    /// The verdict and the problem it is about.
    pub fn verdict_of(&self) -> Option<super::VerdictOf> {
        let c = self.result.certificate.as_ref()?;
        let p = &self.rig.problem;
        let (frames, edges) = (p.num_frames(), p.edges().len());
        let soft = p.gravity().map(|g| g.weight().is_some());
        let joint = (self.result.details.rig_joint.as_ref())
            .is_some_and(crate::certify::Certificate::is_certified);
        let kind = match (&self.robust, p.all_held(), soft) {
            (Some(_), _, Some(true)) if joint => {
                CertifiedProblemKind::ChordalL2RigImagesGravitySoftInliers
            }
            (None, _, Some(true)) if joint => CertifiedProblemKind::ChordalL2RigImagesGravitySoft,
            (Some(_), _, Some(true)) => CertifiedProblemKind::ChordalL2RigGravitySoftInliers,
            (Some(_), _, Some(false)) => CertifiedProblemKind::ChordalL2RigGravityInliers,
            (None, _, Some(true)) => CertifiedProblemKind::ChordalL2RigGravitySoft,
            (None, _, Some(false)) => CertifiedProblemKind::ChordalL2RigGravity,
            (Some(_), _, None) => CertifiedProblemKind::ChordalL2RigImagesInliers,
            (None, true, None) => CertifiedProblemKind::ChordalL2RigImagesSensorsHeld,
            (None, false, None) => CertifiedProblemKind::ChordalL2RigImages,
        };
        Some(super::VerdictOf {
            verdict: c.verdict,
            estimate: super::CertifiedEstimate::Returned,
            problem: CertifiedProblem {
                kind,
                num_nodes: frames,
                total_nodes: frames,
                num_edges: self.robust.as_ref().map_or(edges, |r| r.inlier_edges),
                total_edges: edges,
            },
        })
    }

    /// Every warning: the reader's, and the outlier diagnosis of the least-squares estimate
    /// (which turned the solve robust under `auto`).
    pub fn warnings(&self) -> Vec<Warning> {
        let outliers = self.result.details.outliers.as_ref().map(|w| {
            Warning::new("outliers_suspected", format!("{}: {w}", self.input))
                .with_count(w.suspected)
        });
        let gravity = self.gravity.iter().flat_map(RigGravityDetails::warnings);
        let refinement = (self.calibration.as_ref())
            .and_then(|c| c.refinement_failed.as_ref())
            .map(|why| {
                Warning::new(
                    "gravity_refinement_failed",
                    format!(
                        "the soft gravity priors did not refine the sensors ({why}): the \
                         calibration without them is held [G15]"
                    ),
                )
            });
        (self.rig.warnings.iter().cloned())
            .chain(gravity)
            .chain(outliers)
            .chain(refinement)
            .collect()
    }

    /// How many sensors were estimated (not held; with a calibration, by it).
    fn estimated(&self) -> usize {
        self.estimated_sensors.len()
    }
}

impl fmt::Display for RigSolution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // with soft gravity priors, their terms are part of it
        write!(f, "rig cost {:.9e}; {}", self.cost, self.report)?;
        for (s, r) in self.sensors.iter().enumerate() {
            let axis = log(r).try_normalize(0.0).unwrap_or_default();
            write!(
                f,
                "\n  sensor {s}: sensor_from_rig {:.6} deg about ({:.6}, {:.6}, {:.6})",
                angle(r).to_degrees(),
                axis.x,
                axis.y,
                axis.z
            )?;
        }
        Ok(())
    }
}

/// `certified, gap 1.234e-8 (relative 5.6e-11)`: the absolute gap beside the relative one, which
/// is not telling at a cost near 0 (noise-free data).
fn verdict_and_gap(c: &crate::certify::Certificate) -> String {
    match (c.gap, c.relative_gap) {
        (Some(gap), Some(relative)) => {
            format!("{}, gap {gap:.3e} (relative {relative:.1e})", c.verdict)
        }
        _ => format!("{} ({})", c.verdict, c.explanation),
    }
}

impl fmt::Display for RigFileReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = &self.rig.problem;
        write!(
            f,
            "rig: {} ({} format): {} frames, {} sensors ({} estimated), {} images, {} edges",
            self.input,
            self.rig.format,
            p.num_frames(),
            p.sensors().len(),
            self.estimated(),
            p.images().len(),
            p.edges().len()
        )?;
        if let Some(info) = p.information().and_then(InformationSummary::of) {
            write!(f, "\n{info} [H24]")?;
        }
        if let Some(c) = &self.calibration {
            let verdict = c
                .certificate
                .as_ref()
                .map_or("no certificate".into(), verdict_and_gap);
            let then = match c.refined_sensors_from_rig {
                Some(_) => "then refined by the soft priors [G15] and held with them",
                None => "then held with the priors",
            };
            write!(
                f,
                "\ncalibration without the gravity priors [G14]: sensors {:?} estimated, cost \
                 {:.9e}, {verdict}; {then}",
                c.estimated, c.cost
            )?;
        }
        if let Some(j) = &self.result.details.rig_joint {
            write!(
                f,
                "\njoint problem with the sensors free and the soft priors [G16]: {}{}",
                verdict_and_gap(j),
                match j.is_certified() {
                    true => " (the certificate below)",
                    false => "; the certificate below is the held rig's",
                }
            )?;
        }
        if let Some(g) = &self.gravity {
            write!(f, "\n{g}")?;
        }
        for w in &self.warnings() {
            write!(f, "\nwarning: {w}")?;
        }
        if let Some(r) = &self.robust {
            write!(f, "\n{}", r.summary(p.is_anisotropic()))?;
        }
        super::result_and_verdict(f, &self.result, self.verdict_of())
    }
}

#[derive(Serialize)]
struct Json<'a> {
    problem: &'static str,
    num_rotations: usize,
    num_measurements: usize,
    warnings: Vec<Warning>,
    input: &'a str,
    format: &'a str,
    cost: f64,
    estimate: Rows<'a>,
    frame_ids: &'a [u64],
    sensors_from_rig: Rows<'a>,
    sensor_ids: &'a [u64],
    sensors_held: Vec<bool>,
    num_images: usize,
    /// The information matrices' summary, when the edges carry some (`[H24]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    information: Option<InformationSummary>,
    #[serde(skip_serializing_if = "Option::is_none")]
    robust: Option<&'a RigRobustDetails>,
    #[serde(skip_serializing_if = "Option::is_none")]
    gravity: Option<&'a RigGravityDetails>,
    #[serde(skip_serializing_if = "Option::is_none")]
    calibration: Option<&'a RigCalibration>,
    solver: &'a crate::termination::SolverReport,
    certificate: Option<&'a crate::certify::Certificate>,
    verdict: Option<super::VerdictOf>,
    pipeline: &'a crate::pipeline::PipelineDetails,
}

impl Serialize for RigFileReport {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        let (s, p) = (&self.result.solution, &self.rig.problem);
        Json {
            problem: "rig",
            // the frames and the estimated sensors
            num_rotations: s.frames.len() + self.estimated(),
            num_measurements: p.edges().len(),
            warnings: self.warnings(),
            input: &self.input,
            format: &self.rig.format,
            cost: s.cost,
            estimate: Rows::Many(&s.frames),
            frame_ids: &self.rig.frame_ids,
            sensors_from_rig: Rows::Many(&s.sensors),
            sensor_ids: &self.rig.sensor_ids,
            sensors_held: p.held().iter().map(Option::is_some).collect(),
            num_images: p.images().len(),
            information: p.information().and_then(InformationSummary::of),
            robust: self.robust.as_ref(),
            gravity: self.gravity.as_ref(),
            calibration: self.calibration.as_ref(),
            solver: &s.report,
            certificate: self.result.certificate.as_ref(),
            verdict: self.verdict_of(),
            pipeline: &self.result.details,
        }
        .serialize(serializer)
    }
}
