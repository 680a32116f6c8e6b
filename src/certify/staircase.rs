//! Riemannian staircase (Burer-Monteiro) for the multiple-rotation SDP `[D11]`
//! (`paper-notes/certificates.md`): when the dual certificate of an estimate fails, solve the
//! rank-lifted problem `min tr(Y^T Q Y)` over `Y_i` in `St(3, p)` (3 x p, orthonormal rows),
//! `p = 3, 4, ...`, escaping saddles along the negative eigenvector of `S`; the multipliers of
//! the final lifted point are verified exactly like any other multipliers
//! ([`super::multiple::lower_bound_from_multipliers`]), so the bound is proven whatever the
//! optimiser achieved, and approaches the SDP optimum when the optimiser converges.
//!
//! The optimiser here is a plain Riemannian gradient descent (Barzilai-Borwein steps, Armijo
//! backtracking, polar retraction): adequate for moderate sizes; it reports why it stopped.

use crate::certificate::{BoundMethod, Certificate};
use crate::certify::multiple::{CertifySettings, VerifiedBound, lower_bound_from_multipliers};
use crate::error::{Error, Result};
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use nalgebra::{Matrix3, Matrix3xX, SymmetricEigen};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Settings of [`staircase_bound`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct StaircaseSettings {
    /// Largest rank `p` tried (`>= 3`).
    pub max_rank: usize,
    /// Gradient-descent iterations per rank.
    pub max_iterations: usize,
    /// Stop the descent when `||grad|| <= gradient_tolerance * (1 + F)`.
    pub gradient_tolerance: f64,
    /// Verification settings (tolerance, shifts, Lanczos).
    pub certify: CertifySettings,
}

impl Default for StaircaseSettings {
    fn default() -> Self {
        StaircaseSettings {
            max_rank: 8,
            max_iterations: 5000,
            gradient_tolerance: 1e-10,
            certify: CertifySettings::default(),
        }
    }
}

/// Result of [`staircase_bound`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StaircaseResult {
    /// Certificate of the given estimate with the staircase bound (method `Staircase`).
    pub certificate: Certificate,
    /// The verified bound from the final lifted point's multipliers.
    pub bound: VerifiedBound,
    /// Final rank `p`.
    pub rank: usize,
    /// Cost `F(Y)` of the final lifted point (an estimate of the SDP optimum from above).
    pub lifted_cost: f64,
    /// Total gradient-descent iterations.
    pub iterations: usize,
    /// Why the staircase stopped.
    pub stop_reason: String,
}

type Block = Matrix3xX<f64>;

fn lifted_qy(problem: &MultipleProblem, y: &[Block]) -> Vec<Block> {
    let p = y[0].ncols();
    let mut qy = vec![Block::zeros(p); y.len()];
    for e in problem.edges() {
        let r = e.rotation.matrix();
        let (yi, yj) = (&y[e.i], &y[e.j]);
        qy[e.i] += e.weight * (yi - r.transpose() * yj);
        qy[e.j] += e.weight * (yj - r * yi);
    }
    qy
}

fn lifted_cost(problem: &MultipleProblem, y: &[Block]) -> f64 {
    problem
        .edges()
        .iter()
        .map(|e| e.weight * (&y[e.j] - e.rotation.matrix() * &y[e.i]).norm_squared())
        .sum()
}

fn lifted_multipliers(problem: &MultipleProblem, y: &[Block]) -> Vec<Matrix3<f64>> {
    lifted_qy(problem, y)
        .iter()
        .zip(y)
        .map(|(g, yi)| {
            let m: Matrix3<f64> = g * yi.transpose();
            0.5 * (m + m.transpose())
        })
        .collect()
}

/// Riemannian gradient `2 ((QY)_i - sym((QY)_i Y_i^T) Y_i)`.
fn gradient(problem: &MultipleProblem, y: &[Block]) -> Vec<Block> {
    lifted_qy(problem, y)
        .iter()
        .zip(y)
        .map(|(g, yi)| {
            let m: Matrix3<f64> = g * yi.transpose();
            let l = 0.5 * (m + m.transpose());
            2.0 * (g - l * yi)
        })
        .collect()
}

/// Polar retraction: `(M M^T)^{-1/2} M` (orthonormal rows).
fn polar(m: &Block) -> Option<Block> {
    let g: Matrix3<f64> = m * m.transpose();
    let eig = SymmetricEigen::new(g);
    if eig.eigenvalues.iter().any(|&v| v.is_nan() || v <= 1e-300) {
        return None;
    }
    let d = Matrix3::from_diagonal(&eig.eigenvalues.map(|v| 1.0 / v.sqrt()));
    let inv_sqrt = eig.eigenvectors * d * eig.eigenvectors.transpose();
    Some(inv_sqrt * m)
}

fn retract(y: &[Block], d: &[Block], t: f64) -> Option<Vec<Block>> {
    y.iter()
        .zip(d)
        .map(|(yi, di)| polar(&(yi + t * di)))
        .collect()
}

