//! The one-dimensional profile `h(theta) = rho(d(theta))` of a cost term as a function of its
//! residual angle, with the derivative bounds the cell bounds need (`paper-notes/branch_and_bound.md`,
//! `[B3]`, `[B5]`).
//!
//! Every objective of the crate has `h(0) = 0`, `h` non-decreasing on `[0, pi]`, `h'` continuous
//! there, and `h''` bounded below on every interval (piecewise; Huber's `h''` jumps but its `h'`
//! is continuous).

use crate::objective::{Loss, Objective};
use crate::so3::Metric;
use std::f64::consts::{PI, SQRT_2};

/// `h(theta) = rho(d(theta))` for one objective, with bounds on `h'` and `h''`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Profile {
    objective: Objective,
    /// Robust threshold / scale in the metric's unit (infinite for L1 and L2).
    c: f64,
}

impl Profile {
    /// The profile of `objective`.
    pub(crate) fn new(objective: Objective) -> Self {
        Profile {
            objective,
            c: objective.threshold().unwrap_or(f64::INFINITY),
        }
    }

    /// `h(theta)`.
    #[inline]
    pub(crate) fn h(&self, theta: f64) -> f64 {
        self.objective.term(theta)
    }

    /// `d(theta)`.
    #[inline]
    fn d(&self, theta: f64) -> f64 {
        self.objective.metric.from_angle(theta)
    }

    /// `d'(theta) >= 0`: geodesic 1, chordal `sqrt 2 cos(theta/2)`, quaternion `cos(theta/4) / 2`
    /// (non-increasing on `[0, pi]`).
    #[inline]
    fn d1(&self, theta: f64) -> f64 {
        let t = theta.clamp(0.0, PI);
        match self.objective.metric {
            Metric::Geodesic => 1.0,
            Metric::Chordal => SQRT_2 * (0.5 * t).cos(),
            Metric::Quaternion => 0.5 * (0.25 * t).cos(),
        }
    }

    /// `sup |d''|` on `[0, hi]`: geodesic 0, chordal `sin(hi/2) / sqrt 2`, quaternion
    /// `sin(hi/4) / 8` (non-decreasing in `hi`).
    #[inline]
    fn d2_abs_sup(&self, hi: f64) -> f64 {
        let t = hi.clamp(0.0, PI);
        match self.objective.metric {
            Metric::Geodesic => 0.0,
            Metric::Chordal => (0.5 * t).sin() / SQRT_2,
            Metric::Quaternion => 0.125 * (0.25 * t).sin(),
        }
    }

    /// `rho'(d)`.
    #[inline]
    fn rho1(&self, d: f64) -> f64 {
        match self.objective.loss {
            Loss::L1 => 1.0,
            Loss::L2 => 2.0 * d,
            Loss::Huber { .. } => 2.0 * d.min(self.c),
            Loss::Cauchy { .. } => 2.0 * d / (1.0 + (d / self.c) * (d / self.c)),
        }
    }

    /// `sup rho'` on `[0, dhi]`: L1 1, L2 `2 dhi`, Huber `2 min(dhi, c)`, Cauchy
    /// `min(2 dhi, c)` (`2d / (1 + d^2/c^2) <= c`).
    #[inline]
    fn rho1_sup(&self, dhi: f64) -> f64 {
        match self.objective.loss {
            Loss::L1 => 1.0,
            Loss::L2 => 2.0 * dhi,
            Loss::Huber { .. } => 2.0 * dhi.min(self.c),
            Loss::Cauchy { .. } => (2.0 * dhi).min(self.c),
        }
    }

    /// `min(0, inf rho'')` over all `d >= 0`: 0, except Cauchy `-1/4` (at `d = sqrt 3 c`).
    #[inline]
    fn rho2_neg_inf(&self) -> f64 {
        match self.objective.loss {
            Loss::Cauchy { .. } => -0.25,
            _ => 0.0,
        }
    }

    /// `h'(theta) = rho'(d(theta)) d'(theta)`.
    #[inline]
    pub(crate) fn h1(&self, theta: f64) -> f64 {
        self.rho1(self.d(theta)) * self.d1(theta)
    }

    /// `sup h'` on `[lo, hi]`: `sup rho'(d(hi)) * d'(lo)` (`d` increasing, `d'` non-increasing).
    #[inline]
    pub(crate) fn h1_sup(&self, lo: f64, hi: f64) -> f64 {
        self.rho1_sup(self.d(hi.min(PI))) * self.d1(lo)
    }

    /// `max(0, -inf h'')` on `[lo, hi]`, from
    /// `h'' = rho''(d) d'^2 + rho'(d) d'' >= min(0, inf rho'') d'(lo)^2 - sup rho' * sup |d''|`.
    #[inline]
    pub(crate) fn concavity(&self, lo: f64, hi: f64) -> f64 {
        let d1 = self.d1(lo);
        let neg =
            self.rho2_neg_inf() * d1 * d1 - self.rho1_sup(self.d(hi.min(PI))) * self.d2_abs_sup(hi);
        (-neg).max(0.0)
    }

    /// `inf h'` on `[0, r]` (the slope credited for a term at the cell centre, `[B4]`):
    /// `d'(r)` for L1 (`rho' = 1`), 0 for the losses with `rho'(0) = 0`.
    #[inline]
    pub(crate) fn slope_inf(&self, r: f64) -> f64 {
        match self.objective.loss {
            Loss::L1 => self.d1(r),
            _ => 0.0,
        }
    }

    /// A bound on how much a term can change when its distance changes by `delta` in the
    /// metric's unit, or its angle by `delta_angle`: `sup rho' * (delta + sup d' * delta_angle)`
    /// (used for data that are rotations only to within the validation tolerance, `[B6]`).
    pub(crate) fn perturbation(&self, delta: f64, delta_angle: f64) -> f64 {
        self.rho1_sup(self.d(PI)) * (delta + self.d1(0.0) * delta_angle)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::certify::branch_and_bound::test_objectives as objectives;

    /// Finite differences: `h'` matches, the sup and concavity bounds hold on a grid.
    #[test]
    fn derivative_bounds_hold() {
        for o in objectives() {
            let p = Profile::new(o);
            let e = 1e-5;
            for i in 1..300 {
                let t = PI * i as f64 / 301.0;
                let fd = (p.h(t + e) - p.h(t - e)) / (2.0 * e);
                assert!((fd - p.h1(t)).abs() < 1e-6 * (1.0 + fd.abs()), "{o} {t}");
                let d2 = (p.h(t + e) - 2.0 * p.h(t) + p.h(t - e)) / (e * e);
                for (lo, hi) in [(0.0, PI), (t * 0.5, t), (t, (t * 1.5).min(PI))] {
                    if lo <= t && t <= hi {
                        assert!(p.h1(t) <= p.h1_sup(lo, hi) * (1.0 + 1e-12) + 1e-12, "{o}");
                        assert!(d2 >= -p.concavity(lo, hi) - 1e-3, "{o} {t}: {d2}");
                    }
                }
                assert!(p.h1(t) >= 0.0);
            }
            assert_eq!(p.h(0.0), 0.0);
        }
    }
}
