//! Settings, solution type and the dispatching entry point [`solve_multiple`] of the local
//! multiple-rotation-averaging solvers (`paper-notes/multiple.md`, `[M4]`..`[M9]`).

use crate::error::{Error, Result};
use crate::linalg::linear_solver::SolverKind;
use crate::multiple::robust::inlier_threshold_deg;
use crate::multiple::{MultipleProblem, fix_gauge};
use crate::objective::{Loss, Objective};
use crate::so3::{Rotation, nearest_rotation};
use crate::termination::SolverReport;
use serde::{Deserialize, Serialize};
use std::fmt;

/// The window of [`MultipleSettings::irls_decrease_tolerance`], iterations.
pub const IRLS_DECREASE_WINDOW: usize = 10;

/// How the local solver is started.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Initialisation {
    /// The shortest-path spanning tree (lengths `1 / w`) from a central node, rotations
    /// propagated along it, gauge `R_0 = I` (`[M4]`, [`crate::multiple::spanning_tree`]).
    SpanningTree,
    /// Bottom-3 eigenvectors of the connection Laplacian, rounded to SO(3) (`[M5]`). In
    /// [`solve_multiple`], graphs whose Newton systems are solved with the scalar Laplacian
    /// preconditioner (block factor too large: long chains, large grids, `[M6b]`) start from
    /// the spanning tree instead.
    #[default]
    Spectral,
    /// A given estimate (one rotation per node).
    Given(#[serde(with = "crate::so3::serde_rows::rotations")] Vec<Rotation>),
    /// The problem's L1 start (`[M9]`) already solved, as the rule `auto`'s scale from the
    /// data solves it ([`data_scale`](crate::multiple::robust_scale::data_scale)): Huber and
    /// Cauchy use it as their L1 start instead of solving it again; every other solve starts
    /// from it as from a spectral start (the two stages of `[A14]` and `[G8]` still run).
    L1Start(#[serde(with = "crate::so3::serde_rows::rotations")] Vec<Rotation>),
}

/// Settings of [`solve_multiple`]. Build with struct update syntax:
/// `MultipleSettings { max_iterations: 50, ..Default::default() }`. The cost minimised is the
/// problem's objective ([`MultipleProblem::with_objective`]; `[M7]`):
///
/// | objective | cost | method |
/// |---|---|---|
/// | chordal L2 | `sum w_e ||R_j - R_ij R_i||_F^2 = sum w_e 8 sin^2(theta_e / 2)` | Riemannian Newton / Levenberg-Marquardt |
/// | geodesic L2 | `sum w_e theta_e^2` | Lie-algebraic averaging (Govindu) |
/// | geodesic L1 | `sum w_e theta_e` | IRLS (Weiszfeld-type weights `1 / max(theta, l1_epsilon)`) |
/// | geodesic Huber | `sum w_e rho(theta_e)`, `rho = theta^2` if `theta <= c`, else `2 c theta - c^2` | IRLS |
/// | geodesic Cauchy | `sum w_e c^2 ln(1 + theta_e^2 / c^2)` | IRLS |
///
/// (`theta_e` the residual angle of edge `e`; `c` the threshold of [`crate::objective::Loss`],
/// given in degrees. With information matrices the losses apply to the Mahalanobis angle,
/// `sum wbar_e rho(theta_H)`; the robust ones are then solved in two stages, `[A14]`.)
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MultipleSettings {
    /// The initialisation (default spectral; [`solve_multiple`] starts graphs solved with the
    /// scalar Laplacian preconditioner, `[M6b]`, from the spanning tree instead).
    pub init: Initialisation,
    /// Maximum number of outer iterations (default 1000, for the second-order methods and the
    /// IRLS methods alike; the gravity solve's reweighting passes at most a tenth of it).
    /// Well-conditioned graphs converge in 2-20 Newton iterations; strongly anisotropic
    /// information (eigenvalue ratios 1e5-1e8) needs a few hundred, with steps the
    /// Levenberg-Marquardt damping shortens (a 2000-pose SLAM graph: 394, `[M6]`).
    pub max_iterations: usize,
    /// Stop when the **relative gradient norm** `||grad f(R)||_2 / sum_e w_e` is at most this
    /// (default `1e-8`). `grad f` is the Riemannian gradient of the chosen cost in the
    /// right-perturbation chart `R_i exp(hat w_i)` (`[M3]`), all nodes stacked; `sum_e w_e` is
    /// the scale of the largest possible gradient (each edge contributes at most
    /// `4 sqrt(2) w_e`, `[M3]`), which makes the test invariant to scaling all weights and
    /// independent of the start. For the non-smooth L1 loss the test is on the smoothed cost.
    pub gradient_tolerance: f64,
    /// Chordal L2 (Newton): stop only when, besides the gradient test, the Newton model's
    /// predicted decrease `-(g.s + s^T H s / 2)` is at most this times the cost (default
    /// `1e-12`; plus `1e-30 sum_e w_e` for costs near zero). The gradient test alone stops
    /// early on small costs: on parking-garage it left the estimate `5e-6` (relative) above the
    /// optimum, which no certificate can then close. One more Newton step near the optimum costs
    /// one factorisation.
    pub decrease_tolerance: f64,
    /// The L1 loss (IRLS, `[M9]`): also stop (converged) when the cost
    /// decreased by at most this fraction of itself over the last [`IRLS_DECREASE_WINDOW`]
    /// iterations (default `1e-10`). IRLS converges linearly, and for L1 its gradient test is
    /// on a smoothed, non-smooth cost: on 1DSfM Madrid (23,784 edges) the L1 gradient hovered
    /// near `8.5e-7` from iteration 140 to 405 while the cost changed by `6e-12` relative. This
    /// test stops there after about 100 iterations, at a cost `3e-10` (relative) above where
    /// 405 iterations end. The smooth losses keep the gradient test alone.
    pub irls_decrease_tolerance: f64,
    /// Also stop (converged) when every node moves by less than this angle in one step, radians
    /// (default `1e-12`).
    pub step_tolerance: f64,
    /// L1 smoothing: IRLS weights `1 / max(theta_e, l1_epsilon)`, radians (default `1e-6`).
    pub l1_epsilon: f64,
    /// The L1 loss (IRLS, `[M9]`): each step is first tried at this multiple of the
    /// reweighted least-squares step (over-relaxation, in `[1, 2)`; default `1.8`), then at 1
    /// and halved while the cost increases. 1.0 is the plain Weiszfeld-type step. Measured on
    /// generated SfM scenes: 1.3-1.5x fewer iterations (`paper-notes/multiple.md` `[M9]`). The
    /// L1 start of Huber and Cauchy keeps 1.0.
    pub l1_overrelaxation: f64,
    /// The robust losses (L1, Huber, Cauchy): an edge is an **inlier** iff its residual angle
    /// at the final estimate is at most this many degrees. `None` (default): the Huber
    /// threshold or Cauchy scale, and for L1
    /// [`DEFAULT_L1_INLIER_THRESHOLD_DEG`](crate::multiple::robust::DEFAULT_L1_INLIER_THRESHOLD_DEG)
    /// ([`crate::multiple::robust::inlier_threshold_deg`]). The solution's
    /// [`MultipleSolution::residuals`] and the inlier-graph certificate of the pipeline use it.
    pub inlier_threshold_deg: Option<f64>,
    /// The rule `auto` of the pipeline ([`crate::pipeline::average_multiple`]; the command
    /// line's and Python's default `--loss auto`): for a chordal L2 problem, when the
    /// least-squares estimate's residuals show outliers
    /// ([`suspected_outliers`](crate::multiple::robust::suspected_outliers)), solve this robust
    /// objective instead and certify its inlier graph. `None` (default): the problem's
    /// objective as given (least squares only warns). [`solve_multiple`] ignores it.
    pub robust_on_outliers: Option<crate::objective::Objective>,
    /// How the rule `auto` scales `robust_on_outliers` (`[D20]`): from the data (the default,
    /// [`data_scale`](crate::multiple::robust_scale::data_scale): 1.5 times the median
    /// residual at the robust solve's L1 start, within 0.01-10 degrees, and unless
    /// `inlier_threshold_deg` is given the inlier threshold 3 times it), or as given (the
    /// command line's `--loss-threshold`).
    pub robust_scale: crate::multiple::robust_scale::ScaleRule,
    /// Time limit of the solve, seconds (`None`, the default: no limit; the command line's
    /// `--max-seconds`). Checked before each iteration of the Newton-LM and IRLS loops (the
    /// initialisation, the L1 start and both stages of `[A14]` share the clock); when reached
    /// the solve ends with [`Termination::TimeLimit`](crate::Termination::TimeLimit) at its last
    /// accepted iterate. It ends within the limit plus one iteration (and the initialisation,
    /// which is not interrupted).
    pub max_seconds: Option<f64>,
}

impl Default for MultipleSettings {
    fn default() -> Self {
        MultipleSettings {
            init: Initialisation::Spectral,
            max_iterations: 1000,
            gradient_tolerance: 1e-8,
            decrease_tolerance: 1e-12,
            irls_decrease_tolerance: 1e-10,
            step_tolerance: 1e-12,
            l1_epsilon: 1e-6,
            l1_overrelaxation: 1.8,
            inlier_threshold_deg: None,
            robust_on_outliers: None,
            robust_scale: crate::multiple::robust_scale::ScaleRule::FromData,
            max_seconds: None,
        }
    }
}

impl MultipleSettings {
    /// Check every field; [`Error::InvalidSettings`] names the first bad one.
    ///
    /// ```
    /// use rotavg::multiple::MultipleSettings;
    /// assert!(MultipleSettings::default().validate().is_ok());
    /// let bad = MultipleSettings { max_iterations: 0, ..Default::default() };
    /// assert!(matches!(bad.validate(), Err(rotavg::Error::InvalidSettings { .. })));
    /// ```
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: String| {
            Err(Error::InvalidSettings {
                name: name.into(),
                reason,
            })
        };
        if self.max_iterations == 0 {
            return bad("max_iterations", "must be at least 1".into());
        }
        for (name, v) in [
            ("gradient_tolerance", self.gradient_tolerance),
            ("decrease_tolerance", self.decrease_tolerance),
            ("irls_decrease_tolerance", self.irls_decrease_tolerance),
            ("step_tolerance", self.step_tolerance),
            ("l1_epsilon", self.l1_epsilon),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return bad(name, format!("must be finite and >= 0, got {v}"));
            }
        }
        if self.l1_epsilon <= 0.0 {
            return bad("l1_epsilon", "must be > 0".into());
        }
        if !(1.0..2.0).contains(&self.l1_overrelaxation) {
            let v = self.l1_overrelaxation;
            return bad("l1_overrelaxation", format!("must be in [1, 2), got {v}"));
        }
        if let Some(t) = self.inlier_threshold_deg
            && !(t.is_finite() && t > 0.0 && t <= 180.0)
        {
            return bad(
                "inlier_threshold_deg",
                format!("must be a finite angle in (0, 180] degrees, got {t}"),
            );
        }
        crate::deadline::validate_max_seconds(self.max_seconds)?;
        if let Some(o) = self.robust_on_outliers {
            o.validate()?;
            if o.loss == crate::objective::Loss::L2 || o.metric != crate::so3::Metric::Geodesic {
                return bad(
                    "robust_on_outliers",
                    format!(
                        "must be a robust loss of the geodesic angle (l1, huber, cauchy), got {o}"
                    ),
                );
            }
        }
        Ok(())
    }
}

