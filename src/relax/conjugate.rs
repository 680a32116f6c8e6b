//! The SDP relaxation of conjugate averaging (contract section 3) and the rank-one extraction of
//! its solution; the verified lower bound from its multipliers is in
//! [`crate::certify::conjugate`].
//!
//! `s = vec(S)` is **column-major**: `s[3c + r] = S[r][c]` (nalgebra's storage order), and
//! `z = [s; y]` (index 9 is the homogenising `y`). The cost is `g(S) = s^T M s` with
//! `M = sum_i w_i (R_i^T (x) I - I (x) L_i)^T (R_i^T (x) I - I (x) L_i)` `[H2]`. The QCQP
//! `min z^T blkdiag(M, 0) z` subject to `z^T A_k z = b_k` for the 22 constraints of
//! [`constraint_matrices`] `[H3]` is relaxed to `min tr(C Z)`, `Z` PSD 10x10, and solved with
//! Clarabel. The lower bound is recomputed from the multipliers with an independent dense
//! eigenvalue computation `[H8]`; Clarabel's objective is never used as a bound.

use crate::conjugate::ConjugateProblem;
use crate::error::Result;
use crate::relax::clarabel::{Cone, csc, solve_conic};
use crate::relax::settings::{SdpSettings, SdpStatus};
use crate::relax::svec::{svec_index, svec_len, svec_weight};
use crate::so3::{Rotation, project_to_so3};
use nalgebra::{Matrix3, SMatrix, SVector, SymmetricEigen};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// 9x9 matrix.
pub type Mat9 = SMatrix<f64, 9, 9>;
/// 10x10 matrix.
pub type Mat10 = SMatrix<f64, 10, 10>;
/// 10-vector `z = [vec(S); y]`.
pub type Vec10 = SVector<f64, 10>;

/// Index of `S[r][c]` in `z` (column-major `vec`).
pub const fn s_index(r: usize, c: usize) -> usize {
    3 * c + r
}
/// Index of the homogenising variable `y` in `z`.
pub const Y_INDEX: usize = 9;

/// `z = [vec(S); y]` for a 3x3 matrix `S` (column-major `vec`).
pub fn lift(s: &Matrix3<f64>, y: f64) -> Vec10 {
    let mut z = Vec10::zeros();
    z.fixed_rows_mut::<9>(0).copy_from_slice(s.as_slice());
    z[Y_INDEX] = y;
    z
}

/// The cost matrix `M` `[H2]`: `s^T M s = sum_i w_i ||S R_i - L_i S||_F^2` for every 3x3 `S`.
///
/// ```
/// use rand::SeedableRng;
/// use rotavg::relax::conjugate::cost_matrix;
/// use rotavg::conjugate::synthetic::random_instance;
/// use rotavg::so3::random_rotation;
/// let mut rng = rand::rngs::StdRng::seed_from_u64(3);
/// let (p, _) = random_instance(8, 0.1, 0.0, &mut rng);
/// let s = random_rotation(&mut rng);
/// // g(S) = vec(S)^T M vec(S), column-major vec.
/// let v = nalgebra::SVector::<f64, 9>::from_column_slice(s.matrix().as_slice());
/// let quad = (v.transpose() * cost_matrix(&p) * v)[0];
/// assert!((quad - p.chordal_cost(&s)).abs() < 1e-12 * (1.0 + quad));
/// ```
pub fn cost_matrix(problem: &ConjugateProblem) -> Mat9 {
    cost_matrix_with_error(problem).0
}

