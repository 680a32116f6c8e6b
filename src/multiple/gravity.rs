//! Gravity priors (contract section 5, "Rigs and gravity"; `paper-notes/gravity.md`,
//! `[G1]`-`[G7]`): per image `i`, the unit vector `g_i`, the world's down direction expressed in
//! camera `i`'s frame, so that **`R_i g_world = g_i`** (`g_world = (0, 0, 1)` unless the priors
//! state another, [`GravityPriors::with_world_down`]). With a prior, `R_i` keeps one degree of
//! freedom: a turn about `g_world` (`R_i = F_i Rz(theta_i) W^T`, `[G1]`).
//!
//! - Data: [`GravityPriors`] (all images, or some: the mixed problem), and the problem
//!   [`GravityProblem`]: a view graph with its priors.
//! - Local solver: [`solve_gravity`] (the unconstrained chordal solve, aligned to the priors and
//!   projected onto them, then the chordal Newton-LM with the tilt of each image with a prior
//!   held, `[G4]`).
//! - Conventions: [`GravityProblem::check_conventions`] compares each edge's `R_ij g_i` with
//!   `g_j` (no estimate needed), and names a better-fitting axis convention when there is one.
//! - Certificate: [`crate::certify::certify_gravity`]; pipeline:
//!   [`crate::pipeline::average_with_gravity`].
//!
//! ```
//! use rotavg::multiple::gravity::{GravityProblem, solve_gravity};
//! use rotavg::multiple::synthetic::SyntheticGraph;
//! use rotavg::multiple::MultipleSettings;
//! let (graph, truth) = SyntheticGraph { num_rotations: 30, num_edges: 90, noise_sigma: 0.02, ..Default::default() }.generate();
//! // exact gravity: the world's down direction seen by each camera
//! let gravity = GravityProblem::from_truth(graph, &truth)?;
//! let sol = solve_gravity(&gravity, &MultipleSettings::default())?;
//! assert!(sol.report.termination.is_converged());
//! assert!(gravity.max_prior_violation_deg(&sol.rotations) < 1e-9);
//! # Ok::<(), rotavg::Error>(())
//! ```

mod soft;
mod two_stage;

pub use soft::{LIGHT_STRENGTH_FRACTION, SURROGATE_STIFFNESS, Stiffness};

use super::chordal::solve_chordal_tilt_fixed;
use super::init::initialise;
use super::problem::MultipleProblem;
use super::robust::{
    edge_residuals, inlier_threshold_deg, objective_cost_gradient, relative_weight,
};
use super::solve::{
    IRLS_DECREASE_WINDOW, Initialisation, MultipleSettings, MultipleSolution, solve_multiple,
};
use crate::error::{Error, Result};
use crate::objective::Loss;
use crate::so3::Rotation;
use crate::termination::{SolverReport, Termination};
use nalgebra::{Matrix3, Unit, Vector3};
use serde::{Deserialize, Serialize};

/// The smallest norm a gravity vector may have before it is normalised (a zero vector has no
/// direction).
pub const MIN_GRAVITY_NORM: f64 = 1e-9;

/// Per-image gravity directions: `directions[i]` is `g_i` (normalised), the world's down
/// direction in camera `i`'s frame, or `None` for an image without a prior. Invariant: at least
/// one prior, every direction a finite unit vector, `world_down` too.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawGravityPriors")]
pub struct GravityPriors {
    directions: Vec<Option<[f64; 3]>>,
    world_down: [f64; 3],
    /// `None`: hard constraints; `Some(w)`: soft terms `2 w ||R_i world_down - g_i||^2`
    /// ([`GravityPriors::with_weight`], `[G10]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    weight: Option<f64>,
    /// Per image, its prior's weight relative to `weight` (`None`: 1 for every image;
    /// [`GravityPriors::with_scales`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    scales: Option<Vec<f64>>,
}

/// Unvalidated serde form of [`GravityPriors`] (`world_down` optional, default `(0, 0, 1)`).
#[derive(Deserialize)]
struct RawGravityPriors {
    directions: Vec<Option<[f64; 3]>>,
    #[serde(default)]
    world_down: Option<[f64; 3]>,
    #[serde(default)]
    weight: Option<f64>,
    #[serde(default)]
    scales: Option<Vec<f64>>,
}

impl TryFrom<RawGravityPriors> for GravityPriors {
    type Error = Error;
    fn try_from(raw: RawGravityPriors) -> Result<Self> {
        let p = GravityPriors::new(raw.directions)?;
        let p = match raw.world_down {
            Some(w) => p.with_world_down(w)?,
            None => p,
        };
        let p = match raw.scales {
            Some(s) => p.with_scales(s.into_iter().map(Some).collect())?,
            None => p,
        };
        p.soft_if(raw.weight)
    }
}

/// `v / |v|`, or an error naming `item` when `v` is not finite or (nearly) zero.
fn unit(v: [f64; 3], item: &str) -> Result<[f64; 3]> {
    let v = Vector3::from(v);
    if !v.iter().all(|x| x.is_finite()) {
        return Err(Error::NonFinite { item: item.into() });
    }
    let norm = v.norm();
    if norm < MIN_GRAVITY_NORM {
        return Err(Error::Degenerate {
            reason: format!(
                "{item} has norm {norm:.3e}: a gravity direction needs a nonzero vector"
            ),
        });
    }
    Ok((v / norm).into())
}

