//! `rotavg rig RIGHT LEFT --loss auto|cauchy`: a two-sensor rig with outliers. The two view
//! graphs are a rig of two sensors with no edge between them (`paper-notes/conjugate.md`
//! `[H22]`); least squares is judged as a rig file's (`[H20]`), and when its residuals look like
//! outliers (or with `cauchy`) the rig's Cauchy solve runs and its inlier problem is returned and
//! certified ([`crate::pipeline::rig::average_rig_with_loss`]).

use super::rig::{RigReport, rig_problem};
use crate::Result;
use crate::certify::CertifySettings;
use crate::io::detect::LoadedGraph;
use crate::multiple::Edge;
use crate::multiple::robust::suspected_outliers;
use crate::pipeline::rig::{RigLoss, average_rig_with_loss};
use crate::pipeline::simultaneous::{SimultaneousProblem, SimultaneousSolution};
use crate::pipeline::{AverageSettings, Averaged};
use crate::rig::{Image, RigProblem, RigRobust, RigSettings, RigSolution, Sensor};

impl RigReport {
    /// Average the rig of `right` and `left` with `loss` (`rotavg rig RIGHT LEFT --loss`):
    /// `chordal`, [`RigReport::average`]'s least squares; `auto`, the same, then the Cauchy loss
    /// when the residuals look like outliers (the images' view graph judged as `multiple` judges
    /// its own); `cauchy`, the Cauchy loss. A robust solve returns and certifies the inlier
    /// problem (`robust` in the report says so).
    pub fn average_with_loss(
        inputs: [String; 2],
        (right, left): (&LoadedGraph, &LoadedGraph),
        (loss, robust): (RigLoss, RigRobust),
        certify: CertifySettings,
        max_seconds: Option<f64>,
    ) -> Result<Self> {
        let graphs = (right, left);
        let clock = std::time::Instant::now();
        let rig = two_sensor_rig(&rig_problem(right, left)?)?;
        let (mut diagnosis, mut judged_seconds) = (None, 0.0);
        if loss != RigLoss::Cauchy {
            let mut ls = Self::average(inputs.clone(), graphs, None, certify.clone(), max_seconds)?;
            let s = &ls.result.solution;
            let x = rig.image_rotations(&s.rotations, &[crate::Rotation::identity(), s.s]);
            diagnosis = suspected_outliers(&rig.image_graph()?, &x);
            judged_seconds = ls.result.details.total_seconds;
            if loss == RigLoss::Chordal || diagnosis.is_none() {
                if let Some(w) = &mut diagnosis {
                    w.suggestion = "`--loss cauchy` (or the default `--loss auto`) solves it and \
                                    certifies the chordal L2 problem on the inlier edges"
                        .into();
                    ls.outliers_warning(w);
                }
                return Ok(ls);
            }
        }
        let solve = RigSettings {
            max_seconds: crate::deadline::remaining(max_seconds, clock),
            ..Default::default()
        };
        let settings = AverageSettings { solve, certify };
        let (mut out, _, details) =
            average_rig_with_loss(&rig, RigLoss::Cauchy, &robust, &settings)?;
        // the least-squares run judged before it is part of the solve
        out.details.solve_seconds += judged_seconds;
        out.details.total_seconds += judged_seconds;
        let mut report = RigReport::new(inputs, right, left, as_joint(out));
        if let Some(w) = &mut diagnosis {
            w.suggestion = "so the Cauchy loss ran instead (`--loss auto`; `--loss chordal` keeps \
                            least squares)"
                .into();
            report.outliers_warning(w);
        }
        report.robust = details.map(|d| crate::pipeline::rig::RigRobustDetails {
            requested: loss,
            outliers: diagnosis,
            ..d
        });
        Ok(report)
    }
}

impl RigReport {
    /// Add the warning `outliers_suspected` of the diagnosis `w`.
    fn outliers_warning(&mut self, w: &crate::multiple::robust::OutlierWarning) {
        let text = format!("{} and {}: {w}", self.inputs[0], self.inputs[1]);
        let warning = crate::warning::Warning::new("outliers_suspected", text);
        self.warnings.push(warning.with_count(w.suspected));
    }
}

/// The two view graphs as a rig: images `0..n` the right graph's nodes (sensor 0, the
/// reference), `n..2n` the left's (sensor 1, estimated), each graph's edges between its images.
fn two_sensor_rig(p: &SimultaneousProblem) -> Result<RigProblem> {
    let n = p.num_nodes;
    let images = (0..2 * n)
        .map(|a| Image {
            frame: a % n,
            sensor: a / n,
        })
        .collect();
    let shifted = p.left.iter().map(|e| Edge {
        i: e.i + n,
        j: e.j + n,
        ..e.clone()
    });
    let edges = p.right.iter().cloned().chain(shifted).collect();
    let unknown = Sensor {
        sensor_from_rig: None,
    };
    RigProblem::new(n, vec![unknown.clone(), unknown], images, edges)
}

/// The rig's result as the joint one: the frames (sensor 0 held at the identity) and sensor 1's
/// `sensor_from_rig`.
fn as_joint(out: Averaged<RigSolution>) -> Averaged<SimultaneousSolution> {
    let RigSolution {
        frames,
        sensors,
        cost,
        report,
    } = out.solution;
    Averaged {
        solution: SimultaneousSolution {
            rotations: frames,
            s: sensors[1],
            cost,
            report,
        },
        certificate: out.certificate,
        details: out.details,
    }
}