impl MultipleSettings {
    /// These settings for an L1 start (`[M9]`): stopped at [`L1_START_DECREASE_TOLERANCE`],
    /// smoothed at [`L1_START_EPSILON`] (each at least), no rule `auto`.
    pub(crate) fn for_l1_start(&self) -> MultipleSettings {
        MultipleSettings {
            irls_decrease_tolerance: self
                .irls_decrease_tolerance
                .max(L1_START_DECREASE_TOLERANCE),
            l1_epsilon: self.l1_epsilon.max(L1_START_EPSILON),
            // the start the robust defaults were measured with (`[M9]`)
            l1_overrelaxation: 1.0,
            robust_on_outliers: None,
            ..self.clone()
        }
    }

    /// The same settings with the time limit reduced by the time since `start` (at least 0).
    pub(crate) fn remaining(&self, start: std::time::Instant) -> MultipleSettings {
        MultipleSettings {
            max_seconds: crate::deadline::remaining(self.max_seconds, start),
            ..self.clone()
        }
    }

    /// The instant the time limit ends, counted from now (`None` without a limit).
    pub(crate) fn deadline(&self) -> Option<crate::deadline::Deadline> {
        crate::deadline::Deadline::after(self.max_seconds)
    }
}

/// The result of [`solve_multiple`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MultipleSolution {
    /// The estimate, gauge fixed so that `R_0 = I`.
    #[serde(with = "crate::so3::serde_rows::rotations")]
    pub rotations: Vec<Rotation>,
    /// The cost under the problem's objective (`[M7]`).
    pub cost: f64,
    /// The chordal L2 cost `sum w ||R_j - R_ij R_i||_F^2` of the estimate (`[M1]`).
    pub chordal_cost: f64,
    /// `||grad||_2` of the chosen cost at the estimate (absolute; the relative value used for
    /// stopping is this divided by the sum of weights, see
    /// [`MultipleSettings::gradient_tolerance`]). For the two-stage robust solve of
    /// anisotropic measurements (`[A14]`), of the cost on the edges its second stage kept.
    pub gradient_norm: f64,
    /// The objective minimised.
    pub objective: Objective,
    /// Iterations, why it stopped, wall time (including the initialisation).
    pub report: SolverReport,
    /// The cost of the initialisation under the objective.
    pub init_cost: f64,
    /// The robust losses (L1, Huber, Cauchy): per-edge residual angles at the estimate, final
    /// relative IRLS weights and inlier flags ([`crate::multiple::robust::edge_residuals`] with
    /// [`MultipleSettings::inlier_threshold_deg`]); `None` for the L2 losses.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub residuals: Option<crate::multiple::robust::EdgeResiduals>,
    /// The linear algebra of the chordal Newton-LM solve (`[M6]`, `[M6b]`): which solver, and
    /// how many symbolic analyses, numeric factorisations and conjugate-gradient iterations it
    /// took; `None` for the other objectives.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub linear_algebra: Option<LinearAlgebraCounts>,
}