impl GravityPriors {
    /// Validate and normalise: each known direction finite and nonzero (any length: an
    /// accelerometer reading in m/s^2 is fine). Errors: no prior at all, a non-finite or zero
    /// vector.
    ///
    /// ```
    /// use rotavg::multiple::gravity::GravityPriors;
    /// let p = GravityPriors::new(vec![Some([0.0, 9.81, 0.0]), None])?;
    /// assert_eq!(p.direction(0).unwrap(), nalgebra::Vector3::new(0.0, 1.0, 0.0));
    /// assert!(p.direction(1).is_none() && !p.is_full());
    /// assert!(GravityPriors::new(vec![Some([0.0, 0.0, 0.0])]).is_err());
    /// assert!(GravityPriors::new(vec![None]).is_err());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn new(directions: Vec<Option<[f64; 3]>>) -> Result<Self> {
        let directions = directions
            .into_iter()
            .enumerate()
            .map(|(i, d)| {
                d.map(|v| unit(v, &format!("gravity of image {i}")))
                    .transpose()
            })
            .collect::<Result<Vec<_>>>()?;
        if directions.iter().all(Option::is_none) {
            return Err(Error::Empty {
                what: "the gravity priors (no image has one)".into(),
            });
        }
        Ok(GravityPriors {
            directions,
            world_down: [0.0, 0.0, 1.0],
            weight: None,
            scales: None,
        })
    }

    /// The same priors with another world down direction (`R_i world_down = g_i`).
    pub fn with_world_down(mut self, world_down: [f64; 3]) -> Result<Self> {
        self.world_down = unit(world_down, "the world's down direction")?;
        Ok(self)
    }

    /// The same priors as **soft terms** of weight `weight` (`[G10]`): each adds
    /// `2 weight ||R_i world_down - g_i||^2` to the chordal cost, as an edge of that weight
    /// would for a tilt error (`~ 2 weight theta^2`), and leaves the heading free. A prior of
    /// standard deviation `sigma` radians per tilt axis, on edges weighted `1 / sigma_ij^2`,
    /// has `weight = 1 / sigma^2`. Errors: a weight that is not finite and positive.
    ///
    /// ```
    /// use rotavg::multiple::gravity::GravityPriors;
    /// let p = GravityPriors::new(vec![Some([0.0, 0.0, 1.0])])?.with_weight(4.0)?;
    /// assert_eq!(p.weight(), Some(4.0));
    /// assert!(GravityPriors::new(vec![Some([0.0, 0.0, 1.0])])?.with_weight(f64::NAN).is_err());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn with_weight(mut self, weight: f64) -> Result<Self> {
        crate::validate::check_weight(|| "the gravity priors' weight".into(), weight)?;
        self.weight = Some(weight);
        Ok(self)
    }

    /// [`Self::with_weight`] when `weight` is given, else the priors unchanged (the readers'
    /// optional `--gravity-weight`).
    pub fn soft_if(self, weight: Option<f64>) -> Result<Self> {
        match weight {
            Some(w) => self.with_weight(w),
            None => Ok(self),
        }
    }

    /// The soft priors' weight (`None`: hard constraints).
    pub fn weight(&self) -> Option<f64> {
        self.weight
    }

    /// The same priors with per-image **relative weights**: image `i`'s soft prior weighs
    /// `weight * scales[i]` (`None`: 1), e.g. `(sigma / sigma_i)^2` for a prior of `sigma_i`
    /// against the typical `sigma`. Held priors ignore them. Errors: a count that differs from
    /// the images', a scale that is not finite and positive.
    ///
    /// ```
    /// use rotavg::multiple::gravity::GravityPriors;
    /// let p = GravityPriors::new(vec![Some([0.0, 0.0, 1.0]), Some([0.0, 0.1, 1.0]), None])?
    ///     .with_scales(vec![Some(4.0), None, None])?
    ///     .with_weight(2.0)?;
    /// assert_eq!(p.prior_weight(0), Some(8.0));
    /// assert_eq!(p.prior_weight(1), Some(2.0));
    /// assert_eq!(p.prior_weight(2), None);
    /// assert!(p.clone().with_scales(vec![Some(-1.0), None, None]).is_err());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn with_scales(mut self, scales: Vec<Option<f64>>) -> Result<Self> {
        if scales.len() != self.directions.len() {
            return Err(Error::InvalidSettings {
                name: "gravity scales".into(),
                reason: format!(
                    "{} relative weights for {} images",
                    scales.len(),
                    self.directions.len()
                ),
            });
        }
        let scales = scales
            .into_iter()
            .enumerate()
            .map(|(i, s)| {
                let s = s.unwrap_or(1.0);
                crate::validate::check_weight(|| format!("the gravity prior of image {i}"), s)?;
                Ok(s)
            })
            .collect::<Result<Vec<_>>>()?;
        self.scales = scales.iter().any(|s| *s != 1.0).then_some(scales);
        Ok(self)
    }

    /// Image `i`'s weight relative to [`Self::weight`] (1 unless [`Self::with_scales`] said
    /// otherwise).
    pub fn scale(&self, i: usize) -> f64 {
        self.scales
            .as_ref()
            .and_then(|s| s.get(i).copied())
            .unwrap_or(1.0)
    }

    /// Images whose prior has a relative weight other than 1.
    pub fn num_scaled(&self) -> usize {
        (0..self.len())
            .filter(|&i| self.directions[i].is_some() && self.scale(i) != 1.0)
            .count()
    }

    /// The soft prior weight of image `i`, `weight * scale(i)` (`None`: held priors, or no
    /// prior for `i`).
    pub fn prior_weight(&self, i: usize) -> Option<f64> {
        self.direction(i)?;
        self.weight.map(|w| w * self.scale(i))
    }

    /// Number of images (with or without a prior).
    pub fn len(&self) -> usize {
        self.directions.len()
    }

    /// Never true (the priors hold at least one direction); for clippy's `len` rule.
    pub fn is_empty(&self) -> bool {
        self.directions.is_empty()
    }

    /// Images with a prior.
    pub fn num_known(&self) -> usize {
        self.directions.iter().filter(|d| d.is_some()).count()
    }

    /// Every image has a prior (the full-gravity problem, `[G2]`).
    pub fn is_full(&self) -> bool {
        self.directions.iter().all(Option::is_some)
    }

    /// `g_i`, the unit down direction in camera `i`'s frame, if image `i` has a prior.
    pub fn direction(&self, i: usize) -> Option<Vector3<f64>> {
        self.directions.get(i).copied().flatten().map(Vector3::from)
    }

    /// The world's down direction (unit).
    pub fn world_down(&self) -> Vector3<f64> {
        Vector3::from(self.world_down)
    }

    /// `W`, the smallest rotation with `W e_3 = world_down` (`[G1]`): `R_i W` satisfies the
    /// standard convention `(R_i W) e_3 = g_i`.
    pub fn world_frame(&self) -> Rotation {
        frame_of(&self.world_down())
    }

    /// The priors of the images `nodes` (indices into these priors), in that order, with the
    /// same world down direction. Errors: none of them has a prior.
    pub fn restricted(&self, nodes: &[usize]) -> Result<Self> {
        let directions = nodes
            .iter()
            .map(|&v| self.directions.get(v).copied().flatten())
            .collect();
        let mut out = GravityPriors::new(directions)?.with_world_down(self.world_down)?;
        out.weight = self.weight;
        out.scales = self
            .scales
            .as_ref()
            .map(|_| nodes.iter().map(|&v| self.scale(v)).collect());
        Ok(out)
    }

    /// These priors with every direction replaced by `t g_i` (a convention being tested).
    fn transformed(&self, t: &Matrix3<f64>) -> Vec<Option<Vector3<f64>>> {
        (0..self.len())
            .map(|i| self.direction(i).map(|g| t * g))
            .collect()
    }
}

