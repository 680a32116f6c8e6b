//! Two-pass Lanczos without reorthogonalisation `[D7]`: the smallest eigenpair (an *estimate*)
//! of a symmetric operator when thousands of iterations are needed and storing the Krylov basis
//! (memory `m x dim`, reorthogonalisation `m^2 dim`) is not affordable.
//!
//! The first pass runs the three-term recurrence and keeps only the tridiagonal matrix `T_m`;
//! every few steps the smallest eigenvalue `theta` of `T_m` is found by Sturm bisection and its
//! eigenvector `z` by inverse iteration, and the residual estimate `beta_m |z_m|` decides
//! convergence. Without reorthogonalisation the basis loses orthogonality as Ritz values
//! converge, which only produces copies of converged values ("ghosts", Paige): the smallest Ritz
//! value still approximates the smallest eigenvalue. The second pass regenerates the same
//! vectors (the recurrence is deterministic) and accumulates the Ritz vector `V z`; the value
//! returned is that vector's own Rayleigh quotient, so a negative value is a direction of
//! negative curvature whatever the loss of orthogonality did.
//!
//! The operator may be restricted to the orthogonal complement of orthonormal vectors
//! (`deflate`): every new vector is projected off them, so the recurrence works on
//! `P A P` (`P` the projector), as the Riemannian staircase needs when the columns of its point
//! span the (approximate) null space of its certificate matrix.
//!
//! ```
//! use rotavg::linalg::two_pass_lanczos::{TwoPassSettings, two_pass_smallest};
//! // a diagonal operator 1, 2, ..., 2000 with one negative entry -1e-3: width 2000, the
//! // negative value 1e-3 below the next
//! let n = 2000;
//! let d: Vec<f64> = (0..n).map(|i| if i == 7 { -1e-3 } else { 1.0 + i as f64 }).collect();
//! let op = |x: &[f64], y: &mut [f64]| y.iter_mut().zip(x).zip(&d).for_each(|((y, x), d)| *y = d * x);
//! let r = two_pass_smallest(n, op, 2000.0, &TwoPassSettings::default(), &[]);
//! assert!((r.value + 1e-3).abs() < 1e-6, "{}", r.value);
//! assert!(r.vector[7].abs() > 0.999);
//! ```

use super::lanczos::{LanczosResult, LanczosStop};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};

/// Settings of [`two_pass_smallest`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TwoPassSettings {
    /// Most Lanczos steps of the first pass (the second pass repeats as many; memory does not
    /// grow with it: a few vectors and the tridiagonal matrix).
    pub max_iterations: usize,
    /// Converged when the residual estimate `beta_m |z_m| <= tolerance * scale`.
    pub tolerance: f64,
    /// Steps between two convergence tests (each a Sturm bisection of `T_m`, `O(64 m)`).
    pub check_every: usize,
    /// Seed of the random start vector.
    pub seed: u64,
}

