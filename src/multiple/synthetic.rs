//! Seeded synthetic view graphs with a planted ground truth, for tests, benchmarks and the demo:
//! [`SyntheticGraph::generate`] (random connected graph, Gaussian noise, outliers) and
//! [`SyntheticAnisotropic::generate`] (the same with anisotropic noise and its information matrices),
//! [`SyntheticChain::generate`] (a SLAM-like trajectory: an odometry chain with loop closures,
//! planar or 3-D), [`SyntheticGrid::generate`] (a robot sweeping a planar grid or torus, loop
//! closures between spatially adjacent poses) and [`z_cycle`] (a cycle with a known loop error, whose local minima are known
//! in closed form).

use crate::multiple::anisotropic::Information;
use crate::multiple::{Edge, MultipleProblem};
use crate::so3::{Rotation, exp, perturb_gaussian, random_rotation};
use nalgebra::{Matrix3, Vector3};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

/// Parameters of a random connected view graph with planted rotations.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SyntheticGraph {
    /// Number of nodes (>= 2).
    pub num_rotations: usize,
    /// Total number of edges (at least `num_rotations - 1`; a random spanning tree is always
    /// included so the graph is connected; extra edges join uniformly random distinct pairs,
    /// multi-edges possible).
    pub num_edges: usize,
    /// Gaussian noise per tangent component on every edge, radians.
    pub noise_sigma: f64,
    /// Fraction of edges replaced by uniformly random rotations (outliers), in `[0, 1]`.
    pub outlier_fraction: f64,
    /// RNG seed.
    pub seed: u64,
}

impl Default for SyntheticGraph {
    fn default() -> Self {
        SyntheticGraph {
            num_rotations: 100,
            num_edges: 300,
            noise_sigma: 0.05,
            outlier_fraction: 0.0,
            seed: 0,
        }
    }
}

impl SyntheticGraph {
    /// Generate `(problem, ground truth)`; the ground truth has `R_0 = I`. Unit weights.
    ///
    /// ```
    /// use rotavg::multiple::synthetic::SyntheticGraph;
    /// let (p, gt) = SyntheticGraph { num_rotations: 10, num_edges: 20, noise_sigma: 0.0, ..Default::default() }.generate();
    /// assert!(p.chordal_cost(&gt) < 1e-20);
    /// ```
    pub fn generate(&self) -> (MultipleProblem, Vec<Rotation>) {
        let (problem, truth, _) = self.generate_labelled();
        (problem, truth)
    }

    /// [`Self::generate`] (the same graph for the same parameters) with, per edge, whether it
    /// is a planted outlier (its measurement a uniformly random rotation).
    ///
    /// ```
    /// use rotavg::multiple::synthetic::SyntheticGraph;
    /// let spec = SyntheticGraph { outlier_fraction: 0.2, ..Default::default() };
    /// let (p, gt, outlier) = spec.generate_labelled();
    /// assert_eq!((p.clone(), gt.clone()), spec.generate());
    /// let k = outlier.iter().filter(|&&o| o).count();
    /// assert!(k > 30 && k < 90, "{k} of 300 edges"); // about 20 %
    /// ```
    pub fn generate_labelled(&self) -> (MultipleProblem, Vec<Rotation>, Vec<bool>) {
        let (n, mut rng, gt, pairs) = planted_graph(self.num_rotations, self.num_edges, self.seed);
        let mut outlier = Vec::with_capacity(pairs.len());
        let edges = pairs
            .into_iter()
            .map(|(i, j)| {
                let is_outlier = rng.random::<f64>() < self.outlier_fraction;
                outlier.push(is_outlier);
                let rotation = if is_outlier {
                    random_rotation(&mut rng)
                } else {
                    perturb_gaussian(&(gt[j] * gt[i].inverse()), self.noise_sigma, &mut rng)
                };
                Edge {
                    i,
                    j,
                    rotation,
                    weight: 1.0,
                }
            })
            .collect();
        (
            MultipleProblem::new(n, edges).expect("generated graph is valid"),
            gt,
            outlier,
        )
    }
}

