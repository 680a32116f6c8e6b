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
use crate::linalg::block_pattern::BlockPattern;
use crate::linalg::linear_solver::{Factor, LinearSolver, SolverKind};
use crate::multiple::MultipleProblem;
use crate::multiple::chordal::{grad_norm as norm, grounded_pattern, root_fixed_steps};
use crate::multiple::robust::{Eval, evaluate};
use crate::multiple::solve::{IRLS_DECREASE_WINDOW, MultipleSettings, MultipleSolution};
use crate::objective::Loss;
use crate::so3::{Rotation, exp};
use crate::termination::{SolverReport, Termination};
use faer::Mat;
use nalgebra::{Matrix3, Vector3};
use std::collections::VecDeque;

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
    let mut r = init;
    let mut ev = evaluate(problem, &r, settings.l1_epsilon);
    let init_cost = ev.cost;
    let solution = |r: Vec<Rotation>, ev: &Eval, iterations, termination| MultipleSolution {
        chordal_cost: problem.chordal_cost(&r),
        rotations: r,
        cost: ev.cost,
        gradient_norm: norm(&ev.grad),
        objective: problem.objective(),
        report: SolverReport {
            name: name.into(),
            iterations,
            termination,
            seconds: start.elapsed().as_secs_f64(),
        },
        init_cost,
        residuals: None,
        linear_algebra: None,
    };
    let total_weight: f64 = problem.edges().iter().map(|e| e.weight).sum();
    let g = norm(&ev.grad);
    if g / total_weight <= settings.gradient_tolerance || problem.num_rotations() < 2 {
        return Ok(solution(r, &ev, 0, converged(g, total_weight, settings)));
    }
    let irls = Reweighted::new(problem, settings, solver_kind)?;
    let (iterations, termination) = irls.run(&mut r, &mut ev, max_iterations);
    Ok(solution(r, &ev, iterations, termination))
}

/// The gradient test passed: `||grad|| / sum(w) <= gradient_tolerance`.
fn converged(g: f64, total_weight: f64, settings: &MultipleSettings) -> Termination {
    Termination::Converged {
        measure: "relative gradient norm ||grad|| / sum(w)".into(),
        value: g / total_weight,
        threshold: settings.gradient_tolerance,
    }
}

/// The node index of variable block `i - 1` (node 0 is fixed: `None`).
fn var(i: usize) -> Option<usize> {
    i.checked_sub(1)
}

/// The weighted least-squares steps of [`lie_algebraic`] `[M8]`, `[M9]`, `[A10]`: the grounded
/// pattern of the (scalar or 3x3-block) weighted Laplacian and its linear solver.
struct Reweighted<'a> {
    problem: &'a MultipleProblem,
    settings: &'a MultipleSettings,
    total_weight: f64,
    /// isotropic: one scalar Laplacian for the three axes; anisotropic: 3x3 blocks [A10]
    anisotropic: bool,
    /// Geodesic L2 (isotropic): the weights never change, one factorisation serves every step.
    constant_weights: bool,
    pattern: BlockPattern,
    /// The pattern slot of each edge (0 for edges at node 0).
    slots: Vec<usize>,
    solver: LinearSolver,
}

