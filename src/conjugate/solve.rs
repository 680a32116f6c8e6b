//! Local solvers for conjugate rotation averaging: the quaternion closed form `[H6]` (the
//! initialiser), and Gauss-Newton / IRLS on SO(3) for the chordal and geodesic metrics with
//! squared, L1, Huber or Cauchy loss `[H7]`. Equations: `paper-notes/conjugate.md`.

use super::problem::{ConjugateProblem, DiagnosticSettings};
use crate::deadline::{Deadline, limit_reached, remaining};
use crate::error::{Error, Result};
use crate::objective::{Loss, Objective};
use crate::so3::{Metric, Rotation, exp, hat, log, nearest_rotation, to_quaternion};
use crate::termination::{SolverReport, Termination};
use crate::validate::{at_least_one, check_rotation, non_negative};
use nalgebra::{Matrix3, Matrix4, Quaternion, SMatrix, SymmetricEigen, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Settings of [`solve_conjugate`]. The cost minimised is the problem's objective
/// ([`ConjugateProblem::with_objective`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ConjugateSettings {
    /// Iteration limit (default 200; >= 1).
    pub max_iterations: usize,
    /// Stop when the Riemannian gradient norm is below `gradient_tolerance * total weight`
    /// (default `1e-12`).
    pub gradient_tolerance: f64,
    /// Stop when the accepted step is shorter than this angle in radians (default `1e-13`).
    pub step_tolerance: f64,
    /// Thresholds of the identifiability test; data that do not determine `S` are refused.
    pub diagnostics: DiagnosticSettings,
    /// Start of the iterative solver (default `None`: the quaternion closed form `[H6]`).
    #[serde(with = "crate::so3::serde_rows::optional_rotation")]
    pub init: Option<Rotation>,
    /// Time limit of the solve, seconds (`None`, the default: no limit; the command line's
    /// `--max-seconds`). Checked before each Gauss-Newton / IRLS iteration; when reached the
    /// solve ends with [`Termination::TimeLimit`] at its last
    /// iterate, within one iteration (`O(n)` work) of the limit. The closed-form start is not
    /// interrupted.
    pub max_seconds: Option<f64>,
}

impl Default for ConjugateSettings {
    fn default() -> Self {
        ConjugateSettings {
            max_iterations: 200,
            gradient_tolerance: 1e-12,
            step_tolerance: 1e-13,
            diagnostics: DiagnosticSettings::default(),
            init: None,
            max_seconds: None,
        }
    }
}

impl ConjugateSettings {
    /// Check every value; [`Error::InvalidSettings`] names the first bad one.
    ///
    /// ```
    /// use rotavg::conjugate::ConjugateSettings;
    /// assert!(ConjugateSettings::default().validate().is_ok());
    /// let bad = ConjugateSettings { gradient_tolerance: f64::NAN, ..Default::default() };
    /// assert!(bad.validate().unwrap_err().to_string().contains("gradient_tolerance"));
    /// ```
    pub fn validate(&self) -> Result<()> {
        at_least_one("max_iterations", self.max_iterations)?;
        non_negative("gradient_tolerance", self.gradient_tolerance)?;
        non_negative("step_tolerance", self.step_tolerance)?;
        crate::deadline::validate_max_seconds(self.max_seconds)?;
        self.diagnostics.validate()?;
        if let Some(r) = &self.init {
            check_rotation(|| "init".into(), r)?;
        }
        Ok(())
    }
}

/// A local solution: the estimate `S`, its cost `sum_i w_i rho(d(R_i, S^T L_i S))` under the
/// problem's objective, the chordal cost `g(S)` (contract section 1), and the solver report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConjugateSolution {
    /// The estimate `S`.
    #[serde(with = "crate::so3::serde_rows::rotation")]
    pub estimate: Rotation,
    /// Cost under the objective.
    pub cost: f64,
    /// The chordal L2 cost `g(S)` (the SDP's objective).
    pub chordal_cost: f64,
    /// The objective of `cost`.
    pub objective: Objective,
    /// Iterations, termination, time.
    pub report: SolverReport,
}

/// Quaternion L2, the objective of the closed form.
const QUATERNION_L2: Objective = Objective {
    metric: Metric::Quaternion,
    loss: Loss::L2,
};

/// Left- and right-multiplication matrices of a quaternion, coordinates `(x, y, z, w)`
/// (nalgebra's storage order): `left(p) q = p q`, `right(r) q = q r`.
fn quat_mult_matrices(p: &Quaternion<f64>, r: &Quaternion<f64>) -> Matrix4<f64> {
    let mut m = Matrix4::zeros();
    for k in 0..4 {
        let mut e = nalgebra::Vector4::zeros();
        e[k] = 1.0;
        let q = Quaternion::from(e);
        let d = p * q - q * r;
        m.set_column(k, &d.coords);
    }
    m
}

