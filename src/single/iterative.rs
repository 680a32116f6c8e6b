//! The iterative means: geodesic L2 (Karcher) `[S3]`, geodesic L1 (Weiszfeld on SO(3)) `[S5]`
//! and chordal L1 (majorise-minimise / IRLS on SO(3)) `[S6]`, plus the Euclidean geometric
//! median in `R^{3x3}` used to start the chordal L1 mean and to bound it `[S7]`.
//!
//! Every method evaluates the cost once per accepted step and backtracks (halving the step, at
//! most [`MAX_BACKTRACKS`] times) if a step would increase it, so the cost never increases.

use super::closed_form::chordal_l2_local;
use super::problem::SingleProblem;
use super::solve::{Local, Norm, SingleSettings};
use crate::deadline::{Deadline, limit_reached, remaining};
use crate::so3::{self, Rotation};
use crate::termination::Termination;
use nalgebra::{Matrix3, Vector3};
use std::f64::consts::SQRT_2;

/// A sample within this angle (radians) of the estimate is treated as coinciding with it: its
/// term is handled by the subgradient ball of `[S5]` instead of a division by `theta_i`. The
/// error this makes in a lower bound is accounted for (`[S4]`, slack term).
pub const COINCIDENCE_ANGLE: f64 = 1e-12;

/// Maximum number of step halvings before an iteration is declared stalled.
pub const MAX_BACKTRACKS: usize = 40;

/// Below this distance (radians) to the nearest sample, or below 10 times the last step, the
/// Weiszfeld iterations test whether that sample is the minimiser (subgradient condition
/// `[S5]`) and jump to it if so.
const SAMPLE_TEST_RADIUS: f64 = 1e-3;

/// Everything the geodesic methods need at one point `R`.
#[derive(Debug, Clone)]
pub(crate) struct GeodesicEval {
    /// Which cost (`p`).
    pub norm: Norm,
    /// `sum_i w_i theta_i^p`.
    pub cost: f64,
    /// L2: `sum_i w_i log(R^T R_i)`; L1: `sum_{i not coincident} w_i log(R^T R_i) / theta_i`.
    /// This is minus the (sub)gradient (`[S3]`, `[S5]`) up to the factor 2 for L2.
    pub descent: Vector3<f64>,
    /// L1: `sum_{i not coincident} w_i / theta_i` (the Weiszfeld denominator).
    pub inverse_distance_weight: f64,
    /// Total weight of the samples within [`COINCIDENCE_ANGLE`] of `R`.
    pub coincident_weight: f64,
    /// `sum w_i theta_i` over those samples (the slack of `[S4]`).
    pub coincident_slack: f64,
    /// Nearest non-coincident sample `(index, theta)`, if any.
    pub nearest: Option<(usize, f64)>,
}

impl GeodesicEval {
    /// Norm of the (minimum-norm sub)gradient: L2 `2 |sum w_i log_i|`; L1
    /// `max(0, |sum w_i u_i| - coincident weight)` `[S5]`.
    pub fn gradient_norm(&self, norm: Norm) -> f64 {
        match norm {
            Norm::L2 => 2.0 * self.descent.norm(),
            Norm::L1 => (self.descent.norm() - self.coincident_weight).max(0.0),
        }
    }
}

/// Evaluate cost and (sub)gradient data of the geodesic L^p cost at `r`.
pub(crate) fn eval_geodesic(problem: &SingleProblem, r: &Rotation, norm: Norm) -> GeodesicEval {
    let rt = r.inverse();
    let mut e = GeodesicEval {
        norm,
        cost: 0.0,
        descent: Vector3::zeros(),
        inverse_distance_weight: 0.0,
        coincident_weight: 0.0,
        coincident_slack: 0.0,
        nearest: None,
    };
    for (k, ri, w) in problem.samples() {
        let v = so3::log(&(rt * ri));
        let t = v.norm();
        match norm {
            Norm::L2 => {
                e.cost += w * t * t;
                e.descent += v * w;
            }
            Norm::L1 => {
                e.cost += w * t;
                if t <= COINCIDENCE_ANGLE {
                    e.coincident_weight += w;
                    e.coincident_slack += w * t;
                } else {
                    e.descent += v * (w / t);
                    e.inverse_distance_weight += w / t;
                }
            }
        }
        if t > COINCIDENCE_ANGLE && e.nearest.is_none_or(|(_, d)| t < d) {
            e.nearest = Some((k, t));
        }
    }
    e
}

