//! Step 2 of the block comparison `[A15]`: edge by edge,
//! `q_e = d^T S_e d - 2 m^T K_e d >= d^T W_e d - x_a^T Delta_e x_a - x_b^T Delta_e x_b`, each proven by a
//! verified `6 x 6` eigenvalue bound, and the diagonal blocks' rest `G_i`; every quantity rounded
//! in the safe direction.

use super::outcome::BlockFailure;
use crate::certify::multiple::multipliers::symmetrize;
use crate::certify::multiple::scalar::{fro, parallel_groups};
use crate::linalg::cholesky::{UNIT_ROUNDOFF, gamma};
use crate::linalg::small_symmetric::verified_negative_part;
use crate::linalg::symmetric3::eigenvalues_estimate;
use crate::multiple::MultipleProblem;
use crate::multiple::anisotropic::Information;
use crate::so3::Rotation;
use nalgebra::{Matrix3, Matrix6, SymmetricEigen, Vector3};

/// The split of the cross term of a kept edge: `2 m^T K d <= beta d^T B d + m^T K (beta
/// B)^{-1} K^T m` with `B` the edge's `S_e` (its eigenvalues floored, below): the edge keeps
/// `(1 - beta) S_e` and charges `K (beta B)^{-1} K^T`. Measured on the realistic two-view
/// generator (2026-11-30): `0.3` proves a 10^4-camera graph of 10^5 edges on 4 edges per node
/// (`0.5`, the scalar comparison's choice, needs 5; `0.2` fails at 4 with 5 negative pivots),
/// and a 3000-camera graph on 5 (`0.5` and `0.1` fail at 5, 6 and 8).
const BETA: f64 = 0.3;

/// The floor of `B`'s eigenvalues relative to its largest: directions of `S_e` weaker than
/// this are not used to absorb the cross term (its charge would grow like their inverse).
const EIGENVALUE_FLOOR: f64 = 1e-3;

/// The largest floor of an edge's `B` in a direction, as a fraction of an endpoint's kept
/// strength per edge there ([`floored_inverse`]).
const COVER_FRACTION: f64 = 0.1;

/// The error of `fl(E_e)`, `fl(S_e)`, `fl(K_e)` in Frobenius norm per unit of `tr(H_e)`, in
/// units of `gamma(3)`: entries of `|R_i^T| |F| |R_ij^T| |R_j|` are at most `29 tr(H)`, the
/// three products and `F = fl(tr(H) I - 2H)` err by at most `160 gamma(3) tr(H)` per entry,
/// `480` in Frobenius, and forming the symmetric and skew parts adds `174 u tr(H)`.
const EDGE_ERROR_PER_TRACE: f64 = 700.0;

/// Step 2's result: `M >= C - blkdiag(Delta)`, `C` the block Laplacian of the kept weights.
pub(super) struct EdgeBlocks {
    /// Each edge's kept `3 x 3` weight `W_e` (zero for a dropped edge).
    pub kept: Vec<Matrix3<f64>>,
    /// Each node's charge `Delta_i` (symmetric `3 x 3`, positive semidefinite up to the
    /// rounding already added to its diagonal; at least `1e-14 d_max` there).
    pub delta: Vec<Matrix3<f64>>,
    /// Each node's number of edges.
    pub deg_n: Vec<usize>,
    /// The largest row sum of `|C|` (the scale of the headroom).
    pub d_max: f64,
}

/// `E_e = R_i^T F R_ij^T R_j` (`F = 2M = tr(H) I - 2H`) split into its symmetric and skew
/// parts, and `eta_e >= ||E_exact - S_e - K_e||_2`.
fn edge_parts(
    h: &Information,
    r_ij: &Rotation,
    r_i: &Rotation,
    r_j: &Rotation,
) -> (Matrix3<f64>, Matrix3<f64>, f64) {
    let (e, eta) = edge_matrix(h, r_ij, r_i, r_j);
    let s = symmetrize(&e);
    let k = 0.5 * (e - e.transpose());
    (s, k, eta)
}