impl<'a> Reweighted<'a> {
    fn new(
        problem: &'a MultipleProblem,
        settings: &'a MultipleSettings,
        solver_kind: Option<SolverKind>,
    ) -> Result<Self> {
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
        // The system is scalar (one row per node): a sparse Cholesky is cheap far beyond the
        // fill budget of the 3 x 3 block systems, and it is refactorised at every reweighting,
        // where PCG to 1e-10 would cost hundreds of products ([M8], measured on 1DSfM Madrid:
        // 23784 edges on 394 nodes, 67 ms per IRLS iteration with PCG).
        // With constant weights (geodesic L2) the one factorisation serves every iteration, so
        // it is used up to the Laplacian preconditioner's limit ([M6b]); reweighted losses
        // refactorise at every iteration and keep the smaller limit.
        let constant_weights = problem.objective().loss == Loss::L2 && !anisotropic;
        let limit = if constant_weights {
            crate::multiple::chordal::LAPLACIAN_PRECONDITIONER_VALUES
        } else {
            SCALAR_DIRECT_VALUES
        };
        let solver = match solver_kind {
            Some(SolverKind::Direct) => LinearSolver::new(&pattern, true)?,
            // 3x3 blocks of an expander-like graph: its choice stands ([M6]); a direct factor
            // nearly dense in 3n costs 27x the scalar one at every reweighting (1000 nodes, 4000
            // edges: 30 ms per IRLS iteration against 7 ms for block-Jacobi PCG)
            Some(SolverKind::Jacobi) if anisotropic => LinearSolver::new(&pattern, false)?,
            _ => LinearSolver::direct_up_to(&pattern, limit)?,
        };
        Ok(Reweighted {
            problem,
            settings,
            total_weight: problem.edges().iter().map(|e| e.weight).sum(),
            anisotropic,
            constant_weights,
            pattern,
            slots,
            solver,
        })
    }

    /// Iterate from `r` (evaluated: `ev`) until a stopping test, `max_iterations` or a failure;
    /// `r` and `ev` end at the last accepted iterate. Returns the iterations and why it stopped.
    fn run(
        &self,
        r: &mut Vec<Rotation>,
        ev: &mut Eval,
        max_iterations: usize,
    ) -> (usize, Termination) {
        let mut factor = None;
        let mut val = vec![0.0; self.pattern.nnz()];
        // costs of the last IRLS_DECREASE_WINDOW + 1 iterates, oldest first
        let mut recent = VecDeque::with_capacity(IRLS_DECREASE_WINDOW + 1);
        recent.push_back(ev.cost);
        let failure = |reason: &str| Termination::NumericalFailure {
            reason: reason.into(),
        };
        let mut iterations = 0;
        let deadline = self.settings.deadline();
        loop {
            let g = norm(&ev.grad);
            let measure = (g / self.total_weight, self.settings.gradient_tolerance);
            let limit =
                crate::deadline::limit_reached(iterations, max_iterations, deadline, measure);
            if let Some(limit) = limit {
                return (iterations, limit);
            }
            iterations += 1;
            crate::progress::emit(|| crate::progress::Event::Iteration {
                phase: crate::progress::Phase::Solve,
                iteration: iterations,
                cost: ev.cost,
                measure: g / self.total_weight,
            });
            if factor.is_none() || !self.constant_weights {
                self.laplacian_values(ev, &mut val);
                match self.solver.factor(&self.pattern, &val) {
                    Some(l) => factor = Some(l),
                    None => {
                        return (
                            iterations,
                            failure("weighted Laplacian not positive definite"),
                        );
                    }
                }
            }
            let Some(llt) = factor.as_ref() else {
                return (iterations, failure("no factorisation"));
            };
            let Some(step) = self.step(llt, ev) else {
                return (
                    iterations,
                    failure("weighted Laplacian not positive definite (CG)"),
                );
            };
            let max_step = step.iter().map(|s| s.norm()).fold(0.0, f64::max);
            if !max_step.is_finite() {
                return (iterations, failure("non-finite step"));
            }
            let Some((cand, cev, t)) = self.backtrack(r, ev, &step) else {
                let (value, threshold) = measure;
                return (iterations, Termination::Stalled { value, threshold });
            };
            *r = cand;
            *ev = cev;
            if t < 1.0 {
                // the weights changed along a shortened step: refactor next time
                factor = None;
            }
            if let Some(stop) = self.stop(ev, &mut recent, max_step * t) {
                return (iterations, stop);
            }
        }
    }

