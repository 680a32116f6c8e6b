//! Steps 1 and 2 of the scalar comparison `[D13]`: the estimate's orthogonality defects, and the
//! edge-by-edge comparison `M >= (L' - diag(delta)) (x) I_3` (the kept weights of `L'` and the
//! charges `delta`), every quantity rounded in the safe direction.

use super::analysis::fro;
use super::{MAX_ORTHOGONALITY_DEFECT, SECOND_ORDER_BETA, ScalarFailure};
use crate::linalg::cholesky::{UNIT_ROUNDOFF, gamma};
use crate::linalg::small_symmetric::verified_min_eigenvalue3;
use crate::multiple::{Edge, MultipleProblem};
use crate::so3::Rotation;
use nalgebra::Matrix3;

/// The error of `fl(P_e)` against the exact product: entries of the exact product are <= 3.3 in
/// magnitude (`|R|` entries <= 1 + 1e-3); the two 3-term products err by < 2e-14 per entry,
/// 6e-14 in Frobenius; 2e-13 also covers forming the symmetric and skew parts.
pub(super) const PRODUCT_ERROR: f64 = 2e-13;

/// Step 1 (Ostrowski): `lambda_min(S) >= mu_M / sigma_min(D)^2` for a non-positive `mu_M`
/// proven for `M = D^T S D`, with `sigma_min(D)^2 >= 1 - t_max` ([`orthogonality_defect`]),
/// rounded down and capped at 0; `None` when not finite. The one form of this step for every
/// comparison (scalar, hub, bordered, block).
pub(in crate::certify::multiple) fn ostrowski(mu_m: f64, t_max: f64) -> Option<f64> {
    let mu = mu_m / (1.0 - t_max) * (1.0 + 1e-10);
    mu.is_finite().then(|| mu.min(0.0))
}

/// Step 1: `t_max >= max_i ||R_i^T R_i - I||_F` (entries of `R^T R` are inner products of 3
/// terms bounded by ~1: error <= `gamma_3 3 + u` per entry; 1e-14 covers 3x that).
pub(in crate::certify::multiple) fn orthogonality_defect(
    rotations: &[Rotation],
) -> std::result::Result<f64, ScalarFailure> {
    let mut t_max = 0.0f64;
    for r in rotations {
        let m = r.matrix();
        let ti =
            fro(&(m.transpose() * m - Matrix3::identity())) * (1.0 + 4.0 * UNIT_ROUNDOFF) + 1e-14;
        if ti.is_nan() || ti >= MAX_ORTHOGONALITY_DEFECT {
            return Err(ScalarFailure::NotOrthogonal);
        }
        t_max = t_max.max(ti);
    }
    Ok(t_max)
}

/// Step 2's result: `M >= (L' - diag(delta)) (x) I_3`.
pub(super) struct EdgeCharges {
    /// Each edge's kept weight `w'_e` (any sign; 0 for a dropped edge), rounded down.
    pub reduced: Vec<f64>,
    /// Each node's charge `delta_i`, rounded up, floored at `1e-14 d_max`.
    pub delta: Vec<f64>,
    /// Each node's number of edges.
    pub deg_n: Vec<usize>,
    /// The largest weighted degree.
    pub d_max: f64,
    /// Edges compared to second order.
    pub second_order_edges: usize,
}

/// `fl(P_e) = fl(R_i^T R_ij^T R_j)`, within [`PRODUCT_ERROR`] of the exact product.
pub(super) fn edge_product(e: &Edge, rotations: &[Rotation]) -> Matrix3<f64> {
    let (ri, rj, rij) = (
        rotations[e.i].matrix(),
        rotations[e.j].matrix(),
        e.rotation.matrix(),
    );
    ri.transpose() * (rij.transpose() * rj)
}