impl Default for TwoPassSettings {
    fn default() -> Self {
        TwoPassSettings {
            max_iterations: 3000,
            tolerance: 1e-10,
            check_every: 20,
            seed: 0x5eed,
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    // four accumulators: the compiler vectorises them (one serial sum does not)
    let mut s = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for k in 0..4 {
            s[k] += x[k] * y[k];
        }
    }
    let tail: f64 = ra.iter().zip(rb).map(|(x, y)| x * y).sum();
    (s[0] + s[1]) + (s[2] + s[3]) + tail
}

fn project_off(deflate: &[Vec<f64>], w: &mut [f64]) {
    for u in deflate {
        let c = dot(u, w);
        w.iter_mut().zip(u).for_each(|(x, u)| *x -= c * u);
    }
}

/// The number of eigenvalues of the symmetric tridiagonal `T` (diagonal `a`, off-diagonal `b`)
/// below `x` (Sturm count: negative pivots of `T - x I = L D L^T`).
fn sturm_count(a: &[f64], b: &[f64], x: f64) -> usize {
    let mut count = 0;
    let mut d = 1.0f64;
    for (i, &ai) in a.iter().enumerate() {
        let off = if i > 0 { b[i - 1] * b[i - 1] / d } else { 0.0 };
        d = ai - x - off;
        if d == 0.0 {
            d = -f64::EPSILON * (ai.abs() + x.abs()).max(f64::MIN_POSITIVE);
        }
        if d < 0.0 {
            count += 1;
        }
    }
    count
}

/// The smallest eigenvalue of the tridiagonal `T` by bisection between its Gershgorin bounds.
fn smallest_tridiagonal(a: &[f64], b: &[f64]) -> f64 {
    let m = a.len();
    let radius = |i: usize| {
        (if i > 0 { b[i - 1].abs() } else { 0.0 }) + (if i + 1 < m { b[i].abs() } else { 0.0 })
    };
    let mut lo = (0..m)
        .map(|i| a[i] - radius(i))
        .fold(f64::INFINITY, f64::min);
    let mut hi = (0..m)
        .map(|i| a[i] + radius(i))
        .fold(f64::NEG_INFINITY, f64::max);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid <= lo || mid >= hi {
            break;
        }
        if sturm_count(a, b, mid) >= 1 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    0.5 * (lo + hi)
}

/// A unit eigenvector of the tridiagonal `T` for its eigenvalue `theta`: inverse iteration
/// (three solves with `T - theta I`, Gaussian elimination with partial pivoting).
fn tridiagonal_eigenvector(a: &[f64], b: &[f64], theta: f64) -> Vec<f64> {
    let m = a.len();
    let scale = a
        .iter()
        .chain(b)
        .fold(0.0f64, |s, x| s.max(x.abs()))
        .max(1e-300);
    let tiny = f64::EPSILON * scale;
    let mut z: Vec<f64> = (0..m)
        .map(|i| 1.0 + 0.1 * ((i * 7919) % 13) as f64)
        .collect();
    for _ in 0..3 {
        // LU with partial pivoting of the tridiagonal T - theta I: rows keep three entries
        let (mut d, mut du, mut du2) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
        let mut dl: Vec<f64> = b.to_vec();
        let mut piv = vec![false; m];
        for i in 0..m {
            d[i] = a[i] - theta;
            if i + 1 < m {
                du[i] = b[i];
            }
        }
        for i in 0..m.saturating_sub(1) {
            if d[i].abs() >= dl[i].abs() {
                if d[i] == 0.0 {
                    d[i] = tiny;
                }
                let f = dl[i] / d[i];
                dl[i] = f;
                d[i + 1] -= f * du[i];
            } else {
                // swap rows i and i + 1
                piv[i] = true;
                let f = d[i] / dl[i];
                d[i] = dl[i];
                dl[i] = f;
                let t = du[i];
                du[i] = d[i + 1];
                d[i + 1] = t - f * d[i + 1];
                if i + 2 < m {
                    du2[i] = du[i + 1];
                    du[i + 1] *= -f;
                }
            }
        }
        if m > 0 && d[m - 1] == 0.0 {
            d[m - 1] = tiny;
        }
        // forward: apply the row interchanges and L
        for i in 0..m.saturating_sub(1) {
            if piv[i] {
                z.swap(i, i + 1);
                z[i + 1] -= dl[i] * z[i];
            } else {
                z[i + 1] -= dl[i] * z[i];
            }
        }
        // backward: U (diagonal d, superdiagonals du, du2)
        for i in (0..m).rev() {
            let mut s = z[i];
            if i + 1 < m {
                s -= du[i] * z[i + 1];
            }
            if i + 2 < m {
                s -= du2[i] * z[i + 2];
            }
            z[i] = s / d[i];
        }
        let n = dot(&z, &z).sqrt();
        if !(n.is_finite() && n > 0.0) {
            return (0..m).map(|i| if i == 0 { 1.0 } else { 0.0 }).collect();
        }
        z.iter_mut().for_each(|x| *x /= n);
    }
    z
}

/// The smallest eigenpair (an estimate) of the symmetric operator `op(x, y): y = A x` of
/// dimension `dim` on the orthogonal complement of the orthonormal vectors `deflate`, by
/// two-pass Lanczos without reorthogonalisation (module docs). `scale` estimates `||A||` for
/// the convergence test. The returned value is the Rayleigh quotient of the returned unit
/// vector; `residual` is the first pass's estimate `beta_m |z_m|`.
pub fn two_pass_smallest(
    dim: usize,
    mut op: impl FnMut(&[f64], &mut [f64]),
    scale: f64,
    settings: &TwoPassSettings,
    deflate: &[Vec<f64>],
) -> LanczosResult {
    let scale = scale.abs().max(f64::MIN_POSITIVE);
    let mut rng = StdRng::seed_from_u64(settings.seed);
    let mut start: Vec<f64> = (0..dim).map(|_| rng.random::<f64>() - 0.5).collect();
    project_off(deflate, &mut start);
    project_off(deflate, &mut start);
    let norm = dot(&start, &start).sqrt();
    let empty = |stop| LanczosResult {
        value: 0.0,
        vector: vec![0.0; dim],
        residual: 0.0,
        iterations: 0,
        stop,
    };
    if !(norm.is_finite() && norm > 0.0) {
        return empty(LanczosStop::InvariantSubspace { dimension: 0 });
    }
    start.iter_mut().for_each(|x| *x /= norm);
    let Some(first) = first_pass(&mut op, deflate, &start, scale, settings) else {
        return empty(LanczosStop::InvariantSubspace { dimension: 0 });
    };
    let z = &first.z;
    let mut x = second_pass(&mut op, deflate, start, z, &first.betas);
    project_off(deflate, &mut x);
    let nx = dot(&x, &x).sqrt();
    if nx > 0.0 {
        x.iter_mut().for_each(|xi| *xi /= nx);
    }
    let mut ax = vec![0.0; dim];
    op(&x, &mut ax);
    let value = dot(&x, &ax);
    LanczosResult {
        value,
        vector: x,
        residual: first.residual,
        iterations: z.len(),
        stop: first.stop,
    }
}

/// The smallest Ritz value of `steps` steps of the first pass alone from `start` (no second
/// pass, no Ritz vector): an **estimate** from above of the smallest eigenvalue, for deciding
/// what runs, never part of a bound. In exact arithmetic every Ritz value lies in
/// `[lambda_min, lambda_max]`; without reorthogonalisation they stay within `O(u ||A||)` of that
/// interval (Paige 1980; lost orthogonality only repeats converged values). `None` for a zero or
/// non-finite start.
pub fn smallest_ritz_value(
    mut op: impl FnMut(&[f64], &mut [f64]),
    steps: usize,
    scale: f64,
    start: &[f64],
) -> Option<f64> {
    let norm = dot(start, start).sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        return None;
    }
    let start: Vec<f64> = start.iter().map(|x| x / norm).collect();
    let settings = TwoPassSettings {
        max_iterations: steps,
        tolerance: 0.0,
        check_every: steps.max(1),
        seed: 0,
    };
    let scale = scale.abs().max(f64::MIN_POSITIVE);
    first_pass(&mut op, &[], &start, scale, &settings)
        .map(|f| f.theta)
        .filter(|t| t.is_finite())
}

