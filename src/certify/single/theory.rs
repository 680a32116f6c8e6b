//! Certificates for single rotation averaging (`paper-notes/single.md`): a proven lower bound on
//! the global minimum of `sum_i w_i d(R_i, R)^p`, computed from the data and the estimate only
//! (never from a solver's own claims), and the verdict of [`crate::Certificate::from_bounds`].
//!
//! - chordal L2 `[S1]`: the global minimum value `6W - 2 (s1 + s2 + sign(det M) s3)` from the
//!   singular values of `M = sum w_i R_i`;
//! - quaternion L2 `[S2b]`/`[S2c]`: exact value `2W - 2 |sum w_i s_i q_i|` when the aligned
//!   quaternions have pairwise non-negative inner products (e.g. all samples within pi/2 of the
//!   estimate), else the Cauchy-Schwarz bound `2W - 2 sqrt(W lambda_max(sum w_i q_i q_i^T))`;
//! - geodesic L2/L1 `[S4]`: `f(R) - |g| rho` when all samples lie within `rho < pi/2` of `R`,
//!   else no bound (inconclusive, naming the farthest sample);
//! - chordal L1 `[S7]`: `f_E(M) - |g| (sqrt 3 + |M|_F)` at a Euclidean geometric-median iterate.
//!
//! Every bound subtracts a floating-point safety margin (`rounding_margin`). The theorems are
//! one rung (`TheoryRung`) of a single certification.

use crate::certify::branch_and_bound::terms::projected_samples;
use crate::certify::log::Prediction;
use crate::certify::one_rotation::{Bound, RotationState};
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifyMode;
use crate::deadline::Deadline;
use crate::error::Result;
use crate::linalg::compensated::Accumulator;
use crate::objective::{Loss, Objective};
use crate::single::closed_form::{aligned_sum, sample_quaternions, weighted_matrix_sum};
use crate::single::iterative::{euclidean_median, eval_geodesic};
use crate::single::solve::Norm;
use crate::single::{SingleProblem, SingleSettings, SingleSolution};
use crate::so3::{self, Metric, Rotation};
use nalgebra::Matrix4;
use std::f64::consts::FRAC_PI_2;

/// Above this many samples the O(n^2) pairwise test of `[S2b]` is skipped (the O(n) ball test
/// is still applied).
pub const PAIRWISE_TEST_LIMIT: usize = 2048;

/// Iterations of [`enclosing_centre`] (each one pass over the samples).
const ENCLOSING_ITERATIONS: usize = 100;

/// Margin added to measured angles before comparing with pi/2 (their computed accuracy is a few
/// ulps; `[S4]`).
const ANGLE_MARGIN: f64 = 1e-12;

/// Samples whose `||R^T R - I||_F` exceeds this are not rotations to rounding (data read within
/// the validation tolerance, e.g. matrices printed with 6 digits): the theorems `[S2]`-`[S7]`,
/// which hold for rotations, are applied to their nearest rotations, and the data margin `[B6]`
/// of that replacement is subtracted (issue 24: the bound is of the cost of the data as given).
const EXACT_SAMPLE_DEFECT: f64 = 1e-13;

/// The theorems `[S1]`-`[S7]` for the estimate (no bound for the other costs). The chordal L2
/// closed form `[S1]` holds for any matrices; the others are applied to the samples' nearest
/// rotations where a sample is not a rotation to rounding, minus the data margin `[B6]`.
fn theory_bound(
    problem: &SingleProblem,
    estimate: &Rotation,
    cost: f64,
    deadline: Option<Deadline>,
) -> (Option<f64>, String) {
    let objective = problem.objective();
    let inexact = |r: &Rotation| so3::rotation_defect(r.matrix()).0 > EXACT_SAMPLE_DEFECT;
    if objective != Objective::new(Metric::Chordal, Loss::L2)
        && problem.rotations().iter().any(inexact)
    {
        let (samples, slack) = projected_samples(problem, inexact);
        let exact = SingleProblem::new(
            samples
                .iter()
                .map(|m| Rotation::from_matrix_unchecked(*m))
                .collect(),
            Some(problem.weights().to_vec()),
        )
        .and_then(|p| p.with_objective(objective));
        let Ok(exact) = exact else {
            return (
                None,
                "the samples' nearest rotations do not form a problem".into(),
            );
        };
        let (lb, text) = theory_bound_exact(&exact, estimate, exact.cost(estimate), deadline);
        let lb = lb.map(|l| l - slack).filter(|l| l.is_finite());
        return (
            lb,
            format!(
                "{text}; applied to the nearest rotations of the samples that are rotations only \
                 to the validation tolerance, less their data margin [B6] {slack:.1e}"
            ),
        );
    }
    theory_bound_exact(problem, estimate, cost, deadline)
}