/// [`cost_matrix`] and a bound on the Frobenius norm of its rounding error `M_fl - M`:
/// `gamma(n + 12) ||sum_k w_k |K_k|^T |K_k| ||_F` (each `K` entry is one subtraction, each
/// `K^T K` entry a sum of 9 products, one product by `w`, then `n` terms summed recursively;
/// Higham 2002, §3.1 and §3.5). The verified bound [`verify_lower_bound`] on `M_fl` is
/// lowered by 4 times this for the exact `M` (Weyl; `||z||^2 = 4`).
pub(crate) fn cost_matrix_with_error(problem: &ConjugateProblem) -> (Mat9, f64) {
    let mut m = Mat9::zeros();
    let mut mag = Mat9::zeros();
    let eye = Matrix3::<f64>::identity();
    for p in problem.pairs() {
        // vec(A X B) = (B^T (x) A) vec(X): vec(S R) = (R^T (x) I) s, vec(L S) = (I (x) L) s.
        let k = p.right.matrix().transpose().kronecker(&eye) - eye.kronecker(p.left.matrix());
        m += k.transpose() * k * p.weight;
        let ka = k.abs();
        mag += ka.transpose() * ka * p.weight;
    }
    let error = crate::linalg::gamma(problem.num_pairs() + 12) * mag.norm();
    (m, error)
}

/// One quadratic equality constraint `z^T A z = b` of the QCQP `[H3]`.
#[derive(Debug, Clone, PartialEq)]
pub struct QcqpConstraint {
    /// Symmetric 10x10 `A`.
    pub matrix: Mat10,
    /// Right-hand side `b`.
    pub rhs: f64,
    /// What it states, e.g. `"(S^T S)_01 = 0"`.
    pub name: String,
}

/// Add `coef * z_i z_j` to the quadratic form of the symmetric `a`.
fn add_bilinear(a: &mut Mat10, i: usize, j: usize, coef: f64) {
    if i == j {
        a[(i, i)] += coef;
    } else {
        a[(i, j)] += 0.5 * coef;
        a[(j, i)] += 0.5 * coef;
    }
}

/// The 22 constraints `[H3]`, in this order: `y^2 = 1`; `S^T S = y^2 I` (6, entries `a <= b`);
/// `S S^T = y^2 I` (6); `col_a x col_b = y col_c` for cyclic `(a, b, c)` (9), i.e.
/// `cof(S) = y S`. The row versions `row_a x row_b = y row_c` are the same 9 polynomials
/// (`cof(S)_ck = y S_ck`) and are not repeated. Every `S` in SO(3) with `y = 1` satisfies all.
///
/// ```
/// use rotavg::relax::conjugate::{constraint_matrices, lift};
/// use rotavg::so3::exp;
/// let s = exp(&nalgebra::Vector3::new(0.3, -1.2, 0.8));
/// let z = lift(s.matrix(), 1.0);
/// let cons = constraint_matrices();
/// assert_eq!(cons.len(), 22);
/// // A rotation with y = 1 satisfies every constraint z^T A_k z = b_k.
/// assert!(cons.iter().all(|c| ((z.transpose() * c.matrix * z)[0] - c.rhs).abs() < 1e-14));
/// // A reflection does not (the cross-product constraints fix det S = +1).
/// let f = -s.matrix();
/// let zf = lift(&f, 1.0);
/// assert!(cons.iter().any(|c| ((zf.transpose() * c.matrix * zf)[0] - c.rhs).abs() > 0.5));
/// ```
pub fn constraint_matrices() -> Vec<QcqpConstraint> {
    let y = Y_INDEX;
    let mut out = Vec::with_capacity(22);
    let mut a = Mat10::zeros();
    a[(y, y)] = 1.0;
    out.push(QcqpConstraint {
        matrix: a,
        rhs: 1.0,
        name: "y^2 = 1".into(),
    });
    // Orthogonality: (S^T S)_ab = col_a . col_b = sum_r S[r][a] S[r][b]; (S S^T)_ab = sum_c S[a][c] S[b][c].
    for rows in [false, true] {
        for ia in 0..3 {
            for ib in ia..3 {
                let mut a = Mat10::zeros();
                for t in 0..3 {
                    let (i, j) = if rows {
                        (s_index(ia, t), s_index(ib, t))
                    } else {
                        (s_index(t, ia), s_index(t, ib))
                    };
                    add_bilinear(&mut a, i, j, 1.0);
                }
                if ia == ib {
                    a[(y, y)] -= 1.0;
                }
                let what = if rows { "S S^T" } else { "S^T S" };
                out.push(QcqpConstraint {
                    matrix: a,
                    rhs: 0.0,
                    name: format!("({what})_{ia}{ib} = {} y^2", u8::from(ia == ib)),
                });
            }
        }
    }
    // Handedness: (col_a x col_b)[k] = col_a[k+1] col_b[k+2] - col_a[k+2] col_b[k+1] = y col_c[k],
    // i.e. cof(S)_{kc} = y S_{kc}. The row version (row_a x row_b)[k] = y row_c[k] states
    // cof(S)_{ck} = y S_{ck}: the same 9 polynomials, so it is not added again [H3].
    for (ia, ib, ic) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)] {
        for k in 0..3 {
            // element t of column v
            let e = |v: usize, t: usize| s_index(t, v);
            let (k1, k2) = ((k + 1) % 3, (k + 2) % 3);
            let mut a = Mat10::zeros();
            add_bilinear(&mut a, e(ia, k1), e(ib, k2), 1.0);
            add_bilinear(&mut a, e(ia, k2), e(ib, k1), -1.0);
            add_bilinear(&mut a, y, e(ic, k), -1.0);
            out.push(QcqpConstraint {
                matrix: a,
                rhs: 0.0,
                name: format!("(col_{ia} x col_{ib})[{k}] = y col_{ic}[{k}]"),
            });
        }
    }
    out
}