/// `fl(E_e)`, `E_e = R_i^T F R_ij^T R_j` (`M_ij = -E_e`), and `eta_e`, at least its error in
/// the 2-norm (and the error of its symmetric and skew parts, [`EDGE_ERROR_PER_TRACE`]).
pub(super) fn edge_matrix(
    h: &Information,
    r_ij: &Rotation,
    r_i: &Rotation,
    r_j: &Rotation,
) -> (Matrix3<f64>, f64) {
    let f = h.twice_chordal_matrix();
    let e = r_i.matrix().transpose() * (f * (r_ij.matrix().transpose() * r_j.matrix()));
    let trace = h.matrix().trace().abs() * (1.0 + gamma(3));
    let eta = EDGE_ERROR_PER_TRACE * gamma(3) * trace * (1.0 + 4.0 * UNIT_ROUNDOFF);
    (e, eta)
}

/// `fl(M_ii)`, `M_ii = R_i^T (sum_e F_e - sym(Lambda_i)) R_i` over the edges `F_e` at node
/// `i` (`traces`: their `sum_e tr(H_e)`, `degree` their number), and a bound on its error in
/// the 2-norm: three times [`NodeSums::rest_of_block`]'s entrywise bound of the products.
pub(super) fn diagonal_block(
    rotation: &Rotation,
    lambda: &Matrix3<f64>,
    f_sum: &Matrix3<f64>,
    (traces, degree): (f64, usize),
) -> (Matrix3<f64>, f64) {
    let r = rotation.matrix();
    let lam = symmetrize(lambda);
    let block = r.transpose() * (f_sum - lam) * r;
    let scale = 1.01 * traces + lam.amax();
    let entry = 18.4 * gamma(degree + 12) * scale + gamma(2) * lambda.amax();
    (block, 3.0 * entry * (1.0 + 4.0 * UNIT_ROUNDOFF))
}

/// An edge's (or a merged group's) parts: `S_e`, `K_e` and `eta_e`.
pub(super) type Parts = (Matrix3<f64>, Matrix3<f64>, f64);

/// Every edge's parts at `rotations`, each group of parallel edges as one (`[D13]`'s groups,
/// `scalar::parallel_groups`, ordered by `order`: the edge of the largest `order` first): the
/// group's first edge carries the sum of their `E_e` (each in its direction; a reversed edge's
/// `E_e` transposed), the others `None`. Only the block `M_ij` enters step 1's identity, and
/// it is the sum of the group's: a rig's within-frame couplings `[H21]`, three pseudo-edges
/// whose sum is a skew block, are charged `|u|` as one where apart each is far from
/// consistent. `eta` of a group: the sum of its edges' and the summation's error
/// (`gamma(k)` of the magnitudes).
pub(super) fn merged_parts(
    problem: &MultipleProblem,
    information: &[Information],
    rotations: &[Rotation],
    order: &[u32],
) -> Vec<Option<Parts>> {
    let edges = problem.edges();
    let mut parts: Vec<Option<Parts>> = edges
        .iter()
        .zip(information)
        .map(|(e, h)| Some(edge_parts(h, &e.rotation, &rotations[e.i], &rotations[e.j])))
        .collect();
    for group in parallel_groups(problem, order) {
        let first = &edges[group[0]];
        let (mut s, mut k, mut eta, mut magnitude) = (Matrix3::zeros(), Matrix3::zeros(), 0.0, 0.0);
        for &g in &group {
            let Some((sg, kg, eg)) = parts[g].take() else {
                continue;
            };
            s += sg;
            k += if edges[g].i == first.i { kg } else { -kg };
            eta += eg;
            magnitude += fro(&sg) + fro(&kg);
        }
        let g = gamma(group.len() + 1);
        let eta = (eta + g * magnitude) * (1.0 + g);
        parts[group[0]] = Some((s, k, eta));
    }
    parts
}

/// The edge's symmetric part `S_e` (its strength in the comparison) and an estimate of the
/// charge `Z_e` it leaves when dropped (`K B^-1 K^T`, `B` = `S_e` floored at
/// [`EIGENVALUE_FLOOR`] of its largest eigenvalue, as at a node that covers it; a kept edge
/// leaves `Z_e / BETA` and keeps `(1 - BETA) S_e`, [`KEPT_SHARE`]), from its `parts`
/// ([`merged_parts`]; zero for a merged group's other edges): for the choice of a subgraph
/// only.
pub(super) fn strength_and_charge(parts: Option<&Parts>) -> (Matrix3<f64>, Matrix3<f64>) {
    let Some((s, k, _)) = parts else {
        return (Matrix3::zeros(), Matrix3::zeros());
    };
    // covered: the floor alone (the kept strength per edge is large at most nodes)
    let unbounded = Matrix3::identity() * 1e300;
    let z = match floored_inverse(s, [&unbounded, &unbounded]) {
        Some((b_inv, _)) => symmetrize(&(k * b_inv * k.transpose())),
        None => Matrix3::identity() * (s.norm() + k.norm()),
    };
    (*s, z)
}

