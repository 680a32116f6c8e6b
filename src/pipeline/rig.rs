//! A rig of any number of sensors solved and certified (`paper-notes/conjugate.md` `[H19]`):
//! [`solve_rig`], then [`certify_rig`].

use super::{AverageSettings, Averaged, PipelineProblem, PipelineSolution, average};
use crate::certify::{Certification, CertifyMode, CertifySettings, certify_rig};
use crate::error::Result;
use crate::rig::{RigProblem, RigSettings, RigSolution, solve_rig};
use crate::termination::SolverReport;

/// Settings of [`average_rig`].
pub type AverageRigSettings = AverageSettings<RigSettings>;

/// Solve a rig ([`solve_rig`]) and certify the estimate ([`certify_rig`]): with every sensor
/// held, by the frames' view graph; otherwise by the images' view graph without the rig's
/// constraints, tight on noise-free rigs and a stated gap on noisy ones.
///
/// ```
/// use rotavg::pipeline::average_rig;
/// use rotavg::rig::RigScene;
/// let (p, truth) = RigScene { frames: 40, sensors: 4, noise_sigma: 0.01, known: true, ..Default::default() }.generate();
/// let out = average_rig(&p, &Default::default())?;
/// assert!(out.certificate.unwrap().is_certified()); // every sensor known: the frames' graph
/// assert!(rotavg::so3::angle_between(&out.solution.sensors[3], &truth.sensors[3]) < 1e-12);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_rig(
    problem: &RigProblem,
    settings: &AverageRigSettings,
) -> Result<Averaged<RigSolution>> {
    average(problem, settings)
}

impl PipelineSolution for RigSolution {
    fn certified_cost(&self) -> f64 {
        self.cost
    }
    fn report_mut(&mut self) -> &mut SolverReport {
        &mut self.report
    }
}

impl PipelineProblem for RigProblem {
    type Settings = RigSettings;
    type Solution = RigSolution;
    const NAME: &'static str = "rig";
    const MODES: &'static [CertifyMode] =
        &[CertifyMode::Auto, CertifyMode::Dual, CertifyMode::None];
    fn validate(settings: &RigSettings) -> Result<()> {
        settings.validate()
    }
    fn uncertifiable(&self, _mode: CertifyMode) -> Option<String> {
        None
    }
    fn solve(&self, settings: &RigSettings) -> Result<RigSolution> {
        solve_rig(self, settings)
    }
    fn certify(
        &self,
        solution: &RigSolution,
        settings: &CertifySettings,
    ) -> Result<Certification<RigSolution>> {
        let c = certify_rig(self, &solution.frames, &solution.sensors, settings)?;
        Ok(Certification {
            certificate: c.certificate,
            details: c.details,
            improvement: None,
        })
    }
}
