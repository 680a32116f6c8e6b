//! What a verification of multipliers proves and reports: the verified bound and the
//! quantities of the check that gave it (`paper-notes/certificates.md` `[D4]`-`[D8]`, `[D13]`,
//! `[D15]`, `[D16]`).

use super::block::BlockComparison;
use super::scalar::ScalarComparison;
use crate::certify::log::Attempt;
use crate::certify::proof::Proof;
use crate::linalg::{ChebyshevOutcome, ChebyshevTest, LanczosStop};
use serde::{Deserialize, Serialize};
use std::fmt;

/// A verified lower bound from multipliers `Lambda` `[D4]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VerifiedBound {
    /// The proven lower bound on the global minimum of the chordal cost (over `O(3)^n`, hence
    /// over `SO(3)^n`): `sum tr(Lambda_i) + 3n min(mu_verified, 0)` minus rounding margins.
    pub lower_bound: f64,
    /// `sum_i tr(Lambda_i)` (as computed).
    pub trace: f64,
    /// Verified lower bound `mu` on `lambda_min(S)`.
    pub verified_min_eigenvalue: f64,
    /// Which check verified `mu` (grounded, shifted Cholesky, scalar comparison, Gershgorin).
    pub verification: Proof,
    /// The Cholesky shift that verified `mu` (`mu = -shift - fp_margin`), if any.
    pub shift: Option<f64>,
    /// The rigorous floating-point margin included in `mu` `[D6]`.
    pub fp_margin: f64,
    /// Iterative *estimate* of `lambda_min(S)` (Lanczos), if computed.
    pub min_eigenvalue_estimate: Option<f64>,
    /// Ritz residual of that estimate.
    pub estimate_residual: Option<f64>,
    /// Unit eigenvector estimate for `lambda_min(S)` when the estimate is negative (length `3n`):
    /// the direction of descent for a rank-lifted (staircase) solve.
    pub negative_eigenvector: Option<Vec<f64>>,
    /// Lanczos iterations (all runs).
    pub lanczos_iterations: usize,
    /// Numeric factorisations attempted (all rungs).
    pub factorizations: usize,
    /// Stored values of the factor of the proof that gave the bound (fill indicator).
    pub factor_nonzeros: usize,
    /// The scalar comparison's quantities, when `verification` is `ScalarComparison` `[D13]`
    /// (among them how many edges its factorised subgraph dropped).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scalar_comparison: Option<ScalarComparison>,
    /// The block comparison's quantities, when `verification` is `BlockComparison` `[A15]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub block_comparison: Option<BlockComparison>,
    /// `true` when nothing was proved and a proof was kept out by the budget (then no lower
    /// bound is claimed: the verdict is `inconclusive` with [`VerifiedBound::budget_exceeded`]).
    pub factorization_skipped: bool,
    /// The grounded bound's quantities, when `verification` is `Grounded` `[D15]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grounded: Option<GroundedBound>,
    /// The estimate is too far from a critical point for a bound within the tolerance (its
    /// stationarity residual `rho` against the largest possible curvature `c`, `[D15]`).
    #[serde(default)]
    pub not_critical: bool,
    /// Why no proof was tried when none fitted the budget ([`crate::certify::budget::Budget`]); the
    /// bound is then Gershgorin's, and no lower bound is claimed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub budget_exceeded: Option<String>,
    /// When no proof fit the budget and the rotations were known: the estimate of
    /// `lambda_min(S)` on the complement of the gauge directions (never a proof).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub complement_estimate: Option<ComplementEstimate>,
    /// When no proof fit the budget: the randomized Chebyshev test `[D16]` on the complement
    /// of the gauge directions (a Monte Carlo bound, never a proof).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub randomized: Option<RandomizedBound>,
    /// Every rung of the ladder this verification considered, in order, with its prediction
    /// and outcome ([`crate::certify::ladder`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ladder: Vec<Attempt>,
}

