//! The rig problem (`paper-notes/conjugate.md` `[H19]`): frames, sensors and the images they
//! take, measured by relative rotations between images.

use crate::error::{Error, Result};
use crate::multiple::anisotropic::{Information, chordal_cost_compensated, chordal_term};
use crate::multiple::{Edge, MultipleProblem};
use crate::so3::{Rotation, nearest_rotation};
use serde::{Deserialize, Serialize};

/// One sensor (camera) of a rig: its `sensor_from_rig` rotation `S_s`, known or unknown.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Sensor {
    /// `S_s` when it is known (held, never estimated); `None`: estimated.
    #[serde(with = "crate::so3::serde_rows::optional_rotation", default)]
    pub sensor_from_rig: Option<Rotation>,
}

/// One image: taken by `sensor` at `frame`, its absolute rotation `X = S_sensor F_frame`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Image {
    /// The frame (rig pose) index.
    pub frame: usize,
    /// The sensor index.
    pub sensor: usize,
}

/// A rig problem: `num_frames` unknown frame rotations `F_f`, sensors with `sensor_from_rig`
/// rotations `S_s` (known or unknown), images `a = (f_a, s_a)` with absolute rotations
/// `X_a = S_{s_a} F_{f_a}` (world-to-camera, contract section 5), and edges between images
/// (`i`, `j` index [`Self::images`]) with `R_ab X_a ~ X_b`. Edges may join images of any two
/// sensors and any two frames (two images of one frame measure the sensors only). Chordal cost
/// `J(F, S) = sum w ||S_{s_b} F_{f_b} - R_ab S_{s_a} F_{f_a}||_F^2`.
///
/// Gauges: `F -> F G` (fixed by `F_0 = I`) and, for each rig (a set of frames and sensors joined
/// by images) with no known sensor, `S -> S H`, `F -> H^T F`, fixed by holding that rig's first
/// sensor at the identity, as COLMAP's reference sensor ([`Self::held`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RigData")]
pub struct RigProblem {
    num_frames: usize,
    sensors: Vec<Sensor>,
    images: Vec<Image>,
    edges: Vec<Edge>,
    #[serde(skip)]
    held: Vec<Option<Rotation>>,
    /// Gravity priors on the images (`[G14]`, [`Self::with_gravity`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(super) gravity: Option<crate::multiple::gravity::GravityPriors>,
    /// One information matrix per edge, for anisotropic measurements (`[H24]`,
    /// [`Self::with_information`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    information: Option<Vec<Information>>,
}

/// A rig problem as read (validated into a [`RigProblem`] on deserialisation).
#[derive(Deserialize)]
struct RigData {
    num_frames: usize,
    sensors: Vec<Sensor>,
    images: Vec<Image>,
    edges: Vec<Edge>,
    #[serde(default)]
    gravity: Option<crate::multiple::gravity::GravityPriors>,
    #[serde(default)]
    information: Option<Vec<Information>>,
}

impl TryFrom<RigData> for RigProblem {
    type Error = Error;
    fn try_from(d: RigData) -> Result<Self> {
        let mut p = RigProblem::new(d.num_frames, d.sensors, d.images, d.edges)?;
        if let Some(info) = d.information {
            p = p.with_information(info)?;
        }
        match d.gravity {
            Some(g) => p.with_gravity(g),
            None => Ok(p),
        }
    }
}