/// The work of the sparse linear algebra of a local solve (`[M6]`, `[M6b]`). One sparse
/// factorisation per Newton step is the cost a direct solver pays; the Laplacian-preconditioned
/// path pays one per solve.
///
/// ```
/// use rotavg::multiple::{solve_multiple, MultipleSettings, synthetic::SyntheticGraph};
/// let (p, _) = SyntheticGraph { num_rotations: 50, num_edges: 150, noise_sigma: 0.01, ..Default::default() }.generate();
/// let sol = solve_multiple(&p, &MultipleSettings::default())?;
/// let la = sol.linear_algebra.unwrap();
/// assert_eq!(la.solver, "sparse Cholesky");
/// assert!(la.numeric_factorizations >= sol.report.iterations.saturating_sub(1));
/// # Ok::<(), rotavg::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct LinearAlgebraCounts {
    /// The solver of the Newton systems: `sparse Cholesky`, `PCG (scalar Laplacian
    /// preconditioner)` or `PCG (block-Jacobi preconditioner)`.
    pub solver: String,
    /// Symbolic sparse Cholesky analyses (orderings), including the one that chose the solver.
    pub symbolic_analyses: usize,
    /// Numeric sparse Cholesky factorisations (of the Newton systems, or of the preconditioner).
    pub numeric_factorizations: usize,
    /// Conjugate-gradient iterations over all Newton steps (0 for the direct solver).
    pub cg_iterations: usize,
}

