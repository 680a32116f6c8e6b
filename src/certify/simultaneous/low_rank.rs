//! The couplings of least norm of the dual certificate at the estimate `[H15]` in low-rank form
//! (`paper-notes/conjugate.md` `[H25]`): no `n x n` matrix, no `3n x 3n` system.
//!
//! With `p_i = vec(R_i)` (columns stacked) and `u_ij = vee(R_j R_i^T) = B_i p_j / 2`
//! (`B_i = [hat(r_i^1), hat(r_i^2), hat(r_i^3)]`, `r_i^c` the columns of `R_i`), the least-norm
//! couplings `gamma = A^T y` are `gamma_ij = u_ij . (y_i - y_j) / 2 = (p_j . q_i + p_i . q_j) / 4`
//! with `q_i = B_i^T y_i = [y_i x r_i^c]_c`: the coupling matrix is
//! `Gamma = (P Q^T + Q P^T) / 4 = (P_+ P_+^T - P_- P_-^T) / 8` with `P_+- = P +- Q` (rank at most
//! 18; its diagonal `p_i . q_i / 2` vanishes in exact arithmetic and is kept: the trace coupling
//! holds on the diagonal blocks too). `y` solves `A A^T y = (a - b) / 2` by conjugate gradients
//! whose products cost `O(n)`: `(A A^T y)_i = B_i (G_PP q_i + G_PQ p_i) / 16`,
//! `G_PP = sum_j p_j p_j^T`, `G_PQ = sum_j p_j q_j^T`. Whatever `y` the iteration ends at, the
//! multipliers are defined from the floating-point `P_+-` and verified as they are; only how
//! close `Z Y` is to zero (and so the bound) depends on it.

use super::multipliers::PointTerms;
use crate::linalg::gamma;
use crate::linalg::pcg::pcg;
use nalgebra::{Matrix3, SMatrix, SVector, Vector3};
use std::ops::AddAssign;

/// A 9-vector (`vec` of a `3 x 3` matrix, columns stacked).
pub(super) type Vec9 = SVector<f64, 9>;
type Mat9 = SMatrix<f64, 9, 9>;

/// Relative residual at which the conjugate gradients on `A A^T y = rhs` stop.
const CG_TOLERANCE: f64 = 1e-13;
/// The most conjugate-gradient iterations (each `O(n)`).
const CG_MAX_ITERATIONS: usize = 500;

/// The least-norm couplings in low-rank form at a point `(R, S)`, with what the multipliers
/// need: `R_i`, `C_i = S R_i` and `G = Q Y` of both sides.
pub(super) struct LowRankCouplings {
    /// `R_i`, `C_i`, `G = Q Y` of both sides and the coupling system's right side.
    pub point: PointTerms,
    /// The rows of `P_+ = a P + Q / a` and `P_- = a P - Q / a` (`a` a power of two):
    /// `Gamma = (P_+ P_+^T - P_- P_-^T) / 8`.
    pub plus: Vec<Vec9>,
    pub minus: Vec<Vec9>,
    /// Conjugate-gradient iterations and the relative residual they ended at.
    pub iterations: usize,
    pub residual: f64,
}

/// `vec(R)`, columns stacked.
fn vec9(r: &Matrix3<f64>) -> Vec9 {
    Vec9::from_column_slice(r.as_slice())
}

/// `B^T y = [y x r^c]_c` for `B = [hat(r^1), hat(r^2), hat(r^3)]`.
fn b_transpose(r: &Matrix3<f64>, y: &Vector3<f64>) -> Vec9 {
    let mut q = Vec9::zeros();
    for c in 0..3 {
        let v = y.cross(&r.column(c).into_owned());
        q.fixed_rows_mut::<3>(3 * c).copy_from(&v);
    }
    q
}

/// `B v = sum_c r^c x v_c`.
fn b_times(r: &Matrix3<f64>, v: &Vec9) -> Vector3<f64> {
    (0..3)
        .map(|c| {
            r.column(c)
                .into_owned()
                .cross(&v.fixed_rows::<3>(3 * c).into_owned())
        })
        .sum()
}