/// Returns (Y, F, iterations).
fn descend(
    problem: &MultipleProblem,
    mut y: Vec<Block>,
    settings: &StaircaseSettings,
) -> (Vec<Block>, f64, usize) {
    let mut f = lifted_cost(problem, &y);
    let mut g = gradient(problem, &y);
    let mut step = 1e-2;
    let mut prev: Option<(Vec<Block>, f64)> = None;
    let mut it = 0;
    while it < settings.max_iterations {
        let gn2: f64 = g.iter().map(|b| b.norm_squared()).sum();
        if gn2.sqrt() <= settings.gradient_tolerance * (1.0 + f) {
            break;
        }
        if let Some((gp, tp)) = &prev {
            let s2 = tp * tp * gp.iter().map(|b| b.norm_squared()).sum::<f64>();
            let sy: f64 = -tp * gp.iter().zip(&g).map(|(a, b)| a.dot(&(b - a))).sum::<f64>();
            if sy > 0.0 {
                step = (s2 / sy).clamp(1e-10, 10.0);
            }
        }
        let dir: Vec<Block> = g.iter().map(|b| -b).collect();
        let mut t = step;
        let mut accepted = None;
        for _ in 0..50 {
            if let Some(c) = retract(&y, &dir, t) {
                let fc = lifted_cost(problem, &c);
                if fc <= f - 1e-4 * t * gn2 {
                    accepted = Some((c, fc));
                    break;
                }
            }
            t *= 0.5;
        }
        let Some((c, fc)) = accepted else { break };
        y = c;
        f = fc;
        prev = Some((g, t));
        g = gradient(problem, &y);
        it += 1;
    }
    (y, f, it)
}

/// Bound the global minimum by a Riemannian staircase started at `rotations` `[D11]`, and
/// certify `rotations` against it (method [`BoundMethod::Staircase`]). The bound is verified
/// exactly like any multipliers (`[D4]`-`[D8]`): it is valid whatever the descent achieved.
///
/// ```
/// use rotavg::certify::staircase::{staircase_bound, StaircaseSettings};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, gt) = SyntheticGraph { num_rotations: 8, num_edges: 14, noise_sigma: 0.0, ..Default::default() }.generate();
/// let r = staircase_bound(&p, &gt, &StaircaseSettings::default()).unwrap();
/// assert!(r.certificate.lower_bound.unwrap() <= p.chordal_cost(&gt) + 1e-12);
/// ```
pub fn staircase_bound(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &StaircaseSettings,
) -> Result<StaircaseResult> {
    let start = Instant::now();
    crate::certify::multiple::check_rotations(problem, rotations)?;
    settings.certify.validate()?;
    if settings.max_rank < 3 {
        return Err(Error::InvalidSettings {
            name: "max_rank".into(),
            reason: "must be at least 3".into(),
        });
    }
    let upper = problem.chordal_cost(rotations);
    let mut y: Vec<Block> = rotations
        .iter()
        .map(|r| Block::from_column_slice(r.matrix().as_slice()))
        .collect();
    let mut iterations = 0;
    let mut rank = 3;
    let (bound, lifted, stop_reason) = loop {
        let (yn, f, it) = descend(problem, y, settings);
        y = yn;
        iterations += it;
        let lambdas = lifted_multipliers(problem, &y);
        let bound = lower_bound_from_multipliers(problem, &lambdas, &settings.certify)?;
        let Some(v) = bound.negative_eigenvector.clone() else {
            break (
                bound,
                f,
                format!(
                    "certificate S of the rank-{rank} point verified (no negative eigenvector)"
                ),
            );
        };
        if rank >= settings.max_rank {
            break (bound, f, format!("maximum rank {rank} reached"));
        }
        // escape along v in a new column: Y_i <- [Y_i, alpha v_i], retract; second-order
        // decrease ~ alpha^2 lambda_min
        rank += 1;
        let lift = |alpha: f64| -> Option<Vec<Block>> {
            y.iter()
                .enumerate()
                .map(|(i, yi)| {
                    let mut b = yi.clone().insert_column(rank - 1, 0.0);
                    for a in 0..3 {
                        b[(a, rank - 1)] = alpha * v[3 * i + a];
                    }
                    polar(&b)
                })
                .collect()
        };
        let mut alpha = 1.0;
        let mut next = None;
        for _ in 0..40 {
            if let Some(c) = lift(alpha)
                && lifted_cost(problem, &c) < f
            {
                next = Some(c);
                break;
            }
            alpha *= 0.5;
        }
        match next {
            Some(c) => y = c,
            None => {
                break (
                    bound,
                    f,
                    "escape along the negative eigenvector did not decrease the cost".to_string(),
                );
            }
        }
    };
    let certificate = Certificate::from_bounds(
        upper,
        Some(bound.lower_bound),
        BoundMethod::Staircase,
        bound.min_eigenvalue_estimate,
        settings.certify.tolerance,
        format!(
            "Riemannian staircase: rank {rank}, lifted cost {lifted:.9e}; {stop_reason}; bound \
             verified from the lifted multipliers (lambda_min(S) >= {:.3e})",
            bound.verified_min_eigenvalue
        ),
        start.elapsed().as_secs_f64(),
    );
    Ok(StaircaseResult {
        certificate,
        bound,
        rank,
        lifted_cost: lifted,
        iterations,
        stop_reason,
    })
}
