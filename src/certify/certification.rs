//! What every `certify_*` function returns: one shape for the three problems.

use super::certificate::Certificate;
pub use super::evidence::SdpSummary;
use super::log::{Attempt, Outcome, Refusal};
use super::proof::BoundMethod;
use super::settings::CertifyMode;
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
    /// The rounding of the `conv(SO(3))` SDP's solution, polished by the local solver
    /// (anisotropic multiple averaging).
    ConvSdpRounding,
    /// The rig solver's steps that polish a rig's estimate for its coupled bound
    /// (`paper-notes/conjugate.md` `[H21]`).
    RigPolish,
}

/// A solution of lower cost than the certified estimate, found while bounding.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Improvement {
    /// Where it came from.
    pub source: ImprovementSource,
    /// Its cost.
    pub cost: f64,
}

/// What a certification did. Its one record is the log ([`CertifyDetails::ladder`]); the
/// report's `methods` are derived from it ([`CertifyDetails::methods`]).
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
#[serde(default)]
pub struct CertifyDetails {
    /// The mode requested.
    pub mode: CertifyMode,
    /// Multiple averaging: the stationarity residual `[D3]` of the point whose multipliers
    /// were verified last by the dual certificate (the refined estimate when there is one; 0
    /// at a critical point).
    pub stationarity_residual: Option<f64>,
    /// Multiple averaging: the stationarity residual `[D3]` of the given estimate.
    pub given_stationarity_residual: Option<f64>,
    /// Why a requested or default method was not run (e.g. the SDP after a dual certificate
    /// limited by floating-point precision), if one was skipped: the last rung of the
    /// certification refused, unless the entry point states another reason.
    pub skipped_reason: Option<String>,
    /// The SDP solve, when one ran.
    pub sdp: Option<SdpSummary>,
    /// The Riemannian staircase, when it ran: every rank, its estimate of `lambda_min(S)`
    /// and whether it was verified (multiple averaging).
    pub staircase_steps: Vec<crate::certify::evidence::StaircaseStep>,
    /// The branch and bound, when one ran.
    pub branch_and_bound: Option<crate::certify::evidence::BranchAndBoundStats>,
    /// The improvement found, if any (the solution is in [`Certification::improvement`]).
    pub improvement: Option<Improvement>,
    /// Time spent refining the estimate before verifying multipliers (included in `seconds`).
    pub refine_seconds: f64,
    /// Every rung considered, in order: the rungs of the certification itself and the checks
    /// inside each proof ([`Attempt::within`]): which proof, at which point (the given
    /// estimate, the refined one, the SDP, the staircase), its predicted cost, its outcome and
    /// what it did ([`crate::certify::log`]).
    pub ladder: Vec<Attempt>,
    /// Total time, seconds.
    pub seconds: f64,
}

/// The JSON form of [`CertifyDetails`]: its fields and the derived `methods`.
#[derive(Serialize)]
struct DetailsJson<'a> {
    mode: CertifyMode,
    methods: Vec<MethodRun>,
    stationarity_residual: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    given_stationarity_residual: Option<f64>,
    skipped_reason: &'a Option<String>,
    sdp: &'a Option<SdpSummary>,
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    staircase_steps: &'a [crate::certify::evidence::StaircaseStep],
    #[serde(skip_serializing_if = "Option::is_none")]
    branch_and_bound: &'a Option<crate::certify::evidence::BranchAndBoundStats>,
    improvement: &'a Option<Improvement>,
    refine_seconds: f64,
    #[serde(skip_serializing_if = "<[_]>::is_empty")]
    ladder: &'a [Attempt],
    seconds: f64,
}

impl Serialize for CertifyDetails {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        DetailsJson {
            mode: self.mode,
            methods: self.methods(),
            stationarity_residual: self.stationarity_residual,
            given_stationarity_residual: self.given_stationarity_residual,
            skipped_reason: &self.skipped_reason,
            sdp: &self.sdp,
            staircase_steps: &self.staircase_steps,
            branch_and_bound: &self.branch_and_bound,
            improvement: &self.improvement,
            refine_seconds: self.refine_seconds,
            ladder: &self.ladder,
            seconds: self.seconds,
        }
        .serialize(serializer)
    }
}

impl CertifyDetails {
    /// The details of a certification in `mode` whose log is `ladder`, `seconds` long; the
    /// skipped reason is the last refusal of a rung of the certification itself.
    pub(crate) fn from_log(mode: CertifyMode, ladder: Vec<Attempt>, seconds: f64) -> Self {
        let skipped_reason = ladder
            .iter()
            .rev()
            .filter(|a| a.within.is_none())
            .find_map(|a| match &a.outcome {
                Outcome::Refused(Refusal::OverBudget { reason })
                | Outcome::Refused(Refusal::NotApplicable { reason }) => {
                    Some(format!("{} not run: {reason}", a.rung))
                }
                _ => None,
            });
        CertifyDetails {
            mode,
            skipped_reason,
            ladder,
            seconds,
            ..Default::default()
        }
    }

    /// The certificate of `cost` from a climb's best verified bound `best` (its value, family,
    /// proven `lambda_min` and note), under `tolerance`; without one, an `inconclusive`
    /// certificate of family `none_method` explained by the last rung's note.
    pub(crate) fn certificate_of(
        &self,
        cost: f64,
        best: Option<(f64, BoundMethod, Option<f64>, String)>,
        none_method: BoundMethod,
        tolerance: super::tolerance::GapTolerance,
    ) -> Certificate {
        let (lb, method, mu, why) = match best {
            Some((lb, method, mu, note)) => (Some(lb), method, mu.filter(|v| v.is_finite()), note),
            None => (
                None,
                none_method,
                None,
                self.methods()
                    .last()
                    .map_or_else(|| "no rung ran".into(), |m| m.note.clone()),
            ),
        };
        let mut c = Certificate::from_bounds(cost, lb, method, mu, tolerance, why, self.seconds);
        c.verified_min_eigenvalue = mu;
        c
    }

    /// The bounding methods that ran (or were refused), in order: the rungs of the
    /// certification itself ([`Attempt::within`] absent), not those not needed.
    pub fn methods(&self) -> Vec<MethodRun> {
        self.ladder
            .iter()
            .filter(|a| a.within.is_none())
            .filter(|a| !matches!(a.outcome, Outcome::Refused(Refusal::NotNeeded)))
            .map(|a| MethodRun {
                method: a.rung.method(),
                lower_bound: a.lower_bound(),
                seconds: a.seconds,
                note: a.words(),
            })
            .collect()
    }
}

impl fmt::Display for CertifyDetails {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "mode {}", self.mode)?;
        for m in &self.methods() {
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