/// One step of the recurrence on `P A P`: from `(v_prev, v, beta_prev)` to
/// `w = A v - alpha v - beta_prev v_prev` (projected off `deflate`); returns `alpha`.
fn recurrence_step(
    op: &mut dyn FnMut(&[f64], &mut [f64]),
    deflate: &[Vec<f64>],
    v_prev: &[f64],
    v: &[f64],
    beta_prev: f64,
    w: &mut [f64],
) -> f64 {
    op(v, w);
    project_off(deflate, w);
    let alpha = dot(w, v);
    w.iter_mut()
        .zip(v)
        .zip(v_prev)
        .for_each(|((w, v), p)| *w -= alpha * v + beta_prev * p);
    // one local reorthogonalisation against v (cheap; keeps alpha accurate)
    let c = dot(w, v);
    w.iter_mut().zip(v).for_each(|(w, v)| *w -= c * v);
    alpha + c
}

/// What the first pass found: the eigenvector `z` of `T_m` for its smallest eigenvalue, the
/// residual estimate `beta_m |z_m|`, the recurrence's `beta`s (for the second pass) and why it
/// stopped.
struct FirstPass {
    /// The smallest eigenvalue of `T_m`: the smallest Ritz value.
    theta: f64,
    z: Vec<f64>,
    residual: f64,
    betas: Vec<f64>,
    stop: LanczosStop,
}