/// The planted part of [`SyntheticGraph`] and [`SyntheticAnisotropic`]: `n = max(2, nodes)`,
/// the RNG seeded with `seed`, uniformly random ground truth with `R_0 = I`, and the node pairs
/// of a random connected graph with `max(edges, n - 1)` edges ([`random_connected_pairs`]); the
/// RNG continues from there.
fn planted_graph(
    nodes: usize,
    edges: usize,
    seed: u64,
) -> (usize, StdRng, Vec<Rotation>, Vec<(usize, usize)>) {
    let n = nodes.max(2);
    let mut rng = StdRng::seed_from_u64(seed);
    let mut gt: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
    crate::multiple::fix_gauge(&mut gt);
    let pairs = random_connected_pairs(n, edges.max(n - 1), &mut rng);
    (n, rng, gt, pairs)
}

/// Parameters of a SLAM trajectory ([`SyntheticChain`]'s: odometry and loop closures) whose
/// measurements carry anisotropic noise and information as [`SyntheticAnisotropic`]'s
/// (`noise.num_edges` is not used).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SyntheticAnisotropicSlam {
    /// Noise, information and seed (`num_rotations` poses).
    pub noise: SyntheticAnisotropic,
    /// Loop closures per pose.
    pub loop_closure_fraction: f64,
    /// Standard deviation of each turn of the heading, radians.
    pub turn_sigma: f64,
}

impl SyntheticAnisotropicSlam {
    /// Issue 37's strongly anisotropic SLAM information: a trajectory of `num_rotations` poses
    /// with 5 % loop closures, 0.005 degrees along one well-determined axis per edge and two
    /// weak axes whose standard-deviation ratio is log-normal around 300 (`ratio_spread` 1: the
    /// weak axes' deviations mostly 0.5 to 4 degrees, eigenvalue ratios from about 1e4 to 1e6,
    /// every `M` indefinite), random axes, no outliers.
    ///
    /// ```
    /// use rotavg::multiple::synthetic::SyntheticAnisotropicSlam;
    /// let (p, _) = SyntheticAnisotropicSlam::strongly_anisotropic(300, 1).generate();
    /// let mut ratios: Vec<f64> = p.information().unwrap().iter().map(|h| h.anisotropy()).collect();
    /// ratios.sort_by(f64::total_cmp);
    /// let median = ratios[ratios.len() / 2];
    /// assert!(median > 3e4 && median < 3e5, "{median}");
    /// assert_eq!(p.num_edges(), 299 + 15); // odometry and 5 % closures
    /// ```
    pub fn strongly_anisotropic(num_rotations: usize, seed: u64) -> Self {
        SyntheticAnisotropicSlam {
            noise: SyntheticAnisotropic {
                num_rotations,
                sigma: 0.005f64.to_radians(),
                ratio: 300.0,
                ratio_spread: 1.0,
                weak_axes: 2,
                seed,
                ..Default::default()
            },
            loop_closure_fraction: 0.05,
            turn_sigma: 0.1,
        }
    }

    /// Generate `(problem, ground truth)`; the ground truth has `R_0 = I`. Panics on settings
    /// [`SyntheticAnisotropic::generate`] refuses.
    pub fn generate(&self) -> (MultipleProblem, Vec<Rotation>) {
        let (p, gt) = SyntheticChain {
            num_rotations: self.noise.num_rotations,
            loop_closure_fraction: self.loop_closure_fraction,
            turn_sigma: self.turn_sigma,
            noise_sigma: 0.0,
            planar: false,
            seed: self.noise.seed,
        }
        .generate();
        let pairs = p.edges().iter().map(|e| (e.i, e.j)).collect();
        // the noise seeded apart from the trajectory
        let rng = StdRng::seed_from_u64(self.noise.seed ^ 0x5eed_a150);
        self.noise.measure(gt.len(), rng, gt, pairs)
    }
}

