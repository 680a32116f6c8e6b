//! The one name of every proof ([`Proof`]), and the family of the verdict's bound that the JSON
//! contract calls its `method` ([`BoundMethod`], derived from the proof: [`Proof::method`]).
//!
//! A new proof is one variant here and one file of its own (its rung: a predicted cost and an
//! attempt, [`crate::certify::rung::Rung`]).

use serde::{Deserialize, Serialize};
use std::fmt;

/// Every way a certification can bound the global minimum (`paper-notes/certificates.md`,
/// `single.md`, `conjugate.md`, `anisotropic.md`, `branch_and_bound.md`), and the labelled
/// estimate that is never a proof ([`Proof::Randomized`]).
///
/// The first group bounds a problem (a rung of the certification's climb); the second proves
/// `lambda_min(S) >= mu` for the certificate matrix `S` of given multipliers (a rung of the
/// climb inside [`Proof::DualCertificate`], [`Proof::Sdp`], [`Proof::Staircase`] and
/// [`Proof::ConvDual`], which verify their multipliers with it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(tag = "proof", rename_all = "snake_case")]
pub enum Proof {
    /// Closed forms and convexity theorems `[S1]`-`[S7]` (single averaging).
    Theory,
    /// The dual certificate of an estimate `[D3]`-`[D9]`: its own multipliers, verified.
    DualCertificate,
    /// The SDP relaxation solved by Clarabel, its multipliers verified `[D4]`, `[H8]`, `[H14]`.
    Sdp,
    /// The Riemannian staircase `[D11]`, its multipliers verified.
    Staircase,
    /// The SDP with `conv(SO(3))` constraints on the edges' Gram blocks (small anisotropic
    /// problems), its multipliers verified `[A6]`.
    ConvSdp,
    /// The `conv(SO(3))` dual certificate at the estimate `[A11]`: multipliers searched by
    /// cutting planes; the `O(3)` certificate of the penalised surrogate minus verified offsets.
    ConvDual,
    /// The dual certificate of the simultaneous problem at the estimate `[H15]`.
    SimultaneousDual,
    /// The same certificate with its least-norm couplings in low-rank form and each side's
    /// grounded bound from a sparse bordered factorisation `[H25]` (no dense matrix).
    SimultaneousLowRank,
    /// The decoupled bound of the simultaneous problem `[H16]`: the two view graphs' certified
    /// minima, summed.
    SimultaneousDecoupled,
    /// The simultaneous problem's `conv(SO(3))` surrogate `[H27]`: each anisotropic side's
    /// edges penalised against reflections at the estimate (`[A11]`), the trace-coupled dual
    /// certificate of the surrogate pair less the verified offsets.
    SimultaneousConv,
    /// A rig with every sensor held `[H19]`: the frames' view graph's certified bound (every
    /// rung of [`crate::certify::certify_multiple`]) plus its within-frame edges' cost.
    RigFrames,
    /// A rig's constraints dropped `[H19]`: the certified bounds of the images' view graph's
    /// components, summed.
    RigImages,
    /// A rig's within-frame couplings `[H21]`: the certified bounds of the components of the
    /// images' view graph with pseudo-edges inside each frame, less their constant on rig points.
    RigCoupled,
    /// The SO(2) dual certificate of the full-gravity problem at the estimate `[G3]`.
    GravityDual,
    /// The gravity problem's constraints dropped `[G7]`: the certified bound of the view graph
    /// alone (every rung of [`crate::certify::certify_multiple`]).
    GravityRelaxed,
    /// The held priors' tilted soft surrogate `[G12]`: soft priors turned so that the estimate
    /// is their critical point, certified by the multiple-averaging ladder, less their constant
    /// on the held problem's feasible set.
    GravitySurrogate,
    /// Information isotropic to rounding compared with scalar weights `lambda_min(H_e)` `[A13]`:
    /// the isotropic problem's dual certificate plus a proven constant.
    ScalarWeights,
    /// Branch and bound over SO(3) `[B1]`-`[B6]`.
    BranchAndBound,
    /// The grounded bound `[D15]`: `S` without one node's block verified positive definite.
    Grounded,
    /// A shifted sparse Cholesky factorisation of the `3n x 3n` matrix `S` `[D5]`, `[D6]`.
    ShiftedCholesky,
    /// The scalar comparison `[D13]`: the inertia of `n x n` factorisations (the whole graph,
    /// a subgraph, or a split into parts; the attempt's note says which).
    ScalarComparison,
    /// The block comparison `[A15]`: the inertia of the `3n` block Laplacian of a subgraph
    /// (anisotropic edges; the attempt's note says which subgraph).
    BlockComparison,
    /// Gershgorin discs `[D8]`: always available, usually weak.
    Gershgorin,
    /// The randomized Chebyshev test `[D16]`: a Monte Carlo bound, never a proof.
    Randomized,
}

impl Proof {
    /// The checks of `lambda_min(S) >= mu` that a dual certificate may climb, strongest first
    /// (the default of `dual.proofs`).
    pub const MATRIX_CHECKS: [Proof; 4] = [
        Proof::Grounded,
        Proof::ShiftedCholesky,
        Proof::ScalarComparison,
        Proof::BlockComparison,
    ];

