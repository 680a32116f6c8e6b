//! The rounding of `[H19]`'s reformulations of a rig's cost, charged to its bounds.

use crate::linalg::compensated::Accumulator;
use nalgebra::Matrix3;

/// The per-entry rounding allowance of `[H19]`'s exact reformulations, in the Frobenius norm of
/// an edge's residual: the products `S_b^T R S_a` and `S_b F_b - R S_a F_a` of rotations known to
/// about `2u` are exact to far less than `1e-13` (about `450 u`).
pub(crate) const RIG_ROUNDING: f64 = 1e-13;

/// A lower bound on `J*` from a proven bound `lower` on the minimum of a cost `J'` whose edge
/// terms satisfy `sqrt(J_e) >= (1 - RIG_ROUNDING) (sqrt(J'_e) - RIG_ROUNDING sqrt(w_e))`
/// (`[H19]`, rounding): `J >= (1 - eps)^2 (J' - 2 eps sqrt(W J'))`, `W = sum w`, which is
/// increasing in `J'` where `J' >= eps^2 W`; never below 0.
pub(crate) fn rounding_floor(lower: f64, total_weight: f64) -> f64 {
    let eps = RIG_ROUNDING;
    if !(lower.is_finite() && lower > eps * eps * total_weight) {
        return 0.0;
    }
    let shrunk = lower - 2.0 * eps * (total_weight * lower).sqrt();
    ((1.0 - eps) * (1.0 - eps) * shrunk).max(0.0)
}

/// The rounding allowance of one anisotropic edge's term in `[H24]`'s reformulations, per unit
/// of `||H||_F`: the frames' edge `S_b^T R S_a` with information `S_a^T H S_a` changes the term
/// `4 (tr M - tr(M E))` by at most about `632 u ||H||_F` (`paper-notes/conjugate.md` `[H24]`,
/// rounding), and the within-frame terms are formed to about `50 u ||H||_F`; `1e-12` is over
/// seven times both.
pub(crate) const RIG_INFORMATION_ROUNDING: f64 = 1e-12;

/// A lower bound on `J*` from a proven bound `lower` on the minimum of a reformulation whose
/// anisotropic terms are each within `RIG_INFORMATION_ROUNDING ||H_e||_F` of the rig's
/// (`[H24]`): `lower - RIG_INFORMATION_ROUNDING sum ||H_e||_F` (no floor at 0: the trace form
/// of data orthogonal only to rounding can be slightly negative; not finite when `lower` is
/// not).
pub(crate) fn information_floor(
    lower: f64,
    info: &[crate::multiple::anisotropic::Information],
) -> f64 {
    let charge: f64 = info.iter().map(|h| h.matrix().norm()).sum();
    lower - RIG_INFORMATION_ROUNDING * charge * (1.0 + 1e-12)
}

/// The frames' reformulation of an anisotropic rig with every sensor held (`[H24]` Claim 1,
/// "Measured rounding"), its rounding measured edge by edge instead of charged at
/// [`RIG_INFORMATION_ROUNDING`]: for a cross-frame edge whose frames' edge is stored as
/// `(R'_f, H'_f)` (`graph`'s edge and information, in `problem`'s order of cross-frame edges), the
/// rig's term and the frames' term differ, at any frames, by at most
/// `4 (|tr M'_f - tr M| + sqrt(3) (||dR||_F ||M'_f||_F + g^3 ||dM||_F) + sqrt(3) g^3 ||D||_F
/// ||M||_F)`, where `dR = R'_f - S_b^T R S_a`, `dM = M'_f - S_a^T M S_a`, `D = S_a S_a^T - I`
/// (each measured in double-double against the exact products of the stored matrices, their
/// accumulators' error bounds added) and `g = 1 + 1e-12` bounds the spectral norm of the
/// stored, nearly orthogonal rotations. A within-frame edge keeps the allowance
/// `RIG_INFORMATION_ROUNDING ||H||_F` (its constant is summed in plain floating point). `None`
/// when `graph` does not hold the cross-frame edges with their information.
pub(crate) fn frames_information_charge(
    problem: &crate::rig::RigProblem,
    sensors: &[crate::Rotation],
    graph: &crate::multiple::MultipleProblem,
) -> Option<f64> {
    let (info, frames_info) = (problem.information()?, graph.information()?);
    let mut cross = graph.edges().iter().zip(frames_info);
    let mut charge = 0.0;
    for (e, h) in problem.edges().iter().zip(info) {
        let (a, b) = (problem.images()[e.i], problem.images()[e.j]);
        if a.frame == b.frame {
            charge += RIG_INFORMATION_ROUNDING * h.matrix().norm();
            continue;
        }
        let (turned, turned_h) = cross.next()?;
        let (sa, sb) = (sensors[a.sensor].matrix(), sensors[b.sensor].matrix());
        charge += edge_charge(
            (e.rotation.matrix(), h.matrix()),
            (sa, sb),
            (turned.rotation.matrix(), turned_h.matrix()),
        );
    }
    cross.next().is_none().then_some(charge * (1.0 + 1e-10))
}

