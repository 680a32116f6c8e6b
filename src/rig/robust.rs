//! A rig with outliers (`paper-notes/conjugate.md` `[H20]`): the Cauchy loss by iteratively
//! reweighted alternations, then the chordal L2 problem on the inlier edges (those whose residual
//! at the robust estimate is within the inlier threshold), solved from the robust estimate: the
//! problem the certificate is about, as for view graphs.

use super::joint::{JOINT_DIRECT_VALUES, Joint};
use super::problem::RigProblem;
use super::solve::{RigSettings, RigSolution, solve_rig, solve_rig_from, solve_rig_from_joint};
use crate::deadline::remaining;
use crate::error::Result;
use crate::multiple::Edge;
use crate::multiple::robust_scale::{DEFAULT_THRESHOLD_DEG, DataScale, ScaleAngles, ScaleRule};
use crate::so3::Rotation;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Joint Gauss-Newton steps (or alternation passes where those do not apply) per reweighting
/// of [`solve_rig_robust`]: the steps converge quadratically and the weights change after them
/// anyway. 2 instead of 5 since 2026-12-07: a 10^4-frame rig of 6 sensors with 10 % outliers
/// solved in 11.3-11.6 s instead of 13.5 s (the same 9 reweightings, the same inliers and cost
/// to 15 digits), and the same estimates on the rigs of `examples/rig_robust_scale`.
pub const REWEIGHT_PASSES: usize = 2;

/// The reweightings stop when one changes the robust (Cauchy) cost by at most this fraction
/// of it. The robust estimate only chooses the inliers (the inlier problem is then solved to
/// convergence and certified). `1e-6` since 2026-12-07 (`1e-9` before): on a 10^4-frame,
/// 6-sensor rig with 10 % outliers 7 reweightings instead of 9 (the last two changed the cost
/// by 1e-7 and 3e-9 of it), the same 164,519 inliers and the inlier estimate's cost to 14
/// digits; on the 39 rows of `examples/rig_robust_scale -- 300 4 3` the same estimates under
/// the default scale, and within 2 % under a given one.
pub const REWEIGHT_TOLERANCE: f64 = 1e-6;

/// Reweightings of the first stage of the scale from the data at most ([`rig_data_scale`]).
pub const FIRST_STAGE_REWEIGHTS: usize = 3;

/// Settings of [`solve_rig_robust`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RigRobust {
    /// The Cauchy loss's scale `c`, degrees (5 unless set), used with [`ScaleRule::Given`]: an
    /// edge of residual angle `theta` weighs `w / (1 + (theta / c)^2)`.
    pub threshold_deg: f64,
    /// An edge is an inlier when its residual at the robust estimate (its Mahalanobis angle
    /// with information) is at most this, degrees (5 unless set), with [`ScaleRule::Given`].
    pub inlier_threshold_deg: f64,
    /// Reweighted alternations at most (default 50); they stop earlier when one changes the
    /// robust cost by at most [`REWEIGHT_TOLERANCE`] of it.
    pub max_reweights: usize,
    /// Where the two thresholds come from: [`ScaleRule::FromData`] (the default) finds both
    /// from the data ([`rig_data_scale`], `paper-notes/conjugate.md` `[H20]` "The scale", the
    /// rule `[D20]` of view graphs) and ignores the two fields above; [`ScaleRule::Given`] uses
    /// them as given (the command line's `--loss-threshold`, and `--loss cauchy`, whose scale
    /// is 5 degrees unless given).
    pub scale: ScaleRule,
}

impl Default for RigRobust {
    fn default() -> Self {
        RigRobust {
            threshold_deg: DEFAULT_THRESHOLD_DEG,
            inlier_threshold_deg: DEFAULT_THRESHOLD_DEG,
            max_reweights: 50,
            scale: ScaleRule::FromData,
        }
    }
}

impl RigRobust {
    /// The thresholds of `scale` ([`DataScale::scale_deg`] and
    /// [`DataScale::inlier_threshold_deg`]) with the rule [`ScaleRule::Given`].
    pub fn with_data_scale(self, scale: &DataScale) -> RigRobust {
        RigRobust {
            threshold_deg: scale.scale_deg,
            inlier_threshold_deg: scale.inlier_threshold_deg,
            scale: ScaleRule::Given,
            ..self
        }
    }

