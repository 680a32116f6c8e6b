//! The multiple-averaging SDP strengthened by `conv(SO(3))` constraints on its Gram blocks
//! (`paper-notes/anisotropic.md` `[A6]`; Saunderson, Parrilo & Willsky, "Semidefinite
//! descriptions of the convex hull of rotation matrices", SIAM J. Optim. 2015):
//!
//! ```text
//! min tr(Q X)  s.t.  X PSD,  X_ii = I_3,  A(X_ij) PSD for every edge (i, j)
//! ```
//!
//! with the 4x4 matrix `A(R)` ([`conv_matrix`]) that is PSD exactly when `R` lies in the convex
//! hull of SO(3). The `O(3)` relaxation's reflected solutions (`[A5]`) violate it: on the two
//! examples of `tests/suite/anisotropic.rs` it gives 0 and 6 (the rotation optima) where the `O(3)`
//! relaxation gives -8 and 0.8. Solved densely in primal form with Clarabel, for small graphs
//! ([`CONV_MAX_NODES`]); the multipliers `Lambda_i` and `Z_e` it returns are verified
//! independently by [`crate::certify::multiple::conv_bound`]. Its objective values are never a
//! bound.

use super::clarabel::{Cone, csc, solve_conic};
use super::settings::{SdpSettings, SdpStatus};
use super::svec::{smat, svec_index, svec_len, svec_weight};
use crate::error::{Error, Result};
use crate::multiple::MultipleProblem;
use crate::multiple::laplacian::connection_laplacian;
use nalgebra::{Matrix3, Matrix4};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// The largest graph the dense `conv(SO(3))` SDP accepts. Its `X` has `m = 3n (3n + 1) / 2`
/// free entries and Clarabel's PSD cone scaling is a dense `m x m` matrix: 1830 entries and
/// 27 MB at 20 nodes, but 7260 entries, 420 MB and `m^3 / 3 = 1.3e11` flops per iteration at
/// 40 (no budget prediction guards this Rust-only call yet, so the limit does).
pub const CONV_MAX_NODES: usize = 20;

/// The predicted cost of [`relax_multiple_conv`] on `problem`: the dense scaling of its PSD cone
/// (`m^2` values, `m = 3n (3n + 1) / 2`) held seven times (the scaling, the KKT matrix and its
/// LDL factor with their row indices, copies) and `m^3 / 3` multiply-adds per interior-point
/// iteration, at the rates of [`super::multiple::predict_relax_multiple`]. A model for the
/// budget, never a bound. The factor 7 is measured: peak RSS of `rotavg multiple --certify sdp`
/// on anisotropic graphs of 12, 16 and 20 nodes whose `conv(SO(3))` rung ran (34, 82 and
/// 193 MB, about 10 MB of them the process) is 6.5-6.8 times `8 m^2` bytes (the factor 3 of
/// the first model predicted 81 MB for the 193 MB measured at 20 nodes).
pub fn predict_relax_multiple_conv(problem: &MultipleProblem) -> super::SdpPrediction {
    let m = svec_len(3 * problem.num_rotations()) as f64;
    let cones = 10.0 * problem.num_edges() as f64;
    super::SdpPrediction {
        bytes: 8.0 * (7.0 * m * m + 20.0 * (m + cones)),
        seconds: super::multiple::SDP_ITERATIONS * (m * m * m / 3.0)
            / super::multiple::SDP_MULTIPLY_ADD_RATE,
        largest_clique: problem.num_rotations(),
        cliques: 1,
    }
}

/// `A(R)` (rows and columns in quaternion order `w, x, y, z`): PSD iff `R` is in
/// `conv(SO(3))`; `A(R(q)) = 4 q q^T` for a rotation, eigenvalues `(-2, 2, 2, 2)` for a
/// reflection `[A6]`.
///
/// ```
/// use rotavg::relax::conv_so3::conv_matrix;
/// use rotavg::so3::exp;
/// use nalgebra::{Matrix3, Vector3};
/// let r = exp(&Vector3::new(0.3, -1.0, 0.5));
/// assert!(conv_matrix(r.matrix()).symmetric_eigenvalues().min() > -1e-12);
/// let reflection = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
/// assert!((conv_matrix(&reflection).symmetric_eigenvalues().min() + 2.0).abs() < 1e-12);
/// ```
pub fn conv_matrix(r: &Matrix3<f64>) -> Matrix4<f64> {
    let e = |a: usize, b: usize| r[(a - 1, b - 1)];
    Matrix4::new(
        1.0 + e(1, 1) + e(2, 2) + e(3, 3),
        e(3, 2) - e(2, 3),
        e(1, 3) - e(3, 1),
        e(2, 1) - e(1, 2),
        e(3, 2) - e(2, 3),
        1.0 + e(1, 1) - e(2, 2) - e(3, 3),
        e(1, 2) + e(2, 1),
        e(1, 3) + e(3, 1),
        e(1, 3) - e(3, 1),
        e(1, 2) + e(2, 1),
        1.0 - e(1, 1) + e(2, 2) - e(3, 3),
        e(2, 3) + e(3, 2),
        e(2, 1) - e(1, 2),
        e(1, 3) + e(3, 1),
        e(2, 3) + e(3, 2),
        1.0 - e(1, 1) - e(2, 2) + e(3, 3),
    )
}