/// One edge's comparison (step 2), for the block `-w P` of any matrix `P`: its kept weight
/// coefficient, its charge per unit of weight and whether it is second order. Second order:
/// `w (alpha_e - beta) |d|^2 - w k_e^2 / (2 beta) (|x_a|^2 + |x_b|^2)`; first order (outliers,
/// `alpha_e < beta`): `w |d|^2 - w c1 (|x_a|^2 + |x_b|^2)`; a dropped edge keeps no weight, so
/// its `beta` may be `alpha_e`. Given `err` bounding the Frobenius error of `pm = fl(P)` and of
/// forming its symmetric and skew parts. With `merged` (parallel edges as one,
/// [`merged_bound`]) a third form may be chosen: `d^T A d - 2 x_a^T K x_b >= lambda |d|^2 -
/// k (|x_a|^2 + |x_b|^2)` for any `lambda <= lambda_min(A)` (of either sign) and `k >= ||K||_2`
/// (`2 |x_a^T K x_b| <= k (|x_a|^2 + |x_b|^2)`), or dropped, nothing kept and the charge
/// `k + 2 max(0, -lambda)` (`|d|^2 <= 2 (|x_a|^2 + |x_b|^2)`).
fn matrix_bound(
    pm: &Matrix3<f64>,
    err: f64,
    (dropped, merged): (bool, bool),
    beta: f64,
) -> (f64, f64, bool) {
    let u = UNIT_ROUNDOFF;
    let sym = 0.5 * (pm + pm.transpose());
    // the axial vector of the skew part: ||K||_2 = |k| for a 3 x 3 skew matrix
    let k_e = crate::so3::vee(pm).norm() * (1.0 + 8.0 * u) + err;
    // lambda_min(A) >= 1 - ||A - I||_2 >= 1 - ||A - I||_F
    let sym_defect = fro(&(sym - Matrix3::identity()));
    let alpha = 1.0 - (sym_defect * (1.0 + 4.0 * u) + err);
    let c1 = (sym_defect + fro(&(pm - Matrix3::identity()))) * (1.0 + 4.0 * u) + 2.0 * err;
    // the third form's lambda (merged edges only: one more 3 x 3 eigenvalue bound)
    let lowest = || verified_min_eigenvalue3(&sym).map_or(alpha, |l| l.max(alpha)) - err;
    if dropped {
        let mut charge = if alpha > 0.0 {
            c1.min(k_e * k_e / (2.0 * alpha) * (1.0 + 8.0 * u))
        } else {
            c1
        };
        if merged {
            charge = charge.min((k_e + 2.0 * (-lowest()).max(0.0)) * (1.0 + 4.0 * u));
        }
        return (0.0, charge, false);
    }
    if alpha - beta > 0.0 && k_e * k_e / (2.0 * beta) < c1 * (alpha - beta) {
        // the smaller charge per unit of weight kept (the condition is roughly lambda_2 >=
        // charge / weight): second order for small residuals, first order for outliers
        return (alpha - beta, k_e * k_e / (2.0 * beta), true);
    }
    let lambda = if merged { lowest() } else { f64::NEG_INFINITY };
    if lambda - k_e > 1.0 - c1 {
        // the third form leaves more on the diagonal than the first order (a rig's
        // within-frame couplings `[H21]`, three pseudo-edges summing to a skew block: kept
        // lambda = 0 and charge 1/2 against 1 and about 3.6)
        (round_down(lambda, 4.0 * u), k_e, false)
    } else {
        (1.0, c1, false)
    }
}

/// `x` moved towards `-inf` by the relative error `r` (kept weights may be negative: the third
/// form's `lambda`).
fn round_down(x: f64, r: f64) -> f64 {
    if x >= 0.0 {
        x * (1.0 - r)
    } else {
        x * (1.0 + r)
    }
}