    /// The weighted Laplacian with edge weights `w_e psi_e` (anisotropic: the blocks
    /// `psi G^T H G`), node 0 removed `[M8]`, `[A10]`, into `val`.
    fn laplacian_values(&self, ev: &Eval, val: &mut [f64]) {
        val.iter_mut().for_each(|v| *v = 0.0);
        for (k, (e, &slot)) in self.problem.edges().iter().zip(&self.slots).enumerate() {
            let one = match self.anisotropic {
                true => ev.blocks[k],
                false => Matrix3::from_element(e.weight * ev.psi[k]),
            };
            let (vi, vj) = (var(e.i), var(e.j));
            if let Some(p) = vi {
                self.pattern.add(val, p, p, 0, &one);
            }
            if let Some(q) = vj {
                self.pattern.add(val, q, q, 0, &one);
            }
            if let (Some(p), Some(q)) = (vi, vj) {
                self.pattern.add(val, q, p, slot, &(-one));
            }
        }
    }

    /// The per-node step solving the weighted least-squares system against `-grad`; `None`
    /// when the (PCG) solve meets non-positive curvature.
    fn step(&self, llt: &Factor<'_>, ev: &Eval) -> Option<Vec<Vector3<f64>>> {
        let n = self.problem.num_rotations();
        let mut rhs = match self.anisotropic {
            true => Mat::<f64>::from_fn(3 * (n - 1), 1, |k, _| -ev.grad[k / 3 + 1][k % 3]),
            false => Mat::<f64>::from_fn(n - 1, 3, |p, a| -ev.grad[p + 1][a]),
        };
        llt.solve(&mut rhs, 1e-10, 5000)?;
        Some(match self.anisotropic {
            true => root_fixed_steps(n, |i, a| rhs[(3 * i + a, 0)]),
            false => root_fixed_steps(n, |i, a| rhs[(i, a)]),
        })
    }

    /// Backtracking along `R_i exp(t step_i)`: for L1 first at the over-relaxed `t =`
    /// [`MultipleSettings::l1_overrelaxation`], then `t` halved from 1 until the cost does not
    /// increase (up to 30 halvings). Returns the point, its evaluation and `t`.
    fn backtrack(
        &self,
        r: &[Rotation],
        ev: &Eval,
        step: &[Vector3<f64>],
    ) -> Option<(Vec<Rotation>, Eval, f64)> {
        let over = match self.problem.objective().loss {
            Loss::L1 => self.settings.l1_overrelaxation,
            _ => 1.0,
        };
        let mut t = over;
        for _ in 0..30 {
            let cand: Vec<Rotation> = r
                .iter()
                .zip(step)
                .map(|(ri, s)| ri * exp(&(s * t)))
                .collect();
            let cev = evaluate(self.problem, &cand, self.settings.l1_epsilon);
            if cev.cost <= ev.cost {
                return Some((cand, cev, t));
            }
            t = if t > 1.0 { 1.0 } else { 0.5 * t };
        }
        None
    }

    /// The stopping tests after an accepted step of angle `step` (at most, over the nodes):
    /// the gradient, for L1 the relative cost decrease over the last
    /// [`IRLS_DECREASE_WINDOW`] iterations (`recent`, updated here), the step angle.
    fn stop(&self, ev: &Eval, recent: &mut VecDeque<f64>, step: f64) -> Option<Termination> {
        let settings = self.settings;
        let g = norm(&ev.grad);
        if g / self.total_weight <= settings.gradient_tolerance {
            return Some(converged(g, self.total_weight, settings));
        }
        recent.push_back(ev.cost);
        if self.problem.objective().loss == Loss::L1 && recent.len() > IRLS_DECREASE_WINDOW {
            let oldest = recent.pop_front().unwrap_or(ev.cost);
            let decrease = (oldest - ev.cost) / ev.cost.abs().max(f64::MIN_POSITIVE);
            if decrease <= settings.irls_decrease_tolerance {
                return Some(Termination::Converged {
                    measure: format!(
                        "relative cost decrease over the last {IRLS_DECREASE_WINDOW} iterations"
                    ),
                    value: decrease,
                    threshold: settings.irls_decrease_tolerance,
                });
            }
        }
        (step < settings.step_tolerance).then(|| Termination::Converged {
            measure: "max step angle (rad)".into(),
            value: step,
            threshold: settings.step_tolerance,
        })
    }
}
