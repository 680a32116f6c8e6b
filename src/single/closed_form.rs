//! The closed-form means: chordal L2 `[S1]` and quaternion L2 `[S2]` (reached through
//! [`crate::single::solve_single`] with those objectives).

use super::problem::SingleProblem;
use super::solve::{Local, SingleSettings};
use crate::deadline::{Deadline, limit_reached};
use crate::so3::{self, Rotation};
use crate::termination::Termination;
use nalgebra::{Matrix3, Vector4};

/// `M = sum_i w_i R_i`, summed in blocks (pairwise-style) to keep the rounding error small for
/// millions of samples.
pub(crate) fn weighted_matrix_sum(problem: &SingleProblem) -> Matrix3<f64> {
    let mut total = Matrix3::zeros();
    for (rs, ws) in problem
        .rotations()
        .chunks(1024)
        .zip(problem.weights().chunks(1024))
    {
        let mut block = Matrix3::zeros();
        for (r, w) in rs.iter().zip(ws) {
            block += r.matrix() * *w;
        }
        total += block;
    }
    total
}

/// Chordal L2 mean `[S1]`: the det-corrected SVD projection `[C5]` of `M = sum_i w_i R_i`.
pub(crate) fn chordal_l2_local(problem: &SingleProblem) -> Local {
    let m = weighted_matrix_sum(problem);
    match so3::project_to_so3(&m) {
        Some(r) => Local {
            estimate: r,
            iterations: 0,
            termination: Termination::ClosedForm,
            name: "chordal-l2-svd",
        },
        None => Local {
            estimate: problem.rotations()[0],
            iterations: 0,
            termination: Termination::NumericalFailure {
                reason: "the weighted sum of the samples is not finite".into(),
            },
            name: "chordal-l2-svd",
        },
    }
}

/// Unit quaternions `q_i` of the samples (as 4-vectors, nalgebra's `(i, j, k, w)` order).
pub(crate) fn sample_quaternions(problem: &SingleProblem) -> Vec<Vector4<f64>> {
    problem
        .rotations()
        .iter()
        .map(|r| so3::to_quaternion(r).into_inner().coords)
        .collect()
}

/// `sum_i w_i s_i q_i` with `s_i = sign(q_i . q)` (`+1` on ties) and the number of `s_i = -1`.
pub(crate) fn aligned_sum(
    quats: &[Vector4<f64>],
    weights: &[f64],
    q: &Vector4<f64>,
) -> (Vector4<f64>, Vec<bool>) {
    let mut m = Vector4::zeros();
    let mut flipped = Vec::with_capacity(quats.len());
    for (qi, w) in quats.iter().zip(weights) {
        let neg = qi.dot(q) < 0.0;
        flipped.push(neg);
        if neg {
            m -= qi * *w;
        } else {
            m += qi * *w;
        }
    }
    (m, flipped)
}

