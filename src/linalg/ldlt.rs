//! A verified inertia: the sparse `LDL^T` factorisation of a symmetric matrix without pivoting
//! or regularisation, the number of its negative pivots, and a rigorous bound on its backward
//! error (`paper-notes/certificates.md`, `[D13]`). By Sylvester's law of inertia the pivots'
//! signs are the eigenvalues' signs of `P^T L D L^T P`, which is within the backward error of
//! the floating-point matrix.

use super::cholesky::{for_each_factor_entry, gamma};
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
    let n = a.nrows();
    let mut values = vec![0.0f64; symbolic.len_val()];
    let par = super::factor_parallelism(symbolic.len_val());
    let req = symbolic.factorize_numeric_ldlt_scratch::<f64>(par, Default::default());
    let mut mem = MemBuffer::try_new(req).map_err(|_| LdltFailure::Numerical)?;
    // Soundness: `LdltRegularization::default()` has delta = epsilon = 0 and no signs, and faer
    // only alters pivots when both are > 0 (faer 0.24, ldlt/factor.rs); a zero pivot is an error.
    symbolic
        .factorize_numeric_ldlt::<f64>(
            &mut values,
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
    // visit (row, col, value) of the factor: diagonal entries are D, strictly lower ones L
    let visit = |f: &mut dyn FnMut(usize, usize, f64)| for_each_factor_entry(symbolic, &values, f);
    let mut d = vec![0.0f64; n];
    let mut colsum = vec![1.0f64; n]; // the unit diagonal of L
    let mut rowcount = vec![1usize; n];
    visit(&mut |r, c, v| {
        if r == c {
            d[c] = v;
        } else {
            colsum[c] += v.abs();
            rowcount[r] += 1;
        }
    });
    if d.iter().any(|&v| v == 0.0 || !v.is_finite()) {
        return Err(LdltFailure::Numerical);
    }
    let negative = d.iter().filter(|&&v| v < 0.0).count();
    // row sums of |L| |D| |L|^T: sum_m |L_im| |d_m| colsum_m (including the unit diagonal)
    let mut rowsum: Vec<f64> = (0..n).map(|i| d[i].abs() * colsum[i]).collect();
    visit(&mut |r, c, v| {
        if r != c {
            rowsum[r] += v.abs() * d[c].abs() * colsum[c];
        }
    });
    let k = rowcount.iter().copied().max().unwrap_or(1);
    let ldl_norm = rowsum.into_iter().fold(0.0, f64::max);
    let backward_error = 2.0 * gamma(k + 4) * ldl_norm;
    if !backward_error.is_finite() {
        return Err(LdltFailure::Numerical);
    }
    Ok(Inertia {
        negative,
        backward_error,
    })
}
