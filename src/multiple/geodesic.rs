//! Geodesic L2 multiple rotation averaging by Lie-algebraic averaging (Govindu), and the
//! reweighted iteration shared with the robust losses (`paper-notes/multiple.md`, `[M8]`,
//! `[M9]`).
//!
//! Each iteration linearises `r_e(w) = log(exp(-hat w_j) R_j^T R_ij R_i exp(hat w_i))` as
//! `r_e + w_i - w_j` and solves the weighted least-squares problem
//! `min sum_e (w_e psi_e / 2) |r_e + w_i - w_j|^2` (node 0 fixed): the normal matrix is the
//! weighted graph Laplacian (n-1 square, scalar, same for the 3 axes). Its sparsity pattern and
//! symbolic Cholesky are built once; for the geodesic loss (`psi = 2`) the numeric factor is
//! also computed only once. A backtracking safeguard halves the step until the cost decreases.
//!
//! Anisotropic measurements (`paper-notes/anisotropic.md` `[A10]`): the loss applies to the
//! Mahalanobis angle `theta_H = sqrt(e^T H e / wbar)` of `e = log(R_ij^T R_j R_i^T)`, which moves
//! as `e + G (w_j - w_i)`, `G = J_r^{-1}(e) R_i`; the step solves the (reweighted) Gauss-Newton
//! system with 3x3 blocks `psi G^T H G` (refactorised at every iteration: the blocks turn with
//! the estimate) against the exact gradient, so the iteration stops at a true stationary point.

use crate::error::Result;
use crate::linalg::linear_solver::{LinearSolver, SolverKind};
use crate::multiple::MultipleProblem;
use crate::multiple::chordal::{grad_norm as norm, grounded_pattern, root_fixed_steps};
use crate::multiple::robust::{Eval, evaluate};
use crate::multiple::solve::{IRLS_DECREASE_WINDOW, MultipleSettings, MultipleSolution};
use crate::objective::Loss;
use crate::so3::{Rotation, exp};
use crate::termination::{SolverReport, Termination};
use faer::Mat;
use nalgebra::Matrix3;

/// The scalar Laplacian systems of the reweighted (robust) Lie-algebraic iterations are
/// factorised directly when the factor has at most this many values (~40 MB); geodesic L2,
/// whose weights are constant, factorises once up to
/// [`LAPLACIAN_PRECONDITIONER_VALUES`](crate::multiple::chordal::LAPLACIAN_PRECONDITIONER_VALUES).
pub const SCALAR_DIRECT_VALUES: usize = 5_000_000;

/// Geodesic L2 (`sum w theta^2`) from `init`.
pub(crate) fn solve_geodesic(
    problem: &MultipleProblem,
    init: Vec<Rotation>,
    settings: &MultipleSettings,
    solver_kind: Option<SolverKind>,
) -> Result<MultipleSolution> {
    lie_algebraic(
        problem,
        init,
        settings,
        "lie-algebraic",
        settings.max_iterations,
        solver_kind,
    )
}

