//! Settings, solution type and the dispatching entry point [`solve_multiple`] of the local
//! multiple-rotation-averaging solvers (`paper-notes/multiple.md`, `[M4]`..`[M9]`).

use crate::error::{Error, Result};
use crate::multiple::{MultipleProblem, fix_gauge};
use crate::report::SolverReport;
use crate::so3::Rotation;
use serde::{Deserialize, Serialize};
use std::fmt;

/// The loss minimised by [`solve_multiple`]. With `theta_e` the residual angle
/// `theta(R_ij R_i, R_j)` of edge `e` and `w_e` its weight (`paper-notes/multiple.md`, `[M7]`):
///
/// | loss | cost |
/// |---|---|
/// | `Chordal` | `sum w_e ||R_j - R_ij R_i||_F^2 = sum w_e 8 sin^2(theta_e / 2)` |
/// | `Geodesic` | `sum w_e theta_e^2` |
/// | `L1` | `sum w_e theta_e` |
/// | `Huber { c }` | `sum w_e rho(theta_e)`, `rho = theta^2 / 2` if `theta <= c`, else `c (theta - c / 2)` |
/// | `Cauchy { c }` | `sum w_e (c^2 / 2) ln(1 + theta_e^2 / c^2)` |
///
/// The Huber and Cauchy thresholds `c` are given in degrees.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Loss {
    /// Chordal L2 (the SDP-certifiable cost): Riemannian Newton / Levenberg-Marquardt.
    #[default]
    Chordal,
    /// Geodesic L2: Lie-algebraic averaging (Govindu).
    Geodesic,
    /// Geodesic L1: IRLS (Weiszfeld-type weights `1 / max(theta, epsilon)`).
    L1,
    /// Huber loss on the residual angle, threshold in degrees: IRLS.
    Huber {
        /// Threshold `c` in degrees (> 0).
        threshold_deg: f64,
    },
    /// Cauchy loss on the residual angle, scale in degrees: IRLS.
    Cauchy {
        /// Scale `c` in degrees (> 0).
        threshold_deg: f64,
    },
}

impl Loss {
    /// Short name: `chordal`, `geodesic`, `l1`, `huber`, `cauchy`.
    pub fn name(&self) -> &'static str {
        match self {
            Loss::Chordal => "chordal",
            Loss::Geodesic => "geodesic",
            Loss::L1 => "l1",
            Loss::Huber { .. } => "huber",
            Loss::Cauchy { .. } => "cauchy",
        }
    }
}

/// How the local solver is started.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Initialisation {
    /// Maximum-weight spanning tree, rotations propagated from node 0 (`[M4]`).
    SpanningTree,
    /// Bottom-3 eigenvectors of the connection Laplacian, rounded to SO(3) (`[M5]`).
    #[default]
    Spectral,
    /// A given estimate (one rotation per node).
    Given(#[serde(with = "crate::serde_rot::rotations")] Vec<Rotation>),
}

/// Settings of [`solve_multiple`]. Build with struct update syntax:
/// `MultipleSettings { loss: Loss::Geodesic, ..Default::default() }`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MultipleSettings {
    /// The loss (default chordal L2).
    pub loss: Loss,
    /// The initialisation (default spectral).
    pub init: Initialisation,
    /// Maximum number of outer iterations (default 100 for the second-order methods; the IRLS
    /// methods use `10 * max_iterations`).
    pub max_iterations: usize,
    /// Stop when the **relative gradient norm** `||grad f(R)||_2 / sum_e w_e` is at most this
    /// (default `1e-8`). `grad f` is the Riemannian gradient of the chosen cost in the
    /// right-perturbation chart `R_i exp(hat w_i)` (`[M3]`), all nodes stacked; `sum_e w_e` is
    /// the scale of the largest possible gradient (each edge contributes at most
    /// `4 sqrt(2) w_e`, `[M3]`), which makes the test invariant to scaling all weights and
    /// independent of the start. For the non-smooth L1 loss the test is on the smoothed cost.
    pub gradient_tolerance: f64,
    /// Also stop (converged) when every node moves by less than this angle in one step, radians
    /// (default `1e-12`).
    pub step_tolerance: f64,
    /// L1 smoothing: IRLS weights `1 / max(theta_e, l1_epsilon)`, radians (default `1e-6`).
    pub l1_epsilon: f64,
}

