//! A verified inertia: the sparse `LDL^T` factorisation of a symmetric matrix without pivoting
//! or regularisation, the number of its negative pivots, and a rigorous bound on its backward
//! error (`paper-notes/certificates.md`, `[D13]`). By Sylvester's law of inertia the pivots'
//! signs are the eigenvalues' signs of `P^T L D L^T P`, which is within the backward error of
//! the floating-point matrix.

use super::cholesky::{for_each_factor_column, gamma};
use faer::Side;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::ldlt::factor::LdltRegularization;
use faer::sparse::SparseColMatRef;
use faer::sparse::linalg::cholesky::SymbolicCholesky;

/// The inertia of a factorised matrix, with its backward error.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Inertia {
    /// Number of negative pivots of `D` (= negative eigenvalues of `P^T L D L^T P`).
    pub negative: usize,
    /// Rigorous bound on `||A - P^T L D L^T P||_2` for the floating-point `A` that was
    /// factorised: `2 gamma(k + 4) || |L| |D| |L^T| ||_inf` (Higham, Thm 10.5 and its `LDL^T`
    /// analogue; `k` the largest row count of `L`), doubled to cover evaluating the bound.
    pub backward_error: f64,
}

/// Why no inertia could be certified.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum LdltFailure {
    /// A zero or non-finite pivot, or a failed factorisation (no claim is made).
    Numerical,
}

/// `LDL^T` of the symmetric `a` (lower triangle read) with the given symbolic analysis (fill
/// reducing order, no pivoting), and its verified inertia.
pub(crate) fn ldlt_inertia(
    symbolic: &SymbolicCholesky<usize>,
    a: SparseColMatRef<'_, usize, f64>,
) -> Result<Inertia, LdltFailure> {
    let rows = ldlt_inertia_by_row(symbolic, a)?;
    let backward_error = rows.backward.iter().copied().fold(0.0, f64::max);
    Ok(Inertia {
        negative: rows.negative,
        backward_error,
    })
}

/// The inertia of a factorised matrix with its backward error row by row: with `Delta` the
/// difference between `P^T L D L^T P` and the floating-point `A`, `x^T Delta x <= sum_i
/// backward[i] x_i^2` for every `x` (`|Delta| <= N` entrywise with `N` symmetric, and
/// `2 |x_i| |x_j| <= x_i^2 + x_j^2`: the row sums of `N`), rows in `A`'s own order.
pub(crate) struct RowInertia {
    /// Number of negative pivots of `D`.
    pub negative: usize,
    /// `2 gamma(k + 4)` times the row sums of `P^T |L| |D| |L^T| P`, in `A`'s order.
    pub backward: Vec<f64>,
    /// The pivots `D`, by elimination position.
    pub pivots: Vec<f64>,
}

/// [`ldlt_inertia`] with the backward error of every row ([`RowInertia`]).
pub(crate) fn ldlt_inertia_by_row(
    symbolic: &SymbolicCholesky<usize>,
    a: SparseColMatRef<'_, usize, f64>,
) -> Result<RowInertia, LdltFailure> {
    let mut storage = FactorStorage::default();
    let values = ldlt_values(symbolic, a, &mut storage)?;
    row_inertia(symbolic, values, a.nrows())
}

/// The storage of a factor's values, kept across the factorisations of a sequence (a region's
/// and the next region's): a fresh allocation of a large factor is mapped by the kernel page by
/// page as the factorisation first writes it (at 10^4 cameras, 5e7 bytes per region and about
/// a tenth of the certificate's time in page faults).
#[derive(Default)]
pub(crate) struct FactorStorage {
    values: Vec<f64>,
}

