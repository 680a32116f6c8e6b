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
use crate::linalg::block_pattern::SymbolicFactor;
use crate::linalg::linear_solver::{LinearSolver, ScalarLaplacian, SolverKind};
use crate::multiple::MultipleProblem;
use crate::multiple::anisotropic::edge_b;
use crate::multiple::solve::LinearAlgebraCounts;
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
/// the skew part `(A - A^T) / 2`. Anisotropic problems ([`MultipleProblem::with_information`]):
/// `f_e = 4 tr M - 4 tr B_e`, `grad_i -= 8 vee(B_e)`, `grad_j += 8 vee(B_e)` with
/// `B_e = R_i^T M R_ij^T R_j` (`paper-notes/anisotropic.md` `[A4]`). Panics if `rotations.len() != n` (check with
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
    if let Some(info) = problem.information() {
        // [A4]: f_e = 4 tr M - 4 tr B, grad_i = -8 vee(B), grad_j = 8 vee(B)
        for (e, h) in problem.edges().iter().zip(info) {
            let (ri, rj) = (rotations[e.i].matrix(), rotations[e.j].matrix());
            let b = edge_b(h, e.rotation.matrix(), ri, rj);
            cost += 4.0 * (h.chordal_matrix().trace() - b.trace());
            let g = vee(&b) * 8.0;
            grad[e.i] -= g;
            grad[e.j] += g;
        }
        return (cost, grad);
    }
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

/// Fill-in budget of the direct solver: a sparse Cholesky of the 3x3-block Newton systems is
/// used when the scalar (one entry per node) symbolic factor has at most this many entries per
/// node (`[M6]`, "linear solver").
pub const DIRECT_FILL_PER_NODE: usize = 60;

/// Largest scalar Cholesky factor (stored values, AMD ordering) of the graph Laplacian used as
/// the preconditioner of conjugate gradients when the block factor is over
/// [`DIRECT_FILL_PER_NODE`] (`[M6b]`): 1.5e8 values, about 1.2 GB of values (plus indices).
/// Graphs whose scalar factor is larger (expander-like graphs, 3-D grids of 10^6 nodes) use
/// block-Jacobi PCG.
pub const LAPLACIAN_PRECONDITIONER_VALUES: usize = 150_000_000;

/// From this many nodes on, graphs whose factor stays sparse are solved with the Laplacian
/// preconditioner rather than the block Cholesky (`[M6b]`): measured on a 10^5-node chain,
/// Newton-LM from the spanning tree took 0.5-0.8 s against 6.5 s for the block Cholesky
/// path with the spectral start.
pub const LAPLACIAN_FROM_NODES: usize = 20_000;

/// The linear solver of the Newton systems, chosen once from the graph (`[M6]`, `[M6b]`):
/// expander-like graphs by the BFS pre-filter below -> block-Jacobi PCG (well conditioned,
/// every factor nearly dense); a scalar symbolic factor (AMD) of at most
/// [`DIRECT_FILL_PER_NODE`] entries per node, below [`LAPLACIAN_FROM_NODES`] nodes -> sparse
/// Cholesky; on more than 1000 nodes, up to
/// [`LAPLACIAN_PRECONDITIONER_VALUES`] -> PCG with the factorised scalar Laplacian as
/// preconditioner; otherwise block-Jacobi PCG (small graphs that fill are dense-ish random
/// graphs, which keep the spectral start).
pub(crate) fn choose_solver(problem: &MultipleProblem) -> Result<SolverChoice> {
    let n = problem.num_rotations();
    // Cheap pre-filter, O(m): every BFS level is a vertex separator; if the widest level from
    // node 0 holds more than a quarter of the nodes the graph is expander-like and its factor
    // nearly dense, so skip the (then expensive) symbolic analysis ([M6]).
    if n > 1000 && max_bfs_level_width(problem) * 4 > n {
        return Ok(SolverKind::Jacobi.into());
    }
    // the scalar Laplacian grounded at node 0: the pattern of the preconditioner [M6b], whose
    // symbolic analysis is kept for it (the AMD ordering of a 10^6-node graph costs about 1 s)
    let edges = laplacian_edges(problem, true, 1.0);
    let scalar = ScalarLaplacian::pattern(n.saturating_sub(1), &edges);
    let symbolic = scalar.symbolic_llt()?;
    let len = symbolic.len_val() + 1;
    let kind = if len <= DIRECT_FILL_PER_NODE * n.max(1) && n < LAPLACIAN_FROM_NODES {
        SolverKind::Direct
    } else if len <= LAPLACIAN_PRECONDITIONER_VALUES && n > 1000 {
        SolverKind::Laplacian
    } else {
        SolverKind::Jacobi
    };
    Ok(SolverChoice {
        kind,
        grounded_scalar: (kind == SolverKind::Laplacian).then_some(symbolic),
        symbolic_analyses: 1,
    })
}

