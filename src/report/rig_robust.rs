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
use crate::pipeline::rig::{RigLoss, robust_from};
use crate::pipeline::simultaneous::{
    SimultaneousProblem, SimultaneousSettings, SimultaneousSolution,
};
use crate::pipeline::{AverageSettings, Averaged, PipelineProblem};
use crate::rig::{Image, RigProblem, RigRobust, RigSettings, RigSolution, Sensor};
use crate::so3::Rotation;

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
        let start = std::time::Instant::now();
        let problem = rig_problem(right, left)?;
        let rig = two_sensor_rig(&problem)?;
        let solve = SimultaneousSettings {
            max_memory_bytes: certify.budget.max_memory_bytes,
            max_seconds,
            ..Default::default()
        };
        let settings = AverageSettings { solve, certify };
        let skip = crate::pipeline::validate(&problem, &settings)?;
        // the joint least squares, judged before anything is certified
        let ls = problem.solve(&settings.solve)?;
        let x = rig.image_rotations(&ls.rotations, &[Rotation::identity(), ls.s]);
        let mut diagnosis = match loss {
            RigLoss::Cauchy => None,
            _ => suspected_outliers(&rig.image_graph()?, &x),
        };
        if loss == RigLoss::Chordal || (loss == RigLoss::Auto && diagnosis.is_none()) {
            let result = crate::pipeline::certify_solved(&problem, ls, &settings, skip, start)?;
            let mut report = RigReport::new(inputs, right, left, result);
            if let Some(w) = &mut diagnosis {
                w.suggestion = "`--loss cauchy` (or the default `--loss auto`) solves it and \
                                certifies the chordal L2 problem on the inlier edges"
                    .into();
                report.outliers_warning(w);
            }
            return Ok(report);
        }
        if let Some(w) = &mut diagnosis {
            w.suggestion = "so the Cauchy loss ran instead (`--loss auto`; `--loss chordal` keeps \
                            least squares)"
                .into();
        }
        let sensors = vec![Rotation::identity(), ls.s];
        let ls = RigSolution {
            cost: rig.cost(&ls.rotations, &sensors),
            frames: ls.rotations,
            sensors,
            report: ls.report,
        };
        let rig_settings = AverageSettings {
            solve: RigSettings {
                max_seconds,
                ..Default::default()
            },
            certify: settings.certify,
        }
        .remaining(start);
        let (mut out, _, details) = robust_from(
            &rig,
            Some(ls),
            (loss, diagnosis.clone()),
            &robust,
            &rig_settings,
        )?;
        out.details
            .add_solve_seconds(start.elapsed().as_secs_f64() - out.details.total_seconds);
        let mut report = RigReport::new(inputs, right, left, as_joint(out));
        if let Some(w) = &diagnosis {
            report.outliers_warning(w);
        }
        report.robust = Some(details);
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
