//! Compensated (double-double) accumulation with error-free transformations (Knuth's TwoSum,
//! the fused-multiply-add TwoProd; Ogita, Rump & Oishi 2005): sums of products evaluated to
//! about twice the working precision, with an a-posteriori error bound. Used where a residual
//! that cancels to almost nothing must be known with an error far below its size `[D15]`.

use super::cholesky::UNIT_ROUNDOFF;

/// Knuth's error-free sum: `a + b = s + e` exactly (no overflow assumed).
#[inline(always)]
pub(crate) fn two_sum(a: f64, b: f64) -> (f64, f64) {
    let s = a + b;
    let bb = s - a;
    let e = (a - (s - bb)) + (b - bb);
    (s, e)
}

/// Veltkamp's split: `a = hi + lo` exactly, each half with at most 26 significant bits (no
/// overflow assumed: `|a| < 2^996`).
#[inline(always)]
fn split(a: f64) -> (f64, f64) {
    let c = 134_217_729.0 * a; // 2^27 + 1
    let hi = c - (c - a);
    (hi, a - hi)
}

/// Error-free product: `a b = p + e` exactly (Dekker's TwoProduct with Veltkamp's split; no
/// overflow or underflow assumed). Not `f64::mul_add`: without a guaranteed FMA instruction in
/// the target (x86_64's baseline has none) it calls a software routine, measured 1.5x slower
/// than these 17 inline flops, and the certificates spend most of their non-factorisation
/// time here (issue 35).
#[inline(always)]
pub(crate) fn two_prod(a: f64, b: f64) -> (f64, f64) {
    let p = a * b;
    let (ah, al) = split(a);
    let (bh, bl) = split(b);
    (p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)
}

/// A sum of products accumulated in double-double, with the bookkeeping for its error bound:
/// after `k` terms, `|value() - exact| <= bound()` where `exact` is the real sum of the real
/// products.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Accumulator {
    hi: f64,
    lo: f64,
    /// `sum |term|` (for the bound).
    abs: f64,
    /// Number of terms.
    terms: usize,
}

impl Accumulator {
    /// Add `a b` (error-free product, compensated sum).
    #[inline]
    pub(crate) fn add_product(&mut self, a: f64, b: f64) {
        let (p, e) = two_prod(a, b);
        let (s, t) = two_sum(self.hi, p);
        self.hi = s;
        self.lo += t + e;
        self.abs += p.abs();
        self.terms += 1;
    }

    /// Add `x`, a term far below the sum (a product with a double-double's low part, itself
    /// at most `u` of its high part): rounded into the low part, its error second order.
    #[inline]
    pub(crate) fn add_low(&mut self, x: f64) {
        self.lo += x;
        self.abs += x.abs();
        self.terms += 1;
    }

    /// Add `w a b` (a triple product; the second-order error `u^2 |w a b|` is charged in
    /// [`Self::bound`]).
    #[inline]
    pub(crate) fn add_triple(&mut self, w: f64, a: f64, b: f64) {
        let (p, e) = two_prod(a, b);
        let (q, f) = two_prod(w, p);
        let (s, t) = two_sum(self.hi, q);
        self.hi = s;
        self.lo += t + f + w * e;
        self.abs += q.abs();
        self.terms += 1;
    }

    /// Add `w a b c` (a quadruple product: `w a b c = r + f_3 + w f_2 + w f_1 c` exactly with
    /// the three error-free products; the second-order errors, at most `3 u^2 |w a b c|`, and
    /// the four additions into the low part are charged in [`Self::bound`] by counting the
    /// term twice).
    pub(crate) fn add_quad(&mut self, w: f64, a: f64, b: f64, c: f64) {
        let (p, f1) = two_prod(a, b);
        let (q, f2) = two_prod(p, c);
        let (r, f3) = two_prod(w, q);
        let (s, t) = two_sum(self.hi, r);
        self.hi = s;
        self.lo += t + f3 + w * f2 + w * (f1 * c);
        self.abs += 2.0 * r.abs();
        self.terms += 2;
    }