/// `m >= n - 1` node pairs of a random connected graph on `n >= 2` nodes: a random spanning tree
/// (node `order[k]` attached to a random earlier one), then uniformly random distinct pairs
/// (multi-edges possible).
fn random_connected_pairs(n: usize, m: usize, rng: &mut StdRng) -> Vec<(usize, usize)> {
    let mut pairs = Vec::with_capacity(m);
    let mut order: Vec<usize> = (0..n).collect();
    for k in (1..n).rev() {
        let j = rng.random_range(0..=k);
        order.swap(k, j);
    }
    for k in 1..n {
        let parent = order[rng.random_range(0..k)];
        pairs.push((parent, order[k]));
    }
    while pairs.len() < m {
        let i = rng.random_range(0..n);
        let j = rng.random_range(0..n);
        if i != j {
            pairs.push((i, j));
        }
    }
    pairs
}

/// Parameters of a random connected view graph with **anisotropic** noise and its information
/// matrices (`paper-notes/anisotropic.md` `[A1]`): each edge's residual `e` (with `R_j R_i^T =
/// R_ij exp([e]x)`) is Gaussian with standard deviations `sigma`, `sigma` and `ratio * sigma`
/// along the axes of a frame `U_e` (one weak axis), or `sigma`, `ratio * sigma`, `ratio * sigma`
/// (`weak_axes = 2`: one well-determined axis), and its information is the inverse covariance,
/// e.g. `H_e = U_e diag(1, 1, 1 / ratio^2) U_e^T / sigma^2`. With two weak axes and `ratio >
/// sqrt(2)` every `M_e` is indefinite: the data on which the `O(3)` relaxation can prefer
/// reflections `[A5]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SyntheticAnisotropic {
    /// Number of nodes (>= 2).
    pub num_rotations: usize,
    /// Total number of edges (a random spanning tree plus random pairs, as [`SyntheticGraph`]).
    pub num_edges: usize,
    /// Standard deviation along the two well-determined axes, radians (> 0).
    pub sigma: f64,
    /// Standard deviation of the weak axis over `sigma` (>= 1; 1 is isotropic).
    pub ratio: f64,
    /// `true`: a uniformly random frame `U_e` per edge; `false`: the weak axis is the z axis of
    /// the measurement's frame for every edge (`U_e = I`).
    pub random_axes: bool,
    /// Fraction of edges replaced by uniformly random rotations (their information kept).
    pub outlier_fraction: f64,
    /// RNG seed.
    pub seed: u64,
    /// Axes whose standard deviation is `ratio * sigma`: 1 (default) or 2.
    #[serde(default = "one_weak_axis")]
    pub weak_axes: usize,
    /// Log-normal spread of the ratio over the edges: edge `e`'s ratio is
    /// `max(1, ratio exp(ratio_spread z_e))` with `z_e` standard normal (default 0: every edge
    /// has `ratio`). Ratio 9 with spread 1 models two-view information from correspondences
    /// (issue 37: standard-deviation ratios log-normal around 9 with a tail to a few hundred,
    /// eigenvalue ratios around 100 with a tail past 10^4).
    #[serde(default)]
    pub ratio_spread: f64,
}

fn one_weak_axis() -> usize {
    1
}

impl Default for SyntheticAnisotropic {
    fn default() -> Self {
        SyntheticAnisotropic {
            num_rotations: 100,
            num_edges: 400,
            sigma: 0.5f64.to_radians(),
            ratio: 10.0,
            random_axes: true,
            outlier_fraction: 0.0,
            seed: 0,
            weak_axes: 1,
            ratio_spread: 0.0,
        }
    }
}

