//! What the proofs report beside their bound, carried by certificates and reports: an SDP's
//! statistics, the staircase's ranks, the branch and bound's search, the smallest-eigenvalue
//! estimates of a certificate matrix. Data only (the vocabulary below the proofs).

use crate::linalg::LanczosStop;
use crate::relax::SdpStatus;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Why the branch and bound stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BranchAndBoundStop {
    /// Every cell was bounded within the tolerance of the best cost found.
    #[default]
    Converged,
    /// `max_cells` cells were bounded.
    CellBudget,
    /// The time budget (`budget.max_seconds`) ran out.
    TimeBudget,
    /// A cell to split was below the resolution of the floating-point margins.
    Resolution,
    /// Not searched: the data margin `[B6]` has no proof (quaternion metric, samples that are
    /// rotations only to the validation tolerance); the bound is the trivial 0.
    UnprovenData,
}

/// What a branch and bound did (in the certificate's JSON as `branch_and_bound`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct BranchAndBoundStats {
    /// Cells whose bound was computed.
    pub cells_explored: usize,
    /// Cells discarded because their bound reached the best cost minus half the tolerance.
    pub cells_pruned: usize,
    /// Cells discarded because they lie in a ball around an incumbent (`[B5]`).
    pub cells_in_balls: usize,
    /// Cells still open when the search stopped (0 when converged).
    pub live_cells: usize,
    /// Deepest level of subdivision reached (0: the initial cells).
    pub max_depth: u32,
    /// Radius (rad) of the ball around the estimate bounded at once (`[B5]`; 0 if none).
    pub ball_radius: f64,
    /// Local solves started from cell centres.
    pub local_solves: usize,
    /// The proven lower bound of the global minimum.
    pub lower_bound: f64,
    /// The best cost seen (estimate, cell centres, local solves).
    pub best_cost: f64,
    /// Why it stopped.
    pub stop: BranchAndBoundStop,
    /// Wall time, seconds.
    pub seconds: f64,
}

impl fmt::Display for BranchAndBoundStop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BranchAndBoundStop::Converged => "converged",
            BranchAndBoundStop::CellBudget => "cell budget",
            BranchAndBoundStop::TimeBudget => "time budget",
            BranchAndBoundStop::Resolution => "resolution limit",
            BranchAndBoundStop::UnprovenData => "unproven data margin",
        })
    }
}

impl fmt::Display for BranchAndBoundStats {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "branch and bound ({}): {} cells bounded, {} pruned, {} in the incumbent balls, {} open, depth {}, ball radius {:.3e} rad, {} local solves, {:.3} s",
            self.stop,
            self.cells_explored,
            self.cells_pruned,
            self.cells_in_balls,
            self.live_cells,
            self.max_depth,
            self.ball_radius,
            self.local_solves,
            self.seconds
        )
    }
}

/// One rank of the staircase, as it ran: what the trust region reached, what the estimate of
/// `lambda_min(S)` said and whether the rank was verified (the trace behind
/// `StaircaseResult::stop_reason`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StaircaseStep {
    /// The rank `p`.
    pub rank: usize,
    /// Trust-region iterations at this rank (loose and strict solves together).
    pub iterations: usize,
    /// Whether the rank was solved to [`crate::certify::settings::StaircaseSettings::gradient_tolerance`] (a strict
    /// solve, before a verification) rather than only to [`crate::certify::multiple::staircase::ESCAPE_GRADIENT_TOLERANCE`].
    pub strict: bool,
    /// The lifted cost `F(Y)` reached.
    pub lifted_cost: f64,
    /// The matrix-free Lanczos estimate of `lambda_min(S)` (deflated by the columns of `Y`,
    /// the null space of `S` at a critical point) and its Ritz residual.
    pub estimate: f64,
    /// The Ritz residual of [`StaircaseStep::estimate`].
    pub estimate_residual: f64,
    /// The estimate of `lambda_min(S)` on the whole space: the null-space block `B^T S B` of
    /// the columns `B` of `Y` coupled to the complement's estimate (the smaller eigenvalue of
    /// `[[lambda_min(B^T S B), ||S B - B B^T S B||_F], [., estimate]]`).
    pub full_estimate: f64,
    /// The verified bound at this rank, when the rank was verified.
    pub verified_bound: Option<f64>,
    /// Seconds since the staircase started, at the end of this rank.
    pub seconds: f64,
}

/// How the estimates were computed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SpectrumMethod {
    /// Dense symmetric eigen-decomposition (all eigenvalues, accurate to `~ u ||S||`).
    Dense,
    /// Block Lanczos on `(S + shift I)^-1` through a sparse Cholesky factor.
    ShiftInvertLanczos,
    /// Block Lanczos on `S`.
    Lanczos,
}

/// The `k` smallest eigenvalues of a symmetric matrix: **estimates**, not bounds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpectrumEstimate {
    /// Estimated smallest eigenvalues, ascending (Rayleigh quotients of the Ritz vectors).
    pub values: Vec<f64>,
    /// Residual `||S x - value x||_2` of each value (unit `x`): some eigenvalue of `S` lies
    /// within it.
    pub residuals: Vec<f64>,
    /// How they were computed.
    pub method: SpectrumMethod,
    /// The shift of the shift-invert iteration, if used.
    pub shift: Option<f64>,
    /// Why the Lanczos iteration stopped (`None` for `Dense`, which is exact up to rounding).
    pub stop: Option<LanczosStop>,
    /// Krylov subspace dimension reached (the matrix dimension for `Dense`).
    pub subspace_dim: usize,
    /// Wall time, seconds.
    pub seconds: f64,
}

impl SpectrumEstimate {
    /// `true` when the estimates are exact up to rounding (dense) or the Lanczos iteration
    /// converged.
    pub fn converged(&self) -> bool {
        self.stop.is_none_or(|s| s.converged())
    }
}

/// Statistics of an SDP solve inside a certification.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SdpSummary {
    /// Clarabel's outcome.
    pub status: SdpStatus,
    /// Interior-point iterations.
    pub iterations: u32,
    /// Time of the solve (setup, solve, rounding), seconds.
    pub seconds: f64,
    /// Tightness indicator of the primal solution: multiple averaging `lambda_4(X) / lambda_3(X)`,
    /// conjugate `lambda_2(Z) / lambda_1(Z)` (0 for a tight, exactly low-rank solution).
    pub eigenvalue_ratio: f64,
    /// Cost of the rounded (multiple) or extracted (conjugate) estimate, before polishing.
    pub rounded_cost: Option<f64>,
    /// Cost after polishing it with the local solver.
    pub polished_cost: Option<f64>,
}