/// One cross-frame edge's term of [`frames_information_charge`].
fn edge_charge(
    (r, h): (&Matrix3<f64>, &Matrix3<f64>),
    (sa, sb): (&Matrix3<f64>, &Matrix3<f64>),
    (r_f, h_f): (&Matrix3<f64>, &Matrix3<f64>),
) -> f64 {
    let g3 = (1.0 + 1e-12f64).powi(3);
    let chordal = |h: &Matrix3<f64>| Matrix3::identity() * (h.trace() / 2.0) - h;
    let (m, m_f) = (chordal(h), chordal(h_f));
    // tr M' - tr M = (tr H' - tr H) / 2, exactly from the stored entries
    let mut trace = Accumulator::default();
    for k in 0..3 {
        trace.add_product(h_f[(k, k)], 0.5);
        trace.add_product(h[(k, k)], -0.5);
    }
    let trace = trace.value().abs() + trace.bound();
    let d_r = distance(r_f, |i, j, acc| triple(acc, 1.0, (sb, r, sa), (i, j)));
    // dM = M'_f - S_a^T M S_a with M'_f = tr(H'_f)/2 I - H'_f exactly, as the frames' problem
    // defines it from the stored H'_f
    let d_m = distance(&Matrix3::zeros(), |i, j, acc| {
        if i == j {
            for t in 0..3 {
                acc.add_product(h_f[(t, t)], -0.5);
            }
        }
        acc.add_product(h_f[(i, j)], 1.0);
        exact_turned_chordal(acc, h, sa, (i, j));
    });
    let d = distance(&Matrix3::zeros(), |i, j, acc| {
        for k in 0..3 {
            acc.add_product(sa[(i, k)], sa[(j, k)]);
        }
        acc.add_product(-1.0, if i == j { 1.0 } else { 0.0 });
    });
    let s3 = 3f64.sqrt();
    let term = trace
        + s3 * (d_r * m_f.norm() * (1.0 + 1e-12) + g3 * d_m)
        + s3 * g3 * d * m.norm() * (1.0 + 1e-12);
    4.0 * term * (1.0 + 1e-12)
}

/// An upper bound on `||stored - exact||_F`, each entry of `exact` accumulated by `entry` in
/// double-double (its error bound added).
fn distance(stored: &Matrix3<f64>, entry: impl Fn(usize, usize, &mut Accumulator)) -> f64 {
    let mut squares = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let mut acc = Accumulator::default();
            acc.add_product(-stored[(i, j)], 1.0);
            entry(i, j, &mut acc);
            let e = acc.value().abs() + acc.bound();
            squares += e * e;
        }
    }
    squares.sqrt() * (1.0 + 1e-12)
}

/// Add `w (B^T C A)_ij = w sum_kl B_ki C_kl A_lj` to `acc` (nine error-free products of four
/// factors).
fn triple(
    acc: &mut Accumulator,
    w: f64,
    (b, c, a): (&Matrix3<f64>, &Matrix3<f64>, &Matrix3<f64>),
    (i, j): (usize, usize),
) {
    for k in 0..3 {
        for l in 0..3 {
            acc.add_quad(w, b[(k, i)], c[(k, l)], a[(l, j)]);
        }
    }
}