/// What the descent driver needs at an iterate of one of the iterative means.
pub(crate) trait Iterate {
    /// The cost.
    fn cost(&self) -> f64;
    /// Norm of the (minimum-norm sub)gradient.
    fn gradient_norm(&self) -> f64;
    /// The nearest sample `(index, distance)`, for the sample test of the L1 means (`None` for
    /// smooth costs: no test).
    fn nearest_sample(&self) -> Option<(usize, f64)>;
}

impl Iterate for GeodesicEval {
    fn cost(&self) -> f64 {
        self.cost
    }
    fn gradient_norm(&self) -> f64 {
        GeodesicEval::gradient_norm(self, self.norm)
    }
    fn nearest_sample(&self) -> Option<(usize, f64)> {
        (self.norm == Norm::L1).then_some(self.nearest).flatten()
    }
}

/// One iterative mean for the descent driver.
struct Method<E, F, S> {
    name: &'static str,
    /// What the gradient test measures.
    measure: &'static str,
    /// Expanding line search (the slow majorise-minimise steps of chordal L1).
    expand: bool,
    eval: F,
    /// The proposed tangent step `v` (`R_new = R exp(v)`); `None`: no step possible.
    step: S,
    _iterate: std::marker::PhantomData<E>,
}

/// The loop shared by the iterative means: gradient test; for the L1 means the sample test
/// `[S5]` (if the nearest sample satisfies the optimality condition and is no worse, it is the
/// answer: avoids the slow approach of Weiszfeld iterations to a sample); the method's step
/// with a line search that never increases the cost; step-angle test.
fn descend<E, F, S>(
    problem: &SingleProblem,
    settings: &SingleSettings,
    start: Rotation,
    method: Method<E, F, S>,
) -> Local
where
    E: Iterate,
    F: Fn(&Rotation) -> E,
    S: Fn(&Rotation, &E) -> Option<Vector3<f64>>,
{
    // the method's result: where it stopped, after how many iterations, and why
    let stop = |estimate, iterations, termination| Local {
        estimate,
        iterations,
        termination,
        name: method.name,
    };
    let tol = settings.gradient_tolerance;
    let total = problem.total_weight();
    let mut r = start;
    let mut e = (method.eval)(&r);
    let mut last_step = 0.0;
    // Samples whose optimality test failed (the test depends on the sample only).
    let mut rejected: Vec<usize> = Vec::new();
    let deadline = Deadline::after(settings.max_seconds);
    let mut it = 0;
    loop {
        let g = e.gradient_norm() / total;
        if g <= tol {
            return stop(r, it, converged(method.measure, g, tol));
        }
        if let Some(limit) = limit_reached(it, settings.max_iterations, deadline, (g, tol)) {
            return stop(r, it, limit);
        }
        it += 1;
        if let Some((k, t)) = e.nearest_sample()
            && (t < SAMPLE_TEST_RADIUS || t < 10.0 * last_step)
            && !rejected.contains(&k)
        {
            let rk = problem.rotations()[k];
            let ek = (method.eval)(&rk);
            let gk = ek.gradient_norm() / total;
            if ek.cost() <= e.cost() && gk <= tol {
                let measure = "min-norm subgradient / total weight at a sample";
                return stop(rk, it, converged(measure, gk, tol));
            }
            if gk > tol {
                rejected.push(k);
            }
        }
        let accepted = (method.step)(&r, &e).and_then(|v| {
            line_search(
                problem.len(),
                &r,
                e.cost(),
                &v,
                method.expand,
                &method.eval,
                E::cost,
            )
        });
        let Some((r_new, e_new, step)) = accepted else {
            let stalled = Termination::Stalled {
                value: g,
                threshold: tol,
            };
            return stop(r, it - 1, stalled);
        };
        r = r_new;
        e = e_new;
        last_step = step;
        if step < settings.step_tolerance {
            let measure = "step angle (rad)";
            return stop(r, it, converged(measure, step, settings.step_tolerance));
        }
    }
}

/// The given start, or the chordal L2 mean `[S1]`.
fn init_or_chordal_mean(problem: &SingleProblem, init: Option<&Rotation>) -> Rotation {
    init.copied()
        .unwrap_or_else(|| chordal_l2_local(problem).estimate)
}

