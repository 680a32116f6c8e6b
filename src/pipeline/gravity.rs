//! Chordal L2 averaging with gravity priors (contract section 5, "Rigs and gravity";
//! `paper-notes/gravity.md`): [`crate::multiple::gravity::solve_gravity`], then
//! [`crate::certify::certify_gravity`], in the one pipeline shape. The priors' agreement with
//! the relative rotations ([`GravityProblem::check_conventions`]) is part of the report.

use super::{AverageSettings, Averaged, PipelineProblem, average};
use crate::certify::{
    Certification, CertifiedProblem, CertifiedProblemKind, CertifyMode, CertifySettings,
    certify_gravity,
};
use crate::error::Result;
use crate::multiple::gravity::{GravityCheck, GravityProblem, solve_gravity};
use crate::multiple::robust::suspected_outliers;
use crate::multiple::{MultipleSettings, MultipleSolution};
use crate::warning::Warning;
use serde::{Deserialize, Serialize};
use std::fmt;

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
/// squares, with the outlier diagnosis in `details.outliers`. The priors and their agreement
/// with the view graph are in `details.gravity`; the certificate names its problem
/// ([`CertifiedProblemKind::ChordalL2Gravity`]).
///
/// ```
/// use rotavg::pipeline::{average_with_gravity, AverageSettings};
/// use rotavg::multiple::gravity::GravityProblem;
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (graph, truth) = SyntheticGraph { num_rotations: 30, num_edges: 90, noise_sigma: 0.05, ..Default::default() }.generate();
/// let p = GravityProblem::from_truth(graph, &truth)?;
/// let est = average_with_gravity(&p, &AverageSettings::default())?;
/// assert_eq!(est.details.gravity.as_ref().unwrap().kind, "full");
/// assert!(est.certificate.unwrap().is_certified());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_with_gravity(
    problem: &GravityProblem,
    settings: &AverageSettings<MultipleSettings>,
) -> Result<Averaged<MultipleSolution>> {
    let mut settings = settings.clone();
    settings.solve.robust_on_outliers = None;
    let mut out = average(problem, &settings)?;
    out.details.outliers = suspected_outliers(problem.problem(), &out.solution.rotations);
    let graph = problem.problem();
    out.certificate = out.certificate.map(|c| {
        c.for_problem(CertifiedProblem {
            kind: CertifiedProblemKind::ChordalL2Gravity,
            num_nodes: graph.num_rotations(),
            total_nodes: graph.num_rotations(),
            num_edges: graph.num_edges(),
            total_edges: graph.num_edges(),
        })
    });
    out.details.gravity = Some(GravityDetails::of(problem));
    Ok(out)
}

impl GravityDetails {
    /// The priors of `problem` and their check (`[G6]`).
    pub fn of(problem: &GravityProblem) -> Self {
        let priors = problem.priors();
        GravityDetails {
            num_with_prior: priors.num_known(),
            num_images: priors.len(),
            kind: if priors.is_full() { "full" } else { "mixed" }.into(),
            world_down: priors.world_down().into(),
            check: problem.check_conventions(),
        }
    }

    /// What the priors' check says that a user must hear (`[G6]`): a convention that fits far
    /// better (`gravity_convention`), priors that disagree with the relative rotations by more
    /// than 5 degrees in median (`gravity_inconsistent`), most priors pointing up the image
    /// (`gravity_points_up`).
    pub fn warnings(&self) -> Vec<Warning> {
        let Some(c) = &self.check else {
            return Vec::new();
        };
        let mut out = Vec::new();
        let disagree = format!(
            "the gravity priors disagree with the relative rotations: R_ij g_i and g_j are a \
             median {:.2} degrees apart (90th percentile {:.2}) over {} edges",
            c.median_deg, c.p90_deg, c.edges_checked
        );
        match &c.better_convention {
            Some((name, median)) => out.push(Warning::new(
                "gravity_convention",
                format!(
                    "{disagree}; with {name} they agree to {median:.2} degrees: were they \
                     written in that convention? (rotavg reads g_i in the camera frame of \
                     R_ij R_i = R_j, pointing down)"
                ),
            )),
            None if c.median_deg > 5.0 => out.push(Warning::new(
                "gravity_inconsistent",
                format!(
                    "{disagree}: check that each g_i is the down direction in camera i's frame"
                ),
            )),
            None => {}
        }
        if c.pointing_up_fraction > 0.5 {
            out.push(Warning::new(
                "gravity_points_up",
                format!(
                    "{:.0} % of the priors point up the image (-y in OpenCV / COLMAP camera \
                     axes): for upright cameras these are up vectors, or vectors written with \
                     OpenGL camera axes (y up, z backward); negating them (or y and z) gives \
                     the right frame",
                    100.0 * c.pointing_up_fraction
                ),
            ));
        }
        out
    }
}

impl fmt::Display for GravityDetails {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let w = self.world_down;
        write!(
            f,
            "gravity: {} of {} images with a prior, held as constraints ({}), world down \
             ({}, {}, {})",
            self.num_with_prior,
            self.num_images,
            if self.kind == "full" {
                "full: the SO(2) certificate [G3] applies"
            } else {
                "mixed: bounded by the view graph alone [G7]"
            },
            w[0],
            w[1],
            w[2]
        )?;
        if let Some(c) = &self.check {
            write!(
                f,
                "; R_ij g_i vs g_j over {} edges: median {:.3} deg, 90th percentile {:.3} deg",
                c.edges_checked, c.median_deg, c.p90_deg
            )?;
        }
        Ok(())
    }
}
