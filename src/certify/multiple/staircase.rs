//! Riemannian staircase (Burer-Monteiro) for the multiple-rotation SDP `[D11]`
//! (`paper-notes/certificates.md`): when the dual certificate of an estimate fails, solve the
//! rank-lifted problem `min tr(Y^T Q Y)` over `Y_i` in `St(3, p)` (3 x p, orthonormal rows),
//! `p = 3, 4, ...`, escaping saddles along the negative eigenvector of `S`; the multipliers of
//! the final lifted point are verified exactly like any other multipliers
//! ([`super::lower_bound_from_multipliers`]), so the bound is proven whatever the
//! optimiser achieved, and approaches the SDP optimum when the optimiser converges.
//!
//! The optimiser here is a plain Riemannian gradient descent (Barzilai-Borwein steps, Armijo
//! backtracking, polar retraction): adequate for moderate sizes; it reports why it stopped.

use super::multipliers::check_rotations;
use super::verify::{VerifiedBound, lower_bound_from_multipliers};
use crate::certify::certificate::{BoundMethod, Certificate};
use crate::certify::settings::CertifySettings;
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
}

impl Default for StaircaseSettings {
    fn default() -> Self {
        StaircaseSettings {
            max_rank: 8,
            max_iterations: 5000,
            gradient_tolerance: 1e-10,
        }
    }
}

impl StaircaseSettings {
    /// Check every value; [`Error::InvalidSettings`] names the first bad one
    /// (`staircase.<field>`).
    pub fn validate(&self) -> Result<()> {
        if self.max_rank < 3 {
            return Err(Error::InvalidSettings {
                name: "staircase.max_rank".into(),
                reason: format!("must be at least 3, got {}", self.max_rank),
            });
        }
        crate::validate::at_least_one("staircase.max_iterations", self.max_iterations)?;
        crate::validate::positive("staircase.gradient_tolerance", self.gradient_tolerance)
    }
}

/// Why the staircase stopped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum StaircaseStop {
    /// The certificate matrix of the rank-`rank` point has no negative eigenvalue estimate
    /// below the shift budget: the bound is as good as the verification.
    Verified {
        /// The rank.
        rank: usize,
        /// The Lanczos estimate of `lambda_min(S)` at that point.
        min_eigenvalue_estimate: Option<f64>,
    },
    /// The rank limit was reached with a negative eigenvalue left.
    MaxRank {
        /// The limit ([`StaircaseSettings::max_rank`]).
        max_rank: usize,
        /// The negative eigenvalue estimate left.
        min_eigenvalue_estimate: Option<f64>,
    },
    /// Moving along the negative eigenvector did not decrease the lifted cost (40 halvings).
    EscapeFailed {
        /// The rank at which it failed.
        rank: usize,
        /// The negative eigenvalue estimate.
        min_eigenvalue_estimate: Option<f64>,
    },
}

impl std::fmt::Display for StaircaseStop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let est = |e: &Option<f64>| e.map_or("n/a".to_string(), |v| format!("{v:.3e}"));
        match self {
            StaircaseStop::Verified {
                rank,
                min_eigenvalue_estimate,
            } => write!(
                f,
                "certificate S of the rank-{rank} point verified (no negative eigenvector; lambda_min estimate {})",
                est(min_eigenvalue_estimate)
            ),
            StaircaseStop::MaxRank {
                max_rank,
                min_eigenvalue_estimate,
            } => write!(
                f,
                "maximum rank {max_rank} reached (lambda_min estimate {} < 0)",
                est(min_eigenvalue_estimate)
            ),
            StaircaseStop::EscapeFailed {
                rank,
                min_eigenvalue_estimate,
            } => write!(
                f,
                "escape along the negative eigenvector at rank {rank} did not decrease the cost (lambda_min estimate {})",
                est(min_eigenvalue_estimate)
            ),
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
    pub stop_reason: StaircaseStop,
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
/// use rotavg::certify::multiple::staircase::staircase_bound;
/// use rotavg::certify::CertifySettings;
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, gt) = SyntheticGraph { num_rotations: 8, num_edges: 14, noise_sigma: 0.0, ..Default::default() }.generate();
/// let r = staircase_bound(&p, &gt, &CertifySettings::default()).unwrap();
/// assert!(r.certificate.lower_bound.unwrap() <= p.chordal_cost(&gt) + 1e-12);
/// ```
pub fn staircase_bound(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    certify: &CertifySettings,
) -> Result<StaircaseResult> {
    let start = Instant::now();
    check_rotations(problem, rotations)?;
    certify.validate()?;
    let settings = &certify.staircase;
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
        let bound = lower_bound_from_multipliers(problem, &lambdas, certify)?;
        let estimate = bound.min_eigenvalue_estimate;
        let Some(v) = bound.negative_eigenvector.clone() else {
            break (
                bound,
                f,
                StaircaseStop::Verified {
                    rank,
                    min_eigenvalue_estimate: estimate,
                },
            );
        };
        if rank >= settings.max_rank {
            break (
                bound,
                f,
                StaircaseStop::MaxRank {
                    max_rank: settings.max_rank,
                    min_eigenvalue_estimate: estimate,
                },
            );
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
                    StaircaseStop::EscapeFailed {
                        rank,
                        min_eigenvalue_estimate: estimate,
                    },
                );
            }
        }
    };
    let certificate = Certificate::from_bounds(
        upper,
        Some(bound.lower_bound),
        BoundMethod::Staircase,
        bound.min_eigenvalue_estimate,
        certify.tolerance.resolve(problem.min_weight()),
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
