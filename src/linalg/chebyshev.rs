//! The randomized Chebyshev test `[D16]`: a Monte Carlo lower bound on the smallest eigenvalue
//! of a symmetric operator from matrix-vector products only (no factorisation, hence no fill).
//!
//! Let `A` be symmetric (dimension `d`), `kappa > 0`, `c0` real, `M = c0 I - kappa A`, and let
//! `y_k = T_k(M) g` for a standard Gaussian vector `g` (`T_k` the Chebyshev polynomial of the
//! first kind, evaluated by `y_{j+1} = 2 M y_j - y_{j-1}`). If `A` had an eigenvalue
//! `a <= mu` with unit eigenvector `u`, then `theta = c0 - kappa a >= theta_0 = c0 - kappa mu`,
//! and for `theta_0 > 1`
//!
//! `|u^T y_k| = T_k(theta) |u^T g| >= T_k(theta_0) |u^T g|`,
//!
//! while `u^T g ~ N(0, 1)` has `|u^T g| < t` with probability at most `t sqrt(2 / pi)`. The
//! computed vectors carry rounding errors `f_j` (bounded rigorously from computed norms); they
//! reach `u^T y_k` through `U_{k-1-j}(theta) <= (k - j) T_k(theta)` (Chebyshev polynomials of the
//! second kind, `theta >= 1`), so with `E = sum_j (k - j) ||f_j||`:
//!
//! `||computed y_k|| >= T_k(theta_0) (|u^T g| - E)`.
//!
//! Hence if `||computed y_k|| < T_k(theta_0) (t - E)` for each of `r` independent vectors,
//! `lambda_min(A) > mu`, unless an event of probability at most `(t sqrt(2 / pi))^r` (over the
//! test's own random vectors, whatever `A` is) occurred. The test never claims more: when an
//! eigenvalue lies below `mu` it passes only on that rare event, and when the spectrum is
//! above the interval's lower end it passes with certainty in exact arithmetic (every
//! component is then at most `|u^T g|`), so the degree is chosen to make the threshold
//! `T_k(theta_0) t` exceed `||g||`.

use super::cholesky::{UNIT_ROUNDOFF, gamma};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

/// The interval, degree and number of vectors of one randomized Chebyshev test `[D16]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ChebyshevTest {
    /// The lower end `alpha` of the interval `[alpha, Lambda]` mapped onto `[-1, 1]` (where the
    /// spectrum is expected).
    pub lower: f64,
    /// The upper end `Lambda` (an upper bound on `lambda_max(A)`).
    pub upper: f64,
    /// The claimed bound: `lambda_min(A) > threshold` when the test passes (`threshold < lower`).
    pub threshold: f64,
    /// Polynomial degree `k` (matrix-vector products per vector).
    pub degree: usize,
    /// Independent Gaussian vectors `r`.
    pub vectors: usize,
    /// The level `t` of each vector: `P(|u^T g| < t) <= t sqrt(2 / pi)`.
    pub level: f64,
}

/// What a randomized Chebyshev test found.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ChebyshevOutcome {
    /// Every vector stayed below its threshold: `lambda_min(A) > threshold` unless an event of
    /// probability at most `failure_probability` occurred.
    pub passed: bool,
    /// `(t sqrt(2 / pi))^r`.
    pub failure_probability: f64,
    /// The largest rounding term `E` (in units of `|u^T g|`) over the vectors.
    pub rounding: f64,
    /// The smallest margin `ln(T_k(theta_0) (t - E)) - ln ||y_k||` over the vectors (`> 0` for
    /// each vector that passed).
    pub log_margin: f64,
    /// Matrix-vector products done.
    pub matvecs: usize,
    /// The test stopped early: an iterate grew past `1e3 ||g||`, which happens only when an
    /// eigenvalue lies below the interval's lower end (the test fails).
    pub grew: bool,
}

/// `sqrt(2 / pi)`: the largest density of `N(0, 1)` times 2.
const TWO_OVER_PI_SQRT: f64 = 0.797_884_560_802_865_4;

/// An upper bound on the Euclidean norm of `v` (the computed sum of squares has relative error
/// at most `gamma(d)`; the square root adds one rounding).
fn norm_up(v: &[f64]) -> f64 {
    let s: f64 = v.iter().map(|x| x * x).sum();
    (s * (1.0 + gamma(v.len() + 2))).sqrt() * (1.0 + 2.0 * UNIT_ROUNDOFF)
}

