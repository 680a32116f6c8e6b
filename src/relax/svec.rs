//! The symmetric-matrix vectorisation used by Clarabel's `PSDTriangleConeT` (`paper-notes/sdp.md`,
//! `[P1]`): the upper triangle, column by column, off-diagonal entries multiplied by `sqrt(2)`,
//! so that `<svec(A), svec(B)> = tr(A B)` for symmetric `A`, `B`.

use faer::{Mat, MatRef};

/// Length of `svec` of an `n x n` symmetric matrix: `n (n + 1) / 2`.
pub fn svec_len(n: usize) -> usize {
    n * (n + 1) / 2
}

/// Position of entry `(i, j)` (either order) in `svec` of a symmetric matrix.
///
/// ```
/// use rotavg::relax::svec::svec_index;
/// // column 0: (0,0); column 1: (0,1), (1,1); column 2: (0,2), (1,2), (2,2)
/// assert_eq!(svec_index(1, 1), 2);
/// assert_eq!(svec_index(2, 0), 3);
/// ```
pub fn svec_index(i: usize, j: usize) -> usize {
    let (i, j) = if i <= j { (i, j) } else { (j, i) };
    j * (j + 1) / 2 + i
}

/// `(i, j)`, `i <= j`, of `svec` row `row` (the inverse of [`svec_index`]).
pub(crate) fn svec_entry(row: usize) -> (usize, usize) {
    let mut j = 0;
    while (j + 1) * (j + 2) / 2 <= row {
        j += 1;
    }
    (row - j * (j + 1) / 2, j)
}

/// Weight of entry `(i, j)` in `svec`: `1` on the diagonal, `sqrt(2)` off it.
pub fn svec_weight(i: usize, j: usize) -> f64 {
    if i == j {
        1.0
    } else {
        std::f64::consts::SQRT_2
    }
}

/// `svec` of a symmetric matrix (only the upper triangle is read).
///
/// ```
/// use faer::Mat;
/// use rotavg::relax::svec::{smat, svec};
/// let a = Mat::from_fn(2, 2, |i, j| if i == j { 1.0 } else { 3.0 });
/// let v = svec(a.as_ref());
/// assert_eq!(v, vec![1.0, 3.0 * 2f64.sqrt(), 1.0]);
/// // <svec A, svec A> = tr(A A) = 1 + 9 + 9 + 1
/// assert!((v.iter().map(|x| x * x).sum::<f64>() - 20.0).abs() < 1e-12);
/// assert!((smat(&v, 2).unwrap() - &a).norm_max() < 1e-15);
/// ```
pub fn svec(a: MatRef<'_, f64>) -> Vec<f64> {
    let n = a.nrows();
    let mut v = Vec::with_capacity(svec_len(n));
    for j in 0..n {
        for i in 0..=j {
            v.push(a[(i, j)] * svec_weight(i, j));
        }
    }
    v
}

/// Inverse of [`svec`]: the symmetric `n x n` matrix. Returns `None` if `v.len() != n(n+1)/2`.
pub fn smat(v: &[f64], n: usize) -> Option<Mat<f64>> {
    if v.len() != svec_len(n) {
        return None;
    }
    let mut a = Mat::zeros(n, n);
    for j in 0..n {
        for i in 0..=j {
            let x = v[svec_index(i, j)] / svec_weight(i, j);
            a[(i, j)] = x;
            a[(j, i)] = x;
        }
    }
    Some(a)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inner_product_is_trace() {
        // <svec A, svec B> = tr(AB) is the defining property [P1].
        let a = Mat::from_fn(4, 4, |i, j| (i + j) as f64 + 0.5 * (i * j) as f64);
        let b = Mat::from_fn(4, 4, |i, j| 1.0 / (1.0 + i as f64 + j as f64));
        let dot: f64 = svec(a.as_ref())
            .iter()
            .zip(svec(b.as_ref()))
            .map(|(x, y)| x * y)
            .sum();
        let tr: f64 = (0..4)
            .map(|i| (0..4).map(|k| a[(i, k)] * b[(k, i)]).sum::<f64>())
            .sum();
        assert!((dot - tr).abs() < 1e-12);
        let back = smat(&svec(a.as_ref()), 4).unwrap();
        assert!((back - &a).norm_max() < 1e-14);
        assert!(smat(&[1.0, 2.0], 2).is_none());
    }
}
