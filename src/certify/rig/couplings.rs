//! The within-frame couplings of a rig (`paper-notes/conjugate.md` `[H21]`): pseudo-edges
//! between the images of one frame whose weighted rotations, summed over the frames, vanish for
//! each pair of sensors, so that on every rig point they add a constant to the images' view
//! graph's cost. Their flows are the least-norm ones that make the estimate a critical point of
//! the images' view graph with them; the bound is the certified minimum of that graph less the
//! constant (and the charge for the sums' rounding), whatever the flows are.

use super::traces::Traces;
use crate::error::Result;
use crate::linalg::compensated::Accumulator;
use crate::multiple::{Edge, MultipleProblem};
use crate::rig::RigProblem;
use crate::so3::{Rotation, hat, vee};
use nalgebra::{DMatrix, Matrix3, Vector3};
use std::collections::HashMap;

/// Most sensors photographing one frame that the couplings handle (`k (k - 1) / 2` pairs per
/// frame, a `p x p` projector each).
pub(crate) const MAX_SENSORS_PER_FRAME: usize = 16;

/// Most pairs of sensors photographing a frame together (a dense `P x P` eigen-decomposition).
pub(crate) const MAX_COUPLED_PAIRS: usize = 500;

/// One frame's pair of images' coupling in rig coordinates: the pseudo-edges' weighted sum
/// `sum c N = hat(u) + k` (`[H21]`): the flow `u` (its torques) and a symmetric part `k`
/// (zero for the least-norm couplings; the search of `[H21]` "The search" moves it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PairSum {
    pub u: Vector3<f64>,
    pub k: Matrix3<f64>,
}

impl PairSum {
    /// The sum `hat(u) + k` as a matrix.
    pub fn matrix(&self) -> Matrix3<f64> {
        hat(&self.u) + self.k
    }
}

/// Where the couplings go: each frame's `(sensor, image)` and the pairs of sensors.
#[derive(Clone)]
pub(crate) struct Layout {
    pub per_frame: Vec<Vec<(usize, usize)>>,
    pairs: Pairs,
}

/// The images' view graph with the couplings, and what they add on a rig point.
pub(crate) struct Coupled {
    /// The images' edges, then the pseudo-edges.
    pub graph: MultipleProblem,
    pub pseudo_edges: usize,
    /// `L` with `J(F, S) >= J_aug(S F) - L` on every rig point of exact rotations: the
    /// pseudo-edges' constant, their sums' charge, minus the held pairs' terms (`[H21]`).
    pub offset: f64,
    /// The part of `offset` charged for the constrained pairs' sums `r_st` (nonzero where the
    /// estimate is not exactly critical in its sensors): `2 sqrt(3) sum ||r_st||_F`.
    pub charge: f64,
    /// Where they go, and each frame's pairs' sums (in the order of [`local_pairs`]).
    pub layout: Layout,
    pub sums: Vec<Vec<PairSum>>,
}

/// Bytes an edge of the augmented graph is charged (the edge, 96 bytes, in the graph, its
/// component's copy and the local solve's and the checks' per-edge arrays).
pub(super) const BYTES_PER_EDGE: u64 = 400;

/// The couplings at the estimate (`frames`, `sensors`, held sensors at their held rotations),
/// or why there are none (among the reasons: the augmented graph's edges would take more than
/// half of `max_bytes`).
pub(crate) fn couple(
    problem: &RigProblem,
    frames: &[Rotation],
    sensors: &[Rotation],
    max_bytes: u64,
) -> Result<std::result::Result<Coupled, String>> {
    let per_frame = frame_images(problem);
    if per_frame.iter().any(|f| f.len() > MAX_SENSORS_PER_FRAME) {
        return Ok(Err(format!(
            "a frame photographed by more than {MAX_SENSORS_PER_FRAME} sensors"
        )));
    }
    let pseudo: usize = per_frame
        .iter()
        .map(|f| 3 * f.len() * f.len().saturating_sub(1) / 2)
        .sum();
    let bytes = (pseudo + problem.edges().len()) as u64 * BYTES_PER_EDGE;
    if bytes > max_bytes / 2 {
        return Ok(Err(format!(
            "{pseudo} pseudo-edges: the augmented graph would take about {bytes} bytes, more \
             than half of the memory budget"
        )));
    }
    let pairs = Pairs::new(problem, &per_frame);
    if pairs.ids.is_empty() {
        return Ok(Err("no frame is photographed by two sensors".into()));
    }
    if pairs.ids.len() > MAX_COUPLED_PAIRS {
        return Ok(Err(format!(
            "{} pairs of sensors share a frame (at most {MAX_COUPLED_PAIRS})",
            pairs.ids.len()
        )));
    }
    let x = problem.image_rotations(frames, sensors);
    let images = problem.image_graph()?;
    let demand = demands(problem, &images, &x, sensors);
    let sums = least_norm_flows(&per_frame, &demand, &pairs)
        .into_iter()
        .map(|f| {
            f.into_iter()
                .map(|u| PairSum {
                    u,
                    k: Matrix3::zeros(),
                })
                .collect()
        })
        .collect();
    let layout = Layout { per_frame, pairs };
    Ok(Ok(coupled(
        &images,
        layout,
        (sums, Traces::none()),
        sensors,
    )?))
}

