//! The verified offsets of the `conv(SO(3))` dual certificate's surrogate
//! (`paper-notes/anisotropic.md` `[A11]`, Statement 1 and "The offsets, in the estimate's
//! frame"): for an edge's data `(R, H)` and its surrogate's `(R', H')`, a verified upper bound
//! on `delta = max over SO(3) of (f'_e - f_e) = 2 tr H' - 2 tr H + h(D)`, `D = N - N'`,
//! `N = R (2 tr(H) I - 4 H)`, `h(D) = max over R in SO(3) of <D, R>`.
//!
//! Two bounds, the smaller taken: the singular values of `D` in floating point
//! ([`special_support`], errors of size `u ||D||`), and the bound in the estimate's frame `Z`
//! ([`framed_offset`]): `D` and `Q = Z^T D` in double-double, `h(Q) <= tr Q + sqrt(4 |q|^2 +
//! mu^2) - mu` (`q` the skew part's vector, `mu <= lambda_min(tr(Q_s) I - Q_s)`), whose
//! rounding is of size `u^2 ||D||` and whose slack is second order in `q` when `mu > 0`. With
//! information eigenvalues of `1e8` the first loses about `2e-6` per edge, the second about
//! `1e-10`: the difference between a gap and a certificate on strongly anisotropic SLAM graphs.

use crate::linalg::compensated::{Accumulator, two_sum};
use crate::linalg::small_symmetric::verified_min_eigenvalue3;
use crate::linalg::{UNIT_ROUNDOFF, gamma};
use nalgebra::{Matrix3, Vector3};

/// A verified upper bound on `h(D) = max over SO(3) of <D, R> = s_1 + s_2 + sign(det D) s_3`
/// (the special orthogonal Procrustes problem), for `D` as computed: the singular values'
/// backward error `64 u ||D||_F` each, and `+s_3` when the sign of the determinant is not
/// certain.
///
/// ```
/// use rotavg::certify::multiple::conv_dual::special_support;
/// use nalgebra::{Matrix3, Vector3};
/// // h(I) = 3; a reflection's best rotation reaches only 1
/// assert!((special_support(&Matrix3::identity()) - 3.0).abs() < 1e-12);
/// let f = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
/// assert!((special_support(&f) - 1.0).abs() < 1e-12);
/// assert!(special_support(&f) >= 1.0);
/// ```
pub fn special_support(d: &Matrix3<f64>) -> f64 {
    let s = descending_singular_values(d);
    let norm = d.norm();
    let svd_error = 64.0 * UNIT_ROUNDOFF * norm;
    // the cofactor determinant's error bound: 6 triple products, 2 roundings each, 5 sums
    let perm = |m: &Matrix3<f64>| {
        let a = m.abs();
        a[(0, 0)] * (a[(1, 1)] * a[(2, 2)] + a[(1, 2)] * a[(2, 1)])
            + a[(0, 1)] * (a[(1, 0)] * a[(2, 2)] + a[(1, 2)] * a[(2, 0)])
            + a[(0, 2)] * (a[(1, 0)] * a[(2, 1)] + a[(1, 1)] * a[(2, 0)])
    };
    let det = d.determinant();
    let negative = det < -gamma(8) * perm(d) && s[2] > 2.0 * svd_error;
    let third = if negative { -s[2] } else { s[2] };
    round_up(s[0] + s[1] + third + 3.0 * svd_error)
}

/// The singular values of `d`, largest first (as computed).
fn descending_singular_values(d: &Matrix3<f64>) -> [f64; 3] {
    let mut s: [f64; 3] = d.svd(false, false).singular_values.into();
    s.sort_by(|a, b| b.total_cmp(a));
    s
}

/// `D = N - N'` in floating point: `r (2 tr(h) I - 4 h) - r2 (2 tr(h2) I - 4 h2)`.
fn rounded_difference(
    r: &Matrix3<f64>,
    h: &Matrix3<f64>,
    r2: &Matrix3<f64>,
    h2: &Matrix3<f64>,
) -> Matrix3<f64> {
    let a = Matrix3::identity() * (2.0 * h.trace()) - h * 4.0;
    let a2 = Matrix3::identity() * (2.0 * h2.trace()) - h2 * 4.0;
    r * a - r2 * a2
}