/// Quaternion L2 mean `[S2]`: maximise `g(q) = sum_i w_i |q_i . q|` over unit `q` (since
/// `d_quat^2 = 2 - 2 |q_i . q|`) by the monotone fixed-point iteration
/// `q <- normalise(sum_i w_i sign(q_i . q) q_i)`, started from the chordal L2 mean. Each step
/// does not decrease `g` (`[S2]`, ascent of a convex function); it stops when no sign changes,
/// i.e. at a fixed point, which is the closed form `normalise(sum_i w_i s_i q_i)` for the final
/// signs. Global optimality is decided by `certify_single` (`[S2b]`, `[S2c]`).
pub(crate) fn quaternion_l2_local(
    problem: &SingleProblem,
    settings: &SingleSettings,
    init: Option<&Rotation>,
) -> Local {
    let quats = sample_quaternions(problem);
    let start = init
        .copied()
        .unwrap_or_else(|| chordal_l2_local(problem).estimate);
    let mut q = so3::to_quaternion(&start).into_inner().coords;
    let (mut m, mut signs) = aligned_sum(&quats, problem.weights(), &q);
    let (deadline, mut changes) = (Deadline::after(settings.max_seconds), signs.len());
    for it in 1..=settings.max_iterations {
        let measure = (changes as f64, 1.0);
        if let Some(limit) = limit_reached(it - 1, settings.max_iterations, deadline, measure) {
            return Local {
                estimate: quaternion_to_rotation(&q),
                iterations: it - 1,
                termination: limit,
                name: "quaternion-l2-aligned-sum",
            };
        }
        let norm = m.norm();
        if !(norm.is_finite() && norm > 0.0) {
            return Local {
                estimate: quaternion_to_rotation(&q),
                iterations: it - 1,
                termination: Termination::NumericalFailure {
                    reason: "the sign-aligned quaternion sum vanished: all samples are orthogonal \
                             to the current quaternion"
                        .into(),
                },
                name: "quaternion-l2-aligned-sum",
            };
        }
        q = m / norm;
        let (m_new, signs_new) = aligned_sum(&quats, problem.weights(), &q);
        changes = signs.iter().zip(&signs_new).filter(|(a, b)| a != b).count();
        m = m_new;
        signs = signs_new;
        if changes == 0 {
            return Local {
                estimate: quaternion_to_rotation(&q),
                iterations: it,
                termination: Termination::Converged {
                    measure: "sign changes in the last alignment pass".into(),
                    value: 0.0,
                    threshold: 1.0,
                },
                name: "quaternion-l2-aligned-sum",
            };
        }
        if it == settings.max_iterations {
            return Local {
                estimate: quaternion_to_rotation(&q),
                iterations: it,
                termination: Termination::IterationLimit {
                    iterations: it,
                    value: changes as f64,
                    threshold: 1.0,
                },
                name: "quaternion-l2-aligned-sum",
            };
        }
    }
    // max_iterations >= 1 (validated), so the loop returns; keep a safe fallback.
    Local {
        estimate: quaternion_to_rotation(&q),
        iterations: settings.max_iterations,
        termination: Termination::IterationLimit {
            iterations: settings.max_iterations,
            value: 1.0,
            threshold: 1.0,
        },
        name: "quaternion-l2-aligned-sum",
    }
}

/// The rotation of a unit 4-vector in nalgebra's `(i, j, k, w)` order.
pub(crate) fn quaternion_to_rotation(q: &Vector4<f64>) -> Rotation {
    nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion { coords: *q })
        .to_rotation_matrix()
}

/// `sum_i w_i min(|q_i - q|, |q_i + q|)`: the quaternion L1 cost of the unit 4-vector `q`.
fn quaternion_l1_cost(quats: &[Vector4<f64>], weights: &[f64], q: &Vector4<f64>) -> f64 {
    quats
        .iter()
        .zip(weights)
        .map(|(p, w)| w * (p - q).norm().min((p + q).norm()))
        .sum()
}

