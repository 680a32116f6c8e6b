//! Solving the symmetric positive definite block-sparse systems of the local solvers `[M6]`:
//! a sparse Cholesky factorisation (symbolic analysis once), or block-Jacobi preconditioned
//! conjugate gradients ([`super::pcg`]) on graphs whose factors fill.

use super::block_pattern::BlockPattern;
use super::pcg::pcg;
use crate::error::Result;
use faer::Mat;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use nalgebra::Matrix3;

/// Linear solver for a symmetric block-sparse matrix with the pattern of a [`BlockPattern`].
pub(crate) enum LinearSolver {
    /// Sparse Cholesky; symbolic factorisation done once.
    Direct(SymbolicLlt<usize>),
    /// Block-Jacobi preconditioned conjugate gradients.
    Pcg,
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
    /// Sparse Cholesky if `direct` (symbolic analysis now), else PCG.
    pub(crate) fn new(pattern: &BlockPattern, direct: bool) -> Result<Self> {
        if direct {
            Ok(LinearSolver::Direct(pattern.symbolic_llt()?))
        } else {
            Ok(LinearSolver::Pcg)
        }
    }

    /// Sparse Cholesky when its factor has at most `max_values` stored values (the symbolic
    /// analysis decides), else PCG.
    pub(crate) fn direct_up_to(pattern: &BlockPattern, max_values: usize) -> Result<Self> {
        let size = pattern.factor_len()?;
        Self::new(pattern, size <= max_values)
    }

    /// Prepare to solve with matrix values `val`; `None` if not positive definite (direct) or
    /// if a diagonal block is not positive definite (PCG; indefiniteness found later is
    /// reported by [`Factor::solve`]).
    pub(crate) fn factor<'a>(&self, pattern: &'a BlockPattern, val: &[f64]) -> Option<Factor<'a>> {
        match self {
            LinearSolver::Direct(sym) => pattern.llt(sym, val).map(Factor::Direct),
            LinearSolver::Pcg => {
                let bs = pattern.block_size();
                let col_ptr = pattern.col_ptr();
                let nb = (col_ptr.len() - 1) / bs;
                let mut precond = Vec::with_capacity(nb);
                for q in 0..nb {
                    let mut m = Matrix3::identity();
                    for b in 0..bs {
                        let c = col_ptr[bs * q + b];
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