/// The images' view graph `images` with the pseudo-edges of `sums` and of the trace couplings
/// `traces` (`[H21]` "Trace couplings"), and their constant.
pub(crate) fn coupled(
    images: &MultipleProblem,
    layout: Layout,
    (sums, traces): (Vec<Vec<PairSum>>, Traces),
    sensors: &[Rotation],
) -> Result<Coupled> {
    let pseudo = pseudo_edges(&layout.per_frame, &sums, sensors);
    let (mut offset, mut charge) = offset(&pseudo, &layout.pairs, sensors, images.is_anisotropic());
    let between = traces.pseudo_edges(&layout.per_frame);
    if !between.is_empty() {
        // each of constant `6 c` (`3 + ||N||_F^2`, and the trace form's, `[H24]`), exact rotations
        let mut constant = Accumulator::default();
        between
            .iter()
            .for_each(|e| constant.add_product(e.weight, 6.0));
        let traced = traces.charge();
        offset += (constant.value() + constant.bound()) * (1.0 + 1e-13) + traced;
        charge += traced;
    }
    let edges: Vec<Edge> = pseudo.into_iter().map(|(_, e)| e).chain(between).collect();
    Ok(Coupled {
        pseudo_edges: edges.len(),
        graph: augmented(images, edges)?,
        offset,
        charge,
        layout,
        sums,
    })
}

/// The images' view graph with the pseudo-edges; with information (`[H24]`), each
/// pseudo-edge's weight `c` as the information `c I`, whose torques are the isotropic ones
/// (`2M = c I` in `[A2]`'s `(Q Y)`), so the flows are unchanged.
fn augmented(images: &MultipleProblem, pseudo: Vec<Edge>) -> Result<MultipleProblem> {
    // sized once: the pseudo-edges are most of a large rig's augmented graph
    let total = images.edges().len() + pseudo.len();
    let mut edges = Vec::with_capacity(total);
    edges.extend_from_slice(images.edges());
    let mut info = images.information().map(|given| {
        let mut all = Vec::with_capacity(total);
        all.extend_from_slice(given);
        all
    });
    for e in pseudo {
        if let Some(info) = &mut info {
            info.push(crate::multiple::anisotropic::Information::isotropic(
                e.weight,
            )?);
        }
        edges.push(e);
    }
    let graph = MultipleProblem::new(images.num_rotations(), edges)?;
    match info {
        Some(info) => graph.with_information(info),
        None => Ok(graph),
    }
}

/// Each frame's `(sensor, image)`, sorted by sensor.
fn frame_images(problem: &RigProblem) -> Vec<Vec<(usize, usize)>> {
    let mut per_frame = vec![Vec::new(); problem.num_frames()];
    for (a, im) in problem.images().iter().enumerate() {
        per_frame[im.frame].push((im.sensor, a));
    }
    for f in &mut per_frame {
        f.sort_unstable();
    }
    per_frame
}

/// The pairs `(s, t)`, `s < t`, of sensors photographing a frame together, numbered; a pair
/// is *constrained* (its pseudo-edges' rotations must sum to zero) unless both are held.
#[derive(Clone)]
struct Pairs {
    ids: HashMap<(usize, usize), usize>,
    constrained: Vec<bool>,
    sensors: Vec<(usize, usize)>,
}