/// The quantities of the grounded bound `[D15]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GroundedBound {
    /// The ground node `g` whose block is removed.
    pub ground: usize,
    /// Proven `c > 0` with `S_{-g} >= c I`.
    pub c: f64,
    /// Proven `rho >= ||S Y||_2`.
    pub rho: f64,
    /// Proven `h >= 0` with `Y^T S Y >= -h I`.
    pub h: f64,
    /// The deficit `(rho^2 / c + h) ||R_g^-1||_F^2` subtracted from `sum tr(Lambda)`.
    pub deficit: f64,
}

/// The smallest eigenvalue of `S` on the orthogonal complement of the gauge directions `Y`
/// (the rotations stacked, `S Y ~ 0` at a critical point), estimated by Lanczos on
/// `P S P`, `P = I - Y Y^T / n`: an *estimate*, never a proof. Positive with a small residual,
/// it says `S` looks positive semidefinite with that much room; it is reported when no proof
/// fits the budget ([`crate::certify::budget::Budget`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ComplementEstimate {
    /// The Ritz value.
    pub value: f64,
    /// Its Ritz residual `||P S P x - value x||` (some eigenvalue of `P S P` lies within it).
    pub residual: f64,
    /// Krylov subspace dimension reached.
    pub iterations: usize,
    /// The gauge directions' smallest Rayleigh quotient `lambda_min(sym(Y^T S Y)) / n`.
    pub gauge_rayleigh_quotient: f64,
    /// Why the Lanczos iteration stopped.
    pub stop: LanczosStop,
}

impl fmt::Display for ComplementEstimate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Lanczos estimates (not a proof): lambda_min(S) on the complement of the gauge \
             directions ~ {:.3e} (Ritz residual {:.1e} after {} iterations), on the gauge \
             directions ~ {:.3e}",
            self.value, self.residual, self.iterations, self.gauge_rayleigh_quotient
        )
    }
}

/// The randomized bound `[D16]` of a dual certificate: what the test claimed and found.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RandomizedBound {
    /// The lower bound on the global minimum of the chordal cost when the test passed (valid
    /// unless an event of probability at most `outcome.failure_probability`, over the test's
    /// random vectors, occurred); `None` when it did not pass.
    pub lower_bound: Option<f64>,
    /// Seed of the random vectors.
    pub seed: u64,
    /// The claimed `mu`: `x^T S x >= mu ||x||^2` for `x` orthogonal to the gauge directions
    /// (the exact `S` of the data; the floating-point forming error is subtracted).
    pub complement_bound: f64,
    /// Proven `rho >= ||S Y||_2`.
    pub rho: f64,
    /// Proven `h` with `Y^T S Y >= -h I`.
    pub h: f64,
    /// `(rho^2 / mu + h) 3n / lambda_min(Y^T Y)`, subtracted from `sum tr(Lambda_i)`.
    pub deficit: f64,
    /// The test's interval, degree and vectors.
    pub test: ChebyshevTest,
    /// What the test found.
    pub outcome: ChebyshevOutcome,
    /// Time spent, in seconds.
    pub seconds: f64,
}

impl fmt::Display for RandomizedBound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "randomized Chebyshev test [D16] ({} vectors of degree {}, {} products with S, \
             {:.1} s): ",
            self.test.vectors, self.test.degree, self.outcome.matvecs, self.seconds
        )?;
        if self.lower_bound.is_some() {
            write!(
                f,
                "lambda_min(S) >= {:.3e} on the complement of the gauge directions unless an \
                 event of probability <= {:.0e} occurred (seed {}); deficit {:.1e}",
                self.complement_bound, self.outcome.failure_probability, self.seed, self.deficit
            )
        } else if self.outcome.grew {
            write!(
                f,
                "did not pass: the iterates grew, as they do when S has an eigenvalue on the \
                 complement of the gauge directions below half the Lanczos estimate; no \
                 randomized bound"
            )
        } else {
            write!(
                f,
                "did not pass (lambda_min(S) >= {:.3e} on the complement was not shown; log \
                 margin {:.2}), no randomized bound",
                self.complement_bound, self.outcome.log_margin
            )
        }
    }
}