impl Default for MultipleSettings {
    fn default() -> Self {
        MultipleSettings {
            loss: Loss::Chordal,
            init: Initialisation::Spectral,
            max_iterations: 100,
            gradient_tolerance: 1e-8,
            step_tolerance: 1e-12,
            l1_epsilon: 1e-6,
        }
    }
}

impl MultipleSettings {
    /// Check every field; [`Error::InvalidSettings`] names the first bad one.
    ///
    /// ```
    /// use rotavg::multiple::{Loss, MultipleSettings};
    /// assert!(MultipleSettings::default().validate().is_ok());
    /// let bad = MultipleSettings { loss: Loss::Huber { threshold_deg: -1.0 }, ..Default::default() };
    /// assert!(matches!(bad.validate(), Err(rotavg::Error::InvalidSettings { .. })));
    /// ```
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: String| {
            Err(Error::InvalidSettings {
                name: name.into(),
                reason,
            })
        };
        match self.loss {
            Loss::Huber { threshold_deg } | Loss::Cauchy { threshold_deg }
                if !(threshold_deg.is_finite() && threshold_deg > 0.0) =>
            {
                return bad(
                    "loss.threshold_deg",
                    format!("must be finite and > 0, got {threshold_deg}"),
                );
            }
            _ => {}
        }
        if self.max_iterations == 0 {
            return bad("max_iterations", "must be at least 1".into());
        }
        for (name, v) in [
            ("gradient_tolerance", self.gradient_tolerance),
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
        Ok(())
    }
}

/// The result of [`solve_multiple`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MultipleSolution {
    /// The estimate, gauge fixed so that `R_0 = I`.
    #[serde(with = "crate::serde_rot::rotations")]
    pub rotations: Vec<Rotation>,
    /// The cost under the chosen loss ([`Loss`], `[M7]`).
    pub cost: f64,
    /// The chordal L2 cost `sum w ||R_j - R_ij R_i||_F^2` of the estimate (`[M1]`).
    pub chordal_cost: f64,
    /// `||grad||_2` of the chosen cost at the estimate (absolute; the relative value used for
    /// stopping is this divided by the sum of weights, see
    /// [`MultipleSettings::gradient_tolerance`]).
    pub gradient_norm: f64,
    /// The chosen loss.
    pub loss: Loss,
    /// Iterations, why it stopped, wall time (including the initialisation).
    pub report: SolverReport,
    /// The cost of the initialisation under the chosen loss.
    pub init_cost: f64,
}

impl fmt::Display for MultipleSolution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} loss: cost {:.6e} (initial {:.6e}), chordal cost {:.6e}, gradient norm {:.3e}; {}",
            self.loss.name(),
            self.cost,
            self.init_cost,
            self.chordal_cost,
            self.gradient_norm,
            self.report
        )
    }
}

/// Solve multiple rotation averaging locally: initialise ([`Initialisation`]), then minimise the
/// chosen [`Loss`]. The graph must be connected ([`Error::Disconnected`] otherwise; solve
/// [`MultipleProblem::largest_component`] to go on). The output has `R_0 = I`.
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
    // direct sparse Cholesky or PCG, decided once from the graph ([M6])
    let direct = Some(crate::multiple::chordal::prefers_direct(problem)?);
    let init = match &settings.init {
        Initialisation::Spectral => crate::multiple::init::spectral_with(problem, direct)?,
        other => crate::multiple::init::initialise(problem, other)?,
    };
    let mut out = match settings.loss {
        Loss::Chordal => crate::multiple::chordal::solve_chordal(problem, init, settings, direct)?,
        Loss::Geodesic => {
            crate::multiple::geodesic::solve_geodesic(problem, init, settings, direct)?
        }
        _ => crate::multiple::robust::solve_robust(problem, init, settings, direct)?,
    };
    fix_gauge(&mut out.rotations);
    // R_0 R_0^T is I up to rounding; make it exact.
    if let Some(r0) = out.rotations.first_mut() {
        *r0 = Rotation::identity();
    }
    out.chordal_cost = problem.chordal_cost(&out.rotations);
    out.report.seconds = start.elapsed().as_secs_f64();
    Ok(out)
}