impl Pairs {
    fn new(problem: &RigProblem, per_frame: &[Vec<(usize, usize)>]) -> Self {
        let held = problem.held();
        let mut p = Pairs {
            ids: HashMap::new(),
            constrained: Vec::new(),
            sensors: Vec::new(),
        };
        for f in per_frame {
            for (i, j) in local_pairs(f.len()) {
                let key = (f[i].0, f[j].0);
                if !p.ids.contains_key(&key) {
                    p.ids.insert(key, p.sensors.len());
                    p.sensors.push(key);
                    p.constrained
                        .push(held[key.0].is_none() || held[key.1].is_none());
                }
            }
        }
        p
    }

    fn id(&self, s: usize, t: usize) -> usize {
        self.ids[&(s, t)]
    }
}

/// The pairs `(i, j)`, `i < j`, of `k` local indices.
pub(crate) fn local_pairs(k: usize) -> Vec<(usize, usize)> {
    (0..k)
        .flat_map(|i| (i + 1..k).map(move |j| (i, j)))
        .collect()
}

/// Each image's demand in rig coordinates: `d_a = -S_s^T vee(skew((Q Y)_a X_a^T))`, what the
/// couplings' torques at `a` must supply for the images' view graph with them to be critical.
fn demands(
    problem: &RigProblem,
    images: &MultipleProblem,
    x: &[Rotation],
    sensors: &[Rotation],
) -> Vec<Vector3<f64>> {
    let qy = crate::certify::multiple::multipliers::laplacian_times(images, x);
    problem
        .images()
        .iter()
        .enumerate()
        .map(|(a, im)| {
            let torque = vee(&(qy[a] * x[a].matrix().transpose()));
            -(sensors[im.sensor].matrix().transpose() * torque)
        })
        .collect()
}

/// Entry `(a, b)` of the projector `I - B^T L^+ B` onto the circulations of the complete graph
/// on `k` nodes (`B` its incidence, `+1` at `i` and `-1` at `j` for the pair `(i, j)`;
/// `L^+ = (I - 11^T / k) / k`, so the projector is `I - B^T B / k`).
fn circulation(a: (usize, usize), b: (usize, usize), k: f64) -> f64 {
    let overlap = |x: usize, y: usize| f64::from(u8::from(x == y));
    let btb = overlap(a.0, b.0) + overlap(a.1, b.1) - overlap(a.0, b.1) - overlap(a.1, b.0);
    overlap(a.0, b.0) * overlap(a.1, b.1) - btb / k
}

/// The least-norm flows (one 3-vector per frame and local pair, `+u` at the pair's first
/// sensor, `-u` at its second) with divergence the demands in every frame and, on every
/// constrained pair, zero sum over the frames (`[H21]`): `u_f = u0_f + Pi_f E_f^T beta` with
/// `u0_f` the frame's least-norm flow, `Pi_f` its circulation projector and `beta` from the
/// pairs' `P x P` system `(sum_f E_f Pi_f E_f^T) beta = -sum_f E_f u0_f` (pseudo-inverse).
fn least_norm_flows(
    per_frame: &[Vec<(usize, usize)>],
    demand: &[Vector3<f64>],
    pairs: &Pairs,
) -> Vec<Vec<Vector3<f64>>> {
    let np = pairs.sensors.len();
    let mut m = DMatrix::<f64>::zeros(np, np);
    let mut c = DMatrix::<f64>::zeros(np, 3);
    let mut particular = Vec::with_capacity(per_frame.len());
    for f in per_frame {
        let (local, k) = (local_pairs(f.len()), f.len() as f64);
        let ids: Vec<Option<usize>> = local
            .iter()
            .map(|&(i, j)| Some(pairs.id(f[i].0, f[j].0)).filter(|&g| pairs.constrained[g]))
            .collect();
        let u0: Vec<Vector3<f64>> = local
            .iter()
            .map(|&(i, j)| (demand[f[i].1] - demand[f[j].1]) / k)
            .collect();
        for (e, g) in ids
            .iter()
            .enumerate()
            .filter_map(|(e, g)| g.map(|g| (e, g)))
        {
            for r in 0..3 {
                c[(g, r)] += u0[e][r];
            }
            for (e2, g2) in ids
                .iter()
                .enumerate()
                .filter_map(|(e, g)| g.map(|g| (e, g)))
            {
                m[(g, g2)] += circulation(local[e], local[e2], k);
            }
        }
        particular.push((local, ids, u0, k));
    }
    let beta = -pseudo_inverse(m) * c;
    particular
        .into_iter()
        .map(|(local, ids, mut u, k)| {
            for (e, ue) in u.iter_mut().enumerate() {
                for (e2, g2) in ids
                    .iter()
                    .enumerate()
                    .filter_map(|(e, g)| g.map(|g| (e, g)))
                {
                    let w = circulation(local[e], local[e2], k);
                    *ue += w * Vector3::new(beta[(g2, 0)], beta[(g2, 1)], beta[(g2, 2)]);
                }
            }
            u
        })
        .collect()
}

