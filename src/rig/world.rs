//! Soft gravity priors on a rig with sensors to estimate, as a rig without priors
//! (`paper-notes/gravity.md` `[G16]`): one more frame, the **world**, photographed by one more
//! sensor held at the identity, and one edge per prior from the world's image to the prior's
//! image with the information `w diag(1, 1, 0)` (`[G10]`'s world node, made a frame). The
//! rig's own edges carry `w I`. Its minimum is the joint problem's (sensors, frames and
//! priors), so the rig's certificates (`[H19]`-`[H24]`: the couplings of `[H21]` first) bound
//! the joint problem, which `[G15]` only solved.

use super::problem::{Image, RigProblem, Sensor};
use crate::error::Result;
use crate::multiple::Edge;
use crate::multiple::anisotropic::Information;
use crate::multiple::gravity::frame_of;
use crate::so3::Rotation;
use nalgebra::{Matrix3, Vector3};

/// A rig with soft priors and sensors to estimate, as the rig of `[G16]`.
#[derive(Debug, Clone)]
pub struct WorldRig {
    /// The rig with the world frame (last frame), the world sensor (last sensor, held at the
    /// identity) and its image (last image); no priors; information on every edge.
    pub problem: RigProblem,
    /// The world frame's rotation at which the world rig's cost is the posed one: `W^T` with
    /// `W e_3 = world_down` ([`frame_of`]).
    world: Rotation,
    /// A lower bound on the posed cost (edges and priors) minus the world rig's at every rig
    /// point with the world frame at an exact rotation taking `e_3` to `world_down`: the data's
    /// orthogonality and unit-length defects and the rounding of the priors' rotations.
    defect: f64,
}

impl RigProblem {
    /// The rig of `[G16]` when this one has soft gravity priors and a sensor to estimate;
    /// `None` otherwise (no priors, held ones, or every sensor held: `[G14]`'s frames'
    /// gravity problem is then exact). Errors: none expected (the parts were validated).
    pub fn soft_priors_as_world_frame(&self) -> Result<Option<WorldRig>> {
        let Some(priors) = self.gravity().filter(|g| g.weight().is_some()) else {
            return Ok(None);
        };
        if self.all_held() {
            return Ok(None);
        }
        let (frames, sensors, images) = (self.num_frames(), self.sensors(), self.images());
        let mut world_sensors = sensors.to_vec();
        world_sensors.push(Sensor {
            sensor_from_rig: Some(Rotation::identity()),
        });
        let mut world_images = images.to_vec();
        world_images.push(Image {
            frame: frames,
            sensor: sensors.len(),
        });
        let (mut edges, mut info) = (self.edges().to_vec(), own_information(self)?);
        let mut defect = DefectSum::default();
        // scalar edges: the posed norm form exceeds the world rig's trace form of `w I` by
        // `w (||R||^2 - 3)`; edges with information have the trace form in both (no defect:
        // charging theirs raised the bound above the minimum, `tests/suite/soundness_rig.rs`)
        if !self.is_anisotropic() {
            for e in self.edges() {
                let term = e.weight * (e.rotation.matrix().norm_squared() - 3.0);
                defect.add(term, e.weight);
            }
        }
        let down = priors.world_down();
        for a in 0..images.len() {
            let (Some(g), Some(w)) = (priors.direction(a), priors.prior_weight(a)) else {
                continue;
            };
            let rotation = frame_of(&g);
            defect.add(-w * prior_defect(&rotation, &g, &down), w);
            info.push(Information::new(Matrix3::from_diagonal(&Vector3::new(
                w, w, 0.0,
            )))?);
            edges.push(Edge {
                i: images.len(),
                j: a,
                rotation,
                weight: w,
            });
        }
        let problem = RigProblem::new(frames + 1, world_sensors, world_images, edges)?
            .with_information(info)?;
        Ok(Some(WorldRig {
            problem,
            world: frame_of(&down).inverse(),
            defect: defect.lower(),
        }))
    }
}