/// [`theory_bound`] for samples that are rotations to rounding (and chordal L2 for any).
fn theory_bound_exact(
    problem: &SingleProblem,
    estimate: &Rotation,
    cost: f64,
    deadline: Option<Deadline>,
) -> (Option<f64>, String) {
    let objective = problem.objective();
    match (objective.metric, objective.loss) {
        (Metric::Chordal, Loss::L2) => chordal_l2_bound(problem, cost),
        (Metric::Quaternion, Loss::L2) => quaternion_l2_bound(problem, estimate, cost),
        (Metric::Geodesic, Loss::L2) => geodesic_ball_bound(problem, estimate, Norm::L2),
        (Metric::Geodesic, Loss::L1) => geodesic_ball_bound(problem, estimate, Norm::L1),
        (Metric::Chordal, Loss::L1) => chordal_l1_bound(problem, deadline),
        _ => (None, format!("no theorem bounds the {objective} cost")),
    }
}

/// Safety margin for the rounding error of a computed cost `f = sum_i w_i d_i^p` of `n` terms
/// (summation: `(n + 8) eps f`), doubled, plus the error of the distances themselves (a few
/// ulps of absolute error per angle: `16 eps (W + sqrt(W f))`).
pub(crate) fn rounding_margin(n: usize, cost: f64, total_weight: f64) -> f64 {
    let eps = f64::EPSILON;
    2.0 * (n as f64 + 8.0) * eps * cost.abs()
        + 16.0 * eps * (total_weight + (total_weight * cost.abs()).sqrt())
}

/// A convex cost's bound from its value `cost` at a point, over a set within reach of it
/// (`[S4]`, `[S7]`): `cost - |g| L - 2 slack` less the rounding margin, `step = |g| L` (the
/// subgradient's norm, its rounding included, times the set's reach), `slack` the coincident
/// samples' (whose subgradient is any vector of the unit ball).
fn first_order_bound(problem: &SingleProblem, cost: f64, step: f64, slack: f64) -> f64 {
    cost - step - 2.0 * slack - rounding_margin(problem.len(), cost, problem.total_weight())
}

/// `[S1]`: `min_R sum w_i ||R_i - R||^2 = sum w_i ||R_i||_F^2 + 3W - 2 (s1 + s2 + sign(det M) s3)`
/// (`= 6W - ...` for exactly orthogonal samples; the samples are orthogonal only within the
/// validation tolerance, so `sum w_i ||R_i||_F^2` is evaluated, in double-double, not assumed).
fn chordal_l2_bound(problem: &SingleProblem, cost: f64) -> (Option<f64>, String) {
    let total = problem.total_weight();
    let m = weighted_matrix_sum(problem);
    let sv = m.singular_values();
    let mut s = [sv[0], sv[1], sv[2]];
    s.sort_by(|a, b| b.total_cmp(a));
    let sign = if m.determinant() < 0.0 { -1.0 } else { 1.0 };
    let mut norms = Accumulator::default();
    for (_, r, w) in problem.samples() {
        for v in r.matrix().iter() {
            norms.add_triple(w, *v, *v);
        }
    }
    let sum_norms = norms.value() - norms.bound();
    let fstar = sum_norms + 3.0 * total - 2.0 * (s[0] + s[1] + sign * s[2]);
    let lb =
        fstar - rounding_margin(problem.len(), cost, total) - 16.0 * f64::EPSILON * 6.0 * total;
    let mut text = format!(
        "closed form [S1]: global minimum sum w_i |R_i|^2 + 3W - 2(s1 + s2 + sign(det M) s3) = {fstar:.9e} from the singular values of M = sum w_i R_i"
    );
    // Umeyama: the maximiser of tr(R^T M) is unique iff rank M >= 2 and, when det M < 0,
    // s2 > s3.
    let tiny = 1e-12 * s[0].max(f64::MIN_POSITIVE);
    if s[1] <= tiny || (sign < 0.0 && s[1] - s[2] <= tiny) {
        text.push_str(" (M is degenerate: the minimiser is not unique, the minimum value is)");
    }
    (Some(lb), text)
}

