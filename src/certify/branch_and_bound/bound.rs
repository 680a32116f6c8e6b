//! The lower bound of a cost `sum_k w_k h(theta_k(X))` over a geodesic ball `B(C, r)` of
//! rotations `X`, from the terms at the centre (`paper-notes/branch_and_bound.md`):
//!
//! - `[B2]` per-term Lipschitz bound: `theta_k(X) >= theta_k(C) - lambda r`, so
//!   `h(theta_k(X)) >= h(max(0, theta_k(C) - lambda r))` (`lambda = 1` single, `2` conjugate);
//! - `[B3]` first-order bound along the radial geodesics `C exp(t v)`, `|v| <= r`: for a term
//!   whose angle stays below `pi` on the ball, `h(theta_k(1)) >= h(theta_k(0)) + <g_k, v> -
//!   c_k |v|^2 / 2` with `g_k = h'(theta_k) grad theta_k` and `c_k = lambda^2 m_k + kappa
//!   sup h'` (`m_k = max(0, -inf h'')`, `theta'' >= -kappa |v|^2`: `kappa = 0` single, `2`
//!   conjugate); summed: `f(C) - |sum g_k| r - sum c_k r^2 / 2`, with the other terms bounded
//!   by `[B2]`;
//! - `[B4]` single averaging, a sample at the centre: `h(theta_k(X)) >= s (|v| - theta_k(C))`
//!   with `s = inf h'` (a convex kink that pays back part of the gradient);
//! - `[B6]` floating point: angles carry an absolute error of at most [`ANGLE_ERROR`], the
//!   direction of a term's gradient `64 eps / sin theta_k`, and every sum a relative error
//!   `(n + 16) eps`; all are subtracted.
//!
//! The bound of a ball is `max([B2], [B3]) - margins`, and never below 0 (every term is `>= 0`).

use super::profile::Profile;
use nalgebra::Vector3;
use std::f64::consts::PI;

/// Absolute error bound of a computed angle `atan2(|vee(X)|, (tr X - 1) / 2)` for products `X`
/// of two rotations that are orthogonal to rounding (entries of `X` within `~8 eps`; `[B6]`).
pub(crate) const ANGLE_ERROR: f64 = 128.0 * f64::EPSILON;

/// Angles below this are "at the centre" (`[B4]`): their gradient direction is not used.
pub(crate) const COINCIDENT_ANGLE: f64 = 1e-9;

/// How a problem's term angles move on a ball (`[B2]`, `[B3]`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Geometry {
    /// `|theta_k(C exp(v)) - theta_k(C)| <= lambda |v|`.
    pub lambda: f64,
    /// `theta_k''(t) >= -kappa |v|^2` along `C exp(t v)` where `0 < theta_k < pi`.
    pub kappa: f64,
    /// `|grad theta_k| <= grad_norm_sup`.
    pub grad_norm_sup: f64,
    /// Terms at the centre earn the `[B4]` credit (single averaging only).
    pub credit: bool,
}

/// Accumulates the terms of one ball; [`Accumulator::finish`] gives the bound.
pub(crate) struct Accumulator<'a> {
    profile: &'a Profile,
    geometry: Geometry,
    r: f64,
    slope: f64,
    lipschitz: f64,
    first_order: f64,
    grad: Vector3<f64>,
    grad_err: f64,
    curvature: f64,
    credit: f64,
    magnitude: f64,
    cost: f64,
    n: usize,
}

/// The bound of one ball, and the cost at its centre.
#[derive(Debug, Clone, Copy)]
pub(crate) struct BallBound {
    /// Proven lower bound of the cost on the ball.
    pub lower_bound: f64,
    /// `sum_k w_k h(theta_k(C))` as computed (not a bound).
    pub centre_cost: f64,
}

impl<'a> Accumulator<'a> {
    /// A ball of (geodesic) radius `r` (inflated here by a relative `1e-12` and `1e-14` for the
    /// rounding of the centre and of the cell geometry).
    #[inline]
    pub(crate) fn new(profile: &'a Profile, geometry: Geometry, r: f64) -> Self {
        let r = r * (1.0 + 1e-12) + 1e-14;
        Accumulator {
            profile,
            geometry,
            r,
            slope: if geometry.credit {
                profile.slope_inf(r)
            } else {
                0.0
            },
            lipschitz: 0.0,
            first_order: 0.0,
            grad: Vector3::zeros(),
            grad_err: 0.0,
            curvature: 0.0,
            credit: 0.0,
            magnitude: 0.0,
            cost: 0.0,
            n: 0,
        }
    }

    /// One term: weight `w`, angle `theta` at the centre and `sin_theta` (the norm of the vee
    /// of the relative rotation), and `grad` computing the gradient of `theta` with respect to
    /// `v` at the centre from the unit axis `u` (`log / theta`).
    #[inline]
    pub(crate) fn add(
        &mut self,
        w: f64,
        theta: f64,
        sin_theta: f64,
        grad: impl FnOnce() -> Vector3<f64>,
    ) {
        let p = self.profile;
        let g = self.geometry;
        self.n += 1;
        let h0 = p.h(theta);
        self.cost += w * h0;
        self.magnitude += w * h0;
        let reach = g.lambda * self.r + ANGLE_ERROR;
        let lo = (theta - reach).max(0.0);
        let hi = theta + reach;
        let h_lo = p.h(lo);
        self.lipschitz += w * h_lo;
        if hi >= PI {
            // [B2] only: the angle may reach pi (a concave kink) on the ball.
            self.first_order += w * h_lo;
        } else if theta <= COINCIDENT_ANGLE || sin_theta.is_nan() || sin_theta <= 0.0 {
            // [B4] (single) or h >= h(0) = 0.
            if g.credit {
                self.first_order -= w * self.slope * (theta + ANGLE_ERROR);
                self.credit += w * self.slope;
            }
        } else {
            // [B3]
            let hs = p.h1_sup(lo, hi);
            let m = p.concavity(lo, hi);
            let h1 = p.h1(theta);
            self.first_order += w * (h0 - hs * ANGLE_ERROR);
            self.grad += grad() * (w * h1);
            self.grad_err += w
                * g.grad_norm_sup
                * (h1 * 64.0 * f64::EPSILON / sin_theta + (m + hs) * ANGLE_ERROR);
            self.curvature += w * (g.lambda * g.lambda * m + g.kappa * hs);
        }
    }

    /// The bound: `max([B2], [B3]/[B4]) - rounding`, at least 0; `data_slack` is subtracted
    /// (`[B6]`, data that are rotations only to within the validation tolerance).
    #[inline]
    pub(crate) fn finish(&self, data_slack: f64) -> BallBound {
        let r = self.r;
        let gnorm = self.grad.norm() * (1.0 + 4.0 * f64::EPSILON) + self.grad_err;
        let drop = ((self.credit - gnorm) * r - 0.5 * self.curvature * r * r).min(0.0);
        let first = self.first_order + drop;
        let best = self.lipschitz.max(first);
        let rounding = 4.0
            * (self.n as f64 + 16.0)
            * f64::EPSILON
            * (self.magnitude + (gnorm + self.credit) * r + self.curvature * r * r);
        let lb = best - rounding - data_slack;
        BallBound {
            lower_bound: if lb.is_nan() { 0.0 } else { lb.max(0.0) },
            centre_cost: self.cost,
        }
    }
}