impl RigProblem {
    /// A validated rig problem. Known `sensor_from_rig` rotations are projected to the nearest
    /// rotation. Errors: no frames or no edges, an image's frame or sensor out of range, two
    /// images of one sensor at one frame, an edge's image out of range, a self loop, a weight
    /// that is not finite and positive, a non-finite rotation.
    ///
    /// ```
    /// use rotavg::multiple::Edge;
    /// use rotavg::rig::{Image, RigProblem, Sensor};
    /// use rotavg::Rotation;
    /// let sensors = vec![Sensor { sensor_from_rig: None }; 2];
    /// let images = vec![Image { frame: 0, sensor: 0 }, Image { frame: 0, sensor: 1 }];
    /// let e = Edge { i: 0, j: 1, rotation: Rotation::identity(), weight: 1.0 };
    /// let p = RigProblem::new(1, sensors, images, vec![e])?;
    /// // sensor 0 is the rig's reference: held at the identity
    /// assert_eq!(p.held()[0], Some(Rotation::identity()));
    /// assert_eq!(p.held()[1], None);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn new(
        num_frames: usize,
        sensors: Vec<Sensor>,
        images: Vec<Image>,
        edges: Vec<Edge>,
    ) -> Result<Self> {
        check_images(num_frames, sensors.len(), &images)?;
        // the edges as a view graph over the images: the same checks as `multiple`'s
        MultipleProblem::new(images.len(), edges.clone())?;
        let sensors: Vec<Sensor> = sensors
            .into_iter()
            .map(|s| Sensor {
                sensor_from_rig: s.sensor_from_rig.as_ref().map(nearest_rotation),
            })
            .collect();
        let held = held_sensors(num_frames, &sensors, &images);
        Ok(RigProblem {
            num_frames,
            sensors,
            images,
            edges,
            held,
            gravity: None,
            information: None,
        })
    }

    /// The same rig with anisotropic measurements (`paper-notes/conjugate.md` `[H24]`): one
    /// information matrix `H` per edge, in edge order, for the residual of contract section 1
    /// between the edge's images (`X_b X_a^T = R_ab exp([e]x)`). The cost becomes the anisotropic
    /// chordal cost `sum 4 (tr M - <R_ab M, X_b X_a^T>)`, `M = tr(H)/2 I - H`; each edge's weight
    /// becomes `tr(H) / 3`, which only starts the solver. Information that is exactly `w I` on
    /// every edge is scalar weights `w` (as [`MultipleProblem::with_information`]). Errors: a
    /// count that differs from the edges', gravity priors (not supported with information).
    ///
    /// ```
    /// use rotavg::multiple::anisotropic::Information;
    /// use rotavg::rig::RigScene;
    /// use nalgebra::{Matrix3, Vector3};
    /// let (p, truth) = RigScene { frames: 20, sensors: 2, noise_sigma: 0.0, ..Default::default() }.generate();
    /// let h = Information::new(Matrix3::from_diagonal(&Vector3::new(1.0, 4.0, 100.0)))?;
    /// let m = p.edges().len();
    /// let p = p.with_information(vec![h; m])?;
    /// assert!(p.is_anisotropic());
    /// assert!(p.cost(&truth.frames, &truth.sensors).abs() < 1e-9); // noise-free
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn with_information(mut self, information: Vec<Information>) -> Result<Self> {
        let graph = MultipleProblem::new(self.images.len(), self.edges.clone())?
            .with_information(information)?;
        self.edges = graph.edges().to_vec();
        self.information = graph.information().map(<[Information]>::to_vec);
        Ok(self)
    }

    /// The information matrices, one per edge, when the measurements are anisotropic.
    pub fn information(&self) -> Option<&[Information]> {
        self.information.as_deref()
    }

    /// `true` when the edges carry information matrices ([`Self::with_information`]).
    pub fn is_anisotropic(&self) -> bool {
        self.information.is_some()
    }

    /// The same rig measured by the edges whose `keep` entry is `true`, with their information
    /// (and the gravity priors). Panics if `keep.len()` differs from the number of edges.
    /// Errors: those of [`Self::new`] (none kept).
    pub fn edge_subset(&self, keep: &[bool]) -> Result<Self> {
        assert_eq!(keep.len(), self.edges.len(), "one flag per edge");
        let kept = |k: &usize| keep[*k];
        let edges = (0..self.edges.len())
            .filter(kept)
            .map(|k| self.edges[k].clone())
            .collect();
        let p = self.scalar().with_edges(edges)?;
        match &self.information {
            Some(info) => {
                p.with_information((0..info.len()).filter(kept).map(|k| info[k]).collect())
            }
            None => Ok(p),
        }
    }

    /// The same rig without the images that no edge measures, the held sensors unchanged
    /// (`paper-notes/conjugate.md` `[H19]` "Unmeasured images"): `J(F, S)` is the same function
    /// of the same unknowns, so a bound of one is a bound of the other, while an unmeasured
    /// image, a node without edges, leaves the images' view graphs a null direction that no
    /// certificate of theirs can pay for. `None` when every image is measured, and for rigs
    /// with gravity priors (a prior measures its image).
    pub(crate) fn without_unmeasured_images(&self) -> Option<Self> {
        if self.gravity.is_some() {
            return None;
        }
        let mut index = vec![None; self.images.len()];
        for e in &self.edges {
            index[e.i] = Some(0);
            index[e.j] = Some(0);
        }
        let mut images = Vec::with_capacity(self.images.len());
        for (k, im) in self.images.iter().enumerate() {
            if index[k].is_some() {
                index[k] = Some(images.len());
                images.push(*im);
            }
        }
        if images.len() == self.images.len() {
            return None;
        }
        let at = |k: usize| index[k].unwrap_or(usize::MAX);
        let edges = (self.edges.iter())
            .map(|e| Edge {
                i: at(e.i),
                j: at(e.j),
                ..e.clone()
            })
            .collect();
        Some(RigProblem {
            num_frames: self.num_frames,
            sensors: self.sensors.clone(),
            images,
            edges,
            held: self.held.clone(),
            gravity: None,
            information: self.information.clone(),
        })
    }

    /// The same rig with scalar weights: the information dropped, each edge weighing
    /// `tr(H) / 3` (itself when it has none).
    pub fn scalar(&self) -> Self {
        RigProblem {
            information: None,
            ..self.clone()
        }
    }

    /// The same rig (and gravity priors) measured by `edges` instead, with their scalar
    /// weights (validated as by [`Self::new`]; the information, if any, is not carried:
    /// [`Self::edge_subset`] keeps it).
    pub fn with_edges(&self, edges: Vec<Edge>) -> Result<Self> {
        let p = RigProblem::new(
            self.num_frames,
            self.sensors.clone(),
            self.images.clone(),
            edges,
        )?;
        match &self.gravity {
            Some(g) => p.with_gravity(g.clone()),
            None => Ok(p),
        }
    }

    /// The same rig (and gravity priors) with every sensor held at `sensors` (one per sensor;
    /// the held ones keep their rotations): the rig of a calibration, for gravity priors on a
    /// rig whose sensors were estimated (`[G14]`). Errors: a count that differs.
    pub fn with_sensors_held(&self, sensors: &[Rotation]) -> Result<Self> {
        if sensors.len() != self.sensors.len() {
            return Err(Error::InvalidSettings {
                name: "sensors".into(),
                reason: format!(
                    "{} sensor rotations for a rig of {} sensors",
                    sensors.len(),
                    self.sensors.len()
                ),
            });
        }
        let known = (self.held.iter().zip(sensors))
            .map(|(h, s)| Sensor {
                sensor_from_rig: Some(h.unwrap_or(*s)),
            })
            .collect();
        let mut p = RigProblem::new(
            self.num_frames,
            known,
            self.images.clone(),
            self.edges.clone(),
        )?;
        p.information = self.information.clone();
        match &self.gravity {
            Some(g) => p.with_gravity(g.clone()),
            None => Ok(p),
        }
    }

    /// Number of frames.
    pub fn num_frames(&self) -> usize {
        self.num_frames
    }

    /// The sensors as given.
    pub fn sensors(&self) -> &[Sensor] {
        &self.sensors
    }

    /// The images.
    pub fn images(&self) -> &[Image] {
        &self.images
    }

    /// The edges between images.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// The sensors held fixed, by index: the known ones, and the first sensor of every rig
    /// without a known one, at the identity (the gauge). `None`: estimated.
    pub fn held(&self) -> &[Option<Rotation>] {
        &self.held
    }

    /// The sensors to estimate (not [`RigProblem::held`]), by increasing index.
    pub fn estimated_sensors(&self) -> Vec<usize> {
        (0..self.held.len())
            .filter(|&s| self.held[s].is_none())
            .collect()
    }

    /// `sensors` (one per sensor) with the held ones at their held rotations: an estimate as the
    /// problem poses it (its held sensors within rounding of them); as long as the shorter of
    /// `sensors` and the problem's sensors.
    pub fn at_held(&self, sensors: &[Rotation]) -> Vec<Rotation> {
        (sensors.iter().zip(&self.held))
            .map(|(s, held)| held.unwrap_or(*s))
            .collect()
    }

    /// Every sensor is held: the frames alone are unknown, and the problem is one view graph
    /// over them ([`Self::frame_graph`], `[H19]`).
    pub fn all_held(&self) -> bool {
        self.held.iter().all(Option::is_some)
    }

    /// The smallest weight of any edge or soft gravity prior (the tolerance's `w_min`); with
    /// information, the smallest positive eigenvalue of any `H` (contract section 3).
    pub fn min_weight(&self) -> f64 {
        if let Some(info) = &self.information {
            return crate::validate::min_weight(
                info.iter().map(Information::min_positive_eigenvalue),
            );
        }
        let priors = self
            .gravity
            .iter()
            .flat_map(|g| (0..self.images.len()).filter_map(|a| g.prior_weight(a)));
        self.edges
            .iter()
            .map(|e| e.weight)
            .chain(priors)
            .fold(f64::INFINITY, f64::min)
    }

    /// The absolute rotations `X_a = S_{s_a} F_{f_a}` of the images.
    pub fn image_rotations(&self, frames: &[Rotation], sensors: &[Rotation]) -> Vec<Rotation> {
        self.images
            .iter()
            .map(|im| sensors[im.sensor] * frames[im.frame])
            .collect()
    }

    /// The chordal cost `J(F, S)`, plus the soft gravity priors' terms when it has them
    /// ([`Self::prior_cost`]).
    pub fn cost(&self, frames: &[Rotation], sensors: &[Rotation]) -> f64 {
        let x = self.image_rotations(frames, sensors);
        let edges = match &self.information {
            Some(info) => chordal_cost_compensated(&self.edges, info, &x),
            None => (self.edges.iter())
                .map(|e| {
                    let r = x[e.j].matrix() - e.rotation.matrix() * x[e.i].matrix();
                    e.weight * r.norm_squared()
                })
                .sum(),
        };
        edges + self.prior_cost(frames, sensors)
    }

    /// The frames' view graph at fixed sensors `S` (`[H19]`): each edge between images of two
    /// frames as the frame edge `S_b^T R_ab S_a` (`||S_b F_b - R S_a F_a|| = ||F_b - S_b^T R S_a
    /// F_a||`), with information `S_a^T H S_a` when it has some (`[H24]`), and the cost of the
    /// edges within one frame, which `F` does not change. Errors: no edge joins two frames.
    pub fn frame_graph(&self, sensors: &[Rotation]) -> Result<(MultipleProblem, f64)> {
        self.frames_graph(sensors, true)
    }

    /// [`Self::frame_graph`] for a solve: the turned information's eigenvalues are taken from
    /// `H` ([`Information::turned_for_solve`]) instead of computed again; never certified.
    pub(crate) fn frame_graph_for_solve(
        &self,
        sensors: &[Rotation],
    ) -> Result<(MultipleProblem, f64)> {
        self.frames_graph(sensors, false)
    }

    /// [`Self::frame_graph`], the turned information validated again when `checked`.
    fn frames_graph(&self, sensors: &[Rotation], checked: bool) -> Result<(MultipleProblem, f64)> {
        let (mut edges, mut info, mut constant) = (Vec::new(), Vec::new(), 0.0);
        for (k, e) in self.edges.iter().enumerate() {
            let (a, b) = (self.images[e.i], self.images[e.j]);
            let (sa, sb) = (sensors[a.sensor], sensors[b.sensor]);
            let h = self.information.as_ref().map(|i| i[k]);
            if a.frame == b.frame {
                constant += match &h {
                    Some(h) => chordal_term(h, &e.rotation, &sa, &sb),
                    None => {
                        e.weight * (sb.matrix() - e.rotation.matrix() * sa.matrix()).norm_squared()
                    }
                };
                continue;
            }
            if let Some(h) = h {
                info.push(match checked {
                    true => {
                        let turned = sa.matrix().transpose() * h.matrix() * sa.matrix();
                        Information::new((turned + turned.transpose()) * 0.5)?
                    }
                    false => h.turned_for_solve(&sa),
                });
            }
            edges.push(Edge {
                i: a.frame,
                j: b.frame,
                rotation: sb.inverse() * e.rotation * sa,
                weight: e.weight,
            });
        }
        let graph = MultipleProblem::new(self.num_frames, edges)?;
        let graph = match self.information {
            Some(_) => graph.with_information(info)?,
            None => graph,
        };
        Ok((graph, constant))
    }

    /// The view graph over the images, with the rig's constraints dropped (`[H19]`'s
    /// relaxation): its chordal cost at `X = S F` is `J(F, S)`.
    pub fn image_graph(&self) -> Result<MultipleProblem> {
        let graph = MultipleProblem::new(self.images.len(), self.edges.clone())?;
        match &self.information {
            Some(info) => graph.with_information(info.clone()),
            None => Ok(graph),
        }
    }

    /// The angles a robust loss and the inlier threshold apply to, per edge, radians: each
    /// edge's residual angle, or with information its Mahalanobis angle
    /// `sqrt(e^T H e / (tr(H) / 3))` (`[A10]`), at `(frames, sensors)`.
    pub fn objective_angles(&self, frames: &[Rotation], sensors: &[Rotation]) -> Vec<f64> {
        let graph = self.image_graph().ok().filter(|_| self.is_anisotropic());
        match graph {
            Some(g) => g.objective_angles(&self.image_rotations(frames, sensors)),
            None => super::robust::residual_angles(self, frames, sensors),
        }
    }

    /// The images of a rig of `frames` frames in which every one of `sensors` sensors
    /// photographs every frame: image `f * sensors + s` is sensor `s` at frame `f`.
    pub fn full_images(frames: usize, sensors: usize) -> Vec<Image> {
        (0..frames)
            .flat_map(|frame| (0..sensors).map(move |sensor| Image { frame, sensor }))
            .collect()
    }
}

