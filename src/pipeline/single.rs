//! The single-averaging pipeline: [`solve_single`], then [`certify_single`].

use super::{AverageSettings, Averaged, PipelineProblem, PipelineSolution, average};
use crate::certify::{Certification, CertifyMode, CertifySettings, certify_single};
use crate::error::Result;
use crate::single::{SingleProblem, SingleSettings, SingleSolution, solve_single};
use crate::termination::SolverReport;

impl PipelineSolution for SingleSolution {
    fn certified_cost(&self) -> f64 {
        self.cost
    }
    fn report_mut(&mut self) -> &mut SolverReport {
        &mut self.report
    }
}

impl PipelineProblem for SingleProblem {
    type Settings = SingleSettings;
    type Solution = SingleSolution;
    const NAME: &'static str = "single";
    const MODES: &'static [CertifyMode] = &[
        CertifyMode::Auto,
        CertifyMode::Theory,
        CertifyMode::BranchAndBound,
        CertifyMode::None,
    ];
    fn validate(settings: &SingleSettings) -> Result<()> {
        settings.validate()
    }
    fn uncertifiable(&self, _mode: CertifyMode) -> Option<String> {
        None
    }
    fn solve(&self, settings: &SingleSettings) -> Result<SingleSolution> {
        solve_single(self, settings)
    }
    fn certify(
        &self,
        solution: &SingleSolution,
        settings: &CertifySettings,
    ) -> Result<Certification<SingleSolution>> {
        certify_single(self, &solution.estimate, settings)
    }
}

/// Average the samples of `problem` under its objective ([`solve_single`]) and certify the mean
/// ([`certify_single`], unless `settings.certify.mode` is `none`). All settings are validated
/// before any work.
///
/// ```
/// use rotavg::pipeline::{average_single, AverageSettings};
/// use rotavg::single::SingleProblem;
/// use rotavg::objective::{Loss, Objective};
/// use rotavg::so3::{exp, Metric};
/// use nalgebra::Vector3;
/// // Rz(0.2), Rz(-0.2) and I: every mean is I by symmetry.
/// let p = SingleProblem::new(
///     vec![exp(&Vector3::new(0.0, 0.0, 0.2)), exp(&Vector3::new(0.0, 0.0, -0.2)), exp(&Vector3::zeros())],
///     None,
/// )?;
/// for objective in [Objective::CHORDAL_L2, Objective::new(Metric::Geodesic, Loss::L1)] {
///     let est = average_single(&p.clone().with_objective(objective)?, &AverageSettings::default())?;
///     assert!(rotavg::so3::angle(&est.solution.estimate) < 1e-9);
///     assert!(est.certificate.unwrap().is_certified());
/// }
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_single(
    problem: &SingleProblem,
    settings: &AverageSettings<SingleSettings>,
) -> Result<Averaged<SingleSolution>> {
    average(problem, settings)
}
