//! The one vocabulary of costs for all three problems: a [`Metric`] (how far apart two
//! rotations are) and a [`Loss`] (what is summed), together an [`Objective`]
//! (`paper-notes/conventions.md` `[C2]`; the losses: `paper-notes/multiple.md` `[M7]`).
//!
//! Every problem minimises `sum_k w_k rho(d_k)` where `d_k` is the metric distance of the
//! k-th residual (single: `d(R_k, R)`; multiple: `d(R_ij R_i, R_j)`; conjugate:
//! `d(R_k, S^T L_k S)`) and `rho` is the loss:
//!
//! | loss | `rho(d)` |
//! |---|---|
//! | `L2` | `d^2` |
//! | `L1` | `d` |
//! | `Huber { threshold_deg }` | `d^2` for `d <= c`, `2 c d - c^2` beyond |
//! | `Cauchy { scale_deg }` | `c^2 ln(1 + d^2 / c^2)` |
//!
//! Thresholds are **residual angles in degrees** whatever the metric: `c` is the distance of a
//! rotation by that angle under the metric (`c = metric.from_angle(threshold_deg.to_radians())`),
//! so `Huber { threshold_deg: 5.0 }` down-weights residuals beyond 5 degrees under every
//! metric. Huber and Cauchy agree with `L2` to second order at `d = 0` (`rho(d) = d^2 + O(d^4)`).
//!
//! ```
//! use rotavg::objective::{Loss, Objective};
//! use rotavg::Metric;
//! let huber = Objective::new(Metric::Geodesic, Loss::Huber { threshold_deg: 10.0 });
//! let c = 10f64.to_radians();
//! assert_eq!(huber.rho(0.5 * c), 0.25 * c * c); // quadratic inside
//! assert!((huber.rho(2.0 * c) - 3.0 * c * c).abs() < 1e-15); // 2 c d - c^2 beyond
//! assert_eq!(Objective::default(), Objective::CHORDAL_L2);
//! assert_eq!(huber.to_string(), "geodesic huber (10 deg)");
//! ```

use crate::error::{Error, Result};
use crate::so3::Metric;
use serde::{Deserialize, Serialize};
use std::fmt;

/// What is summed over the residual distances `d_k` (see the module docs for `rho`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Loss {
    /// `rho(d) = d^2`: least squares.
    #[default]
    L2,
    /// `rho(d) = d`: the median-like, outlier-robust loss.
    L1,
    /// Huber: quadratic up to the residual angle `threshold_deg`, linear beyond.
    Huber {
        /// Threshold as a residual angle in degrees (> 0).
        threshold_deg: f64,
    },
    /// Cauchy (Lorentzian): `c^2 ln(1 + d^2 / c^2)` with `c` the distance of the angle
    /// `scale_deg`.
    Cauchy {
        /// Scale as a residual angle in degrees (> 0).
        scale_deg: f64,
    },
}

impl Loss {
    /// Short name: `l2`, `l1`, `huber`, `cauchy`.
    pub fn name(&self) -> &'static str {
        match self {
            Loss::L2 => "l2",
            Loss::L1 => "l1",
            Loss::Huber { .. } => "huber",
            Loss::Cauchy { .. } => "cauchy",
        }
    }

    /// The threshold or scale angle in degrees, for the robust losses.
    pub fn threshold_deg(&self) -> Option<f64> {
        match *self {
            Loss::Huber { threshold_deg } => Some(threshold_deg),
            Loss::Cauchy { scale_deg } => Some(scale_deg),
            Loss::L2 | Loss::L1 => None,
        }
    }

    /// Checks the threshold: [`Error::InvalidSettings`] names `loss.threshold_deg` or
    /// `loss.scale_deg` when it is not finite and in `(0, 180]`.
    ///
    /// ```
    /// use rotavg::objective::Loss;
    /// assert!(Loss::Huber { threshold_deg: 5.0 }.validate().is_ok());
    /// let e = Loss::Cauchy { scale_deg: -1.0 }.validate().unwrap_err();
    /// assert!(e.to_string().contains("loss.scale_deg"));
    /// ```
    pub fn validate(&self) -> Result<()> {
        let (name, v) = match *self {
            Loss::Huber { threshold_deg } => ("loss.threshold_deg", threshold_deg),
            Loss::Cauchy { scale_deg } => ("loss.scale_deg", scale_deg),
            Loss::L2 | Loss::L1 => return Ok(()),
        };
        if v.is_finite() && v > 0.0 && v <= 180.0 {
            Ok(())
        } else {
            Err(Error::InvalidSettings {
                name: name.into(),
                reason: format!("must be a finite angle in (0, 180] degrees, got {v}"),
            })
        }
    }
}

