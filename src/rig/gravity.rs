//! Gravity priors on a rig whose every sensor is held (`paper-notes/gravity.md` `[G14]`), and
//! soft priors on a rig with sensors to estimate (`[G15]`: they enter the sensor step).
//!
//! Image `a` of sensor `s` at frame `f` has `X_a = S_s F_f`, so its prior `X_a d = g_a` (`d`
//! the world's down direction) is the frame's prior `F_f d = u_a` with `u_a = S_s^T g_a`. A
//! frame with several priors:
//!
//! - **soft** (weights `w_a`): `sum_a 2 w_a ||F d - u_a||^2 = 2 |v| ||F d - v/|v| ||^2 +
//!   4 (sum_a w_a - |v|)` with `v = sum_a w_a u_a` (both sides are affine in `F d` on the unit
//!   sphere): one prior of direction `v/|v|` and weight `|v|`, plus a constant;
//! - **held**: the constraints of one frame agree only on noise-free data; the frame holds the
//!   least-squares direction `v/|v|` (the unit vector nearest to all of them) and the largest
//!   angle between it and a `u_a` is reported.
//!
//! So the rig with held sensors and priors is the gravity problem of the frames' view graph
//! ([`crate::multiple::gravity::GravityProblem`]) plus a constant, and its solvers and
//! certificates are that problem's.

use super::problem::RigProblem;
use crate::error::{Error, Result};
use crate::multiple::gravity::{GravityPriors, GravityProblem};
use crate::so3::Rotation;
use nalgebra::Vector3;

/// The frames' gravity problem of a rig at its held sensors (`[G14]`), with what the reduction
/// adds and charges.
#[derive(Debug, Clone)]
pub struct FrameGravity {
    /// The frames' view graph with one prior per frame that has any.
    pub problem: GravityProblem,
    /// `J(F, S) + P(F, S) - J'(F)` for every `F` (exact arithmetic): the edges within frames
    /// and the soft priors' combination constant.
    pub constant: f64,
    /// Frames with more than one prior (combined into one).
    pub combined: usize,
    /// The largest angle between a frame's combined direction and one of its images' priors
    /// brought to the frame (`S^T g`), degrees: 0 on noise-free data, large for a wrong
    /// `sensor_from_rig` or axis convention.
    pub max_disagreement_deg: f64,
    /// A bound on `|P(F, S) - P'(F) - c|` over every `F` from the rounding of the combined
    /// priors (soft; `[G14]`, rounding), to be charged to a lower bound.
    pub soft_charge: f64,
    /// A bound on the angle between a held frame direction as computed and as exact, radians
    /// (held priors; `[G14]`, rounding).
    pub held_angle: f64,
}

impl RigProblem {
    /// The same rig with gravity priors on its images (`priors` has one entry per image, in
    /// [`Self::images`] order; held, or soft with [`GravityPriors::with_weight`]), solved and
    /// certified as the frames' gravity problem (`[G14]`); with soft priors the sensors to
    /// estimate are estimated with them (`[G15]`). Errors: a count that differs from the
    /// images', held priors on a rig with a sensor whose `sensor_from_rig` is estimated (held
    /// gravity on a rig needs every sensor known), held priors of one frame that cancel (no
    /// direction to hold).
    ///
    /// ```
    /// use rotavg::multiple::gravity::GravityPriors;
    /// use rotavg::rig::{RigScene, solve_rig};
    /// let (p, truth) = RigScene { frames: 30, sensors: 3, noise_sigma: 0.02, known: true, ..Default::default() }.generate();
    /// let down = nalgebra::Vector3::z();
    /// let priors = p.images().iter().map(|im| {
    ///     Some((truth.sensors[im.sensor] * truth.frames[im.frame] * down).into())
    /// }).collect();
    /// let p = p.with_gravity(GravityPriors::new(priors)?)?;
    /// let s = solve_rig(&p, &Default::default())?;
    /// let tilt = (s.sensors[1] * s.frames[4] * down - truth.sensors[1] * truth.frames[4] * down).norm();
    /// assert!(tilt < 1e-9); // the priors are held
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn with_gravity(mut self, priors: GravityPriors) -> Result<Self> {
        let invalid = |reason: String| Error::InvalidSettings {
            name: "gravity".into(),
            reason,
        };
        if priors.len() != self.images().len() {
            return Err(invalid(format!(
                "{} gravity entries for a rig of {} images (one per image)",
                priors.len(),
                self.images().len()
            )));
        }
        if !self.all_held() && priors.weight().is_none() {
            let unknown = self.held().iter().filter(|h| h.is_none()).count();
            return Err(invalid(format!(
                "held gravity priors on a rig need every sensor's sensor_from_rig known; \
                 {unknown} sensors are to be estimated (calibrate the rig without the priors, \
                 then hold its sensors: RigProblem::with_sensors_held; `rotavg rig FILE \
                 --gravity` and average_rig_calibrated_with_gravity do both; soft priors, \
                 GravityPriors::with_weight, refine estimated sensors, [G15])"
            )));
        }
        // the frames' problem at any sensors (the unknown ones at the identity) checks the rest
        let sensors: Vec<Rotation> = (self.held().iter())
            .map(|h| h.unwrap_or_else(Rotation::identity))
            .collect();
        self.gravity = Some(priors);
        self.frame_gravity(&sensors)?;
        Ok(self)
    }

