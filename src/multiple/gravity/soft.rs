//! Gravity priors as soft terms (`paper-notes/gravity.md` `[G10]`): a prior of weight `w` adds
//! `2 w ||R_i world_down - g_i||^2` to the cost. In the standard convention (`world_down = e_3`)
//! that term is exactly an anisotropic edge from a **world node** `R_n` to image `i`, with the
//! measurement `F_i` (`F_i e_3 = g_i`) and the information `H = w diag(1, 1, 0)`: its chordal
//! matrix `M = tr(H)/2 I - H = w e_3 e_3^T`, so the edge costs
//! `4 w (1 - g_i^T R_i R_n^T e_3)`, the prior's term at `R_n = I`. The augmented view graph is an
//! ordinary (anisotropic) multiple-averaging problem: solved by the chordal Newton-LM, certified
//! by the multiple-averaging ladder, and its minimum is the soft problem's (the world node is
//! the gauge's representative: any minimiser turned by `R_n^T` has `R_n = I`).

use super::GravityProblem;
use crate::error::Result;
use crate::multiple::anisotropic::Information;
use crate::multiple::chordal::solve_chordal;
use crate::multiple::problem::{Edge, MultipleProblem};
use crate::multiple::robust::objective_cost_gradient;
use crate::multiple::solve::{MultipleSettings, MultipleSolution};
use crate::so3::Rotation;
use nalgebra::{Matrix3, Vector3};

/// The tilted surrogate's weight over the largest node strength (`[G12]`): stiff enough that
/// the held problem's second-order condition carries over to the surrogate, small enough that
/// the world node's rounding margin stays below the tolerance (a factor 10 left relative gaps
/// of 3e-6 at 10^4 cameras, 2 certified them).
pub const SURROGATE_STIFFNESS: f64 = 2.0;

/// The light surrogate's weight is at least this fraction of the stiff one's node strength
/// (`[G12]` "Two weights"): a positive weight where the gradient vanishes.
pub const LIGHT_STRENGTH_FRACTION: f64 = 1e-3;

/// How stiff the tilted surrogate's priors are (`[G12]` "Two weights"); both keep the tilt
/// `|v_i| <= 0.5`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stiffness {
    /// `w = `[`SURROGATE_STIFFNESS`]` max(|gradient| / 4, `[`LIGHT_STRENGTH_FRACTION`]` x node
    /// strength)`: the smallest weight of that tilt, whose world node's rows (the rounding
    /// margin of its verification) are smallest.
    Light,
    /// `w = `[`SURROGATE_STIFFNESS`]` max(node strength, |gradient| / 4)`: the surrogate's
    /// curvature dominated by the priors'.
    Stiff,
}

impl Stiffness {
    /// `"light"` or `"stiff"`.
    pub fn name(self) -> &'static str {
        match self {
            Stiffness::Light => "light",
            Stiffness::Stiff => "stiff",
        }
    }

    /// The weight for the largest node strength `strength` and largest gradient norm
    /// `gradient`.
    pub fn weight(self, strength: f64, gradient: f64) -> f64 {
        let floor = match self {
            Stiffness::Light => LIGHT_STRENGTH_FRACTION * strength,
            Stiffness::Stiff => strength,
        };
        SURROGATE_STIFFNESS * floor.max(gradient / 4.0)
    }
}

impl GravityProblem {
    /// The soft problem as one view graph, standard convention: `graph` (this problem's view
    /// graph or a reweighting of it, `n` nodes) with its information matrices (`w I` for scalar
    /// weights), and node `n`, the world, joined to every image with a prior by the edge of
    /// `[G10]`. Errors: priors that are not soft.
    pub(crate) fn soft_augmented(&self, graph: &MultipleProblem) -> Result<MultipleProblem> {
        let (mut edges, mut info) = (graph.edges().to_vec(), own_information(graph)?);
        let (prior_edges, prior_info) = self.prior_edges()?;
        edges.extend(prior_edges);
        info.extend(prior_info);
        MultipleProblem::new(graph.num_rotations() + 1, edges)?.with_information(info)
    }