/// `x` raised by the rounding of a sum of up to four terms, whatever its sign (multiplying by
/// `1 + 4u` would lower a negative `x`).
pub(crate) fn round_up(x: f64) -> f64 {
    x + 4.0 * UNIT_ROUNDOFF * x.abs()
}

/// A verified upper bound on the offset `max over SO(3) of (f'_e - f_e)` of an edge with data
/// `(r, h)` and surrogate data `(r2, h2)` (matrices as stored), using `frame` (the estimate's
/// `X_e = R_j R_i^T`, any matrix near a rotation) for the second of the two bounds: the
/// smaller of [`svd_offset`] and [`framed_offset`].
pub(crate) fn edge_offset(
    r: &Matrix3<f64>,
    h: &Matrix3<f64>,
    r2: &Matrix3<f64>,
    h2: &Matrix3<f64>,
    frame: &Matrix3<f64>,
) -> f64 {
    let svd = svd_offset(r, h, r2, h2);
    match framed_offset(r, h, r2, h2, frame) {
        Some(framed) => svd.min(framed),
        None => svd,
    }
}

/// The offset by the singular values of `D` in floating point: `N`, `N'` formed with
/// `gamma(8)` of their magnitude each, `h` Lipschitz in the nuclear norm (`sqrt(3)` times the
/// Frobenius norm), [`special_support`].
pub(crate) fn svd_offset(
    r: &Matrix3<f64>,
    h: &Matrix3<f64>,
    r2: &Matrix3<f64>,
    h2: &Matrix3<f64>,
) -> f64 {
    let a = Matrix3::identity() * (2.0 * h.trace()) - h * 4.0;
    let a2 = Matrix3::identity() * (2.0 * h2.trace()) - h2 * 4.0;
    let d = rounded_difference(r, h, r2, h2);
    let magnitude = r.abs().norm() * a.abs().norm() + r2.abs().norm() * a2.abs().norm();
    let traces = 2.0 * h2.trace() - 2.0 * h.trace();
    let trace_error = gamma(4) * 2.0 * (h.abs().trace() + h2.abs().trace());
    let forming = 3f64.sqrt() * (gamma(8) * magnitude + UNIT_ROUNDOFF * d.norm());
    round_up(traces + special_support(&d) + trace_error + forming)
}

/// A `3 x 3` matrix in double-double, `hi + lo` entrywise, with `err` bounding each entry's
/// distance to the exact value it stands for.
struct Compensated {
    hi: Matrix3<f64>,
    lo: Matrix3<f64>,
    err: Matrix3<f64>,
}

impl Compensated {
    /// From nine accumulators (row-major), normalised (`|lo| <= u |hi|`, error-free).
    fn from_sums(sums: &[Accumulator; 9], extra: &Matrix3<f64>) -> Self {
        let mut out = Compensated {
            hi: Matrix3::zeros(),
            lo: Matrix3::zeros(),
            err: Matrix3::zeros(),
        };
        for (k, acc) in sums.iter().enumerate() {
            let (r, c) = (k / 3, k % 3);
            let (hi, lo) = acc.parts();
            let (s, t) = two_sum(hi, lo);
            out.hi[(r, c)] = s;
            out.lo[(r, c)] = t;
            out.err[(r, c)] = acc.parts_bound() + extra[(r, c)];
        }
        out
    }

    /// `a^T self`, `a` given as `hi + lo` (its error is the caller's).
    fn left_transpose_product(&self, a_hi: &Matrix3<f64>, a_lo: &Matrix3<f64>) -> Self {
        let mut sums = [Accumulator::default(); 9];
        let mut extra = Matrix3::zeros();
        for (k, acc) in sums.iter_mut().enumerate() {
            let (i, j) = (k / 3, k % 3);
            for l in 0..3 {
                acc.add_product(a_hi[(l, i)], self.hi[(l, j)]);
                acc.add_low(a_hi[(l, i)] * self.lo[(l, j)]);
                acc.add_low(a_lo[(l, i)] * self.hi[(l, j)]);
                acc.add_low(a_lo[(l, i)] * self.lo[(l, j)]);
                extra[(i, j)] += (a_hi[(l, i)].abs() + a_lo[(l, i)].abs()) * self.err[(l, j)];
            }
        }
        Self::from_sums(&sums, &(extra * (1.0 + 8.0 * UNIT_ROUNDOFF)))
    }