/// The linear solver [`choose_solver`] picked for a graph, with the symbolic analysis of the
/// grounded scalar Laplacian when the Laplacian preconditioner will use it `[M6b]`.
#[derive(Clone)]
pub(crate) struct SolverChoice {
    /// The solver.
    pub(crate) kind: SolverKind,
    /// The symbolic analysis of the scalar Laplacian grounded at node 0
    /// ([`ScalarLaplacian::pattern`] of [`laplacian_edges`] with `grounded`).
    pub(crate) grounded_scalar: Option<SymbolicFactor>,
    /// Symbolic analyses the choice took (0 or 1).
    pub(crate) symbolic_analyses: usize,
}

impl From<SolverKind> for SolverChoice {
    fn from(kind: SolverKind) -> Self {
        SolverChoice {
            kind,
            grounded_scalar: None,
            symbolic_analyses: 0,
        }
    }
}

/// The edges `(p, q, scale w_e)` of the scalar Laplacian on nodes `1..n` (node 0 grounded:
/// `None`) or on all nodes.
fn laplacian_edges(
    problem: &MultipleProblem,
    grounded: bool,
    scale: f64,
) -> Vec<(Option<usize>, Option<usize>, f64)> {
    let var = |i: usize| match (grounded, i) {
        (true, 0) => None,
        (true, i) => Some(i - 1),
        (false, i) => Some(i),
    };
    problem
        .edges()
        .iter()
        .map(|e| (var(e.i), var(e.j), scale * e.weight))
        .collect()
}

