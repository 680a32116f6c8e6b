//! The rounding of `[H19]`'s reformulations of a rig's cost, charged to its bounds.

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
}