/// `d` independent standard normal values (Box-Muller).
fn gaussian(d: usize, rng: &mut StdRng) -> Vec<f64> {
    let mut g = Vec::with_capacity(d + 1);
    while g.len() < d {
        let u1 = 1.0 - rng.random::<f64>(); // (0, 1]
        let u2: f64 = rng.random();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        g.push(r * c);
        g.push(r * s);
    }
    g.truncate(d);
    g
}

impl ChebyshevTest {
    /// `M = c0 I - kappa A` maps `[lower, upper]` onto `[-1, 1]` (reversed).
    fn map(&self) -> (f64, f64) {
        let width = self.upper - self.lower;
        ((self.upper + self.lower) / width, 2.0 / width)
    }

    /// A lower bound on `ln T_k(theta_0)`, `theta_0 = c0 - kappa threshold`, with the constants
    /// as rounded; `None` when `theta_0 <= 1` is possible.
    fn log_growth(&self, c0: f64, kappa: f64) -> Option<f64> {
        let u = UNIT_ROUNDOFF;
        let km = kappa * self.threshold;
        let d = (c0 - 1.0) - km;
        // three roundings (c0 - 1, kappa mu, the difference)
        let d = d - 4.0 * u * ((c0 - 1.0).abs() + km.abs() + d.abs());
        if !(d > 0.0 && d.is_finite()) {
            return None;
        }
        // T_k(1 + d) = cosh(k acosh(1 + d)) >= exp(k acosh(1 + d)) / 2
        let acosh = (d + (d * (2.0 + d)).sqrt()).ln_1p();
        Some(self.degree as f64 * acosh * (1.0 - 1e-12) - std::f64::consts::LN_2 * (1.0 + 1e-12))
    }

    /// Choose the degree, the number of vectors and the level for `failure_probability` on the
    /// interval `[lower, upper]` and claimed `threshold`, given `rounding_per_norm`: the
    /// rounding error of one application of `A` per unit norm of its argument (as the `apply`
    /// of [`Self::run`] reports it). The plan minimises the matrix-vector products
    /// `degree x vectors` subject to a predicted rounding term below a tenth of the level;
    /// `None` when no plan needs at most `max_matvecs` products.
    ///
    /// ```
    /// use rotavg::linalg::ChebyshevTest;
    /// // A diagonal operator with spectrum in [1, 10]: claim lambda_min > 0.5 (interval [0.8, 11]).
    /// let d: Vec<f64> = (0..500).map(|i| 1.0 + 9.0 * i as f64 / 499.0).collect();
    /// let apply = |x: &[f64], y: &mut [f64]| {
    ///     for ((yi, xi), di) in y.iter_mut().zip(x).zip(&d) {
    ///         *yi = di * xi;
    ///     }
    ///     // one rounding per entry: |error| <= u |y|
    ///     1.2e-16 * y.iter().map(|v| v * v).sum::<f64>().sqrt()
    /// };
    /// let test = ChebyshevTest::plan(500, 0.8, 11.0, 0.5, 1e-12, 2.3e-16, 10_000).unwrap();
    /// let outcome = test.run(500, apply, 42);
    /// assert!(outcome.passed && outcome.failure_probability <= 1.0001e-12);
    /// // a planted eigenvalue at 0.1 is found: the test does not pass
    /// let mut bad = d.clone();
    /// bad[100] = 0.1;
    /// let apply_bad = |x: &[f64], y: &mut [f64]| {
    ///     for ((yi, xi), di) in y.iter_mut().zip(x).zip(&bad) {
    ///         *yi = di * xi;
    ///     }
    ///     1.2e-16 * y.iter().map(|v| v * v).sum::<f64>().sqrt()
    /// };
    /// assert!(!test.run(500, apply_bad, 42).passed);
    /// ```
    pub fn plan(
        dim: usize,
        lower: f64,
        upper: f64,
        threshold: f64,
        failure_probability: f64,
        rounding_per_norm: f64,
        max_matvecs: usize,
    ) -> Option<ChebyshevTest> {
        if !(threshold < lower && lower < upper && failure_probability > 0.0) {
            return None;
        }
        let mut best: Option<ChebyshevTest> = None;
        for vectors in 1..=8usize {
            let q = failure_probability.powf(1.0 / vectors as f64);
            let level = q / TWO_OVER_PI_SQRT;
            if !(level > 0.0 && level < 1.0) {
                continue;
            }
            let mut test = ChebyshevTest {
                lower,
                upper,
                threshold,
                degree: 1,
                vectors,
                level,
            };
            let (c0, kappa) = test.map();
            let per_degree = test.log_growth(c0, kappa)?;
            let per_degree = per_degree + std::f64::consts::LN_2;
            // ||g|| <= sqrt(d) + 6 except with a negligible probability; the norms of the
            // iterates stay near ||g|| when the test passes
            let g = (dim as f64).sqrt() + 6.0;
            let step = 2.0 * kappa * rounding_per_norm
                + gamma(3) * (2.0 * c0.abs() + 2.0 * kappa * upper + 1.0);
            let mut degree = 1usize;
            for _ in 0..4 {
                let e = 2.0 * g * step * (degree * degree) as f64;
                if e >= 0.1 * level {
                    degree = usize::MAX;
                    break;
                }
                let need = (1.1 * g).ln() - (level - e).ln() + std::f64::consts::LN_2;
                degree = (need / per_degree).ceil().max(1.0) as usize + 2;
            }
            if degree == usize::MAX || degree.saturating_mul(vectors) > max_matvecs {
                continue;
            }
            test.degree = degree;
            if best.is_none_or(|b| degree * vectors < b.degree * b.vectors) {
                best = Some(test);
            }
        }
        best
    }