/// The scalar Laplacian preconditioner `[M6b]` of a system on nodes `1..n` (node 0 grounded)
/// with edge coefficients `scale * w_e`, or on all nodes (`grounded = false`) plus `shift I`,
/// in the per-node `frames`; block-Jacobi PCG if it is not numerically positive definite.
/// `symbolic`: the analysis of that pattern when known ([`SolverChoice::grounded_scalar`]).
pub(crate) fn laplacian_solver(
    problem: &MultipleProblem,
    grounded: bool,
    scale: f64,
    shift: f64,
    frames: Option<Vec<Matrix3<f64>>>,
    symbolic: Option<SymbolicFactor>,
) -> Result<LinearSolver> {
    let edges = laplacian_edges(problem, grounded, scale);
    let nblocks = problem.num_rotations() - usize::from(grounded);
    Ok(
        match ScalarLaplacian::new(nblocks, &edges, shift, frames, symbolic)? {
            Some(l) => LinearSolver::Laplacian(l),
            None => LinearSolver::Jacobi,
        },
    )
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

/// The pattern of a system with node 0 fixed (grounded; `n >= 1` nodes): nodes `1..n` are the
/// blocks `0..n-1`, of `block` rows each, joined by the edges between them (an edge at node 0
/// adds to the diagonal block of its other end only).
pub(crate) fn grounded_pattern(problem: &MultipleProblem, block: usize) -> BlockPattern {
    BlockPattern::new(
        problem.num_rotations() - 1,
        block,
        problem
            .edges()
            .iter()
            .filter(|e| e.i != 0 && e.j != 0)
            .map(|e| (e.i - 1, e.j - 1)),
    )
}

/// The linear solver of the chordal Newton systems on `pattern` (nodes `1..n`, node 0
/// grounded), as [`choose_solver`] chose (or a forced [`SolverKind`]). The Laplacian
/// preconditioner is `4 L ⊗ I_3`, the Hessian at a consistent estimate `[M6b]`.
pub(crate) fn linear_solver(
    problem: &MultipleProblem,
    pattern: &BlockPattern,
    choice: SolverChoice,
) -> Result<LinearSolver> {
    match choice.kind {
        SolverKind::Direct => LinearSolver::new(pattern, true),
        SolverKind::Jacobi => LinearSolver::new(pattern, false),
        SolverKind::Laplacian => {
            laplacian_solver(problem, true, 4.0, 0.0, None, choice.grounded_scalar)
        }
    }
}

fn max_bfs_level_width(problem: &MultipleProblem) -> usize {
    let adjacency = problem.adjacency();
    let n = problem.num_rotations();
    // a hub (a node joined to more than a quarter of the graph, as the world node of soft
    // gravity priors [G10]) is left out: eliminated last it adds one block row to the factor,
    // not fill among the others; through it every node would be two levels from node 0
    let hub = |v: usize| adjacency.neighbours(v).len() * 4 > n;
    let mut seen = vec![false; n];
    let mut level = vec![0usize];
    seen[0] = true;
    let mut widest = 1;
    while !level.is_empty() {
        let mut next = Vec::new();
        for &u in &level {
            for &(v, _) in adjacency.neighbours(u) {
                if !seen[v] && !hub(v) {
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
    let info = problem.information();
    for (k, (e, s)) in problem.edges().iter().zip(slots).enumerate() {
        let (ri, rj) = (rotations[e.i].matrix(), rotations[e.j].matrix());
        // [M6]: H_ii = H_jj = 2w (tr(A) I - sym(A)), H_ji = 2w (A^T - tr(A) I), i.e. [A4] with
        // B = (w / 2) A^T: H_ii = H_jj = 4 (tr(B) I - sym(B)), H_ji = 4 (B - tr(B) I)
        let b = match info {
            Some(info) => edge_b(&info[k], e.rotation.matrix(), ri, rj),
            None => (rj.transpose() * e.rotation.matrix() * ri).transpose() * (0.5 * e.weight),
        };
        let t = b.trace();
        let diag = (Matrix3::identity() * t - (b + b.transpose()) * 0.5) * 4.0;
        let off = (b - Matrix3::identity() * t) * 4.0;
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

/// Assemble `4 L ⊗ I_3` (node 0 removed), the chordal Hessian at a consistent estimate
/// (`A_e = I` in [`assemble_hessian`]), into `val` (zeroed first) `[M6b]`.
fn assemble_laplacian(
    problem: &MultipleProblem,
    pattern: &BlockPattern,
    slots: &[EdgeSlots],
    val: &mut [f64],
) {
    val.iter_mut().for_each(|v| *v = 0.0);
    for (e, s) in problem.edges().iter().zip(slots) {
        let c = Matrix3::identity() * (4.0 * e.weight);
        if let Some(p) = s.vi {
            pattern.add(val, p, p, 0, &c);
        }
        if let Some(q) = s.vj {
            pattern.add(val, q, q, 0, &c);
        }
        if let (Some(p), Some(q)) = (s.vi, s.vj) {
            pattern.add(val, q, p, s.slot, &(-c));
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
    solver: Option<SolverChoice>,
) -> Result<MultipleSolution> {
    solve_chordal_tilt_fixed(problem, init, settings, solver, None)
}

/// [`solve_chordal`] with the tilt of the nodes `tilt_fixed[i]` held: those only turn about
/// their own third axis, `R_i exp(t hat e_3)` (so `R_i e_3`, the gravity direction, stays,
/// `[G4]`). Node 0 is grounded, so it must be tilt-fixed whenever any node is.
pub(crate) fn solve_chordal_tilt_fixed(
    problem: &MultipleProblem,
    init: Vec<Rotation>,
    settings: &MultipleSettings,
    solver: Option<SolverChoice>,
    tilt_fixed: Option<&[bool]>,
) -> Result<MultipleSolution> {
    let start = std::time::Instant::now();
    let total_weight: f64 = problem.edges().iter().map(|e| e.weight).sum();
    let tol = settings.gradient_tolerance;
    let mut point = Point::at(problem, init, tilt_fixed);
    let init_cost = point.cost;
    let solution = |point: Point, iterations, termination, linear_algebra| MultipleSolution {
        chordal_cost: point.cost,
        cost: point.cost,
        gradient_norm: point.gn,
        rotations: point.r,
        objective: Objective::CHORDAL_L2,
        report: SolverReport {
            name: "riemannian-newton-lm".into(),
            iterations,
            termination,
            seconds: start.elapsed().as_secs_f64(),
        },
        init_cost,
        residuals: None,
        linear_algebra,
    };
    if point.gn == 0.0 || problem.num_rotations() < 2 {
        let converged = Termination::Converged {
            measure: "relative gradient norm ||grad|| / sum(w)".into(),
            value: point.gn / total_weight,
            threshold: tol,
        };
        return Ok(solution(point, 0, converged, None));
    }
    let mut lm = NewtonLm::new(problem, settings, solver)?;
    lm.tilt_fixed = tilt_fixed;
    lm.pinned = tilt_fixed.map(grounded_pins);
    let mut iterations = 0;
    let deadline = settings.deadline();
    let termination = loop {
        let measure = (point.gn / total_weight, tol);
        if let Some(limit) =
            crate::deadline::limit_reached(iterations, settings.max_iterations, deadline, measure)
        {
            break limit;
        }
        iterations += 1;
        crate::progress::emit(|| crate::progress::Event::Iteration {
            phase: crate::progress::Phase::Solve,
            iteration: iterations,
            cost: point.cost,
            measure: point.gn / total_weight,
        });
        if let Some(t) = lm.iterate(&mut point) {
            break t;
        }
    };
    Ok(solution(point, iterations, termination, Some(lm.counts)))
}

/// An iterate of the Newton-LM solve: the rotations, their chordal cost, gradient and its norm.
struct Point {
    r: Vec<Rotation>,
    cost: f64,
    grad: Vec<Vector3<f64>>,
    gn: f64,
}

impl Point {
    /// The cost and gradient at `r` ([`chordal_gradient`]), the gradient's first two
    /// components zero at the tilt-fixed nodes (the projection onto their tangent, `[G4]`).
    fn at(problem: &MultipleProblem, r: Vec<Rotation>, tilt_fixed: Option<&[bool]>) -> Self {
        let (cost, mut grad) = chordal_gradient(problem, &r);
        if let Some(fixed) = tilt_fixed {
            for (g, _) in grad.iter_mut().zip(fixed).filter(|(_, f)| **f) {
                (g.x, g.y) = (0.0, 0.0);
            }
        }
        let gn = grad_norm(&grad);
        Point { r, cost, grad, gn }
    }
}

/// The Newton-LM machinery of [`solve_chordal`] `[M6]`: the grounded block pattern and its
/// linear solver (chosen once), the Hessian at the current point, the Levenberg-Marquardt
/// damping and the work counted.
struct NewtonLm<'a> {
    problem: &'a MultipleProblem,
    settings: &'a MultipleSettings,
    total_weight: f64,
    pattern: BlockPattern,
    slots: Vec<EdgeSlots>,
    solver: LinearSolver,
    counts: LinearAlgebraCounts,
    /// The damping matrix `4 L ⊗ I_3` with the Laplacian preconditioner (`None`: the mean
    /// Hessian diagonal x I).
    damping: Option<Vec<f64>>,
    /// The Hessian at the current point, and the damped system's values.
    hval: Vec<f64>,
    val: Vec<f64>,
    need_hessian: bool,
    mean_diag: f64,
    /// The damping relative to the mean Hessian diagonal (or to `4 L ⊗ I_3`).
    mu: f64,
    /// The nodes whose tilt is held, and the rows of the grounded system held at zero for
    /// them (`[G4]`).
    tilt_fixed: Option<&'a [bool]>,
    pinned: Option<Vec<bool>>,
}

/// The pinned rows of the grounded system (nodes `1..n`, 3 rows each) for tilt-fixed nodes:
/// their first two components.
fn grounded_pins(tilt_fixed: &[bool]) -> Vec<bool> {
    tilt_fixed
        .iter()
        .skip(1)
        .flat_map(|&f| [f, f, false])
        .collect()
}

impl<'a> NewtonLm<'a> {
    fn new(
        problem: &'a MultipleProblem,
        settings: &'a MultipleSettings,
        solver: Option<SolverChoice>,
    ) -> Result<Self> {
        let pattern = grounded_pattern(problem, 3);
        let slots = edge_slots(problem, &pattern);
        let choice = match solver {
            Some(c) => c,
            None => choose_solver(problem)?,
        };
        // the choice's own analysis; the direct solver analyses the block pattern, the
        // Laplacian preconditioner reuses the choice's (or analyses its pattern) and
        // factorises once
        let symbolic_analyses = choice.symbolic_analyses
            + match choice.kind {
                SolverKind::Direct => 1,
                SolverKind::Laplacian => usize::from(choice.grounded_scalar.is_none()),
                SolverKind::Jacobi => 0,
            };
        let numeric_factorizations = usize::from(choice.kind == SolverKind::Laplacian);
        let solver = linear_solver(problem, &pattern, choice)?;
        let counts = LinearAlgebraCounts {
            solver: solver.kind().to_string(),
            symbolic_analyses,
            numeric_factorizations,
            cg_iterations: 0,
        };
        // Levenberg-Marquardt damping `lambda D` [M6]: D = mean Hessian diagonal x I, or, with
        // the Laplacian preconditioner, D = its matrix 4 L ⊗ I_3 (then the damped system stays
        // preconditioned by the one factorisation, [M6b]).
        let damping = (solver.kind() == SolverKind::Laplacian).then(|| {
            let mut d = vec![0.0; pattern.nnz()];
            assemble_laplacian(problem, &pattern, &slots, &mut d);
            d
        });
        Ok(NewtonLm {
            problem,
            settings,
            total_weight: problem.edges().iter().map(|e| e.weight).sum(),
            hval: vec![0.0; pattern.nnz()],
            val: vec![0.0; pattern.nnz()],
            pattern,
            slots,
            solver,
            counts,
            damping,
            need_hessian: true,
            mean_diag: 0.0,
            mu: 1e-6,
            tilt_fixed: None,
            pinned: None,
        })
    }

    /// One Newton-LM iteration from `p` (moved when the step is accepted); `Some` when the
    /// solve stops.
    fn iterate(&mut self, p: &mut Point) -> Option<Termination> {
        if self.need_hessian {
            assemble_hessian(
                self.problem,
                &p.r,
                &self.pattern,
                &self.slots,
                &mut self.hval,
            );
            let d = self.pattern.diagonal(&self.hval);
            self.mean_diag = d.iter().map(|x| x.abs()).sum::<f64>() / d.len() as f64;
            self.need_hessian = false;
        }
        let Some(x) = self.damped_step(p) else {
            return Some(Termination::NumericalFailure {
                reason: "damped Newton system not positive definite".into(),
            });
        };
        let step = root_fixed_steps(p.r.len(), |i, a| x[(3 * i + a, 0)]);
        let max_step = step.iter().map(|s| s.norm()).fold(0.0, f64::max);
        let predicted = self.predicted_decrease(&p.grad, &step, &x);
        // converged: the gradient is small and the model cannot decrease the cost materially
        let settings = self.settings;
        let decrease_limit = settings.decrease_tolerance * p.cost.abs() + 1e-30 * self.total_weight;
        if p.gn / self.total_weight <= settings.gradient_tolerance && predicted <= decrease_limit {
            // the cost's own rounding: the anisotropic trace form cancels, u tr(H_e) per edge
            let rounding = if self.problem.is_anisotropic() {
                64.0 * f64::EPSILON * self.total_weight
            } else {
                0.0
            };
            self.last_step(p, &step, decrease_limit + rounding);
            return Some(Termination::Converged {
                measure:
                    "predicted Newton decrease / cost (with ||grad|| / sum(w) <= its tolerance)"
                        .into(),
                value: predicted / p.cost.abs().max(f64::MIN_POSITIVE),
                threshold: settings.decrease_tolerance,
            });
        }
        if !max_step.is_finite() {
            return Some(Termination::NumericalFailure {
                reason: "non-finite Newton step".into(),
            });
        }
        self.trial(p, &step, predicted, max_step)
    }

    /// Converged: the step already solved for is taken when it lowers the gradient without
    /// raising the cost by more than `noise`: the convergence test's decrease limit (relative
    /// `1e-12`, the floor where `trial` also judges by the gradient), plus, on anisotropic
    /// problems, the rounding of their trace-form cost (`64 u sum w`: it cancels to its small
    /// value and is known only to `u tr(H_e)` per edge; the isotropic form has no cancellation).
    /// One cost and gradient evaluation, no factorisation: Newton's last step squares the stationarity residual (PCG: multiplies it
    /// by about `eta`), so the estimate is critical to the certificate's precision `[D3]`
    /// without the certificate's refinement (a 10^6-node lattice: residual 4.8e-6 before,
    /// 2.8e-9 after; its certify 52 s -> 20 s).
    fn last_step(&self, p: &mut Point, step: &[Vector3<f64>], noise: f64) {
        let cand = self.stepped(p, step);
        if cand.gn < p.gn && cand.cost <= p.cost + noise {
            *p = cand;
        }
    }

    /// The point `R_i exp(step_i)`, evaluated.
    fn stepped(&self, p: &Point, step: &[Vector3<f64>]) -> Point {
        let moved = p.r.iter().zip(step).map(|(ri, s)| ri * exp(s)).collect();
        Point::at(self.problem, moved, self.tilt_fixed)
    }

    /// The step `x` (variables of nodes `1..n`) of `(H + lambda D) x = -grad`, the damping
    /// multiplied by 10 until the system is solved (positive definite); `None` past `mu = 1e16`.
    /// Inexact Newton tolerance for PCG: `eta = min(1e-2, sqrt(relative gradient))` `[M6]`.
    fn damped_step(&mut self, p: &Point) -> Option<Mat<f64>> {
        let rhs = Mat::<f64>::from_fn(3 * (p.r.len() - 1), 1, |k, _| -p.grad[k / 3 + 1][k % 3]);
        let eta = (p.gn / self.total_weight).sqrt().clamp(1e-12, 1e-2);
        loop {
            self.val.copy_from_slice(&self.hval);
            match &self.damping {
                Some(d) => self
                    .val
                    .iter_mut()
                    .zip(d)
                    .for_each(|(v, d)| *v += self.mu * d),
                None => {
                    let lambda = self.mu * self.mean_diag.max(f64::MIN_POSITIVE);
                    self.pattern.add_diagonal(&mut self.val, lambda);
                }
            }
            if let Some(pinned) = &self.pinned {
                self.pattern.pin(&mut self.val, pinned);
            }
            let mut x = rhs.clone();
            if self.solver.kind() == SolverKind::Direct {
                self.counts.numeric_factorizations += 1;
            }
            let solved = self
                .solver
                .factor(&self.pattern, &self.val)
                .and_then(|f| f.solve(&mut x, eta, 2000));
            self.counts.cg_iterations += solved.unwrap_or(0);
            if solved.is_some() {
                if let Some(pinned) = &self.pinned {
                    // an inexact (PCG) solve leaves rounding there
                    for (k, _) in pinned.iter().enumerate().filter(|(_, p)| **p) {
                        x[(k, 0)] = 0.0;
                    }
                }
                return Some(x);
            }
            self.mu *= 10.0;
            if self.mu > 1e16 {
                return None;
            }
        }
    }

    /// The decrease `-(g.s + s^T H s / 2)` the quadratic model predicts for the per-node step
    /// `step` (stacked: `x`).
    fn predicted_decrease(
        &self,
        grad: &[Vector3<f64>],
        step: &[Vector3<f64>],
        x: &Mat<f64>,
    ) -> f64 {
        let g_dot_s: f64 = grad.iter().zip(step).map(|(g, s)| g.dot(s)).sum();
        let flat: Vec<f64> = (0..x.nrows()).map(|k| x[(k, 0)]).collect();
        let mut hs = vec![0.0; flat.len()];
        self.pattern.sym_mul_flat(&self.hval, &flat, &mut hs);
        let shs: f64 = flat.iter().zip(&hs).map(|(a, b)| a * b).sum();
        -(g_dot_s + 0.5 * shs)
    }

    /// Try `R_i exp(step_i)`: accept it when the cost decreased by at least 1e-4 of the
    /// prediction (or, at the noise floor where the decrease drowns in rounding ~1e-16 f, when
    /// the gradient decreased, `[M6]`) and adapt the damping; `Some` when the solve stops
    /// (converged on a tiny accepted step, stalled when no damping makes progress).
    fn trial(
        &mut self,
        p: &mut Point,
        step: &[Vector3<f64>],
        predicted: f64,
        max_step: f64,
    ) -> Option<Termination> {
        let cand = self.stepped(p, step);
        let rho = if predicted > 0.0 {
            (p.cost - cand.cost) / predicted
        } else {
            -1.0
        };
        let at_noise_floor = predicted <= 1e-12 * p.cost.max(f64::MIN_POSITIVE);
        let step_tolerance = self.settings.step_tolerance;
        if rho > 1e-4 || (at_noise_floor && cand.gn < p.gn) {
            *p = cand;
            self.need_hessian = true;
            if rho > 0.75 || at_noise_floor {
                self.mu = (self.mu / 4.0).max(1e-14);
            } else if rho < 0.25 {
                self.mu *= 4.0;
            }
            return (max_step < step_tolerance).then(|| Termination::Converged {
                measure: "max step angle (rad)".into(),
                value: max_step,
                threshold: step_tolerance,
            });
        }
        self.mu *= 8.0;
        (self.mu > 1e16 || (at_noise_floor && max_step < step_tolerance)).then(|| {
            Termination::Stalled {
                value: p.gn / self.total_weight,
                threshold: self.settings.gradient_tolerance,
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multiple::init::spectral_with;
    use crate::multiple::synthetic::{SyntheticChain, SyntheticGraph};
    use crate::so3::angle_between;

    /// The three linear solvers reach the same minimiser, from the same spectral start; the
    /// direct solver is the reference (`[M6]`, `[M6b]`).
    fn agree(problem: &MultipleProblem) {
        let settings = MultipleSettings::default();
        let solve = |kind| {
            let init = spectral_with(problem, Some(kind)).unwrap();
            let s = solve_chordal(problem, init, &settings, Some(kind.into())).unwrap();
            assert!(
                s.report.termination.is_converged(),
                "{kind}: {:?}",
                s.report
            );
            // gauge: compare R_i R_0^T
            let r0 = s.rotations[0].inverse();
            (
                s.cost,
                s.rotations.iter().map(|r| r * r0).collect::<Vec<_>>(),
            )
        };
        let (c_ref, r_ref) = solve(SolverKind::Direct);
        for kind in [SolverKind::Laplacian, SolverKind::Jacobi] {
            let (c, r) = solve(kind);
            assert!((c - c_ref).abs() <= 1e-9 * c_ref, "{kind}: {c} vs {c_ref}");
            let worst = r
                .iter()
                .zip(&r_ref)
                .map(|(a, b)| angle_between(a, b))
                .fold(0.0, f64::max);
            assert!(worst < 1e-6, "{kind}: {worst} rad from the direct solution");
        }
    }

    #[test]
    fn solvers_agree_on_a_chain_with_closures() {
        let (p, _) = SyntheticChain {
            num_rotations: 3000,
            noise_sigma: 0.01,
            ..Default::default()
        }
        .generate();
        agree(&p);
    }

    /// A hub (a node joined to every other, as the world node of soft gravity priors [G10])
    /// does not make a chain look like an expander to the BFS pre-filter [M6]: the chain with
    /// a hub keeps the chain's solver (block-Jacobi PCG before the hub was left out).
    #[test]
    fn a_hub_keeps_the_chains_solver() {
        let (chain, _) = SyntheticChain {
            num_rotations: 3000,
            ..Default::default()
        }
        .generate();
        let n = chain.num_rotations();
        let mut edges = chain.edges().to_vec();
        edges.extend((0..n).map(|i| crate::multiple::Edge {
            i,
            j: n,
            rotation: Rotation::identity(),
            weight: 1.0,
        }));
        let hub = MultipleProblem::new(n + 1, edges).unwrap();
        let kind = |p: &MultipleProblem| choose_solver(p).unwrap().kind;
        assert_eq!(kind(&hub), kind(&chain));
        assert_ne!(kind(&hub), SolverKind::Jacobi);
    }

    #[test]
    fn solvers_agree_on_a_noisy_random_graph() {
        let (p, _) = SyntheticGraph {
            num_rotations: 300,
            num_edges: 900,
            noise_sigma: 0.1,
            ..Default::default()
        }
        .generate();
        agree(&p);
    }

    #[test]
    fn laplacian_preconditioner_is_exact_on_a_consistent_chain() {
        // On noise-free data the Hessian at the solution equals 4 L ⊗ I: one PCG iteration
        // solves the Newton system exactly, so the preconditioned solve reproduces it.
        let (p, gt) = SyntheticChain {
            num_rotations: 500,
            noise_sigma: 0.0,
            ..Default::default()
        }
        .generate();
        let n = p.num_rotations();
        let pattern = grounded_pattern(&p, 3);
        let slots = edge_slots(&p, &pattern);
        let mut h = vec![0.0; pattern.nnz()];
        assemble_hessian(&p, &gt, &pattern, &slots, &mut h);
        let mut l4 = vec![0.0; pattern.nnz()];
        assemble_laplacian(&p, &pattern, &slots, &mut l4);
        let diff = h
            .iter()
            .zip(&l4)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        assert!(diff < 1e-12, "Hessian - 4 L ⊗ I = {diff}");
        let solver = linear_solver(&p, &pattern, SolverKind::Laplacian.into()).unwrap();
        assert_eq!(solver.kind(), SolverKind::Laplacian);
        let b = Mat::<f64>::from_fn(3 * (n - 1), 1, |k, _| ((k * 7) % 11) as f64 - 5.0);
        let mut x = b.clone();
        let f = solver.factor(&pattern, &h).unwrap();
        assert!(f.solve(&mut x, 1e-12, 1).is_some());
        let hx = pattern.sym_mul(&h, &x);
        let res = (&hx - &b).norm_l2() / b.norm_l2();
        assert!(res < 1e-10, "relative residual after one iteration {res}");
    }

    /// `[A4]`: the anisotropic gradient and Hessian match central differences of the cost in
    /// the right-perturbation chart (node 0 fixed), with indefinite `M` on some edges.
    #[test]
    fn anisotropic_gradient_and_hessian_match_finite_differences() {
        use crate::multiple::synthetic::SyntheticAnisotropic;
        let (p, truth) = SyntheticAnisotropic {
            num_rotations: 6,
            num_edges: 12,
            sigma: 0.2,
            ratio: 8.0,
            ..Default::default()
        }
        .generate();
        let n = p.num_rotations();
        let r: Vec<Rotation> = truth
            .iter()
            .enumerate()
            .map(|(k, t)| t * exp(&Vector3::new(0.3, -0.2 * k as f64, 0.1)))
            .collect();
        let (_, grad) = chordal_gradient(&p, &r);
        let pattern = grounded_pattern(&p, 3);
        let slots = edge_slots(&p, &pattern);
        let mut h = vec![0.0; pattern.nnz()];
        assemble_hessian(&p, &r, &pattern, &slots, &mut h);
        let dir: Vec<Vector3<f64>> = (0..n)
            .map(|k| match k {
                0 => Vector3::zeros(),
                _ => Vector3::new(0.7, -0.3 * k as f64, 0.2 + 0.1 * k as f64),
            })
            .collect();
        let at = |t: f64| {
            let moved: Vec<Rotation> = r
                .iter()
                .zip(&dir)
                .map(|(ri, d)| ri * exp(&(d * t)))
                .collect();
            p.chordal_cost(&moved)
        };
        let t = 1e-4;
        let slope = (at(t) - at(-t)) / (2.0 * t);
        let g_dot: f64 = grad.iter().zip(&dir).map(|(g, d)| g.dot(d)).sum();
        assert!(
            (slope - g_dot).abs() < 1e-6 * (1.0 + g_dot.abs()),
            "{slope} vs {g_dot}"
        );
        let t = 1e-3;
        let curvature = (at(t) - 2.0 * at(0.0) + at(-t)) / (t * t);
        let flat: Vec<f64> = dir[1..].iter().flat_map(|d| d.iter().copied()).collect();
        let mut hd = vec![0.0; flat.len()];
        pattern.sym_mul_flat(&h, &flat, &mut hd);
        let dhd: f64 = flat.iter().zip(&hd).map(|(a, b)| a * b).sum();
        assert!(
            (curvature - dhd).abs() < 1e-4 * (1.0 + dhd.abs()),
            "{curvature} vs {dhd}"
        );
    }
}