/// `svec` of a symmetric 10x10 matrix in Clarabel's layout (the shared encoding of
/// [`crate::relax::svec`]: upper triangle column by column, off-diagonals times `sqrt(2)`).
fn svec(a: &Mat10) -> Vec<f64> {
    let mut v = vec![0.0; svec_len(10)];
    for j in 0..10 {
        for i in 0..=j {
            v[svec_index(i, j)] = a[(i, j)] * svec_weight(i, j);
        }
    }
    v
}

/// Inverse of [`svec`].
fn smat(v: &[f64]) -> Mat10 {
    Mat10::from_fn(|i, j| v[svec_index(i, j)] / svec_weight(i, j))
}

/// The solved relaxation: the primal `Z`, the multipliers `nu` (in the units of the unscaled
/// cost, one per constraint of [`constraint_matrices`]) and solver statistics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConjugateRelaxation {
    /// Primal solution `Z` (10x10, PSD up to solver accuracy).
    pub z: Mat10,
    /// Multipliers `nu_k` such that `blkdiag(M, 0) - sum_k nu_k A_k` is (nearly) PSD.
    pub multipliers: Vec<f64>,
    /// Clarabel's status.
    pub status: SdpStatus,
    /// Clarabel's iterations.
    pub iterations: u32,
    /// Wall time (setup + solve) in seconds.
    pub seconds: f64,
    /// `lambda_2(Z) / lambda_1(Z)`: 0 for a rank-one (tight) solution.
    pub eigenvalue_ratio: f64,
}