/// A rotation `F` with `F e_3 = g` (unit `g`), accurate to rounding for every `g`: the
/// smallest one, `I + hat(v) + hat(v)^2 / (1 + c)` with `v = e_3 x g`, `c = g_z`, when
/// `g_z > -1/2`; otherwise the smallest rotation from `-e_3` to `g` after a half turn about
/// `e_1` (the smallest rotation's formula loses half the digits as `g -> -e_3`).
///
/// ```
/// use rotavg::multiple::gravity::frame_of;
/// use nalgebra::Vector3;
/// for g in [Vector3::new(0.3, -0.2, 0.9), Vector3::new(1e-9, 0.0, -1.0), Vector3::new(0.0, 1.0, 0.0)] {
///     let g = g.normalize();
///     let f = frame_of(&g);
///     assert!((f * Vector3::z() - g).norm() < 1e-15);
///     assert!((f.matrix().transpose() * f.matrix() - nalgebra::Matrix3::identity()).norm() < 1e-15);
/// }
/// ```
pub fn frame_of(g: &Vector3<f64>) -> Rotation {
    let smallest = |a: Vector3<f64>| {
        let v = a.cross(g);
        let h = crate::so3::hat(&v);
        Matrix3::identity() + h + h * h / (1.0 + a.dot(g))
    };
    let m = if g.z > -0.5 {
        smallest(Vector3::z())
    } else {
        smallest(-Vector3::z()) * Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0))
    };
    Rotation::from_matrix_unchecked(m)
}

/// `Rz(theta)`, the turn by `theta` about `e_3`.
fn rz(theta: f64) -> Rotation {
    Rotation::from_axis_angle(&Unit::new_unchecked(Vector3::z()), theta)
}

/// A view graph with gravity priors (one per node, some may be missing), validated together
/// (deserialisation too: [`GravityProblem::new`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawGravityProblem")]
pub struct GravityProblem {
    problem: MultipleProblem,
    priors: GravityPriors,
}

/// Unvalidated serde form of [`GravityProblem`].
#[derive(Deserialize)]
struct RawGravityProblem {
    problem: MultipleProblem,
    priors: GravityPriors,
}

impl TryFrom<RawGravityProblem> for GravityProblem {
    type Error = Error;
    fn try_from(raw: RawGravityProblem) -> Result<Self> {
        GravityProblem::new(raw.problem, raw.priors)
    }
}

/// How well the priors agree with the relative rotations, without an estimate (`[G6]`): for
/// each edge `(i, j)` with both priors, the angle between `R_ij g_i` and `g_j` (zero for exact
/// data, whatever the absolute rotations).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GravityCheck {
    /// Edges with a prior at both ends.
    pub edges_checked: usize,
    /// Median of those angles as given, degrees.
    pub median_deg: f64,
    /// 90th percentile, degrees.
    pub p90_deg: f64,
    /// A convention that fits far better (median below a quarter of the given one, and the
    /// given one above 2 degrees), with its median: the likely mistake, in words.
    pub better_convention: Option<(String, f64)>,
    /// Fraction of images whose `g_i` points up the image (`-y` in OpenCV / COLMAP camera
    /// axes, x right, y down, z forward): above one half, the vectors are probably up vectors.
    pub pointing_up_fraction: f64,
    /// On a graph with information matrices, the median over the edges with both priors of
    /// the smallest Mahalanobis norm `sqrt(e^T H e)` of a residual `e` that turns `g_i` onto
    /// `R_ij^T g_j` (the priors' disagreement in units of the edge's standard deviation, the
    /// heading left free): about 1.2 (`chi` with 2 degrees of freedom) for exact priors, far
    /// above where the priors are much less precise than the edges (`[G6]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub information_sigma: Option<f64>,
}

