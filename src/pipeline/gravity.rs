//! Chordal L2 averaging with gravity priors (contract section 5, "Rigs and gravity";
//! `paper-notes/gravity.md`): [`crate::multiple::gravity::solve_gravity`], then
//! [`crate::certify::certify_gravity`], in the one pipeline shape. The priors' agreement with
//! the relative rotations ([`GravityProblem::check_conventions`]) is part of the report.

use super::{AverageSettings, Averaged, PipelineProblem, average};
use crate::certify::{Certification, CertifyMode, CertifySettings, certify_gravity};
use crate::error::Result;
use crate::multiple::gravity::{GravityCheck, GravityProblem, solve_gravity};
use crate::multiple::robust::suspected_outliers;
use crate::multiple::{MultipleSettings, MultipleSolution};
use serde::{Deserialize, Serialize};

impl PipelineProblem for GravityProblem {
    type Settings = MultipleSettings;
    type Solution = MultipleSolution;
    const NAME: &'static str = "gravity";
    const MODES: &'static [CertifyMode] =
        &[CertifyMode::Auto, CertifyMode::Dual, CertifyMode::None];
    fn validate(settings: &MultipleSettings) -> Result<()> {
        settings.validate()
    }
    fn uncertifiable(&self, _mode: CertifyMode) -> Option<String> {
        let objective = self.problem().objective();
        (!objective.is_chordal_l2()).then(|| {
            format!("the {objective} cost has no certificate (only chordal L2 is certifiable)")
        })
    }
    fn solve(&self, settings: &MultipleSettings) -> Result<MultipleSolution> {
        solve_gravity(self, settings)
    }
    fn certify(
        &self,
        solution: &MultipleSolution,
        settings: &CertifySettings,
    ) -> Result<Certification<MultipleSolution>> {
        certify_gravity(self, &solution.rotations, settings)
    }
}

/// What the gravity priors were, and how they agree with the view graph.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GravityDetails {
    /// Images with a prior, and in all.
    pub num_with_prior: usize,
    /// Images in all.
    pub num_images: usize,
    /// `full` (every image has a prior: the SO(2) certificate applies) or `mixed`.
    pub kind: String,
    /// The world's down direction (`R_i world_down = g_i`).
    pub world_down: [f64; 3],
    /// The edges' agreement with the priors (`None`: no edge has priors at both ends).
    pub check: Option<GravityCheck>,
}

/// Chordal L2 averaging with gravity as a hard constraint, certified: the local solve
/// ([`solve_gravity`]) and the certificate ([`certify_gravity`]: SO(2) dual certificate for
/// full gravity, the view graph's bound otherwise). Least squares only: a robust loss in
/// `settings.solve` is an error, and the rule `auto` (`robust_on_outliers`) keeps least
/// squares, with the outlier diagnosis in `details.outliers`. Returns the pipeline result and
/// the priors' details.
///
/// ```
/// use rotavg::pipeline::{average_with_gravity, AverageSettings};
/// use rotavg::multiple::gravity::GravityProblem;
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (graph, truth) = SyntheticGraph { num_rotations: 30, num_edges: 90, noise_sigma: 0.05, ..Default::default() }.generate();
/// let p = GravityProblem::from_truth(graph, &truth)?;
/// let (est, details) = average_with_gravity(&p, &AverageSettings::default())?;
/// assert!(est.certificate.unwrap().is_certified());
/// assert_eq!(details.kind, "full");
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_with_gravity(
    problem: &GravityProblem,
    settings: &AverageSettings<MultipleSettings>,
) -> Result<(Averaged<MultipleSolution>, GravityDetails)> {
    let mut settings = settings.clone();
    settings.solve.robust_on_outliers = None;
    let mut out = average(problem, &settings)?;
    out.details.outliers = suspected_outliers(problem.problem(), &out.solution.rotations);
    let priors = problem.priors();
    let details = GravityDetails {
        num_with_prior: priors.num_known(),
        num_images: priors.len(),
        kind: if priors.is_full() { "full" } else { "mixed" }.into(),
        world_down: priors.world_down().into(),
        check: problem.check_conventions(),
    };
    Ok((out, details))
}