    /// The prior terms alone as a view graph of `n + 1` nodes (standard convention): the world
    /// node's edges of [`Self::soft_augmented`].
    fn prior_problem(&self) -> Result<MultipleProblem> {
        let (edges, info) = self.prior_edges()?;
        MultipleProblem::new(self.problem.num_rotations() + 1, edges)?.with_information(info)
    }

    /// The world node's edges and their information (`[G10]`), each of its image's prior
    /// weight.
    fn prior_edges(&self) -> Result<(Vec<Edge>, Vec<Information>)> {
        self.soft_weight()?;
        let world = self.problem.num_rotations();
        let (mut edges, mut info) = (Vec::new(), Vec::new());
        for i in 0..world {
            let (Some(rotation), Some(weight)) = (self.frame(i), self.priors.prior_weight(i))
            else {
                continue;
            };
            let h = Vector3::new(weight, weight, 0.0);
            info.push(Information::new(Matrix3::from_diagonal(&h))?);
            edges.push(Edge {
                i: world,
                j: i,
                rotation,
                weight,
            });
        }
        Ok((edges, info))
    }

    /// The soft priors' weight, or an error for hard ones.
    fn soft_weight(&self) -> Result<f64> {
        self.priors
            .weight()
            .ok_or_else(|| crate::Error::InvalidSettings {
                name: "gravity".into(),
                reason: "the priors are hard constraints, not soft terms".into(),
            })
    }

    /// The held priors' **tilted soft surrogate** at `rotations` (file convention; `[G12]`):
    /// the same view graph with soft priors of weight `w` whose directions `g_i'` are turned
    /// so that `rotations` is a critical point of the soft problem (`R_i^T g_i' = h_i` with
    /// `e_3 x h_i = v_i`, `v_i` the view graph's chordal gradient at image `i` without its
    /// heading part, over `4 w`), and `C >= sum 2 w ||g_i - g_i'||^2`, rounded up. On every
    /// point of the held problem (`R_i world_down = g_i`) the surrogate's cost is the view
    /// graph's plus exactly that sum, so `min held >= min surrogate - C` whatever `g'` is.
    /// `w` by `stiffness` ([`Stiffness::weight`]): `|v_i| <= 0.5`. Errors: priors that are
    /// already soft, a count of rotations that differs from the graph's.
    pub fn tilted_surrogate(
        &self,
        rotations: &[Rotation],
        stiffness: Stiffness,
    ) -> Result<(GravityProblem, f64)> {
        if self.priors.weight().is_some() {
            return Err(crate::Error::InvalidSettings {
                name: "gravity".into(),
                reason: "the tilted surrogate is of held priors, these are soft".into(),
            });
        }
        self.problem.check_estimate(rotations)?;
        let standard = self.to_standard(rotations);
        let (_, grad) = crate::multiple::chordal_gradient(&self.problem, &standard);
        let mut strength = vec![0.0f64; standard.len()];
        for e in self.problem.edges() {
            strength[e.i] += e.weight;
            strength[e.j] += e.weight;
        }
        let most = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
        let grad_max = most(&grad.iter().map(|g| g.norm()).collect::<Vec<_>>());
        let w = stiffness.weight(most(&strength), grad_max);
        let e3 = Vector3::z();
        let dirs = (0..standard.len())
            .map(|i| {
                self.priors.direction(i).map(|_| {
                    let v = (grad[i] - e3 * grad[i].z) / (4.0 * w);
                    let h = e3 * (1.0 - v.norm_squared()).sqrt() + v.cross(&e3);
                    (standard[i] * h).into()
                })
            })
            .collect();
        let priors = super::GravityPriors::new(dirs)?
            .with_world_down(self.priors.world_down().into())?
            .with_weight(w)?;
        let mut sum = 0.0;
        let mut terms = 0usize;
        for i in 0..standard.len() {
            if let (Some(g), Some(t)) = (self.priors.direction(i), priors.direction(i)) {
                sum += 2.0 * w * (g - t).norm_squared();
                terms += 1;
            }
        }
        // every term is a rounded product of rounded squares: relative error <= 8u each, and
        // the sum of `terms` nonnegative terms adds gamma(terms)
        let upper = sum * (1.0 + crate::linalg::cholesky::gamma(terms + 8));
        Ok((GravityProblem::new(self.problem.clone(), priors)?, upper))
    }