    /// Run the test on the operator `apply(x, y)`: `y <- A x` computed in floating point, and
    /// returning a rigorous bound on `||y - A x||` (the exact `A x`) for the computed `y`.
    /// The random vectors come from `seed`.
    pub fn run(
        &self,
        dim: usize,
        mut apply: impl FnMut(&[f64], &mut [f64]) -> f64,
        seed: u64,
    ) -> ChebyshevOutcome {
        let (c0, kappa) = self.map();
        let k = self.degree.max(1);
        let failure_probability = (self.level * TWO_OVER_PI_SQRT).powi(self.vectors as i32);
        let mut outcome = ChebyshevOutcome {
            passed: false,
            failure_probability,
            rounding: 0.0,
            log_margin: f64::INFINITY,
            matvecs: 0,
            grew: false,
        };
        let Some(log_growth) = (ChebyshevTest { degree: k, ..*self }).log_growth(c0, kappa) else {
            outcome.log_margin = f64::NEG_INFINITY;
            return outcome;
        };
        let mut rng = StdRng::seed_from_u64(seed);
        let mut all = true;
        for _ in 0..self.vectors {
            let g = gaussian(dim, &mut rng);
            let Some((e_total, y)) = self.recurrence(g, &mut apply, &mut outcome.matvecs) else {
                outcome.grew = true;
                outcome.log_margin = f64::NEG_INFINITY;
                all = false;
                break;
            };
            let e_total = e_total * (1.0 + 1e-10);
            outcome.rounding = outcome.rounding.max(e_total);
            let margin = self.log_margin(log_growth, e_total, y);
            outcome.log_margin = outcome.log_margin.min(margin);
            all &= margin > 0.0;
            if !all {
                break;
            }
        }
        outcome.passed = all && self.vectors > 0;
        outcome
    }

    /// The Chebyshev recurrence of degree `max(degree, 1)` on the mapped operator from the
    /// Gaussian `g`, its products counted in `matvecs`: a bound on the accumulated rounding
    /// (before its final margin) and an upper bound on the final iterate's norm; `None` when the
    /// iterates grew past `1e3 ||g||`.
    fn recurrence(
        &self,
        mut prev: Vec<f64>,
        apply: &mut impl FnMut(&[f64], &mut [f64]) -> f64,
        matvecs: &mut usize,
    ) -> Option<(f64, f64)> {
        let (c0, kappa) = self.map();
        let k = self.degree.max(1);
        let g3 = gamma(3);
        // the stored g is the Gaussian to a few units of rounding per entry
        let mut e_total = 16.0 * UNIT_ROUNDOFF * norm_up(&prev);
        let mut z = vec![0.0f64; prev.len()];
        let err = apply(&prev, &mut z);
        *matvecs += 1;
        let mut cur: Vec<f64> = prev
            .iter()
            .zip(&z)
            .map(|(x, z)| c0 * x - kappa * z)
            .collect();
        let phi = kappa * err + gamma(2) * (c0.abs() * norm_up(&prev) + kappa * norm_up(&z));
        e_total += k as f64 * phi;
        let gn = norm_up(&prev);
        for j in 1..k {
            let err = apply(&cur, &mut z);
            *matvecs += 1;
            let (nc, nz, np) = (norm_up(&cur), norm_up(&z), norm_up(&prev));
            // with the spectrum inside the interval every iterate stays within ||g|| plus
            // rounding; growth past 1e3 ||g|| means an eigenvalue below the interval's
            // lower end: stop (a failed test, never a pass)
            if nc.is_nan() || nc > 1e3 * gn {
                return None;
            }
            let phi = 2.0 * kappa * err + g3 * (2.0 * c0.abs() * nc + 2.0 * kappa * nz + np);
            e_total += (k - j) as f64 * phi;
            for ((p, c), zi) in prev.iter_mut().zip(&cur).zip(&z) {
                *p = 2.0 * (c0 * c - kappa * zi) - *p;
            }
            std::mem::swap(&mut prev, &mut cur);
        }
        Some((e_total, norm_up(&cur)))
    }