impl fmt::Display for MultipleSolution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: cost {:.6e} (initial {:.6e}), chordal cost {:.6e}, gradient norm {:.3e}; {}",
            self.objective,
            self.cost,
            self.init_cost,
            self.chordal_cost,
            self.gradient_norm,
            self.report
        )
    }
}

/// The exit of every local solve (contract section 1): each rotation replaced by its nearest
/// rotation ([`nearest_rotation`]: the last iterate carries the rounding of its steps, and a
/// solver that stopped at once keeps its start), the gauge fixed (`R_0 = I` exactly), and the
/// costs those of the problem at exactly this estimate. The termination measures (gradient
/// norm, iterations) stay those of the last iterate.
fn on_so3(problem: &MultipleProblem, out: &mut MultipleSolution) {
    for r in &mut out.rotations {
        *r = nearest_rotation(r);
    }
    fix_gauge(&mut out.rotations);
    if let Some(r0) = out.rotations.first_mut() {
        *r0 = Rotation::identity();
    }
    out.chordal_cost = problem.chordal_cost(&out.rotations);
    out.cost = match problem.objective().is_chordal_l2() {
        true => out.chordal_cost,
        false => problem.cost(&out.rotations),
    };
}

/// Solve multiple rotation averaging locally: initialise ([`Initialisation`]), then minimise the
/// problem's objective. The graph must be connected ([`Error::Disconnected`] otherwise; solve
/// [`MultipleProblem::largest_component`] to go on). The output has `R_0 = I`; whatever the
/// defect of the measurements (used as given), the start and the estimate are rotations to
/// rounding (contract section 1), and `cost` and `chordal_cost` are the problem's costs at exactly
/// the returned estimate. A robust loss on anisotropic measurements without a given start is
/// solved in two stages (`paper-notes/anisotropic.md` `[A14]`): unit weights first, then the
/// information on the edges consistent with that estimate; its report is named `two-stage ...`.
///
/// ```
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// use rotavg::multiple::{solve_multiple, MultipleSettings};
/// let (p, gt) = SyntheticGraph { num_rotations: 50, num_edges: 150, noise_sigma: 0.0, ..Default::default() }.generate();
/// let sol = solve_multiple(&p, &MultipleSettings::default()).unwrap();
/// assert!(sol.cost < 1e-12);
/// assert!(sol.report.termination.is_converged());
/// assert!(rotavg::so3::angle_between(&sol.rotations[7], &gt[7]) < 1e-6);
/// ```
pub fn solve_multiple(
    problem: &MultipleProblem,
    settings: &MultipleSettings,
) -> Result<MultipleSolution> {
    settings.validate()?;
    problem.require_connected()?;
    let start = std::time::Instant::now();
    // sparse Cholesky or PCG (which preconditioner), decided once from the graph ([M6], [M6b])
    let choice = crate::multiple::chordal::choose_solver(problem)?;
    let kind = Some(choice.kind);
    crate::progress::phase(crate::progress::Phase::Initialise, || {
        format!(
            "{} nodes, {} edges",
            problem.num_rotations(),
            problem.num_edges()
        )
    });
    if problem.is_anisotropic()
        && inlier_threshold_deg(&problem.objective(), settings).is_some()
        && !matches!(settings.init, Initialisation::Given(_))
    {
        // [A14]: a robust loss with information, in two stages
        let out =
            crate::multiple::two_stage::solve_two_stage(problem, &settings.remaining(start), kind)?;
        return Ok(finish(problem, settings, out, start));
    }
    let init = match &settings.init {
        // [M6b]: on graphs solved with the Laplacian preconditioner (block factor too large),
        // the near-singular solves of the spectral inverse iteration are not cheap; Newton-LM
        // from the spanning tree is (10^6-node chain: 14 s against 122 s for the spectral step).
        Initialisation::Spectral if kind == Some(SolverKind::Laplacian) => {
            crate::multiple::init::spanning_tree(problem)
        }
        Initialisation::Spectral => crate::multiple::init::spectral_within(
            problem,
            kind,
            settings.remaining(start).deadline(),
        )?,
        other => crate::multiple::init::initialise(problem, other)?,
    };
    let objective = problem.objective();
    crate::progress::phase(crate::progress::Phase::Solve, || objective.to_string());
    let left = settings.remaining(start);
    let out = if objective.is_chordal_l2() {
        crate::multiple::chordal::solve_chordal(problem, init, &left, Some(choice))?
    } else if objective.loss == Loss::L2 {
        crate::multiple::geodesic::solve_geodesic(problem, init, &left, kind)?
    } else {
        let init = l1_start(problem, init, &left, kind)?;
        let left = settings.remaining(start);
        crate::multiple::robust::solve_robust(problem, init, &left, kind)?
    };
    Ok(finish(problem, settings, out, start))
}

