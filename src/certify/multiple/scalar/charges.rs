//! Steps 1 and 2 of the scalar comparison `[D13]`: the estimate's orthogonality defects, and the
//! edge-by-edge comparison `M >= (L' - diag(delta)) (x) I_3` (the kept weights of `L'` and the
//! charges `delta`), every quantity rounded in the safe direction.

use super::analysis::fro;
use super::{MAX_ORTHOGONALITY_DEFECT, SECOND_ORDER_BETA, ScalarFailure};
use crate::linalg::cholesky::{UNIT_ROUNDOFF, gamma};
use crate::multiple::{Edge, MultipleProblem};
use crate::so3::Rotation;
use nalgebra::Matrix3;

/// The error of `fl(P_e)` against the exact product: entries of the exact product are <= 3.3 in
/// magnitude (`|R|` entries <= 1 + 1e-3); the two 3-term products err by < 2e-14 per entry,
/// 6e-14 in Frobenius; 2e-13 also covers forming the symmetric and skew parts.
pub(super) const PRODUCT_ERROR: f64 = 2e-13;

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

/// One edge's comparison: its kept weight coefficient and its charge per unit of weight.
/// Second order: `w (alpha_e - beta) |d|^2 - w k_e^2 / (2 beta) (|x_a|^2 + |x_b|^2)`; first order
/// (outliers, `alpha_e < beta`): `w |d|^2 - w c1 (|x_a|^2 + |x_b|^2)`; a dropped edge keeps no
/// weight, so its `beta` may be `alpha_e`. Also `A_e` (for `G_i`).
fn edge_bound(e: &Edge, rotations: &[Rotation], dropped: bool) -> (f64, f64, bool, Matrix3<f64>) {
    let u = UNIT_ROUNDOFF;
    let (ri, rj, rij) = (
        rotations[e.i].matrix(),
        rotations[e.j].matrix(),
        e.rotation.matrix(),
    );
    let pm = ri.transpose() * (rij.transpose() * rj);
    let sym = 0.5 * (pm + pm.transpose());
    // the axial vector of the skew part: ||K||_2 = |k| for a 3 x 3 skew matrix
    let k_e = crate::so3::vee(&pm).norm() * (1.0 + 8.0 * u) + PRODUCT_ERROR;
    // lambda_min(A) >= 1 - ||A - I||_2 >= 1 - ||A - I||_F
    let sym_defect = fro(&(sym - Matrix3::identity()));
    let alpha = 1.0 - (sym_defect * (1.0 + 4.0 * u) + PRODUCT_ERROR);
    let c1 =
        (sym_defect + fro(&(pm - Matrix3::identity()))) * (1.0 + 4.0 * u) + 2.0 * PRODUCT_ERROR;
    let beta = SECOND_ORDER_BETA;
    let (coeff, charge, second) = if dropped {
        let charge = if alpha > 0.0 {
            c1.min(k_e * k_e / (2.0 * alpha) * (1.0 + 8.0 * u))
        } else {
            c1
        };
        (0.0, charge, false)
    } else if alpha - beta > 0.0 && k_e * k_e / (2.0 * beta) < c1 * (alpha - beta) {
        // the smaller charge per unit of weight kept (the condition is roughly lambda_2 >=
        // charge / weight): second order for small residuals, first order for outliers
        (alpha - beta, k_e * k_e / (2.0 * beta), true)
    } else {
        (1.0, c1, false)
    };
    (coeff, charge, second, sym)
}

/// Step 2 for every edge (`copies[k] == 0`: edge `k` is dropped from `L'`), then the diagonal
/// blocks' rest `G_i = M_ii - sum_e w_e A_e` added to the charges.
pub(super) fn edge_charges(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    copies: &[u32],
) -> std::result::Result<EdgeCharges, ScalarFailure> {
    let u = UNIT_ROUNDOFF;
    let n = problem.num_rotations();
    let mut deg_w = vec![0.0f64; n];
    let mut deg_n = vec![0usize; n];
    let mut delta = vec![0.0f64; n];
    let mut sym_sum = vec![Matrix3::zeros(); n];
    let mut reduced = Vec::with_capacity(problem.num_edges());
    let mut second_order_edges = 0usize;
    for (k, e) in problem.edges().iter().enumerate() {
        let (coeff, charge, second, sym) = edge_bound(e, rotations, copies[k] == 0);
        second_order_edges += usize::from(second);
        // rounded towards -inf: a smaller weight only weakens the comparison
        reduced.push(e.weight * coeff * (1.0 - 4.0 * u));
        let dk = e.weight * charge * (1.0 + 8.0 * u);
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