    /// Rank among rungs of (nearly) equal predicted time: the stronger first.
    pub fn strength(self) -> u8 {
        match self {
            Proof::Theory => 0,
            Proof::Grounded => 1,
            // the isotropic path of the same bound: first among the cheap ones
            Proof::ScalarWeights => 1,
            Proof::DualCertificate
            | Proof::ConvDual
            | Proof::SimultaneousDual
            | Proof::SimultaneousLowRank
            | Proof::SimultaneousConv
            | Proof::GravityDual => 2,
            Proof::GravitySurrogate => 3,
            Proof::RigFrames | Proof::RigCoupled => 4,
            Proof::GravityRelaxed | Proof::SimultaneousDecoupled | Proof::RigImages => 5,
            Proof::ShiftedCholesky => 2,
            Proof::ScalarComparison | Proof::BlockComparison => 3,
            Proof::Sdp | Proof::ConvSdp => 6,
            Proof::BranchAndBound => 7,
            Proof::Staircase => 8,
            Proof::Gershgorin => 9,
            Proof::Randomized => 10,
        }
    }

    /// The family of the bound this proof gives (the JSON contract's `method`).
    pub fn method(self) -> BoundMethod {
        match self {
            Proof::Theory => BoundMethod::Theory,
            Proof::Sdp | Proof::ConvSdp => BoundMethod::Sdp,
            Proof::Staircase => BoundMethod::Staircase,
            Proof::BranchAndBound => BoundMethod::BranchAndBound,
            Proof::DualCertificate
            | Proof::ConvDual
            | Proof::SimultaneousDual
            | Proof::SimultaneousLowRank
            | Proof::SimultaneousConv
            | Proof::GravityDual
            | Proof::GravityRelaxed
            | Proof::GravitySurrogate
            | Proof::SimultaneousDecoupled
            | Proof::RigFrames
            | Proof::RigImages
            | Proof::RigCoupled
            | Proof::ScalarWeights
            | Proof::Grounded
            | Proof::ShiftedCholesky
            | Proof::ScalarComparison
            | Proof::BlockComparison
            | Proof::Gershgorin
            | Proof::Randomized => BoundMethod::Dual,
        }
    }
}

impl fmt::Display for Proof {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Proof::Theory => "theorems [S1]-[S7]",
            Proof::DualCertificate => "dual certificate [D3]-[D9]",
            Proof::Sdp => "SDP relaxation (Clarabel)",
            Proof::Staircase => "Riemannian staircase [D11]",
            Proof::ConvSdp => "conv(SO(3)) SDP relaxation [A6] (Clarabel)",
            Proof::ConvDual => "conv(SO(3)) dual certificate at the estimate [A11]",
            Proof::SimultaneousDual => "trace-coupled dual certificate at the estimate [H15]",
            Proof::SimultaneousLowRank => {
                "trace-coupled dual certificate at the estimate, low-rank couplings, sparse [H25]"
            }
            Proof::SimultaneousDecoupled => "the two view graphs' bounds, decoupled [H16]",
            Proof::SimultaneousConv => {
                "trace-coupled dual certificate of the conv(SO(3)) surrogate [H27]"
            }
            Proof::RigFrames => "the frames' view graph, every sensor held [H19]",
            Proof::RigImages => "the images' view graph, the rig's constraints dropped [H19]",
            Proof::RigCoupled => "the images' view graph with within-frame couplings [H21]",
            Proof::GravityDual => "SO(2) dual certificate at the estimate [G3]",
            Proof::GravityRelaxed => "the view graph without its gravity priors [G7]",
            Proof::GravitySurrogate => "the priors' tilted soft surrogate [G12]",
            Proof::ScalarWeights => "comparison with scalar weights [A13]",
            Proof::BranchAndBound => "branch and bound [B1]-[B6]",
            Proof::Grounded => "grounded bound [D15]",
            Proof::ShiftedCholesky => "shifted Cholesky of S [D5]",
            Proof::ScalarComparison => "scalar comparison [D13]",
            Proof::BlockComparison => "block comparison [A15]",
            Proof::Gershgorin => "Gershgorin discs [D8]",
            Proof::Randomized => "randomized test [D16] (not a proof)",
        })
    }
}

/// The family of the argument that produced a certificate's lower bound (the JSON contract's
/// `method`: `dual`, `sdp`, `theory`, `staircase`, `branch_and_bound`). Always derived from the
/// [`Proof`] that gave the bound ([`Proof::method`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoundMethod {
    /// A theorem (closed form, or a convexity argument).
    Theory,
    /// Multipliers of an estimate (from first-order conditions, or searched at it), verified.
    Dual,
    /// Multipliers from an SDP solve (Clarabel), verified by an independent eigenvalue check.
    Sdp,
    /// A rank-lifted (Riemannian staircase) solve of the SDP, with its own dual certificate.
    Staircase,
    /// Branch and bound over SO(3) with proven per-cell bounds (single and conjugate
    /// averaging, `[B1]`-`[B6]`).
    BranchAndBound,
}

impl fmt::Display for BoundMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BoundMethod::Theory => "theory",
            BoundMethod::Dual => "dual",
            BoundMethod::Sdp => "sdp",
            BoundMethod::Staircase => "staircase",
            BoundMethod::BranchAndBound => "branch_and_bound",
        })
    }
}