/// [`ldlt_inertia`], and when the negative pivots are not `expected` but at most `most`, the columns `L e_k`
/// of the factor at the negative pivots `k`, in `A`'s order (sparse: `(row, value)`): `y^T
/// P^T L D L^T P y >= 0` for every `y` orthogonal to all of them (`u = L^T P y` is zero at
/// every negative pivot). Only a choice of directions for a later, verified factorisation.
pub(crate) fn ldlt_negative_columns(
    symbolic: &SymbolicCholesky<usize>,
    a: SparseColMatRef<'_, usize, f64>,
    (expected, most): (usize, usize),
    storage: &mut FactorStorage,
) -> Result<(Inertia, NegativePivots), LdltFailure> {
    let n = a.nrows();
    let values = ldlt_values(symbolic, a, storage)?;
    let rows = row_inertia(symbolic, values, n)?;
    let inertia = Inertia {
        negative: rows.negative,
        backward_error: rows.backward.iter().copied().fold(0.0, f64::max),
    };
    if rows.negative == expected || rows.negative > most {
        return Ok((inertia, NegativePivots::default()));
    }
    let fwd: Vec<usize> = match symbolic.perm() {
        Some(perm) => perm.arrays().0.to_vec(),
        None => (0..n).collect(),
    };
    let mut at = vec![usize::MAX; n];
    let mut columns: Vec<NegativeColumn> = Vec::new();
    for (c, &v) in rows.pivots.iter().enumerate() {
        if v < 0.0 {
            at[c] = columns.len();
            columns.push(NegativeColumn {
                pivot: v,
                entries: vec![(fwd[c], 1.0)],
            });
        }
    }
    let last = n.saturating_sub(TRAILING);
    let mut trailing = Trailing {
        rows: fwd[last..].to_vec(),
        pivots: vec![0.0; n - last],
        lower: vec![vec![0.0; n - last]; n - last],
    };
    // only the columns at negative pivots and the trailing ones are read
    for_each_factor_column(symbolic, values, |column| {
        let c = column.col;
        if at[c] == usize::MAX && c < last {
            return;
        }
        column.entries().for_each(|(r, v)| {
            if r != c && at[c] != usize::MAX {
                columns[at[c]].entries.push((fwd[r], v));
            }
            if c >= last {
                if r == c {
                    trailing.pivots[c - last] = v;
                } else {
                    trailing.lower[r - last][c - last] = v;
                }
            }
        });
    });
    Ok((inertia, NegativePivots { columns, trailing }))
}

/// A negative pivot `d_k` of an `LDL^T` and its column `P^T L e_k` (the stored values exactly,
/// `(row, value)` in the matrix's own order, the unit diagonal first).
pub(crate) struct NegativeColumn {
    pub pivot: f64,
    pub entries: Vec<(usize, f64)>,
}

/// The positions last in the elimination order that [`NegativePivots::trailing`] reports.
pub(crate) const TRAILING: usize = 3;

/// The factor's columns at its negative pivots and its last [`TRAILING`] positions.
#[derive(Default)]
pub(crate) struct NegativePivots {
    pub columns: Vec<NegativeColumn>,
    pub trailing: Trailing,
}

/// The last positions of the elimination: their rows in the matrix's order, their pivots and
/// the strictly lower entries of `L` among them (`lower[i][j]`, `i > j`; by position).
#[derive(Default)]
pub(crate) struct Trailing {
    pub rows: Vec<usize>,
    pub pivots: Vec<f64>,
    pub lower: Vec<Vec<f64>>,
}

/// An `LDL^T` factor (no pivoting, no regularisation) kept for solves: shift-invert
/// *estimates* of a symmetric indefinite matrix's eigenvectors (the large rigs' couplings
/// search, `certify::rig::wide`). No bound is claimed from it.
pub(crate) struct LdltSolver {
    symbolic: SymbolicCholesky<usize>,
    values: Vec<f64>,
}

impl LdltSolver {
    /// The factor of `a` (both triangles stored), or `None` when its analysis predicts more
    /// than `max_values` values or a pivot is zero or not finite.
    pub fn new(
        a: SparseColMatRef<'_, usize, f64>,
        max_values: usize,
    ) -> crate::Result<Option<Self>> {
        let Ok(symbolic) = super::cholesky::symbolic_cholesky_within(a.symbolic(), max_values)?
        else {
            return Ok(None);
        };
        let mut storage = FactorStorage::default();
        if ldlt_values(&symbolic, a, &mut storage).is_err() {
            return Ok(None);
        }
        Ok(Some(LdltSolver {
            symbolic,
            values: storage.values,
        }))
    }

    /// The number of negative pivots of `D`: by Sylvester's law the negative eigenvalues of the
    /// factorised matrix (no bound on its backward error: an estimate, as the solves are).
    pub fn negative_pivots(&self) -> usize {
        let mut negative = 0;
        for_each_factor_column(&self.symbolic, &self.values, |column| {
            let c = column.col;
            negative += column.entries().filter(|&(r, v)| r == c && v < 0.0).count();
        });
        negative
    }