/// The axis conventions [`GravityProblem::check_conventions`] tries, with what each means.
fn conventions() -> [(&'static str, Matrix3<f64>); 4] {
    [
        (
            "y and z negated (OpenGL camera axes: y up, z backward)",
            Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0)),
        ),
        (
            "x and z negated",
            Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, -1.0)),
        ),
        (
            "x and y negated (sensor turned upside down in the image plane)",
            Matrix3::from_diagonal(&Vector3::new(-1.0, -1.0, 1.0)),
        ),
        (
            "x and y swapped, z negated (device axes of a phone in landscape)",
            Matrix3::new(0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, -1.0),
        ),
    ]
}

impl GravityProblem {
    /// Pair a view graph with its priors. Errors: a count that differs from the graph's nodes.
    pub fn new(problem: MultipleProblem, priors: GravityPriors) -> Result<Self> {
        if priors.len() != problem.num_rotations() {
            return Err(Error::InvalidSettings {
                name: "gravity".into(),
                reason: format!(
                    "{} gravity entries for a view graph of {} images (one entry per image, \
                     null where an image has none)",
                    priors.len(),
                    problem.num_rotations()
                ),
            });
        }
        Ok(GravityProblem { problem, priors })
    }

    /// Exact priors from absolute rotations (`g_i = R_i e_3`): planted test cases.
    pub fn from_truth(problem: MultipleProblem, truth: &[Rotation]) -> Result<Self> {
        let dirs = truth
            .iter()
            .map(|r| Some((r * Vector3::z()).into()))
            .collect();
        GravityProblem::new(problem, GravityPriors::new(dirs)?)
    }

    /// The view graph.
    pub fn problem(&self) -> &MultipleProblem {
        &self.problem
    }

    /// The priors.
    pub fn priors(&self) -> &GravityPriors {
        &self.priors
    }

    /// `F_i` with `F_i e_3 = g_i` ([`frame_of`]), when image `i` has a prior.
    pub fn frame(&self, i: usize) -> Option<Rotation> {
        self.priors.direction(i).map(|g| frame_of(&g))
    }

    /// Which nodes have a prior (their tilt is fixed, `[G4]`).
    pub fn tilt_fixed(&self) -> Vec<bool> {
        (0..self.priors.len())
            .map(|i| self.priors.direction(i).is_some())
            .collect()
    }

    /// The largest angle between `R_i world_down` and `g_i` over the images with a prior,
    /// degrees (0 for a feasible estimate, up to rounding).
    pub fn max_prior_violation_deg(&self, rotations: &[Rotation]) -> f64 {
        self.prior_pairs(rotations)
            .map(|(down, g)| angle_between(&down, &g))
            .fold(0.0, f64::max)
            .to_degrees()
    }

