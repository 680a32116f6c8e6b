//! Settings, solution and the dispatching local solver [`solve_single`] of single rotation
//! averaging (`paper-notes/single.md`, `[S1]`..`[S7]`).

use super::problem::SingleProblem;
use super::{closed_form, iterative};
use crate::error::Result;
use crate::objective::{Loss, Objective};
use crate::so3::{self, Metric, Rotation};
use crate::termination::{SolverReport, Termination};
use crate::validate::{at_least_one, check_rotation, non_negative, positive};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Instant;

/// Settings of [`solve_single`]. All fields have defaults; use struct update syntax:
/// `SingleSettings { max_iterations: 50, ..Default::default() }`. The cost minimised is the
/// problem's objective ([`SingleProblem::with_objective`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SingleSettings {
    /// Iteration limit of the iterative methods (default 1000; >= 1).
    pub max_iterations: usize,
    /// Stop when the step of an iteration is shorter than this angle in radians
    /// (default 1e-12; > 0).
    pub step_tolerance: f64,
    /// Stop when the (minimum-norm sub)gradient norm divided by the total weight is below this
    /// (default 1e-12; >= 0).
    pub gradient_tolerance: f64,
    /// Start of the iterative methods (default `None`: each method's own start, see the module
    /// docs; the closed-form chordal L2 mean ignores it).
    #[serde(with = "crate::so3::serde_rows::optional_rotation")]
    pub init: Option<Rotation>,
    /// Time limit of the iterative methods, seconds (`None`, the default: no limit; the
    /// command line's `--max-seconds`). Checked before each iteration (and of the chordal L1
    /// start's Euclidean median); when reached the method ends with
    /// [`Termination::TimeLimit`] at its last iterate, within
    /// one iteration (`O(n)` work) of the limit. The closed forms are not interrupted.
    pub max_seconds: Option<f64>,
}

impl Default for SingleSettings {
    fn default() -> Self {
        SingleSettings {
            max_iterations: 1000,
            step_tolerance: 1e-12,
            gradient_tolerance: 1e-12,
            init: None,
            max_seconds: None,
        }
    }
}

impl SingleSettings {
    /// Check every value; [`crate::Error::InvalidSettings`] names the first bad one.
    ///
    /// ```
    /// use rotavg::single::SingleSettings;
    /// assert!(SingleSettings::default().validate().is_ok());
    /// let bad = SingleSettings { max_iterations: 0, ..Default::default() };
    /// assert!(bad.validate().unwrap_err().to_string().contains("max_iterations"));
    /// ```
    pub fn validate(&self) -> Result<()> {
        at_least_one("max_iterations", self.max_iterations)?;
        positive("step_tolerance", self.step_tolerance)?;
        non_negative("gradient_tolerance", self.gradient_tolerance)?;
        crate::deadline::validate_max_seconds(self.max_seconds)?;
        if let Some(r) = &self.init {
            check_rotation(|| "init".into(), r)?;
        }
        Ok(())
    }
}

/// The result of [`solve_single`]: the mean, its cost, and how the solver stopped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SingleSolution {
    /// The objective minimised.
    pub objective: Objective,
    /// Number of samples.
    pub num_samples: usize,
    /// The mean (row-major in JSON).
    #[serde(with = "crate::so3::serde_rows::rotation")]
    pub estimate: Rotation,
    /// `sum_i w_i rho(d(R_i, estimate))` under the objective.
    pub cost: f64,
    /// Solver name, iterations, why it stopped, wall time.
    pub report: SolverReport,
}

