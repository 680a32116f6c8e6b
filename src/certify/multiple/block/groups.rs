//! The block comparison `[A15]` in regions (`paper-notes/anisotropic.md` `[A15]`, "Regions"):
//! the grouped scalar comparison of `[D13]` ("Groups") with a `3 x 3` weight per node. The
//! edges between regions are dropped from the factorised block Laplacian (charged as dropped
//! edges), each component `g` of what is left proves its own pencil (exactly three negative
//! pivots per component), so `x1^T M x1 >= zeta |x1|^2` on the space `U` of the `x` with
//! `sum_{i in g} W_i x_i = 0` in every component; the `3k` coarse directions are bounded by the
//! shared coarse correction (`certify/multiple/coarse.rs`).

use super::edges::{self, diagonal_block, edge_matrix};
use super::{BlockAnalysis, BlockComparison, BlockFailure, Proven};
use crate::certify::multiple::coarse::{
    BlockOperator, CoarseSpace, GaugeBounds, Layout, ZETA_FRACTION, coarse_terms_gauged,
};
use crate::certify::multiple::multipliers::GaugeTerms;
use crate::certify::multiple::scalar::{fro, orthogonality_defect};
use crate::linalg::UNIT_ROUNDOFF as U;
use crate::linalg::cholesky::gamma;
use crate::linalg::small_symmetric::verified_min_eigenvalue3;
use crate::multiple::MultipleProblem;
use crate::multiple::anisotropic::Information;
use crate::so3::Rotation;
use nalgebra::{Matrix3, Vector3};
use std::time::Instant;

/// Steps 1, 2 and 5 of `[A15]` on the regions' components, then the coarse directions: a
/// proven `lambda_min(S) >= mu` whatever the regions (they decide only whether it proves),
/// the conjugate gradients stopping at `stop_at` (a weaker bound, never a wrong one).
pub(super) fn compare_grouped(
    (problem, information): (&MultipleProblem, &[Information]),
    analysis: &BlockAnalysis,
    (rotations, lambdas): (&[Rotation], &[Matrix3<f64>]),
    (rel, stop_at): (f64, Option<Instant>),
    terms: &GaugeTerms,
) -> std::result::Result<BlockComparison, BlockFailure> {
    let t_max = orthogonality_defect(rotations).map_err(|_| BlockFailure::NotOrthogonal)?;
    let c = edges::edge_blocks(problem, information, rotations, lambdas, &analysis.keep)?;
    let zeta = ZETA_FRACTION * c.d_max;
    let (weights, zeta_free) = super::pencil_weights(&c.delta, zeta);
    if zeta_free <= 0.0 || !zeta_free.is_finite() {
        return Err(BlockFailure::Numerical);
    }
    let (headroom, backward_error) = super::prove_inertia(analysis, problem, &c, &weights)?;
    let space = BlockGroups::new(&analysis.components, &weights).ok_or(BlockFailure::Numerical)?;
    let m = anisotropic_operator(problem, information, rotations, lambdas);
    let gauge = GaugeBounds::of(terms, t_max);
    let coarse = coarse_terms_gauged(&m, &space, gauge, (zeta_free, rel, stop_at))
        .ok_or(BlockFailure::Numerical)?;
    let proven = Proven {
        mu_m: coarse.mu(space.kappa()),
        t_max,
        zeta,
        inertia: (headroom, backward_error),
        kappa: space.kappa(),
        residual_bound: coarse.rho,
    };
    proven.outcome(&c, analysis)
}

/// `M = D^T S D` of an anisotropic problem as `3 x 3` blocks (`M_ij = -E_e`, `M_ii = R_i^T
/// (sum_e F_e - sym Lambda_i) R_i`) with its forming errors.
pub(super) fn anisotropic_operator(
    problem: &MultipleProblem,
    information: &[Information],
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
) -> BlockOperator {
    let n = rotations.len();
    let mut f_sum = vec![Matrix3::zeros(); n];
    let mut traces = vec![0.0f64; n];
    let mut degree = vec![0usize; n];
    let mut form_rows = vec![0.0f64; n];
    let mut blocks = Vec::with_capacity(problem.num_edges());
    for (e, h) in problem.edges().iter().zip(information) {
        let (block, eta) = edge_matrix(h, &e.rotation, &rotations[e.i], &rotations[e.j]);
        let f = h.twice_chordal_matrix();
        for v in [e.i, e.j] {
            f_sum[v] += f;
            traces[v] += h.matrix().trace().abs();
            degree[v] += 1;
            form_rows[v] += eta;
        }
        blocks.push((e.i, e.j, -block));
    }
    let diag = (0..n)
        .map(|i| {
            let (block, err) = diagonal_block(
                &rotations[i],
                &lambdas[i],
                &f_sum[i],
                (traces[i], degree[i]),
            );
            form_rows[i] += err;
            block
        })
        .collect();
    let max_degree = degree.iter().copied().max().unwrap_or(0);
    BlockOperator::new(diag, blocks, &form_rows, max_degree)
}

/// The components and their `3 x 3` weights: `U = {x : sum_{i in g} W_i x_i = 0 for all g}`,
/// its projector `P x = x - E a(x)` (`a_g` the weighted mean `(sum W_i)^{-1} sum W_i x_i`,
/// exact in the proof) and `kappa`.
pub(super) struct BlockGroups<'a> {
    /// The groups; `kappa = max_g sqrt(sum ||W_i||_F^2) / lambda_min(sum W_i)` rounded up
    /// (`|a|^2 <= kappa^2 |x|^2`), `kappa_last` the last group's own.
    layout: Layout<'a>,
    weights: &'a [Matrix3<f64>],
    /// Per component, `(sum W_i^2)^{-1}` (computed: the coefficients of an approximately
    /// orthogonal projection, any of which is valid).
    inverse_sq: Vec<Matrix3<f64>>,
    /// Per component, a proven lower bound on `lambda_min(sum W_i)` (positive).
    sum_low: Vec<f64>,
    /// Per component, its nodes.
    size: Vec<usize>,
}