impl SyntheticAnisotropic {
    /// Generate `(problem, ground truth)`; the ground truth has `R_0 = I`. Panics if `sigma` is
    /// not finite and positive, `ratio < 1` or `weak_axes` is not 1 or 2 (settings of a test,
    /// not user data).
    ///
    /// ```
    /// use rotavg::multiple::synthetic::SyntheticAnisotropic;
    /// let (p, gt) = SyntheticAnisotropic { num_rotations: 10, num_edges: 20, ..Default::default() }.generate();
    /// assert!(p.is_anisotropic());
    /// let h = p.information().unwrap()[0].matrix().symmetric_eigenvalues();
    /// assert!((h.max() / h.min() - 100.0).abs() < 1e-6); // ratio 10 in standard deviation
    /// ```
    pub fn generate(&self) -> (MultipleProblem, Vec<Rotation>) {
        let (n, rng, gt, pairs) = planted_graph(self.num_rotations, self.num_edges, self.seed);
        self.measure(n, rng, gt, pairs)
    }

    /// The anisotropic measurements of `pairs` of the planted rotations `gt`, with their
    /// information.
    fn measure(
        &self,
        n: usize,
        mut rng: StdRng,
        gt: Vec<Rotation>,
        pairs: Vec<(usize, usize)>,
    ) -> (MultipleProblem, Vec<Rotation>) {
        assert!(self.sigma.is_finite() && self.sigma > 0.0 && self.ratio >= 1.0);
        assert!(matches!(self.weak_axes, 1 | 2), "weak_axes is 1 or 2");
        let mut edges = Vec::with_capacity(pairs.len());
        let mut information = Vec::with_capacity(pairs.len());
        for (i, j) in pairs {
            let frame = if self.random_axes {
                random_rotation(&mut rng)
            } else {
                Rotation::identity()
            };
            let ratio = if self.ratio_spread > 0.0 {
                let z = crate::so3::gaussian(&mut rng);
                (self.ratio * (self.ratio_spread * z).exp()).max(1.0)
            } else {
                self.ratio
            };
            let stds = self.standard_deviations(ratio);
            let inverse_variances = stds.map(|s| 1.0 / (s * s));
            let u = frame.matrix();
            let h = u * Matrix3::from_diagonal(&inverse_variances) * u.transpose();
            let h = 0.5 * (h + h.transpose()); // exactly symmetric
            let is_outlier = rng.random::<f64>() < self.outlier_fraction;
            let rotation = if is_outlier {
                random_rotation(&mut rng)
            } else {
                let g = Vector3::from_fn(|k, _| stds[k] * crate::so3::gaussian(&mut rng));
                // R_j R_i^T = R_ij exp([e]x)  =>  R_ij = R_j R_i^T exp(-[e]x)
                gt[j] * gt[i].inverse() * exp(&(-(u * g)))
            };
            edges.push(Edge {
                i,
                j,
                rotation,
                weight: 1.0,
            });
            information.push(Information::new(h).expect("generated information is valid"));
        }
        let problem = MultipleProblem::new(n, edges)
            .and_then(|p| p.with_information(information))
            .expect("generated graph is valid");
        (problem, gt)
    }

    /// Issue 37's two-view-like anisotropy: 0.5 degrees along the well-determined axes, one weak
    /// axis whose standard-deviation ratio is log-normal around 9 (`ratio_spread` 1: eigenvalue
    /// ratios around 80 with a tail past 10^5), random axes, `outlier_fraction` of the edges
    /// random rotations with their information kept (confident wrong pairs), seed 1.
    ///
    /// ```
    /// use rotavg::multiple::synthetic::SyntheticAnisotropic;
    /// let spec = SyntheticAnisotropic::two_view_like(50, 200, 0.1);
    /// assert_eq!((spec.ratio, spec.ratio_spread, spec.seed), (9.0, 1.0, 1));
    /// assert!(spec.generate().0.is_anisotropic());
    /// ```
    pub fn two_view_like(num_rotations: usize, num_edges: usize, outlier_fraction: f64) -> Self {
        SyntheticAnisotropic {
            num_rotations,
            num_edges,
            ratio: 9.0,
            ratio_spread: 1.0,
            outlier_fraction,
            seed: 1,
            ..Default::default()
        }
    }