/// Geodesic L2 (Karcher) mean `[S3]`: `R <- R exp(t v)`, `v = sum_i w_i log(R^T R_i) / W`,
/// `t = 1` unless that increases the cost (then halved). Starts from the chordal L2 mean.
/// Stops when `2 |v| <= gradient_tolerance` (gradient norm / W) or the step angle is below
/// `step_tolerance`.
pub(crate) fn geodesic_l2_local(
    problem: &SingleProblem,
    settings: &SingleSettings,
    init: Option<&Rotation>,
) -> Local {
    geodesic_local(problem, settings, init, Norm::L2)
}

/// Geodesic L1 mean by Weiszfeld on SO(3) (Hartley, Aftab & Trumpf 2011) with the Vardi-Zhang
/// modification at samples `[S5]`: `v = (1 - w_Z / |G|) G / D` with `G = sum w_i u_i`,
/// `u_i = log(R^T R_i) / theta_i`, `D = sum w_i / theta_i` over non-coincident samples and
/// `w_Z` the weight of samples coinciding with `R`. Starts from the chordal L2 mean. Near a
/// sample it tests the subgradient condition at that sample and jumps there when it holds.
pub(crate) fn geodesic_l1_local(
    problem: &SingleProblem,
    settings: &SingleSettings,
    init: Option<&Rotation>,
) -> Local {
    geodesic_local(problem, settings, init, Norm::L1)
}

/// The geodesic mean with exponent `norm` ([`geodesic_l2_local`], [`geodesic_l1_local`]): the
/// two differ only in their step, both evaluate [`eval_geodesic`] and start from `init` or the
/// chordal L2 mean.
fn geodesic_local(
    problem: &SingleProblem,
    settings: &SingleSettings,
    init: Option<&Rotation>,
    norm: Norm,
) -> Local {
    let total = problem.total_weight();
    let (name, measure) = match norm {
        Norm::L2 => ("karcher", "gradient norm / total weight"),
        Norm::L1 => ("weiszfeld-so3", "min-norm subgradient / total weight"),
    };
    let step = |_: &Rotation, e: &GeodesicEval| match norm {
        Norm::L2 => Some(e.descent / total),
        Norm::L1 => {
            let gn = e.descent.norm();
            // All samples coincide with R, or G = 0: then the gradient test has passed.
            (gn > 0.0 && e.inverse_distance_weight > 0.0)
                .then(|| e.descent * ((1.0 - e.coincident_weight / gn) / e.inverse_distance_weight))
        }
    };
    let method = Method {
        name,
        measure,
        expand: false,
        eval: |x: &Rotation| eval_geodesic(problem, x, norm),
        step,
        _iterate: std::marker::PhantomData,
    };
    descend(
        problem,
        settings,
        init_or_chordal_mean(problem, init),
        method,
    )
}

/// The rounding error of a cost summed over `n` terms, `(n + 8) eps |f|`: an increase below it
/// is not an increase (without this slack, a converged iterate on 10^6 samples would backtrack
/// 40 times on rounding noise).
fn rounding_slack(n: usize, cost: f64) -> f64 {
    (n as f64 + 8.0) * f64::EPSILON * cost.abs()
}

/// Line search along `R exp(t v)`: halve `t` from 1 until the cost does not increase (beyond
/// [`rounding_slack`]); if `t = 1`
/// decreases it and `expand` is set, keep doubling `t` while the cost strictly decreases and
/// the step stays below pi/2 (this accelerates the slow, majorise-minimise-like L1 steps, e.g.
/// when the minimiser is a sample). Returns the point, its evaluation and the step angle.
fn line_search<E>(
    n: usize,
    r: &Rotation,
    cost: f64,
    v: &Vector3<f64>,
    expand: bool,
    eval: impl Fn(&Rotation) -> E,
    cost_of: impl Fn(&E) -> f64,
) -> Option<(Rotation, E, f64)> {
    let vn = v.norm();
    let mut t = 1.0;
    let slack = rounding_slack(n, cost);
    for _ in 0..MAX_BACKTRACKS {
        let r_new = r * so3::exp(&(v * t));
        let e_new = eval(&r_new);
        if cost_of(&e_new) <= cost + slack {
            let mut best = (r_new, e_new, t * vn);
            if expand && t == 1.0 {
                for _ in 0..MAX_BACKTRACKS {
                    let t2 = 2.0 * best.2 / vn.max(f64::MIN_POSITIVE);
                    if t2 * vn > std::f64::consts::FRAC_PI_2 || t2.is_nan() {
                        break;
                    }
                    let r2 = r * so3::exp(&(v * t2));
                    let e2 = eval(&r2);
                    if cost_of(&e2) < cost_of(&best.1) {
                        best = (r2, e2, t2 * vn);
                    } else {
                        break;
                    }
                }
            }
            return Some(best);
        }
        t *= 0.5;
    }
    None
}

