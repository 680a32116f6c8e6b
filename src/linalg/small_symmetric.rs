//! A proven lower bound on the smallest eigenvalue of a small dense symmetric matrix (the `6 x 6`
//! edge comparisons of the block comparison `[A15]`, `paper-notes/anisotropic.md`): a Cholesky
//! factorisation of `A + sigma I` in floating point with Higham's backward error bound.

use super::cholesky::{UNIT_ROUNDOFF, gamma};
use nalgebra::{Matrix3, Matrix6, SMatrix};

/// A proven lower bound `l <= lambda_min(A)` for the symmetric `6 x 6` matrix `A`
/// whose lower triangle is `a`'s (the upper is not read), or `None` for non-finite entries.
///
/// With `sigma` chosen just past minus an eigenvalue estimate, the Cholesky factorisation of
/// `B = fl(A + sigma I)` runs to completion with positive pivots; its computed factor
/// satisfies `L L^T = B + dB` with `|dB| <= gamma(N + 1) |L| |L^T|` (Higham, *Accuracy and
/// Stability of Numerical Algorithms*, 2nd ed., Thm 10.3), so `B + dB` is positive semidefinite
/// and `lambda_min(A) >= -sigma - ||dB||_2 - ||B - (A + sigma I)||_2`, each norm bounded by a
/// Frobenius norm of entrywise bounds. Retried with larger shifts when the factorisation
/// breaks down (an estimate that was too optimistic).
pub(crate) fn verified_min_eigenvalue(a: &Matrix6<f64>) -> Option<f64> {
    let a = Matrix6::<f64>::from_fn(|r, c| if r >= c { a[(r, c)] } else { a[(c, r)] });
    let estimate = a.symmetric_eigenvalues().min();
    verified_from_estimate(&a, estimate)
}

/// A proven lower bound `l <= min(lambda_min(A), 0)` for the symmetric `6 x 6` matrix `A` whose
/// lower triangle is `a`'s, or `None` for non-finite entries: for callers that use only the
/// negative part of the bound (a charge `max(-l, 0)`). A matrix positive semidefinite to within
/// `1e-12 ||A||_F` (half the block comparison's edge checks at a solution of 10^4 cameras and
/// 10^5 edges: 51,841 of its first 100,000) gives about `-1e-12 ||A||_F` from one Cholesky
/// factorisation of `A + 1e-12 ||A||_F I`, without the eigenvalue estimate (1.4 us each on
/// this machine); any other, its [`verified_min_eigenvalue`] (at most 0).
pub(crate) fn verified_negative_part(a: &Matrix6<f64>) -> Option<f64> {
    let a = Matrix6::<f64>::from_fn(|r, c| if r >= c { a[(r, c)] } else { a[(c, r)] });
    if !a.iter().all(|x| x.is_finite()) {
        return None;
    }
    let scale = a.norm();
    if scale > 0.0
        && let Some(bound) = shifted_bound(&a, 1e-12 * scale)
    {
        return Some(bound.min(0.0));
    }
    verified_min_eigenvalue(&a).map(|l| l.min(0.0))
}

/// [`verified_min_eigenvalue`] of a `3 x 3` matrix.
pub(crate) fn verified_min_eigenvalue3(a: &Matrix3<f64>) -> Option<f64> {
    let a = Matrix3::<f64>::from_fn(|r, c| if r >= c { a[(r, c)] } else { a[(c, r)] });
    let estimate = a.symmetric_eigenvalues().min();
    verified_from_estimate(&a, estimate)
}

/// The bound for the symmetric `a` (both triangles equal) from an estimate of its smallest
/// eigenvalue (which only chooses the shift).
fn verified_from_estimate<const N: usize>(a: &SMatrix<f64, N, N>, estimate: f64) -> Option<f64> {
    if !a.iter().all(|x| x.is_finite()) || !estimate.is_finite() {
        return None;
    }
    let scale = a.norm();
    if scale == 0.0 {
        return Some(0.0);
    }
    // a shift just past the estimate (negative for a positive definite matrix, whose bound
    // is then positive), larger after every breakdown
    let mut margin = 1e-12 * scale;
    for _ in 0..12 {
        if let Some(bound) = shifted_bound(a, margin - estimate) {
            return Some(bound);
        }
        margin *= 8.0;
    }
    None
}

