//! Seeded rigs with planted frames and sensors (`[H19]`).

use super::problem::{RigProblem, Sensor};
use crate::multiple::Edge;
use crate::multiple::anisotropic::Information;
use crate::so3::{Rotation, perturb_gaussian, random_rotation};
use nalgebra::{Matrix3, Vector3};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

/// A generated rig: `frames` frames with random rotations, `sensors` sensors (sensor 0 the
/// reference, `S_0 = I`; the others random), every sensor photographing every frame. Each
/// sensor's images are joined along the frame sequence (`f`, `f + 1`) and by
/// `extra_edges_per_frame` random frame pairs (within `extra_edge_span` frames of each other, or
/// any two frames when it is 0); a fraction `cross_fraction` of frames adds an
/// edge from the reference sensor's image to another sensor's, of the same frame or of a random
/// one. Measurements are perturbed by Gaussian noise of `noise_sigma` radians; a fraction
/// `outlier_fraction` replaced by random rotations. With `known`, every sensor's
/// `sensor_from_rig` is given. With `anisotropy` above 1 the edges carry information matrices
/// (`[H24]`, issue 37's two-view-like class): each edge's residual has standard deviations
/// `sigma`, `sigma` and `anisotropy exp(z) sigma` (`z` standard normal, at least `sigma`) along
/// the axes of a random frame, `sigma = noise_sigma` (0.01 rad for the information of a
/// noise-free scene), and its information is the inverse covariance; outliers keep theirs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RigScene {
    /// Frames.
    pub frames: usize,
    /// Sensors.
    pub sensors: usize,
    /// Random same-sensor edges per frame, besides the sequence's.
    pub extra_edges_per_frame: usize,
    /// The largest frame distance of those edges; 0 (default): any two frames (a view graph
    /// without locality, the hardest for the certificate's factorisations). A capture along a
    /// path sees its neighbours: e.g. 10, with the cross-sensor edges to random frames as its
    /// revisits.
    pub extra_edge_span: usize,
    /// Fraction of frames with an edge between two sensors.
    pub cross_fraction: f64,
    /// Gaussian noise, radians.
    pub noise_sigma: f64,
    /// Fraction of edges replaced by outliers: random rotations, or see `outlier_angle_deg`.
    pub outlier_fraction: f64,
    /// `Some((lo, hi))`: each outlier is its edge's true rotation turned by an angle uniform in
    /// `lo..hi` degrees about a random axis (the wrong pairs repeated structure makes: a few
    /// degrees to tens off, with the information of an inlier), instead of a random rotation.
    pub outlier_angle_deg: Option<(f64, f64)>,
    /// Every sensor's `sensor_from_rig` given.
    pub known: bool,
    /// The weak axis's standard deviation over the others' (median), above 1 for information
    /// matrices; 1 (default): scalar weights 1.
    pub anisotropy: f64,
    /// Seed.
    pub seed: u64,
}

impl Default for RigScene {
    fn default() -> Self {
        RigScene {
            frames: 100,
            sensors: 3,
            extra_edges_per_frame: 2,
            extra_edge_span: 0,
            cross_fraction: 0.3,
            noise_sigma: 0.01,
            outlier_fraction: 0.0,
            outlier_angle_deg: None,
            known: false,
            anisotropy: 1.0,
            seed: 0,
        }
    }
}

/// The planted rig: frames (`F_0 = I`) and sensors (`S_0 = I`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigTruth {
    /// `F_f`.
    #[serde(with = "crate::so3::serde_rows::rotations")]
    pub frames: Vec<Rotation>,
    /// `S_s`.
    #[serde(with = "crate::so3::serde_rows::rotations")]
    pub sensors: Vec<Rotation>,
}

impl RigScene {
    /// The default scene with `frames` frames, `sensors` sensors, `noise_sigma` radians of
    /// noise, every `sensor_from_rig` given or not (`known`), and `seed`.
    ///
    /// ```
    /// use rotavg::rig::RigScene;
    /// let s = RigScene::sized(20, 2, 0.0, true, 7);
    /// assert_eq!((s.frames, s.sensors, s.known, s.seed), (20, 2, true, 7));
    /// assert!(s.generate().0.all_held());
    /// ```
    pub fn sized(frames: usize, sensors: usize, noise_sigma: f64, known: bool, seed: u64) -> Self {
        RigScene {
            frames,
            sensors,
            noise_sigma,
            known,
            seed,
            ..Default::default()
        }
    }

