//! The sparsity pattern of a symmetric block-sparse matrix (the Newton systems of the local
//! solvers, `[M6]`): lower-triangular CSC storage, one block row/column per node, assembly,
//! products, and the sparse Cholesky on it.

use crate::error::{Error, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, Mat, MatMut, Par, Side};
use nalgebra::Matrix3;
use std::sync::Arc;

/// A symbolic sparse Cholesky analysis (AMD ordering) of a [`BlockPattern`], shared by the
/// numeric factorisations of matrices with that pattern.
#[derive(Clone)]
pub(crate) struct SymbolicFactor(Arc<SymbolicCholesky<usize>>);

impl SymbolicFactor {
    /// Stored values of the factor.
    pub(crate) fn len_val(&self) -> usize {
        self.0.len_val()
    }

    /// Multiply-adds of a numeric factorisation ([`super::cholesky::factor_multiply_adds`]).
    pub(crate) fn multiply_adds(&self) -> f64 {
        super::cholesky::factor_multiply_adds(&self.0)
    }
}

/// A numeric sparse Cholesky factor `P A P^T = L L^T`.
pub(crate) struct SparseLlt {
    symbolic: SymbolicFactor,
    values: Vec<f64>,
}

impl SparseLlt {
    /// Stored values of the factor.
    pub(crate) fn len_val(&self) -> usize {
        self.values.len()
    }

    /// Solve `A X = B` in place. The triangular solves run sequentially: with a few
    /// right-hand sides, rayon's synchronisation costs more than it saves (the preconditioner
    /// of a 10^6-node grid sweep, 3 right-hand sides: 1.2-3 s per solve with faer's default
    /// parallelism against 0.25 s sequentially, 2-core machine).
    pub(crate) fn solve_in_place(&self, rhs: MatMut<'_, f64>) {
        let sym = &self.symbolic.0;
        let req = sym.solve_in_place_scratch::<f64>(rhs.ncols(), Par::Seq);
        let mut mem = MemBuffer::new(req);
        LltRef::<usize, f64>::new(sym, &self.values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut mem),
        );
    }
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

    /// The block size.
    pub(crate) fn block_size(&self) -> usize {
        self.bs
    }

    /// The column pointers of the lower-triangular storage.
    pub(crate) fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    /// The same pattern as `other` (block size and every block column's neighbours).
    pub(crate) fn same_as(&self, other: &BlockPattern) -> bool {
        self.bs == other.bs && self.nbrs == other.nbrs
    }

    /// Stored values.
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

    /// Decouple the pinned rows and columns (`pinned[k]`: row/column `k` of the matrix): their
    /// off-diagonal entries become 0 and their diagonal 1, so that a solve with a zero
    /// right-hand side there leaves those unknowns at 0 (the constrained directions of a
    /// Newton system, `[G4]`). One pass over the stored values.
    pub(crate) fn pin(&self, val: &mut [f64], pinned: &[bool]) {
        let rows = self.symbolic.row_idx();
        for c in 0..self.col_ptr.len() - 1 {
            for idx in self.col_ptr[c]..self.col_ptr[c + 1] {
                let r = rows[idx];
                if pinned[r] || pinned[c] {
                    val[idx] = if r == c { 1.0 } else { 0.0 };
                }
            }
        }
    }

    /// Diagonal entries.
    pub(crate) fn diagonal(&self, val: &[f64]) -> Vec<f64> {
        (0..self.col_ptr.len() - 1)
            .map(|c| val[self.col_ptr[c]])
            .collect()
    }

    /// The diagonal `bs x bs` blocks, each in the top-left of a 3x3 matrix (identity beyond `bs`).
    pub(crate) fn diagonal_blocks(&self, val: &[f64]) -> Vec<Matrix3<f64>> {
        let bs = self.bs;
        let blocks = (self.col_ptr.len() - 1) / bs;
        (0..blocks)
            .map(|q| {
                let mut m = Matrix3::identity();
                for b in 0..bs {
                    let c = self.col_ptr[bs * q + b];
                    for a in b..bs {
                        m[(a, b)] = val[c + a - b];
                        m[(b, a)] = val[c + a - b];
                    }
                }
                m
            })
            .collect()
    }

    /// Stored values of the Cholesky factor (AMD ordering), from a symbolic analysis.
    pub(crate) fn factor_len(&self) -> Result<usize> {
        Ok(self.symbolic_llt()?.len_val())
    }

    /// The symbolic Cholesky analysis (AMD ordering) refused before its column counts when the
    /// ordering predicts more than `max_values` stored values
    /// ([`super::cholesky::symbolic_cholesky_within`]; the lower triangle is the pattern of
    /// `A + A^T` the ordering reads).
    /// With it, the ordering's count of the factor's values
    /// ([`super::cholesky::symbolic_cholesky_counted_within`]).
    pub(crate) fn symbolic_within(
        &self,
        max_values: usize,
    ) -> Result<std::result::Result<(SymbolicCholesky<usize>, usize), usize>> {
        super::cholesky::symbolic_cholesky_counted_within(self.symbolic.as_ref(), max_values)
    }

    /// The matrix with this pattern and the values `val` (lower triangle).
    pub(crate) fn matrix<'a>(&'a self, val: &'a [f64]) -> SparseColMatRef<'a, usize, f64> {
        SparseColMatRef::new(self.symbolic.as_ref(), val)
    }

    /// Symbolic Cholesky (once), in the minimum-degree ordering of the blocks
    /// ([`super::cholesky::symbolic_cholesky_within`]).
    pub(crate) fn symbolic_llt(&self) -> Result<SymbolicFactor> {
        super::cholesky::symbolic_cholesky_within(self.symbolic.as_ref(), usize::MAX)?
            .map(|s| SymbolicFactor(Arc::new(s)))
            .map_err(|predicted| Error::Solver {
                message: format!("symbolic sparse Cholesky refused at {predicted} values"),
            })
    }

    /// [`Self::symbolic_llt`], `None` when the ordering predicts more than `max_values` stored
    /// values (refused before the column counts, [`Self::symbolic_within`]).
    pub(crate) fn symbolic_llt_within(&self, max_values: usize) -> Result<Option<SymbolicFactor>> {
        Ok(self
            .symbolic_within(max_values)?
            .ok()
            .map(|(s, _)| SymbolicFactor(Arc::new(s))))
    }

    /// Numeric Cholesky with the given values; `None` if the matrix is not positive definite
    /// (or its scratch space cannot be allocated). Factors above 2e6 values use all threads.
    pub(crate) fn llt(&self, sym: &SymbolicFactor, val: &[f64]) -> Option<SparseLlt> {
        let mat = SparseColMatRef::new(self.symbolic.as_ref(), val);
        let par = super::factor_parallelism(sym.len_val());
        let mut values = vec![0.0f64; sym.len_val()];
        let req = sym
            .0
            .factorize_numeric_llt_scratch::<f64>(par, Default::default());
        let mut mem = MemBuffer::try_new(req).ok()?;
        sym.0
            .factorize_numeric_llt::<f64>(
                &mut values,
                mat,
                Side::Lower,
                LltRegularization::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            .ok()?;
        Some(SparseLlt {
            symbolic: sym.clone(),
            values,
        })
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