/// The share of `S_e` a kept edge keeps, and the factor on its dropped charge (estimates: the
/// floors of [`floored_inverse`] aside).
pub(super) const KEPT_SHARE: (f64, f64) = (1.0 - BETA, 1.0 / BETA);

/// One edge's `(W, Delta_e)` (`Delta_e = Z / 2 + c I`, the charge at each endpoint), from the
/// same steps as [`edge_blocks`] with the edge its endpoints' only one.
#[cfg(test)]
pub(super) fn edge_parts_for_tests(
    h: &Information,
    r_ij: &Rotation,
    r_i: &Rotation,
    r_j: &Rotation,
    dropped: bool,
) -> Option<(Matrix3<f64>, Matrix3<f64>)> {
    let (s, k, eta) = edge_parts(h, r_ij, r_i, r_j);
    let b = edge_bound(&s, &k, eta, dropped, [&s, &s])?;
    Some((b.kept, b.half_charge + Matrix3::identity() * b.iso))
}

/// One edge's comparison, second order ([`second_order_bound`]) where its `S_e` has a positive
/// eigenvalue and the check succeeds, else first order: nothing kept and the charge
/// `-lambda_min(K6)` of its whole form `K6 = [[S, -E], [-E^T, S]]` (an outlier far from its
/// estimate, at a random point). The first order is also taken when its charge is below the
/// second's largest and the second keeps no more than it (both are proven): the second order
/// charge `K B^-1 K^T` of an edge far from consistent, whose `S_e` is nearly singular, is about
/// `1 / floor` times its first order one (a rig's within-frame couplings, rotations by
/// `pi / 2` and `pi`), and without bound as `S_e` vanishes (the three as one, [`merged_parts`]:
/// `S_e = 0` up to rounding).
fn edge_bound(
    s: &Matrix3<f64>,
    k: &Matrix3<f64>,
    eta: f64,
    dropped: bool,
    cover: [&Matrix3<f64>; 2],
) -> Option<EdgeBound> {
    let Some(b) = second_order_bound(s, k, eta, dropped, cover) else {
        return first_order_bound(s, k, eta);
    };
    let largest = eigenvalues_estimate(&b.half_charge)[2] + b.iso;
    let keeps = eigenvalues_estimate(&b.kept)[2].max(0.0);
    // a kept edge keeping at least its charge (most, at a good estimate): no `6 x 6` check
    if keeps >= largest {
        return Some(b);
    }
    match first_order_bound(s, k, eta) {
        Some(f) if f.iso < largest && keeps <= f.iso => Some(f),
        _ => Some(b),
    }
}

/// `q_e = [x_a; x_b]^T [[S, -E], [-E^T, S]] [x_a; x_b] >= l (|x_a|^2 + |x_b|^2)`, `E = S + K`.
fn first_order_bound(s: &Matrix3<f64>, k: &Matrix3<f64>, eta: f64) -> Option<EdgeBound> {
    let u = UNIT_ROUNDOFF;
    let e = s + k;
    let k6 = two_by_two(s, &-e, s);
    // fl(S + K) errs by u |E|
    let l = verified_negative_part(&k6)? - 2.0 * u * fro(&e);
    let iso = ((-l).max(0.0) + eta) * (1.0 + 8.0 * u);
    iso.is_finite().then_some(EdgeBound {
        kept: Matrix3::zeros(),
        half_charge: Matrix3::zeros(),
        iso,
    })
}