/// `[S2b]` / `[S2c]`.
fn quaternion_l2_bound(
    problem: &SingleProblem,
    estimate: &Rotation,
    cost: f64,
) -> (Option<f64>, String) {
    let total = problem.total_weight();
    let n = problem.len();
    let quats = sample_quaternions(problem);
    let q = so3::to_quaternion(estimate).into_inner().coords;
    let (m, flipped) = aligned_sum(&quats, problem.weights(), &q);
    let (far, rho) = problem.farthest(estimate);
    let margin = rounding_margin(n, cost, total) + 16.0 * f64::EPSILON * 2.0 * total;
    let in_ball = rho + ANGLE_MARGIN < FRAC_PI_2;
    let pairwise = !in_ball && n <= PAIRWISE_TEST_LIMIT && {
        let aligned: Vec<_> = quats
            .iter()
            .zip(&flipped)
            .map(|(qi, &f)| if f { -qi } else { *qi })
            .collect();
        aligned.iter().enumerate().all(|(i, a)| {
            aligned[i + 1..]
                .iter()
                .all(|b| a.dot(b) >= 16.0 * f64::EPSILON)
        })
    };
    if in_ball || pairwise {
        let fstar = 2.0 * total - 2.0 * m.norm();
        let why = if in_ball {
            format!("all samples lie within {rho:.6} rad < pi/2 of the estimate")
        } else {
            "the sign-aligned sample quaternions have pairwise non-negative inner products".into()
        };
        (
            Some(fstar - margin),
            format!(
                "quaternion L2 [S2b]: {why}, so the global minimum is 2W - 2|sum w_i s_i q_i| = {fstar:.9e}"
            ),
        )
    } else {
        let mut a = Matrix4::zeros();
        for (qi, w) in quats.iter().zip(problem.weights()) {
            a += qi * qi.transpose() * *w;
        }
        let lmax = a.symmetric_eigenvalues().max() + 16.0 * f64::EPSILON * total;
        let lb = 2.0 * total - 2.0 * (total * lmax).sqrt() - margin;
        (
            Some(lb),
            format!(
                "quaternion L2 [S2c]: sample {far} is {rho:.6} rad (>= pi/2) from the estimate and the aligned quaternions are not pairwise non-negative{}; Cauchy-Schwarz bound 2W - 2 sqrt(W lambda_max(sum w_i q_i q_i^T))",
                if n > PAIRWISE_TEST_LIMIT {
                    " (pairwise test skipped: too many samples)"
                } else {
                    ""
                }
            ),
        )
    }
}