    /// Errors: a threshold that is not a positive number of degrees.
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("threshold_deg", self.threshold_deg),
            ("inlier_threshold_deg", self.inlier_threshold_deg),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(crate::Error::InvalidSettings {
                    name: name.into(),
                    reason: format!("must be a positive number of degrees, got {v}"),
                });
            }
        }
        Ok(())
    }
}

/// A robust rig estimate and its inlier problem.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobustRig {
    /// The Cauchy estimate on every edge (its `cost` the chordal cost `J` on every edge).
    pub robust: RigSolution,
    /// Reweighted alternations run.
    pub reweights: usize,
    /// Which edges are inliers at the robust estimate, in edge order.
    pub inliers: Vec<bool>,
    /// The rig with the inlier edges only (original weights).
    pub inlier_problem: RigProblem,
    /// Its chordal L2 estimate, solved from the robust one: what is certified.
    pub inlier_solution: RigSolution,
    /// The settings the Cauchy loss and the inliers ran with: those given, or with
    /// [`ScaleRule::FromData`] the thresholds found ([`RigRobust::with_data_scale`]).
    pub applied: RigRobust,
    /// With [`ScaleRule::FromData`], the scale and inlier threshold found ([`rig_data_scale`]).
    pub scale: Option<DataScale>,
}

/// The Cauchy scale and inlier threshold of `p` from its data (`[H20]` "The scale"): the
/// Cauchy alternations of [`solve_rig_robust`] at 5 degrees from least squares (on unit
/// weights with information), [`FIRST_STAGE_REWEIGHTS`] reweightings at most, then `[D20]`'s rule of view graphs on the edges' angles at their
/// estimate: 1.5 times the median residual angle, the inlier threshold 3 times the median of
/// the angle it is compared with (the Mahalanobis angle with information), within 0.01-10
/// degrees. The median is an inlier's while fewer than half the edges are wrong. Scaling every
/// weight changes neither. Its solves share `settings`' clock. Errors: those of [`solve_rig`].
///
/// ```
/// use rotavg::rig::{RigScene, RigSettings, rig_data_scale};
/// let (p, _) = RigScene { frames: 60, sensors: 3, noise_sigma: 0.01, outlier_fraction: 0.1, ..Default::default() }.generate();
/// let s = rig_data_scale(&p, &RigSettings::default())?;
/// // 0.01 rad per axis: inlier angles 0.88 deg at the median, the scale about 1.3 deg
/// assert!((1.0..1.6).contains(&s.scale_deg), "{}", s.scale_deg);
/// assert!((2.0..3.2).contains(&s.inlier_threshold_deg), "{}", s.inlier_threshold_deg);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn rig_data_scale(p: &RigProblem, settings: &RigSettings) -> Result<DataScale> {
    let clock = Instant::now();
    let unit = unit_weights(p)?;
    let q = unit.as_ref().unwrap_or(p);
    let start = solve_rig(q, settings)?;
    let within = RigSettings {
        max_seconds: remaining(settings.max_seconds, clock),
        ..*settings
    };
    let shape = Joint::new(q, &start.sensors, JOINT_DIRECT_VALUES)?;
    let posed = (p, q, shape.as_ref());
    let (_, _, scale) = first_stage(posed, start, &RigRobust::default(), &within)?;
    Ok(scale)
}

/// `p` with unit weights and no information when it has information (where its Cauchy
/// alternations run, `[H24]`), else `None` (`p` itself).
fn unit_weights(p: &RigProblem) -> Result<Option<RigProblem>> {
    if !p.is_anisotropic() {
        return Ok(None);
    }
    let edges = (p.edges().iter())
        .map(|e| Edge {
            weight: 1.0,
            ..e.clone()
        })
        .collect();
    Ok(Some(p.scalar().with_edges(edges)?))
}