impl fmt::Display for Loss {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.threshold_deg() {
            Some(t) => write!(f, "{} ({t} deg)", self.name()),
            None => f.write_str(self.name()),
        }
    }
}

/// A cost: the metric of the residuals and the loss summed over them (module docs).
/// Every problem type carries one; the default is chordal L2, the certifiable cost of all
/// three problems.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Objective {
    /// The distance of each residual.
    pub metric: Metric,
    /// The loss applied to each distance.
    pub loss: Loss,
}

impl Objective {
    /// Chordal L2: `sum w ||.||_F^2`, the cost of the SDP relaxations.
    pub const CHORDAL_L2: Objective = Objective {
        metric: Metric::Chordal,
        loss: Loss::L2,
    };

    /// `Objective { metric, loss }`.
    pub const fn new(metric: Metric, loss: Loss) -> Self {
        Objective { metric, loss }
    }

    /// `true` for chordal L2.
    pub fn is_chordal_l2(&self) -> bool {
        self.metric == Metric::Chordal && self.loss == Loss::L2
    }

    /// The robust threshold or scale `c` in the metric's unit (distance of a rotation by the
    /// threshold angle), for Huber and Cauchy.
    pub fn threshold(&self) -> Option<f64> {
        self.loss
            .threshold_deg()
            .map(|deg| self.metric.from_angle(deg.to_radians()))
    }

    /// `rho(d)` for a residual distance `d` in the metric's unit.
    pub fn rho(&self, d: f64) -> f64 {
        match self.loss {
            Loss::L2 => d * d,
            Loss::L1 => d,
            Loss::Huber { .. } => {
                let c = self.threshold().unwrap_or(f64::INFINITY);
                if d <= c { d * d } else { 2.0 * c * d - c * c }
            }
            Loss::Cauchy { .. } => {
                let c = self.threshold().unwrap_or(f64::INFINITY);
                c * c * (d * d / (c * c)).ln_1p()
            }
        }
    }

    /// `rho(d(theta))` for a residual angle `theta` in radians.
    pub fn term(&self, theta: f64) -> f64 {
        self.rho(self.metric.from_angle(theta))
    }

    /// The iteratively-reweighted-least-squares factor `psi(d) = rho'(d) / (2 d)`, so that
    /// `rho(d) ~ psi d^2` locally (1 for L2); `eps` guards the L1 singularity at `d = 0`.
    pub fn irls_weight(&self, d: f64, eps: f64) -> f64 {
        match self.loss {
            Loss::L2 => 1.0,
            Loss::L1 => 0.5 / d.max(eps),
            Loss::Huber { .. } => {
                let c = self.threshold().unwrap_or(f64::INFINITY);
                if d <= c { 1.0 } else { c / d }
            }
            Loss::Cauchy { .. } => {
                let c = self.threshold().unwrap_or(f64::INFINITY);
                1.0 / (1.0 + d * d / (c * c))
            }
        }
    }

    /// Checks the loss's threshold ([`Loss::validate`]).
    pub fn validate(&self) -> Result<()> {
        self.loss.validate()
    }

    /// [`Error::InvalidSettings`] (field `objective`) saying that `problem` has no solver for
    /// this objective.
    pub(crate) fn unsupported(&self, problem: &str, supported: &str) -> Error {
        Error::InvalidSettings {
            name: "objective".into(),
            reason: format!(
                "{problem} averaging has no solver for the {self} cost (supported: {supported})"
            ),
        }
    }
}

impl fmt::Display for Objective {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} {}", self.metric, self.loss)
    }
}