/// `sum_i a_i b_i^T` over 9-vectors.
fn gram(a: &[Vec9], b: &[Vec9]) -> Mat9 {
    a.iter()
        .zip(b)
        .fold(Mat9::zeros(), |acc, (x, y)| acc + x * y.transpose())
}

/// `A A^T y` (blocks of 3), through `q_i = B_i^T y_i` and `G_PQ`.
fn coupling_gram_times(
    rs: &[Matrix3<f64>],
    ps: &[Vec9],
    gpp: &Mat9,
    y: &[Vector3<f64>],
) -> Vec<Vector3<f64>> {
    let qs: Vec<Vec9> = rs.iter().zip(y).map(|(r, y)| b_transpose(r, y)).collect();
    let gpq = gram(ps, &qs);
    rs.iter()
        .zip(ps.iter().zip(&qs))
        .map(|(r, (p, q))| b_times(r, &(gpp * q + gpq * p)) / 16.0)
        .collect()
}

fn dot(a: &[Vector3<f64>], b: &[Vector3<f64>]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x.dot(y)).sum()
}

/// The orthogonal projector onto the complement of the kernel of `A A^T`: the constant vectors
/// `(e_a)_i` and the gauge directions `(R_i e_a)_i` (six, not orthogonal to each other).
struct KernelProjector<'a> {
    rs: &'a [Matrix3<f64>],
    gram_inverse: SMatrix<f64, 6, 6>,
}

impl<'a> KernelProjector<'a> {
    fn new(rs: &'a [Matrix3<f64>]) -> Option<Self> {
        let n = rs.len() as f64;
        let sum: Matrix3<f64> = rs.iter().sum();
        // [[n I, sum R_i], [sum R_i^T, n I]]
        let mut g = SMatrix::<f64, 6, 6>::identity() * n;
        g.fixed_view_mut::<3, 3>(0, 3).copy_from(&sum);
        g.fixed_view_mut::<3, 3>(3, 0).copy_from(&sum.transpose());
        g.try_inverse()
            .map(|gram_inverse| KernelProjector { rs, gram_inverse })
    }

    fn project(&self, v: &mut [Vector3<f64>]) {
        let mut k = SVector::<f64, 6>::zeros();
        for (r, x) in self.rs.iter().zip(v.iter()) {
            k.fixed_rows_mut::<3>(0).add_assign(x);
            k.fixed_rows_mut::<3>(3).add_assign(&(r.transpose() * x));
        }
        let c = self.gram_inverse * k;
        let (a, w) = (
            c.fixed_rows::<3>(0).into_owned(),
            c.fixed_rows::<3>(3).into_owned(),
        );
        for (r, x) in self.rs.iter().zip(v.iter_mut()) {
            *x -= a + r * w;
        }
    }
}

/// Preconditioned conjugate gradients on `A A^T y = rhs` (block-Jacobi: the diagonal blocks
/// `B_i G_PP B_i^T / 16`); `rhs` is orthogonal to the kernel (the constants and the gauge
/// directions), so the singular system is consistent. Returns `y`, the iterations and the
/// relative residual.
fn solve_coupling_system(
    rs: &[Matrix3<f64>],
    ps: &[Vec9],
    rhs: &[Vector3<f64>],
) -> (Vec<Vector3<f64>>, usize, f64) {
    let n = rs.len();
    let gpp = gram(ps, ps);
    let scale = gpp.trace() / 9.0;
    let precond: Vec<Matrix3<f64>> = rs
        .iter()
        .map(|r| {
            let block = Matrix3::from_columns(&[0, 1, 2].map(|k| {
                let e = Vector3::ith(k, 1.0);
                b_times(r, &(gpp * b_transpose(r, &e))) / 16.0
            }));
            (block + Matrix3::identity() * (1e-12 * scale))
                .try_inverse()
                .unwrap_or_else(Matrix3::identity)
        })
        .collect();
    let zeros = vec![Vector3::zeros(); n];
    let Some(kernel) = KernelProjector::new(rs) else {
        return (zeros, 0, f64::INFINITY);
    };
    let mut b = rhs.to_vec();
    kernel.project(&mut b);
    let norm_rhs = dot(&b, &b).sqrt();
    if norm_rhs == 0.0 || !norm_rhs.is_finite() {
        return (zeros, 0, 0.0);
    }
    let times = |x: &[f64], out: &mut [f64]| {
        out.copy_from_slice(&flat(&coupling_gram_times(rs, ps, &gpp, &blocks(x))));
    };
    let precondition = |r: &[&[f64]], z: &mut [&mut [f64]]| {
        for (r, z) in r.iter().zip(z.iter_mut()) {
            let mut v: Vec<Vector3<f64>> =
                precond.iter().zip(blocks(r)).map(|(m, v)| m * v).collect();
            kernel.project(&mut v);
            z.copy_from_slice(&flat(&v));
        }
    };
    let solved = pcg(
        &times,
        &precondition,
        &[flat(&b)],
        CG_TOLERANCE,
        (CG_MAX_ITERATIONS, None),
    );
    // non-positive curvature (rounding on a nearly singular system): no couplings, a weaker
    // bound, still verified
    let Some((x, iterations)) = solved else {
        return (zeros, CG_MAX_ITERATIONS, 1.0);
    };
    let y = blocks(&x[0]);
    let mut r = coupling_gram_times(rs, ps, &gpp, &y);
    for (r, b) in r.iter_mut().zip(&b) {
        *r = b - *r;
    }
    kernel.project(&mut r);
    (y, iterations, dot(&r, &r).sqrt() / norm_rhs)
}

