//! The robust loss's scale from the data (`paper-notes/certificates.md` `[D20]`, issue 37): the
//! rule `auto` solves Cauchy with a scale that follows the noise of the measurements instead of
//! a fixed angle. The scale is [`SCALE_PER_MEDIAN`] times the median residual angle at the
//! robust solve's own L1 start (`[M9]`; of the view graph with its weights, or with unit weights
//! and no information where it has information, `[A14]`'s first stage), and the inlier
//! threshold (the certified inlier graph's) [`INLIER_PER_MEDIAN`] times it (times the median
//! Mahalanobis angle at that solution where the graph has information: the angle the threshold
//! cuts there, about 0.4 of the residual angle on generated COLMAP scenes): the L1 solution fits
//! the inliers and leaves the outliers' residuals large, so with fewer than half the edges wrong
//! the median is an inlier's. For Gaussian noise of `sigma` per axis the inliers' residual angle
//! is `sigma chi(3)`, median `1.538 sigma`; the scale `1.5 x median = 2.3 sigma` is about
//! Cauchy's classical tuning constant (`2.385 sigma`, 95 % efficiency at the normal), and the
//! threshold `3 x median = 4.6 sigma` leaves 0.01 % of such inliers outside the inlier graph.

use crate::error::Result;
use crate::multiple::problem::MultipleProblem;
use crate::multiple::solve::{MultipleSettings, solve_multiple};
use crate::objective::{Loss, Objective};
use crate::so3::{Metric, Rotation};
use serde::{Deserialize, Serialize};

/// How the rule `auto` ([`MultipleSettings::robust_on_outliers`]) scales its robust loss.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ScaleRule {
    /// The scale from the data ([`data_scale`]), the default.
    #[default]
    FromData,
    /// The Huber threshold or Cauchy scale of `robust_on_outliers` as given (the command line's
    /// `--loss-threshold`).
    Given,
}

impl ScaleRule {
    /// The threshold (degrees) and rule of a threshold a user may give (the command line's
    /// `--loss-threshold`, Python's `loss_threshold`): given, that threshold as given; not
    /// given, [`DEFAULT_THRESHOLD_DEG`] for the losses named explicitly and the scale from the
    /// data for the rule `auto`.
    ///
    /// ```
    /// use rotavg::multiple::robust_scale::ScaleRule;
    /// assert_eq!(ScaleRule::of(Some(2.0)), (2.0, ScaleRule::Given));
    /// assert_eq!(ScaleRule::of(None), (5.0, ScaleRule::FromData));
    /// ```
    pub fn of(given: Option<f64>) -> (f64, ScaleRule) {
        match given {
            Some(t) => (t, ScaleRule::Given),
            None => (DEFAULT_THRESHOLD_DEG, ScaleRule::FromData),
        }
    }
}

/// The Huber threshold and Cauchy scale of a loss named without one, degrees.
pub const DEFAULT_THRESHOLD_DEG: f64 = 5.0;

/// The scale is this many times the median residual angle at the L1 solution (`[D20]`: `2.3
/// sigma` for Gaussian noise of `sigma` per axis).
pub const SCALE_PER_MEDIAN: f64 = 1.5;

/// The inlier threshold, unless one is given, is this many times the median residual angle at
/// the L1 solution, or where the graph has information its median Mahalanobis angle
/// (`[D20]`: `4.6 sigma`, 0.01 % of Gaussian inliers beyond it).
pub const INLIER_PER_MEDIAN: f64 = 3.0;

/// The data's scale and inlier threshold are at least this many degrees (data that fit to
/// rounding: the loss's weights stay finite and exact inliers keep weight 1).
pub const MIN_DATA_SCALE_DEG: f64 = 0.01;

/// The data's scale and inlier threshold are at most this many degrees: pairs off by more are
/// outliers in SfM practice (COLMAP's global mapper marks them invalid), and a median residual
/// past 3 degrees is more likely one that outliers inflate than noise (1DSfM Madrid_Metropolis:
/// residual quantiles 2.8 / 9.3 / 32.6 degrees at 25 / 50 / 75 % at the L1 solution, so the
/// scale `1.5 m` would be 14 degrees and the inlier threshold `3 m` 28).
pub const MAX_DATA_SCALE_DEG: f64 = 10.0;

