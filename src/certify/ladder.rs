//! The proof ladder: every way a certification can bound the global minimum, as data.
//!
//! A certification tries **rungs** (proofs) one after the other. Each rung has a predicted cost
//! ([`Prediction`]: seconds and bytes, computed from the problem before it runs) and an attempt
//! whose [`Outcome`] is a verified lower bound, a failure (it ran and proved nothing usable), a
//! typed refusal (not started: over the [`crate::certify::Budget`] or not applicable), or, for the
//! randomized test `[D16]` only, a labelled estimate that is never a proof. The list of rungs is
//! built from the settings; the rungs that fit are run in the order of their predicted time (the
//! strongest first among those predicted at most [`FREE_SECONDS`]), a failure falls through to
//! the next, and the first whose bound is good enough for the verdict ends the climb. Because a
//! rung is refused only by its own prediction, raising a budget can only add rungs: a larger
//! budget never gives a weaker verdict (issue 24). The report lists every rung tried
//! ([`crate::certify::CertifyDetails::ladder`]).

use serde::{Deserialize, Serialize};
use std::fmt;

/// Predicted times below this many seconds are not told apart: such rungs run strongest first
/// (the timer and the time model resolve no finer; `paper-notes/certificates.md` `[D12]`).
pub const FREE_SECONDS: f64 = 0.05;

/// One proof of the ladder (`paper-notes/certificates.md`, `single.md`, `conjugate.md`,
/// `branch_and_bound.md`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "proof", rename_all = "snake_case")]
pub enum Rung {
    /// Closed forms and convexity theorems `[S1]`-`[S7]` (single averaging).
    Theory,
    /// The grounded bound `[D15]`: `S` without one node's block verified positive definite.
    Grounded,
    /// A shifted sparse Cholesky factorisation of the `3n x 3n` matrix `S` `[D5]`, `[D6]`.
    ShiftedCholesky,
    /// The scalar comparison `[D13]` with one `n x n` factorisation of the whole graph.
    ScalarWhole,
    /// The scalar comparison `[D13]` on a subgraph (every node keeps `edges_per_node` edges;
    /// the dropped edges keep their charges).
    ScalarSubgraph {
        /// Edges kept per node (the strongest choice that fits the budget).
        edges_per_node: f64,
    },
    /// The scalar comparison `[D13]` split into sparse parts, each proving a share.
    ScalarSplit {
        /// Factorisations.
        parts: usize,
        /// Parts holding each edge.
        copies: usize,
        /// Edges every node keeps in every part.
        min_degree: usize,
    },
    /// Gershgorin discs `[D8]`: always available, usually weak.
    Gershgorin,
    /// The SDP relaxation solved by Clarabel, its multipliers verified `[D4]`, `[H8]`.
    Sdp,
    /// The Riemannian staircase `[D11]`, its multipliers verified.
    Staircase,
    /// The SDP with `conv(SO(3))` constraints on the edges' Gram blocks (anisotropic problems
    /// of at most [`crate::relax::conv_so3::CONV_MAX_NODES`] nodes), its multipliers verified
    /// `[A6]`.
    ConvSdp,
    /// The `conv(SO(3))` dual certificate at the estimate `[A11]`: its multipliers searched by
    /// cutting planes, the `O(3)` certificate of the penalised surrogate verified by the rungs
    /// above (logged at [`Point::ConvDual`]), minus the verified offsets.
    ConvDual,
    /// The dual certificate of the simultaneous problem at the estimate `[H15]`: multipliers of
    /// the trace-coupled relaxation `[H14]` from the joint stationarity, couplings of least norm,
    /// verified by dense eigen-decompositions.
    SimultaneousDual,
    /// Branch and bound over SO(3) `[B1]`-`[B6]`.
    BranchAndBound,
    /// The randomized Chebyshev test `[D16]`: a Monte Carlo bound, never a proof.
    Randomized,
}

impl Rung {
    /// Rank among rungs of (nearly) equal predicted time: the stronger first.
    pub fn strength(&self) -> u8 {
        match self {
            Rung::Theory => 0,
            Rung::Grounded => 1,
            Rung::ShiftedCholesky => 2,
            Rung::ScalarWhole => 3,
            Rung::ScalarSubgraph { .. } => 4,
            Rung::ScalarSplit { .. } => 5,
            Rung::Sdp => 6,
            Rung::ConvSdp => 6,
            Rung::ConvDual => 2,
            Rung::SimultaneousDual => 2,
            Rung::BranchAndBound => 7,
            Rung::Staircase => 8,
            Rung::Gershgorin => 9,
            Rung::Randomized => 10,
        }
    }
}

