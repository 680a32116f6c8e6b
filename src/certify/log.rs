//! The log of a certification: every rung considered, with its prediction and outcome
//! ([`Attempt`]), and the vocabulary of both ([`Refusal`], [`Outcome`], [`Point`]; the
//! [`Prediction`] is the budget's).

pub use super::budget::{FREE_SECONDS, Prediction};
use super::proof::Proof;
use serde::{Deserialize, Serialize};
use std::fmt;

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

/// One rung of a climb as it was climbed: the one record of what a certification did (the
/// report's `ladder`; its `methods` are derived from the rungs of the certification itself,
/// those with no [`Attempt::within`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Attempt {
    /// Which proof.
    pub rung: Proof,
    /// Whose multipliers (or which estimate) it worked on.
    pub point: Point,
    /// Its predicted cost, when one was computed.
    pub predicted: Option<Prediction>,
    /// What it did.
    pub outcome: Outcome,
    /// Wall time spent on it (its prediction included), seconds.
    pub seconds: f64,
    /// What it did, in words (empty for a refusal or a check whose outcome says it all).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub note: String,
    /// The proof whose multipliers this check verified (a rung of the climb inside it); absent
    /// for a rung of the certification itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub within: Option<Proof>,
}

impl Attempt {
    /// The verified lower bound it proved, if any (never an estimate's).
    pub fn lower_bound(&self) -> Option<f64> {
        match self.outcome {
            Outcome::Proved { lower_bound, .. } => Some(lower_bound),
            _ => None,
        }
    }

    /// Its note, or its outcome in words when it has none.
    pub fn words(&self) -> String {
        if self.note.is_empty() {
            self.outcome.to_string()
        } else {
            self.note.clone()
        }
    }
}

impl fmt::Display for Attempt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} at {}: {}", self.rung, self.point, self.outcome)?;
        if let Some(p) = self.predicted {
            write!(
                f,
                " (predicted {:.2} s, {}; took {:.2} s)",
                p.seconds,
                crate::certify::budget::human_bytes(p.bytes),
                self.seconds
            )?;
        }
        Ok(())
    }
}