    /// The entries rounded to `f64`, and a bound on `||exact - rounded||_F`.
    fn rounded(&self) -> (Matrix3<f64>, f64) {
        let m = self.hi + self.lo;
        let rounding = UNIT_ROUNDOFF * m.norm();
        (
            m,
            (self.err.norm() + rounding) * (1.0 + 8.0 * UNIT_ROUNDOFF),
        )
    }
}

/// `D = r (2 tr(h) I - 4 h) - r2 (2 tr(h2) I - 4 h2)` in double-double: every entry a sum of
/// twelve exact products of stored numbers (the factors 2 and 4 are exact).
fn difference(
    r: &Matrix3<f64>,
    h: &Matrix3<f64>,
    r2: &Matrix3<f64>,
    h2: &Matrix3<f64>,
) -> Compensated {
    let mut sums = [Accumulator::default(); 9];
    for (k, acc) in sums.iter_mut().enumerate() {
        let (i, j) = (k / 3, k % 3);
        for l in 0..3 {
            acc.add_product(2.0 * r[(i, j)], h[(l, l)]);
            acc.add_product(-2.0 * r2[(i, j)], h2[(l, l)]);
            acc.add_product(-4.0 * r[(i, l)], h[(l, j)]);
            acc.add_product(4.0 * r2[(i, l)], h2[(l, j)]);
        }
    }
    Compensated::from_sums(&sums, &Matrix3::zeros())
}

/// A matrix `Z = hi + lo` within about `u^2` of a rotation near `x` (one Newton step of the
/// polar decomposition, `Z = x - x (x^T x - I) / 2`, the correction in double), and a
/// verified bound `eps >= ||Z^T Z - I||_F`: the rotation `Z_p` of `Z`'s polar decomposition
/// then satisfies `||Z_p - Z||_2 <= eps` (`|sigma - 1| <= |sigma^2 - 1|`). `None` unless
/// `det x > 0.5`, `||x^T x - I||_F <= 1e-6` and `eps < 0.5` (then `Z_p` is in SO(3)).
fn frame_rotation(x: &Matrix3<f64>) -> Option<(Matrix3<f64>, Matrix3<f64>, f64)> {
    if !x.iter().all(|v| v.is_finite()) || x.determinant() <= 0.5 {
        return None;
    }
    let gram = |hi: &Matrix3<f64>, lo: &Matrix3<f64>| {
        let mut sums = [Accumulator::default(); 9];
        for (k, acc) in sums.iter_mut().enumerate() {
            let (i, j) = (k / 3, k % 3);
            for l in 0..3 {
                acc.add_product(hi[(l, i)], hi[(l, j)]);
                acc.add_low(hi[(l, i)] * lo[(l, j)]);
                acc.add_low(lo[(l, i)] * hi[(l, j)]);
                acc.add_low(lo[(l, i)] * lo[(l, j)]);
            }
            if i == j {
                acc.add_product(-1.0, 1.0);
            }
        }
        sums
    };
    let g = gram(x, &Matrix3::zeros());
    let defect = Matrix3::from_fn(|i, j| g[3 * i + j].value());
    // the accumulators take the products with `lo` as low parts (`|lo|` about `u |x|`): a frame
    // further from orthogonal is refused, not corrected
    if defect.norm().is_nan() || defect.norm() > 1e-6 {
        return None;
    }
    let lo = -(x * defect) * 0.5;
    let f = gram(x, &lo);
    let eps = f
        .iter()
        .map(|acc| {
            let e = acc.value().abs() + acc.bound();
            e * e
        })
        .sum::<f64>()
        .sqrt()
        * (1.0 + 8.0 * UNIT_ROUNDOFF);
    (eps < 0.5).then_some((*x, lo, eps))
}