/// `3`-vectors stacked into one slice's values.
fn flat(v: &[Vector3<f64>]) -> Vec<f64> {
    v.iter().flat_map(|x| x.iter().copied()).collect()
}

/// A slice of `3k` values as `k` `3`-vectors.
fn blocks(x: &[f64]) -> Vec<Vector3<f64>> {
    x.chunks_exact(3).map(Vector3::from_column_slice).collect()
}

impl LowRankCouplings {
    /// The least-norm couplings at `point`; `None` when a value is not finite.
    pub fn new(point: PointTerms) -> Option<Self> {
        let rs = &point.rs;
        let ps: Vec<Vec9> = rs.iter().map(vec9).collect();
        let (y, iterations, residual) = solve_coupling_system(rs, &ps, &point.rhs);
        let qs: Vec<Vec9> = rs.iter().zip(&y).map(|(r, y)| b_transpose(r, y)).collect();
        // (a P + Q / a)(..)^T - (a P - Q / a)(..)^T = 2 (P Q^T + Q P^T) for any a; a power of two
        // near sqrt(|Q| / |P|) balances the halves: their norms about sqrt(|P| |Q|) each
        // instead of |P| (|Q| << |P| near a critical point), which the factorisation's border
        // and its backward error scale with
        let norm = |v: &[Vec9]| v.iter().map(|x| x.norm_squared()).sum::<f64>().sqrt();
        let ratio = (norm(&qs) / norm(&ps)).sqrt();
        let a = if ratio > 0.0 && ratio.is_finite() {
            2f64.powi(ratio.log2().round().clamp(-60.0, 60.0) as i32)
        } else {
            1.0
        };
        let plus: Vec<Vec9> = ps.iter().zip(&qs).map(|(p, q)| p * a + q / a).collect();
        let minus: Vec<Vec9> = ps.iter().zip(&qs).map(|(p, q)| p * a - q / a).collect();
        let finite = plus
            .iter()
            .chain(&minus)
            .all(|v| v.iter().all(|x| x.is_finite()));
        finite.then_some(LowRankCouplings {
            point,
            plus,
            minus,
            iterations,
            residual,
        })
    }

