//! Chordal L2 multiple rotation averaging: Riemannian Newton with Levenberg-Marquardt damping on
//! `SO(3)^n`, sparse (`paper-notes/multiple.md`, `[M3]`, `[M6]`).
//!
//! Chart: right perturbations `R_i <- R_i exp(hat w_i)`. Node 0 is held fixed during the
//! iteration (the cost is gauge invariant, `[M1]`), so the Newton system is `3(n-1)` square,
//! block sparse with the sparsity of the view graph. Its pattern and the symbolic sparse
//! Cholesky factorisation (faer, AMD ordering) are computed once; each iteration only
//! reassembles the values and refactorises numerically. No dense `3n x 3n` matrix is formed.

use crate::error::{Error, Result};
use crate::multiple::MultipleProblem;
use crate::multiple::solve::{Loss, MultipleSettings, MultipleSolution};
use crate::report::{SolverReport, Termination};
use crate::so3::{Rotation, exp, vee};
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Mat, Side};
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

/// Lower-triangular CSC pattern of a symmetric block-sparse matrix with `bs x bs` blocks, one
/// block row/column per variable node, off-diagonal blocks where the graph has an edge. Built
/// once; [`BlockPattern::add`] accumulates into a value array (`[M6]`, assembly).
pub(crate) struct BlockPattern {
    bs: usize,
    symbolic: SymbolicSparseColMat<usize>,
    col_ptr: Vec<usize>,
    /// sorted neighbours `P > Q` of each block column `Q`
    nbrs: Vec<Vec<usize>>,
}

