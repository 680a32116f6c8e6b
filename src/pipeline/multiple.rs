//! The multiple-rotation-averaging pipeline `[D12]` (`paper-notes/certificates.md`):
//! initialise and solve locally ([`solve_multiple`]), then certify ([`certify_multiple`]: the
//! dual certificate, then the SDP or the staircase when needed) and adopt the refined estimate
//! or the polished SDP rounding when it is better.

use super::{AverageSettings, Averaged, PipelineProblem, PipelineSolution, average};
use crate::certify::{Certification, CertifyMode, CertifySettings, certify_multiple};
use crate::error::Result;
use crate::multiple::{MultipleProblem, MultipleSettings, MultipleSolution, solve_multiple};
use crate::termination::SolverReport;

impl PipelineSolution for MultipleSolution {
    fn certified_cost(&self) -> f64 {
        self.chordal_cost
    }
    fn report_mut(&mut self) -> &mut SolverReport {
        &mut self.report
    }
    fn adopt(self, mut better: Self) -> Self {
        better.report.iterations += self.report.iterations;
        better.report.seconds += self.report.seconds;
        better.init_cost = self.init_cost;
        better
    }
}

impl PipelineProblem for MultipleProblem {
    type Settings = MultipleSettings;
    type Solution = MultipleSolution;
    const NAME: &'static str = "multiple";
    const MODES: &'static [CertifyMode] = &[
        CertifyMode::Auto,
        CertifyMode::Dual,
        CertifyMode::Sdp,
        CertifyMode::Staircase,
        CertifyMode::None,
    ];
    fn validate(settings: &MultipleSettings) -> Result<()> {
        settings.validate()
    }
    fn uncertifiable(&self, _mode: CertifyMode) -> Option<String> {
        let objective = self.objective();
        (!objective.is_chordal_l2()).then(|| {
            format!("the {objective} cost has no certificate (only chordal L2 is certifiable)")
        })
    }
    fn solve(&self, settings: &MultipleSettings) -> Result<MultipleSolution> {
        solve_multiple(self, settings)
    }
    fn certify(
        &self,
        solution: &MultipleSolution,
        settings: &CertifySettings,
    ) -> Result<Certification<MultipleSolution>> {
        certify_multiple(self, &solution.rotations, settings)
    }
}

/// Multiple rotation averaging with a certificate: initialise and solve locally
/// ([`solve_multiple`] with `settings.solve`), then, for the chordal L2 objective, certify with
/// [`certify_multiple`] (dual certificate; SDP for `n <= sdp_max_nodes` or the staircase when it
/// fails) and adopt the better solution it may find (a refinement, or the polished SDP rounding).
/// The certificate's lower bound is the largest verified bound computed. Other objectives get
/// no certificate. All settings are validated before any work.
///
/// ```
/// use rotavg::pipeline::{average_multiple, AverageSettings};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, _) = SyntheticGraph { num_rotations: 30, num_edges: 90, noise_sigma: 0.05, ..Default::default() }.generate();
/// let est = average_multiple(&p, &AverageSettings::default())?;
/// assert!(est.certificate.unwrap().is_certified());
/// assert!(rotavg::so3::angle(&est.solution.rotations[0]) < 1e-12); // gauge R_0 = I
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_multiple(
    problem: &MultipleProblem,
    settings: &AverageSettings<MultipleSettings>,
) -> Result<Averaged<MultipleSolution>> {
    average(problem, settings)
}