/// The first stage of the scale from the data: the Cauchy alternations on `q` (`p`, or its
/// unit weights) at [`DEFAULT_THRESHOLD_DEG`] from `start`, and the scale read at their
/// estimate. The estimate, its reweightings and the scale.
fn first_stage(
    (p, q, shape): (&RigProblem, &RigProblem, Option<&Joint<'_>>),
    start: RigSolution,
    robust: &RigRobust,
    settings: &RigSettings,
) -> Result<(RigSolution, usize, DataScale)> {
    let clock = Instant::now();
    let given = RigRobust {
        threshold_deg: DEFAULT_THRESHOLD_DEG,
        scale: ScaleRule::Given,
        max_reweights: robust.max_reweights.min(FIRST_STAGE_REWEIGHTS),
        ..*robust
    };
    let (estimate, reweights) = reweighted((q, shape), start, &given, settings)?;
    let at = ScaleAngles {
        residual: residual_angles(q, &estimate.frames, &estimate.sensors),
        mahalanobis: (p.is_anisotropic())
            .then(|| p.objective_angles(&estimate.frames, &estimate.sensors)),
        iterations: reweights,
        seconds: clock.elapsed().as_secs_f64(),
    };
    Ok((estimate, reweights, DataScale::from_angles(&at)))
}

/// Each edge's residual angle `theta_e` (radians) at `(frames, sensors)`, from its chordal
/// residual `||X_b - R X_a||_F^2 = 8 sin^2(theta / 2)`.
pub fn residual_angles(p: &RigProblem, frames: &[Rotation], sensors: &[Rotation]) -> Vec<f64> {
    let x = p.image_rotations(frames, sensors);
    p.edges()
        .iter()
        .map(|e| {
            let c = (x[e.j].matrix() - e.rotation.matrix() * x[e.i].matrix()).norm_squared();
            2.0 * (c / 8.0).sqrt().min(1.0).asin()
        })
        .collect()
}

/// The Cauchy rig estimate by reweighted alternations from the least-squares one (each a
/// [`solve_rig_from`] on the edges reweighted by `w / (1 + (theta / c)^2)` at the previous
/// estimate), then the inlier problem solved from it. Errors: those of [`solve_rig`]; an inlier
/// problem that is no rig (a sensor no inlier edge places, frames the inliers do not join).
///
/// ```
/// use rotavg::rig::{RigRobust, RigScene, RigSettings, solve_rig, solve_rig_robust};
/// let scene = RigScene { frames: 60, sensors: 3, noise_sigma: 0.01, outlier_fraction: 0.15, ..Default::default() };
/// let (p, truth) = scene.generate();
/// let robust = solve_rig_robust(&p, &RigRobust::default(), &RigSettings::default())?;
/// let err = |s: &[rotavg::Rotation]| rotavg::so3::angle_between(&s[1], &truth.sensors[1]);
/// let ls = solve_rig(&p, &RigSettings::default())?;
/// assert!(err(&robust.inlier_solution.sensors) < 0.2 * err(&ls.sensors));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn solve_rig_robust(
    p: &RigProblem,
    robust: &RigRobust,
    settings: &RigSettings,
) -> Result<RobustRig> {
    solve_rig_robust_given(p, None, robust, settings)
}

/// [`solve_rig_robust`] from its least-squares estimate `least_squares` (a [`solve_rig`] of
/// `p`, already computed). With information (`[H24]`, as `[A14]` for view graphs) the Cauchy
/// alternations run on the rig with unit weights and no information, from its own least
/// squares, the inliers are the edges whose Mahalanobis angle is within the threshold, and the
/// inlier problem keeps its information.
pub fn solve_rig_robust_from(
    p: &RigProblem,
    least_squares: RigSolution,
    robust: &RigRobust,
    settings: &RigSettings,
) -> Result<RobustRig> {
    solve_rig_robust_given(p, Some(least_squares), robust, settings)
}