    /// The log margin of one vector: how far its final iterate's norm `y` stays below the
    /// growth a pass needs, with the rounding `e_total` taken from the level (negative
    /// infinity when nothing is left).
    fn log_margin(&self, log_growth: f64, e_total: f64, y: f64) -> f64 {
        let room = (self.level - e_total) * (1.0 - 4.0 * UNIT_ROUNDOFF);
        let margin = if room > 0.0 && y.is_finite() {
            log_growth + room.ln() - y.ln() - 1e-9
        } else {
            f64::NEG_INFINITY
        };
        if margin.is_nan() {
            f64::NEG_INFINITY
        } else {
            margin
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A diagonal operator with exact products (rounding bound 0 is exact for a diagonal
    /// product up to one rounding per entry: `u ||A x||`).
    fn diagonal(d: &[f64]) -> impl FnMut(&[f64], &mut [f64]) -> f64 + '_ {
        move |x, y| {
            for ((yi, xi), di) in y.iter_mut().zip(x).zip(d) {
                *yi = di * xi;
            }
            UNIT_ROUNDOFF * norm_up(y) * 1.01
        }
    }

    fn spectrum(dim: usize, low: f64, high: f64) -> Vec<f64> {
        (0..dim)
            .map(|i| low + (high - low) * i as f64 / (dim - 1) as f64)
            .collect()
    }

    #[test]
    fn passes_when_the_spectrum_is_above_the_interval() {
        let d = spectrum(2000, 0.5, 40.0);
        let t = ChebyshevTest::plan(2000, 0.4, 41.0, 0.2, 1e-12, 2.0 * UNIT_ROUNDOFF, 100_000)
            .expect("a plan");
        assert!(t.degree > 10, "{t:?}");
        for seed in 0..5 {
            let o = t.run(2000, diagonal(&d), seed);
            assert!(o.passed, "{o:?}");
            assert!(o.failure_probability <= 1e-12 * 1.0001);
            assert!(o.rounding < 0.1 * t.level);
        }
    }

    /// Soundness: one planted eigenvalue below the threshold makes every run fail (it passes
    /// only when the vector is nearly orthogonal to it, probability <= 1e-12 here).
    #[test]
    fn refuses_a_planted_eigenvalue_below_the_threshold() {
        for (planted, dim) in [(0.19, 500), (0.0, 2000), (-3.0, 2000), (0.1999, 300)] {
            let mut d = spectrum(dim, 0.5, 40.0);
            d[dim / 3] = planted;
            let t = ChebyshevTest::plan(dim, 0.4, 41.0, 0.2, 1e-12, 2.0 * UNIT_ROUNDOFF, 100_000)
                .expect("a plan");
            for seed in 0..20 {
                let o = t.run(dim, diagonal(&d), seed);
                assert!(!o.passed, "planted {planted}, seed {seed}: {o:?}");
                // far below the interval the growth stops the run early
                assert!(planted > -1.0 || (o.grew && o.matvecs < t.degree), "{o:?}");
            }
        }
    }

    /// An eigenvalue just above the threshold (inside `(threshold, lower)`) may pass or not;
    /// the claim `lambda_min > threshold` is then true either way. A tiny level against a large
    /// rounding bound is refused outright (the test cannot separate signal from rounding).
    #[test]
    fn rounding_above_the_level_never_passes() {
        let d = spectrum(100, 0.5, 40.0);
        let t = ChebyshevTest {
            lower: 0.4,
            upper: 41.0,
            threshold: 0.2,
            degree: 50,
            vectors: 1,
            level: 1e-9,
        };
        let o = t.run(100, |x, y| diagonal(&d)(x, y) + 1e-6, 7);
        assert!(!o.passed && o.rounding > 1e-9, "{o:?}");
    }

    #[test]
    fn plan_refuses_an_inverted_interval_and_a_tiny_budget() {
        assert!(ChebyshevTest::plan(10, 0.1, 1.0, 0.2, 1e-9, 0.0, 1000).is_none());
        assert!(ChebyshevTest::plan(10, 0.2, 0.1, 0.0, 1e-9, 0.0, 1000).is_none());
        assert!(ChebyshevTest::plan(10_000, 1e-6, 1e3, 5e-7, 1e-9, 1e-16, 10).is_none());
    }
}