/// `[S4]`: the pi/2-ball bound for the geodesic L^p costs, with the ball centred on the
/// estimate or, when the samples do not fit there, on an approximate minimal enclosing centre
/// `o` (`[S4b]`): `f(R) - |g| (theta(o, R) + rho_o)` when every sample and the estimate lie
/// within `rho_o < pi/2` and `theta(o, R) < pi/2` of `o`.
fn geodesic_ball_bound(
    problem: &SingleProblem,
    estimate: &Rotation,
    norm: Norm,
) -> (Option<f64>, String) {
    let total = problem.total_weight();
    let (far, rho_at_estimate) = problem.farthest(estimate);
    let rho = rho_at_estimate + ANGLE_MARGIN;
    // the radius L of the segment from the estimate to a minimiser, and how it was found
    let (radius, why) = if rho < FRAC_PI_2 {
        (
            rho,
            format!(
                "pi/2-ball bound [S4]: all samples within rho = {rho:.6} rad < pi/2 of the estimate (farthest: sample {far})"
            ),
        )
    } else {
        let o = enclosing_centre(problem, estimate);
        let (far_o, rho_o) = problem.farthest(&o);
        let rho_o = rho_o + ANGLE_MARGIN;
        let to_estimate = so3::angle_between(&o, estimate) + ANGLE_MARGIN;
        if rho_o >= FRAC_PI_2 || to_estimate >= FRAC_PI_2 {
            return (
                None,
                format!(
                    "no lower bound: sample {far} is {:.6} rad ({:.3} deg) from the estimate, and no centre was found with every sample and the estimate inside an open ball of radius pi/2 (best centre: radius {:.6} rad, estimate at {:.6} rad) where the geodesic cost is convex [S4]",
                    rho_at_estimate,
                    rho_at_estimate.to_degrees(),
                    rho_o - ANGLE_MARGIN,
                    to_estimate - ANGLE_MARGIN
                ),
            );
        }
        (
            to_estimate + rho_o,
            format!(
                "pi/2-ball bound [S4b]: all samples within rho = {rho_o:.6} rad < pi/2 of a centre that is {to_estimate:.6} rad from the estimate (farthest: sample {far_o}); segment length at most {:.6} rad",
                to_estimate + rho_o
            ),
        )
    };
    let e = eval_geodesic(problem, estimate, norm);
    let g = e.gradient_norm(norm) + 16.0 * f64::EPSILON * total * (1.0 + radius);
    let lb = first_order_bound(problem, e.cost, g * radius, e.coincident_slack);
    (
        Some(lb),
        format!(
            "{why}; f - |g| L with (min-norm sub)gradient norm |g| = {:.3e}",
            e.gradient_norm(norm)
        ),
    )
}

/// An approximate centre of the smallest geodesic ball holding every sample: from `start`,
/// steps towards the farthest sample by `1 / (k + 2)` of the way (the Badoiu-Clarkson
/// iteration, on SO(3)); the best centre seen. Only a candidate: [`geodesic_ball_bound`]
/// measures its radius itself.
fn enclosing_centre(problem: &SingleProblem, start: &Rotation) -> Rotation {
    let mut o = *start;
    let (mut best, mut best_rho) = (o, problem.farthest(&o).1);
    for k in 0..ENCLOSING_ITERATIONS {
        let (far, _) = problem.farthest(&o);
        let step = so3::log(&(o.inverse() * problem.rotations()[far]));
        o *= so3::exp(&(step / (k + 2) as f64));
        let rho = problem.farthest(&o).1;
        if rho < best_rho {
            (best, best_rho) = (o, rho);
        }
    }
    best
}

/// `[S7]`: `f(R) >= f_E(M) - |g| (sqrt 3 + |M|_F)` for every rotation `R`, at the
/// Euclidean median's best iterate `M` within `deadline` (any `M` gives a bound: one cut
/// short by the time limit gives a weaker one).
fn chordal_l1_bound(problem: &SingleProblem, deadline: Option<Deadline>) -> (Option<f64>, String) {
    let settings = SingleSettings::default();
    let total = problem.total_weight();
    let med = euclidean_median(
        problem,
        settings.max_iterations.max(100),
        settings.gradient_tolerance,
        deadline,
    );
    let g = med.gradient_norm + 16.0 * f64::EPSILON * total;
    let radius = 3f64.sqrt() + med.point.norm();
    let lb = first_order_bound(problem, med.cost, g * radius, med.coincident_slack);
    (
        Some(lb),
        format!(
            "Euclidean bound [S7]: geometric median of the matrices in R^3x3 has cost {:.9e} (subgradient norm {:.3e}); rotations lie in the ball |R|_F = sqrt 3, so f >= f_E(M) - |g|(sqrt 3 + |M|_F). The bound ignores the constraint R in SO(3), so noisy data leave a gap",
            med.cost, med.gradient_norm
        ),
    )
}

