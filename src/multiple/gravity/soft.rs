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

    /// The world node's edges and their information (`[G10]`).
    fn prior_edges(&self) -> Result<(Vec<Edge>, Vec<Information>)> {
        let weight = self.soft_weight()?;
        let world = self.problem.num_rotations();
        let h = Information::new(Matrix3::from_diagonal(&Vector3::new(weight, weight, 0.0)))?;
        let edges: Vec<Edge> = (0..world)
            .filter_map(|i| {
                self.frame(i).map(|f| Edge {
                    i: world,
                    j: i,
                    rotation: f,
                    weight,
                })
            })
            .collect();
        let info = vec![h; edges.len()];
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

    /// The soft priors' cost `sum 2 w ||R_i world_down - g_i||^2` at `rotations` (file
    /// convention); 0 for hard priors (which an estimate of the problem satisfies).
    pub fn prior_cost(&self, rotations: &[Rotation]) -> f64 {
        let Some(w) = self.priors.weight() else {
            return 0.0;
        };
        self.prior_pairs(rotations)
            .map(|(down, g)| 2.0 * w * (down - g).norm_squared())
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