/// `-sigma - ||dB|| - forming error` when the Cholesky factorisation of `fl(A + sigma I)`
/// completes with positive pivots.
fn shifted_bound<const N: usize>(a: &SMatrix<f64, N, N>, sigma: f64) -> Option<f64> {
    let mut b = *a;
    let mut forming = 0.0f64;
    for k in 0..N {
        b[(k, k)] += sigma;
        forming = forming.max(UNIT_ROUNDOFF * (a[(k, k)].abs() + sigma.abs()));
    }
    let mut l = SMatrix::<f64, N, N>::zeros();
    for j in 0..N {
        let mut d = b[(j, j)];
        for k in 0..j {
            d -= l[(j, k)] * l[(j, k)];
        }
        if d.is_nan() || d <= 0.0 || !d.is_finite() {
            return None;
        }
        let djj = d.sqrt();
        l[(j, j)] = djj;
        for i in j + 1..N {
            let mut s = b[(i, j)];
            for k in 0..j {
                s -= l[(i, k)] * l[(j, k)];
            }
            l[(i, j)] = s / djj;
        }
    }
    let abs_l = l.abs();
    let backward = gamma(N + 1) * (abs_l * abs_l.transpose()).norm();
    let loss = backward * (1.0 + 8.0 * UNIT_ROUNDOFF) + forming * N as f64;
    // -sigma - loss, rounded down
    let bound = (-sigma - loss) - 4.0 * UNIT_ROUNDOFF * (sigma.abs() + loss);
    bound.is_finite().then_some(bound)
}

#[cfg(test)]
mod tests {
    use super::{verified_min_eigenvalue, verified_negative_part};
    use nalgebra::{Matrix6, SymmetricEigen};

    /// Planted spectra under random orthogonal changes of basis: the bound is below the true
    /// smallest eigenvalue (or below 0 for a positive one) and within a tiny margin of it.
    #[test]
    fn the_bound_is_below_and_close_to_the_smallest_eigenvalue() {
        let mut seed = 7u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        };
        for case in 0..200 {
            let g = Matrix6::from_fn(|_, _| next());
            let q = g.qr().q();
            let spread = 10f64.powi(case % 12 - 4);
            let eig: Vec<f64> = (0..6).map(|k| (next() + 0.3 * k as f64) * spread).collect();
            let d = Matrix6::from_diagonal(&nalgebra::Vector6::from_iterator(eig.iter().copied()));
            let a = q * d * q.transpose();
            let a = 0.5 * (a + a.transpose());
            let exact = SymmetricEigen::new(a).eigenvalues.min();
            let bound = verified_min_eigenvalue(&a).expect("finite");
            assert!(bound <= exact + 1e-13 * spread, "{bound} vs {exact}");
            assert!(bound >= exact - 1e-9 * spread, "{bound} vs {exact}");
            // the negative part: below min(exact, 0), within 1e-11 of the matrix's scale
            let part = verified_negative_part(&a).expect("finite");
            assert!(part <= exact.min(0.0), "{part} vs {exact}");
            assert!(
                part >= exact.min(0.0) - 1e-11 * a.norm(),
                "{part} vs {exact}"
            );
        }
        assert_eq!(verified_min_eigenvalue(&Matrix6::zeros()), Some(0.0));
        assert_eq!(verified_negative_part(&Matrix6::zeros()), Some(0.0));
        let mut bad = Matrix6::identity();
        bad[(3, 2)] = f64::NAN;
        assert_eq!(verified_min_eigenvalue(&bad), None);
    }
}