/// The edges of each unordered node pair that carries more than one, to be compared as one
/// edge ([`merged_bound`]), the one held by the most parts (`copies`) first: it carries the
/// group's kept weight, shared by every part that holds it. With one pattern (the whole graph or
/// a subgraph: `copies <= 1`) every group is merged (the pair's entry is in the pattern when
/// one of its edges is kept); in a split only groups whose edges are held equally often.
/// Linear: the edges are bucketed by their smaller endpoint, each bucket sorted.
pub(in crate::certify::multiple) fn parallel_groups(
    problem: &MultipleProblem,
    copies: &[u32],
) -> Vec<Vec<usize>> {
    let edges = problem.edges();
    let (low, high) = (
        |k: usize| edges[k].i.min(edges[k].j),
        |k: usize| edges[k].i.max(edges[k].j),
    );
    let mut start = vec![0usize; problem.num_rotations() + 1];
    (0..edges.len()).for_each(|k| start[low(k) + 1] += 1);
    (1..start.len()).for_each(|v| start[v] += start[v - 1]);
    let mut next = start.clone();
    let mut by_low = vec![0usize; edges.len()];
    for k in 0..edges.len() {
        by_low[next[low(k)]] = k;
        next[low(k)] += 1;
    }
    let one_pattern = copies.iter().all(|&c| c <= 1);
    let mut groups = Vec::new();
    for v in 0..start.len() - 1 {
        let bucket = &mut by_low[start[v]..start[v + 1]];
        bucket.sort_unstable_by_key(|&k| (high(k), std::cmp::Reverse(copies[k]), k));
        groups.extend(
            bucket
                .chunk_by(|&a, &b| high(a) == high(b))
                .filter(|g| {
                    g.len() > 1 && (one_pattern || g.iter().all(|&k| copies[k] == copies[g[0]]))
                })
                .map(<[usize]>::to_vec),
        );
    }
    groups
}

/// Step 2 for a group of parallel edges as one: `sum_e w_e (d^T A_e d - 2 x_a^T K_e x_b)` is
/// `W (d^T A d - 2 x_a^T K x_b)` for the weighted mean `P = sum_e w_e P_e / W` (each `P_e` in the
/// first edge's direction), so [`matrix_bound`] applies to `P`, whose form may be far from any
/// single edge's (a rig's within-frame pseudo-edges `[H21]` sum to a skew block). Returns the
/// group's kept weight (rounded down) and its charge (rounded up) at each endpoint.
fn merged_bound(
    group: &[usize],
    problem: &MultipleProblem,
    rotations: &[Rotation],
    dropped: bool,
    beta: f64,
) -> (f64, f64) {
    let edges = problem.edges();
    let first = &edges[group[0]];
    let (mut sum, mut total) = (Matrix3::zeros(), 0.0);
    for &k in group {
        let e = &edges[k];
        let pm = edge_product(e, rotations);
        sum += e.weight * if e.i == first.i { pm } else { pm.transpose() };
        total += e.weight;
    }
    let g = gamma(group.len() + 3);
    // each fl(P_e) within PRODUCT_ERROR; the weighted sum of entries <= 3.3 errs by
    // gamma(k + 1) 3.3 W per entry, the division and the weights' sum by gamma(k + 1) more
    let err = PRODUCT_ERROR + 10.0 * 3.3 * g;
    let (coeff, charge, _) = matrix_bound(&(sum / total), err, (dropped, true), beta);
    (round_down(total * coeff, g), total * charge * (1.0 + g))
}

/// The edges of the parallel groups that keep no weight at `rotations` (the third form's kept
/// weight in `[-1e-9 charge, 0]`): a rig's within-frame pseudo-edge triples `[H21]`, whose mean
/// is a skew block, left out of the whole graph's pattern loses at most `2e-9` of their charge
/// (dropped, a group charges `k + 2 max(0, -lambda)`) and saves their fill (10^4 frames and 4
/// sensors: 4.0e8 factor values with them, 1.2e8 without). `None` when there is none.
pub(super) fn weightless_groups(
    problem: &MultipleProblem,
    rotations: &[Rotation],
) -> Option<Vec<bool>> {
    let mut weightless = vec![false; problem.num_edges()];
    let mut any = false;
    for group in parallel_groups(problem, &vec![1; problem.num_edges()]) {
        let (kept, charge) = merged_bound(&group, problem, rotations, false, SECOND_ORDER_BETA);
        if kept <= 0.0 && -kept <= 1e-9 * charge {
            group.iter().for_each(|&k| weightless[k] = true);
            any = true;
        }
    }
    any.then_some(weightless)
}