impl<'a> BlockGroups<'a> {
    pub(super) fn new(of: &'a [usize], weights: &'a [Matrix3<f64>]) -> Option<Self> {
        let count = of.iter().max().map_or(1, |m| m + 1);
        let mut sum = vec![Matrix3::zeros(); count];
        let mut sq = vec![Matrix3::zeros(); count];
        let (mut fro_sq, mut abs, mut size) = (vec![0.0; count], vec![0.0; count], vec![0; count]);
        for (&g, w) in of.iter().zip(weights) {
            let f = fro(w) * (1.0 + 4.0 * U);
            sum[g] += w;
            sq[g] += w * w;
            fro_sq[g] += f * f;
            abs[g] += f;
            size[g] += 1;
        }
        let mut sum_low = Vec::with_capacity(count);
        let (mut kappa, mut kappa_last) = (0.0f64, 0.0f64);
        for g in 0..count {
            let e = gamma(size[g] + 4);
            // the sum's rounding: gamma(|g| + 2) of the magnitudes in every entry
            let low = verified_min_eigenvalue3(&sum[g])? - 3.0 * e * abs[g] * (1.0 + e);
            if low <= 0.0 || !low.is_finite() {
                return None;
            }
            kappa_last = fro_sq[g].sqrt() * (1.0 + e) / low;
            kappa = kappa.max(kappa_last);
            sum_low.push(low);
        }
        let inverse_sq = sq
            .iter()
            .map(|s| s.try_inverse().unwrap_or_else(Matrix3::zeros))
            .collect();
        Some(BlockGroups {
            layout: Layout {
                of,
                count,
                kappa: kappa * (1.0 + 8.0 * U),
                kappa_last: kappa_last * (1.0 + 8.0 * U),
            },
            weights,
            inverse_sq,
            sum_low,
            size,
        })
    }

    /// Per component, `fl(sum W_i z_i)` and `sum ||W_i||_F |z_i|` (its error is at most
    /// `gamma(|g| + 3)` of the latter).
    fn weighted_sums(&self, z: &[f64]) -> (Vec<Vector3<f64>>, Vec<f64>) {
        let mut sums = vec![Vector3::zeros(); self.layout.count];
        let mut mags = vec![0.0f64; self.layout.count];
        for (i, (&g, w)) in self.layout.of.iter().zip(self.weights).enumerate() {
            let x = node(z, i);
            sums[g] += w * x;
            mags[g] += fro(w) * x.norm();
        }
        (sums, mags)
    }

    /// The coefficients `c_g = (sum W_i^2)^{-1} sum W_i y_i` that [`CoarseSpace::project`]
    /// subtracts.
    fn coefficients(&self, y: &[f64]) -> Vec<Vector3<f64>> {
        let (sums, _) = self.weighted_sums(y);
        sums.iter()
            .zip(&self.inverse_sq)
            .map(|(b, inv)| inv * b)
            .collect()
    }
}

/// Node `i`'s three coordinates.
fn node(v: &[f64], i: usize) -> Vector3<f64> {
    Vector3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2])
}

impl CoarseSpace for BlockGroups<'_> {
    fn layout(&self) -> &Layout<'_> {
        &self.layout
    }

    fn project(&self, z: &mut [f64]) {
        let c = self.coefficients(z);
        for (i, (&g, w)) in self.layout.of.iter().zip(self.weights).enumerate() {
            let d = w * c[g];
            for a in 0..3 {
                z[3 * i + a] -= d[a];
            }
        }
    }

    /// `fl(W_i c_g)` errs by at most `gamma(3) ||W_i||_F |c_g|`, the subtraction by `u` of the
    /// result (`2u |p|` with its own rounding).
    fn projection_error(&self, y: &[f64], p: &[f64]) -> f64 {
        let c = self.coefficients(y);
        let products: f64 = self
            .layout
            .of
            .iter()
            .zip(self.weights)
            .map(|(&g, w)| {
                let e = fro(w) * c[g].norm();
                e * e
            })
            .sum();
        let p_norm = p.iter().map(|x| x * x).sum::<f64>().sqrt();
        (gamma(4) * products.sqrt() + 2.0 * U * p_norm) * (1.0 + gamma(p.len() + 2))
    }

    /// With `P` the weighted-mean projector, `(I - P) x` is `a_g(x)` at every node of `g`:
    /// `|a_g| <= (|fl(b_g)| + gamma(|g| + 3) mag_g) / lambda_min(sum W_i)`, and the norm
    /// sums `|g| |a_g|^2`.
    fn off_space(&self, z: &[Vec<f64>]) -> f64 {
        let mut total = 0.0f64;
        for (col, zc) in z.iter().enumerate() {
            let x: Vec<f64> = zc
                .iter()
                .enumerate()
                .map(|(r, v)| v - f64::from(u8::from(col == 3 * self.layout.of[r / 3] + r % 3)))
                .collect();
            let (sums, mags) = self.weighted_sums(&x);
            for g in 0..self.layout.count {
                let e = gamma(self.size[g] + 3);
                let b = sums[g].norm() * (1.0 + gamma(3)) + e * mags[g] * (1.0 + e);
                let a = b / self.sum_low[g];
                total += self.size[g] as f64 * a * a;
            }
        }
        total.sqrt() * (1.0 + gamma(2 * self.layout.count + 8))
    }
}
