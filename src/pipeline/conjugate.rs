//! The conjugate-averaging pipeline `[H9]`: quaternion closed form -> local solver
//! ([`solve_conjugate`]) -> SDP certificate with rank-one extraction and polish
//! ([`certify_conjugate`]).

use super::{AverageSettings, Averaged, PipelineProblem, PipelineSolution, average};
use crate::certify::{Certification, CertifyMode, CertifySettings, certify_conjugate};
use crate::conjugate::{ConjugateProblem, ConjugateSettings, ConjugateSolution, solve_conjugate};
use crate::error::Result;
use crate::termination::SolverReport;

impl PipelineSolution for ConjugateSolution {
    fn certified_cost(&self) -> f64 {
        self.cost
    }
    fn report_mut(&mut self) -> &mut SolverReport {
        &mut self.report
    }
}

impl PipelineProblem for ConjugateProblem {
    type Settings = ConjugateSettings;
    type Solution = ConjugateSolution;
    const NAME: &'static str = "conjugate";
    const MODES: &'static [CertifyMode] = &[
        CertifyMode::Auto,
        CertifyMode::Sdp,
        CertifyMode::BranchAndBound,
        CertifyMode::None,
    ];
    fn validate(settings: &ConjugateSettings) -> Result<()> {
        settings.validate()
    }
    fn uncertifiable(&self, mode: CertifyMode) -> Option<String> {
        let objective = self.objective();
        (mode == CertifyMode::Sdp && !objective.is_chordal_l2())
            .then(|| format!("the SDP relaxation bounds chordal L2 only, not the {objective} cost"))
    }
    fn solve(&self, settings: &ConjugateSettings) -> Result<ConjugateSolution> {
        solve_conjugate(self, settings)
    }
    fn certify(
        &self,
        solution: &ConjugateSolution,
        settings: &CertifySettings,
    ) -> Result<Certification<ConjugateSolution>> {
        certify_conjugate(self, &solution.estimate, settings)
    }
}

/// The whole conjugate pipeline `[H9]`: local solve (the quaternion closed form, or
/// `settings.solve.init`, then the solver of the problem's objective), and for chordal L2 the
/// SDP certificate: the rank-one extraction of `Z` is polished by the local solver and replaces
/// the local solution when it is better. Other objectives get no certificate (the reason is in
/// `details.skipped_reason`; an explicit `sdp` mode is refused). All settings are validated
/// before any work.
///
/// ```
/// use rotavg::pipeline::{average_conjugate, AverageSettings};
/// use rotavg::conjugate::{ConjugateSettings, synthetic::random_instance};
/// use rotavg::so3::{angle_between, Rotation};
/// use rand::SeedableRng;
/// let mut rng = rand::rngs::StdRng::seed_from_u64(8);
/// let (problem, s) = random_instance(10, 0.02, 0.0, &mut rng);
/// // Even from a poor start the SDP step finds and certifies the global minimum.
/// let settings = AverageSettings {
///     solve: ConjugateSettings { init: Some(Rotation::identity()), ..Default::default() },
///     ..Default::default()
/// };
/// let est = average_conjugate(&problem, &settings)?;
/// let cert = est.certificate.unwrap();
/// assert!(cert.is_certified());
/// assert!((cert.upper_bound - est.solution.chordal_cost).abs() <= 1e-12 * cert.upper_bound);
/// assert!(angle_between(&est.solution.estimate, &s) < 0.05);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_conjugate(
    problem: &ConjugateProblem,
    settings: &AverageSettings<ConjugateSettings>,
) -> Result<Averaged<ConjugateSolution>> {
    average(problem, settings)
}