/// Step 2 for every edge (`copies[k] == 0`: edge `k` is dropped from `L'`; parallel edges as one,
/// [`merged_bound`], the first of each group carrying its kept weight), then the diagonal
/// blocks' rest `G_i = M_ii - sum_e w_e A_e` added to the charges.
pub(super) fn edge_charges(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    copies: &[u32],
    beta: f64,
) -> std::result::Result<EdgeCharges, ScalarFailure> {
    let u = UNIT_ROUNDOFF;
    let n = problem.num_rotations();
    let mut merged: Vec<Option<(f64, f64)>> = vec![None; problem.num_edges()];
    for group in parallel_groups(problem, copies) {
        let bound = merged_bound(&group, problem, rotations, copies[group[0]] == 0, beta);
        merged[group[0]] = Some(bound);
        group[1..]
            .iter()
            .for_each(|&k| merged[k] = Some((0.0, 0.0)));
    }
    let mut deg_w = vec![0.0f64; n];
    let mut deg_n = vec![0usize; n];
    let mut delta = vec![0.0f64; n];
    let mut sym_sum = vec![Matrix3::zeros(); n];
    let mut reduced = Vec::with_capacity(problem.num_edges());
    let mut second_order_edges = 0usize;
    for (k, e) in problem.edges().iter().enumerate() {
        let pm = edge_product(e, rotations);
        let (kept, charge) = merged[k].unwrap_or_else(|| {
            let (coeff, charge, second) =
                matrix_bound(&pm, PRODUCT_ERROR, (copies[k] == 0, false), beta);
            second_order_edges += usize::from(second);
            (e.weight * coeff, e.weight * charge)
        });
        // rounded towards -inf: a smaller weight only weakens the comparison
        reduced.push(round_down(kept, 4.0 * u));
        let dk = charge * (1.0 + 8.0 * u);
        let sym = 0.5 * (pm + pm.transpose());
        for v in [e.i, e.j] {
            delta[v] += dk;
            sym_sum[v] += e.weight * sym;
            deg_w[v] += e.weight;
            deg_n[v] += 1;
        }
    }
    for i in 0..n {
        let g_i = rest_of_block(&rotations[i], &lambdas[i], deg_w[i], deg_n[i], &sym_sum[i]);
        let g = gamma(deg_n[i] + 2);
        delta[i] = (delta[i] * (1.0 + g) + g_i) * (1.0 + 4.0 * u);
    }
    let d_max = deg_w.iter().copied().fold(0.0, f64::max);
    // a positive floor keeps diag(delta) definite (raising delta only weakens the argument)
    let floor = 1e-14 * d_max.max(f64::MIN_POSITIVE);
    delta.iter_mut().for_each(|d| *d = d.max(floor));
    if !delta.iter().chain(&reduced).all(|d| d.is_finite()) {
        return Err(ScalarFailure::Numerical);
    }
    Ok(EdgeCharges {
        reduced,
        delta,
        deg_n,
        d_max,
        second_order_edges,
    })
}