/// Everything the chordal L1 method needs at one point `R`.
#[derive(Debug, Clone)]
pub(crate) struct ChordalEval {
    /// `sum_i w_i ||R_i - R||_F`.
    pub cost: f64,
    /// `sum_{i not coincident} 2 w_i vee(R^T R_i) / c_i`: minus the Riemannian gradient in
    /// body coordinates `[S6]`.
    pub descent: Vector3<f64>,
    /// `sum_{i not coincident} (w_i / c_i) R_i`: the IRLS matrix `[S6]`.
    pub irls_sum: Matrix3<f64>,
    /// `sum_{i not coincident} 2 w_i / c_i`.
    pub curvature: f64,
    /// Total weight of samples with `c_i <= COINCIDENCE_ANGLE`.
    pub coincident_weight: f64,
    /// Nearest non-coincident sample `(index, c_i)`.
    pub nearest: Option<(usize, f64)>,
}

impl ChordalEval {
    /// `max(0, |G| - sqrt(2) w_Z)`: norm of the minimum-norm Riemannian subgradient `[S6]`.
    pub fn gradient_norm(&self) -> f64 {
        (self.descent.norm() - SQRT_2 * self.coincident_weight).max(0.0)
    }
}

/// Evaluate the chordal L1 cost and its IRLS data at `r`.
pub(crate) fn eval_chordal_l1(problem: &SingleProblem, r: &Rotation) -> ChordalEval {
    let rm = r.matrix();
    let rt = r.inverse();
    let mut e = ChordalEval {
        cost: 0.0,
        descent: Vector3::zeros(),
        irls_sum: Matrix3::zeros(),
        curvature: 0.0,
        coincident_weight: 0.0,
        nearest: None,
    };
    for (k, ri, w) in problem.samples() {
        let c = (ri.matrix() - rm).norm();
        e.cost += w * c;
        if c <= COINCIDENCE_ANGLE {
            e.coincident_weight += w;
        } else {
            let a = w / c;
            e.descent += so3::vee((rt * ri).matrix()) * (2.0 * a);
            e.irls_sum += ri.matrix() * a;
            e.curvature += 2.0 * a;
            if e.nearest.is_none_or(|(_, d)| c < d) {
                e.nearest = Some((k, c));
            }
        }
    }
    e
}

/// Chordal L1 mean `[S6]`: IRLS `R <- proj(sum_i (w_i / ||R_i - R||_F) R_i)`, a
/// majorise-minimise step (the cost cannot increase); on a sample (where a weight would be
/// infinite) a Vardi-Zhang step `v = (1 - sqrt(2) w_Z / |G|) G / (sum 2 w_i / c_i)` with
/// backtracking. Starts from the projection of the Euclidean geometric median of the
/// matrices `[S7]`.
pub(crate) fn chordal_l1_local(
    problem: &SingleProblem,
    settings: &SingleSettings,
    init: Option<&Rotation>,
) -> Local {
    let begun = std::time::Instant::now();
    let r = match init {
        Some(r) => *r,
        None => {
            let median = euclidean_median(
                problem,
                settings.max_iterations,
                settings.gradient_tolerance,
                Deadline::after(settings.max_seconds),
            );
            so3::project_to_so3(&median.point).unwrap_or_else(|| chordal_l2_local(problem).estimate)
        }
    };
    // one clock: the descent gets what the start left
    let settings = &SingleSettings {
        max_seconds: remaining(settings.max_seconds, begun),
        ..settings.clone()
    };
    descend(
        problem,
        settings,
        r,
        Method {
            name: "chordal-l1-irls",
            measure: "min-norm subgradient / total weight",
            expand: true,
            eval: |x: &Rotation| eval_chordal_l1(problem, x),
            step: |r: &Rotation, e: &ChordalEval| {
                if e.coincident_weight == 0.0 {
                    // IRLS (majorise-minimise) step
                    so3::project_to_so3(&e.irls_sum).map(|p| so3::log(&(r.inverse() * p)))
                } else {
                    // Vardi-Zhang step at a sample
                    let gn = e.descent.norm();
                    (gn > 0.0 && e.curvature > 0.0).then(|| {
                        e.descent * ((1.0 - SQRT_2 * e.coincident_weight / gn) / e.curvature)
                    })
                }
            },
            _iterate: std::marker::PhantomData,
        },
    )
}

