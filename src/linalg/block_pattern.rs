//! The sparsity pattern of a symmetric block-sparse matrix (the Newton systems of the local
//! solvers, `[M6]`): lower-triangular CSC storage, one block row/column per node, assembly,
//! products, and the sparse Cholesky on it.

use crate::error::{Error, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{LltRef, SymbolicCholesky, SymbolicCholeskyRaw, supernodal};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Conj, Mat, MatMut, Par, Side};
use nalgebra::Matrix3;
use std::sync::{Arc, OnceLock};

/// A symbolic sparse Cholesky analysis (AMD ordering) of a [`BlockPattern`], shared by the
/// numeric factorisations of matrices with that pattern; with a supernodal factor, the
/// permuted pattern its factorisations gather their values into (made at the first).
#[derive(Clone)]
pub(crate) struct SymbolicFactor(Arc<SymbolicCholesky<usize>>, Arc<OnceLock<Permuted>>);

/// The lower triangle of `P A P^T` for a [`BlockPattern`]'s `A` and a factor's ordering `P`:
/// its structure, and for each of its entries the position of its value among the pattern's.
/// A numeric factorisation then gathers its values in one pass where faer's general
/// permutation of `A` (counts, offsets, scatter) took 13 % of an anisotropic L1 solve.
struct Permuted {
    symbolic: SymbolicSparseColMat<usize>,
    source: Vec<usize>,
}

impl Permuted {
    /// The permuted lower triangle of `pattern` under the ordering `new_of` (`new_of[old]`,
    /// faer's inverse permutation), each column's rows sorted.
    fn new(pattern: SymbolicSparseColMatRef<'_, usize>, new_of: &[usize]) -> Permuted {
        let n = pattern.ncols();
        let mut entries: Vec<(usize, usize, usize)> = (0..n)
            .flat_map(|c| {
                let range = pattern.col_range(c);
                (pattern.row_idx()[range.clone()].iter().zip(range)).map(move |(&r, k)| {
                    let (a, b) = (new_of[r], new_of[c]);
                    (a.min(b), a.max(b), k)
                })
            })
            .collect();
        entries.sort_unstable();
        let mut col_ptr = vec![0usize; n + 1];
        for &(c, _, _) in &entries {
            col_ptr[c + 1] += 1;
        }
        for c in 0..n {
            col_ptr[c + 1] += col_ptr[c];
        }
        let row_idx = entries.iter().map(|e| e.1).collect();
        let source = entries.iter().map(|e| e.2).collect();
        let symbolic = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        Permuted { symbolic, source }
    }
}

impl SymbolicFactor {
    /// The analysis `s`, its permuted pattern not made yet.
    fn new(s: SymbolicCholesky<usize>) -> SymbolicFactor {
        SymbolicFactor(Arc::new(s), Arc::new(OnceLock::new()))
    }

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
            .map(SymbolicFactor::new)
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
            .map(|(s, _)| SymbolicFactor::new(s)))
    }

    /// Numeric Cholesky with the given values; `None` if the matrix is not positive definite
    /// (or its scratch space cannot be allocated). Factors above 2e6 values use all threads.
    pub(crate) fn llt(&self, sym: &SymbolicFactor, val: &[f64]) -> Option<SparseLlt> {
        let par = super::factor_parallelism(sym.len_val());
        let mut values = vec![0.0f64; sym.len_val()];
        let req = sym
            .0
            .factorize_numeric_llt_scratch::<f64>(par, Default::default());
        let mut mem = MemBuffer::try_new(req).ok()?;
        let stack = MemStack::new(&mut mem);
        let regularization = LltRegularization::default();
        // a supernodal factor: `P A P^T` gathered by the permuted pattern, made once (an analysis
        // is shared only by patterns built alike from the same edges, `multiple::chordal`; one
        // of another size takes faer's own permutation)
        let permuted = match (sym.0.raw(), sym.0.perm()) {
            (SymbolicCholeskyRaw::Supernodal(s), Some(perm)) => {
                let p = sym
                    .1
                    .get_or_init(|| Permuted::new(self.symbolic.as_ref(), perm.arrays().1));
                (p.source.len() == val.len() && p.symbolic.ncols() == self.symbolic.ncols())
                    .then_some((s, p))
            }
            _ => None,
        };
        match permuted {
            Some((s, permuted)) => {
                let gathered: Vec<f64> = permuted.source.iter().map(|&k| val[k]).collect();
                let a = SparseColMatRef::new(permuted.symbolic.as_ref(), &gathered);
                supernodal::factorize_supernodal_numeric_llt(
                    &mut values,
                    a,
                    regularization,
                    s,
                    par,
                    stack,
                    Default::default(),
                )
                .ok()?;
            }
            _ => {
                let mat = SparseColMatRef::new(self.symbolic.as_ref(), val);
                (sym.0)
                    .factorize_numeric_llt::<f64>(
                        &mut values,
                        mat,
                        Side::Lower,
                        regularization,
                        par,
                        stack,
                        Default::default(),
                    )
                    .ok()?;
            }
        }
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    /// The supernodal factor from the permuted pattern's gathered values solves the system as
    /// faer's own permutation of `A` does, to rounding; on a block pattern dense enough for the
    /// supernodal kernel (the path is taken) and on a chain (simplicial: faer's path).
    #[test]
    fn gathered_factor_solves_as_faer_permuted_one() {
        let mut rng = StdRng::seed_from_u64(3);
        let dense: Vec<(usize, usize)> = (0..600)
            .map(|_| (rng.random_range(0..80), rng.random_range(0..80)))
            .filter(|(p, q)| p != q)
            .collect();
        let chain: Vec<(usize, usize)> = (1..80).map(|p| (p, p - 1)).collect();
        for (pairs, supernodal) in [(dense, true), (chain, false)] {
            let pattern = BlockPattern::new(80, 3, pairs.iter().copied());
            let mut val = vec![0.0; pattern.nnz()];
            for &(p, q) in &pairs {
                let m = Matrix3::from_fn(|_, _| rng.random_range(-1.0..1.0));
                pattern.add(&mut val, p.max(q), p.min(q), pattern.slot(p, q), &m);
            }
            // diagonally dominant: positive definite
            pattern.add_diagonal(&mut val, 3.0 * 600.0);
            let sym = pattern.symbolic_llt().unwrap();
            let is_supernodal = matches!(sym.0.raw(), SymbolicCholeskyRaw::Supernodal(_));
            assert_eq!(is_supernodal, supernodal);
            let fast = pattern.llt(&sym, &val).unwrap();
            let mut reference = vec![0.0; sym.len_val()];
            let req = sym
                .0
                .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default());
            let mut mem = MemBuffer::new(req);
            sym.0
                .factorize_numeric_llt::<f64>(
                    &mut reference,
                    pattern.matrix(&val),
                    Side::Lower,
                    LltRegularization::default(),
                    Par::Seq,
                    MemStack::new(&mut mem),
                    Default::default(),
                )
                .unwrap();
            let reference = SparseLlt {
                symbolic: sym.clone(),
                values: reference,
            };
            let rhs = Mat::<f64>::from_fn(240, 2, |i, j| ((i * 7 + j * 3) % 11) as f64 - 5.0);
            let (mut x, mut y) = (rhs.clone(), rhs);
            fast.solve_in_place(x.as_mut());
            reference.solve_in_place(y.as_mut());
            let diff = (&x - &y).norm_max();
            assert!(diff <= 1e-12 * y.norm_max(), "{diff}");
        }
    }
}
