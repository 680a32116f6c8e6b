//! Chordal L2 averaging with gravity priors (contract section 5, "Rigs and gravity";
//! `paper-notes/gravity.md`): [`crate::multiple::gravity::solve_gravity`], then
//! [`crate::certify::certify_gravity`], in the one pipeline shape. The priors' agreement with
//! the relative rotations ([`GravityProblem::check_conventions`]) is part of the report.

use super::inlier_graph::ViewGraphProblem;
use super::{AverageSettings, Averaged, MultipleEstimate, PipelineProblem};
use crate::certify::{
    Certification, CertifiedProblem, CertifiedProblemKind, CertifyMode, CertifySettings,
    certify_gravity, gravity_problem_kind,
};
use crate::error::Result;
use crate::multiple::gravity::{GravityCheck, GravityProblem, solve_gravity};
use crate::multiple::{MultipleProblem, MultipleSettings, MultipleSolution};
use crate::objective::Objective;
use crate::so3::Rotation;
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
    /// The soft priors' weight (`--gravity-weight`, `[G10]`); absent: held as constraints.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub weight: Option<f64>,
    /// Soft priors with their own relative weight (the priors file's fourth number,
    /// [`crate::multiple::gravity::GravityPriors::with_scales`]): each weighs `weight` times it; 0 or absent: all
    /// `weight`.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub scaled: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// Averaging with gravity priors held as constraints (or soft, `[G10]`), certified, in the
/// shape of [`crate::pipeline::average_multiple`]: least squares ([`solve_gravity`], then
/// [`certify_gravity`]: the SO(2) dual certificate for full gravity, the tilted surrogate's
/// `[G12]` otherwise) with its outlier diagnosis; under the rule `auto` (`robust_on_outliers`) the
/// robust loss when the least-squares residuals show outliers; a robust loss solved by
/// reweighted constrained solves, then the chordal L2 problem with the priors held on its inlier
/// graph refined and certified (`details.inlier_graph`, kind
/// [`CertifiedProblemKind::ChordalL2GravityInliers`]). The priors and their agreement with the
/// view graph are in `details.gravity`; the least-squares certificate names its problem
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
    let mut out = super::multiple::average_view_graph(problem, settings)?;
    let graph = problem.problem();
    out.certificate = out.certificate.map(|c| {
        c.for_problem(CertifiedProblem {
            kind: gravity_problem_kind(problem, false),
            num_nodes: graph.num_rotations(),
            total_nodes: graph.num_rotations(),
            num_edges: graph.num_edges(),
            total_edges: graph.num_edges(),
        })
    });
    out.details.gravity = Some(GravityDetails::of(problem));
    Ok(out)
}

impl ViewGraphProblem for GravityProblem {
    fn inliers_kind(&self) -> CertifiedProblemKind {
        gravity_problem_kind(self, true)
    }
    fn certified_cost(&self, rotations: &[Rotation]) -> f64 {
        self.problem().chordal_cost(rotations) + self.prior_cost(rotations)
    }
    fn graph(&self) -> &MultipleProblem {
        self.problem()
    }
    fn with_objective(&self, objective: Objective) -> Result<Self> {
        GravityProblem::new(
            self.problem().clone().with_objective(objective)?,
            self.priors().clone(),
        )
    }
    fn average_all(
        &self,
        settings: &AverageSettings<MultipleSettings>,
    ) -> Result<MultipleEstimate> {
        average_with_gravity(self, settings)
    }
    fn restricted(&self, sub: MultipleProblem, nodes: &[usize]) -> Result<Self> {
        GravityProblem::new(sub, self.priors().restricted(nodes)?)
    }
    /// The refinement turned about the world's down axis only (the one gauge the priors leave)
    /// to best match the robust estimate; the other nodes keep their robust rotations.
    fn place(&self, nodes: &[usize], refined: &[Rotation], robust: &[Rotation]) -> Vec<Rotation> {
        let w = self.priors().world_frame();
        let mut m = nalgebra::Matrix3::zeros();
        for (k, &v) in nodes.iter().enumerate() {
            m += (refined[k] * w).matrix().transpose() * (robust[v] * w).matrix();
        }
        // the turn G = W Rz(a) W^T maximising tr(G^T sum R_k^T R_v)
        let a = crate::multiple::gravity::yaw(&m);
        let g = w * Rotation::from_axis_angle(&nalgebra::Vector3::z_axis(), a) * w.inverse();
        let mut estimate = robust.to_vec();
        for (k, &v) in nodes.iter().enumerate() {
            estimate[v] = refined[k] * g;
        }
        estimate
    }
}

/// The median disagreement of held priors with the edges' information, in standard deviations
/// ([`crate::multiple::gravity::GravityCheck::information_sigma`]), above which
/// `gravity_imprecise` warns: exact priors give about 1.2 (`chi` with 2 degrees of freedom).
pub const IMPRECISE_SIGMA: f64 = 3.0;

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
            weight: priors.weight(),
            scaled: if priors.weight().is_some() {
                priors.num_scaled()
            } else {
                0
            },
        }
    }

    /// What the priors' check says that a user must hear (`[G6]`): a convention that fits far
    /// better (`gravity_convention`), priors that disagree with the relative rotations by more
    /// than 5 degrees in median (`gravity_inconsistent`), most priors pointing up the image
    /// (`gravity_points_up`), held priors far less precise than the edges' information
    /// (`gravity_imprecise`).
    pub fn warnings(&self) -> Vec<Warning> {
        let Some(c) = &self.check else {
            return Vec::new();
        };
        let mut out = Vec::new();
        if let (Some(sigma), None) = (c.information_sigma, self.weight)
            && sigma > IMPRECISE_SIGMA
        {
            out.push(Warning::new(
                "gravity_imprecise",
                format!(
                    "held gravity priors disagree with the relative rotations by a median \
                     {sigma:.1} standard deviations of the edges' information (about 1.2 for \
                     exact priors): held, they pull the estimate against far more confident \
                     edges; give their weight with --gravity-weight (soft priors) unless they \
                     are exact"
                ),
            ));
        }
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
        let how = match (self.weight, self.kind.as_str()) {
            (Some(weight), _) => format!("as soft terms of weight {weight} [G10]"),
            (None, "full") => {
                "held as constraints (full: the SO(2) certificate [G3] applies)".into()
            }
            (None, _) => {
                "held as constraints (mixed: certified by the tilted surrogate [G12])".into()
            }
        };
        write!(
            f,
            "gravity: {} of {} images with a prior, {how}, world down ({}, {}, {})",
            self.num_with_prior, self.num_images, w[0], w[1], w[2]
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