impl WorldRig {
    /// The world rig's point of the rig point `(frames, sensors)`: the world frame at `W^T`,
    /// the world sensor at the identity.
    pub(crate) fn point(
        &self,
        frames: &[Rotation],
        sensors: &[Rotation],
    ) -> (Vec<Rotation>, Vec<Rotation>) {
        let mut f = frames.to_vec();
        f.push(self.world);
        let mut s = sensors.to_vec();
        s.push(Rotation::identity());
        (f, s)
    }

    /// The rig point of a world rig point: every frame turned by the `G` that brings the world
    /// frame to `W^T` (`F_f G`, `G = F_world^T W^T`; the world rig's cost is unchanged by it,
    /// and there it is the posed cost), the world's frame and sensor dropped.
    pub(crate) fn posed_point(
        &self,
        frames: &[Rotation],
        sensors: &[Rotation],
    ) -> (Vec<Rotation>, Vec<Rotation>) {
        let (world, frames) = frames
            .split_last()
            .expect("the world rig has its world frame");
        let g = world.inverse() * self.world;
        let frames = frames.iter().map(|f| f * g).collect();
        (frames, sensors[..sensors.len() - 1].to_vec())
    }

    /// A lower bound on the posed problem's minimum from a proven lower bound `world_bound` on
    /// the world rig's (`[G16]`): plus the defect, which is a few units in the last place of
    /// the weights on data orthogonal to rounding (not finite when `world_bound` is not).
    pub fn posed_bound(&self, world_bound: f64) -> f64 {
        world_bound + self.defect
    }
}

/// The rig's edges' information: their own, or `w I` for scalar weights (`H = w I` gives
/// exactly the isotropic chordal cost up to the data's orthogonality defect, which the
/// defect sum carries).
fn own_information(p: &RigProblem) -> Result<Vec<Information>> {
    match p.information() {
        Some(info) => Ok(info.to_vec()),
        None => (p.edges().iter())
            .map(|e| Information::new(Matrix3::identity() * e.weight))
            .collect(),
    }
}

/// `|posed - world| / w` of one prior, bounded (`[G16]`, rounding): the posed term
/// `2 w ||X d - g||^2` against the world edge's `4 w (1 - r^T X d')` (`r = R e_3` of the
/// stored rotation, `d'` the unit `d`), at any rotation `X`:
/// `2 ||d|^2 - 1| + 2 ||g|^2 - 1| + 4 |r - g| + 4 |g| ||d| - 1|`.
fn prior_defect(rotation: &Rotation, g: &Vector3<f64>, down: &Vector3<f64>) -> f64 {
    let r = rotation.matrix().column(2).into_owned();
    2.0 * (down.norm_squared() - 1.0).abs()
        + 2.0 * (g.norm_squared() - 1.0).abs()
        + 4.0 * (r - g).norm()
        + 4.0 * g.norm() * (down.norm() - 1.0).abs()
}

/// A sum of signed terms and the weights they came with, bounded below with its rounding.
#[derive(Default)]
struct DefectSum {
    sum: f64,
    magnitude: f64,
    weight: f64,
    terms: usize,
}

impl DefectSum {
    fn add(&mut self, term: f64, weight: f64) {
        self.sum += term;
        self.magnitude += term.abs();
        self.weight += weight;
        self.terms += 1;
    }

    /// The exact sum's lower bound: the summation's error (`gamma_terms` of the magnitudes,
    /// doubled) and `256 u` per unit of weight for each term's own evaluation (norms of 3x3
    /// matrices and vectors: under `40 u`) and for the world rig's `M = tr(H)/2 I - H`, whose
    /// `tr(H)/2` of `w I` may round (`|dM| <= 2 u w` per entry: under `48 u w` per edge).
    fn lower(&self) -> f64 {
        let u = f64::EPSILON / 2.0;
        let n = self.terms as f64 + 2.0;
        self.sum
            - 2.0 * n * u * self.magnitude * (1.0 + 1e-6)
            - 256.0 * u * self.weight * (1.0 + 1e-6)
    }
}