impl BlockPattern {
    /// `pairs`: block pairs (p, q), p != q, duplicates allowed.
    pub(crate) fn new(
        nblocks: usize,
        bs: usize,
        pairs: impl Iterator<Item = (usize, usize)>,
    ) -> Self {
        let mut nbrs: Vec<Vec<usize>> = vec![Vec::new(); nblocks];
        for (p, q) in pairs {
            if p != q {
                nbrs[p.min(q)].push(p.max(q));
            }
        }
        for l in nbrs.iter_mut() {
            l.sort_unstable();
            l.dedup();
        }
        let dim = nblocks * bs;
        let mut col_ptr = Vec::with_capacity(dim + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0);
        for (q, l) in nbrs.iter().enumerate() {
            for b in 0..bs {
                for a in b..bs {
                    row_idx.push(bs * q + a);
                }
                for &p in l {
                    for a in 0..bs {
                        row_idx.push(bs * p + a);
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let symbolic = SymbolicSparseColMat::new_checked(dim, dim, col_ptr.clone(), None, row_idx);
        BlockPattern {
            bs,
            symbolic,
            col_ptr,
            nbrs,
        }
    }

    pub(crate) fn nnz(&self) -> usize {
        *self.col_ptr.last().unwrap_or(&0)
    }

    /// Rank of neighbour `p` in the list of block column `q` (p > q), found once per edge.
    pub(crate) fn slot(&self, p: usize, q: usize) -> usize {
        let (p, q) = (p.max(q), p.min(q));
        self.nbrs[q].binary_search(&p).expect("pair in pattern")
    }

    /// Add `m` (the `bs x bs` block at block row `p`, block column `q`) and, implicitly, its
    /// transpose at `(q, p)`; only the lower triangle is stored. `slot` from [`Self::slot`]
    /// (ignored when `p == q`).
    pub(crate) fn add(&self, val: &mut [f64], p: usize, q: usize, slot: usize, m: &Matrix3<f64>) {
        let bs = self.bs;
        if p == q {
            for b in 0..bs {
                let c = self.col_ptr[bs * q + b];
                for a in b..bs {
                    val[c + a - b] += m[(a, b)];
                }
            }
        } else if p > q {
            for b in 0..bs {
                let c = self.col_ptr[bs * q + b] + (bs - b) + slot * bs;
                for a in 0..bs {
                    val[c + a] += m[(a, b)];
                }
            }
        } else {
            // store the transpose at (q, p)
            for b in 0..bs {
                let c = self.col_ptr[bs * p + b] + (bs - b) + slot * bs;
                for a in 0..bs {
                    val[c + a] += m[(b, a)];
                }
            }
        }
    }

    /// Add `s` to every diagonal entry.
    pub(crate) fn add_diagonal(&self, val: &mut [f64], s: f64) {
        for c in 0..self.col_ptr.len() - 1 {
            val[self.col_ptr[c]] += s;
        }
    }

    /// Diagonal entries.
    pub(crate) fn diagonal(&self, val: &[f64]) -> Vec<f64> {
        (0..self.col_ptr.len() - 1)
            .map(|c| val[self.col_ptr[c]])
            .collect()
    }

    /// Symbolic Cholesky (once).
    pub(crate) fn symbolic_llt(&self) -> Result<SymbolicLlt<usize>> {
        SymbolicLlt::try_new(self.symbolic.as_ref(), Side::Lower).map_err(|e| Error::Solver {
            message: format!("symbolic sparse Cholesky failed: {e:?}"),
        })
    }

    /// Numeric Cholesky with the given values; `None` if the matrix is not positive definite.
    pub(crate) fn llt(&self, sym: &SymbolicLlt<usize>, val: &[f64]) -> Option<Llt<usize, f64>> {
        let mat = SparseColMatRef::new(self.symbolic.as_ref(), val);
        Llt::try_new_with_symbolic(sym.clone(), mat, Side::Lower).ok()
    }

    /// `y = A x` (one vector) for the symmetric matrix stored by its lower triangle.
    pub(crate) fn sym_mul_flat(&self, val: &[f64], x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        let rows = self.symbolic.row_idx();
        for c in 0..self.col_ptr.len() - 1 {
            let xc = x[c];
            let mut acc = 0.0;
            for idx in self.col_ptr[c]..self.col_ptr[c + 1] {
                let r = rows[idx];
                let v = val[idx];
                y[r] += v * xc;
                if r != c {
                    acc += v * x[r];
                }
            }
            y[c] += acc;
        }
    }

    /// `y = A x` for the symmetric matrix stored by its lower triangle; `x`, `y`: dim x k.
    pub(crate) fn sym_mul(&self, val: &[f64], x: &Mat<f64>) -> Mat<f64> {
        let dim = self.col_ptr.len() - 1;
        let k = x.ncols();
        let mut y = Mat::<f64>::zeros(dim, k);
        let rows = self.symbolic.row_idx();
        for c in 0..dim {
            for idx in self.col_ptr[c]..self.col_ptr[c + 1] {
                let r = rows[idx];
                let v = val[idx];
                for t in 0..k {
                    y[(r, t)] += v * x[(c, t)];
                    if r != c {
                        y[(c, t)] += v * x[(r, t)];
                    }
                }
            }
        }
        y
    }
}

/// Fill-in budget of the direct solver: a sparse Cholesky is used when the scalar (one entry
/// per node) symbolic factor has at most this many entries per node; otherwise (expander-like
/// graphs, e.g. random view graphs, whose Cholesky factors are nearly dense) preconditioned
/// conjugate gradients are used (`[M6]`, "linear solver").
pub const DIRECT_FILL_PER_NODE: usize = 60;

/// Linear solver for a symmetric block-sparse matrix with the pattern of a [`BlockPattern`].
pub(crate) enum LinearSolver {
    /// Sparse Cholesky; symbolic factorisation done once.
    Direct(SymbolicLlt<usize>),
    /// Block-Jacobi preconditioned conjugate gradients.
    Pcg,
}

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
    let sym = faer::sparse::linalg::cholesky::factorize_symbolic_cholesky(
        scalar.symbolic.as_ref(),
        Side::Lower,
        Default::default(),
        Default::default(),
    )
    .map_err(|e| Error::Solver {
        message: format!("symbolic sparse Cholesky failed: {e:?}"),
    })?;
    Ok(sym.len_val() <= DIRECT_FILL_PER_NODE * n.max(1))
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

/// A factorised (or preconditioned) system ready to solve.
pub(crate) enum Factor<'a> {
    Direct(Llt<usize, f64>),
    Pcg {
        pattern: &'a BlockPattern,
        val: Vec<f64>,
        /// inverse diagonal blocks (bs x bs each, row-major)
        precond: Vec<Matrix3<f64>>,
    },
}

impl LinearSolver {
    /// Direct if `direct`, else PCG; `direct = None` decides with [`prefers_direct`].
    pub(crate) fn new(
        problem: &MultipleProblem,
        pattern: &BlockPattern,
        direct: Option<bool>,
    ) -> Result<Self> {
        let direct = match direct {
            Some(d) => d,
            None => prefers_direct(problem)?,
        };
        if direct {
            Ok(LinearSolver::Direct(pattern.symbolic_llt()?))
        } else {
            Ok(LinearSolver::Pcg)
        }
    }

    /// Prepare to solve with matrix values `val`; `None` if not positive definite (direct) or
    /// if a diagonal block is not positive definite (PCG; indefiniteness found later is
    /// reported by [`Factor::solve`]).
    pub(crate) fn factor<'a>(&self, pattern: &'a BlockPattern, val: &[f64]) -> Option<Factor<'a>> {
        match self {
            LinearSolver::Direct(sym) => pattern.llt(sym, val).map(Factor::Direct),
            LinearSolver::Pcg => {
                let bs = pattern.bs;
                let nb = (pattern.col_ptr.len() - 1) / bs;
                let mut precond = Vec::with_capacity(nb);
                for q in 0..nb {
                    let mut m = Matrix3::identity();
                    for b in 0..bs {
                        let c = pattern.col_ptr[bs * q + b];
                        for a in b..bs {
                            m[(a, b)] = val[c + a - b];
                            m[(b, a)] = val[c + a - b];
                        }
                    }
                    let inv = m.cholesky()?.inverse();
                    precond.push(inv);
                }
                Some(Factor::Pcg {
                    pattern,
                    val: val.to_vec(),
                    precond,
                })
            }
        }
    }
}

impl Factor<'_> {
    /// Solve `A x = b` in place for each column of `b` (relative residual `rel_tol` for PCG).
    /// Returns `false` if PCG met non-positive curvature (the matrix is not positive definite).
    pub(crate) fn solve(&self, b: &mut Mat<f64>, rel_tol: f64, max_iter: usize) -> bool {
        match self {
            Factor::Direct(l) => {
                l.solve_in_place(b.as_mut());
                true
            }
            Factor::Pcg {
                pattern,
                val,
                precond,
            } => {
                for col in 0..b.ncols() {
                    let rhs: Vec<f64> = (0..b.nrows()).map(|r| b[(r, col)]).collect();
                    let Some(x) = pcg(pattern, val, precond, &rhs, rel_tol, max_iter) else {
                        return false;
                    };
                    for (r, v) in x.into_iter().enumerate() {
                        b[(r, col)] = v;
                    }
                }
                true
            }
        }
    }
}

