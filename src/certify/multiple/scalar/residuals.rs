//! Step 3 of the scalar comparison `[D13]`: the gauge directions. `M v0 = r'` with
//! `r'_i = R_i^T (S Y)_i` (zero at a critical point) and `v0^T M v0 = sum_i r'_i`: rigorous upper
//! bounds `rho1 >= ||r'||_F` and `rho0 >= ||sum_i r'_i||_F`, the latter in double-double when the
//! plain evaluation's rounding (which grows like `n u d`) would matter.

use crate::linalg::cholesky::{UNIT_ROUNDOFF, gamma};
use crate::linalg::compensated::Accumulator;
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use nalgebra::Matrix3;

use super::analysis::fro;

/// `(rho1, rho0)` of step 3 for the comparison's `target` (the double-double `rho0` is computed
/// only when the plain one exceeds `1e-3 n target`).
pub(super) fn residual_bounds(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    deg_n: &[usize],
    target: f64,
) -> (f64, f64) {
    let n = problem.num_rotations();
    let nodes = node_residuals(problem, rotations, lambdas, deg_n, &|_| None);
    let rho1 = nodes.rho1_sq.sqrt() * (1.0 + gamma(n + 4));
    let rho0_plain = (fro(&nodes.sum) + nodes.err_sum + gamma(n + 4) * nodes.abs_sum)
        * (1.0 + 8.0 * UNIT_ROUNDOFF);
    // the plain bound's rounding grows like n u d: above a tiny fraction of the target, evaluate
    // v0^T M v0 in double-double instead (its true size is the rounding of Lambda, ~sqrt(n) u d)
    let rho0 = if rho0_plain * 1e3 > target.max(0.0) * n as f64 {
        rho0_plain.min(gauge_block_bound(problem, rotations, lambdas))
    } else {
        rho0_plain
    };
    (rho1, rho0)
}

/// The blocks `r'_i = R_i^T (S Y)_i` of step 3, bounded node by node.
pub(super) struct NodeResiduals {
    /// `sum_i ||r'_i||_F^2`, each norm rounded up by its error bound.
    pub rho1_sq: f64,
    /// `sum_i fl(r'_i)`.
    pub sum: Matrix3<f64>,
    /// The sum of the blocks' error bounds (Frobenius).
    pub err_sum: f64,
    /// `sum_i ||fl(r'_i)||_F`.
    pub abs_sum: f64,
}

/// Step 3's blocks with `(S Y)_i = (Q Y)_i - sym(Lambda_i) R_i + E_i`, where `extra(i)` gives
/// `fl(E_i)` and a bound on the error of each of its entries (`None`: `E_i = 0`; the hub
/// comparison's spoke terms, `paper-notes/gravity.md` `[G13]`).
pub(super) fn node_residuals(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    deg_n: &[usize],
    extra: &dyn Fn(usize) -> Option<(Matrix3<f64>, f64)>,
) -> NodeResiduals {
    let (qy, qy_err, qy_abs) = laplacian_products(problem, rotations);
    let u = UNIT_ROUNDOFF;
    let mut out = NodeResiduals {
        rho1_sq: 0.0,
        sum: Matrix3::zeros(),
        err_sum: 0.0,
        abs_sum: 0.0,
    };
    for i in 0..problem.num_rotations() {
        let ri = rotations[i].matrix();
        let lam = 0.5 * (lambdas[i] + lambdas[i].transpose());
        let (e, e_err) = extra(i).unwrap_or((Matrix3::zeros(), 0.0));
        let sy = qy[i] - lam * ri + e;
        let r = ri.transpose() * sy;
        // entrywise error of sy: the Q Y sum, the symmetrisation (u |Lambda|), the product
        // Lambda R (gamma_3 3.4 |Lambda|max), the extra term's own and the two additions
        // (2u |sy| each)
        let lam_max = lambdas[i].amax();
        let e_sy = (qy_err[i] + gamma(deg_n[i] + 2) * qy_abs[i]) * (1.0 + 4.0 * u)
            + (gamma(4) * 3.4 + 2.0 * u) * lam_max * 3.0
            + e_err
            + 4.0 * u * (sy.amax() + e.amax());
        // R^T sy: gamma_3 (|R^T| |sy|) <= gamma_3 3.4 |sy|max, plus |R^T| e_sy <= 3.4 e_sy;
        // Frobenius of a 3x3 error <= 3 x its largest entry bound
        let e_r = 3.0 * (gamma(4) * 3.4 * sy.amax() + 3.4 * e_sy) * (1.0 + 1e-12);
        let rn = fro(&r) * (1.0 + 4.0 * u) + e_r;
        out.rho1_sq += rn * rn;
        out.sum += r;
        out.err_sum += e_r;
        out.abs_sum += fro(&r);
    }
    out
}