/// One edge's comparison: its kept weight `W`, and its charges `Z' / 2` (a positive
/// semidefinite matrix) and `c` per node, with
/// `q_e >= d^T W d - x_a^T (Z'/2 + c I) x_a - x_b^T (Z'/2 + c I) x_b` proven: a heuristic choice,
/// then the check `T = [[Z, -K], [-K^T, S - W]] >= l I` and the patch `Z' = Z + |l| I`,
/// `W - |l| I` (`Z'` is then a principal block of a positive semidefinite matrix, so
/// `m^T Z' m <= (x_a^T Z' x_a + x_b^T Z' x_b) / 2`).
fn second_order_bound(
    s: &Matrix3<f64>,
    k: &Matrix3<f64>,
    eta: f64,
    dropped: bool,
    cover: [&Matrix3<f64>; 2],
) -> Option<EdgeBound> {
    let u = UNIT_ROUNDOFF;
    let (b_inv, b) = floored_inverse(s, cover)?;
    let (w, z) = if dropped {
        (Matrix3::zeros(), k * b_inv * k.transpose())
    } else {
        (s - BETA * b, k * (b_inv / BETA) * k.transpose())
    };
    let z = symmetrize(&z);
    let sw = s - w;
    let t = two_by_two(&z, &-k, &sw);
    // fl(S - W) errs by u |S - W|
    let l = verified_negative_part(&t)? - 2.0 * u * fro(&sw);
    let patch = (-l).max(0.0) * (1.0 + 4.0 * u);
    // Z' / 2 = fl(Z / 2) (exact) + patch / 2 I; d^T (-patch I) d >= -2 patch (|x_a|^2 + |x_b|^2)
    let dropped_charge = if dropped { 2.0 * patch } else { 0.0 };
    let iso = (0.5 * patch + dropped_charge + eta) * (1.0 + 8.0 * u);
    // fl(W_aa - p) <= W_aa - patch with p raised by the rounding of the subtraction
    let kept = if dropped {
        Matrix3::zeros()
    } else {
        let p = patch * (1.0 + 4.0 * u) + 4.0 * u * w.diagonal().amax();
        w - Matrix3::identity() * p
    };
    let bound = EdgeBound {
        kept,
        half_charge: 0.5 * z,
        iso,
    };
    (iso.is_finite()
        && bound
            .kept
            .iter()
            .chain(bound.half_charge.iter())
            .all(|x| x.is_finite()))
    .then_some(bound)
}

/// The symmetric `[[A, B], [B^T, C]]`.
fn two_by_two(a: &Matrix3<f64>, b: &Matrix3<f64>, c: &Matrix3<f64>) -> Matrix6<f64> {
    Matrix6::from_fn(|r, col| match (r < 3, col < 3) {
        (true, true) => a[(r, col)],
        (true, false) => b[(r, col - 3)],
        (false, true) => b[(col, r - 3)],
        (false, false) => c[(r - 3, col - 3)],
    })
}

/// What one edge's comparison gives each of its nodes.
struct EdgeBound {
    /// `W` (zero for a dropped edge).
    kept: Matrix3<f64>,
    /// `Z / 2` (the patch is in `iso`).
    half_charge: Matrix3<f64>,
    /// The isotropic charge: half the patch, a dropped edge's `2 patch`, and `eta`.
    iso: f64,
}

/// `(B^{-1}, B)` (`None` when `S` has no positive eigenvalue) for `B = S` with its eigenvalues floored at `EIGENVALUE_FLOOR` of the largest,
/// but in each eigenvector `v` at most `COVER_FRACTION` of `v^T N v` at either endpoint, `N`
/// the endpoint's kept strength per edge (`sum_e S_e / deg`): a floor raises `B` above `S`
/// and so makes the kept `S - beta B` negative along `v`, which other edges must cover (a
/// node of degree 2 whose two edges share a weak direction could not: one negative pivot too
/// many on 3000- and 10^4-camera graphs). Only a choice: the check of [`edge_bound`] proves
/// whatever it gives.
fn floored_inverse(
    s: &Matrix3<f64>,
    cover: [&Matrix3<f64>; 2],
) -> Option<(Matrix3<f64>, Matrix3<f64>)> {
    let eig = SymmetricEigen::new(*s);
    let top = eig.eigenvalues.max();
    // no positive eigenvalue: nothing to keep (NaN included)
    if top.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let floor = (EIGENVALUE_FLOOR * top).max(f64::MIN_POSITIVE);
    let v = eig.eigenvectors;
    let d = Vector3::from_fn(|c, _| {
        let x = eig.eigenvalues[c];
        let dir = v.column(c);
        let covered = cover
            .iter()
            .map(|n| (dir.transpose() * *n * dir)[(0, 0)])
            .fold(f64::INFINITY, f64::min);
        let f = floor.min(COVER_FRACTION * covered);
        if x > 0.0 { x.max(f) } else { x.max(floor) }
    });
    let b = v * Matrix3::from_diagonal(&d) * v.transpose();
    let b_inv = v * Matrix3::from_diagonal(&d.map(|x| 1.0 / x)) * v.transpose();
    Some((symmetrize(&b_inv), symmetrize(&b)))
}