/// The linear part's adjoint: `G(Z)` with `<Z, A(R) - I_4> = <G(Z), R>` for every `R`.
pub fn conv_adjoint(z: &Matrix4<f64>) -> Matrix3<f64> {
    let zero = conv_matrix(&Matrix3::zeros());
    Matrix3::from_fn(|k, l| {
        let mut unit = Matrix3::zeros();
        unit[(k, l)] = 1.0;
        z.dot(&(conv_matrix(&unit) - zero))
    })
}

/// The solution of the `conv(SO(3))`-strengthened SDP: the multipliers to verify.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConvRelaxation {
    /// Solver outcome.
    pub status: SdpStatus,
    /// `Lambda_i` of the constraints `X_ii = I` (symmetrised, in the cost's units).
    pub multipliers: Vec<Matrix3<f64>>,
    /// One `(i, j, Z_e)` per distinct node pair with an edge: the multiplier of `A(X_ij) PSD`
    /// (4x4, only approximately PSD: the verification makes it so).
    pub conv_multipliers: Vec<(usize, usize, Matrix4<f64>)>,
    /// Solver's objective values (informational only, never a bound).
    pub primal_objective: f64,
    /// Solver's dual objective (informational only).
    pub dual_objective: f64,
    /// Interior-point iterations.
    pub iterations: u32,
    /// The rounding `[P5]` of the primal `X` (top three eigenpairs, blocks projected to SO(3),
    /// `R_0 = I`): a feasible estimate whose cost bounds the minimum from above (empty when `X`
    /// is unusable). The certification polishes it and adopts it when it beats its estimate.
    #[serde(with = "crate::so3::serde_rows::rotations")]
    pub rounded: Vec<crate::so3::Rotation>,
    /// Total time, seconds.
    pub seconds: f64,
}