/// [`solve_rig_robust_from`] with `p`'s least squares solved here when not given; with
/// information it is not used (the alternations start from the unit-weight rig's own least
/// squares), so [`solve_rig_robust`] does not compute it.
pub(crate) fn solve_rig_robust_given(
    p: &RigProblem,
    least_squares: Option<RigSolution>,
    robust: &RigRobust,
    settings: &RigSettings,
) -> Result<RobustRig> {
    robust.validate()?;
    let clock = Instant::now();
    let within = |s: &RigSettings| RigSettings {
        max_seconds: remaining(settings.max_seconds, clock),
        ..*s
    };
    let unit = unit_weights(p)?;
    let q = unit.as_ref().unwrap_or(p);
    let start = match least_squares {
        Some(ls) if unit.is_none() => ls,
        _ => solve_rig(q, &within(settings))?,
    };
    // the joint steps' shape, made once: every reweighting of both stages is `q` with other
    // weights
    let shape = Joint::new(q, &start.sensors, JOINT_DIRECT_VALUES)?;
    let (start, first_reweights, scale) = match robust.scale {
        ScaleRule::Given => (start, 0, None),
        ScaleRule::FromData => {
            let posed = (p, q, shape.as_ref());
            let (first, n, scale) = first_stage(posed, start, robust, &within(settings))?;
            (first, n, Some(scale))
        }
    };
    let applied = (scale.as_ref()).map_or(*robust, |s| robust.with_data_scale(s));
    let (mut estimate, more) = reweighted((q, shape.as_ref()), start, &applied, &within(settings))?;
    estimate.cost = p.cost(&estimate.frames, &estimate.sensors);
    let inliers: Vec<bool> = (p
        .objective_angles(&estimate.frames, &estimate.sensors)
        .iter())
    .map(|t| t.to_degrees() <= applied.inlier_threshold_deg)
    .collect();
    let inlier_problem = p.edge_subset(&inliers)?;
    let inlier_solution = solve_rig_from(
        &inlier_problem,
        &estimate.frames,
        &estimate.sensors,
        &within(settings),
    )?;
    Ok(RobustRig {
        robust: estimate,
        reweights: first_reweights + more,
        inliers,
        inlier_problem,
        inlier_solution,
        applied,
        scale,
    })
}

/// The Cauchy alternations of [`solve_rig_robust_from`] on `p`'s scalar weights from
/// `estimate`: each a few passes of [`solve_rig_from`] on the edges reweighted by
/// `w / (1 + (theta / c)^2)` at the previous estimate, until the robust cost changes by at most
/// [`REWEIGHT_TOLERANCE`] of it, each by the joint steps of `shape` (`p`'s, where they apply:
/// `Joint::reweighted`). The estimate and the number of reweightings.
fn reweighted(
    (p, shape): (&RigProblem, Option<&Joint<'_>>),
    mut estimate: RigSolution,
    robust: &RigRobust,
    settings: &RigSettings,
) -> Result<(RigSolution, usize)> {
    let clock = Instant::now();
    let c = robust.threshold_deg.to_radians();
    let (mut reweights, mut last) = (0, f64::INFINITY);
    while reweights < robust.max_reweights {
        let theta = residual_angles(p, &estimate.frames, &estimate.sensors);
        let cost: f64 = p
            .edges()
            .iter()
            .zip(&theta)
            .map(|(e, t)| e.weight * c * c * (1.0 + (t / c).powi(2)).ln())
            .sum();
        if (last - cost).abs() <= REWEIGHT_TOLERANCE * cost.abs()
            || matches!(
                estimate.report.termination,
                crate::termination::Termination::TimeLimit { .. }
            )
        {
            break;
        }
        last = cost;
        reweights += 1;
        let edges = p
            .edges()
            .iter()
            .zip(&theta)
            .map(|(e, t)| Edge {
                weight: e.weight / (1.0 + (t / c).powi(2)),
                ..e.clone()
            })
            .collect();
        let q = p.with_edges(edges)?;
        // a few passes per reweighting: the weights change anyway (the inlier problem is
        // solved to convergence)
        let inner = RigSettings {
            max_passes: REWEIGHT_PASSES.min(settings.max_passes),
            max_seconds: remaining(settings.max_seconds, clock),
        };
        let joint = match shape {
            Some(shape) => shape.reweighted(&q)?,
            None => None,
        };
        let start = (&estimate.frames[..], &estimate.sensors[..]);
        estimate = solve_rig_from_joint(&q, start, &inner, joint)?;
    }
    Ok((estimate, reweights))
}