    /// `b <- a^-1 b` for every column of `b` (one pass over the factor for all of them).
    pub fn solve_columns(&self, b: faer::MatMut<'_, f64>) {
        let par = faer::Par::Seq;
        let req = self.symbolic.solve_in_place_scratch::<f64>(b.ncols(), par);
        let mut mem = MemBuffer::new(req);
        faer::sparse::linalg::cholesky::LdltRef::<usize, f64>::new(&self.symbolic, &self.values)
            .solve_in_place_with_conj(faer::Conj::No, b, par, MemStack::new(&mut mem));
    }
}

/// The factor values of `LDL^T` (no pivoting, no regularisation), all finite, in `storage`.
fn ldlt_values<'s>(
    symbolic: &SymbolicCholesky<usize>,
    a: SparseColMatRef<'_, usize, f64>,
    storage: &'s mut FactorStorage,
) -> Result<&'s [f64], LdltFailure> {
    let values = &mut storage.values;
    values.clear();
    values.resize(symbolic.len_val(), 0.0);
    let par = super::factor_parallelism(symbolic.len_val());
    let req = symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default());
    let mut mem = MemBuffer::try_new(req).map_err(|_| LdltFailure::Numerical)?;
    // Soundness: `LdltRegularization::default()` has delta = epsilon = 0 and no signs, and faer
    // only alters pivots when both are > 0 (faer 0.24, ldlt/factor.rs); a zero pivot is an error.
    symbolic
        .factorize_numeric_ldlt::<f64>(
            values,
            a,
            Side::Lower,
            LdltRegularization::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .map_err(|_| LdltFailure::Numerical)?;
    if !values.iter().all(|v| v.is_finite()) {
        return Err(LdltFailure::Numerical);
    }
    Ok(&storage.values)
}