/// The quaternion closed form `[H6]`: with `q_L`, `q_R` the unit quaternions of `L_i`, `R_i`,
/// each sign-normalised to a non-negative scalar part (conjugation preserves the scalar part
/// `cos(theta / 2)`, so exact pairs then satisfy `q_L q_S = q_S q_R` with the *same* signs),
/// `q_S` is the unit eigenvector of the smallest eigenvalue of
/// `sum_i w_i (P(q_L) - Q(q_R))^T (P(q_L) - Q(q_R))`. Refuses unidentifiable data.
///
/// ```
/// use rotavg::conjugate::{ConjugateProblem, quaternion_closed_form};
/// use rotavg::so3::{exp, angle_between};
/// use nalgebra::Vector3;
/// let s = exp(&Vector3::new(0.4, -0.1, 0.7));
/// let rs = [exp(&Vector3::new(0.5, 0.0, 0.1)), exp(&Vector3::new(0.0, 0.8, -0.3))];
/// let ls: Vec<_> = rs.iter().map(|r| s * r * s.inverse()).collect();
/// let p = ConjugateProblem::from_rotations(&ls, &rs).unwrap();
/// let sol = quaternion_closed_form(&p, &Default::default()).unwrap();
/// assert!(angle_between(&sol.estimate, &s) < 1e-10);
/// ```
pub fn quaternion_closed_form(
    problem: &ConjugateProblem,
    diagnostics: &DiagnosticSettings,
) -> Result<ConjugateSolution> {
    let start = Instant::now();
    problem.require_identifiable(diagnostics)?;
    let mut a = Matrix4::zeros();
    for p in problem.pairs() {
        let mut ql = *to_quaternion(&p.left).quaternion();
        let mut qr = *to_quaternion(&p.right).quaternion();
        if ql.w < 0.0 {
            ql = -ql;
        }
        if qr.w < 0.0 {
            qr = -qr;
        }
        let m = quat_mult_matrices(&ql, &qr);
        a += m.transpose() * m * p.weight;
    }
    let eig = SymmetricEigen::new(a);
    let k = eig.eigenvalues.imin();
    let v = eig.eigenvectors.column(k).into_owned();
    let q = UnitQuaternion::from_quaternion(Quaternion::from(v));
    let s = q.to_rotation_matrix();
    if !s.matrix().iter().all(|x| x.is_finite()) {
        return Err(Error::Solver {
            message: "quaternion closed form: non-finite eigenvector".into(),
        });
    }
    let report = SolverReport {
        name: "quaternion-closed-form".into(),
        iterations: 0,
        termination: Termination::ClosedForm,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok(on_so3(problem, &s, QUATERNION_L2, report))
}

/// Inverse right Jacobian of SO(3): `log(exp(phi) exp(d)) ~ phi + Jr^-1(phi) d`.
fn right_jacobian_inverse(phi: &Vector3<f64>) -> Matrix3<f64> {
    let t = phi.norm();
    let k = hat(phi);
    let c = if t < 1e-4 {
        1.0 / 12.0 + t * t / 720.0
    } else if t > 3.0 {
        // Near pi the coefficient blows up; the Gauss-Newton model only needs a descent direction.
        1.0 / 12.0
    } else {
        1.0 / (t * t) - (1.0 + t.cos()) / (2.0 * t * t.sin())
    };
    Matrix3::identity() + k * 0.5 + k * k * c
}

/// Gauss-Newton normal equations at `s`: (H, b, cost) with `H = sum psi_i w_i J_i^T J_i`,
/// `b = sum psi_i w_i J_i^T r_i` (the Riemannian gradient of the cost is `2 b`).
fn normal_equations(
    problem: &ConjugateProblem,
    s: &Rotation,
    objective: Objective,
) -> (Matrix3<f64>, Vector3<f64>) {
    let sm = *s.matrix();
    let mut h = Matrix3::zeros();
    let mut b = Vector3::zeros();
    let basis = [Vector3::x(), Vector3::y(), Vector3::z()];
    for p in problem.pairs() {
        let (l, r) = (p.left.matrix(), p.right.matrix());
        match objective.metric {
            Metric::Geodesic | Metric::Quaternion => {
                // e = log(L^T S R S^T); S -> S exp(w) gives e + Jr^-1(e) S (R^T - I) w  [H7]
                let e = log(&(p.left.inverse() * s * p.right * s.inverse()));
                let j = right_jacobian_inverse(&e) * sm * (r.transpose() - Matrix3::identity());
                let theta = e.norm();
                let omega = p.weight
                    * match objective.metric {
                        // rho(theta) = (2 sin(theta / 4))^2 has rho' = sin(theta / 2): the IRLS
                        // weight rho' / (2 theta) of the angle (1/4 at 0)
                        Metric::Quaternion if theta > 1e-8 => (0.5 * theta).sin() / (2.0 * theta),
                        Metric::Quaternion => 0.25,
                        _ => objective.irls_weight(theta, 1e-12),
                    };
                h += j.transpose() * j * omega;
                b += j.transpose() * e * omega;
            }
            _ => {
                // r = vec(S R - L S); column k of J = vec(S hat(e_k) R - L S hat(e_k))  [H7]
                let res = sm * r - l * sm;
                let d = res.norm();
                let mut j = SMatrix::<f64, 9, 3>::zeros();
                for (k, e) in basis.iter().enumerate() {
                    let hk = hat(e);
                    let col = sm * hk * r - l * sm * hk;
                    j.set_column(k, &SMatrix::<f64, 9, 1>::from_column_slice(col.as_slice()));
                }
                let rv = SMatrix::<f64, 9, 1>::from_column_slice(res.as_slice());
                let omega = p.weight * objective.irls_weight(d, 1e-12);
                h += j.transpose() * j * omega;
                b += j.transpose() * rv * omega;
            }
        }
    }
    (h, b)
}

/// Minimise the problem's objective `sum_i w_i rho(d(R_i, S^T L_i S))` over SO(3): Gauss-Newton
/// (L2) or IRLS (robust losses, and the quaternion distance `2 sin(theta / 4)` as a loss of the
/// angle: each iteration one Gauss-Newton step with weights `w_i psi(d_i)`) from
/// `settings.init` or the quaternion closed form `[H6]` (which minimises the quaternion cost
/// with the signs of the pairs' quaternions fixed: with outliers not the quaternion distance's
/// minimum, which takes the nearer sign per pair), update `S <- S exp(hat(t delta))`
/// with backtracking (Armijo, `c = 1e-4`) `[H7]`. Stops when the gradient norm
/// `< gradient_tolerance * total weight` ("gradient norm"), the step angle `< step_tolerance`
/// ("step angle"), when the line search fails and the predicted decrease is below
/// `1e3 eps |cost|` (rounding level, counted as converged), or when no decrease is possible
/// otherwise (`Stalled`). Refuses unidentifiable data ([`Error::Degenerate`]).
///
/// ```
/// use rand::SeedableRng;
/// use rotavg::conjugate::{solve_conjugate, synthetic::random_instance, ConjugateSettings};
/// use rotavg::objective::{Loss, Objective};
/// use rotavg::so3::{angle_between, Metric, Rotation};
/// let mut rng = rand::rngs::StdRng::seed_from_u64(6);
/// // 30 pairs, 0.01 rad noise, 20 % of the L_i replaced by random rotations.
/// let (problem, s) = random_instance(30, 0.01, 0.2, &mut rng);
/// let robust = problem.with_objective(Objective::new(Metric::Geodesic, Loss::L1))?;
/// let from_identity = ConjugateSettings { init: Some(Rotation::identity()), ..Default::default() };
/// let sol = solve_conjugate(&robust, &from_identity)?;
/// assert!(angle_between(&sol.estimate, &s) < 0.02); // the outliers are ignored
/// assert!(sol.report.termination.is_converged());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn solve_conjugate(
    problem: &ConjugateProblem,
    settings: &ConjugateSettings,
) -> Result<ConjugateSolution> {
    settings.validate()?;
    problem.require_identifiable(&settings.diagnostics)?;
    let start = Instant::now();
    // the given start (a rotation to the validation tolerance) replaced by its nearest rotation,
    // so that the iteration stays on SO(3) (contract section 1)
    let s = match &settings.init {
        Some(r) => nearest_rotation(r),
        None => quaternion_closed_form(problem, &settings.diagnostics)?.estimate,
    };
    let (s, iterations, termination) = gauss_newton(problem, settings, (s, start));
    let objective = problem.objective();
    let name = match (objective.metric, objective.loss) {
        (Metric::Chordal, Loss::L2) => "chordal-gauss-newton",
        (Metric::Geodesic, Loss::L2) => "geodesic-gauss-newton",
        (Metric::Quaternion, _) => "quaternion-irls",
        (Metric::Chordal, _) => "chordal-irls",
        _ => "geodesic-irls",
    };
    let report = SolverReport {
        name: name.into(),
        iterations,
        termination,
        seconds: start.elapsed().as_secs_f64(),
    };
    Ok(on_so3(problem, &s, objective, report))
}