    /// `(R_i world_down, g_i)` for every image `i` with a prior.
    fn prior_pairs<'a>(
        &'a self,
        rotations: &'a [Rotation],
    ) -> impl Iterator<Item = (Vector3<f64>, Vector3<f64>)> + 'a {
        let w = self.priors.world_down();
        rotations
            .iter()
            .enumerate()
            .filter_map(move |(i, r)| self.priors.direction(i).map(|g| (r * w, g)))
    }

    /// In the standard convention (`world_down = e_3`): `R_i W`.
    pub(crate) fn to_standard(&self, rotations: &[Rotation]) -> Vec<Rotation> {
        let w = self.priors.world_frame();
        rotations.iter().map(|r| r * w).collect()
    }

    /// Back from the standard convention: `R_i W^T`.
    pub(crate) fn out_of_standard(&self, rotations: &[Rotation]) -> Vec<Rotation> {
        let w = self.priors.world_frame().inverse();
        rotations.iter().map(|r| r * w).collect()
    }

    /// Standard convention: the rotation about `e_3` applied on the right (the gravity
    /// problem's gauge) that best aligns `R_i^T g_i` with `e_3` for an unconstrained estimate
    /// (defined up to `R_i -> R_i G`), then each constrained `R_i` projected onto its prior:
    /// the nearest `F_i Rz(theta)` (`[G5]`).
    /// The robust objective's cost at `rotations` (standard convention): the view graph's
    /// cost with the soft priors' terms (of the file convention's rotations).
    fn robust_cost(&self, rotations: &[Rotation]) -> f64 {
        let file = self.out_of_standard(rotations);
        self.problem.cost(&file) + self.prior_cost(&file)
    }

    pub(crate) fn aligned_and_projected(&self, rotations: &[Rotation]) -> Vec<Rotation> {
        let mean: Vector3<f64> = rotations
            .iter()
            .enumerate()
            .filter_map(|(i, r)| self.priors.direction(i).map(|g| r.inverse() * g))
            .sum();
        let align = frame_of(&mean.try_normalize(0.0).unwrap_or(Vector3::z()));
        rotations
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let r = r * align;
                match self.frame(i) {
                    Some(f) => f * rz(yaw((f.inverse() * r).matrix())),
                    None => r,
                }
            })
            .collect()
    }

    /// The gradient norm of the problem at `rotations` (standard convention): the tilt of each
    /// image with a prior held, or with soft priors their terms added (`[G10]`).
    fn gradient_norm(&self, rotations: &[Rotation], l1_epsilon: f64) -> f64 {
        match self.priors.weight() {
            Some(_) => self.soft_gradient_norm(rotations, l1_epsilon),
            None => self.constrained_gradient_norm(rotations, l1_epsilon),
        }
    }

    /// `||grad||` of the objective on the constrained manifold at `rotations` (standard
    /// convention): the chart gradient with the tilt components of the images with a prior
    /// removed (`[G4]`).
    fn constrained_gradient_norm(&self, rotations: &[Rotation], l1_epsilon: f64) -> f64 {
        let (_, mut grad) = objective_cost_gradient(&self.problem, rotations, l1_epsilon);
        for (g, fixed) in grad.iter_mut().zip(self.tilt_fixed()) {
            if fixed {
                (g.x, g.y) = (0.0, 0.0);
            }
        }
        grad.iter().map(|g| g.norm_squared()).sum::<f64>().sqrt()
    }

    /// The edges' agreement with the priors and the conventions that would fit better
    /// (`[G6]`); `None` when no edge has a prior at both ends.
    ///
    /// ```
    /// use rotavg::multiple::gravity::GravityProblem;
    /// use rotavg::multiple::synthetic::SyntheticGraph;
    /// use rotavg::so3::exp;
    /// let (graph, truth) = SyntheticGraph { num_rotations: 20, num_edges: 60, noise_sigma: 0.0, ..Default::default() }.generate();
    /// let ok = GravityProblem::from_truth(graph.clone(), &truth)?.check_conventions().unwrap();
    /// assert!(ok.median_deg < 1e-9 && ok.better_convention.is_none());
    /// // the same vectors written with OpenGL camera axes (y up, z backward)
    /// let flip = nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, -1.0, -1.0));
    /// let gl: Vec<_> = truth.iter().map(|r| Some((flip * (r * nalgebra::Vector3::z())).into())).collect();
    /// let p = GravityProblem::new(graph, rotavg::multiple::gravity::GravityPriors::new(gl)?)?;
    /// let bad = p.check_conventions().unwrap();
    /// assert!(bad.median_deg > 10.0);
    /// assert!(bad.better_convention.unwrap().0.starts_with("y and z negated"));
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn check_conventions(&self) -> Option<GravityCheck> {
        let given = self.priors.transformed(&Matrix3::identity());
        let (median, p90, count) = edge_disagreement(&self.problem, &given)?;
        let better = conventions()
            .into_iter()
            .map(|(name, t)| {
                let (m, _, _) = edge_disagreement(&self.problem, &self.priors.transformed(&t))
                    .unwrap_or((f64::INFINITY, 0.0, 0));
                (name.to_string(), m)
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .filter(|(_, m)| median > 2.0 && *m < 0.25 * median);
        let up = given.iter().flatten().filter(|g| g.y < -0.5).count();
        Some(GravityCheck {
            edges_checked: count,
            median_deg: median,
            p90_deg: p90,
            better_convention: better,
            pointing_up_fraction: up as f64 / self.priors.num_known() as f64,
            information_sigma: information_disagreement(&self.problem, &given),
        })
    }
}

/// [`GravityCheck::information_sigma`]: per edge with both priors and information `H`, with
/// `d` the turn taking `g_i` onto `R_ij^T g_j` (axis `g_i x R_ij^T g_j`, camera `i`'s frame, as
/// the residual of `R_j R_i^T = R_ij exp([e]x)`) and `a = g_i` (the heading, not observed):
/// `min_t (d + t a)^T H (d + t a) = d^T H d - (a^T H d)^2 / a^T H a`; the median of its root.
fn information_disagreement(
    problem: &MultipleProblem,
    dirs: &[Option<Vector3<f64>>],
) -> Option<f64> {
    let info = problem.information()?;
    let mut sigmas: Vec<f64> = (problem.edges().iter().zip(info))
        .filter_map(|(e, h)| {
            let (a, gj) = (dirs[e.i]?, e.rotation.inverse() * dirs[e.j]?);
            let axis = a.cross(&gj);
            let d = match axis.norm() {
                0.0 => Vector3::zeros(),
                n => axis * (angle_between(&a, &gj) / n),
            };
            let h = h.matrix();
            let (hd, aha) = (h * d, a.dot(&(h * a)));
            let yaw = if aha > 0.0 {
                a.dot(&hd).powi(2) / aha
            } else {
                0.0
            };
            Some((d.dot(&hd) - yaw).max(0.0).sqrt())
        })
        .collect();
    sigmas.sort_by(f64::total_cmp);
    sigmas.get(sigmas.len() / 2).copied()
}

/// The angle between two vectors, accurate near 0 (`atan2(|a x b|, a . b)`; `acos` of the
/// cosine resolves no angle below `1.5e-8` rad).
fn angle_between(a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    a.cross(b).norm().atan2(a.dot(b))
}

/// Median and 90th percentile (degrees) of the angles between `R_ij g_i` and `g_j` over the
/// edges with both directions, and their count; `None` when there is no such edge.
fn edge_disagreement(
    problem: &MultipleProblem,
    dirs: &[Option<Vector3<f64>>],
) -> Option<(f64, f64, usize)> {
    let mut angles: Vec<f64> = problem
        .edges()
        .iter()
        .filter_map(|e| match (dirs[e.i], dirs[e.j]) {
            (Some(gi), Some(gj)) => Some(angle_between(&(e.rotation * gi), &gj).to_degrees()),
            _ => None,
        })
        .collect();
    if angles.is_empty() {
        return None;
    }
    angles.sort_by(f64::total_cmp);
    let at = |q: f64| angles[((angles.len() - 1) as f64 * q).round() as usize];
    Some((at(0.5), at(0.9), angles.len()))
}

/// The angle `theta` of the turn about `e_3` nearest to `m` (`argmax tr(Rz(theta)^T m)`, any
/// 3x3 `m`): the heading of `F^T R`, and the best turn aligning two estimates (`[G1]`, `[G5]`).
pub(crate) fn yaw(m: &Matrix3<f64>) -> f64 {
    (m[(1, 0)] - m[(0, 1)]).atan2(m[(0, 0)] + m[(1, 1)])
}

/// The gravity problem's gauge (standard convention): the turn about `e_3`, applied on the
/// right of every rotation, that brings `R_0` nearest to `I` (for a node 0 with a prior:
/// `R_0 = F_0`, the smallest rotation with `R_0 e_3 = g_0`).
fn fix_gravity_gauge(rotations: &mut [Rotation]) {
    let Some(r0) = rotations.first() else { return };
    // tr(R_0 Rz(a)) = tr(Rz(a)^T R_0^T) is largest at the yaw of R_0^T
    let g = rz(yaw(&r0.matrix().transpose()));
    for r in rotations.iter_mut() {
        *r *= g;
    }
}

/// Averaging with gravity as a hard constraint (`[G4]`, `[G5]`, `[G8]`): the unconstrained
/// solve ([`solve_multiple`] with `settings`, under the view graph's objective), aligned to the
/// priors and projected onto them, then, for chordal L2, the chordal Newton-LM in which every
/// image with a prior only turns about its gravity axis; for a robust loss (L1, Huber, Cauchy
/// of the residual or Mahalanobis angle), iteratively reweighted constrained chordal solves
/// (`[G8]`). Images without a prior (the mixed problem) move freely. The costs are the view
/// graph's at the returned estimate, which satisfies every prior to rounding
/// (`R_i g_world = g_i`); robust solves carry the per-edge residuals
/// ([`MultipleSolution::residuals`]). Gauge: the turn about `g_world` that brings `R_0`
/// nearest to `I`. Errors: a disconnected graph, the geodesic L2 objective.
pub fn solve_gravity(
    problem: &GravityProblem,
    settings: &MultipleSettings,
) -> Result<MultipleSolution> {
    let graph = &problem.problem;
    let objective = graph.objective();
    if objective.loss == Loss::L2 && !objective.is_chordal_l2() {
        return Err(Error::InvalidSettings {
            name: "loss".into(),
            reason: "gravity priors are solved with the chordal L2 loss or a robust loss \
                     (l1, huber, cauchy), not geodesic L2"
                .into(),
        });
    }
    graph.require_connected()?;
    let start = std::time::Instant::now();
    let free = start_point(problem, settings)?;
    let init = free.rotations;
    // one clock for MultipleSettings::max_seconds: the constrained solve gets what is left
    let left = settings.remaining(start);
    let (rotations, iterations, termination) = if objective.is_chordal_l2() {
        let s = solve_step(problem, graph, init, &left)?;
        (s.rotations, s.report.iterations, s.report.termination)
    } else {
        reweighted(problem, init, &free.aside, &left)?
    };
    let mut rotations = rotations;
    fix_gravity_gauge(&mut rotations);
    let gradient_norm = problem.gradient_norm(&rotations, settings.l1_epsilon);
    let rotations = problem.out_of_standard(&rotations);
    // the reported costs are the file's (with the soft priors' terms), at exactly the returned
    // rotations
    let prior_cost = problem.prior_cost(&rotations);
    let chordal_cost = graph.chordal_cost(&rotations) + prior_cost;
    let residuals =
        inlier_threshold_deg(&objective, settings).map(|t| edge_residuals(graph, &rotations, t));
    let held = ["tilt held", "soft priors"][usize::from(problem.priors.weight().is_some())];
    Ok(MultipleSolution {
        cost: graph.cost(&rotations) + prior_cost,
        chordal_cost,
        gradient_norm,
        rotations,
        objective,
        report: SolverReport {
            name: if objective.is_chordal_l2() {
                format!("riemannian-newton-lm (gravity: {held})")
            } else {
                format!("irls-{} (gravity: {held})", objective.loss.name())
            },
            iterations: free.iterations + iterations,
            termination,
            seconds: start.elapsed().as_secs_f64(),
        },
        init_cost: free.cost,
        residuals,
        linear_algebra: None,
    })
}

/// Where [`solve_gravity`]'s constrained or soft solve starts (standard convention), with the
/// iterations of getting there and its cost as the solution reports one (the file's, with the
/// priors' terms).
struct Start {
    rotations: Vec<Rotation>,
    iterations: usize,
    cost: f64,
    /// The edges the reweighted solve of a robust loss sets aside (the first stage's,
    /// [`two_stage`]; none outside it).
    aside: Vec<bool>,
}

/// [`solve_gravity`]'s start: the unconstrained solve aligned to the priors and projected onto
/// them; for a robust loss on a graph with information, the first stage of [`two_stage`] (its
/// estimate satisfies the priors); with soft priors and a given estimate (a warm start, as the
/// rig's alternation passes give, `[G15]`), that estimate itself: the free solve and the
/// projection would carry it out of the soft problem's minimum and the soft solve back (1.4 s
/// per pass at 10^4 frames).
fn start_point(problem: &GravityProblem, settings: &MultipleSettings) -> Result<Start> {
    let graph = &problem.problem;
    let none_aside = || vec![false; graph.num_edges()];
    // the start's cost as the solution's is reported: the file's, with the priors' terms
    let cost = |file: &[Rotation]| graph.cost(file) + problem.prior_cost(file);
    if let (Initialisation::Given(_), Some(_)) = (&settings.init, problem.priors.weight()) {
        let rotations = initialise(graph, &settings.init)?;
        return Ok(Start {
            cost: cost(&rotations),
            rotations: problem.to_standard(&rotations),
            iterations: 0,
            aside: none_aside(),
        });
    }
    if let Some(first) = two_stage::first_stage(problem, settings)? {
        return Ok(Start {
            cost: cost(&first.rotations),
            rotations: problem.to_standard(&first.rotations),
            iterations: first.iterations,
            aside: first.aside,
        });
    }
    let free = solve_multiple(graph, settings)?;
    let rotations = problem.aligned_and_projected(&problem.to_standard(&free.rotations));
    Ok(Start {
        cost: cost(&problem.out_of_standard(&rotations)),
        rotations,
        iterations: free.report.iterations,
        aside: none_aside(),
    })
}

/// One chordal solve of the gravity problem on `graph` (its view graph or a reweighting of
/// it) from `init` (standard convention): the priors held ([`solve_constrained`]) or as soft
/// terms (`[G10]`).
fn solve_step(
    problem: &GravityProblem,
    graph: &MultipleProblem,
    init: Vec<Rotation>,
    settings: &MultipleSettings,
) -> Result<MultipleSolution> {
    match problem.priors.weight() {
        Some(_) => soft::solve_soft(problem, graph, init, settings),
        None => solve_constrained(problem, graph, init, settings),
    }
}

/// The chordal Newton-LM with the tilt of every image with a prior held, on `graph` (the
/// problem's view graph or a reweighting of it), from `init` (standard convention); the result
/// in the standard convention, gauge not fixed. Node 0 is grounded by the Newton-LM: it must
/// be a node with a prior (its one degree of freedom is the gauge), so the nodes are relabelled.
fn solve_constrained(
    problem: &GravityProblem,
    graph: &MultipleProblem,
    init: Vec<Rotation>,
    settings: &MultipleSettings,
) -> Result<MultipleSolution> {
    let fixed = problem.tilt_fixed();
    let ground = fixed.iter().position(|&f| f).unwrap_or(0);
    let mut new_of_old: Vec<usize> = (0..fixed.len()).collect();
    new_of_old.swap(0, ground);
    let relabelled = graph.relabelled(&new_of_old);
    let (mut init, mut fixed) = (init, fixed);
    init.swap(0, ground);
    fixed.swap(0, ground);
    let mut sol = solve_chordal_tilt_fixed(&relabelled, init, settings, None, Some(&fixed))?;
    sol.rotations.swap(0, ground);
    Ok(sol)
}

/// The relative IRLS weight of an edge [`reweighted`] sets aside, and the floor of every other
/// (a weight, not a removal: the graph stays the priors' graph).
const ASIDE_WEIGHT: f64 = 1e-12;

/// The largest change of the IRLS weights between two passes below which the reweighted
/// solve of a robust loss with gravity priors (`[G8]`) stops.
pub const IRLS_WEIGHT_TOLERANCE: f64 = 1e-6;

/// The passes of `[G8]`'s reweighted solve (each a whole solve) also stop when the robust cost
/// decreased by at most this fraction of itself over the last [`IRLS_DECREASE_WINDOW`] passes,
/// unless [`MultipleSettings::irls_decrease_tolerance`] is looser (at the data's scale, a
/// 10^4-image scene with information and exact priors ran 27 passes where 14 reach the same
/// estimate to the digits reported, its cost within `2e-9` of the last pass's).
pub const PASS_DECREASE_TOLERANCE: f64 = 1e-6;

/// `[G8]`'s reweighted solve stops when the robust cost rose in this many passes in a row, and
/// returns the pass of the lowest cost (a 1000-image scene with information and exact priors:
/// lowest at the fifth pass, then rising by `1e-8` of itself over ten more).
pub const RISES_TO_STOP: usize = 2;

/// Robust averaging with the priors held (`[G8]`): passes of the constrained chordal solve on
/// the view graph with each edge's weight (information) multiplied by its relative IRLS weight
/// at the current estimate ([`relative_weight`] of the residual or Mahalanobis angle; on graphs
/// with information, the edges `aside` (set aside by the first stage, [`two_stage`]) keep the
/// floor weight), until no weight changes by more than [`IRLS_WEIGHT_TOLERANCE`] or the
/// robust cost settles ([`settled`] at [`PASS_DECREASE_TOLERANCE`] or the settings' looser
/// tolerance) or rises in [`RISES_TO_STOP`] passes in a row (the passes minimise the chordal
/// surrogate, not the robust cost itself: a rise is that mismatch); at most a tenth of
/// `settings.max_iterations` passes, each a whole solve; within `settings.max_seconds`.
/// Returns the rotations of the pass of the lowest robust cost (standard convention; the start
/// when no pass ran), the passes and why it stopped.
fn reweighted(
    problem: &GravityProblem,
    init: Vec<Rotation>,
    aside: &[bool],
    settings: &MultipleSettings,
) -> Result<(Vec<Rotation>, usize, Termination)> {
    let graph = &problem.problem;
    let objective = graph.objective();
    let threshold = inlier_threshold_deg(&objective, settings).unwrap_or(5.0);
    let weights_at = |r: &[Rotation]| -> Vec<f64> {
        (graph.objective_angles(r).iter().zip(aside))
            .map(|(t, &out)| match out {
                true => ASIDE_WEIGHT,
                false => relative_weight(&objective, *t, threshold).max(ASIDE_WEIGHT),
            })
            .collect()
    };
    let mut rotations = init;
    let mut weights = weights_at(&rotations);
    let mut lowest = Lowest::default();
    let (begun, deadline) = (std::time::Instant::now(), settings.deadline());
    let mut change = f64::NAN;
    let mut recent = std::collections::VecDeque::with_capacity(IRLS_DECREASE_WINDOW + 1);
    let max_passes = (settings.max_iterations / 10).max(1);
    let tolerance = settings
        .irls_decrease_tolerance
        .max(PASS_DECREASE_TOLERANCE);
    let (passes, stop) = 'passes: {
        for pass in 1..=max_passes {
            let measure = (change, IRLS_WEIGHT_TOLERANCE);
            let limit = crate::deadline::limit_reached(pass - 1, max_passes, deadline, measure);
            if let Some(limit) = limit {
                break 'passes (pass - 1, limit);
            }
            let reweighted = graph.reweighted(&weights)?;
            let left = settings.remaining(begun);
            rotations = solve_step(problem, &reweighted, rotations, &left)?.rotations;
            let cost = problem.robust_cost(&rotations);
            let stop = (lowest.rose(cost, pass, &rotations))
                .or_else(|| settled(&mut recent, cost, tolerance));
            if let Some(t) = stop {
                break 'passes (pass, t);
            }
            let next = weights_at(&rotations);
            change = (next.iter().zip(&weights))
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            weights = next;
            if change <= IRLS_WEIGHT_TOLERANCE {
                let t = Termination::Converged {
                    measure: "largest change of the IRLS weights".into(),
                    value: change,
                    threshold: IRLS_WEIGHT_TOLERANCE,
                };
                break 'passes (pass, t);
            }
        }
        let t = Termination::IterationLimit {
            iterations: max_passes,
            value: f64::NAN,
            threshold: IRLS_WEIGHT_TOLERANCE,
        };
        (max_passes, t)
    };
    Ok((lowest.or(rotations), passes, stop))
}