/// The theorems `[S1]`-`[S7]` as a rung of a single certification (every mode but
/// `branch_and_bound`): free, once; no bound for a cost no theorem covers.
pub(crate) struct TheoryRung<'p> {
    problem: &'p SingleProblem,
    done: bool,
}

impl<'p> TheoryRung<'p> {
    /// The rung for `problem`.
    pub fn new(problem: &'p SingleProblem) -> Self {
        TheoryRung {
            problem,
            done: false,
        }
    }
}

impl<'a> Rung<RotationState<'a, SingleSolution>> for TheoryRung<'_> {
    fn proof(&self) -> Proof {
        Proof::Theory
    }

    fn plan(&mut self, cx: &RotationState<'a, SingleSolution>) -> Result<Plan> {
        Ok(
            if self.done || cx.settings.mode == CertifyMode::BranchAndBound {
                Plan::Done
            } else {
                Plan::Run(Prediction::new(0.0, 0.0))
            },
        )
    }

    fn attempt(&mut self, cx: &mut RotationState<'a, SingleSolution>) -> Result<Found> {
        self.done = true;
        // the certificate's time left, for the iterative bound [S7]
        let deadline = Deadline::after(cx.deadline.left());
        let (lb, explanation) = theory_bound(self.problem, &cx.estimate, cx.cost, deadline);
        Ok(match lb {
            Some(lb) => {
                let lb = cx.offer(Bound {
                    lower_bound: lb,
                    proof: Proof::Theory,
                    explanation: explanation.clone(),
                    min_eigenvalue: None,
                    verified_min_eigenvalue: None,
                    spectrum: None,
                });
                Found::proved(lb, cx.certifies(lb), explanation)
            }
            None => Found::failed(explanation),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::so3::{exp, random_rotation};
    use nalgebra::Vector3;
    use rand::SeedableRng;
    use rand::rngs::StdRng;

    /// Regression (found while tightening the multiple certificate, issue 11): samples are
    /// accepted when orthogonal within 1e-5, but the closed form `[S1]` assumed
    /// `||R_i||_F^2 = 3`. For samples `(1 - 2e-6) R` that overestimated the minimum by
    /// `1.2e-5 W`, and an estimate `1e-6 W` above the optimum was certified.
    #[test]
    fn chordal_l2_bound_is_below_the_minimum_for_nearly_orthogonal_samples() {
        let mut rng = StdRng::seed_from_u64(9);
        for _ in 0..20 {
            let r0 = random_rotation(&mut rng);
            let scaled = crate::so3::Rotation::from_matrix_unchecked(r0.matrix() * (1.0 - 2e-6));
            let p = SingleProblem::new(vec![scaled; 10], None).unwrap();
            // the minimiser is r0 (the samples' polar factor), f* = 10 * 3 * (2e-6)^2
            let fstar = p.cost(&r0);
            assert!((fstar - 1.2e-10).abs() < 1e-14);
            let worse = r0 * exp(&Vector3::new(1e-4, 0.0, 0.0));
            assert!(p.cost(&worse) > fstar + 5e-8);
            let c =
                crate::certify::single::certify_single(&p, &worse, &Default::default()).unwrap();
            assert!(!c.certificate.is_certified(), "{}", c.certificate);
            let lb = c.certificate.lower_bound.unwrap();
            assert!(lb <= fstar + 1e-14, "bound {lb} above the minimum {fstar}");
            let c = crate::certify::single::certify_single(&p, &r0, &Default::default()).unwrap();
            assert!(c.certificate.is_certified(), "{}", c.certificate);
        }
    }
}
