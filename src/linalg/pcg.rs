//! Preconditioned conjugate gradients `[M6]`, `[M6b]` for any symmetric positive definite
//! operator: a [`super::block_pattern::BlockPattern`] matrix's product, or a matrix-free one
//! (the simultaneous certificate's coupling system, `[H25]`).

/// `apply(x, y)` sets `y = A x` (the operator; `y` is overwritten).
pub(crate) type ApplyOperator<'a> = &'a (dyn Fn(&[f64], &mut [f64]) + Sync);

/// `apply(r, z)` sets `z[k] = M^{-1} r[k]` for every column `k` given (a preconditioner).
pub(crate) type ApplyPreconditioner<'a> = &'a (dyn Fn(&[&[f64]], &mut [&mut [f64]]) + Sync);

/// Unknowns from which [`pcg`] splits its columns over the machine's threads.
const PARALLEL_DIMENSION: usize = 3000;

/// Preconditioned conjugate gradients for the columns of `b` (each an independent system with
/// the same matrix), run in lockstep so that the preconditioner is applied to all active
/// columns at once: `apply_m(r, z)` sets `z[k] = M^{-1} r[k]` for every column `k` given.
/// A column stops when its residual is at most `rel_tol ||b_k||`, or after `max_iter`
/// iterations, or every column when `stop_at` has passed (checked once per iteration). Returns the solutions and the iterations run; `None` on non-positive curvature
/// (the matrix is not positive definite).
///
/// The columns are independent, so from [`PARALLEL_DIMENSION`] unknowns they are split into
/// consecutive groups, one per thread, each run in lockstep on its own: each column's
/// iterates are the same arithmetic as alone (the preconditioner sees fewer columns at once).
pub(crate) fn pcg(
    apply_a: ApplyOperator<'_>,
    apply_m: ApplyPreconditioner<'_>,
    b: &[Vec<f64>],
    rel_tol: f64,
    limits: (usize, Option<std::time::Instant>),
) -> Option<(Vec<Vec<f64>>, usize)> {
    let dim = b.first().map_or(0, Vec::len);
    let mut columns: Vec<&Vec<f64>> = b.iter().collect();
    let parallel = dim >= PARALLEL_DIMENSION && columns.len() > 1;
    let parts = crate::linalg::threads::in_chunks(&mut columns, parallel, |_, part| {
        pcg_lockstep(apply_a, apply_m, part, rel_tol, limits)
    });
    let mut x = Vec::with_capacity(b.len());
    let mut iterations = 0;
    for part in parts {
        let (xs, its) = part?;
        x.extend(xs);
        iterations = iterations.max(its);
    }
    Some((x, iterations))
}

/// [`pcg`] on one group of columns, in lockstep.
fn pcg_lockstep(
    apply_a: ApplyOperator<'_>,
    apply_m: ApplyPreconditioner<'_>,
    b: &[&Vec<f64>],
    rel_tol: f64,
    (max_iter, stop_at): (usize, Option<std::time::Instant>),
) -> Option<(Vec<Vec<f64>>, usize)> {
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
    let k = b.len();
    let dim = b.first().map_or(0, |c| c.len());
    let bnorm: Vec<f64> = b.iter().map(|c| dot(c, c).sqrt()).collect();
    let mut x = vec![vec![0.0; dim]; k];
    let mut r: Vec<Vec<f64>> = b.iter().map(|c| c.to_vec()).collect();
    let mut z = vec![vec![0.0; dim]; k];
    let mut active: Vec<usize> = (0..k).filter(|&c| bnorm[c] > 0.0).collect();
    let precondition = |r: &[Vec<f64>], z: &mut [Vec<f64>], cols: &[usize]| {
        let rs: Vec<&[f64]> = cols.iter().map(|&c| r[c].as_slice()).collect();
        let mut zs: Vec<&mut [f64]> = z
            .iter_mut()
            .enumerate()
            .filter(|(c, _)| cols.contains(c))
            .map(|(_, v)| v.as_mut_slice())
            .collect();
        apply_m(&rs, &mut zs);
    };
    precondition(&r, &mut z, &active);
    let mut p = z.clone();
    let mut rz: Vec<f64> = (0..k).map(|c| dot(&r[c], &z[c])).collect();
    let mut ap = vec![0.0; dim];
    let mut iterations = 0;
    for _ in 0..max_iter {
        if active.is_empty() || stop_at.is_some_and(|t| std::time::Instant::now() >= t) {
            break;
        }
        iterations += 1;
        for &c in &active {
            apply_a(&p[c], &mut ap);
            let pap = dot(&p[c], &ap);
            if pap <= 0.0 || !pap.is_finite() {
                return None;
            }
            let alpha = rz[c] / pap;
            for i in 0..dim {
                x[c][i] += alpha * p[c][i];
                r[c][i] -= alpha * ap[i];
            }
        }
        active.retain(|&c| dot(&r[c], &r[c]).sqrt() > rel_tol * bnorm[c]);
        if active.is_empty() {
            break;
        }
        precondition(&r, &mut z, &active);
        for &c in &active {
            let rz_new = dot(&r[c], &z[c]);
            let beta = rz_new / rz[c];
            rz[c] = rz_new;
            for i in 0..dim {
                p[c][i] = z[c][i] + beta * p[c][i];
            }
        }
    }
    Some((x, iterations))
}