    /// The standard deviations along an edge's frame for a ratio `ratio`.
    fn standard_deviations(&self, ratio: f64) -> Vector3<f64> {
        let weak = self.sigma * ratio;
        if self.weak_axes == 2 {
            Vector3::new(self.sigma, weak, weak)
        } else {
            Vector3::new(self.sigma, self.sigma, weak)
        }
    }
}

/// Parameters of a SLAM-like pose graph with planted rotations: a trajectory whose headings
/// perform a random walk (node `i + 1` turns by a Gaussian angle from node `i`), odometry edges
/// `(i, i + 1)`, and loop closures between the current node and a node visited earlier.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SyntheticChain {
    /// Number of nodes (>= 2).
    pub num_rotations: usize,
    /// Loop closures as a fraction of the nodes (e.g. 0.01 to 0.05).
    pub loop_closure_fraction: f64,
    /// Rotation of the trajectory per step (standard deviation per tangent component, or of
    /// the heading when planar), radians.
    pub turn_sigma: f64,
    /// Gaussian measurement noise per tangent component, radians (odometry and closures).
    pub noise_sigma: f64,
    /// All rotations about the z axis (a planar SLAM problem) instead of 3-D.
    pub planar: bool,
    /// RNG seed.
    pub seed: u64,
}

impl Default for SyntheticChain {
    fn default() -> Self {
        SyntheticChain {
            num_rotations: 1000,
            loop_closure_fraction: 0.02,
            turn_sigma: 0.1,
            noise_sigma: 1e-4,
            planar: false,
            seed: 0,
        }
    }
}

impl SyntheticChain {
    /// Generate `(problem, ground truth)`; the ground truth has `R_0 = I`. Unit weights. Loop
    /// closure `k` joins a uniformly random node `j >= 10` to a uniformly random earlier node
    /// `i < j - 5`, so closures span every range, as when a robot revisits a place.
    ///
    /// ```
    /// use rotavg::multiple::synthetic::SyntheticChain;
    /// let (p, gt) = SyntheticChain { num_rotations: 200, noise_sigma: 0.0, planar: true, ..Default::default() }.generate();
    /// assert_eq!(p.num_edges(), 199 + 4); // odometry + 2 % closures
    /// assert!(p.chordal_cost(&gt) < 1e-20);
    /// ```
    pub fn generate(&self) -> (MultipleProblem, Vec<Rotation>) {
        let n = self.num_rotations.max(2);
        let mut rng = StdRng::seed_from_u64(self.seed);
        let step = |rng: &mut StdRng, sigma: f64, planar: bool| -> Vector3<f64> {
            let mut g = || sigma * crate::so3::gaussian(rng);
            if planar {
                Vector3::new(0.0, 0.0, g())
            } else {
                Vector3::new(g(), g(), g())
            }
        };
        let mut gt = Vec::with_capacity(n);
        gt.push(Rotation::identity());
        for i in 1..n {
            let turn = step(&mut rng, self.turn_sigma, self.planar);
            gt.push(exp(&turn) * gt[i - 1]);
        }
        let mut pairs: Vec<(usize, usize)> = (1..n).map(|j| (j - 1, j)).collect();
        let closures = (self.loop_closure_fraction.max(0.0) * n as f64).round() as usize;
        if n > 16 {
            for _ in 0..closures {
                let j = rng.random_range(10..n);
                let i = rng.random_range(0..j - 5);
                pairs.push((i, j));
            }
        }
        let edges = pairs
            .into_iter()
            .map(|(i, j)| {
                let noise = step(&mut rng, self.noise_sigma, self.planar);
                Edge {
                    i,
                    j,
                    rotation: exp(&noise) * gt[j] * gt[i].inverse(),
                    weight: 1.0,
                }
            })
            .collect();
        (
            MultipleProblem::new(n, edges).expect("generated chain is valid"),
            gt,
        )
    }
}

