//! Robust losses on the residual angle (L1, Huber, Cauchy), minimised by iteratively
//! reweighted Lie-algebraic least squares (`paper-notes/multiple.md`, `[M7]`, `[M9]`).

use crate::error::Result;
use crate::linalg::linear_solver::SolverKind;
use crate::multiple::MultipleProblem;
use crate::multiple::chordal::chordal_gradient;
use crate::multiple::geodesic::lie_algebraic;
use crate::multiple::solve::{MultipleSettings, MultipleSolution};
use crate::objective::{Loss, Objective};
use crate::so3::{Rotation, log};
use nalgebra::Vector3;

/// `(rho(theta), psi(theta))` for a residual angle `theta` (radians) under `objective` `[M7]`,
/// where the edge cost is `w rho(theta)` ([`Objective::term`]) and `psi = rho'(theta) / theta`
/// is the IRLS weight factor. For L1, `psi = 1 / max(theta, l1_epsilon)` (the smoothing). For
/// chordal L2, `rho = 8 sin^2(theta / 2)` and `psi = 4 sin(theta) / theta`; for the geodesic
/// metric `psi = 2 psi_irls(theta)` with [`Objective::irls_weight`].
pub fn objective_terms(objective: &Objective, theta: f64, l1_epsilon: f64) -> (f64, f64) {
    if objective.is_chordal_l2() {
        let s = (0.5 * theta).sin();
        let psi = if theta < 1e-8 {
            4.0
        } else {
            4.0 * theta.sin() / theta
        };
        return (8.0 * s * s, psi);
    }
    let psi = match objective.loss {
        Loss::L1 => 1.0 / theta.max(l1_epsilon),
        _ => 2.0 * objective.irls_weight(theta, l1_epsilon),
    };
    (objective.term(theta), psi)
}

/// Cost `sum_e w_e rho(theta_e)` under the problem's objective and its gradient in the right-perturbation chart
/// `R_i exp(hat w_i)` `[M8]`: with `r_e = log(R_j^T R_ij R_i)` (so `theta_e = |r_e|`),
/// `grad_i += w_e psi(theta_e) r_e`, `grad_j -= w_e psi(theta_e) r_e`. For
/// chordal L2 this is [`chordal_gradient`]. For L1 the gradient is that of the smoothed
/// cost (the cost returned is the exact `sum w theta`). Panics if `rotations.len() != n`.
///
/// ```
/// use rotavg::multiple::{objective_cost_gradient, synthetic::SyntheticGraph};
/// use rotavg::objective::{Loss, Objective};
/// use rotavg::Metric;
/// let (p, gt) = SyntheticGraph { noise_sigma: 0.0, ..Default::default() }.generate();
/// let p = p.with_objective(Objective::new(Metric::Geodesic, Loss::L2)).unwrap();
/// let (cost, grad) = objective_cost_gradient(&p, &gt, 1e-6);
/// assert!(cost < 1e-20 && grad.iter().all(|g| g.norm() < 1e-12));
/// ```
pub fn objective_cost_gradient(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    l1_epsilon: f64,
) -> (f64, Vec<Vector3<f64>>) {
    let objective = problem.objective();
    if objective.is_chordal_l2() {
        return chordal_gradient(problem, rotations);
    }
    assert_eq!(rotations.len(), problem.num_rotations());
    let mut grad = vec![Vector3::zeros(); rotations.len()];
    let mut cost = 0.0;
    for e in problem.edges() {
        let r = edge_log(e, rotations);
        let (rho, psi) = objective_terms(&objective, r.norm(), l1_epsilon);
        cost += e.weight * rho;
        let g = r * (e.weight * psi);
        grad[e.i] += g;
        grad[e.j] -= g;
    }
    (cost, grad)
}

/// `r_e = log(R_j^T R_ij R_i)`.
pub(crate) fn edge_log(e: &crate::multiple::Edge, rotations: &[Rotation]) -> Vector3<f64> {
    log(&(rotations[e.j].inverse() * e.rotation * rotations[e.i]))
}

/// IRLS for L1 / Huber / Cauchy from `init` `[M9]`. At most `10 * max_iterations` iterations.
pub(crate) fn solve_robust(
    problem: &MultipleProblem,
    init: Vec<Rotation>,
    settings: &MultipleSettings,
    solver_kind: Option<SolverKind>,
) -> Result<MultipleSolution> {
    let objective = problem.objective();
    let name = match objective.loss {
        _ if objective.is_chordal_l2() => "irls-chordal",
        Loss::L1 => "irls-l1",
        Loss::Huber { .. } => "irls-huber",
        Loss::Cauchy { .. } => "irls-cauchy",
        Loss::L2 => "lie-algebraic",
    };
    lie_algebraic(
        problem,
        init,
        settings,
        name,
        10 * settings.max_iterations,
        solver_kind,
    )
}
