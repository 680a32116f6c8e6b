//! Chordal L2 multiple rotation averaging: Riemannian Newton with Levenberg-Marquardt damping on
//! `SO(3)^n`, sparse (`paper-notes/multiple.md`, `[M3]`, `[M6]`).
//!
//! Chart: right perturbations `R_i <- R_i exp(hat w_i)`. Node 0 is held fixed during the
//! iteration (the cost is gauge invariant, `[M1]`), so the Newton system is `3(n-1)` square,
//! block sparse with the sparsity of the view graph. Its pattern and the symbolic sparse
//! Cholesky factorisation (faer, AMD ordering) are computed once; each iteration only
//! reassembles the values and refactorises numerically. No dense `3n x 3n` matrix is formed.

use crate::error::Result;
use crate::linalg::block_pattern::BlockPattern;
use crate::linalg::linear_solver::LinearSolver;
use crate::multiple::MultipleProblem;
use crate::multiple::solve::{MultipleSettings, MultipleSolution};
use crate::objective::Objective;
use crate::so3::{Rotation, exp, vee};
use crate::termination::{SolverReport, Termination};
use faer::Mat;
use nalgebra::{Matrix3, Vector3};

/// Chordal L2 cost and its Riemannian gradient `[M3]`.
///
/// The gradient is taken in the right-perturbation chart `R_i exp(hat w_i)`: entry `i` is
/// `d/dw_i f(R_0 exp(hat w_0), ..., R_{n-1} exp(hat w_{n-1}))` at `w = 0`. Per edge
/// `e = (i, j)` with `A_e = R_j^T R_ij R_i`: `f_e = w_e ||I - A_e||_F^2`,
/// `grad_i += 4 w_e vee(A_e)`, `grad_j -= 4 w_e vee(A_e)`, where `vee(A)` is the axial vector of
/// the skew part `(A - A^T) / 2`. Panics if `rotations.len() != n` (check with
/// [`MultipleProblem::check_estimate`]).
///
/// ```
/// use rotavg::multiple::{chordal_gradient, synthetic::SyntheticGraph};
/// let (p, gt) = SyntheticGraph { noise_sigma: 0.0, ..Default::default() }.generate();
/// let (cost, grad) = chordal_gradient(&p, &gt);
/// assert!(cost < 1e-20 && grad.iter().all(|g| g.norm() < 1e-12));
/// ```
pub fn chordal_gradient(
    problem: &MultipleProblem,
    rotations: &[Rotation],
) -> (f64, Vec<Vector3<f64>>) {
    assert_eq!(rotations.len(), problem.num_rotations());
    let mut grad = vec![Vector3::zeros(); rotations.len()];
    let mut cost = 0.0;
    for e in problem.edges() {
        let m = e.rotation.matrix() * rotations[e.i].matrix();
        let rj = rotations[e.j].matrix();
        cost += e.weight * (rj - m).norm_squared();
        let a = rj.transpose() * m;
        let g = vee(&a) * (4.0 * e.weight);
        grad[e.i] += g;
        grad[e.j] -= g;
    }
    (cost, grad)
}

/// Fill-in budget of the direct solver: a sparse Cholesky is used when the scalar (one entry
/// per node) symbolic factor has at most this many entries per node; otherwise (expander-like
/// graphs, e.g. random view graphs, whose Cholesky factors are nearly dense) preconditioned
/// conjugate gradients are used (`[M6]`, "linear solver").
pub const DIRECT_FILL_PER_NODE: usize = 60;

/// `true` if a sparse Cholesky of the graph Laplacian pattern is cheap: not expander-like by
/// the BFS pre-filter below, and the scalar symbolic
/// factor (AMD ordering) has at most [`DIRECT_FILL_PER_NODE`] entries per node.
pub(crate) fn prefers_direct(problem: &MultipleProblem) -> Result<bool> {
    let n = problem.num_rotations();
    // Cheap pre-filter, O(m): every BFS level is a vertex separator; if the widest level from
    // node 0 holds more than a quarter of the nodes the graph is expander-like and its factor
    // nearly dense, so skip the (then expensive) symbolic analysis and use PCG, which is always
    // applicable ([M6]).
    if n > 1000 && max_bfs_level_width(problem) * 4 > n {
        return Ok(false);
    }
    let scalar = BlockPattern::new(n, 1, problem.edges().iter().map(|e| (e.i, e.j)));
    Ok(scalar.factor_len()? <= DIRECT_FILL_PER_NODE * n.max(1))
}