/// Parameters of a SLAM-like lattice pose graph with planted rotations: a robot sweeps a
/// `width x height` grid row by row (a boustrophedon path, the odometry edges), and every other
/// lattice edge between spatially adjacent nodes (the next row, and with `torus` the
/// wrap-around edges) is a loop closure kept with probability `closure_fraction`. Closures are
/// spatially local, as in real SLAM (a Manhattan-world trajectory), so the graph is planar (a
/// torus with `torus`) and its Cholesky factors fill like `O(n log n)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SyntheticGrid {
    /// Nodes per row (>= 2).
    pub width: usize,
    /// Rows (>= 2).
    pub height: usize,
    /// Also join the last column to the first and the last row to the first.
    pub torus: bool,
    /// Probability that a non-odometry lattice edge is measured (0..=1).
    pub closure_fraction: f64,
    /// Rotation of the trajectory per step along the path (standard deviation per tangent
    /// component), radians.
    pub turn_sigma: f64,
    /// Gaussian measurement noise per tangent component, radians.
    pub noise_sigma: f64,
    /// RNG seed.
    pub seed: u64,
}

impl Default for SyntheticGrid {
    fn default() -> Self {
        SyntheticGrid {
            width: 30,
            height: 30,
            torus: false,
            closure_fraction: 0.5,
            turn_sigma: 0.1,
            noise_sigma: 1e-3,
            seed: 0,
        }
    }
}

impl SyntheticGrid {
    /// Generate `(problem, ground truth)`; node `k` is the `k`-th pose of the path, the ground
    /// truth has `R_0 = I`. Unit weights.
    ///
    /// ```
    /// use rotavg::multiple::synthetic::SyntheticGrid;
    /// let g = SyntheticGrid { width: 4, height: 3, closure_fraction: 1.0, noise_sigma: 0.0, ..Default::default() };
    /// let (p, gt) = g.generate();
    /// // 11 odometry edges + the 17 - 11 = 6 other lattice edges of a 4 x 3 grid
    /// assert_eq!((p.num_rotations(), p.num_edges()), (12, 17));
    /// assert!(p.chordal_cost(&gt) < 1e-20);
    /// ```
    pub fn generate(&self) -> (MultipleProblem, Vec<Rotation>) {
        let (w, h) = (self.width.max(2), self.height.max(2));
        let n = w * h;
        let mut rng = StdRng::seed_from_u64(self.seed);
        let gaussian3 = |rng: &mut StdRng, sigma: f64| {
            Vector3::new(
                sigma * crate::so3::gaussian(rng),
                sigma * crate::so3::gaussian(rng),
                sigma * crate::so3::gaussian(rng),
            )
        };
        let mut gt = Vec::with_capacity(n);
        gt.push(Rotation::identity());
        for k in 1..n {
            let turn = gaussian3(&mut rng, self.turn_sigma);
            gt.push(exp(&turn) * gt[k - 1]);
        }
        // path index of lattice cell (row, column): rows alternate direction
        let node = |r: usize, c: usize| {
            if r.is_multiple_of(2) {
                r * w + c
            } else {
                r * w + (w - 1 - c)
            }
        };
        let mut pairs: Vec<(usize, usize)> = (1..n).map(|k| (k - 1, k)).collect();
        let p = self.closure_fraction.clamp(0.0, 1.0);
        for r in 0..h {
            for c in 0..w {
                let down = (r + 1 < h).then_some((r + 1, c));
                let wrap_down = (self.torus && r + 1 == h && h > 2).then_some((0, c));
                let wrap_right = (self.torus && c + 1 == w && w > 2).then_some((r, 0));
                for (r2, c2) in [down, wrap_down, wrap_right].into_iter().flatten() {
                    let (a, b) = (node(r, c), node(r2, c2));
                    if a.abs_diff(b) != 1 && rng.random::<f64>() < p {
                        pairs.push((a.min(b), a.max(b)));
                    }
                }
            }
        }
        let edges = pairs
            .into_iter()
            .map(|(i, j)| {
                let noise = gaussian3(&mut rng, self.noise_sigma);
                Edge {
                    i,
                    j,
                    rotation: exp(&noise) * gt[j] * gt[i].inverse(),
                    weight: 1.0,
                }
            })
            .collect();
        (
            MultipleProblem::new(n, edges).expect("generated grid is valid"),
            gt,
        )
    }
}