/// The first pass from the unit vector `start`: the recurrence, keeping only `T_m`, tested every
/// `check_every` steps, at the last and when the subspace is invariant; `None` when no step ran.
fn first_pass(
    op: &mut dyn FnMut(&[f64], &mut [f64]),
    deflate: &[Vec<f64>],
    start: &[f64],
    scale: f64,
    settings: &TwoPassSettings,
) -> Option<FirstPass> {
    let dim = start.len();
    let max = settings.max_iterations.max(1).min(dim);
    let every = settings.check_every.max(1);
    let (mut alphas, mut betas): (Vec<f64>, Vec<f64>) = (Vec::new(), Vec::new());
    let (mut v_prev, mut v, mut w) = (vec![0.0; dim], start.to_vec(), vec![0.0; dim]);
    let mut beta_prev = 0.0;
    for j in 0..max {
        let alpha = recurrence_step(op, deflate, &v_prev, &v, beta_prev, &mut w);
        alphas.push(alpha);
        let beta = dot(&w, &w).sqrt();
        let last = j + 1 == max;
        let invariant = beta.is_nan() || beta <= 1e-14 * scale;
        if (j + 1) % every == 0 || last || invariant {
            let theta = smallest_tridiagonal(&alphas, &betas);
            let z = tridiagonal_eigenvector(&alphas, &betas, theta);
            let residual = if invariant {
                0.0
            } else {
                beta * z.last().map_or(0.0, |x| x.abs())
            };
            let converged = residual <= settings.tolerance * scale;
            if converged || last || invariant {
                let relative = residual / scale;
                let stop = if invariant {
                    LanczosStop::InvariantSubspace { dimension: j + 1 }
                } else if converged {
                    LanczosStop::Converged {
                        residual: relative,
                        threshold: settings.tolerance,
                    }
                } else {
                    LanczosStop::SubspaceLimit {
                        dimension: j + 1,
                        residual: relative,
                        threshold: settings.tolerance,
                    }
                };
                return Some(FirstPass {
                    theta,
                    z,
                    residual,
                    betas,
                    stop,
                });
            }
        }
        betas.push(beta);
        w.iter_mut().for_each(|x| *x /= beta);
        std::mem::swap(&mut v_prev, &mut v);
        std::mem::swap(&mut v, &mut w);
        beta_prev = beta;
    }
    None
}