    /// The unevaluated double-double sum `(hi, lo)`: `hi + lo` exactly is the compensated sum
    /// ([`Self::bound`] bounds its distance to the exact one, plus the final rounding).
    pub(crate) fn parts(&self) -> (f64, f64) {
        (self.hi, self.lo)
    }

    /// The sum, rounded to `f64`.
    pub(crate) fn value(&self) -> f64 {
        self.hi + self.lo
    }

    /// A rigorous bound on `|value() - exact|`: the compensated sum's error
    /// `u |s| + gamma_{3k+2}^2 sum |term|` (Ogita-Rump-Oishi, Prop. 4.5, `k` terms), plus the
    /// second-order errors of the triple products `2 u^2 sum |term|`, doubled to cover the
    /// evaluation of the bound.
    pub(crate) fn bound(&self) -> f64 {
        2.0 * UNIT_ROUNDOFF * self.value().abs() + self.parts_bound()
    }

    /// A rigorous bound on `|hi + lo - exact|` for the unevaluated pair of [`Self::parts`]:
    /// [`Self::bound`] without the final rounding to `f64` (the `u |s|` term).
    pub(crate) fn parts_bound(&self) -> f64 {
        let u = UNIT_ROUNDOFF;
        // the low parts are sums of up to three roundings per term
        let k = 3.0 * self.terms as f64 + 2.0;
        let gamma = k * u / (1.0 - k * u);
        2.0 * (gamma * gamma + 2.0 * u * u) * self.abs * (1.0 + 4.0 * u)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sum that cancels to 2^-70: plain summation returns 0, the accumulator the exact value,
    /// within its bound.
    #[test]
    fn accumulator_recovers_a_cancelled_sum() {
        let tiny = 2f64.powi(-70);
        let mut acc = Accumulator::default();
        acc.add_product(1.0, 1.0 + 2f64.powi(-52));
        acc.add_product(-1.0, 1.0);
        acc.add_product(-1.0, 2f64.powi(-52));
        acc.add_product(1.0, tiny);
        assert_eq!(acc.value(), tiny);
        assert!(acc.bound() < 1e-3 * tiny + 1e-30);
        let plain: f64 = (1.0 + 2f64.powi(-52)) - 1.0 - 2f64.powi(-52) + 0.0;
        assert_eq!(plain, 0.0);
    }

    /// Quadruple products: `(1 + 2^-30)^3 * 5 - 5 - 15 * 2^-30 = 15 * 2^-60 + 5 * 2^-90`
    /// exactly; plain arithmetic loses the last term and most of the first.
    #[test]
    fn quadruple_products_are_exact_to_second_order() {
        let x = 1.0 + 2f64.powi(-30);
        let mut acc = Accumulator::default();
        acc.add_quad(5.0, x, x, x);
        acc.add_product(-5.0, 1.0);
        acc.add_product(-15.0, 2f64.powi(-30));
        let exact = 15.0 * 2f64.powi(-60) + 5.0 * 2f64.powi(-90);
        assert!((acc.value() - exact).abs() <= acc.bound());
        assert!((acc.value() - exact).abs() < 1e-6 * exact);
        assert!(acc.bound() < 1e-3 * exact);
    }

    /// Triple products: `(1 + 2^-30)^2 * 3 - 3 - 6 * 2^-30 = 3 * 2^-60` exactly.
    #[test]
    fn triple_products_are_exact_to_second_order() {
        let x = 1.0 + 2f64.powi(-30);
        let mut acc = Accumulator::default();
        acc.add_triple(3.0, x, x);
        acc.add_product(-3.0, 1.0);
        acc.add_product(-6.0, 2f64.powi(-30));
        let exact = 3.0 * 2f64.powi(-60);
        assert!((acc.value() - exact).abs() <= acc.bound());
        assert!((acc.value() - exact).abs() < 1e-6 * exact);
    }
}
