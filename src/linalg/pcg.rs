//! Preconditioned conjugate gradients with a block-Jacobi preconditioner on a
//! [`BlockPattern`] matrix `[M6]`.

use super::block_pattern::BlockPattern;
use nalgebra::Matrix3;

/// Preconditioned conjugate gradients (block-Jacobi). `None` on non-positive curvature.
pub(crate) fn pcg(
    pattern: &BlockPattern,
    val: &[f64],
    precond: &[Matrix3<f64>],
    b: &[f64],
    rel_tol: f64,
    max_iter: usize,
) -> Option<Vec<f64>> {
    let bs = pattern.block_size();
    let dim = b.len();
    let apply_m = |r: &[f64], z: &mut [f64]| {
        for (q, m) in precond.iter().enumerate() {
            for a in 0..bs {
                let mut s = 0.0;
                for c in 0..bs {
                    s += m[(a, c)] * r[bs * q + c];
                }
                z[bs * q + a] = s;
            }
        }
    };
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
    let bnorm = dot(b, b).sqrt();
    let mut x = vec![0.0; dim];
    if bnorm == 0.0 {
        return Some(x);
    }
    let mut r = b.to_vec();
    let mut z = vec![0.0; dim];
    apply_m(&r, &mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut ap = vec![0.0; dim];
    for _ in 0..max_iter {
        pattern.sym_mul_flat(val, &p, &mut ap);
        let pap = dot(&p, &ap);
        if pap <= 0.0 || !pap.is_finite() {
            return None;
        }
        let alpha = rz / pap;
        for k in 0..dim {
            x[k] += alpha * p[k];
            r[k] -= alpha * ap[k];
        }
        if dot(&r, &r).sqrt() <= rel_tol * bnorm {
            break;
        }
        apply_m(&r, &mut z);
        let rz_new = dot(&r, &z);
        let beta = rz_new / rz;
        rz = rz_new;
        for k in 0..dim {
            p[k] = z[k] + beta * p[k];
        }
    }
    Some(x)
}