/// The scale [`data_scale`] found and how.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DataScale {
    /// The rule: `"from_data"`.
    pub rule: String,
    /// Median residual angle at the estimate it was read at, degrees: a view graph's L1
    /// solution (of unit weights where it has information; [`data_scale`]), or a rig's Cauchy
    /// estimate after a few reweightings at 5 degrees (`crate::rig::rig_data_scale`).
    pub median_deg: f64,
    /// The scale: [`SCALE_PER_MEDIAN`] x `median_deg`, within
    /// [`MIN_DATA_SCALE_DEG`]..[`MAX_DATA_SCALE_DEG`], rounded to three significant digits,
    /// degrees.
    pub scale_deg: f64,
    /// Where the graph has information: the median Mahalanobis angle (`[A14]`, the angle its
    /// inlier threshold is compared with) at the same estimate, degrees; `None` with scalar
    /// weights (and in records written before it existed).
    #[serde(default)]
    pub mahalanobis_median_deg: Option<f64>,
    /// The inlier threshold unless one is given: [`INLIER_PER_MEDIAN`] x the median of the angle
    /// it is compared with (`mahalanobis_median_deg` where the graph has information, else
    /// `median_deg`), within the same bounds, rounded the same way, degrees (0 in records
    /// written before it existed).
    #[serde(default)]
    pub inlier_threshold_deg: f64,
    /// Whether `SCALE_PER_MEDIAN x median_deg` was outside
    /// [`MIN_DATA_SCALE_DEG`]..[`MAX_DATA_SCALE_DEG`] and the scale is that bound.
    #[serde(default)]
    pub clamped: bool,
    /// IRLS iterations of that L1 solve (a rig's: its reweightings at 5 degrees).
    pub iterations: usize,
    /// Time of that solve, seconds.
    pub seconds: f64,
}

impl DataScale {
    /// `", at most 10 deg"` (or `", at least 0.01 deg"`) when the scale
    /// ([`SCALE_PER_MEDIAN`] x `median_deg`) was outside
    /// [`MIN_DATA_SCALE_DEG`]..[`MAX_DATA_SCALE_DEG`] and the bound was taken instead, else `""`.
    pub fn scale_bound_note(&self) -> String {
        bound_note(SCALE_PER_MEDIAN * self.median_deg)
    }

    /// The same note for the inlier threshold ([`INLIER_PER_MEDIAN`] x
    /// [`DataScale::threshold_median_deg`]).
    pub fn threshold_bound_note(&self) -> String {
        bound_note(INLIER_PER_MEDIAN * self.threshold_median_deg())
    }

    /// The scale in words: `"1.5 x the median residual 0.881 deg at {at}"`, and the bound
    /// taken when it was outside the range ([`DataScale::scale_bound_note`]).
    pub fn scale_words(&self, at: &str) -> String {
        format!(
            "{SCALE_PER_MEDIAN} x the median residual {:.3} deg at {at}{}",
            self.median_deg,
            self.scale_bound_note()
        )
    }

    /// The inlier threshold in words: `"3 x that median (2.64 deg)"`, or where the graph has
    /// information `"3 x the median Mahalanobis angle 0.4 deg there (1.2 deg)"`.
    pub fn threshold_words(&self) -> String {
        let of = match self.mahalanobis_median_deg {
            Some(m) => format!("the median Mahalanobis angle {m:.3} deg there"),
            None => "that median".into(),
        };
        format!(
            "{INLIER_PER_MEDIAN} x {of} ({} deg{})",
            self.inlier_threshold_deg,
            self.threshold_bound_note()
        )
    }

    /// The median the inlier threshold is a multiple of: `mahalanobis_median_deg` where the
    /// graph has information, else `median_deg`.
    pub fn threshold_median_deg(&self) -> f64 {
        self.mahalanobis_median_deg.unwrap_or(self.median_deg)
    }

    /// `objective` with this scale: the Huber threshold or Cauchy scale replaced; other losses
    /// unchanged.
    pub fn applied_to(&self, objective: Objective) -> Objective {
        let loss = match objective.loss {
            Loss::Huber { .. } => Loss::Huber {
                threshold_deg: self.scale_deg,
            },
            Loss::Cauchy { .. } => Loss::Cauchy {
                scale_deg: self.scale_deg,
            },
            other => other,
        };
        Objective { loss, ..objective }
    }
}

/// The scale of `graph`'s robust loss of `metric` from its data, and the L1 solution it was
/// read at: that of the robust solve's own L1 start (`[M9]`, stopped at
/// [`L1_START_DECREASE_TOLERANCE`](crate::multiple::solve::L1_START_DECREASE_TOLERANCE), smoothed at [`L1_START_EPSILON`](crate::multiple::solve::L1_START_EPSILON)) on the graph's edges with
/// their weights, or with unit weights and no information where the graph has information
/// (`[A14]`'s first stage); the median of its residual angles, times [`SCALE_PER_MEDIAN`], and
/// [`INLIER_PER_MEDIAN`] times the median of the angle the inlier threshold is compared with
/// (the Mahalanobis angle where the graph has information) for the inlier threshold.
/// Scaling every weight (or information matrix) by one factor changes neither. The solution
/// is the start [`Initialisation::L1Start`](crate::multiple::Initialisation::L1Start) hands to the robust solve. Errors: those of the
/// solve (a disconnected graph).
///
/// ```
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// use rotavg::multiple::{MultipleSettings, robust_scale::data_scale};
/// use rotavg::Metric;
/// let (p, _) = SyntheticGraph { num_rotations: 60, num_edges: 400, noise_sigma: 0.01, ..Default::default() }.generate();
/// let (s, _) = data_scale(&p, Metric::Geodesic, &MultipleSettings::default()).unwrap();
/// // 0.01 rad per axis: inlier angles 0.88 deg at the median, the scale about 1.3 deg
/// assert!((1.0..1.6).contains(&s.scale_deg), "{}", s.scale_deg);
/// assert!((2.0..3.2).contains(&s.inlier_threshold_deg), "{}", s.inlier_threshold_deg);
/// ```
pub fn data_scale(
    graph: &MultipleProblem,
    metric: Metric,
    settings: &MultipleSettings,
) -> Result<(DataScale, Vec<Rotation>)> {
    let (at, solution) = l1_angles(graph, metric, settings)?;
    Ok((DataScale::from_angles(&at), solution))
}