    /// `H_i = sum_j Gamma_ij V_j` for every `i` (`V_j` 3 x k blocks, here `3 x 3` or `3 x 1`),
    /// and an entrywise bound on its rounding error: `T_k^+- = sum_j P_+-(j, k) V_j` first, then
    /// `H_i = sum_k (P_+(i, k) T_k^+ - P_-(i, k) T_k^-) / 8`; each entry a sum of `n + 18`
    /// products, within `gamma(n + 20)` of the sum of their magnitudes.
    pub fn times<const C: usize>(
        &self,
        v: &[SMatrix<f64, 3, C>],
    ) -> (Vec<SMatrix<f64, 3, C>>, Vec<SMatrix<f64, 3, C>>) {
        let n = self.plus.len();
        let zero = SMatrix::<f64, 3, C>::zeros();
        let (mut tp, mut tm) = ([zero; 9], [zero; 9]);
        let (mut ap, mut am) = ([zero; 9], [zero; 9]);
        for ((p, m), x) in self.plus.iter().zip(&self.minus).zip(v) {
            let xa = x.abs();
            for k in 0..9 {
                tp[k] += x * p[k];
                tm[k] += x * m[k];
                ap[k] += xa * p[k].abs();
                am[k] += xa * m[k].abs();
            }
        }
        let g = gamma(n + 20);
        let mut out = Vec::with_capacity(n);
        let mut err = Vec::with_capacity(n);
        for (p, m) in self.plus.iter().zip(&self.minus) {
            let (mut h, mut e) = (zero, zero);
            for k in 0..9 {
                h += tp[k] * p[k] - tm[k] * m[k];
                e += ap[k] * p[k].abs() + am[k] * m[k].abs();
            }
            out.push(h / 8.0);
            err.push(e * (g / 8.0));
        }
        (out, err)
    }

    /// The `2n` multipliers complementary slackness fixes for these couplings:
    /// `Lambda_R,i = sym((G_R,i - H_R,i / 2) R_i^T)`, `Lambda_C,i = sym((G_C,i + H_C,i / 2) C_i^T)`
    /// with `H_i = sum_j Gamma_ij Y_j` (the diagonal included).
    pub fn lambdas(&self) -> Vec<Matrix3<f64>> {
        let t = &self.point;
        let (hr, _) = self.times(&t.rs);
        let (hc, _) = self.times(&t.cs);
        let sym = |m: Matrix3<f64>| (m + m.transpose()) * 0.5;
        let mut lambdas: Vec<Matrix3<f64>> = (0..t.rs.len())
            .map(|i| sym((t.gr[i] - hr[i] * 0.5) * t.rs[i].transpose()))
            .collect();
        lambdas.extend((0..t.cs.len()).map(|i| sym((t.gc[i] + hc[i] * 0.5) * t.cs[i].transpose())));
        lambdas
    }

    /// `Gamma_ij` (the diagonal included), for tests.
    #[cfg(test)]
    pub fn coupling(&self, i: usize, j: usize) -> f64 {
        (self.plus[i].dot(&self.plus[j]) - self.minus[i].dot(&self.minus[j])) / 8.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certify::simultaneous::grounded::tests::rig_of;
    use crate::certify::simultaneous::multipliers::EstimateMultipliers;
    use crate::so3::Rotation;
    use crate::so3::perturb_gaussian;
    use rand::SeedableRng;

    /// The low-rank couplings are the dense least-norm ones (`multipliers.rs`, a dense Cholesky
    /// of `A A^T` plus its kernel's fill), at the planted point of noisy rigs (not critical: the
    /// right side and the couplings are not small) and 0.02 rad off it; and their multipliers
    /// agree.
    #[test]
    fn the_low_rank_couplings_are_the_dense_least_norm_ones() {
        for (seed, off) in [(3u64, 0.0), (4, 0.02)] {
            let (right, left, truth, s) = rig_of(25, 80, seed, 0.03);
            let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
            let r: Vec<Rotation> = truth
                .iter()
                .map(|r| perturb_gaussian(r, off, &mut rng))
                .collect();
            let at = || PointTerms::new(&right, &left, &r, &s).unwrap();
            let dense = EstimateMultipliers::new(at()).unwrap();
            let low = LowRankCouplings::new(at()).unwrap();
            assert!(low.residual < 1e-10, "CG residual {}", low.residual);
            let scale = dense.least_norm.iter().fold(0.0f64, |m, g| m.max(g.abs()));
            for (k, &(i, j)) in dense.pairs.iter().enumerate() {
                let d = (low.coupling(i, j) - dense.least_norm[k]).abs();
                assert!(d <= 1e-8 * scale, "pair ({i},{j}): {d:e} of {scale:e}");
            }
            let ld = dense.lambdas(&dense.least_norm);
            let ll = low.lambdas();
            let lscale = ld.iter().map(|l| l.norm()).fold(0.0, f64::max);
            for (a, b) in ld.iter().zip(&ll) {
                assert!((a - b).norm() <= 1e-8 * lscale);
            }
        }
    }
}