/// Quaternion L1 mean `[S10]`: minimise `sum_i w_i min(|q_i - q|, |q_i + q|)` over unit `q`
/// by a sign-aligned Weiszfeld iteration on `S^3`. With the signs `s_i = sign(q_i . q)` and
/// `c_i = |s_i q_i - q| > 0`, `c <= c^2 / (2 c_i) + c_i / 2` and `|p - q|^2 = 2 - 2 p . q` on the
/// sphere, so `q <- normalise(sum_i (w_i / c_i) s_i q_i)` minimises a majoriser (the cost cannot
/// increase; re-aligning the signs can only lower it). When the iterate coincides with samples
/// (`c_i <= 1e-12`, total weight `w_Z`) the step is the Vardi-Zhang one: it moves by the
/// fraction `(1 - w_Z / |t|)^+` of the way, `t` the tangential part of the Weiszfeld numerator,
/// and stops there when `|t| <= w_Z` (the sample satisfies the optimality condition). Every step
/// is halved while it would increase the cost. Starts from the chordal L2 mean (or `init`).
pub(crate) fn quaternion_l1_local(
    problem: &SingleProblem,
    settings: &SingleSettings,
    init: Option<&Rotation>,
) -> Local {
    let quats = sample_quaternions(problem);
    let weights = problem.weights();
    let start = init
        .copied()
        .unwrap_or_else(|| chordal_l2_local(problem).estimate);
    let mut q = so3::to_quaternion(&start).into_inner().coords;
    let mut cost = quaternion_l1_cost(&quats, weights, &q);
    let done = |q: &Vector4<f64>, iterations: usize, termination: Termination| Local {
        estimate: quaternion_to_rotation(q),
        iterations,
        termination,
        name: "quaternion-l1-weiszfeld",
    };
    let deadline = Deadline::after(settings.max_seconds);
    for it in 1..=settings.max_iterations {
        let (num, zero) = weiszfeld_numerator(&quats, weights, &q);
        let tangent = num - q * num.dot(&q);
        let tn = tangent.norm();
        let total = problem.total_weight();
        let measure = ((tn - zero).max(0.0) / total, settings.gradient_tolerance);
        if tn <= zero || tn <= settings.gradient_tolerance * total {
            let converged = Termination::Converged {
                measure: "(tangential Weiszfeld numerator - coincident weight) / total weight"
                    .into(),
                value: measure.0,
                threshold: measure.1,
            };
            return done(&q, it - 1, converged);
        }
        if let Some(limit) = limit_reached(it - 1, settings.max_iterations, deadline, measure) {
            return done(&q, it - 1, limit);
        }
        let Some(target) = num.try_normalize(0.0) else {
            let failure = Termination::NumericalFailure {
                reason: "the Weiszfeld numerator vanished".into(),
            };
            return done(&q, it - 1, failure);
        };
        let frac = if zero > 0.0 { 1.0 - zero / tn } else { 1.0 };
        let Some((cand, c)) = toward(&quats, weights, &q, cost, &target, frac) else {
            let stalled = Termination::Stalled {
                value: tn,
                threshold: zero,
            };
            return done(&q, it - 1, stalled);
        };
        let step = (cand - q).norm();
        q = cand;
        cost = c;
        if step < settings.step_tolerance {
            let converged = Termination::Converged {
                measure: "step (quaternion distance)".into(),
                value: step,
                threshold: settings.step_tolerance,
            };
            return done(&q, it, converged);
        }
    }
    let limit = Termination::IterationLimit {
        iterations: settings.max_iterations,
        value: 1.0,
        threshold: settings.gradient_tolerance,
    };
    done(&q, settings.max_iterations, limit)
}

/// The Weiszfeld numerator `sum_i (w_i / c_i) s_i q_i` at `q` over the samples not coinciding
/// with it (`c_i = |s_i q_i - q| > 1e-12`), and the total weight of those that do.
fn weiszfeld_numerator(
    quats: &[Vector4<f64>],
    weights: &[f64],
    q: &Vector4<f64>,
) -> (Vector4<f64>, f64) {
    let mut num = Vector4::zeros();
    let mut zero = 0.0;
    for (p, &w) in quats.iter().zip(weights) {
        let p = if p.dot(q) < 0.0 { -p } else { *p };
        let c = (p - q).norm();
        if c <= 1e-12 {
            zero += w;
        } else {
            num += p * (w / c);
        }
    }
    (num, zero)
}

/// The point `normalise(q + frac (target - q))`, `frac` halved (at most 40 times) while it
/// would increase the quaternion L1 cost `cost` at `q` beyond rounding: the point and its cost.
fn toward(
    quats: &[Vector4<f64>],
    weights: &[f64],
    q: &Vector4<f64>,
    cost: f64,
    target: &Vector4<f64>,
    mut frac: f64,
) -> Option<(Vector4<f64>, f64)> {
    let slack = (quats.len() as f64 + 8.0) * f64::EPSILON * cost.abs();
    for _ in 0..40 {
        if let Some(cand) = (q + (target - q) * frac).try_normalize(0.0) {
            let c = quaternion_l1_cost(quats, weights, &cand);
            if c <= cost + slack {
                return Some((cand, c));
            }
        }
        frac *= 0.5;
    }
    None
}