/// Step 2 for every edge (`keep[k]`: edge `k` is in `C`; parallel edges as one,
/// [`merged_parts`], the group's first kept edge carrying its `W`), then the diagonal blocks'
/// rest `G_i = M_ii - sum_e S_e` added to the charges.
pub(super) fn edge_blocks(
    problem: &MultipleProblem,
    information: &[Information],
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    keep: &[bool],
) -> std::result::Result<EdgeBlocks, BlockFailure> {
    let n = problem.num_rotations();
    let order: Vec<u32> = keep.iter().map(|&k| u32::from(k)).collect();
    let parts = merged_parts(problem, information, rotations, &order);
    let strength = kept_strength(problem, &parts, keep);
    let bounds = edge_bounds(problem, &parts, &strength, keep)?;
    let mut node = vec![NodeSums::default(); n];
    let mut kept = Vec::with_capacity(problem.num_edges());
    let nothing = EdgeBound {
        kept: Matrix3::zeros(),
        half_charge: Matrix3::zeros(),
        iso: 0.0,
    };
    for (((e, h), parts), b) in problem
        .edges()
        .iter()
        .zip(information)
        .zip(&parts)
        .zip(&bounds)
    {
        let f = h.twice_chordal_matrix();
        let trace = h.matrix().trace().abs();
        // a merged group's other edges: their `F_e` in `M_ii`, their `E_e` in the first's
        let (b, s) = match (parts, b) {
            (Some((s, _, _)), Some(b)) => (b, s),
            _ => (&nothing, &Matrix3::zeros()),
        };
        for v in [e.i, e.j] {
            node[v].add(b, &f, trace, s);
        }
        kept.push(b.kept);
    }
    let d_max = node.iter().map(|s| 2.0 * s.kept_abs).fold(0.0, f64::max);
    let floor = 1e-14 * d_max.max(f64::MIN_POSITIVE);
    let mut delta = Vec::with_capacity(n);
    for (i, sums) in node.iter().enumerate() {
        let g_i = sums.rest_of_block(&rotations[i], &lambdas[i]);
        delta.push(sums.charge(g_i, floor));
    }
    if !delta.iter().all(|d| d.iter().all(|x| x.is_finite())) || !d_max.is_finite() {
        return Err(BlockFailure::Numerical);
    }
    let deg_n = node.iter().map(|s| s.degree).collect();
    Ok(EdgeBlocks {
        kept,
        delta,
        deg_n,
        d_max,
    })
}

/// Every edge's [`edge_bound`] (`None` for a merged group's other edges), in the edges' order:
/// independent per edge, so split over the machine's threads
/// ([`crate::linalg::threads::PARALLEL_EDGES`]).
fn edge_bounds(
    problem: &MultipleProblem,
    parts: &[Option<Parts>],
    strength: &[Matrix3<f64>],
    keep: &[bool],
) -> std::result::Result<Vec<Option<EdgeBound>>, BlockFailure> {
    let edges = problem.edges();
    let mut bounds: Vec<Option<EdgeBound>> = Vec::new();
    bounds.resize_with(edges.len(), || None);
    let parallel = edges.len() >= crate::linalg::threads::PARALLEL_EDGES;
    let done = crate::linalg::threads::in_chunks(&mut bounds, parallel, |first, out| {
        for (k, slot) in out.iter_mut().enumerate() {
            let (e, index) = (&edges[first + k], first + k);
            if let Some((s, kk, eta)) = &parts[index] {
                let cover = [&strength[e.i], &strength[e.j]];
                *slot = Some(edge_bound(s, kk, *eta, !keep[index], cover).ok_or(())?);
            }
        }
        Ok(())
    });
    match done.into_iter().collect::<std::result::Result<(), ()>>() {
        Ok(()) => Ok(bounds),
        Err(()) => Err(BlockFailure::Numerical),
    }
}