    /// The problem and its planted truth. Panics only on an empty scene (fewer than 2 frames
    /// or no sensor), never on a seed.
    pub fn generate(&self) -> (RigProblem, RigTruth) {
        assert!(
            self.frames >= 2 && self.sensors >= 1,
            "a rig needs 2 frames and a sensor"
        );
        let mut rng = StdRng::seed_from_u64(self.seed);
        let (frames, sensors) = self.planted(&mut rng);
        let k = self.sensors;
        let images = RigProblem::full_images(self.frames, k);
        let mut edges = Vec::new();
        let mut information = Vec::new();
        let mut add = |rng: &mut StdRng, (fa, sa): (usize, usize), (fb, sb): (usize, usize)| {
            let xa = sensors[sa] * frames[fa];
            let xb = sensors[sb] * frames[fb];
            let exact = xb * xa.inverse();
            let outlier = rng.random::<f64>() < self.outlier_fraction;
            let rotation = if self.anisotropy > 1.0 {
                let (h, noise) = self.anisotropic_noise(rng);
                information.push(h);
                // X_b X_a^T = R exp([e]x)
                if outlier {
                    self.outlier(&exact, rng)
                } else {
                    exact * crate::so3::exp(&(-noise))
                }
            } else if outlier {
                self.outlier(&exact, rng)
            } else {
                perturb_gaussian(&exact, self.noise_sigma, rng)
            };
            edges.push(Edge {
                i: fa * k + sa,
                j: fb * k + sb,
                rotation,
                weight: 1.0,
            });
        };
        for s in 0..k {
            for f in 0..self.frames {
                if f + 1 < self.frames {
                    add(&mut rng, (f, s), (f + 1, s));
                }
                for _ in 0..self.extra_edges_per_frame {
                    let g = self.partner(f, &mut rng);
                    if g != f {
                        add(&mut rng, (f, s), (g, s));
                    }
                }
            }
        }
        for f in 0..self.frames {
            if k > 1 && rng.random::<f64>() < self.cross_fraction {
                let t = rng.random_range(1..k);
                let g = if rng.random::<bool>() {
                    f
                } else {
                    rng.random_range(0..self.frames)
                };
                add(&mut rng, (f, 0), (g, t));
            }
        }
        let sensor_list = sensors
            .iter()
            .map(|s| Sensor {
                sensor_from_rig: self.known.then_some(*s),
            })
            .collect();
        let mut problem = RigProblem::new(self.frames, sensor_list, images, edges)
            .expect("a generated rig is valid");
        if !information.is_empty() {
            problem = (problem.with_information(information)).expect("generated information");
        }
        (problem, RigTruth { frames, sensors })
    }

    /// An outlier in place of the edge whose true rotation is `exact`
    /// ([`RigScene::outlier_angle_deg`]).
    fn outlier(&self, exact: &Rotation, rng: &mut StdRng) -> Rotation {
        match self.outlier_angle_deg {
            None => random_rotation(rng),
            Some((lo, hi)) => {
                let axis = Vector3::from_fn(|_, _| crate::so3::gaussian(rng)).normalize();
                let angle = rng.random_range(lo..=hi).to_radians();
                crate::so3::exp(&(axis * angle)) * exact
            }
        }
    }

    /// A random frame for an extra edge from frame `f` ([`RigScene::extra_edge_span`]).
    fn partner(&self, f: usize, rng: &mut StdRng) -> usize {
        match self.extra_edge_span {
            0 => rng.random_range(0..self.frames),
            span => rng.random_range(f.saturating_sub(span)..=(f + span).min(self.frames - 1)),
        }
    }

    /// The planted frames (the first the identity) and sensors (sensor 0 the identity).
    fn planted(&self, rng: &mut StdRng) -> (Vec<Rotation>, Vec<Rotation>) {
        let mut frames: Vec<Rotation> = (0..self.frames).map(|_| random_rotation(rng)).collect();
        let f0 = frames[0].inverse();
        frames.iter_mut().for_each(|f| *f *= f0);
        let mut sensors: Vec<Rotation> = (0..self.sensors).map(|_| random_rotation(rng)).collect();
        sensors[0] = Rotation::identity();
        (frames, sensors)
    }

    /// One edge's information and residual (module docs, `anisotropy`).
    fn anisotropic_noise(&self, rng: &mut StdRng) -> (Information, Vector3<f64>) {
        let sigma = if self.noise_sigma > 0.0 {
            self.noise_sigma
        } else {
            0.01
        };
        let weak = (self.anisotropy * crate::so3::gaussian(rng).exp()).max(1.0) * sigma;
        let stds = Vector3::new(sigma, sigma, weak);
        let u = *random_rotation(rng).matrix();
        let h = u * Matrix3::from_diagonal(&stds.map(|s| 1.0 / (s * s))) * u.transpose();
        let h = Information::new(0.5 * (h + h.transpose())).expect("generated information");
        let z = Vector3::from_fn(|k, _| stds[k] * crate::so3::gaussian(rng));
        let noise = if self.noise_sigma > 0.0 {
            u * z
        } else {
            Vector3::zeros()
        };
        (h, noise)
    }
}

impl RigTruth {
    /// Gravity priors for `problem`'s images (`[G14]`): each image's true down direction
    /// `S_s F_f (0, 0, 1)` tilted by Gaussian noise of `sigma` radians per axis (seeded by
    /// `seed`), and none for every `without`-th image (`a % without == without - 1`; 0: every
    /// image has one). For [`crate::multiple::gravity::GravityPriors::new`].
    ///
    /// ```
    /// use rotavg::rig::RigScene;
    /// let (p, truth) = RigScene { frames: 10, sensors: 2, known: true, ..Default::default() }.generate();
    /// let g = truth.gravity(&p, 0.0, 4, 1);
    /// assert_eq!(g.iter().filter(|d| d.is_none()).count(), 5);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn gravity(
        &self,
        problem: &RigProblem,
        sigma: f64,
        without: usize,
        seed: u64,
    ) -> Vec<Option<[f64; 3]>> {
        let mut rng = StdRng::seed_from_u64(seed);
        (problem.images().iter().enumerate())
            .map(|(a, im)| {
                let x = self.sensors[im.sensor] * self.frames[im.frame];
                let tilt = perturb_gaussian(&Rotation::identity(), sigma, &mut rng);
                let g = tilt * (x * nalgebra::Vector3::z());
                (without == 0 || a % without != without - 1).then(|| g.into())
            })
            .collect()
    }
}
