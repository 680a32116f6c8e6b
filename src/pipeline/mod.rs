//! The pipelines: solve locally, certify, and adopt a better solution found while certifying.
//! One shape for the three problems:
//!
//! ```text
//! problem ──solve_*──▶ solution ──certify_*──▶ certification ──▶ Averaged { solution, certificate, details }
//!                         ▲                          │ improvement (refinement, SDP rounding)
//!                         └──────────────────────────┘
//! ```
//!
//! | problem | pipeline | settings |
//! |---|---|---|
//! | single | [`average_single`] | [`AverageSettings<SingleSettings>`](AverageSettings) |
//! | multiple | [`average_multiple`] | [`AverageSettings<MultipleSettings>`](AverageSettings) |
//! | conjugate | [`average_conjugate`] | [`AverageSettings<ConjugateSettings>`](AverageSettings) |
//! | multiple with gravity priors | [`average_with_gravity`] | [`AverageSettings<MultipleSettings>`](AverageSettings) |
//!
//! [`simultaneous`] estimates the hand-eye rotation jointly with two view graphs `[H12]`, certified by the trace-coupled relaxation `[H14]`.

pub mod conjugate;
pub mod gravity;
pub mod inlier_graph;
pub mod loss_choice;
pub mod multiple;
pub mod rig;
pub mod simultaneous;
pub mod single;

pub use conjugate::average_conjugate;
pub use gravity::{GravityDetails, average_with_gravity};
pub use inlier_graph::{
    EstimateInlierGraph, InlierGraph, certify_estimate_inliers, certify_inlier_graph,
};
pub use loss_choice::LossChoice;
pub use multiple::average_multiple;
pub use rig::average_rig;
pub use simultaneous::average_simultaneous;
pub use single::average_single;

use crate::certify::{
    Certificate, Certification, CertifyDetails, CertifyMode, CertifySettings, ImprovementSource,
};
use crate::conjugate::{ConjugateSettings, ConjugateSolution};
use crate::error::Result;
use crate::multiple::{MultipleSettings, MultipleSolution};
use crate::single::{SingleSettings, SingleSolution};
use crate::termination::SolverReport;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Instant;

/// Settings of a pipeline: the local solver's and the certificate's.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct AverageSettings<S> {
    /// The local solver.
    pub solve: S,
    /// The certificate (`certify.mode = none`: no certificate).
    pub certify: CertifySettings,
}

impl<S> AverageSettings<S> {
    /// These settings with another certify mode.
    pub fn with_mode(mut self, mode: CertifyMode) -> Self {
        self.certify.mode = mode;
        self
    }
}

impl AverageSettings<MultipleSettings> {
    /// What is left of both time limits at `start.elapsed()`: the solve's
    /// ([`MultipleSettings::max_seconds`]) and the certificate's ([`crate::certify::Budget::after`]).
    pub(crate) fn remaining(&self, start: Instant) -> Self {
        let mut left = self.clone();
        left.solve = self.solve.remaining(start);
        left.certify.budget = self.certify.budget.after(start);
        left
    }
}

impl AverageSettings<crate::rig::RigSettings> {
    /// What is left of both time limits at `start.elapsed()`, as for view graphs.
    pub(crate) fn remaining(&self, start: Instant) -> Self {
        let mut left = self.clone();
        left.solve.max_seconds = crate::deadline::remaining(self.solve.max_seconds, start);
        left.certify.budget = self.certify.budget.after(start);
        left
    }
}

/// Settings of [`average_single`].
pub type AverageSingleSettings = AverageSettings<SingleSettings>;
/// Settings of [`average_multiple`].
pub type AverageMultipleSettings = AverageSettings<MultipleSettings>;
/// Settings of [`average_conjugate`].
pub type AverageConjugateSettings = AverageSettings<ConjugateSettings>;

/// The result of a pipeline: the solution (possibly improved while certifying), its
/// certificate (`None` when not requested or not available), and what ran.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Averaged<S> {
    /// The estimate with its cost and solver report.
    pub solution: S,
    /// Its certificate, when one was computed.
    pub certificate: Option<Certificate>,
    /// Times, methods, improvements.
    pub details: PipelineDetails,
}