/// The second pass: the same vectors again from `start` (the recurrence is deterministic, its
/// `beta`s known), accumulating `x = V z`.
fn second_pass(
    op: &mut dyn FnMut(&[f64], &mut [f64]),
    deflate: &[Vec<f64>],
    start: Vec<f64>,
    z: &[f64],
    betas: &[f64],
) -> Vec<f64> {
    let dim = start.len();
    let mut x = vec![0.0; dim];
    let (mut v_prev, mut v, mut w) = (vec![0.0; dim], start, vec![0.0; dim]);
    let mut beta_prev = 0.0;
    for (j, &zj) in z.iter().enumerate() {
        x.iter_mut().zip(&v).for_each(|(x, v)| *x += zj * v);
        if j + 1 == z.len() {
            break;
        }
        recurrence_step(op, deflate, &v_prev, &v, beta_prev, &mut w);
        let beta = betas[j];
        w.iter_mut().for_each(|x| *x /= beta);
        std::mem::swap(&mut v_prev, &mut v);
        std::mem::swap(&mut v, &mut w);
        beta_prev = beta;
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The first pass's smallest Ritz value is never below the smallest eigenvalue (up to
    /// rounding) and equals it once the Krylov space is the whole space; checked against a dense
    /// eigendecomposition of random symmetric matrices with a cluster at the bottom.
    #[test]
    fn smallest_ritz_value_bounds_the_smallest_eigenvalue_from_above() {
        use nalgebra::{DMatrix, DVector};
        let mut rng = StdRng::seed_from_u64(5);
        for dim in [2usize, 7, 40] {
            let q = DMatrix::from_fn(dim, dim, |_, _| rng.random::<f64>() - 0.5)
                .qr()
                .q();
            let spectrum: Vec<f64> = (0..dim)
                .map(|i| {
                    if i < 3 {
                        -1.0 + 1e-3 * i as f64
                    } else {
                        i as f64
                    }
                })
                .collect();
            let a = &q * DMatrix::from_diagonal(&DVector::from_vec(spectrum)) * q.transpose();
            let op = |x: &[f64], y: &mut [f64]| {
                let v = &a * DVector::from_column_slice(x);
                y.copy_from_slice(v.as_slice());
            };
            let start: Vec<f64> = (0..dim).map(|_| rng.random::<f64>() - 0.5).collect();
            let tol = 1e-12 * dim as f64;
            for steps in [1, 3, dim] {
                let v = smallest_ritz_value(op, steps, dim as f64, &start).unwrap();
                assert!(v >= -1.0 - tol, "dim {dim}, {steps} steps: {v}");
                if steps == dim {
                    assert!((v + 1.0).abs() <= 1e-9, "dim {dim}: {v}");
                }
            }
        }
        assert_eq!(smallest_ritz_value(|_, _| {}, 3, 1.0, &[0.0; 3]), None);
    }

    /// The tridiagonal tools against a dense eigendecomposition.
    #[test]
    fn tridiagonal_smallest_pair_matches_dense() {
        let mut rng = StdRng::seed_from_u64(3);
        for m in [1usize, 2, 5, 40] {
            let a: Vec<f64> = (0..m).map(|_| rng.random::<f64>() * 4.0 - 2.0).collect();
            let b: Vec<f64> = (0..m.saturating_sub(1))
                .map(|_| rng.random::<f64>() - 0.5)
                .collect();
            let t = nalgebra::DMatrix::from_fn(m, m, |i, j| {
                if i == j {
                    a[i]
                } else if i + 1 == j {
                    b[i]
                } else if j + 1 == i {
                    b[j]
                } else {
                    0.0
                }
            });
            let exact = t.clone().symmetric_eigenvalues().min();
            let theta = smallest_tridiagonal(&a, &b);
            assert!((theta - exact).abs() < 1e-12, "m {m}: {theta} vs {exact}");
            let z = tridiagonal_eigenvector(&a, &b, theta);
            let zv = nalgebra::DVector::from_vec(z);
            let r = (&t * &zv - theta * &zv).norm();
            assert!(r < 1e-10, "m {m}: residual {r}");
        }
    }

    /// Deflation: the smallest eigenvalue on the complement of the deflated vector.
    #[test]
    fn deflated_smallest_of_a_diagonal() {
        let n = 500;
        let d: Vec<f64> = (0..n).map(|i| i as f64 * 0.01).collect();
        let op = |x: &[f64], y: &mut [f64]| {
            y.iter_mut()
                .zip(x)
                .zip(&d)
                .for_each(|((y, x), d)| *y = d * x)
        };
        let mut e0 = vec![0.0; n];
        e0[0] = 1.0;
        let r = two_pass_smallest(n, op, 5.0, &TwoPassSettings::default(), &[e0]);
        assert!((r.value - 0.01).abs() < 1e-8, "{}", r.value);
        assert!(r.vector[1].abs() > 0.999);
    }
}