/// Each node's kept strength per kept edge, `sum_e S_e / deg` over its edges in `C` (a merged
/// group as one edge).
fn kept_strength(
    problem: &MultipleProblem,
    parts: &[Option<Parts>],
    keep: &[bool],
) -> Vec<Matrix3<f64>> {
    let n = problem.num_rotations();
    let mut sum = vec![Matrix3::zeros(); n];
    let mut count = vec![0usize; n];
    for ((e, part), _) in problem
        .edges()
        .iter()
        .zip(parts)
        .zip(keep)
        .filter(|(_, k)| **k)
    {
        let Some((s, _, _)) = part else { continue };
        for v in [e.i, e.j] {
            sum[v] += s;
            count[v] += 1;
        }
    }
    sum.iter()
        .zip(count)
        .map(|(s, c)| s / c.max(1) as f64)
        .collect()
}

/// What the edges at one node add up to.
#[derive(Clone, Default)]
struct NodeSums {
    degree: usize,
    /// Sum of the edges' `Z_e / 2`.
    half_charge: Matrix3<f64>,
    /// Sum of `||Z_e / 2||_F` (the rounding of that sum).
    half_charge_abs: f64,
    /// Sum of the edges' isotropic charges.
    iso: f64,
    /// `sum_e F_e` (`F = 2M`), the node's part of `Q_ii`.
    f_sum: Matrix3<f64>,
    /// `sum_e tr(H_e)`.
    trace: f64,
    /// `sum_e S_e`.
    s_sum: Matrix3<f64>,
    /// `sum_e max |S_e|`.
    s_abs: f64,
    /// Largest row sum of `sum_e |W_e|` (one block row of `C`'s diagonal block).
    kept_abs: f64,
}

impl NodeSums {
    fn add(&mut self, b: &EdgeBound, f: &Matrix3<f64>, trace: f64, s: &Matrix3<f64>) {
        let w = &b.kept;
        self.degree += 1;
        self.half_charge += b.half_charge;
        self.half_charge_abs += fro(&b.half_charge);
        self.iso += b.iso;
        self.f_sum += f;
        self.trace += trace;
        self.s_sum += s;
        self.s_abs += s.amax();
        self.kept_abs += (0..3).map(|r| w.row(r).abs().sum()).fold(0.0, f64::max);
    }

    /// `Delta_i = sum_e Z_e / 2 + (sum_e c_e + g_i + sum errors) I`, its diagonal rounded up
    /// and at least `floor`.
    fn charge(&self, g_i: f64, floor: f64) -> Matrix3<f64> {
        let u = UNIT_ROUNDOFF;
        let g = gamma(self.degree + 2);
        let iso = ((self.iso + 3.0 * g * self.half_charge_abs) * (1.0 + g) + g_i) * (1.0 + 4.0 * u);
        let mut delta = self.half_charge;
        for a in 0..3 {
            let raised = iso * (1.0 + 4.0 * u) + 4.0 * u * delta[(a, a)].abs();
            delta[(a, a)] = (delta[(a, a)] + raised).max(floor);
        }
        delta
    }

    /// `g_i >= ||G_i||_2`, `G_i = R_i^T (sum_e 2M_e - sym(Lambda_i)) R_i - sum_e S_e`, with the
    /// entrywise errors: `sum_e F_e` within `gamma(d + 4) T_i` of `sum_e 2M_e`; the products with
    /// `R_i` (entries of `|R^T| |X| |R|` at most `9.2 max|X|`) within `18.4 gamma(d + 12)` of
    /// `1.01 T_i + max|Lambda_i|`; the sum of the `S_e` and the subtraction within `gamma(d + 2)`
    /// of the magnitudes.
    fn rest_of_block(&self, rotation: &Rotation, lambda: &Matrix3<f64>) -> f64 {
        let u = UNIT_ROUNDOFF;
        let (rxr, _) = diagonal_block(rotation, lambda, &self.f_sum, (self.trace, self.degree));
        let gm = rxr - self.s_sum;
        let scale = 1.01 * self.trace + symmetrize(lambda).amax();
        let entry = 18.4 * gamma(self.degree + 12) * scale
            + gamma(self.degree + 2) * (self.s_abs + 9.2 * scale);
        (fro(&gm) * (1.0 + 4.0 * u) + 3.0 * entry) * (1.0 + 4.0 * u)
    }
}