/// Every image's frame and sensor in range, at most one image per (frame, sensor).
fn check_images(num_frames: usize, num_sensors: usize, images: &[Image]) -> Result<()> {
    if num_frames == 0 || num_sensors == 0 {
        return Err(Error::Empty {
            what: "the rig (no frames or no sensors)".into(),
        });
    }
    let mut seen = std::collections::HashSet::new();
    for (k, im) in images.iter().enumerate() {
        if im.frame >= num_frames || im.sensor >= num_sensors {
            return Err(Error::InvalidSettings {
                name: "rig images".into(),
                reason: format!(
                    "image {k} has frame {} and sensor {}: the rig has {num_frames} frames and \
                     {num_sensors} sensors",
                    im.frame, im.sensor
                ),
            });
        }
        if !seen.insert((im.frame, im.sensor)) {
            return Err(Error::InvalidSettings {
                name: "rig images".into(),
                reason: format!(
                    "image {k} is a second image of sensor {} at frame {}",
                    im.sensor, im.frame
                ),
            });
        }
    }
    Ok(())
}

/// The held sensors: the known ones, and the first sensor of every rig (component of frames and
/// sensors joined by images) without one, at the identity.
fn held_sensors(num_frames: usize, sensors: &[Sensor], images: &[Image]) -> Vec<Option<Rotation>> {
    // the rigs: components of frames 0..F and sensors F..F+K joined by images
    let mut rigs = crate::multiple::union_find::UnionFind::new(num_frames + sensors.len());
    for im in images {
        rigs.union(im.frame, num_frames + im.sensor);
    }
    let mut held: Vec<Option<Rotation>> = sensors.iter().map(|s| s.sensor_from_rig).collect();
    let mut anchored = std::collections::HashSet::new();
    for (s, h) in held.iter().enumerate() {
        if h.is_some() {
            anchored.insert(rigs.find(num_frames + s));
        }
    }
    for (s, h) in held.iter_mut().enumerate() {
        if anchored.insert(rigs.find(num_frames + s)) {
            *h = Some(Rotation::identity());
        }
    }
    held
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    /// Without its unmeasured images a rig has fewer images, the same held sensors and the same
    /// cost at any point (scalar weights and information); fully measured rigs are left as
    /// they are.
    #[test]
    fn unmeasured_images_leave_the_same_cost() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        for anisotropy in [1.0, 9.0] {
            let scene = crate::rig::RigScene {
                frames: 20,
                sensors: 3,
                anisotropy,
                ..Default::default()
            };
            let (full, _) = scene.generate();
            assert!(full.without_unmeasured_images().is_none());
            let gone = [4, 31];
            let keep: Vec<bool> = (full.edges().iter())
                .map(|e| !gone.contains(&e.i) && !gone.contains(&e.j))
                .collect();
            let p = full.edge_subset(&keep).unwrap();
            let q = p.without_unmeasured_images().unwrap();
            assert_eq!(q.images().len(), p.images().len() - 2);
            assert_eq!((q.edges().len(), q.held()), (p.edges().len(), p.held()));
            assert!(!q.images().contains(&p.images()[4]));
            for _ in 0..3 {
                let frames: Vec<Rotation> = (0..20)
                    .map(|_| crate::so3::random_rotation(&mut rng))
                    .collect();
                let sensors: Vec<Rotation> = (0..3)
                    .map(|_| crate::so3::random_rotation(&mut rng))
                    .collect();
                let (a, b) = (p.cost(&frames, &sensors), q.cost(&frames, &sensors));
                assert!((a - b).abs() <= 1e-12 * a, "{a} against {b}");
            }
        }
    }
}