/// The pass of the lowest robust cost so far in [`reweighted`], and the passes in a row that rose.
#[derive(Default)]
struct Lowest {
    cost: f64,
    rotations: Vec<Rotation>,
    last: Option<f64>,
    rises: usize,
}

impl Lowest {
    /// Record pass `pass` of robust cost `cost` at `rotations`; [`RISES_TO_STOP`] rises in a
    /// row: the reason to stop (the lowest pass's rotations are then `self.rotations`).
    fn rose(&mut self, cost: f64, pass: usize, rotations: &[Rotation]) -> Option<Termination> {
        self.rises = match self.last {
            Some(last) if cost > last => self.rises + 1,
            _ => 0,
        };
        self.last = Some(cost);
        if self.rotations.is_empty() || cost < self.cost {
            self.cost = cost;
            self.rotations = rotations.to_vec();
        }
        (self.rises >= RISES_TO_STOP).then(|| Termination::Converged {
            measure: format!(
                "passes in a row whose robust cost rose (pass {pass}; the lowest, {:.9e}, \
                 returned)",
                self.cost
            ),
            value: self.rises as f64,
            threshold: RISES_TO_STOP as f64,
        })
    }

    /// The lowest pass's rotations, or `last` when no pass was recorded.
    fn or(self, last: Vec<Rotation>) -> Vec<Rotation> {
        match self.rotations.is_empty() {
            true => last,
            false => self.rotations,
        }
    }
}