/// The angles a [`DataScale`] is read from: at the L1 solution of a view graph
/// ([`data_scale`]), or at a rig's first Cauchy estimate (`crate::rig::rig_data_scale`).
#[derive(Debug, Clone)]
pub(crate) struct ScaleAngles {
    /// Every edge's residual angle, radians.
    pub residual: Vec<f64>,
    /// Where the graph has information, every edge's Mahalanobis angle (`[A10]`), radians.
    pub mahalanobis: Option<Vec<f64>>,
    /// Iterations of the solve that found the estimate.
    pub iterations: usize,
    /// Its time, seconds.
    pub seconds: f64,
}

/// The L1 solve of [`data_scale`] on `graph`: its angles and solution.
fn l1_angles(
    graph: &MultipleProblem,
    metric: Metric,
    settings: &MultipleSettings,
) -> Result<(ScaleAngles, Vec<Rotation>)> {
    let base = match graph.is_anisotropic() {
        true => crate::multiple::two_stage::unit_weights(graph)?,
        false => graph.clone(),
    };
    let l1 = base.with_objective(Objective::new(metric, Loss::L1))?;
    let solution = solve_multiple(&l1, &settings.for_l1_start())?;
    let at = ScaleAngles {
        residual: l1.residual_angles(&solution.rotations),
        mahalanobis: (graph.is_anisotropic()).then(|| graph.objective_angles(&solution.rotations)),
        iterations: solution.report.iterations,
        seconds: solution.report.seconds,
    };
    Ok((at, solution.rotations))
}

impl DataScale {
    /// The scale and inlier threshold of the angles `at` (`[D20]`'s rule).
    pub(crate) fn from_angles(at: &ScaleAngles) -> DataScale {
        let median_deg = median_angle_deg(at.residual.clone());
        let mahalanobis_median_deg = at.mahalanobis.clone().map(median_angle_deg);
        let unclamped = SCALE_PER_MEDIAN * median_deg;
        let bounded = |x: f64| three_digits(x.clamp(MIN_DATA_SCALE_DEG, MAX_DATA_SCALE_DEG));
        DataScale {
            rule: "from_data".into(),
            median_deg,
            mahalanobis_median_deg,
            scale_deg: bounded(unclamped),
            inlier_threshold_deg: bounded(
                INLIER_PER_MEDIAN * mahalanobis_median_deg.unwrap_or(median_deg),
            ),
            clamped: !(MIN_DATA_SCALE_DEG..=MAX_DATA_SCALE_DEG).contains(&unclamped),
            iterations: at.iterations,
            seconds: at.seconds,
        }
    }
}

/// `", at most 10 deg"` or `", at least 0.01 deg"` when `x` is outside
/// [`MIN_DATA_SCALE_DEG`]..[`MAX_DATA_SCALE_DEG`], else `""`.
fn bound_note(x: f64) -> String {
    match (x > MAX_DATA_SCALE_DEG, x < MIN_DATA_SCALE_DEG) {
        (true, _) => format!(", at most {MAX_DATA_SCALE_DEG} deg"),
        (_, true) => format!(", at least {MIN_DATA_SCALE_DEG} deg"),
        _ => String::new(),
    }
}

/// The median of `angles` (radians; the upper one of an even count), degrees; 0 for none.
fn median_angle_deg(mut angles: Vec<f64>) -> f64 {
    angles.sort_by(f64::total_cmp);
    angles.get(angles.len() / 2).map_or(0.0, |a| a.to_degrees())
}

/// `x > 0` rounded to three significant digits (the scale as it is printed is the scale used).
fn three_digits(x: f64) -> f64 {
    // divided by an exact power of ten, the nearest double to the three-digit decimal
    let e = x.log10().floor() as i32 - 2;
    match e < 0 {
        true => (x * 10f64.powi(-e)).round() / 10f64.powi(-e),
        false => (x / 10f64.powi(e)).round() * 10f64.powi(e),
    }
}