/// The result of [`average_single`].
pub type SingleEstimate = Averaged<SingleSolution>;
/// The result of [`average_multiple`].
pub type MultipleEstimate = Averaged<MultipleSolution>;
/// The result of [`average_conjugate`].
pub type ConjugateEstimate = Averaged<ConjugateSolution>;

/// What a pipeline did.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PipelineDetails {
    /// The certification's details, when it ran.
    pub certify: Option<CertifyDetails>,
    /// Why no certificate was computed (`certificate` is `None`).
    pub skipped_reason: Option<String>,
    /// Where the returned solution came from when it is not the local solver's.
    pub improved_by: Option<ImprovementSource>,
    /// Time of the local solve (initialisation included), seconds.
    pub solve_seconds: f64,
    /// Time of the certification (refinement and SDP polishing included), seconds.
    pub certify_seconds: f64,
    /// Total time, seconds.
    pub total_seconds: f64,
    /// Multiple averaging with a robust loss (L1, Huber, Cauchy) and a certify mode other
    /// than `none`: the chordal L2 refinement and certificate of the inlier graph
    /// ([`InlierGraph`]). Omitted from JSON when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inlier_graph: Option<Box<InlierGraph>>,
    /// Multiple averaging with a least-squares loss: the residuals suggest outliers, and what to
    /// run instead ([`crate::multiple::robust::suspected_outliers`]). Omitted from JSON when
    /// absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub outliers: Option<crate::multiple::robust::OutlierWarning>,
    /// Multiple averaging under the rule `auto`
    /// ([`MultipleSettings::robust_on_outliers`](crate::multiple::MultipleSettings::robust_on_outliers)):
    /// which loss the data chose, and why. Omitted from JSON when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub loss_choice: Option<LossChoice>,
    /// Multiple averaging with gravity priors ([`average_with_gravity`]): the priors and their
    /// agreement with the view graph. Omitted from JSON when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gravity: Option<GravityDetails>,
    /// A rig with soft gravity priors whose sensors were estimated and then held: the
    /// certificate of the **joint** problem at the returned estimate, the sensors free
    /// (`paper-notes/gravity.md` `[G16]`). When it is `certified` it is also the run's
    /// certificate (it implies the held rig's) and the verdict names that problem. Omitted from
    /// JSON when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rig_joint: Option<crate::certify::Certificate>,
}

/// Write `value` in the form `f` asks for: alternate (`{:#}`, verbose) or not.
pub(crate) fn nested(f: &mut fmt::Formatter<'_>, value: &dyn fmt::Display) -> fmt::Result {
    if f.alternate() {
        write!(f, "{value:#}")
    } else {
        write!(f, "{value}")
    }
}

impl<S: fmt::Display> fmt::Display for Averaged<S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        nested(f, &self.solution)?;
        writeln!(f)?;
        match &self.certificate {
            Some(c) => {
                write!(f, "certificate: ")?;
                nested(f, c)?;
            }
            None => write!(
                f,
                "certificate: none ({})",
                self.details
                    .skipped_reason
                    .as_deref()
                    .unwrap_or("not requested")
            )?,
        }
        if let Some(source) = self.details.improved_by {
            write!(f, "\nimproved while certifying: {source:?}")?;
        }
        write!(
            f,
            "\ntimes: solve {:.3} s, certify {:.3} s, total {:.3} s",
            self.details.solve_seconds, self.details.certify_seconds, self.details.total_seconds
        )
    }
}

/// What the pipelines need of a solution.
pub(crate) trait PipelineSolution: Sized {
    /// The cost the certificate bounds.
    fn certified_cost(&self) -> f64;
    /// The solver's report.
    fn report_mut(&mut self) -> &mut SolverReport;
    /// Adopt `better` (found while certifying), carrying this solution's iterations and time
    /// into its report.
    fn adopt(mut self, mut better: Self) -> Self {
        let before = self.report_mut().clone();
        let report = better.report_mut();
        report.iterations += before.iterations;
        report.seconds += before.seconds;
        better
    }
}

