//! What every `certify_*` function returns: one shape for the three problems.

use super::certificate::{BoundMethod, Certificate};
use super::settings::CertifyMode;
use crate::relax::SdpStatus;
use serde::{Deserialize, Serialize};
use std::fmt;

/// The result of `certify_single`, `certify_multiple` and `certify_conjugate` for an estimate:
/// its [`Certificate`] (upper bound = the estimate's cost, never changed), what was run, and a
/// solution of lower cost if one was found while bounding.
///
/// `S` is the problem's solution type ([`crate::single::SingleSolution`],
/// [`crate::multiple::MultipleSolution`], [`crate::conjugate::ConjugateSolution`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Certification<S> {
    /// Verdict, bounds and gap of the given estimate.
    pub certificate: Certificate,
    /// The methods that ran, their bounds and times.
    pub details: CertifyDetails,
    /// A solution of strictly lower cost found while bounding (the local solver's polish of a
    /// refined estimate, of an SDP rounding or extraction), or `None`. The certificate's lower
    /// bound holds for it as well: [`Certificate::with_upper_bound`] gives its certificate. The
    /// pipelines (`average_*`) return it in place of the estimate; `certify_*` never do.
    pub improvement: Option<S>,
}

/// One bounding method that ran.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MethodRun {
    /// Which method.
    pub method: BoundMethod,
    /// The verified lower bound it produced (on the global minimum), if any.
    pub lower_bound: Option<f64>,
    /// Wall time, seconds.
    pub seconds: f64,
    /// What happened, in words.
    pub note: String,
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

/// Where an improvement came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ImprovementSource {
    /// The local solver run from the estimate to a tighter tolerance (multiple averaging).
    Refinement,
    /// The rounding (multiple) or rank-one extraction (conjugate) of the SDP solution, polished
    /// by the local solver.
    SdpRounding,
    /// A local solve started from a cell centre of the branch and bound that beat the estimate.
    BranchAndBound,
    /// The rounding of the staircase's lifted point, polished by the local solver (multiple
    /// averaging).
    StaircaseRounding,
}

/// A solution of lower cost than the certified estimate, found while bounding.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Improvement {
    /// Where it came from.
    pub source: ImprovementSource,
    /// Its cost.
    pub cost: f64,
}

/// What a certification did.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct CertifyDetails {
    /// The mode requested.
    pub mode: CertifyMode,
    /// The bounding methods that ran, in order.
    pub methods: Vec<MethodRun>,
    /// Multiple averaging: the stationarity residual `[D3]` of the point whose multipliers
    /// were verified last by the dual certificate (the refined estimate when there is one; 0
    /// at a critical point).
    pub stationarity_residual: Option<f64>,
    /// Multiple averaging: the stationarity residual `[D3]` of the given estimate.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub given_stationarity_residual: Option<f64>,
    /// Why a requested or default method was not run (e.g. the SDP after a dual certificate
    /// limited by floating-point precision), if one was skipped.
    pub skipped_reason: Option<String>,
    /// The SDP solve, when one ran.
    pub sdp: Option<SdpSummary>,
    /// The Riemannian staircase, when it ran: every rank, its estimate of `lambda_min(S)`
    /// and whether it was verified (multiple averaging).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub staircase_steps: Vec<crate::certify::multiple::staircase::StaircaseStep>,
    /// The branch and bound, when one ran.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branch_and_bound: Option<crate::certify::branch_and_bound::BranchAndBoundStats>,
    /// The improvement found, if any (the solution is in [`Certification::improvement`]).
    pub improvement: Option<Improvement>,
    /// Time spent refining the estimate before verifying multipliers (included in `seconds`).
    pub refine_seconds: f64,
    /// Every rung of the proof ladder considered, in order: which proof, at which point (the
    /// given estimate, the refined one, the SDP, the staircase), its predicted cost and its
    /// outcome ([`crate::certify::ladder`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ladder: Vec<crate::certify::ladder::Attempt>,
    /// Total time, seconds.
    pub seconds: f64,
}

impl CertifyDetails {
    /// Record a bounding method that ran on the given estimate, as a [`MethodRun`] and as a
    /// rung of the ladder (single and conjugate averaging; multiple averaging logs its rungs as
    /// it climbs): proved when it gave a bound (`sufficient` when that bound certifies), failed
    /// with its note otherwise.
    pub(crate) fn record(&mut self, run: MethodRun, sufficient: bool) {
        use crate::certify::ladder::Rung;
        let rung = match run.method {
            BoundMethod::Theory => Rung::Theory,
            BoundMethod::Sdp => Rung::Sdp,
            BoundMethod::Staircase => Rung::Staircase,
            BoundMethod::BranchAndBound => Rung::BranchAndBound,
            BoundMethod::Dual => Rung::Grounded,
        };
        self.record_rung(run, rung, None, sufficient);
    }

    /// [`Self::record`] on a named rung with its prediction.
    pub(crate) fn record_rung(
        &mut self,
        run: MethodRun,
        rung: crate::certify::ladder::Rung,
        predicted: Option<crate::certify::ladder::Prediction>,
        sufficient: bool,
    ) {
        use crate::certify::ladder::{Attempt, Outcome, Point};
        let outcome = match run.lower_bound {
            Some(lower_bound) => Outcome::Proved {
                lower_bound,
                sufficient,
            },
            None => Outcome::Failed {
                reason: run.note.clone(),
            },
        };
        self.ladder.push(Attempt {
            rung,
            point: Point::Given,
            predicted,
            outcome,
            seconds: run.seconds,
        });
        self.methods.push(run);
    }
}

impl fmt::Display for CertifyDetails {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "mode {}", self.mode)?;
        for m in &self.methods {
            write!(f, "; {} ({:.3} s): {}", m.method, m.seconds, m.note)?;
        }
        if let Some(r) = &self.skipped_reason {
            write!(f, "; {r}")?;
        }
        Ok(())
    }
}

impl<S> fmt::Display for Certification<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.certificate)?;
        if let Some(c) = self.details.sdp.as_ref().and_then(|s| s.polished_cost) {
            write!(f, "; SDP rounding + polish reaches cost {c:.9e}")?;
        }
        Ok(())
    }
}