/// The exit of [`solve_multiple`]: the estimate on SO(3) ([`on_so3`]), the robust losses'
/// residuals at it, the wall time since `start`.
fn finish(
    problem: &MultipleProblem,
    settings: &MultipleSettings,
    mut out: MultipleSolution,
    start: std::time::Instant,
) -> MultipleSolution {
    on_so3(problem, &mut out);
    out.residuals = inlier_threshold_deg(&problem.objective(), settings)
        .map(|t| crate::multiple::robust::edge_residuals(problem, &out.rotations, t));
    out.report.seconds = start.elapsed().as_secs_f64();
    out
}

/// The L1 start of Huber and Cauchy (`[M9]`) stops when its cost decreased by at most
/// this fraction of itself over the last [`IRLS_DECREASE_WINDOW`] iterations (or at the
/// settings' own tests): a start needs the L1 solution's basin, not its digits. Measured
/// (`[M9]`): on a generated 3000-camera graph the L1 start took 455 iterations (11.7 s) at
/// `1e-10` and about 50 (0.6 s) at `1e-4`, with the same Cauchy estimate; on generated SfM
/// scenes of 36 to 10^4 cameras the default's errors are unchanged to 1e-4 degrees.
pub const L1_START_DECREASE_TOLERANCE: f64 = 1e-4;