/// The pseudo-inverse of the symmetric positive semidefinite `m` (eigenvalues below `1e-10` of
/// the largest dropped).
fn pseudo_inverse(m: DMatrix<f64>) -> DMatrix<f64> {
    let eig = m.symmetric_eigen();
    let top = eig.eigenvalues.amax();
    let inv = eig.eigenvalues.map(|l| {
        if l > 1e-10 * top && top > 0.0 {
            1.0 / l
        } else {
            0.0
        }
    });
    &eig.eigenvectors * DMatrix::from_diagonal(&inv) * eig.eigenvectors.transpose()
}

/// The half-turn `2 v v^T - I` about the unit axis `v`.
fn half_turn(v: &Vector3<f64>) -> Matrix3<f64> {
    2.0 * v * v.transpose() - Matrix3::identity()
}

/// Unit `b`, `c` completing the unit `a` to a right-handed orthonormal frame `(a, b, c)`.
fn completing(a: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let helper = if a.x.abs() < 0.6 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let b = a.cross(&helper).normalize();
    (b, a.cross(&b))
}

/// Positive weights `c_k` and rotations `N_k` with `sum c_k N_k = hat(u)`: `|u| N(u/|u|, pi/2) +
/// |u|/2 (N(b, pi) + N(c, pi))` for an orthonormal frame `(u/|u|, b, c)` (`[H21]`).
fn skew_as_rotations(u: &Vector3<f64>) -> [(f64, Matrix3<f64>); 3] {
    let n = u.norm();
    let a = u / n;
    let (b, c) = completing(&a);
    [
        (n, hat(&a) + a * a.transpose()),
        (0.5 * n, half_turn(&b)),
        (0.5 * n, half_turn(&c)),
    ]
}

/// Positive weights `c_k` and rotations `N_k` with `sum c_k N_k = k` for a symmetric `k =
/// sum l v v^T` (its eigenvalues `l`, unit eigenvectors `v`): `l v v^T = l/2 (H(v) + I)` for
/// positive `l` and `-|l| v v^T = |l|/2 (H(b) + H(c))` for negative `l` (`H` the half-turn about a unit
/// axis, `(v, b, c)` orthonormal: `H(v) + H(b) + H(c) = -I`). Eigenvalues below `1e-14` of the
/// largest are left out (any pseudo-edges give a sound bound; the sums' rounding is charged).
fn symmetric_as_rotations(k: &Matrix3<f64>) -> Vec<(f64, Matrix3<f64>)> {
    let eig = (0.5 * (k + k.transpose())).symmetric_eigen();
    let top = eig.eigenvalues.amax();
    let mut out = Vec::new();
    for (l, v) in eig.eigenvalues.iter().zip(eig.eigenvectors.column_iter()) {
        let v: Vector3<f64> = v.normalize();
        if !(l.abs() > 1e-14 * top && l.abs() <= 1e100) {
            continue;
        }
        if *l > 0.0 {
            out.push((0.5 * l, half_turn(&v)));
            out.push((0.5 * l, Matrix3::identity()));
        } else {
            let (b, c) = completing(&v);
            out.push((-0.5 * l, half_turn(&b)));
            out.push((-0.5 * l, half_turn(&c)));
        }
    }
    out
}