impl fmt::Display for Rung {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Rung::Theory => f.write_str("theorems [S1]-[S7]"),
            Rung::Grounded => f.write_str("grounded bound [D15]"),
            Rung::ShiftedCholesky => f.write_str("shifted Cholesky of S [D5]"),
            Rung::ScalarWhole => f.write_str("scalar comparison [D13], whole graph"),
            Rung::ScalarSubgraph { edges_per_node } => write!(
                f,
                "scalar comparison [D13], subgraph of {edges_per_node} edges per node"
            ),
            Rung::ScalarSplit {
                parts,
                copies,
                min_degree,
            } => write!(
                f,
                "scalar comparison [D13], split into {parts} parts ({copies} per edge, degree >= {min_degree})"
            ),
            Rung::Gershgorin => f.write_str("Gershgorin discs [D8]"),
            Rung::Sdp => f.write_str("SDP relaxation (Clarabel)"),
            Rung::ConvSdp => f.write_str("conv(SO(3)) SDP relaxation [A6] (Clarabel)"),
            Rung::ConvDual => f.write_str("conv(SO(3)) dual certificate at the estimate [A11]"),
            Rung::SimultaneousDual => {
                f.write_str("trace-coupled dual certificate at the estimate [H15]")
            }
            Rung::Staircase => f.write_str("Riemannian staircase [D11]"),
            Rung::BranchAndBound => f.write_str("branch and bound [B1]-[B6]"),
            Rung::Randomized => f.write_str("randomized test [D16] (not a proof)"),
        }
    }
}

/// The cost of a rung predicted from the problem before it runs (the models of
/// [`crate::certify::Budget`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Prediction {
    /// Predicted wall time, seconds.
    pub seconds: f64,
    /// Predicted peak memory of its largest allocation (a factor and its scratch), bytes.
    pub bytes: f64,
}

impl Prediction {
    /// The order of the ladder: predicted time, with times below [`FREE_SECONDS`] tied.
    pub(crate) fn order_key(&self) -> f64 {
        self.seconds.max(FREE_SECONDS)
    }
}

/// Why a rung was not started.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "refusal", rename_all = "snake_case")]
pub enum Refusal {
    /// Its predicted memory or time does not fit the budget.
    OverBudget {
        /// What does not fit, with the numbers.
        reason: String,
    },
    /// It does not apply here (the reason says why).
    NotApplicable {
        /// Why.
        reason: String,
    },
    /// An earlier rung already proved what the verdict needs.
    NotNeeded,
}

impl fmt::Display for Refusal {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Refusal::OverBudget { reason } => write!(f, "over budget: {reason}"),
            Refusal::NotApplicable { reason } => write!(f, "not applicable: {reason}"),
            Refusal::NotNeeded => f.write_str("not needed: an earlier rung proved enough"),
        }
    }
}

/// What one rung did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "outcome", rename_all = "snake_case")]
pub enum Outcome {
    /// A verified lower bound on the global minimum.
    Proved {
        /// The bound.
        lower_bound: f64,
        /// The bound was good enough for the verdict (the climb stopped here).
        sufficient: bool,
    },
    /// It ran and proved nothing usable.
    Failed {
        /// Why, with the numbers (e.g. the negative pivots of an inertia test).
        reason: String,
    },
    /// It was not started.
    Refused(Refusal),
    /// A Monte Carlo bound `[D16]`: holds unless an event of probability at most
    /// `failure_probability` occurred; never a proof.
    Estimated {
        /// The bound.
        lower_bound: f64,
        /// The probability of the rare event.
        failure_probability: f64,
    },
}

impl fmt::Display for Outcome {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Outcome::Proved {
                lower_bound,
                sufficient,
            } => write!(
                f,
                "proved lower bound {lower_bound:.9e}{}",
                if *sufficient { "" } else { " (not enough)" }
            ),
            Outcome::Failed { reason } => write!(f, "failed: {reason}"),
            Outcome::Refused(r) => write!(f, "{r}"),
            Outcome::Estimated {
                lower_bound,
                failure_probability,
            } => write!(
                f,
                "estimated lower bound {lower_bound:.9e} (not a proof; failure probability {failure_probability:.0e})"
            ),
        }
    }
}

/// Which point's multipliers (or which estimate) a rung worked on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Point {
    /// The estimate as given.
    #[default]
    Given,
    /// The estimate refined by the local solver.
    Refined,
    /// The SDP's multipliers, or its rounding polished by the local solver.
    Sdp,
    /// The staircase's lifted point.
    Staircase,
    /// The multipliers of the `conv(SO(3))`-strengthened SDP `[A6]`.
    ConvSdp,
    /// The current estimate with its `conv(SO(3))` multipliers recovered by a search `[A11]`.
    ConvDual,
}

impl fmt::Display for Point {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Point::Given => "the given estimate",
            Point::Refined => "the refined estimate",
            Point::Sdp => "the SDP",
            Point::Staircase => "the staircase",
            Point::ConvSdp => "the conv(SO(3)) SDP",
            Point::ConvDual => "the conv(SO(3)) multipliers at the estimate",
        })
    }
}

/// One rung of the ladder as it was climbed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Attempt {
    /// Which proof.
    pub rung: Rung,
    /// Whose multipliers (or which estimate) it worked on.
    pub point: Point,
    /// Its predicted cost, when one was computed.
    pub predicted: Option<Prediction>,
    /// What it did.
    pub outcome: Outcome,
    /// Wall time spent on it (its prediction included), seconds.
    pub seconds: f64,
}

impl fmt::Display for Attempt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} at {}: {}", self.rung, self.point, self.outcome)?;
        if let Some(p) = self.predicted {
            write!(
                f,
                " (predicted {:.2} s, {}; took {:.2} s)",
                p.seconds,
                crate::certify::settings::human_bytes(p.bytes),
                self.seconds
            )?;
        }
        Ok(())
    }
}