/// The L1 start's smoothing ([`MultipleSettings::l1_epsilon`] at least this), radians: its
/// IRLS weights `1 / max(theta, eps)` then span at most `1 / eps` instead of `1e6`, which the
/// conjugate gradients of large graphs pay for. Measured (`[M9]`): on a generated graph of 10^4
/// cameras and 10^5 edges the start took 5.9 s at `1e-6` and 0.71 s at `1e-3` (16 and 15
/// iterations), with the same Cauchy estimate; generated SfM scenes of 36 to 10^4 images: the
/// default's errors unchanged to 2e-4 degrees.
pub const L1_START_EPSILON: f64 = 1e-3;

/// The start of an isotropic Huber or Cauchy solve `[M9]`: without a given estimate, the L1 solution
/// (same metric, weights and information) from `init`, as L1-then-IRLS averaging does
/// (Chatterjee & Govindu; COLMAP's global mapper): these losses are not convex on SO(3), and
/// Cauchy's IRLS from the basin that many outliers create stays in it (a generated
/// 10^4-camera scene with 8 % twisted and repeated-structure pairs: Cauchy from the spectral
/// start 65.8 deg median error, from the L1 solution 1.9 deg). `init` itself for L1, for
/// the least-squares losses and for a given start.
fn l1_start(
    problem: &MultipleProblem,
    init: Vec<Rotation>,
    settings: &MultipleSettings,
    kind: Option<SolverKind>,
) -> Result<Vec<Rotation>> {
    let objective = problem.objective();
    let redescending = matches!(objective.loss, Loss::Huber { .. } | Loss::Cauchy { .. });
    // (anisotropic problems without a given start are solved in two stages, [A14]; their
    // first stage, isotropic, gets this start)
    if !redescending
        || matches!(
            settings.init,
            Initialisation::Given(_) | Initialisation::L1Start(_)
        )
    {
        return Ok(init);
    }
    crate::progress::phase(crate::progress::Phase::Solve, || {
        format!("{} start", Objective::new(objective.metric, Loss::L1))
    });
    let l1 = problem
        .clone()
        .with_objective(Objective::new(objective.metric, Loss::L1))?;
    let start = settings.for_l1_start();
    Ok(crate::multiple::robust::solve_robust(&l1, init, &start, kind)?.rotations)
}