/// Solve the `conv(SO(3))`-strengthened SDP of `problem` (isotropic or anisotropic chordal
/// cost) with Clarabel in primal form. Errors: more than [`CONV_MAX_NODES`] nodes, invalid
/// settings, a solver setup failure; a non-converged solve is a status.
pub fn relax_multiple_conv(
    problem: &MultipleProblem,
    settings: &SdpSettings,
) -> Result<ConvRelaxation> {
    settings.validate()?;
    let start = Instant::now();
    let n = problem.num_rotations();
    if n > CONV_MAX_NODES {
        return Err(Error::InvalidSettings {
            name: "conv_so3".into(),
            reason: format!(
                "the dense conv(SO(3)) relaxation takes at most {CONV_MAX_NODES} nodes, the \
                 graph has {n}"
            ),
        });
    }
    let dim = 3 * n;
    let nv = svec_len(dim);
    // the cost scaled by the mean weighted degree [P4]
    let scale = super::multiple::cost_scale(problem);
    let c = scaled_cost(problem, scale);
    let pairs = edge_pairs(problem);
    let neq = 6 * n;
    let rows = neq + nv + 10 * pairs.len();
    let (trip, b) = constraints(n, &pairs);
    let mut cones = vec![Cone::Zero(neq), Cone::Psd(dim)];
    cones.extend(pairs.iter().map(|_| Cone::Psd(4)));
    let dense = SdpSettings {
        chordal_decomposition: false,
        ..settings.clone()
    };
    let conic = solve_conic(&c, csc(rows, nv, trip), &b, &cones, &dense, "none")?;
    let z = &conic.z;
    if z.len() != rows {
        return Err(Error::Solver {
            message: "Clarabel returned no dual solution".into(),
        });
    }
    let (multipliers, conv_multipliers) = read_multipliers(z, n, &pairs, scale);
    let rounded = round_primal(&conic.x, n).unwrap_or_default();
    Ok(ConvRelaxation {
        rounded,
        status: conic.status,
        multipliers,
        conv_multipliers,
        primal_objective: conic.primal_objective * scale,
        dual_objective: conic.dual_objective * scale,
        iterations: conic.iterations,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The rounding `[P5]` of the primal solution `x` (the entries `X_ab`, `a <= b`, in svec
/// order: the variable is `X` itself, its cone slack carries the svec weights).
fn round_primal(x: &[f64], n: usize) -> Result<Vec<crate::so3::Rotation>> {
    let dim = 3 * n;
    if x.len() != svec_len(dim) {
        return Err(Error::Solver {
            message: "Clarabel returned no primal solution".into(),
        });
    }
    let full = faer::Mat::from_fn(dim, dim, |a, b| x[svec_index(a.min(b), a.max(b))]);
    let (blocks, _) = super::multiple::top_three_blocks(&full, n)?;
    Ok(super::multiple::project_blocks(blocks).0)
}

/// The cost `svec` of `Q / scale` (off-diagonal entries twice: `<C, svec(X)> = tr(Q X) /
/// scale`).
fn scaled_cost(problem: &MultipleProblem, scale: f64) -> Vec<f64> {
    let dim = 3 * problem.num_rotations();
    let q = connection_laplacian(problem).to_dense();
    let mut c = vec![0.0; svec_len(dim)];
    for col in 0..dim {
        for row in 0..=col {
            let w = if row == col { 1.0 } else { 2.0 };
            c[svec_index(row, col)] = w * q[(row, col)] / scale;
        }
    }
    c
}

/// The distinct node pairs `(min, max)` with an edge, sorted.
fn edge_pairs(problem: &MultipleProblem) -> Vec<(usize, usize)> {
    let mut pairs: Vec<(usize, usize)> = problem
        .edges()
        .iter()
        .map(|e| (e.i.min(e.j), e.i.max(e.j)))
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    pairs
}

/// The constraints `A svec(X) + s = b` in primal form: `X_ii = I` (6 rows per node), `X` PSD
/// (`s = svec(X)`), and `A(X_ij)` PSD for every pair (10 rows each).
fn constraints(n: usize, pairs: &[(usize, usize)]) -> (Vec<(usize, usize, f64)>, Vec<f64>) {
    let dim = 3 * n;
    let nv = svec_len(dim);
    let neq = 6 * n;
    let mut trip = Vec::new();
    let mut b = vec![0.0; neq + nv + 10 * pairs.len()];
    for i in 0..n {
        for bb in 0..3 {
            for a in 0..=bb {
                let row = 6 * i + svec_index(a, bb);
                trip.push((row, svec_index(3 * i + a, 3 * i + bb), 1.0));
                b[row] = if a == bb { 1.0 } else { 0.0 };
            }
        }
    }
    for col in 0..dim {
        for row in 0..=col {
            let k = svec_index(row, col);
            trip.push((neq + k, k, -svec_weight(row, col)));
        }
    }
    for (e, &(i, j)) in pairs.iter().enumerate() {
        conv_rows(neq + nv + 10 * e, i, j, &mut trip, &mut b);
    }
    (trip, b)
}

/// The rows of `A(X_ij)` PSD from `offset`: `s = svec(I + L(X_ij))`, `L`'s coefficients from
/// the unit matrices.
fn conv_rows(
    offset: usize,
    i: usize,
    j: usize,
    trip: &mut Vec<(usize, usize, f64)>,
    b: &mut [f64],
) {
    let zero = conv_matrix(&Matrix3::zeros());
    for qq in 0..4 {
        for p in 0..=qq {
            let row = offset + svec_index(p, qq);
            let w = svec_weight(p, qq);
            b[row] = w * zero[(p, qq)];
            for k in 0..3 {
                for l in 0..3 {
                    let mut unit = Matrix3::zeros();
                    unit[(k, l)] = 1.0;
                    let coef = conv_matrix(&unit)[(p, qq)] - zero[(p, qq)];
                    if coef != 0.0 {
                        trip.push((row, svec_index(3 * i + k, 3 * j + l), -w * coef));
                    }
                }
            }
        }
    }
}

/// The multipliers `Lambda_i` of `X_ii = I` and `Z_e` of `A(X_ij)` PSD in the dual solution
/// `z`, unscaled.
#[allow(clippy::type_complexity)]
fn read_multipliers(
    z: &[f64],
    n: usize,
    pairs: &[(usize, usize)],
    scale: f64,
) -> (Vec<Matrix3<f64>>, Vec<(usize, usize, Matrix4<f64>)>) {
    let offset0 = 6 * n + svec_len(3 * n);
    let multipliers = (0..n)
        .map(|i| {
            Matrix3::from_fn(|r, cc| {
                let y = z[6 * i + svec_index(r, cc)];
                scale * if r == cc { -y } else { -0.5 * y }
            })
        })
        .collect();
    let conv_multipliers = pairs
        .iter()
        .enumerate()
        .map(|(e, &(i, j))| {
            let offset = offset0 + 10 * e;
            let m = smat(&z[offset..offset + 10], 4).unwrap_or_else(|| faer::Mat::zeros(4, 4));
            (i, j, Matrix4::from_fn(|p, qq| scale * m[(p, qq)]))
        })
        .collect();
    (multipliers, conv_multipliers)
}