/// The (reweighted) Lie-algebraic iteration for the problem's objective `[M8]`, `[M9]`.
pub(crate) fn lie_algebraic(
    problem: &MultipleProblem,
    init: Vec<Rotation>,
    settings: &MultipleSettings,
    name: &str,
    max_iterations: usize,
    solver_kind: Option<SolverKind>,
) -> Result<MultipleSolution> {
    let start = std::time::Instant::now();
    let objective = problem.objective();
    let eps = settings.l1_epsilon;
    let n = problem.num_rotations();
    let total_weight: f64 = problem.edges().iter().map(|e| e.weight).sum();
    let tol = settings.gradient_tolerance;
    let mut r = init;
    let mut ev = evaluate(problem, &r, eps);
    let init_cost = ev.cost;
    let measure = "relative gradient norm ||grad|| / sum(w)";
    let finish = |r: Vec<Rotation>, ev: &Eval, iterations: usize, termination| {
        Ok(MultipleSolution {
            chordal_cost: problem.chordal_cost(&r),
            rotations: r,
            cost: ev.cost,
            gradient_norm: norm(&ev.grad),
            objective,
            report: SolverReport {
                name: name.into(),
                iterations,
                termination,
                seconds: start.elapsed().as_secs_f64(),
            },
            init_cost,
            residuals: None,
            linear_algebra: None,
        })
    };
    let converged = |g: f64| Termination::Converged {
        measure: measure.into(),
        value: g / total_weight,
        threshold: tol,
    };
    if norm(&ev.grad) / total_weight <= tol || n < 2 {
        let g = norm(&ev.grad);
        return finish(r, &ev, 0, converged(g));
    }
    let var = |i: usize| if i == 0 { None } else { Some(i - 1) };
    // isotropic: one scalar Laplacian for the three axes; anisotropic: 3x3 blocks [A10]
    let anisotropic = problem.is_anisotropic();
    let pattern = grounded_pattern(problem, if anisotropic { 3 } else { 1 });
    let slots: Vec<usize> = problem
        .edges()
        .iter()
        .map(|e| match (var(e.i), var(e.j)) {
            (Some(p), Some(q)) => pattern.slot(p, q),
            _ => 0,
        })
        .collect();
    // The system is scalar (one row per node): a sparse Cholesky is cheap far beyond the fill
    // budget of the 3 x 3 block systems, and it is refactorised at every reweighting, where
    // PCG to 1e-10 would cost hundreds of products ([M8], measured on 1DSfM Madrid: 23784
    // edges on 394 nodes, 67 ms per IRLS iteration with PCG).
    // With constant weights (geodesic L2) the one factorisation serves every iteration, so it
    // is used up to the Laplacian preconditioner's limit ([M6b]); reweighted losses refactorise
    // at every iteration and keep the smaller limit.
    let constant_weights = objective.loss == Loss::L2 && !anisotropic;
    let limit = if constant_weights {
        crate::multiple::chordal::LAPLACIAN_PRECONDITIONER_VALUES
    } else {
        SCALAR_DIRECT_VALUES
    };
    let solver = match solver_kind {
        Some(SolverKind::Direct) => LinearSolver::new(&pattern, true)?,
        _ => LinearSolver::direct_up_to(&pattern, limit)?,
    };
    let mut factor = None;
    let mut val = vec![0.0; pattern.nnz()];
    let mut iterations = 0;
    // costs of the last IRLS_DECREASE_WINDOW + 1 iterates, oldest first
    let mut recent = std::collections::VecDeque::with_capacity(IRLS_DECREASE_WINDOW + 1);
    recent.push_back(ev.cost);
    loop {
        if iterations >= max_iterations {
            let g = norm(&ev.grad);
            return finish(
                r,
                &ev,
                iterations,
                Termination::IterationLimit {
                    iterations,
                    value: g / total_weight,
                    threshold: tol,
                },
            );
        }
        iterations += 1;
        crate::progress::emit(|| crate::progress::Event::Iteration {
            phase: crate::progress::Phase::Solve,
            iteration: iterations,
            cost: ev.cost,
            measure: norm(&ev.grad) / total_weight,
        });
        if factor.is_none() || !constant_weights {
            // weighted Laplacian with edge weights w_e psi_e, node 0 removed [M8]
            val.iter_mut().for_each(|v| *v = 0.0);
            for (k, (e, &slot)) in problem.edges().iter().zip(&slots).enumerate() {
                let one = match anisotropic {
                    true => ev.blocks[k],
                    false => Matrix3::from_element(e.weight * ev.psi[k]),
                };
                let (vi, vj) = (var(e.i), var(e.j));
                if let Some(p) = vi {
                    pattern.add(&mut val, p, p, 0, &one);
                }
                if let Some(q) = vj {
                    pattern.add(&mut val, q, q, 0, &one);
                }
                if let (Some(p), Some(q)) = (vi, vj) {
                    pattern.add(&mut val, q, p, slot, &(-one));
                }
            }
            match solver.factor(&pattern, &val) {
                Some(l) => factor = Some(l),
                None => {
                    return finish(
                        r,
                        &ev,
                        iterations,
                        Termination::NumericalFailure {
                            reason: "weighted Laplacian not positive definite".into(),
                        },
                    );
                }
            }
        }
        let llt = factor.as_ref().expect("factor set above");
        let mut rhs = match anisotropic {
            true => Mat::<f64>::from_fn(3 * (n - 1), 1, |k, _| -ev.grad[k / 3 + 1][k % 3]),
            false => Mat::<f64>::from_fn(n - 1, 3, |p, a| -ev.grad[p + 1][a]),
        };
        if llt.solve(&mut rhs, 1e-10, 5000).is_none() {
            return finish(
                r,
                &ev,
                iterations,
                Termination::NumericalFailure {
                    reason: "weighted Laplacian not positive definite (CG)".into(),
                },
            );
        }
        let step = match anisotropic {
            true => root_fixed_steps(n, |i, a| rhs[(3 * i + a, 0)]),
            false => root_fixed_steps(n, |i, a| rhs[(i, a)]),
        };
        let max_step = step.iter().map(|s| s.norm()).fold(0.0, f64::max);
        if !max_step.is_finite() {
            return finish(
                r,
                &ev,
                iterations,
                Termination::NumericalFailure {
                    reason: "non-finite step".into(),
                },
            );
        }
        // backtracking: halve until the cost does not increase (up to 30 halvings)
        let mut t = 1.0;
        let mut accepted = None;
        for _ in 0..30 {
            let cand: Vec<Rotation> = r
                .iter()
                .zip(&step)
                .map(|(ri, s)| ri * exp(&(s * t)))
                .collect();
            let cev = evaluate(problem, &cand, eps);
            if cev.cost <= ev.cost {
                accepted = Some((cand, cev));
                break;
            }
            t *= 0.5;
        }
        let Some((cand, cev)) = accepted else {
            let g = norm(&ev.grad);
            return finish(
                r,
                &ev,
                iterations,
                Termination::Stalled {
                    value: g / total_weight,
                    threshold: tol,
                },
            );
        };
        r = cand;
        ev = cev;
        if t < 1.0 {
            // the weights changed along a shortened step: refactor next time
            factor = None;
        }
        let g = norm(&ev.grad);
        if g / total_weight <= tol {
            return finish(r, &ev, iterations, converged(g));
        }
        recent.push_back(ev.cost);
        if objective.loss == Loss::L1 && recent.len() > IRLS_DECREASE_WINDOW {
            let oldest = recent.pop_front().unwrap_or(ev.cost);
            let decrease = (oldest - ev.cost) / ev.cost.abs().max(f64::MIN_POSITIVE);
            if decrease <= settings.irls_decrease_tolerance {
                return finish(
                    r,
                    &ev,
                    iterations,
                    Termination::Converged {
                        measure: format!(
                            "relative cost decrease over the last {IRLS_DECREASE_WINDOW} iterations"
                        ),
                        value: decrease,
                        threshold: settings.irls_decrease_tolerance,
                    },
                );
            }
        }
        if max_step * t < settings.step_tolerance {
            return finish(
                r,
                &ev,
                iterations,
                Termination::Converged {
                    measure: "max step angle (rad)".into(),
                    value: max_step * t,
                    threshold: settings.step_tolerance,
                },
            );
        }
    }
}