/// The pseudo-edges of the sums, each with its pair's number: from image `(f, s)` to image
/// `(f, t)`, rotation `S_t N_k S_s^T`, weight `c_k` (those outside `[1e-100, 1e100]` dropped:
/// any pseudo-edges give a sound bound).
fn pseudo_edges(
    per_frame: &[Vec<(usize, usize)>],
    sums: &[Vec<PairSum>],
    sensors: &[Rotation],
) -> Vec<((usize, usize), Edge)> {
    let mut out = Vec::new();
    for (f, u) in per_frame.iter().zip(sums) {
        for ((i, j), sum) in local_pairs(f.len()).into_iter().zip(u) {
            let ((s, a), (t, b)) = (f[i], f[j]);
            let ue = &sum.u;
            let skew = (ue.norm() >= 2e-100 && ue.norm() <= 1e100)
                .then(|| skew_as_rotations(ue))
                .into_iter()
                .flatten();
            let symmetric = (sum.k != Matrix3::zeros())
                .then(|| symmetric_as_rotations(&sum.k))
                .into_iter()
                .flatten();
            for (w, n) in skew.chain(symmetric) {
                let r = sensors[t].matrix() * n * sensors[s].matrix().transpose();
                let edge = Edge {
                    i: a,
                    j: b,
                    rotation: Rotation::from_matrix_unchecked(r),
                    weight: w,
                };
                out.push(((s, t), edge));
            }
        }
    }
    out
}