/// Per-node steps of a Newton-type system solved with node 0 fixed: zero for node 0, and
/// `entry(i - 1, a)` for component `a` of node `i >= 1`.
pub(crate) fn root_fixed_steps(n: usize, entry: impl Fn(usize, usize) -> f64) -> Vec<Vector3<f64>> {
    (0..n)
        .map(|i| match i {
            0 => Vector3::zeros(),
            _ => Vector3::new(entry(i - 1, 0), entry(i - 1, 1), entry(i - 1, 2)),
        })
        .collect()
}

/// The linear solver of the Newton systems on `pattern`: direct when `direct` says so, or, for
/// `None`, when [`prefers_direct`] does.
pub(crate) fn linear_solver(
    problem: &MultipleProblem,
    pattern: &BlockPattern,
    direct: Option<bool>,
) -> Result<LinearSolver> {
    let direct = match direct {
        Some(d) => d,
        None => prefers_direct(problem)?,
    };
    LinearSolver::new(pattern, direct)
}

/// The largest number of nodes at one BFS distance from node 0.
fn max_bfs_level_width(problem: &MultipleProblem) -> usize {
    let n = problem.num_rotations();
    let mut adj_ptr = vec![0usize; n + 1];
    for e in problem.edges() {
        adj_ptr[e.i + 1] += 1;
        adj_ptr[e.j + 1] += 1;
    }
    for k in 0..n {
        adj_ptr[k + 1] += adj_ptr[k];
    }
    let mut fill = adj_ptr.clone();
    let mut adj = vec![0usize; adj_ptr[n]];
    for e in problem.edges() {
        adj[fill[e.i]] = e.j;
        fill[e.i] += 1;
        adj[fill[e.j]] = e.i;
        fill[e.j] += 1;
    }
    let mut seen = vec![false; n];
    let mut level = vec![0usize];
    seen[0] = true;
    let mut widest = 1;
    while !level.is_empty() {
        let mut next = Vec::new();
        for &u in &level {
            for &v in &adj[adj_ptr[u]..adj_ptr[u + 1]] {
                if !seen[v] {
                    seen[v] = true;
                    next.push(v);
                }
            }
        }
        widest = widest.max(next.len());
        level = next;
    }
    widest
}

/// Per-edge data for the Newton system: variable blocks (node 0 fixed -> `None`) and slot.
struct EdgeSlots {
    vi: Option<usize>,
    vj: Option<usize>,
    slot: usize,
}

fn edge_slots(problem: &MultipleProblem, pattern: &BlockPattern) -> Vec<EdgeSlots> {
    let var = |i: usize| if i == 0 { None } else { Some(i - 1) };
    problem
        .edges()
        .iter()
        .map(|e| {
            let (vi, vj) = (var(e.i), var(e.j));
            let slot = match (vi, vj) {
                (Some(p), Some(q)) => pattern.slot(p, q),
                _ => 0,
            };
            EdgeSlots { vi, vj, slot }
        })
        .collect()
}

/// Assemble the Hessian of the chordal cost in the chart `[M6]` (exact second derivative of
/// the pullback, node 0 removed) into `val` (zeroed first).
fn assemble_hessian(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    pattern: &BlockPattern,
    slots: &[EdgeSlots],
    val: &mut [f64],
) {
    val.iter_mut().for_each(|v| *v = 0.0);
    for (e, s) in problem.edges().iter().zip(slots) {
        let a = rotations[e.j].matrix().transpose() * e.rotation.matrix() * rotations[e.i].matrix();
        let t = a.trace();
        let w2 = 2.0 * e.weight;
        // [M6]: H_ii = H_jj = 2w (tr(A) I - sym(A)), H_ji = 2w (A^T - tr(A) I)
        let diag = (Matrix3::identity() * t - (a + a.transpose()) * 0.5) * w2;
        let off = (a.transpose() - Matrix3::identity() * t) * w2;
        if let Some(p) = s.vi {
            pattern.add(val, p, p, 0, &diag);
        }
        if let Some(q) = s.vj {
            pattern.add(val, q, q, 0, &diag);
        }
        if let (Some(p), Some(q)) = (s.vi, s.vj) {
            // block row j (q), block column i (p)
            pattern.add(val, q, p, s.slot, &off);
        }
    }
}