/// The solution at `s` (contract section 1): `s` replaced by its nearest rotation (the last
/// iterate carries the rounding of its steps), its cost under `objective` and chordal cost
/// those of the problem at exactly that estimate.
fn on_so3(
    problem: &ConjugateProblem,
    s: &Rotation,
    objective: Objective,
    report: SolverReport,
) -> ConjugateSolution {
    let estimate = nearest_rotation(s);
    ConjugateSolution {
        estimate,
        cost: problem.cost_under(&estimate, objective),
        chordal_cost: problem.chordal_cost(&estimate),
        objective,
        report,
    }
}

/// Gauss-Newton / IRLS steps of [`solve_conjugate`] from `s` `[H7]`: the last iterate, the
/// iterations and why they stopped.
fn gauss_newton(
    problem: &ConjugateProblem,
    settings: &ConjugateSettings,
    (mut s, start): (Rotation, Instant),
) -> (Rotation, usize, Termination) {
    let objective = problem.objective();
    let gtol = settings.gradient_tolerance * problem.total_weight();
    let mut cost = problem.cost(&s);
    let mut iterations = 0;
    let deadline = Deadline::after(remaining(settings.max_seconds, start));
    let termination = loop {
        let (h, b) = normal_equations(problem, &s, objective);
        let gnorm = 2.0 * b.norm();
        if !(gnorm.is_finite() && cost.is_finite()) {
            break Termination::NumericalFailure {
                reason: "non-finite cost or gradient".into(),
            };
        }
        if gnorm < gtol {
            break Termination::Converged {
                measure: "gradient norm".into(),
                value: gnorm,
                threshold: gtol,
            };
        }
        let limit = limit_reached(iterations, settings.max_iterations, deadline, (gnorm, gtol));
        if let Some(limit) = limit {
            break limit;
        }
        iterations += 1;
        // Levenberg damping only to keep H invertible.
        let damped = h + Matrix3::identity() * (1e-12 * h.trace().abs() + 1e-300);
        let delta = match damped.cholesky() {
            Some(c) => -c.solve(&b),
            None => -b,
        };
        let slope = 2.0 * b.dot(&delta); // directional derivative (< 0)
        let Some((cand, c, t)) = armijo(problem, &s, cost, &delta, slope) else {
            break failed_line_search(cost, slope, &delta, gnorm, gtol, settings);
        };
        s = cand;
        cost = c;
        let step = t * delta.norm();
        if step < settings.step_tolerance {
            break Termination::Converged {
                measure: "step angle".into(),
                value: step,
                threshold: settings.step_tolerance,
            };
        }
    };
    (s, iterations, termination)
}

