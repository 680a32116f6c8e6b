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
    let never: Converged<'_> = &|_, _, _| false;
    pcg_from((apply_a, apply_m), (b, None), (rel_tol, never), limits)
}

/// `enough(k, x_k, r_k)`: column `k` (of `b`) has converged at the iterate `x_k` with the
/// residual `r_k` (asked only while its relative residual is above the tolerance).
pub(crate) type Converged<'a> = &'a (dyn Fn(usize, &[f64], &[f64]) -> bool + Sync);

/// [`pcg`] from the starting iterates `x0` (zero when `None`; one product per column to form
/// their residuals), a column also stopping when `enough` says so.
pub(crate) fn pcg_from(
    (apply_a, apply_m): (ApplyOperator<'_>, ApplyPreconditioner<'_>),
    (b, x0): (&[Vec<f64>], Option<&[Vec<f64>]>),
    (rel_tol, enough): (f64, Converged<'_>),
    limits: (usize, Option<std::time::Instant>),
) -> Option<(Vec<Vec<f64>>, usize)> {
    let dim = b.first().map_or(0, Vec::len);
    let mut columns: Vec<&Vec<f64>> = b.iter().collect();
    let parallel = dim >= PARALLEL_DIMENSION && columns.len() > 1;
    let parts = crate::linalg::threads::in_chunks(&mut columns, parallel, |first, part| {
        let start = x0.map(|x| &x[first..first + part.len()]);
        let enough = |k: usize, x: &[f64], r: &[f64]| enough(first + k, x, r);
        pcg_lockstep(
            (apply_a, apply_m),
            (part, start),
            (rel_tol, &enough),
            limits,
        )
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

/// [`pcg_from`] on one group of columns, in lockstep.
fn pcg_lockstep(
    (apply_a, apply_m): (ApplyOperator<'_>, ApplyPreconditioner<'_>),
    (b, x0): (&[&Vec<f64>], Option<&[Vec<f64>]>),
    (rel_tol, enough): (f64, Converged<'_>),
    (max_iter, stop_at): (usize, Option<std::time::Instant>),
) -> Option<(Vec<Vec<f64>>, usize)> {
    let dot = |x: &[f64], y: &[f64]| x.iter().zip(y).map(|(a, b)| a * b).sum::<f64>();
    let k = b.len();
    let dim = b.first().map_or(0, |c| c.len());
    let bnorm: Vec<f64> = b.iter().map(|c| dot(c, c).sqrt()).collect();
    let (mut x, mut r) = start(apply_a, b, x0);
    let mut z = vec![vec![0.0; dim]; k];
    let converged =
        |c: usize, x: &[f64], r: &[f64]| dot(r, r).sqrt() <= rel_tol * bnorm[c] || enough(c, x, r);
    let mut active: Vec<usize> = (0..k)
        .filter(|&c| bnorm[c] > 0.0 && !converged(c, &x[c], &r[c]))
        .collect();
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
        active.retain(|&c| !converged(c, &x[c], &r[c]));
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

/// The starting iterates (`x0`, or zero) and their residuals `b - A x0`.
fn start(
    apply_a: ApplyOperator<'_>,
    b: &[&Vec<f64>],
    x0: Option<&[Vec<f64>]>,
) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let dim = b.first().map_or(0, |c| c.len());
    let Some(x0) = x0 else {
        return (
            vec![vec![0.0; dim]; b.len()],
            b.iter().map(|c| c.to_vec()).collect(),
        );
    };
    let mut ax = vec![0.0; dim];
    let r = b
        .iter()
        .zip(x0)
        .map(|(bc, xc)| {
            apply_a(xc, &mut ax);
            bc.iter().zip(&ax).map(|(v, a)| v - a).collect()
        })
        .collect();
    (x0.to_vec(), r)
}

#[cfg(test)]
mod tests {
    use super::{Converged, pcg, pcg_from};
    use nalgebra::{DMatrix, DVector};
    use rand::{Rng, SeedableRng};

    /// A random symmetric positive definite matrix of `dim` rows and three right-hand sides.
    fn system(dim: usize, seed: u64) -> (DMatrix<f64>, Vec<Vec<f64>>) {
        let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
        let g = DMatrix::from_fn(dim, dim, |_, _| rng.random::<f64>() - 0.5);
        let a = &g * g.transpose() + DMatrix::identity(dim, dim) * 0.1;
        let b = (0..3)
            .map(|_| (0..dim).map(|_| rng.random::<f64>() - 0.5).collect())
            .collect();
        (a, b)
    }

    /// Stopped by `enough` after a few iterations and resumed from there (`pcg_from`), each
    /// column reaches the relative residual against the dense solution; from the exact
    /// solution no iteration runs and it is returned as given.
    #[test]
    fn a_stopped_solve_resumes_from_its_iterates() {
        let (a, b) = system(40, 3);
        let apply = |x: &[f64], y: &mut [f64]| {
            let v = &a * DVector::from_column_slice(x);
            y.copy_from_slice(v.as_slice());
        };
        let jacobi = |r: &[&[f64]], z: &mut [&mut [f64]]| {
            for (r, z) in r.iter().zip(z.iter_mut()) {
                (0..r.len()).for_each(|i| z[i] = r[i] / a[(i, i)]);
            }
        };
        let small = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>().sqrt();
        // stop each column once its residual has fallen to a tenth of its start
        let start: Vec<f64> = b.iter().map(|c| small(c)).collect();
        let enough: Converged<'_> = &|k, _, r| small(r) <= 0.1 * start[k];
        let limits = (200, None);
        let (early, its) =
            pcg_from((&apply, &jacobi), (&b, None), (1e-10, enough), limits).unwrap();
        assert!((1..40).contains(&its), "{its} iterations");
        let never: Converged<'_> = &|_, _, _| false;
        let resumed = (&b[..], Some(early.as_slice()));
        let (x, _) = pcg_from((&apply, &jacobi), resumed, (1e-10, never), limits).unwrap();
        let chol = a.clone().cholesky().unwrap();
        for (bc, xc) in b.iter().zip(&x) {
            let exact = chol.solve(&DVector::from_column_slice(bc));
            let err = (DVector::from_column_slice(xc) - &exact).norm();
            assert!(err <= 1e-6 * exact.norm(), "{err:e}");
        }
        let exact: Vec<Vec<f64>> = b
            .iter()
            .map(|c| {
                chol.solve(&DVector::from_column_slice(c))
                    .as_slice()
                    .to_vec()
            })
            .collect();
        let from_exact = (&b[..], Some(exact.as_slice()));
        let (same, its) = pcg_from((&apply, &jacobi), from_exact, (1e-8, never), limits).unwrap();
        assert_eq!((same, its), (exact, 0));
        let (plain, _) = pcg(&apply, &jacobi, &b, 1e-10, limits).unwrap();
        assert_eq!(plain.len(), 3);
    }
}