/// The offset in the estimate's frame: with `Z_p` the rotation of [`frame_rotation`] and
/// `Q = Z_p^T D`, `h(D) = h(Q) <= tr Q + sqrt(4 |q|^2 + mu^2) - mu` (every rotation is a turn
/// by `theta` in `[0, pi]` about a unit `w`, `<Q, R - I> = 2 sin(theta) q.w - (1 - cos theta)
/// w^T W w` with `W = tr(Q_s) I - Q_s`, and `max over theta of (a sin + mu cos) =
/// sqrt(a^2 + mu^2)`), with `D`, `Q` and `2 tr H' - 2 tr H + tr Q` in double-double, `|q|`
/// and `mu` from the rounded `Q` moved by its verified error, `mu` below `lambda_min(W)` by
/// a shifted Cholesky ([`verified_min_eigenvalue3`]), and `sqrt(3) eps ||D||_F` for `Z` in
/// place of `Z_p`. `None` when `frame` is not near a rotation or a bound is not finite.
pub(crate) fn framed_offset(
    r: &Matrix3<f64>,
    h: &Matrix3<f64>,
    r2: &Matrix3<f64>,
    h2: &Matrix3<f64>,
    frame: &Matrix3<f64>,
) -> Option<f64> {
    let (z_hi, z_lo, eps) = frame_rotation(frame)?;
    let d = difference(r, h, r2, h2);
    let q = d.left_transpose_product(&z_hi, &z_lo);
    // 2 tr H' - 2 tr H + tr Q, compensated
    let mut linear = Accumulator::default();
    let mut linear_err = 0.0;
    for l in 0..3 {
        linear.add_product(2.0, h2[(l, l)]);
        linear.add_product(-2.0, h[(l, l)]);
        linear.add_product(1.0, q.hi[(l, l)]);
        linear.add_low(q.lo[(l, l)]);
        linear_err += q.err[(l, l)];
    }
    let linear_up = linear.value() + linear.bound() + linear_err * (1.0 + 4.0 * UNIT_ROUNDOFF);
    let (qm, q_err) = q.rounded();
    let skew = Vector3::new(
        qm[(2, 1)] - qm[(1, 2)],
        qm[(0, 2)] - qm[(2, 0)],
        qm[(1, 0)] - qm[(0, 1)],
    ) * 0.5;
    let a = (skew.norm() + q_err) * (1.0 + 8.0 * UNIT_ROUNDOFF);
    let qs = (qm + qm.transpose()) * 0.5;
    let w = Matrix3::identity() * qs.trace() - qs;
    // W is linear in Q with ||W(E)||_F <= 4 ||E||_F; forming it rounds each entry by at most
    // 3u (|tr Q_s| + |Q_s|), under 32 u ||Q||_F in the Frobenius norm
    let w_err = 4.0 * q_err + 32.0 * UNIT_ROUNDOFF * qm.norm();
    let mu = verified_min_eigenvalue3(&w)? - w_err * (1.0 + 4.0 * UNIT_ROUNDOFF);
    let slack = if mu > 0.0 {
        4.0 * a * a / ((4.0 * a * a + mu * mu).sqrt() + mu) * (1.0 + 8.0 * UNIT_ROUNDOFF)
    } else {
        ((4.0 * a * a + mu * mu).sqrt() - mu) * (1.0 + 8.0 * UNIT_ROUNDOFF)
    };
    let (dm, d_err) = d.rounded();
    let turn = 3f64.sqrt() * eps * (dm.norm() + d_err) * (1.0 + 8.0 * UNIT_ROUNDOFF);
    let total = linear_up + slack + turn;
    let bound = total + 4.0 * UNIT_ROUNDOFF * (linear_up.abs() + slack + turn);
    bound.is_finite().then_some(bound)
}

#[cfg(test)]
mod tests {
    use super::{
        descending_singular_values, edge_offset, framed_offset, round_up, rounded_difference,
        svd_offset,
    };
    use nalgebra::{Matrix3, Rotation3, Vector3};

