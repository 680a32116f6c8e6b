//! The log of a certification: every rung considered, with its prediction and outcome
//! ([`Attempt`]), and the vocabulary of both ([`Prediction`], [`Refusal`], [`Outcome`],
//! [`Point`]).

use super::proof::Proof;
use serde::{Deserialize, Serialize};
use std::fmt;

/// Predicted times below this many seconds are not told apart: such rungs run strongest first
/// (the timer and the time model resolve no finer; `paper-notes/certificates.md` `[D12]`).
pub const FREE_SECONDS: f64 = 0.05;

/// The cost of a rung predicted from the problem before it runs (the models of
/// [`crate::certify::Budget`]), and its chance of proving what the verdict needs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Prediction {
    /// Predicted wall time, seconds.
    pub seconds: f64,
    /// Predicted peak memory of its largest allocation (a factor and its scratch), bytes.
    pub bytes: f64,
    /// The predicted chance, in `(0, 1]`, that it proves what the verdict needs (from cheap
    /// observables of the problem; 1 when nothing predicts a failure). Omitted from JSON at 1.
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub success: f64,
}

fn one() -> f64 {
    1.0
}

fn is_one(x: &f64) -> bool {
    *x == 1.0
}

impl Prediction {
    /// A prediction of `seconds` and `bytes` with nothing predicting a failure.
    pub fn new(seconds: f64, bytes: f64) -> Self {
        Prediction {
            seconds,
            bytes,
            success: 1.0,
        }
    }

    /// The same prediction with a chance of success `p` (clamped to `[1e-3, 1]`).
    pub fn with_success(self, p: f64) -> Self {
        Prediction {
            success: if p.is_nan() { 1.0 } else { p.clamp(1e-3, 1.0) },
            ..self
        }
    }

    /// The order of the climb: the expected time to a proof, `seconds / success` (the order
    /// that minimises the expected time of a sequence of independent tries), with times below
    /// [`FREE_SECONDS`] tied.
    pub(crate) fn order_key(&self) -> f64 {
        self.seconds.max(FREE_SECONDS) / self.success
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
