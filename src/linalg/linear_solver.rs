//! Solving the symmetric positive definite block-sparse systems of the local solvers `[M6]`:
//! a sparse Cholesky factorisation (symbolic analysis once), or preconditioned conjugate
//! gradients ([`super::pcg`]) on graphs whose block factors fill, preconditioned either by the
//! factorised scalar graph Laplacian ([`ScalarLaplacian`], `[M6b]`) or block-Jacobi.

use super::block_pattern::{BlockPattern, SparseLlt, SymbolicFactor};
use super::pcg::pcg;
use crate::error::Result;
use faer::Mat;
use nalgebra::Matrix3;

/// Which linear solver the Newton systems of the local solvers use (`[M6]`, `[M6b]`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum SolverKind {
    /// Sparse Cholesky of the block system (graphs whose factor stays sparse).
    Direct,
    /// Conjugate gradients preconditioned by a sparse Cholesky of the scalar graph Laplacian
    /// (one factorisation per solve; long chains and grids whose block factor does not fit).
    Laplacian,
    /// Block-Jacobi preconditioned conjugate gradients (expander-like graphs: well conditioned,
    /// and every factorisation nearly dense).
    Jacobi,
}

impl std::fmt::Display for SolverKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            SolverKind::Direct => "sparse Cholesky",
            SolverKind::Laplacian => "PCG (scalar Laplacian preconditioner)",
            SolverKind::Jacobi => "PCG (block-Jacobi preconditioner)",
        })
    }
}

/// The preconditioner `[M6b]` `M = F (K ⊗ I_3) F^T` of a 3x3-block system, where `K` is a
/// scalar weighted graph Laplacian plus a diagonal shift (an endpoint `None` is grounded: the
/// edge only adds to the other endpoint's diagonal) and `F` is block diagonal with orthogonal
/// `frames` (identity when absent). `K` is factorised once (sparse Cholesky, AMD ordering);
/// applying `M^{-1}` costs one sparse triangular solve pair with 3 right-hand sides.
pub(crate) struct ScalarLaplacian {
    nblocks: usize,
    llt: SparseLlt,
    frames: Option<Vec<Matrix3<f64>>>,
}

impl ScalarLaplacian {
    /// Factorise `K = sum_e c_e (e_p - e_q)(e_p - e_q)^T + shift I` on `nblocks` nodes;
    /// `Ok(None)` if `K` is not numerically positive definite.
    /// `symbolic`: the symbolic analysis of [`ScalarLaplacian::pattern`] of the same
    /// `nblocks` and `edges`, when it was computed already (else it is computed here).
    pub(crate) fn new(
        nblocks: usize,
        edges: &[(Option<usize>, Option<usize>, f64)],
        shift: f64,
        frames: Option<Vec<Matrix3<f64>>>,
        symbolic: Option<SymbolicFactor>,
    ) -> Result<Option<Self>> {
        let pattern = Self::pattern(nblocks, edges);
        let mut val = vec![0.0; pattern.nnz()];
        for &(p, q, c) in edges {
            let one = Matrix3::from_element(c);
            if let Some(p) = p {
                pattern.add(&mut val, p, p, 0, &one);
            }
            if let Some(q) = q {
                pattern.add(&mut val, q, q, 0, &one);
            }
            if let (Some(p), Some(q)) = (p, q) {
                let (hi, lo) = (p.max(q), p.min(q));
                pattern.add(&mut val, hi, lo, pattern.slot(hi, lo), &(-one));
            }
        }
        pattern.add_diagonal(&mut val, shift);
        let sym = match symbolic {
            Some(sym) => sym,
            None => pattern.symbolic_llt()?,
        };
        Ok(pattern.llt(&sym, &val).map(|llt| ScalarLaplacian {
            nblocks,
            llt,
            frames,
        }))
    }

    /// The scalar pattern of `K` (one node per block; edges with a grounded endpoint only
    /// touch the diagonal).
    pub(crate) fn pattern(
        nblocks: usize,
        edges: &[(Option<usize>, Option<usize>, f64)],
    ) -> BlockPattern {
        BlockPattern::new(
            nblocks,
            1,
            edges.iter().filter_map(|&(p, q, _)| Some((p?, q?))),
        )
    }

    /// Stored values of the factor of `K`.
    pub(crate) fn factor_len(&self) -> usize {
        self.llt.len_val()
    }

    /// `z[k] = M^{-1} r[k]` for node-major vectors (`3 q + a`), all columns in one sparse
    /// triangular solve pair.
    pub(crate) fn apply(&self, r: &[&[f64]], z: &mut [&mut [f64]]) {
        let n = self.nblocks;
        let frame = |q: usize| self.frames.as_ref().map(|f| f[q]);
        // column 3 k + a of `b` holds component a of F^T r[k]
        let mut b = Mat::<f64>::from_fn(n, 3 * r.len(), |q, col| {
            let (k, a) = (col / 3, col % 3);
            match frame(q) {
                Some(f) => (0..3).map(|c| f[(c, a)] * r[k][3 * q + c]).sum(),
                None => r[k][3 * q + a],
            }
        });
        self.llt.solve_in_place(b.as_mut());
        for (k, zk) in z.iter_mut().enumerate() {
            for q in 0..n {
                for a in 0..3 {
                    zk[3 * q + a] = match frame(q) {
                        Some(f) => (0..3).map(|c| f[(a, c)] * b[(q, 3 * k + c)]).sum(),
                        None => b[(q, 3 * k + a)],
                    };
                }
            }
        }
    }
}

