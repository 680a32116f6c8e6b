//! A rig with outliers (`paper-notes/conjugate.md` `[H20]`): the Cauchy loss by iteratively
//! reweighted alternations, then the chordal L2 problem on the inlier edges (those whose residual
//! at the robust estimate is within the inlier threshold), solved from the robust estimate: the
//! problem the certificate is about, as for view graphs.

use super::problem::RigProblem;
use super::solve::{RigSettings, RigSolution, solve_rig, solve_rig_from};
use crate::deadline::remaining;
use crate::error::Result;
use crate::multiple::Edge;
use crate::so3::Rotation;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Alternation passes per reweighting of [`solve_rig_robust`].
pub const REWEIGHT_PASSES: usize = 5;

/// Settings of [`solve_rig_robust`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RigRobust {
    /// The Cauchy loss's scale `c`, degrees (default 5): an edge of residual angle `theta`
    /// weighs `w / (1 + (theta / c)^2)`.
    pub threshold_deg: f64,
    /// An edge is an inlier when its residual at the robust estimate is at most this, degrees
    /// (default 5).
    pub inlier_threshold_deg: f64,
    /// Reweighted alternations at most (default 50); they stop earlier when one changes the
    /// robust cost by less than `1e-9` of it.
    pub max_reweights: usize,
}

impl Default for RigRobust {
    fn default() -> Self {
        RigRobust {
            threshold_deg: 5.0,
            inlier_threshold_deg: 5.0,
            max_reweights: 50,
        }
    }
}

impl RigRobust {
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
    let (mut estimate, reweights) = if p.is_anisotropic() {
        let unit = p.scalar().with_edges(
            (p.edges().iter())
                .map(|e| Edge {
                    weight: 1.0,
                    ..e.clone()
                })
                .collect(),
        )?;
        let start = solve_rig(&unit, &within(settings))?;
        reweighted(&unit, start, robust, &within(settings))?
    } else {
        let start = match least_squares {
            Some(ls) => ls,
            None => solve_rig(p, &within(settings))?,
        };
        reweighted(p, start, robust, &within(settings))?
    };
    estimate.cost = p.cost(&estimate.frames, &estimate.sensors);
    let inliers: Vec<bool> = (p
        .objective_angles(&estimate.frames, &estimate.sensors)
        .iter())
    .map(|t| t.to_degrees() <= robust.inlier_threshold_deg)
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
        reweights,
        inliers,
        inlier_problem,
        inlier_solution,
    })
}

/// The Cauchy alternations of [`solve_rig_robust_from`] on `p`'s scalar weights from
/// `estimate`: each a few passes of [`solve_rig_from`] on the edges reweighted by
/// `w / (1 + (theta / c)^2)` at the previous estimate, until the robust cost changes by at most
/// `1e-9` of it. The estimate and the number of reweightings.
fn reweighted(
    p: &RigProblem,
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
        if (last - cost).abs() <= 1e-9 * cost.abs()
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
        estimate = solve_rig_from(&q, &estimate.frames, &estimate.sensors, &inner)?;
    }
    Ok((estimate, reweights))
}