/// What a pipeline needs of a problem: its solver, its certifier, the certify modes that apply.
pub(crate) trait PipelineProblem {
    /// The local solver's settings.
    type Settings;
    /// The local solution.
    type Solution: PipelineSolution;
    /// `single`, `multiple` or `conjugate`.
    const NAME: &'static str;
    /// The certify modes that apply (`none` included).
    const MODES: &'static [CertifyMode];
    /// Check the solver's settings.
    fn validate(settings: &Self::Settings) -> Result<()>;
    /// Why this problem gets no certificate with `mode` (its objective has no bound), if so.
    fn uncertifiable(&self, mode: CertifyMode) -> Option<String>;
    /// The local solve.
    fn solve(&self, settings: &Self::Settings) -> Result<Self::Solution>;
    /// The certification of a solution.
    fn certify(
        &self,
        solution: &Self::Solution,
        settings: &CertifySettings,
    ) -> Result<Certification<Self::Solution>>;
}

/// The pipeline of every problem: validate all settings, solve, certify unless the mode is
/// `none` or the objective has no certificate, and adopt an improvement.
pub(crate) fn average<P: PipelineProblem>(
    problem: &P,
    settings: &AverageSettings<P::Settings>,
) -> Result<Averaged<P::Solution>> {
    let start = Instant::now();
    let skip = validate(problem, settings)?;
    let solution = problem.solve(&settings.solve)?;
    certify_solved(problem, solution, settings, skip, start)
}

impl PipelineDetails {
    /// Count `seconds` more of solving (work a caller did before this pipeline ran) in the solve
    /// and the total times.
    pub(crate) fn add_solve_seconds(&mut self, seconds: f64) {
        self.solve_seconds += seconds.max(0.0);
        self.total_seconds += seconds.max(0.0);
    }

    /// Count `seconds` more of certifying (a further certificate of the same estimate) in the
    /// certify and the total times.
    pub(crate) fn add_certify_seconds(&mut self, seconds: f64) {
        self.certify_seconds += seconds.max(0.0);
        self.total_seconds += seconds.max(0.0);
    }
}

/// Validate every setting of [`average`] for `problem`; why no certificate will be computed
/// (mode `none`, or an objective without one under mode `auto`), if so.
pub(crate) fn validate<P: PipelineProblem>(
    problem: &P,
    settings: &AverageSettings<P::Settings>,
) -> Result<Option<String>> {
    P::validate(&settings.solve)?;
    settings.certify.validate()?;
    let mode = settings.certify.mode;
    mode.require(P::NAME, P::MODES)?;
    let skip = problem.uncertifiable(mode);
    if let Some(why) = &skip
        && mode != CertifyMode::Auto
        && mode != CertifyMode::None
    {
        return Err(crate::Error::InvalidSettings {
            name: "certify.mode".into(),
            reason: format!("certify mode `{mode}` was requested, but {why}"),
        });
    }
    Ok(skip.or_else(|| (mode == CertifyMode::None).then(|| "certify mode none".into())))
}

/// The second half of [`average`]: certify `solution` (solved from `start`) unless `skip`
/// says why not, and adopt an improvement.
pub(crate) fn certify_solved<P: PipelineProblem>(
    problem: &P,
    mut solution: P::Solution,
    settings: &AverageSettings<P::Settings>,
    skip: Option<String>,
    start: Instant,
) -> Result<Averaged<P::Solution>> {
    let mut details = PipelineDetails {
        solve_seconds: solution.report_mut().seconds,
        ..Default::default()
    };
    if let Some(why) = skip {
        details.skipped_reason = Some(why);
        details.total_seconds = start.elapsed().as_secs_f64();
        return Ok(Averaged {
            solution,
            certificate: None,
            details,
        });
    }
    let t = Instant::now();
    // one clock: the certificate gets what the solve left of the time limit
    let mut certify = settings.certify.clone();
    certify.budget = certify.budget.after(start);
    let c = problem.certify(&solution, &certify)?;
    let (solution, certificate) = match c.improvement {
        Some(better) => {
            details.improved_by = c.details.improvement.map(|i| i.source);
            let certificate = c.certificate.with_upper_bound(better.certified_cost());
            (solution.adopt(better), certificate)
        }
        None => (solution, c.certificate),
    };
    details.certify = Some(c.details);
    details.certify_seconds = t.elapsed().as_secs_f64();
    details.total_seconds = start.elapsed().as_secs_f64();
    Ok(Averaged {
        solution,
        certificate: Some(certificate),
        details,
    })
}