/// Backtracking along `S exp(hat(t delta))` from `t = 1` (halved, at most 40 times) until the
/// Armijo condition `cost(t) <= cost + 1e-4 t slope` holds: the point, its cost and `t`.
fn armijo(
    problem: &ConjugateProblem,
    s: &Rotation,
    cost: f64,
    delta: &Vector3<f64>,
    slope: f64,
) -> Option<(Rotation, f64, f64)> {
    let mut t = 1.0;
    for _ in 0..40 {
        let cand = s * exp(&(delta * t));
        let c = problem.cost(&cand);
        if c <= cost + 1e-4 * t * slope {
            return Some((cand, c, t));
        }
        t *= 0.5;
    }
    None
}

/// Why the iteration stops when no step decreases the cost: converged when the model predicts
/// a decrease below the rounding level of the cost (no representable progress: stationary to
/// precision) or the step is below the step tolerance, stalled otherwise.
fn failed_line_search(
    cost: f64,
    slope: f64,
    delta: &Vector3<f64>,
    gnorm: f64,
    gtol: f64,
    settings: &ConjugateSettings,
) -> Termination {
    let resolution = 1e3 * f64::EPSILON * cost.abs();
    if -slope <= resolution {
        return Termination::Converged {
            measure: "predicted decrease (cost rounding level)".into(),
            value: -slope,
            threshold: resolution,
        };
    }
    let step_tolerance = settings.step_tolerance.max(1e-10);
    if delta.norm() < step_tolerance {
        return Termination::Converged {
            measure: "step angle".into(),
            value: delta.norm(),
            threshold: step_tolerance,
        };
    }
    Termination::Stalled {
        value: gnorm,
        threshold: gtol,
    }
}