    /// The gravity priors (`None`: the rig has none).
    pub fn gravity(&self) -> Option<&GravityPriors> {
        self.gravity.as_ref()
    }

    /// The soft priors' cost `sum_a 2 w_a ||S_{s_a} F_{f_a} d - g_a||^2` at `(frames, sensors)`;
    /// 0 without priors or with held ones.
    pub fn prior_cost(&self, frames: &[Rotation], sensors: &[Rotation]) -> f64 {
        let Some(priors) = &self.gravity else {
            return 0.0;
        };
        let down = priors.world_down();
        (self.images().iter().enumerate())
            .filter_map(|(a, im)| {
                let (g, w) = (priors.direction(a)?, priors.prior_weight(a)?);
                let x = sensors[im.sensor] * frames[im.frame];
                Some(2.0 * w * (x * down - g).norm_squared())
            })
            .sum()
    }

    /// The frames' gravity problem at the sensors `sensors` (the held ones) and its constant
    /// (`[G14]`); `None` without priors. Errors: held priors of one frame that cancel, no
    /// edge between two frames.
    pub fn frame_gravity(&self, sensors: &[Rotation]) -> Result<Option<FrameGravity>> {
        let Some(priors) = &self.gravity else {
            return Ok(None);
        };
        let (graph, within) = self.frame_graph(sensors)?;
        let sums = frame_sums(self, priors, sensors);
        let weight = priors.weight();
        let (mut directions, mut scales) = (Vec::new(), Vec::new());
        let (mut out_constant, mut combined, mut worst) = (within, 0, 0.0f64);
        let (mut soft_charge, mut held_angle) = (0.0, 0.0f64);
        let u = f64::EPSILON / 2.0;
        for (f, s) in sums.iter().enumerate() {
            combined += usize::from(s.count > 1);
            // |v - v_computed| <= drift (each `S^T g` a 3-term product, the sum of `count`)
            let drift = 4.0 * (s.count as f64 + 4.0) * u * s.total;
            let norm = s.v.norm();
            if s.count == 0 || (weight.is_some() && norm <= 1e-12 * s.total) {
                directions.push(None);
                scales.push(None);
                // the dropped term `-4 w F d . v` is at most `4 w |v|`
                out_constant += weight.map_or(0.0, |w| 4.0 * w * s.total);
                soft_charge += weight.map_or(0.0, |w| 4.0 * w * (norm + 4.0 * drift));
                continue;
            }
            if norm <= 1e-12 * s.total || drift >= 0.5 * norm {
                return Err(Error::Degenerate {
                    reason: format!(
                        "the held gravity priors of frame {f}'s images cancel (opposite \
                         directions once brought to the frame by their sensor_from_rig): no \
                         direction to hold"
                    ),
                });
            }
            let dir = s.v / norm;
            worst = worst.max(s.spread(&dir));
            directions.push(Some(dir.into()));
            scales.push(Some(norm));
            match weight {
                Some(w) => {
                    out_constant += 4.0 * w * (s.total - norm);
                    soft_charge += 16.0 * w * drift;
                }
                None => held_angle = held_angle.max(4.0 * drift / norm),
            }
        }
        let mut frame_priors =
            GravityPriors::new(directions)?.with_world_down(priors.world_down().into())?;
        if let Some(w) = weight {
            frame_priors = frame_priors.with_scales(scales)?.with_weight(w)?;
        }
        Ok(Some(FrameGravity {
            problem: GravityProblem::new(graph, frame_priors)?,
            constant: out_constant,
            combined,
            max_disagreement_deg: worst.to_degrees(),
            soft_charge,
            held_angle,
        }))
    }
}

/// One frame's priors brought to it: `v = sum_a s_a S^T g_a` (relative weights `s_a`; 1 for
/// held priors), `total = sum_a s_a`, their count and the directions themselves.
struct FrameSum {
    v: Vector3<f64>,
    total: f64,
    count: usize,
    directions: Vec<Vector3<f64>>,
}

impl FrameSum {
    /// The largest angle between `dir` and a direction of the frame, radians.
    fn spread(&self, dir: &Vector3<f64>) -> f64 {
        self.directions
            .iter()
            // accurate near 0 (acos of the dot product is not)
            .map(|u| 2.0 * (u - dir).norm().atan2((u + dir).norm()))
            .fold(0.0, f64::max)
    }
}

/// Every frame's [`FrameSum`].
fn frame_sums(p: &RigProblem, priors: &GravityPriors, sensors: &[Rotation]) -> Vec<FrameSum> {
    let mut sums: Vec<FrameSum> = (0..p.num_frames())
        .map(|_| FrameSum {
            v: Vector3::zeros(),
            total: 0.0,
            count: 0,
            directions: Vec::new(),
        })
        .collect();
    for (a, im) in p.images().iter().enumerate() {
        let Some(g) = priors.direction(a) else {
            continue;
        };
        let scale = priors.weight().map_or(1.0, |_| priors.scale(a));
        let u = sensors[im.sensor].inverse() * g;
        let s = &mut sums[im.frame];
        s.v += scale * u;
        s.total += scale;
        s.count += 1;
        s.directions.push(u);
    }
    sums
}