/// `(Q Y)_i` in plain floating point with a running entrywise error bound (Higham Lemma 3.1 and
/// 3.5, `|R|` entries <= 1 + 1e-3): each edge term `w (R_i - R_ij^T R_j)` has entries <= `4.4 w`
/// and is formed with error <= `w (gamma_3 3.4 + 2u 4.4)` per entry; summing the `deg_i` terms
/// adds `gamma(deg_i + 1)` times the sum of their magnitudes (returned third).
fn laplacian_products(
    problem: &MultipleProblem,
    rotations: &[Rotation],
) -> (Vec<Matrix3<f64>>, Vec<f64>, Vec<f64>) {
    let n = problem.num_rotations();
    let mut qy = vec![Matrix3::zeros(); n];
    let mut qy_err = vec![0.0f64; n];
    let mut qy_abs = vec![0.0f64; n];
    let edge_err = gamma(3) * 3.4 + 2.0 * UNIT_ROUNDOFF * 4.4;
    for e in problem.edges() {
        let rij = e.rotation.matrix();
        let (ri, rj) = (rotations[e.i].matrix(), rotations[e.j].matrix());
        let ti = e.weight * (ri - rij.transpose() * rj);
        let tj = e.weight * (rj - rij * ri);
        qy[e.i] += ti;
        qy[e.j] += tj;
        qy_err[e.i] += e.weight * edge_err;
        qy_err[e.j] += e.weight * edge_err;
        qy_abs[e.i] += ti.amax();
        qy_abs[e.j] += tj.amax();
    }
    (qy, qy_err, qy_abs)
}

/// A rigorous upper bound on `||v0^T M v0||_F = ||sum_i r'_i||_F` (step 3), evaluated in
/// double-double from the data: `v0^T M v0 = sum_i G_i` with
/// `G_i = sum_{e at i} w_e (R_i^T R_i - (P_e + P_e^T) / 2) - R_i^T sym(Lambda_i) R_i`, each a
/// symmetric 3 x 3 matrix whose entries are sums of triple and quadruple products of stored
/// numbers ([`Accumulator`]). Summed per node first: each `G_i` cancels to the rounding of
/// `Lambda_i`, so the compensated sum's error bound (quadratic in the number of terms) stays
/// at the level of that rounding instead of growing with the number of edges.
pub(super) fn gauge_block_bound(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
) -> f64 {
    // the six entries p <= q
    const ENTRIES: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
    let adjacency = problem.adjacency();
    let mut total = [Accumulator::default(); 6];
    let mut node_bounds = 0.0f64;
    for (i, (r, lam)) in rotations.iter().zip(lambdas).enumerate() {
        let r = r.matrix();
        let mut acc = [Accumulator::default(); 6];
        for &(_, k) in adjacency.neighbours(i) {
            let e = &problem.edges()[k];
            let (ra, rb, rab) = (
                rotations[e.i].matrix(),
                rotations[e.j].matrix(),
                e.rotation.matrix(),
            );
            // P_e = R_a^T R_ab^T R_b; halving the weight is exact
            let half = -0.5 * e.weight;
            for (x, &(p, q)) in acc.iter_mut().zip(&ENTRIES) {
                for k in 0..3 {
                    x.add_triple(e.weight, r[(k, p)], r[(k, q)]);
                    for l in 0..3 {
                        x.add_quad(half, ra[(k, p)], rab[(l, k)], rb[(l, q)]);
                        x.add_quad(half, ra[(k, q)], rab[(l, k)], rb[(l, p)]);
                    }
                }
            }
        }
        for (x, &(p, q)) in acc.iter_mut().zip(&ENTRIES) {
            for k in 0..3 {
                for l in 0..3 {
                    // sym(Lambda)_kl = Lambda_kl / 2 + Lambda_lk / 2 (halving is exact)
                    x.add_triple(-0.5 * lam[(k, l)], r[(k, p)], r[(l, q)]);
                    x.add_triple(-0.5 * lam[(l, k)], r[(k, p)], r[(l, q)]);
                }
            }
        }
        for (t, x) in total.iter_mut().zip(&acc) {
            let (hi, lo) = x.parts();
            t.add_product(hi, 1.0);
            t.add_product(lo, 1.0);
            node_bounds += x.parts_bound();
        }
    }
    let sq: f64 = total
        .iter()
        .zip(&ENTRIES)
        .map(|(x, &(p, q))| {
            let v = x.value().abs() + x.bound();
            if p == q { v * v } else { 2.0 * v * v }
        })
        .sum();
    // every entry's error: the total's own bound plus the nodes' bounds (all of them charged
    // to every entry), with 1 + gamma(6n) for summing the nodes' bounds in floating point
    let node_bounds = node_bounds * (1.0 + gamma(6 * rotations.len() + 2));
    let bound = (sq.sqrt() + 3.0 * node_bounds) * (1.0 + 8.0 * UNIT_ROUNDOFF);
    if bound.is_finite() {
        bound
    } else {
        f64::INFINITY
    }
}