    /// The upward rounding raises sums of either sign (a factor `1 + 4u` would lower a negative
    /// offset, loosening the bound).
    #[test]
    fn round_up_raises_negative_sums_too() {
        for x in [-3.0, -1e-300, 0.0, 1e-300, 2.5, -1e10] {
            assert!(round_up(x) >= x);
        }
        assert!(round_up(-1.0) > -1.0);
    }

    /// A small deterministic generator (the tests need no `rand`).
    struct Lcg(u64);

    impl Lcg {
        fn next(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        }
        fn rotation(&mut self, angle: f64) -> Matrix3<f64> {
            let v = Vector3::new(self.next(), self.next(), self.next());
            *Rotation3::new(v.normalize() * angle * 2.0 * self.next().abs()).matrix()
        }
        /// A symmetric positive definite matrix with eigenvalues `1 .. spread` (log-uniform).
        fn information(&mut self, spread: f64) -> Matrix3<f64> {
            let q = self.rotation(3.0);
            let d = Vector3::from_fn(|_, _| spread.powf(self.next() + 0.5));
            let h = q * Matrix3::from_diagonal(&d) * q.transpose();
            (h + h.transpose()) * 0.5
        }
    }

    /// `2 tr H' - 2 tr H + h(D)` by the singular values of `D` in double precision (an
    /// independent reference, accurate to about `1e-15 ||D||`).
    fn reference(r: &Matrix3<f64>, h: &Matrix3<f64>, r2: &Matrix3<f64>, h2: &Matrix3<f64>) -> f64 {
        let d = rounded_difference(r, h, r2, h2);
        let s = descending_singular_values(&d);
        let third = if d.determinant() < 0.0 { -s[2] } else { s[2] };
        2.0 * h2.trace() - 2.0 * h.trace() + s[0] + s[1] + third
    }

    /// The surrogate's data of `[A11]` for multipliers `p` in the frame `x`: `K - P = U T`,
    /// `R' = x U`, `H' = tr(M') I - M'` with `M' = T / 4` (as `conv_dual` stores them).
    fn surrogate_data(
        r: &Matrix3<f64>,
        h: &Matrix3<f64>,
        x: &Matrix3<f64>,
        p: &Matrix3<f64>,
    ) -> (Matrix3<f64>, Matrix3<f64>) {
        let a = Matrix3::identity() * (2.0 * h.trace()) - h * 4.0;
        let j = x.transpose() * r * a - p;
        let svd = j.svd(true, true);
        let (mut u, v_t) = (svd.u.unwrap(), svd.v_t.unwrap());
        let mut sigma = svd.singular_values;
        if (u * v_t).determinant() < 0.0 {
            let k = (0..3)
                .min_by(|&a, &b| sigma[a].total_cmp(&sigma[b]))
                .unwrap();
            for row in 0..3 {
                u[(row, k)] = -u[(row, k)];
            }
            sigma[k] = -sigma[k];
        }
        let t = v_t.transpose() * Matrix3::from_diagonal(&sigma) * v_t;
        let m = (t + t.transpose()) * 0.125;
        (x * u * v_t, Matrix3::identity() * m.trace() - m)
    }