/// A cycle `0 -> 1 -> ... -> n-1 -> 0` of rotations about the z axis whose measurements compose
/// to a loop error of `phi` radians about z (each edge rotates by `phi / n` about z), unit weights.
/// Its chordal local minima are known in closed form (`paper-notes/multiple.md`).
///
/// ```
/// use rotavg::multiple::synthetic::z_cycle;
/// use rotavg::Rotation;
/// let p = z_cycle(4, 0.4);
/// assert_eq!((p.num_rotations(), p.num_edges()), (4, 4));
/// // All at I: each of the 4 edges has residual angle 0.1.
/// assert!(p.residual_angles(&[Rotation::identity(); 4]).iter().all(|t| (t - 0.1).abs() < 1e-12));
/// ```
pub fn z_cycle(n: usize, phi: f64) -> MultipleProblem {
    let n = n.max(3);
    let step = exp(&(Vector3::z() * (phi / n as f64)));
    let edges = (0..n)
        .map(|i| Edge {
            i,
            j: (i + 1) % n,
            rotation: step,
            weight: 1.0,
        })
        .collect();
    MultipleProblem::new(n, edges).expect("cycle is valid")
}

/// Seeded gravity priors for a planted truth (`paper-notes/gravity.md`): image `i`'s prior is
/// `R_i e_3` (the world's down direction `e_3` seen by camera `i`) turned by a Gaussian angle
/// of standard deviation `noise_deg` about a uniformly random axis orthogonal to it; an image
/// has no prior with probability `missing_fraction` (image 0 always has one).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SyntheticGravity {
    /// Standard deviation of the angle between a prior and the truth, degrees.
    pub noise_deg: f64,
    /// Fraction of images without a prior, in `[0, 1)`.
    pub missing_fraction: f64,
    /// RNG seed.
    pub seed: u64,
}

impl SyntheticGravity {
    /// The priors of `truth`.
    ///
    /// ```
    /// use rotavg::multiple::synthetic::{SyntheticGraph, SyntheticGravity};
    /// let (_, truth) = SyntheticGraph::default().generate();
    /// let g = SyntheticGravity { noise_deg: 0.5, missing_fraction: 0.25, seed: 1 }.priors(&truth)?;
    /// assert!(g.num_known() > 60 && g.num_known() < 90 && g.direction(0).is_some());
    /// let off = (truth[0] * nalgebra::Vector3::z()).angle(&g.direction(0).unwrap()).to_degrees();
    /// assert!(off < 3.0);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn priors(&self, truth: &[Rotation]) -> crate::Result<super::gravity::GravityPriors> {
        let mut rng = StdRng::seed_from_u64(self.seed);
        let dirs = truth
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let g = r * Vector3::z();
                let axis = g.cross(&crate::so3::random_unit_vector(&mut rng));
                let turn = crate::so3::gaussian(&mut rng) * self.noise_deg.to_radians();
                let noisy = match axis.try_normalize(1e-9) {
                    Some(a) => exp(&(a * turn)) * g,
                    None => g,
                };
                let missing = i > 0 && rng.random::<f64>() < self.missing_fraction;
                (!missing).then(|| noisy.into())
            })
            .collect();
        super::gravity::GravityPriors::new(dirs)
    }
}
