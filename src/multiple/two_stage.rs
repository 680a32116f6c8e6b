//! Robust averaging of anisotropic measurements in two stages (`paper-notes/anisotropic.md`
//! `[A14]`): a confidently wrong pair (a twisted pair, repeated structure) carries large
//! information, and the robust cost of the Mahalanobis angle, weighted by `tr(H)/3`, lets it
//! lead. So the robust loss is first solved with unit weights and no information (where every
//! pair's pull is bounded alike), the edges whose Mahalanobis angle at that estimate exceeds the
//! inlier threshold are set aside, and the robust loss with the information of the edges kept is
//! solved from the first estimate.

use crate::error::Result;
use crate::linalg::linear_solver::SolverKind;
use crate::multiple::problem::place_component;
use crate::multiple::robust::{edge_residuals, inlier_threshold_deg, solve_robust};
use crate::multiple::solve::{MultipleSettings, MultipleSolution, solve_multiple};
use crate::multiple::{Edge, MultipleProblem};

/// The two-stage solve of `problem`, an anisotropic problem under a robust loss (L1, Huber,
/// Cauchy) with no given start `[A14]`:
///
/// 1. the same loss on the same edges with **unit weights and no information**
///    ([`solve_multiple`]: its spectral start, its L1 start for Huber and Cauchy);
/// 2. the edges whose Mahalanobis angle at that estimate is within the inlier threshold
///    ([`inlier_threshold_deg`]), on their largest connected component, solved under the
///    problem's loss with their information (IRLS from the first estimate).
///
/// Nodes outside that component keep the first estimate's rotations (aligned). The solution's
/// `cost` and `chordal_cost` are the problem's on every edge (set by the caller's exit); `gradient_norm` and the report's
/// termination are those of the second stage (of the cost on the edges it kept); iterations
/// and time are both stages'.
pub(crate) fn solve_two_stage(
    problem: &MultipleProblem,
    settings: &MultipleSettings,
    kind: Option<SolverKind>,
) -> Result<MultipleSolution> {
    let objective = problem.objective();
    let start = std::time::Instant::now();
    let first = solve_multiple(&unit_weights(problem)?, settings)?;
    let threshold = inlier_threshold_deg(&objective, settings).unwrap_or(180.0);
    let kept = edge_residuals(problem, &first.rotations, threshold).inlier;
    let start_cost = problem.cost(&first.rotations);
    if !kept.contains(&true) {
        return Ok(restated(problem, first, start_cost));
    }
    let (sub, nodes) = problem
        .edge_subset(&kept)?
        .with_objective(objective)?
        .largest_component();
    let init = nodes.iter().map(|&v| first.rotations[v]).collect();
    let second = solve_robust(&sub, init, &settings.remaining(start), kind)?;
    let rotations = place_component(&nodes, &second.rotations, &first.rotations);
    let mut out = MultipleSolution {
        rotations,
        gradient_norm: second.gradient_norm,
        report: second.report,
        ..first
    };
    out.report.name = format!("two-stage {}", out.report.name);
    out.report.iterations += first.report.iterations;
    Ok(restated(problem, out, start_cost))
}

/// The same edges with weight 1 and no information, under the same objective.
pub(crate) fn unit_weights(problem: &MultipleProblem) -> Result<MultipleProblem> {
    let edges = problem
        .edges()
        .iter()
        .map(|e| Edge {
            weight: 1.0,
            ..e.clone()
        })
        .collect();
    MultipleProblem::new(problem.num_rotations(), edges)?.with_objective(problem.objective())
}

/// `solution` as a solution of `problem`: its objective, and as its initial cost `start_cost`,
/// the problem's cost at the first stage's estimate (where the second starts). Its `cost` and
/// `chordal_cost` are restated on every edge by `solve_multiple`'s exit (`on_so3`).
fn restated(
    problem: &MultipleProblem,
    mut solution: MultipleSolution,
    start_cost: f64,
) -> MultipleSolution {
    solution.objective = problem.objective();
    solution.init_cost = start_cost;
    solution
}