impl fmt::Display for SingleSolution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "single rotation average: {} mean of {} samples",
            self.objective, self.num_samples
        )?;
        let v = so3::log(&self.estimate);
        let t = v.norm();
        writeln!(
            f,
            "  estimate     angle {:.6} rad ({:.4} deg) about axis [{:.6}, {:.6}, {:.6}]",
            t,
            t.to_degrees(),
            if t > 0.0 { v.x / t } else { 0.0 },
            if t > 0.0 { v.y / t } else { 0.0 },
            if t > 0.0 { v.z / t } else { 1.0 },
        )?;
        for row in so3::rotation_to_rows(&self.estimate) {
            writeln!(
                f,
                "               [{:>12.9}, {:>12.9}, {:>12.9}]",
                row[0], row[1], row[2]
            )?;
        }
        writeln!(f, "  cost         {:.9e}", self.cost)?;
        write!(f, "  solver       {}", self.report)
    }
}

/// The exponent `p` of an L^p mean, for the internals of the iterative methods.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Norm {
    /// `p = 1`.
    L1,
    /// `p = 2`.
    L2,
}

/// What a local method returns before its cost is evaluated.
#[derive(Debug, Clone)]
pub(crate) struct Local {
    pub estimate: Rotation,
    pub iterations: usize,
    pub termination: Termination,
    pub name: &'static str,
}

/// The mean of the samples of `problem` under its objective, by the method of the module docs
/// (closed form for chordal L2, iterative otherwise). No certificate: see
/// [`crate::certify::certify_single`] and [`crate::pipeline::average_single`].
///
/// Errors only for invalid settings ([`crate::Error::InvalidSettings`]); non-convergence is
/// reported in `solution.report.termination`.
///
/// ```
/// use rotavg::single::{solve_single, SingleProblem, SingleSettings};
/// use rotavg::objective::{Loss, Objective};
/// use rotavg::so3::{exp, Metric};
/// use nalgebra::Vector3;
/// // Rz(0.2), Rz(-0.2) and I: every mean is I by symmetry.
/// let p = SingleProblem::new(
///     vec![exp(&Vector3::new(0.0, 0.0, 0.2)), exp(&Vector3::new(0.0, 0.0, -0.2)), exp(&Vector3::zeros())],
///     None,
/// )?;
/// for objective in [Objective::CHORDAL_L2, Objective::new(Metric::Geodesic, Loss::L1)] {
///     let s = solve_single(&p.clone().with_objective(objective)?, &SingleSettings::default())?;
///     assert!(rotavg::so3::angle(&s.estimate) < 1e-9);
/// }
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn solve_single(problem: &SingleProblem, settings: &SingleSettings) -> Result<SingleSolution> {
    settings.validate()?;
    let objective = problem.objective();
    let start = Instant::now();
    // a given start (a rotation to the validation tolerance) replaced by its nearest rotation:
    // the iterations then stay on SO(3) (contract section 1)
    let init = settings.init.as_ref().map(so3::nearest_rotation);
    let init = init.as_ref();
    let local = match (objective.metric, objective.loss) {
        (Metric::Chordal, Loss::L2) => closed_form::chordal_l2_local(problem),
        (Metric::Quaternion, Loss::L2) => closed_form::quaternion_l2_local(problem, settings, init),
        (Metric::Geodesic, Loss::L2) => iterative::geodesic_l2_local(problem, settings, init),
        (Metric::Geodesic, Loss::L1) => iterative::geodesic_l1_local(problem, settings, init),
        (Metric::Chordal, Loss::L1) => iterative::chordal_l1_local(problem, settings, init),
        (Metric::Quaternion, Loss::L1) => closed_form::quaternion_l1_local(problem, settings, init),
        _ => return Err(objective.unsupported("single", SingleProblem::SUPPORTED)),
    };
    let seconds = start.elapsed().as_secs_f64();
    // contract section 1: the estimate in SO(3) to rounding (a mean that stopped at a sample, which
    // is a rotation only to the validation tolerance, or the last iterate), its cost the
    // problem's at exactly that estimate
    let estimate = so3::nearest_rotation(&local.estimate);
    Ok(SingleSolution {
        objective,
        num_samples: problem.len(),
        estimate,
        cost: problem.cost(&estimate),
        report: SolverReport {
            name: local.name.into(),
            iterations: local.iterations,
            termination: local.termination,
            seconds,
        },
    })
}
