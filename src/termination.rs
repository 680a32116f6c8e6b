//! What every solver reports: iterations, why it stopped (with the measured value and its
//! threshold), and wall time: [`SolverReport`] with its [`Termination`]. Every solution type
//! carries one (`report` field); its `Display` is what the CLI prints on the `solver` line.

use serde::{Deserialize, Serialize};
use std::fmt;

/// Why an iterative solver stopped. Each variant carries the measured value and the threshold
/// it was compared against, so that "converged" is never an unexplained word.
///
/// ```
/// use rotavg::Termination;
/// let t = Termination::Converged { measure: "gradient norm".into(), value: 3.2e-11, threshold: 1e-10 };
/// assert!(t.is_converged() && t.name() == "converged");
/// assert_eq!(t.to_string(), "converged: gradient norm 3.200e-11 < 1.0e-10");
/// let t = Termination::IterationLimit { iterations: 100, value: 1e-3, threshold: 1e-10 };
/// assert!(!t.is_converged());
/// // JSON form (contract section 5): a `status` tag plus the variant's fields.
/// let json = serde_json::to_value(&t).unwrap();
/// assert_eq!(json["status"], "iteration_limit");
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum Termination {
    /// A closed-form solution: no iterations.
    ClosedForm,
    /// The stopping test was met: `value < threshold` for the named quantity.
    Converged {
        /// What was measured, e.g. `"gradient norm"`, `"relative cost decrease"`, `"step angle"`.
        measure: String,
        /// Its value at the last iterate.
        value: f64,
        /// The threshold.
        threshold: f64,
    },
    /// The iteration limit was reached before the stopping test was met.
    IterationLimit {
        /// The limit.
        iterations: usize,
        /// The stopping quantity at the last iterate (e.g. gradient norm).
        value: f64,
        /// Its threshold.
        threshold: f64,
    },
    /// No further decrease could be made (e.g. line search or trust region failed) while the
    /// stopping test was not met.
    Stalled {
        /// The stopping quantity at the last iterate.
        value: f64,
        /// Its threshold.
        threshold: f64,
    },
    /// The solve's time limit was reached before the stopping test was met (multiple
    /// averaging's [`crate::multiple::MultipleSettings::max_seconds`], the command line's
    /// `--max-seconds`); the last accepted iterate is returned.
    TimeLimit {
        /// The time this iteration loop was given, seconds: the solve's limit less what came
        /// before the loop (the initialisation, an L1 start, a first stage).
        seconds: f64,
        /// The stopping quantity at the last iterate.
        value: f64,
        /// Its threshold.
        threshold: f64,
    },
    /// A numerical failure (non-finite values, failed factorisation) ended the iteration; the
    /// best iterate so far is returned.
    NumericalFailure {
        /// What failed.
        reason: String,
    },
}

impl Termination {
    /// `true` for [`Termination::ClosedForm`] and [`Termination::Converged`].
    pub fn is_converged(&self) -> bool {
        matches!(
            self,
            Termination::ClosedForm | Termination::Converged { .. }
        )
    }

    /// Short machine-readable name: `closed_form`, `converged`, `iteration_limit`, `stalled`,
    /// `time_limit`, `numerical_failure`.
    pub fn name(&self) -> &'static str {
        match self {
            Termination::ClosedForm => "closed_form",
            Termination::Converged { .. } => "converged",
            Termination::IterationLimit { .. } => "iteration_limit",
            Termination::Stalled { .. } => "stalled",
            Termination::TimeLimit { .. } => "time_limit",
            Termination::NumericalFailure { .. } => "numerical_failure",
        }
    }
}

impl fmt::Display for Termination {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Termination::ClosedForm => write!(f, "closed form"),
            Termination::Converged {
                measure,
                value,
                threshold,
            } => {
                write!(f, "converged: {measure} {value:.3e} < {threshold:.1e}")
            }
            Termination::IterationLimit {
                iterations,
                value,
                threshold,
            } => write!(
                f,
                "iteration limit {iterations} reached (stopping value {value:.3e}, threshold {threshold:.1e})"
            ),
            Termination::Stalled { value, threshold } => {
                write!(
                    f,
                    "stalled: no further decrease (stopping value {value:.3e}, threshold {threshold:.1e})"
                )
            }
            Termination::TimeLimit {
                seconds,
                value,
                threshold,
            } => write!(
                f,
                "time limit reached ({seconds:.3} s left to this loop; stopping value {value:.3e}, threshold {threshold:.1e})"
            ),
            Termination::NumericalFailure { reason } => write!(f, "numerical failure: {reason}"),
        }
    }
}

/// The common part of every solver's report (contract section 5, `"solver"`).
///
/// ```
/// use rotavg::{SolverReport, Termination};
/// let r = SolverReport { name: "karcher".into(), iterations: 7, termination: Termination::ClosedForm, seconds: 0.0025 };
/// assert_eq!(r.to_string(), "karcher: 7 iterations, closed form (2.500 ms)");
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SolverReport {
    /// Solver name, e.g. `"karcher"`, `"gauss-newton"`.
    pub name: String,
    /// Iterations performed (0 for closed forms).
    pub iterations: usize,
    /// Why it stopped.
    pub termination: Termination,
    /// Wall time in seconds.
    pub seconds: f64,
}

impl fmt::Display for SolverReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {} iterations, {} ({:.3} ms)",
            self.name,
            self.iterations,
            self.termination,
            self.seconds * 1e3
        )
    }
}