impl Iterate for ChordalEval {
    fn cost(&self) -> f64 {
        self.cost
    }
    fn gradient_norm(&self) -> f64 {
        ChordalEval::gradient_norm(self)
    }
    fn nearest_sample(&self) -> Option<(usize, f64)> {
        self.nearest
    }
}

/// A point of `R^{3x3}` with the Euclidean geometric-median data `[S7]`.
#[derive(Debug, Clone)]
pub(crate) struct EuclideanMedian {
    /// The point `M`.
    pub point: Matrix3<f64>,
    /// `f_E(M) = sum_i w_i ||R_i - M||_F`.
    pub cost: f64,
    /// Norm of the minimum-norm subgradient of `f_E` at `M` (coincident samples contribute a
    /// ball of radius `w_i`).
    pub gradient_norm: f64,
    /// `sum w_i ||R_i - M||_F` over the samples treated as coincident with `M`.
    pub coincident_slack: f64,
}

fn eval_euclidean(
    problem: &SingleProblem,
    y: &Matrix3<f64>,
) -> (EuclideanMedian, Matrix3<f64>, f64) {
    let mut cost = 0.0;
    let mut g = Matrix3::zeros(); // sum w (R_i - y) / d_i  (descent direction)
    let mut num = Matrix3::zeros(); // sum w R_i / d_i
    let mut den = 0.0;
    let mut wz = 0.0;
    let mut slack = 0.0;
    for (ri, &w) in problem.rotations().iter().zip(problem.weights()) {
        let diff = ri.matrix() - y;
        let d = diff.norm();
        cost += w * d;
        if d <= COINCIDENCE_ANGLE {
            wz += w;
            slack += w * d;
        } else {
            g += diff * (w / d);
            num += ri.matrix() * (w / d);
            den += w / d;
        }
    }
    let gnorm = g.norm();
    let median = EuclideanMedian {
        point: *y,
        cost,
        gradient_norm: (gnorm - wz).max(0.0),
        coincident_slack: slack,
    };
    // Vardi-Zhang modified Weiszfeld step: y + (1 - wz/|G|)^+ (T(y) - y), T(y) = num / den.
    let next = if den > 0.0 && gnorm > 0.0 {
        let t = (1.0 - wz / gnorm).max(0.0);
        y + (num / den - y) * t
    } else {
        *y
    };
    (median, next, wz)
}

/// Geometric median of the sample matrices in `R^{3x3}` (Weiszfeld with the Vardi-Zhang
/// modification, monotone in the cost), from `sum w_i R_i / W`. Stops when the minimum-norm
/// subgradient norm / W is at most `gradient_tolerance`, the step is below 1e-15 (relative),
/// after 3 steps without a strict decrease of the cost (rounding floor), or after
/// `max_iterations`. Returns, among the iterates, the one with the largest lower bound `[S7]`
/// `f_E(M) - |g| (sqrt 3 + |M|_F) - 2 slack` (every iterate gives a valid bound).
pub(crate) fn euclidean_median(
    problem: &SingleProblem,
    max_iterations: usize,
    gradient_tolerance: f64,
    deadline: Option<Deadline>,
) -> EuclideanMedian {
    let total = problem.total_weight();
    let bound = |m: &EuclideanMedian| {
        m.cost - m.gradient_norm * (3f64.sqrt() + m.point.norm()) - 2.0 * m.coincident_slack
    };
    let mut y = super::closed_form::weighted_matrix_sum(problem) / total;
    let (mut cur, mut next, _) = eval_euclidean(problem, &y);
    let mut best = cur.clone();
    let mut flat = 0;
    for _ in 0..max_iterations {
        if cur.gradient_norm / total <= gradient_tolerance || deadline.is_some_and(|d| d.passed()) {
            break;
        }
        let (cand, cand_next, _) = eval_euclidean(problem, &next);
        if cand.cost.is_nan() || cand.cost > cur.cost + rounding_slack(problem.len(), cur.cost) {
            break;
        }
        if cand.cost >= cur.cost {
            flat += 1;
        }
        let moved = (next - y).norm();
        y = next;
        cur = cand;
        next = cand_next;
        if bound(&cur) > bound(&best) {
            best = cur.clone();
        }
        if flat >= 3 || moved <= 1e-15 * (1.0 + y.norm()) {
            break;
        }
    }
    best
}

/// The termination of a mean whose `measure` is `value`, within `threshold`.
fn converged(measure: &str, value: f64, threshold: f64) -> Termination {
    Termination::Converged {
        measure: measure.into(),
        value,
        threshold,
    }
}