/// Add `(S^T M S)_ij` with `M = tr(H)/2 I - H` exactly: `sum_t H_tt / 2 (S^T S)_ij - (S^T H
/// S)_ij`.
fn exact_turned_chordal(
    acc: &mut Accumulator,
    h: &Matrix3<f64>,
    s: &Matrix3<f64>,
    ij: (usize, usize),
) {
    let (i, j) = ij;
    for t in 0..3 {
        for k in 0..3 {
            acc.add_quad(0.5 * h[(t, t)], s[(k, i)], s[(k, j)], 1.0);
        }
    }
    triple(acc, -1.0, (s, h, s), ij);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_floor_is_below_the_bound_increasing_and_never_negative() {
        let w = 1e4;
        let mut last = 0.0;
        for k in -30..10 {
            let x = 10f64.powi(k);
            let y = rounding_floor(x, w);
            assert!((0.0..=x).contains(&y) && y >= last, "{x} -> {y}");
            // the charge 2 eps sqrt(W x): relative 2e-11 at x = 1e-3 W
            if x >= 1e-3 * w {
                assert!(y >= x * (1.0 - 1e-10));
            }
            last = y;
        }
        assert_eq!(rounding_floor(f64::NAN, w), 0.0);
        assert_eq!(rounding_floor(-1.0, w), 0.0);
    }

    /// `edge_charge` bounds the difference of the rig's term and the frames' term at every
    /// frames' rotation `P`, with the frames' data off the exact products by planted amounts, or
    /// a sensor off orthogonality by `1e-7` (far above rounding, so the terms are compared in
    /// plain floating point); and it is not vacuous: within 20 times the largest difference
    /// seen over 400 random `P`. (Without its `dR` part the even cases fail.)
    #[test]
    fn the_measured_charge_bounds_the_terms_difference() {
        use crate::so3::{exp, random_rotation};
        use nalgebra::Vector3;
        use rand::SeedableRng;
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let chordal = |h: &Matrix3<f64>| Matrix3::identity() * (h.trace() / 2.0) - h;
        for case in 0..20 {
            let a = Matrix3::from_fn(|p, q| ((p * 5 + q * 3 + case) % 7) as f64 - 3.0);
            let h = a * a.transpose() * 1e6 + Matrix3::identity();
            let r = *random_rotation(&mut rng).matrix();
            // odd cases: sensors off orthogonality by 1e-7 and the frames' data the products
            // themselves (the charge's `D` part alone); even cases: 1e-9 and planted data
            let (off, plant) = if case % 2 == 1 {
                (1e-7, 0.0)
            } else {
                (1e-9, 1.0)
            };
            let skew = Matrix3::from_fn(|p, q| {
                if p == q {
                    0.0
                } else {
                    off * (p + 2 * q) as f64
                }
            });
            let sa = random_rotation(&mut rng).matrix() + skew;
            let sb = *random_rotation(&mut rng).matrix();
            let exact_h = sa.transpose() * h * sa;
            let exact_r = sb.transpose() * r * sa;
            let planted = Matrix3::from_fn(|p, q| plant * 1e-6 * ((p + q) as f64 - 1.5));
            let h_f = exact_h + planted + planted.transpose();
            let r_f = exact_r * exp(&(Vector3::new(1e-8, -2e-8, 3e-8) * plant)).matrix();
            let charge = edge_charge((&r, &h), (&sa, &sb), (&r_f, &h_f));
            let (m, m_f) = (chordal(&h), chordal(&h_f));
            let mut largest: f64 = 0.0;
            for _ in 0..400 {
                let p = *random_rotation(&mut rng).matrix();
                let rig = 4.0 * (m.trace() - (r * m).dot(&(sb * p * sa.transpose())));
                let frames = 4.0 * (m_f.trace() - (r_f * m_f).dot(&p));
                largest = largest.max((rig - frames).abs());
            }
            assert!(
                largest <= charge,
                "case {case}: difference {largest:e} above {charge:e}"
            );
            assert!(
                charge <= 20.0 * largest,
                "case {case}: {charge:e} against {largest:e}"
            );
        }
    }
}