/// The inverses of the diagonal blocks of the matrix with `pattern` and values `val` (the
/// block-Jacobi preconditioner); `None` if a block is not positive definite.
pub(crate) fn jacobi_inverses(pattern: &BlockPattern, val: &[f64]) -> Option<Vec<Matrix3<f64>>> {
    let blocks = pattern.diagonal_blocks(val).into_iter();
    blocks.map(|m| Some(m.cholesky()?.inverse())).collect()
}

/// Linear solver for a symmetric block-sparse matrix with the pattern of a [`BlockPattern`].
pub(crate) enum LinearSolver {
    /// Sparse Cholesky; symbolic factorisation done once.
    Direct(SymbolicFactor),
    /// Conjugate gradients preconditioned by a factorised scalar Laplacian (3x3 blocks only).
    Laplacian(ScalarLaplacian),
    /// Block-Jacobi preconditioned conjugate gradients.
    Jacobi,
}

/// The preconditioner of a [`Factor::Pcg`].
pub(crate) enum Preconditioner<'a> {
    /// inverse diagonal blocks (bs x bs each)
    Jacobi(Vec<Matrix3<f64>>),
    Laplacian(&'a ScalarLaplacian),
}

/// A factorised (or preconditioned) system ready to solve.
pub(crate) enum Factor<'a> {
    Direct(SparseLlt),
    Pcg {
        pattern: &'a BlockPattern,
        val: Vec<f64>,
        precond: Preconditioner<'a>,
    },
}

impl LinearSolver {
    /// Sparse Cholesky if `direct` (symbolic analysis now), else block-Jacobi PCG.
    pub(crate) fn new(pattern: &BlockPattern, direct: bool) -> Result<Self> {
        if direct {
            Ok(LinearSolver::Direct(pattern.symbolic_llt()?))
        } else {
            Ok(LinearSolver::Jacobi)
        }
    }

    /// Sparse Cholesky when its factor has at most `max_values` stored values (the symbolic
    /// analysis decides), else PCG.
    pub(crate) fn direct_up_to(pattern: &BlockPattern, max_values: usize) -> Result<Self> {
        let size = pattern.factor_len()?;
        Self::new(pattern, size <= max_values)
    }

    /// The kind of this solver.
    pub(crate) fn kind(&self) -> SolverKind {
        match self {
            LinearSolver::Direct(_) => SolverKind::Direct,
            LinearSolver::Laplacian(_) => SolverKind::Laplacian,
            LinearSolver::Jacobi => SolverKind::Jacobi,
        }
    }

    /// Prepare to solve with matrix values `val`; `None` if not positive definite (direct) or
    /// if a diagonal block is not positive definite (block-Jacobi; indefiniteness found later
    /// is reported by [`Factor::solve`]).
    pub(crate) fn factor<'a>(
        &'a self,
        pattern: &'a BlockPattern,
        val: &[f64],
    ) -> Option<Factor<'a>> {
        let precond = match self {
            LinearSolver::Direct(sym) => return pattern.llt(sym, val).map(Factor::Direct),
            LinearSolver::Laplacian(l) => Preconditioner::Laplacian(l),
            LinearSolver::Jacobi => Preconditioner::Jacobi(jacobi_inverses(pattern, val)?),
        };
        Some(Factor::Pcg {
            pattern,
            val: val.to_vec(),
            precond,
        })
    }
}

impl Factor<'_> {
    /// Solve `A x = b` in place for each column of `b` (relative residual `rel_tol` for PCG).
    /// Returns the conjugate-gradient iterations (0 for the direct solver), or `None` if PCG
    /// met non-positive curvature (the matrix is not positive definite).
    pub(crate) fn solve(&self, b: &mut Mat<f64>, rel_tol: f64, max_iter: usize) -> Option<usize> {
        match self {
            Factor::Direct(l) => {
                l.solve_in_place(b.as_mut());
                Some(0)
            }
            Factor::Pcg {
                pattern,
                val,
                precond,
            } => {
                let bs = pattern.block_size();
                let apply = |r: &[&[f64]], z: &mut [&mut [f64]]| match precond {
                    Preconditioner::Jacobi(inv) => {
                        for (rk, zk) in r.iter().zip(z.iter_mut()) {
                            for (q, m) in inv.iter().enumerate() {
                                for a in 0..bs {
                                    zk[bs * q + a] =
                                        (0..bs).map(|c| m[(a, c)] * rk[bs * q + c]).sum();
                                }
                            }
                        }
                    }
                    Preconditioner::Laplacian(l) => l.apply(r, z),
                };
                let rhs: Vec<Vec<f64>> = (0..b.ncols())
                    .map(|col| (0..b.nrows()).map(|r| b[(r, col)]).collect())
                    .collect();
                let times = |x: &[f64], y: &mut [f64]| pattern.sym_mul_flat(val, x, y);
                let (x, iterations) = pcg(&times, &apply, &rhs, rel_tol, (max_iter, None))?;
                for (col, xc) in x.into_iter().enumerate() {
                    for (r, v) in xc.into_iter().enumerate() {
                        b[(r, col)] = v;
                    }
                }
                Some(iterations)
            }
        }
    }
}
