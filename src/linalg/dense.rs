//! Dense symmetric eigenproblems and Cholesky solves of `nalgebra` matrices through faer's
//! blocked kernels: the simultaneous problem's dense certificate `[H15]` (`3n x 3n`). At
//! `3n = 3000` faer takes 1.1 s for the eigenvalues where nalgebra's unblocked QR iteration
//! takes 9.6 s (this 2-core machine, 2026-12-01). Both are backward stable; the callers' error
//! bounds (`10 (3n) eps ||Z||_F`, `paper-notes/conjugate.md` `[H14]`) are the same for either.

use faer::{MatRef, Side};
use nalgebra::{DMatrix, DVector};

fn view(m: &DMatrix<f64>) -> MatRef<'_, f64> {
    MatRef::from_column_major_slice(m.as_slice(), m.nrows(), m.ncols())
}

/// The eigenvalues of the symmetric matrix `m` (its lower triangle is read), ascending; `None`
/// when the solver does not converge or `m` is not square.
pub fn symmetric_eigenvalues(m: &DMatrix<f64>) -> Option<Vec<f64>> {
    if !m.is_square() {
        return None;
    }
    view(m).self_adjoint_eigenvalues(Side::Lower).ok()
}

/// The eigenvalues (ascending) and unit eigenvectors (the columns, in the same order) of the
/// symmetric matrix `m` (its lower triangle is read); `None` when the solver does not converge
/// or `m` is not square.
pub fn symmetric_eigen(m: &DMatrix<f64>) -> Option<(Vec<f64>, DMatrix<f64>)> {
    if !m.is_square() {
        return None;
    }
    let evd = view(m).self_adjoint_eigen(Side::Lower).ok()?;
    let (s, u) = (evd.S(), evd.U());
    let values = (0..m.nrows()).map(|k| s[k]).collect();
    let vectors = DMatrix::from_fn(m.nrows(), m.ncols(), |r, c| u[(r, c)]);
    Some((values, vectors))
}

/// The Cholesky factorisation of a symmetric positive definite matrix (its lower triangle).
pub struct DenseCholesky {
    llt: faer::linalg::solvers::Llt<f64>,
}

impl DenseCholesky {
    /// `None` when `m` is not square or not numerically positive definite.
    pub fn new(m: &DMatrix<f64>) -> Option<Self> {
        if !m.is_square() {
            return None;
        }
        view(m)
            .llt(Side::Lower)
            .ok()
            .map(|llt| DenseCholesky { llt })
    }

    /// `||L||_F^2` of the computed factor `L` (`m ~ L L^T`): with Higham's Thm 10.3 it bounds
    /// the backward error, `lambda_min(m) >= -gamma(d + 1) ||L||_F^2`.
    pub fn factor_norm_squared(&self) -> f64 {
        let l = self.llt.L();
        let mut sum = 0.0;
        for c in 0..l.ncols() {
            for r in c..l.nrows() {
                sum += l[(r, c)] * l[(r, c)];
            }
        }
        sum
    }

    /// `m^-1 b`.
    pub fn solve(&self, b: &DVector<f64>) -> DVector<f64> {
        use faer::linalg::solvers::Solve;
        let x = self
            .llt
            .solve(MatRef::from_column_major_slice(b.as_slice(), b.len(), 1));
        DVector::from_fn(b.len(), |r, _| x[(r, 0)])
    }
}

/// An orthonormal basis of the first `first` columns of `a` and, with `more`, the first columns
/// of another matrix (a thin QR; nearly dependent columns are kept: the model only needs a
/// spanning set of orthonormal columns, which Householder's `Q` is).
pub(crate) fn orthonormal_columns(
    a: &DMatrix<f64>,
    first: usize,
    more: Option<(&DMatrix<f64>, usize)>,
) -> DMatrix<f64> {
    let first = first.min(a.ncols());
    let extra = more.map_or(0, |(m, k)| k.min(m.ncols()));
    let mut stacked = DMatrix::zeros(a.nrows(), first + extra);
    stacked
        .columns_mut(0, first)
        .copy_from(&a.columns(0, first));
    if let Some((m, _)) = more {
        stacked
            .columns_mut(first, extra)
            .copy_from(&m.columns(0, extra));
    }
    stacked.qr().q()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against nalgebra's own solvers on a random symmetric matrix (an indefinite one for the
    /// eigenvalues, a positive definite one for the solve): the same spectrum, `A v = lambda v`
    /// and `A x = b` to rounding.
    #[test]
    fn agrees_with_nalgebra() {
        let n = 40;
        let a = DMatrix::<f64>::from_fn(n, n, |r, c| (((r * 7 + c * 13) % 17) as f64) - 8.0);
        let a = &a + a.transpose();
        let mut ours = symmetric_eigenvalues(&a).unwrap();
        let mut theirs: Vec<f64> = a.clone().symmetric_eigenvalues().iter().copied().collect();
        theirs.sort_by(f64::total_cmp);
        ours.sort_by(f64::total_cmp);
        for (x, y) in ours.iter().zip(&theirs) {
            assert!((x - y).abs() < 1e-10 * a.norm(), "{x} vs {y}");
        }
        let (values, vectors) = symmetric_eigen(&a).unwrap();
        assert!(values.windows(2).all(|w| w[0] <= w[1]));
        for (k, l) in values.iter().enumerate() {
            let v = vectors.column(k);
            assert!((&a * v - v * *l).norm() < 1e-10 * a.norm());
            assert!((v.norm() - 1.0).abs() < 1e-12);
        }
        let spd = &a * a.transpose() + DMatrix::identity(n, n);
        let b = DVector::from_fn(n, |r, _| r as f64 - 3.0);
        let x = DenseCholesky::new(&spd).unwrap().solve(&b);
        assert!((&spd * &x - &b).norm() < 1e-9 * b.norm());
        assert!(DenseCholesky::new(&a).is_none(), "indefinite");
        assert!(symmetric_eigenvalues(&DMatrix::zeros(2, 3)).is_none());
    }
}