/// `L` of [`Coupled::offset`]: `c_P = sum c_k (3 + ||R'_k||_F^2)` (with information, `[H24]`:
/// `sum 6 c_k`, the trace form's constant of `H = c I`) rounded up, plus
/// `2 sqrt(3) ||r_st||_F` for each constrained pair (`r_st = sum c_k R'_k` over its
/// pseudo-edges, `||M||_2 = 1` for `M = S_s S_t^T`), minus `2 tr(r_st S_s S_t^T)` for each held
/// pair; every sum in double-double with its error bound charged. With the constrained pairs'
/// part apart.
fn offset(
    pseudo: &[((usize, usize), Edge)],
    pairs: &Pairs,
    sensors: &[Rotation],
    trace_form: bool,
) -> (f64, f64) {
    let mut constant = Accumulator::default();
    let mut sums = vec![[Accumulator::default(); 9]; pairs.sensors.len()];
    for (key, e) in pseudo {
        let r = e.rotation.matrix();
        let per_weight = if trace_form {
            6.0
        } else {
            3.0 + r.norm_squared()
        };
        constant.add_product(e.weight, per_weight);
        for (acc, v) in sums[pairs.id(key.0, key.1)].iter_mut().zip(r.iter()) {
            acc.add_product(e.weight, *v);
        }
    }
    let mut offset = (constant.value() + constant.bound()) * (1.0 + 1e-13);
    let mut charge = 0.0;
    for (g, sum) in sums.iter().enumerate() {
        let r = Matrix3::from_iterator(sum.iter().map(Accumulator::value));
        let r_norm = sum
            .iter()
            .map(|a| (a.value().abs() + a.bound()).powi(2))
            .sum::<f64>()
            .sqrt()
            * (1.0 + 1e-15);
        if pairs.constrained[g] {
            charge += 2.0 * 3f64.sqrt() * r_norm * (1.0 + 1e-15);
        } else {
            let (s, t) = pairs.sensors[g];
            let m = sensors[s].matrix() * sensors[t].matrix().transpose();
            // |tr(r (M_exact - M))| <= ||r|| 1e-13; the trace's rounding far below 1e-12 ||r||
            offset -= 2.0 * ((r * m).trace() - 1e-12 * r_norm);
        }
    }
    (offset + charge * (1.0 + 1e-15), charge)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certify::multiple::multipliers::stationarity_residual;
    use crate::rig::{RigScene, RigSettings, polish_passes, solve_rig};
    use crate::so3::random_rotation;
    use rand::rngs::StdRng;
    use rand::{Rng, SeedableRng};

    /// A solved noisy rig (every sensor estimated, or some known), polished, with its held
    /// sensors at their held rotations.
    fn solved(known: bool, seed: u64) -> (RigProblem, Vec<Rotation>, Vec<Rotation>) {
        let scene = RigScene {
            frames: 30,
            sensors: 3,
            noise_sigma: 0.01,
            known,
            seed,
            ..Default::default()
        };
        let (p, _) = scene.generate();
        let s = solve_rig(&p, &RigSettings::default()).unwrap();
        let (frames, sensors, _) =
            polish_passes(&p, (s.frames, s.sensors), 30, (None, u64::MAX)).unwrap();
        let sensors = p.at_held(&sensors);
        (p, frames, sensors)
    }

    /// `hat(u)` as three positively weighted rotations, for directions near every axis.
    #[test]
    fn a_skew_matrix_is_a_positive_combination_of_three_rotations() {
        let mut rng = StdRng::seed_from_u64(3);
        let mut us: Vec<Vector3<f64>> = vec![Vector3::x(), Vector3::y(), -Vector3::z() * 1e-30];
        us.extend((0..50).map(|_| random_rotation(&mut rng) * Vector3::new(0.0, 0.0, 2.5)));
        for u in us {
            let parts = skew_as_rotations(&u);
            let mut sum = Matrix3::zeros();
            for (w, n) in &parts {
                assert!(*w > 0.0);
                assert!((n.transpose() * n - Matrix3::identity()).norm() < 1e-14);
                assert!((n.determinant() - 1.0).abs() < 1e-14);
                sum += *w * n;
            }
            assert!((sum - hat(&u)).norm() <= 1e-14 * u.norm(), "{u}");
        }
    }

    /// The circulation projector of the complete graph on `k` nodes: symmetric, idempotent, and
    /// every column a circulation (zero divergence), checked against its definition.
    #[test]
    fn the_circulation_projector_is_one() {
        for k in 2..=6usize {
            let pairs = local_pairs(k);
            let p = DMatrix::from_fn(pairs.len(), pairs.len(), |a, b| {
                circulation(pairs[a], pairs[b], k as f64)
            });
            assert!((&p - p.transpose()).norm() < 1e-14);
            assert!((&p * &p - &p).norm() < 1e-12, "k = {k}");
            let b = DMatrix::from_fn(k, pairs.len(), |n, e| {
                let (i, j) = pairs[e];
                f64::from(u8::from(n == i)) - f64::from(u8::from(n == j))
            });
            assert!((&b * &p).norm() < 1e-12);
            // rank: the cycle space of K_k has dimension p - (k - 1)
            let trace: f64 = (0..pairs.len()).map(|a| p[(a, a)]).sum();
            assert!((trace - (pairs.len() + 1 - k) as f64).abs() < 1e-12);
        }
    }

    #[test]
    fn the_couplings_make_the_estimate_critical() {
        let (p, frames, sensors) = solved(false, 1);
        let c = couple(&p, &frames, &sensors, u64::MAX).unwrap().unwrap();
        let x = p.image_rotations(&frames, &sensors);
        let images = p.image_graph().unwrap();
        let before = stationarity_residual(&images, &x).unwrap();
        let after = stationarity_residual(&c.graph, &x).unwrap();
        assert!(
            before > 1e-3 && after < 1e-9 * before,
            "{before} -> {after}"
        );
        assert!(c.charge >= 0.0 && c.charge < 1e-6 * p.cost(&frames, &sensors));
    }

    /// A symmetric matrix of any signature as a positive combination of rotations.
    #[test]
    fn a_symmetric_matrix_is_a_positive_combination_of_rotations() {
        let mut rng = StdRng::seed_from_u64(3);
        for scale in [1e-6, 1.0, 1e6] {
            for _ in 0..50 {
                let a = Matrix3::from_fn(|_, _| rng.random::<f64>() - 0.5) * scale;
                let k = a + a.transpose();
                let parts = symmetric_as_rotations(&k);
                let sum: Matrix3<f64> = parts.iter().map(|(c, n)| *c * n).sum();
                assert!((sum - k).norm() <= 1e-13 * k.norm(), "{sum} {k}");
                for (c, n) in &parts {
                    assert!(*c > 0.0);
                    assert!((n.transpose() * n - Matrix3::identity()).norm() < 1e-14);
                    assert!((n.determinant() - 1.0).abs() < 1e-14);
                }
            }
        }
    }

    /// The least-norm sums of `c` with random symmetric parts of zero sum over the frames on
    /// every pair and random trace couplings of zero sum over the sensors between every two
    /// frames of the same sensors (what the search moves, `[H21]` "The search"), coupled again.
    fn with_symmetric_parts(
        p: &RigProblem,
        c: &Coupled,
        sensors: &[Rotation],
        rng: &mut StdRng,
    ) -> Coupled {
        let mut sums = c.sums.clone();
        let pairs = sums.first().map_or(0, Vec::len);
        for q in 0..pairs {
            let mut mean = Matrix3::zeros();
            for f in sums.iter_mut() {
                let a = Matrix3::from_fn(|_, _| rng.random::<f64>() - 0.5) * 10.0;
                f[q].k = a + a.transpose();
                mean += f[q].k;
            }
            let frames = sums.len() as f64;
            sums.iter_mut().for_each(|f| f[q].k -= mean / frames);
        }
        // trace couplings (`[H21]` "Trace couplings") between frames of the same sensors
        let per_frame = &c.layout.per_frame;
        let same = |f: usize, g: usize| {
            let sensors = |f: usize| per_frame[f].iter().map(|p| p.0).collect::<Vec<_>>();
            sensors(f) == sensors(g)
        };
        let mut traces = Traces::none();
        for f in 0..per_frame.len() {
            for g in (f + 1..per_frame.len()).filter(|&g| same(f, g)) {
                let mut mu: Vec<f64> = (0..per_frame[f].len())
                    .map(|_| 10.0 * (rng.random::<f64>() - 0.5))
                    .collect();
                let mean = mu.iter().sum::<f64>() / mu.len() as f64;
                mu.iter_mut().for_each(|m| *m -= mean);
                traces.pairs.push((f, g));
                traces.mu.push(mu);
            }
        }
        assert!(!traces.pairs.is_empty());
        let images = p.image_graph().unwrap();
        coupled(&images, c.layout.clone(), (sums, traces), sensors).unwrap()
    }

    /// On every rig point the images' view graph with the couplings costs the rig's cost plus at
    /// most `offset` (less at most the charge): checked on random rig points from the two
    /// costs' own evaluations, for the least-norm couplings and with random symmetric parts of
    /// zero sum over the frames (the search's moves); on points that are no rig the difference
    /// is not constant.
    #[test]
    fn on_rig_points_the_couplings_add_a_constant() {
        let mut rng = StdRng::seed_from_u64(5);
        for (known, symmetric) in [(false, false), (true, false), (false, true), (true, true)] {
            let (p, frames, sensors) = solved(known, 2);
            let mut c = couple(&p, &frames, &sensors, u64::MAX).unwrap().unwrap();
            if symmetric {
                let before = c.pseudo_edges;
                c = with_symmetric_parts(&p, &c, &sensors, &mut rng);
                assert!(c.pseudo_edges > before, "{} {before}", c.pseudo_edges);
                // zero sum over the frames: nothing charged beyond the sensors' gradient's
                assert!(c.charge < 1e-6 * p.cost(&frames, &sensors), "{}", c.charge);
            }
            assert!(c.pseudo_edges > 0);
            let mut differences = Vec::new();
            for _ in 0..20 {
                let f: Vec<Rotation> = (0..p.num_frames())
                    .map(|_| random_rotation(&mut rng))
                    .collect();
                let s: Vec<Rotation> = p
                    .held()
                    .iter()
                    .map(|h| h.unwrap_or_else(|| random_rotation(&mut rng)))
                    .collect();
                let j = p.cost(&f, &s);
                let augmented = c.graph.cost(&p.image_rotations(&f, &s));
                let slack = 1e-9 * augmented;
                assert!(
                    j >= augmented - c.offset - slack,
                    "{j} < {augmented} - {}",
                    c.offset
                );
                assert!(j <= augmented - c.offset + 2.0 * c.charge + slack);
                // not a rig: every image rotated on its own
                let x: Vec<Rotation> = (0..p.images().len())
                    .map(|_| random_rotation(&mut rng))
                    .collect();
                let images = p.image_graph().unwrap();
                differences.push(c.graph.cost(&x) - images.cost(&x));
            }
            let spread = differences.iter().cloned().fold(f64::MIN, f64::max)
                - differences.iter().cloned().fold(f64::MAX, f64::min);
            assert!(spread > 1e-3 * c.offset.abs(), "{spread}");
        }
    }
}