/// `g_i >= ||G_i||_2`, `G_i = d_i R_i^T R_i - R_i^T sym(Lambda_i) R_i - sum_e w_e A_e` evaluated
/// with an entrywise error of at most `gamma(12)` times the magnitudes (3 x 3 products of
/// entries <= 1.001 with `Lambda`'s, three subtractions), plus the sums' errors (`gamma(deg +
/// 2)` of the magnitudes: weights positive, entries of `A_e` <= 3.3) and the products'.
fn rest_of_block(
    rotation: &Rotation,
    lambda: &Matrix3<f64>,
    deg_w: f64,
    deg_n: usize,
    sym_sum: &Matrix3<f64>,
) -> f64 {
    let u = UNIT_ROUNDOFF;
    let g = gamma(deg_n + 2);
    let d_i = deg_w * (1.0 + g);
    let ri = rotation.matrix();
    let lam = 0.5 * (lambda + lambda.transpose());
    let gm = (ri.transpose() * ri) * deg_w - ri.transpose() * lam * ri - sym_sum;
    let magnitude = 1.01 * deg_w + 9.1 * lambda.amax() + 3.3 * d_i;
    let entry_err = gamma(12) * magnitude * 3.0 + g * 3.3 * d_i * 2.0;
    fro(&gm) * (1.0 + 4.0 * u) + 3.0 * entry_err + deg_w * PRODUCT_ERROR * (1.0 + g)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix6, Vector3};

    /// `lambda_min` of `T - B` for the six-dimensional form of one edge of unit weight,
    /// `T = [[A, -P], [-P^T, A]]` (`x^T T x = d^T A d - 2 x_a^T K x_b`) and the claimed bound
    /// `B = kept [[I, -I], [-I, I]] - charge I`.
    fn slack(pm: &Matrix3<f64>, kept: f64, charge: f64) -> f64 {
        let sym = 0.5 * (pm + pm.transpose());
        let mut t = Matrix6::zeros();
        let id = Matrix3::identity();
        t.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(sym - (kept - charge) * id));
        t.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(sym - (kept - charge) * id));
        t.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-pm + kept * id));
        t.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&(-pm.transpose() + kept * id));
        t.symmetric_eigen().eigenvalues.min()
    }

    /// The weighted mean of a rig's three pseudo-edges `[H21]` at the identity: a skew block.
    fn pseudo_mean(axis: Vector3<f64>) -> Matrix3<f64> {
        let axis = axis.normalize();
        let other = axis.cross(&Vector3::new(0.3, -0.5, 0.8)).normalize();
        let third = axis.cross(&other);
        let n = |v: Vector3<f64>, a: f64| *crate::so3::exp(&(v * a)).matrix();
        let (h, pi) = (std::f64::consts::FRAC_PI_2, std::f64::consts::PI);
        (n(axis, h) * 2.0 + n(other, pi) + n(third, pi)) / 4.0
    }

    /// Every form of [`matrix_bound`] (second order at `beta` 1/2, 0.15 and 0.02, first order,
    /// the merged edges' third form, dropped) is a lower bound of the edge's six-dimensional form (checked by a dense
    /// eigensolver, independent of the bound's derivation), on rotations by 0 to pi, pseudo-edge
    /// means and their mixtures with a rotation; and the third form is tight on the skew block
    /// of the pseudo-edges (a charge halved would not hold there).
    #[test]
    fn each_edge_form_is_a_lower_bound_of_the_edge_and_the_third_is_tight() {
        let mut tight = 0;
        for k in 0..200 {
            let axis = Vector3::new(
                (k % 7) as f64 - 3.0,
                (k % 5) as f64 - 2.0,
                1.0 + (k % 3) as f64,
            );
            let angle = std::f64::consts::PI * (k as f64 / 199.0);
            let rotation = *crate::so3::exp(&(axis.normalize() * angle)).matrix();
            let pseudo = pseudo_mean(axis);
            let mix = (k % 10) as f64 / 10.0;
            for pm in [rotation, pseudo, pseudo * (1.0 - mix) + rotation * mix] {
                for ((dropped, merged), beta) in
                    [(false, false), (false, true), (true, false), (true, true)]
                        .into_iter()
                        .flat_map(|f| [0.5, 0.15, 0.02].map(|b| (f, b)))
                {
                    let (kept, charge, _) =
                        matrix_bound(&pm, PRODUCT_ERROR, (dropped, merged), beta);
                    let s = slack(&pm, kept, charge);
                    assert!(
                        s >= -1e-12,
                        "{pm} dropped {dropped} merged {merged} beta {beta}: slack {s}"
                    );
                }
            }
            let (kept, charge, _) =
                matrix_bound(&pseudo, PRODUCT_ERROR, (false, true), SECOND_ORDER_BETA);
            assert!(
                kept.abs() < 1e-12 && (charge - 0.5).abs() < 1e-12,
                "{kept} {charge}"
            );
            tight += usize::from(slack(&pseudo, kept, 0.5 * charge) < -0.1);
        }
        assert_eq!(
            tight, 200,
            "a halved charge fails on every pseudo-edge mean"
        );
    }

    /// [`merged_bound`] of a group of edges in both directions between two nodes holds for the
    /// group's six-dimensional form, assembled edge by edge in each edge's own direction (so a
    /// group mean formed in the wrong direction is caught), kept and dropped, with the nodes
    /// at the identity and at random rotations.
    #[test]
    fn a_merged_group_is_bounded_in_either_direction() {
        use crate::multiple::{Edge, MultipleProblem};
        let turn = |v: Vector3<f64>| crate::so3::exp(&v);
        for k in 0..100 {
            let f = k as f64;
            let at = [
                turn(Vector3::new(0.3 * f.sin(), 0.1 * f, -0.2)),
                turn(Vector3::new(-0.1, 0.7 * f.cos(), 0.05 * f)),
            ];
            let edge = |i: usize, v: Vector3<f64>, weight: f64| {
                let j = 1 - i;
                // near consistency at `at` (R_ij R_i = R_j), turned by v
                let rotation = turn(v) * at[j] * at[i].transpose();
                Edge {
                    i,
                    j,
                    rotation,
                    weight,
                }
            };
            let edges = vec![
                edge(0, Vector3::new(0.2, 0.1 * (f % 3.0), 0.0), 1.0),
                edge(1, Vector3::new(0.0, -0.3, 0.1 * (f % 5.0)), 0.7),
                edge(
                    k % 2,
                    Vector3::new(1.5, 0.2 * f.cos(), -0.4),
                    0.2 + 0.01 * f,
                ),
            ];
            let p = MultipleProblem::new(2, edges.clone()).unwrap();
            let mut t = Matrix6::zeros();
            for e in &edges {
                let pm = edge_product(e, &at);
                let sym = 0.5 * (pm + pm.transpose());
                let (a, b) = (3 * e.i, 3 * e.j);
                for (r, c, m) in [
                    (a, a, sym),
                    (b, b, sym),
                    (a, b, -pm),
                    (b, a, -pm.transpose()),
                ] {
                    let mut v = t.fixed_view_mut::<3, 3>(r, c);
                    v += e.weight * m;
                }
            }
            for dropped in [false, true] {
                let (kept, charge) = merged_bound(&[0, 1, 2], &p, &at, dropped, 0.5);
                let id = Matrix3::identity();
                let mut b = Matrix6::zeros();
                b.fixed_view_mut::<3, 3>(0, 0)
                    .copy_from(&((kept - charge) * id));
                b.fixed_view_mut::<3, 3>(3, 3)
                    .copy_from(&((kept - charge) * id));
                b.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-kept * id));
                b.fixed_view_mut::<3, 3>(3, 0).copy_from(&(-kept * id));
                let s = (t - b).symmetric_eigen().eigenvalues.min();
                assert!(s >= -1e-12, "group {k} dropped {dropped}: slack {s}");
            }
        }
    }

    /// The groups are the pairs with more than one edge in either direction, the edge held by
    /// most parts first; in a split, only groups held equally often.
    #[test]
    fn parallel_groups_are_the_pairs_with_several_edges() {
        use crate::multiple::{Edge, MultipleProblem};
        let e = |i, j| Edge {
            i,
            j,
            rotation: Rotation::identity(),
            weight: 1.0,
        };
        let edges = vec![
            e(0, 1),
            e(1, 2),
            e(1, 0),
            e(2, 3),
            e(0, 1),
            e(3, 2),
            e(0, 3),
        ];
        let p = MultipleProblem::new(4, edges).unwrap();
        let whole = parallel_groups(&p, &[1; 7]);
        assert_eq!(whole, vec![vec![0, 2, 4], vec![3, 5]]);
        let sub = parallel_groups(&p, &[0, 1, 1, 1, 1, 0, 1]);
        assert_eq!(sub, vec![vec![2, 4, 0], vec![3, 5]]);
        let split = parallel_groups(&p, &[2, 1, 2, 1, 1, 1, 1]);
        assert_eq!(split, vec![vec![3, 5]]);
    }
}
