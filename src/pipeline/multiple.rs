//! The multiple-rotation-averaging pipeline `[D12]` (`paper-notes/certificates.md`):
//! initialise and solve locally ([`solve_multiple`]), then certify ([`certify_multiple`]: the
//! dual certificate, then the SDP or the staircase when needed) and adopt the refined estimate
//! or the polished SDP rounding when it is better. With a robust loss (L1, Huber, Cauchy) the
//! robust cost has no certificate; the pipeline certifies instead the chordal L2 problem on the
//! edges the robust solver kept ([`super::InlierGraph`], [`super::certify_inlier_graph`]).

use super::inlier_graph::{ViewGraphProblem, inlier_graph_of};
use super::{AverageSettings, Averaged, PipelineProblem, PipelineSolution, average};
use crate::certify::{Certification, CertifyMode, CertifySettings, certify_multiple};
use crate::error::Result;
use crate::multiple::robust::{inlier_threshold_deg, suspected_outliers};
use crate::multiple::{MultipleProblem, MultipleSettings, MultipleSolution, solve_multiple};
use crate::termination::SolverReport;
use std::time::Instant;

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
/// The certificate's lower bound is the largest verified bound computed. Geodesic L2 gets no
/// certificate. The robust losses (L1, Huber, Cauchy) get no certificate of their cost either
/// (`certificate` is `None`); unless the mode is `none`, the pipeline then refines and
/// certifies the chordal L2 problem on their inlier graph with that mode
/// ([`super::certify_inlier_graph`], in `details.inlier_graph`), leaving the robust estimate as the
/// returned solution. All settings are validated before any work.
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
    average_view_graph(problem, settings)
}

/// [`average_multiple`] for any problem on a view graph (with or without gravity priors): the
/// rule `auto`, least squares with its outlier diagnosis, or a robust loss with its inlier
/// graph.
pub(super) fn average_view_graph<P: ViewGraphProblem>(
    problem: &P,
    settings: &AverageSettings<MultipleSettings>,
) -> Result<Averaged<MultipleSolution>> {
    let graph = problem.graph();
    let objective = graph.objective();
    if let Some(robust) = settings.solve.robust_on_outliers
        && objective.is_chordal_l2()
    {
        return super::loss_choice::average_by_residuals(problem, settings, robust);
    }
    if inlier_threshold_deg(&objective, &settings.solve).is_none() {
        // least squares: say when the residuals look like outliers (a robust loss is then the
        // better tool)
        let mut out = average(problem, settings)?;
        out.details.outliers = suspected_outliers(graph, &out.solution.rotations);
        return Ok(out);
    }
    average_robust(problem, settings)
}

/// The pipeline of a robust loss (L1, Huber, Cauchy) on a view graph: the robust solve, then,
/// unless the mode is `none`, the chordal L2 problem on its inlier graph refined and certified
/// ([`inlier_graph_of`]); the robust estimate is the one returned (its cost has no certificate).
pub(super) fn average_robust<P: ViewGraphProblem>(
    problem: &P,
    settings: &AverageSettings<MultipleSettings>,
) -> Result<Averaged<MultipleSolution>> {
    let objective = problem.graph().objective();
    if settings.certify.mode == CertifyMode::None {
        return average(problem, settings);
    }
    let start = Instant::now();
    settings.certify.validate()?;
    settings.certify.mode.require(P::NAME, P::MODES)?;
    let robust_only = AverageSettings {
        solve: settings.solve.clone(),
        certify: CertifySettings {
            mode: CertifyMode::None,
            ..settings.certify.clone()
        },
    };
    let mut out = average(problem, &robust_only)?;
    let t = Instant::now();
    let graph = inlier_graph_of(problem, &out.solution, &settings.remaining(start))?;
    out.details.skipped_reason = Some(format!(
        "the {objective} cost has no certificate (only chordal L2 is certifiable); {}",
        match &graph {
            Some(_) => "the chordal L2 problem on its inlier graph was certified instead",
            None => "no edge is an inlier, so there is no inlier graph to certify",
        }
    ));
    out.details.inlier_graph = graph.map(Box::new);
    out.details.certify_seconds = t.elapsed().as_secs_f64();
    out.details.total_seconds = start.elapsed().as_secs_f64();
    Ok(out)
}