/// The test of a relative decrease `tolerance` on the passes of [`reweighted`]: converged when
/// the robust cost `cost` of the last pass decreased by at most that fraction of itself over
/// the last [`IRLS_DECREASE_WINDOW`] passes (`recent`, updated here). [`reweighted`] asks for
/// [`PASS_DECREASE_TOLERANCE`]; the first stage of [`two_stage`], a start, for
/// [`L1_START_DECREASE_TOLERANCE`](super::solve::L1_START_DECREASE_TOLERANCE).
fn settled(
    recent: &mut std::collections::VecDeque<f64>,
    cost: f64,
    tolerance: f64,
) -> Option<Termination> {
    recent.push_back(cost);
    if recent.len() <= IRLS_DECREASE_WINDOW {
        return None;
    }
    let oldest = recent.pop_front().unwrap_or(cost);
    let decrease = (oldest - cost) / cost.abs().max(f64::MIN_POSITIVE);
    (decrease <= tolerance).then(|| Termination::Converged {
        measure: format!("relative cost decrease over the last {IRLS_DECREASE_WINDOW} passes"),
        value: decrease,
        threshold: tolerance,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::VecDeque;

    #[test]
    fn passes_settle_on_the_cost_decrease_over_the_window() {
        let settings = 1e-4;
        // falling by 1e-3 per pass: 1e-2 over the window, never within 1e-4
        let mut recent = VecDeque::new();
        for k in 0..30 {
            let cost = 1.0 - 1e-3 * k as f64;
            assert!(settled(&mut recent, cost, settings).is_none(), "pass {k}");
        }
        // flat: settled as soon as the window holds IRLS_DECREASE_WINDOW passes before this one
        let mut recent = VecDeque::new();
        let first = (0..20).position(|_| settled(&mut recent, 2.0, settings).is_some());
        assert_eq!(first, Some(IRLS_DECREASE_WINDOW));
    }

    #[test]
    fn passes_stop_after_rises_in_a_row_with_the_lowest_pass() {
        let at = |k: usize| {
            vec![Rotation::from_axis_angle(
                &nalgebra::Vector3::z_axis(),
                k as f64,
            )]
        };
        let mut lowest = Lowest::default();
        // falls, rises once, falls lower, then rises twice in a row
        let costs = [5.0, 3.0, 4.0, 2.0, 2.5, 2.7];
        let stops: Vec<bool> = (costs.iter().enumerate())
            .map(|(k, &c)| lowest.rose(c, k + 1, &at(k)).is_some())
            .collect();
        assert_eq!(stops, [false, false, false, false, false, true]);
        assert_eq!(lowest.cost, 2.0);
        assert_eq!(lowest.rotations, at(3));
    }
}