/// The inertia and row-wise backward error of the factor `values` of an `n x n` matrix.
fn row_inertia(
    symbolic: &SymbolicCholesky<usize>,
    values: &[f64],
    n: usize,
) -> Result<RowInertia, LdltFailure> {
    // visit (row, col, value) of the factor: diagonal entries are D, strictly lower ones L
    let mut d = vec![0.0f64; n];
    let mut colsum = vec![1.0f64; n]; // the unit diagonal of L
    let mut rowcount = vec![1usize; n];
    // row sums of |L| |D| |L|^T: sum_m |L_im| |d_m| colsum_m (the unit diagonal's term last),
    // in one pass: a column's sum is complete before its entries are added to their rows
    let mut rowsum = vec![0.0f64; n];
    for_each_factor_column(symbolic, values, |column| {
        let c = column.col;
        column.entries().for_each(|(r, v)| {
            if r == c {
                d[c] = v;
            } else {
                colsum[c] += v.abs();
                rowcount[r] += 1;
            }
        });
        column.entries().for_each(|(r, v)| {
            if r != c {
                rowsum[r] += v.abs() * d[c].abs() * colsum[c];
            }
        });
    });
    if d.iter().any(|&v| v == 0.0 || !v.is_finite()) {
        return Err(LdltFailure::Numerical);
    }
    let negative = d.iter().filter(|&&v| v < 0.0).count();
    for (i, s) in rowsum.iter_mut().enumerate() {
        *s += d[i].abs() * colsum[i];
    }
    let k = rowcount.iter().copied().max().unwrap_or(1);
    let scale = 2.0 * gamma(k + 4);
    // row r of the factor is row perm_fwd[r] of `a` (P A P^T, faer's forward permutation)
    let mut backward = vec![0.0f64; n];
    match symbolic.perm() {
        Some(perm) => {
            let (fwd, _) = perm.arrays();
            for (r, s) in rowsum.iter().enumerate() {
                backward[fwd[r]] = scale * s;
            }
        }
        None => backward
            .iter_mut()
            .zip(&rowsum)
            .for_each(|(b, s)| *b = scale * s),
    }
    if !backward.iter().all(|b| b.is_finite()) {
        return Err(LdltFailure::Numerical);
    }
    Ok(RowInertia {
        negative,
        backward,
        pivots: d,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::cholesky::symbolic_cholesky_within;
    use faer::sparse::{SparseColMat, Triplet};

    /// An arrow matrix (node 0 joined to every other) is ordered with its hub last, so the
    /// factor's rows are permuted; the row bounds must come back in the matrix's own order.
    /// In exact arithmetic a leaf's row sum of `|L| |D| |L^T|` is `a_ii + 1/2` and the hub's
    /// `1 + (n - 1) / 2` (its pivot `1 - sum 1 / (4 a_ii)` plus `1/2 + 1 / (4 a_ii)` per leaf):
    /// every ratio to those must be the same scale.
    /// Off the factor's columns at its negative pivots the matrix is positive semidefinite:
    /// dense eigenvalues of `Q^T A Q` (`Q` an orthonormal basis of their complement), on a
    /// simplicial factor and a supernodal one (the last case).
    #[test]
    fn the_negative_columns_deflate_every_negative_eigenvalue() {
        use nalgebra::DMatrix;
        for (n, density, seed) in [(30usize, 0.2f64, 1u64), (120, 0.5, 2), (300, 20.0, 3)] {
            let mut state = seed;
            let mut next = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 11) as f64) / ((1u64 << 53) as f64)
            };
            let mut dense = DMatrix::<f64>::zeros(n, n);
            for i in 0..n {
                dense[(i, i)] = 4.0 * next() - 0.5;
                for j in 0..i {
                    if next() < density * 4.0 / n as f64 {
                        let v = next() - 0.5;
                        dense[(i, j)] = v;
                        dense[(j, i)] = v;
                    }
                }
            }
            let mut t = Vec::new();
            for i in 0..n {
                for j in 0..n {
                    if dense[(i, j)] != 0.0 {
                        t.push(Triplet::new(i, j, dense[(i, j)]));
                    }
                }
            }
            let a = SparseColMat::try_new_from_triplets(n, n, &t).unwrap();
            let sym = symbolic_cholesky_within(a.symbolic(), usize::MAX)
                .unwrap()
                .unwrap();
            let (rows, found) = ldlt_negative_columns(
                &sym,
                a.as_ref(),
                (usize::MAX, n),
                &mut FactorStorage::default(),
            )
            .unwrap();
            let cols = found.columns;
            let eig = dense.clone().symmetric_eigen().eigenvalues;
            let negative = eig.iter().filter(|v| **v < 0.0).count();
            assert_eq!(rows.negative, negative);
            assert_eq!(cols.len(), negative);
            let mut c = DMatrix::<f64>::zeros(n, negative.max(1));
            for (k, col) in cols.iter().enumerate() {
                assert!(col.pivot < 0.0);
                for &(r, v) in &col.entries {
                    c[(r, k)] = v;
                }
            }
            // complement of span(C) by the SVD
            let svd = c.clone().svd(true, false);
            let u = svd.u.unwrap();
            let full = DMatrix::<f64>::identity(n, n) - &u * u.transpose();
            let e = full.clone().symmetric_eigen();
            let q: Vec<_> = (0..n)
                .filter(|&i| e.eigenvalues[i] > 0.5)
                .map(|i| e.eigenvectors.column(i).into_owned())
                .collect();
            let q = DMatrix::from_columns(&q);
            let restricted = q.transpose() * &dense * &q;
            let low = restricted.symmetric_eigen().eigenvalues.min();
            assert!(
                low > -1e-10,
                "n {n}: {negative} negatives, restricted min {low}"
            );
        }
    }

    #[test]
    fn row_bounds_come_back_in_the_matrix_order() {
        let n = 12;
        let mut t = vec![Triplet::new(0, 0, 1.0)];
        for i in 1..n {
            t.push(Triplet::new(i, i, 4.0 + i as f64));
            t.push(Triplet::new(i, 0, 0.5));
            t.push(Triplet::new(0, i, 0.5));
        }
        let a = SparseColMat::try_new_from_triplets(n, n, &t).unwrap();
        let sym = symbolic_cholesky_within(a.symbolic(), usize::MAX)
            .unwrap()
            .unwrap();
        let fwd = sym.perm().map(|p| p.arrays().0.to_vec()).unwrap();
        assert_ne!(fwd[0], 0, "the hub is not ordered first");
        let rows = ldlt_inertia_by_row(&sym, a.as_ref()).unwrap();
        assert_eq!(rows.negative, 0);
        let exact: Vec<f64> = (0..n)
            .map(|i| {
                if i == 0 {
                    1.0 + 0.5 * (n - 1) as f64
                } else {
                    4.5 + i as f64
                }
            })
            .collect();
        let scale = rows.backward[0] / exact[0];
        for (b, e) in rows.backward.iter().zip(&exact) {
            assert!((b / e / scale - 1.0).abs() < 1e-12, "{:?}", rows.backward);
        }
    }
}