    /// The soft priors' cost `sum 2 w_i ||R_i world_down - g_i||^2` at `rotations` (file
    /// convention); 0 for hard priors (which an estimate of the problem satisfies).
    pub fn prior_cost(&self, rotations: &[Rotation]) -> f64 {
        let down = self.priors.world_down();
        rotations
            .iter()
            .enumerate()
            .filter_map(|(i, r)| {
                let (g, w) = (self.priors.direction(i)?, self.priors.prior_weight(i)?);
                Some(2.0 * w * (r * down - g).norm_squared())
            })
            .sum()
    }

    /// `rotations` (file convention) as a point of [`Self::soft_augmented`]: standard
    /// convention, the world node at `I`.
    pub(crate) fn soft_point(&self, rotations: &[Rotation]) -> Vec<Rotation> {
        let mut point = self.to_standard(rotations);
        point.push(Rotation::identity());
        point
    }

    /// A point of [`Self::soft_augmented`] back to `n` rotations (standard convention): turned
    /// by `R_n^T` (the gauge that puts the world node at `I`), the world node dropped.
    pub(crate) fn soft_images(&self, mut point: Vec<Rotation>) -> Vec<Rotation> {
        let turn = point
            .pop()
            .map(|w| w.inverse())
            .unwrap_or_else(Rotation::identity);
        point.iter().map(|r| r * turn).collect()
    }

    /// A point of [`Self::soft_augmented`] as an estimate of the problem: its images turned so
    /// that the world node is at `I`, in the gravity problem's gauge, file convention.
    pub(crate) fn soft_estimate(&self, point: Vec<Rotation>) -> Vec<Rotation> {
        let mut standard = self.soft_images(point);
        super::fix_gravity_gauge(&mut standard);
        self.out_of_standard(&standard)
    }

    /// The gradient norm of the soft problem (the view graph's objective plus the prior terms)
    /// at `rotations` (standard convention).
    pub(crate) fn soft_gradient_norm(&self, rotations: &[Rotation], l1_epsilon: f64) -> f64 {
        let (_, mut grad) = objective_cost_gradient(&self.problem, rotations, l1_epsilon);
        if let Ok(priors) = self.prior_problem() {
            let mut point = rotations.to_vec();
            point.push(Rotation::identity());
            let (_, prior_grad) = objective_cost_gradient(&priors, &point, l1_epsilon);
            for (g, p) in grad.iter_mut().zip(prior_grad) {
                *g += p;
            }
        }
        grad.iter().map(|g| g.norm_squared()).sum::<f64>().sqrt()
    }
}

/// The information matrices of `graph`: its own, or `w I` for scalar weights.
fn own_information(graph: &MultipleProblem) -> Result<Vec<Information>> {
    match graph.information() {
        Some(info) => Ok(info.to_vec()),
        None => graph
            .edges()
            .iter()
            .map(|e| Information::new(Matrix3::identity() * e.weight))
            .collect(),
    }
}

/// The chordal Newton-LM on the soft problem of `problem` whose view graph is `graph`, from
/// `init` (standard convention, `n` rotations); the result in the standard convention, gauge
/// not fixed, its costs those of the augmented problem (view graph plus priors).
pub(super) fn solve_soft(
    problem: &GravityProblem,
    graph: &MultipleProblem,
    init: Vec<Rotation>,
    settings: &MultipleSettings,
) -> Result<MultipleSolution> {
    let augmented = problem.soft_augmented(graph)?;
    let mut init = init;
    init.push(Rotation::identity());
    let mut solution = solve_chordal(&augmented, init, settings, None)?;
    solution.rotations = problem.soft_images(solution.rotations);
    Ok(solution)
}