    /// Every bound is above the exact offset (the double-precision reference, within its own
    /// rounding) on data of every kind: surrogates from multipliers inside the cone, on its
    /// boundary (the reflection price) and outside it, and unrelated data (`Q` far from
    /// symmetric); and inside the cone the framed bound is tight, where the singular values'
    /// bound is not.
    #[test]
    fn framed_offsets_bound_the_exact_offset_and_are_tight_inside_the_cone() {
        let mut g = Lcg(11);
        let (mut tight, mut looser) = (0, 0);
        for case in 0..600 {
            let spread = [1.0, 1e2, 1e4][case % 3];
            let r = g.rotation(3.0);
            let h = g.information(spread);
            let x = r * g.rotation(0.05);
            let kind = (case / 3) % 4;
            let (r2, h2) = if kind == 3 {
                (g.rotation(3.0), g.information(spread))
            } else {
                let u = Vector3::new(g.next(), g.next(), g.next()).normalize();
                let beta = spread * (1.0 + g.next());
                let reflection = (Matrix3::identity() - u * u.transpose() * 2.0) * beta;
                let shift = [1e-6, 0.0, -1e-3][kind] * beta;
                surrogate_data(&r, &h, &x, &(reflection + Matrix3::identity() * shift))
            };
            let exact = reference(&r, &h, &r2, &h2);
            let scale = 16.0 * spread;
            let framed = framed_offset(&r, &h, &r2, &h2, &x).unwrap();
            let svd = svd_offset(&r, &h, &r2, &h2);
            assert!(
                framed >= exact - 1e-13 * scale,
                "case {case}: {framed} < {exact}"
            );
            assert!(svd >= exact - 1e-13 * scale, "case {case}: {svd} < {exact}");
            let both = edge_offset(&r, &h, &r2, &h2, &x);
            assert_eq!(both, framed.min(svd));
            if kind == 0 {
                assert!(
                    framed <= exact + 1e-12 * scale,
                    "case {case}: {framed} vs {exact}"
                );
                tight += usize::from(framed < svd);
            }
            looser += usize::from(kind == 3 && svd < framed);
        }
        // inside the cone the framed bound is the smaller one; far from it the other often is
        assert_eq!(tight, 150);
        assert!(looser > 0);
    }

    /// Closed form: with the same rotation and `H' = H - Delta`, the offset is
    /// `8 max(0, -lambda_min(Delta))` (lowering the information is free; raising it costs the
    /// worst direction's rise, eight times). Both bounds are above it, the framed one within
    /// `1e-12` of its scale.
    #[test]
    fn an_information_change_costs_its_worst_rise_eight_times() {
        let mut g = Lcg(5);
        for case in 0..50 {
            let q = g.rotation(3.0);
            let r = g.rotation(3.0);
            let base = Vector3::new(5.0, 7.0, 9.0) * 10f64.powi(case % 9);
            let delta = Vector3::new(1.0, 0.0, if case % 2 == 0 { -3.0 } else { 2.0 })
                * 10f64.powi(case % 9);
            let h = q * Matrix3::from_diagonal(&base) * q.transpose();
            let h2 = q * Matrix3::from_diagonal(&(base - delta)) * q.transpose();
            let (h, h2) = ((h + h.transpose()) * 0.5, (h2 + h2.transpose()) * 0.5);
            let exact = 8.0 * (-delta.min()).max(0.0);
            let scale = 10f64.powi(case % 9) * 32.0;
            let framed = framed_offset(&r, &h, &r, &h2, &r).unwrap();
            assert!(
                framed >= exact - 1e-13 * scale,
                "case {case}: {framed} < {exact}"
            );
            assert!(
                framed <= exact + 1e-12 * scale,
                "case {case}: {framed} vs {exact}"
            );
            assert!(svd_offset(&r, &h, &r, &h2) >= exact - 1e-13 * scale);
        }
    }

    /// A frame that is not near a rotation gives no framed bound (the singular values' bound
    /// stands alone).
    #[test]
    fn a_frame_far_from_a_rotation_gives_no_framed_bound() {
        let h = Matrix3::from_diagonal(&Vector3::new(1.0, 2.0, 3.0));
        let r = Matrix3::identity();
        let reflection = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
        assert!(framed_offset(&r, &h, &r, &h, &reflection).is_none());
        assert!(framed_offset(&r, &h, &r, &h, &(r * 1.5)).is_none());
        assert!(framed_offset(&r, &h, &r, &h, &(r * (1.0 + 1e-5))).is_none());
        assert!(framed_offset(&r, &h, &r, &h, &(r * (1.0 + 1e-9))).is_some());
        assert!(framed_offset(&r, &h, &r, &h, &(r * f64::NAN)).is_none());
        assert_eq!(
            edge_offset(&r, &h, &r, &h, &reflection),
            svd_offset(&r, &h, &r, &h)
        );
    }
}