/// Preconditioned conjugate gradients (block-Jacobi). `None` on non-positive curvature.
fn pcg(
    pattern: &BlockPattern,
    val: &[f64],
    precond: &[Matrix3<f64>],
    b: &[f64],
    rel_tol: f64,
    max_iter: usize,
) -> Option<Vec<f64>> {
    let bs = pattern.bs;
    let dim = b.len();
    let apply_m = |r: &[f64], z: &mut [f64]| {
        for (q, m) in precond.iter().enumerate() {
            for a in 0..bs {
                let mut s = 0.0;
                for c in 0..bs {
                    s += m[(a, c)] * r[bs * q + c];
                }
                z[bs * q + a] = s;
            }
        }
    };
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
    let bnorm = dot(b, b).sqrt();
    let mut x = vec![0.0; dim];
    if bnorm == 0.0 {
        return Some(x);
    }
    let mut r = b.to_vec();
    let mut z = vec![0.0; dim];
    apply_m(&r, &mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; dim];
    for _ in 0..max_iter {
        pattern.sym_mul_flat(val, &p, &mut ap);
        let pap = dot(&p, &ap);
        if pap <= 0.0 || !pap.is_finite() {
            return None;
        }
        let alpha = rz / pap;
        for k in 0..dim {
            x[k] += alpha * p[k];
            r[k] -= alpha * ap[k];
        }
        if dot(&r, &r).sqrt() <= rel_tol * bnorm {
            break;
        }
        apply_m(&r, &mut z);
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for k in 0..dim {
            p[k] = z[k] + beta * p[k];
        }
    }
    Some(x)
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

fn grad_norm(g: &[Vector3<f64>]) -> f64 {
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
            loss: Loss::Chordal,
            report: SolverReport {
                name: "riemannian-newton-lm".into(),
                iterations,
                termination,
                seconds: start.elapsed().as_secs_f64(),
            },
            init_cost,
        })
    };
    let measure = "relative gradient norm ||grad|| / sum(w)";
    let mut gn = grad_norm(&grad);
    if gn / total_weight <= tol || n < 2 {
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
    let solver = LinearSolver::new(problem, &pattern, direct)?;
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
        let step: Vec<Vector3<f64>> = (0..n)
            .map(|i| {
                if i == 0 {
                    Vector3::zeros()
                } else {
                    Vector3::new(
                        rhs[(3 * i - 3, 0)],
                        rhs[(3 * i - 2, 0)],
                        rhs[(3 * i - 1, 0)],
                    )
                }
            })
            .collect();
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
            if gn / total_weight <= tol {
                return finish(
                    r,
                    cost,
                    gn,
                    iterations,
                    Termination::Converged {
                        measure: measure.into(),
                        value: gn / total_weight,
                        threshold: tol,
                    },
                );
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