/// Solve the SDP relaxation `[H3]` with Clarabel. The cost is divided by the total weight
/// before solving (Clarabel ended `AlmostSolved` on unscaled 100-pair instances, contract section 6) and the
/// multipliers are scaled back.
///
/// The solver's objective is never used as a bound: verify one from the multipliers with
/// [`crate::certify::conjugate::verify_lower_bound`] (or let [`crate::certify::certify_conjugate`]
/// do it).
///
/// ```
/// use rand::SeedableRng;
/// use rotavg::certify::conjugate::verify_lower_bound;
/// use rotavg::conjugate::synthetic::random_instance;
/// use rotavg::relax::conjugate::{constraint_matrices, cost_matrix, extract_rotation};
/// use rotavg::relax::{relax_conjugate, SdpSettings};
/// use rotavg::so3::angle_between;
/// let mut rng = rand::rngs::StdRng::seed_from_u64(5);
/// let (problem, s) = random_instance(20, 0.01, 0.0, &mut rng); // 20 pairs, 0.01 rad noise
/// let relax = relax_conjugate(&problem, &SdpSettings::default())?;
/// assert!(relax.status.converged());
/// assert!(relax.eigenvalue_ratio < 1e-6); // Z is rank one: the relaxation is tight
/// let s_sdp = extract_rotation(&relax.z).unwrap();
/// assert!(angle_between(&s_sdp, &s) < 0.05);
/// // An independently verified bound below the cost of every rotation, and close to it here.
/// let bound = verify_lower_bound(&cost_matrix(&problem), &constraint_matrices(), &relax.multipliers).unwrap();
/// let cost = problem.chordal_cost(&s_sdp);
/// assert!(bound.lower_bound <= cost && cost - bound.lower_bound < 1e-5 * cost);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn relax_conjugate(
    problem: &ConjugateProblem,
    settings: &SdpSettings,
) -> Result<ConjugateRelaxation> {
    let start = Instant::now();
    let scale = problem.total_weight();
    let m = cost_matrix(problem) / scale;
    let mut c = Mat10::zeros();
    c.fixed_view_mut::<9, 9>(0, 0).copy_from(&m);
    let cons = constraint_matrices();
    let ncons = cons.len();
    let nv = 55;
    let (mut ii, mut jj, mut vv) = (Vec::new(), Vec::new(), Vec::new());
    let mut b = Vec::with_capacity(ncons + nv);
    for (k, con) in cons.iter().enumerate() {
        for (idx, x) in svec(&con.matrix).into_iter().enumerate() {
            if x != 0.0 {
                ii.push(k);
                jj.push(idx);
                vv.push(x);
            }
        }
        b.push(con.rhs);
    }
    for idx in 0..nv {
        ii.push(ncons + idx);
        jj.push(idx);
        vv.push(-1.0);
        b.push(0.0);
    }
    let a = csc(
        ncons + nv,
        nv,
        ii.into_iter()
            .zip(jj)
            .zip(vv)
            .map(|((i, j), v)| (i, j, v))
            .collect(),
    );
    let q = svec(&c);
    settings.validate()?;
    let sol = solve_conic(
        &q,
        a,
        &b,
        &[Cone::Zero(ncons), Cone::Psd(10)],
        settings,
        "none",
    )?;
    let status = sol.status;
    if sol.x.len() != nv || sol.z.len() != ncons + nv {
        return Err(crate::Error::Solver {
            message: "Clarabel returned vectors of the wrong length".into(),
        });
    }
    let z = smat(&sol.x);
    // Clarabel's dual z_k for the equality rows: C + sum_k z_k A_k is PSD, so nu = -z  [H8].
    let multipliers: Vec<f64> = sol.z[..ncons].iter().map(|v| -v * scale).collect();
    let eig = SymmetricEigen::new(z);
    let mut ev: Vec<f64> = eig.eigenvalues.iter().copied().collect();
    ev.sort_by(|x, y| y.total_cmp(x));
    let ratio = if ev[0] > 0.0 {
        ev[1].max(0.0) / ev[0]
    } else {
        1.0
    };
    Ok(ConjugateRelaxation {
        z,
        multipliers,
        status,
        iterations: sol.iterations,
        seconds: start.elapsed().as_secs_f64(),
        eigenvalue_ratio: ratio,
    })
}

/// Rank-one extraction: top eigenvector `v` of `Z`, scaled so that `y = 1`, `S` = projection
/// of the reshaped (column-major) `v[0..9]` onto SO(3). `None` when `y ~ 0`.
pub fn extract_rotation(z: &Mat10) -> Option<Rotation> {
    let eig = SymmetricEigen::new(*z);
    let k = eig.eigenvalues.imax();
    let v = eig.eigenvectors.column(k);
    if v[Y_INDEX].abs() < 1e-6 {
        return None;
    }
    let s = Matrix3::from_column_slice(&v.as_slice()[..9]) / v[Y_INDEX];
    project_to_so3(&s)
}