/// The Euclidean norm of a stacked gradient (one tangent vector per node).
pub(crate) fn grad_norm(g: &[Vector3<f64>]) -> f64 {
    g.iter().map(|v| v.norm_squared()).sum::<f64>().sqrt()
}

/// Minimise the chordal cost from `init` (Riemannian Newton + Levenberg-Marquardt, `[M6]`).
/// The gauge is not fixed here (node 0 keeps its initial value); [`super::solve_multiple`]
/// fixes it.
pub(crate) fn solve_chordal(
    problem: &MultipleProblem,
    init: Vec<Rotation>,
    settings: &MultipleSettings,
    direct: Option<bool>,
) -> Result<MultipleSolution> {
    let start = std::time::Instant::now();
    let n = problem.num_rotations();
    let total_weight: f64 = problem.edges().iter().map(|e| e.weight).sum();
    let tol = settings.gradient_tolerance;
    let mut r = init;
    let (mut cost, mut grad) = chordal_gradient(problem, &r);
    let init_cost = cost;
    let finish = |r: Vec<Rotation>, cost: f64, g: f64, iterations: usize, termination| {
        Ok(MultipleSolution {
            rotations: r,
            cost,
            chordal_cost: cost,
            gradient_norm: g,
            objective: Objective::CHORDAL_L2,
            report: SolverReport {
                name: "riemannian-newton-lm".into(),
                iterations,
                termination,
                seconds: start.elapsed().as_secs_f64(),
            },
            init_cost,
            residuals: None,
        })
    };
    let measure = "relative gradient norm ||grad|| / sum(w)";
    let mut gn = grad_norm(&grad);
    if gn == 0.0 || n < 2 {
        return finish(
            r,
            cost,
            gn,
            0,
            Termination::Converged {
                measure: measure.into(),
                value: gn / total_weight,
                threshold: tol,
            },
        );
    }
    let pattern = BlockPattern::new(
        n - 1,
        3,
        problem
            .edges()
            .iter()
            .filter(|e| e.i != 0 && e.j != 0)
            .map(|e| (e.i - 1, e.j - 1)),
    );
    let slots = edge_slots(problem, &pattern);
    let solver = linear_solver(problem, &pattern, direct)?;
    let mut hval = vec![0.0; pattern.nnz()];
    let mut val = vec![0.0; pattern.nnz()];
    let mut mu = 1e-6; // damping relative to the mean Hessian diagonal
    let mut iterations = 0;
    let mut need_hessian = true;
    let mut mean_diag = 0.0;
    loop {
        if iterations >= settings.max_iterations {
            return finish(
                r,
                cost,
                gn,
                iterations,
                Termination::IterationLimit {
                    iterations,
                    value: gn / total_weight,
                    threshold: tol,
                },
            );
        }
        iterations += 1;
        crate::progress::emit(|| crate::progress::Event::Iteration {
            phase: crate::progress::Phase::Solve,
            iteration: iterations,
            cost,
            measure: gn / total_weight,
        });
        if need_hessian {
            assemble_hessian(problem, &r, &pattern, &slots, &mut hval);
            let d = pattern.diagonal(&hval);
            mean_diag = d.iter().map(|x| x.abs()).sum::<f64>() / d.len() as f64;
            need_hessian = false;
        }
        // rhs = -grad (variables 1..n)
        let mut rhs = Mat::<f64>::zeros(3 * (n - 1), 1);
        for i in 1..n {
            for a in 0..3 {
                rhs[(3 * (i - 1) + a, 0)] = -grad[i][a];
            }
        }
        // factorise H + lambda I, increasing lambda until positive definite; inexact Newton
        // tolerance for PCG: eta = min(1e-2, sqrt(relative gradient)) ([M6])
        let eta = (gn / total_weight).sqrt().clamp(1e-12, 1e-2);
        let lambda = loop {
            let lambda = mu * mean_diag.max(f64::MIN_POSITIVE);
            val.copy_from_slice(&hval);
            pattern.add_diagonal(&mut val, lambda);
            let mut x = rhs.clone();
            let ok = match solver.factor(&pattern, &val) {
                Some(f) => f.solve(&mut x, eta, 2000),
                None => false,
            };
            if ok {
                rhs = x;
                break lambda;
            }
            mu *= 10.0;
            if mu > 1e16 {
                return finish(
                    r,
                    cost,
                    gn,
                    iterations,
                    Termination::NumericalFailure {
                        reason: "damped Newton system not positive definite".into(),
                    },
                );
            }
        };
        let step = root_fixed_steps(n, |i, a| rhs[(3 * i + a, 0)]);
        let g_dot_s: f64 = grad.iter().zip(&step).map(|(g, s)| g.dot(s)).sum();
        let s2: f64 = step.iter().map(|s| s.norm_squared()).sum();
        let max_step = step.iter().map(|s| s.norm()).fold(0.0, f64::max);
        // predicted decrease of the quadratic model: -(g.s + s^T H s / 2)
        let flat: Vec<f64> = (0..3 * (n - 1)).map(|k| rhs[(k, 0)]).collect();
        let mut hs = vec![0.0; flat.len()];
        pattern.sym_mul_flat(&hval, &flat, &mut hs);
        let shs: f64 = flat.iter().zip(&hs).map(|(a, b)| a * b).sum();
        let predicted = -(g_dot_s + 0.5 * shs);
        let _ = (lambda, s2);
        // converged: the gradient is small and the model cannot decrease the cost materially
        let decrease_limit = settings.decrease_tolerance * cost.abs() + 1e-30 * total_weight;
        if gn / total_weight <= tol && predicted <= decrease_limit {
            return finish(
                r,
                cost,
                gn,
                iterations,
                Termination::Converged {
                    measure:
                        "predicted Newton decrease / cost (with ||grad|| / sum(w) <= its tolerance)"
                            .into(),
                    value: predicted / cost.abs().max(f64::MIN_POSITIVE),
                    threshold: settings.decrease_tolerance,
                },
            );
        }
        if !max_step.is_finite() {
            return finish(
                r,
                cost,
                gn,
                iterations,
                Termination::NumericalFailure {
                    reason: "non-finite Newton step".into(),
                },
            );
        }
        let cand: Vec<Rotation> = r.iter().zip(&step).map(|(ri, s)| ri * exp(s)).collect();
        let (c_cost, c_grad) = chordal_gradient(problem, &cand);
        let c_gn = grad_norm(&c_grad);
        let actual = cost - c_cost;
        let rho = if predicted > 0.0 {
            actual / predicted
        } else {
            -1.0
        };
        // Near convergence the cost decrease drowns in rounding (~1e-16 f): then accept when the
        // gradient decreases instead ([M6]).
        let at_noise_floor = predicted <= 1e-12 * cost.max(f64::MIN_POSITIVE);
        let accept = rho > 1e-4 || (at_noise_floor && c_gn < gn);
        if accept {
            r = cand;
            cost = c_cost;
            grad = c_grad;
            gn = c_gn;
            need_hessian = true;
            if rho > 0.75 || at_noise_floor {
                mu = (mu / 4.0).max(1e-14);
            } else if rho < 0.25 {
                mu *= 4.0;
            }
            if max_step < settings.step_tolerance {
                return finish(
                    r,
                    cost,
                    gn,
                    iterations,
                    Termination::Converged {
                        measure: "max step angle (rad)".into(),
                        value: max_step,
                        threshold: settings.step_tolerance,
                    },
                );
            }
        } else {
            mu *= 8.0;
            if mu > 1e16 || (at_noise_floor && max_step < settings.step_tolerance) {
                return finish(
                    r,
                    cost,
                    gn,
                    iterations,
                    Termination::Stalled {
                        value: gn / total_weight,
                        threshold: tol,
                    },
                );
            }
        }
    }
}
