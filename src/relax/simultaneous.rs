//! The SDP relaxation of the simultaneous problem `[H14]` (`paper-notes/conjugate.md`): two
//! view graphs over the same `n` nodes, right edges `R_ij` (`R_ij R_i = R_j`) and left edges
//! `L_ij ~ S R_ij S^T`, with unknown absolutes `R_i` and hand-eye rotation `S`.
//!
//! With `C_i = S R_i`, the right graph's Gram matrix `X_R` (blocks `R_i R_j^T`) and the left
//! graph's `X_C` (blocks `C_i C_j^T = S R_i R_j^T S^T`), the joint cost is
//! `tr(Q_R X_R) + tr(Q_C X_C)` (two connection Laplacians), every diagonal block is `I_3`, and
//! conjugation keeps traces: `tr(X_C)_ij = tr(X_R)_ij` for **every** pair `i < j`. This is the
//! gauge-averaged form of Shor's relaxation in `vec R_i`, `vec C_i` with the coupling
//! `C_i^T C_j = R_i^T R_j` (`[H14]`); the pairs that are no edge are what makes it tight. The
//! dual, solved here with Clarabel (two dense PSD cones of size `3n`):
//!
//! `max sum_a tr(Lambda_a)` s.t. `Q_R - blkdiag(Lambda_R) - sum gamma_ij E_ij` PSD and
//! `Q_C - blkdiag(Lambda_C) + sum gamma_ij E_ij` PSD,
//!
//! `E_ij` the symmetric matrix with `I_3 / 2` in blocks `(i, j)` and `(j, i)`.
//! [`relax_simultaneous`] returns the multipliers; a bound is only what
//! [`crate::certify::simultaneous::verify_simultaneous_bound`] proves from them.

use crate::conjugate::{ConjugatePair, ConjugateProblem, ConjugateSettings, solve_conjugate};
use crate::error::{Error, Result};
use crate::multiple::MultipleProblem;
use crate::multiple::laplacian::connection_laplacian_triplets;
use crate::relax::clarabel::{Cone, csc, solve_conic};
use crate::relax::multiple::{
    SDP_BYTES_PER_BLOCK_ENTRY, SDP_ITERATIONS, SDP_MULTIPLY_ADD_RATE, SdpPrediction,
    top_three_blocks,
};
use crate::relax::settings::{SdpSettings, SdpStatus};
use crate::relax::svec::{smat, svec_index, svec_len, svec_weight};
use crate::so3::{Rotation, project_to_so3};
use faer::Mat;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// A joint point of the simultaneous problem: `R_0..R_{n-1}` (gauge `R_0 = I`) and `S`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointRotations {
    /// The right absolutes `R_i`.
    #[serde(with = "crate::so3::serde_rows::rotations")]
    pub rotations: Vec<Rotation>,
    /// The hand-eye rotation `S`.
    #[serde(with = "crate::so3::serde_rows::rotation")]
    pub s: Rotation,
    /// The joint cost `J(R, S)` at this point.
    pub cost: f64,
}

/// Result of [`relax_simultaneous`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct SimultaneousRelaxation {
    /// Solver outcome.
    pub status: SdpStatus,
    /// `Lambda_a`, `a = 0..2n` (the `R_i` blocks, then the `C_i` blocks), symmetrised, unscaled.
    pub lambdas: Vec<Matrix3<f64>>,
    /// `gamma_ij` for the pairs `i < j` in the order of [`coupling_pairs`], unscaled.
    pub couplings: Vec<f64>,
    /// Largest eigenvalues of `X_R` (up to 6), descending: tight when the fourth is negligible.
    pub x_top_eigenvalues: Vec<f64>,
    /// The rounding: top three eigenvectors of `X_R` and of `X_C`, blocks projected to SO(3),
    /// gauge `R_0 = I`, `S` the conjugate average of the pairs `(C_i C_0^T, R_i R_0^T)`; its
    /// joint cost is an upper bound.
    pub rounded: JointRotations,
    /// Interior-point iterations.
    pub iterations: u32,
    /// Clarabel's solve time, seconds.
    pub solver_seconds: f64,
    /// Total time, seconds.
    pub seconds: f64,
}

/// The joint cost `sum_right w ||R_j - R_ij R_i||^2 + sum_left w ||S R_j - L_ij S R_i||^2`.
pub fn joint_cost(
    right: &MultipleProblem,
    left: &MultipleProblem,
    rs: &[Rotation],
    s: &Rotation,
) -> f64 {
    let cs: Vec<Rotation> = rs.iter().map(|r| s * r).collect();
    right.chordal_cost(rs) + left.chordal_cost(&cs)
}

/// The pairs `(i, j)`, `i < j`, of the trace couplings, in the order of
/// [`SimultaneousRelaxation::couplings`]: `(0, 1), (0, 2), ..., (0, n-1), (1, 2), ...`.
pub fn coupling_pairs(n: usize) -> impl Iterator<Item = (usize, usize)> {
    (0..n).flat_map(move |i| (i + 1..n).map(move |j| (i, j)))
}

/// The cost of the relaxation on `n` nodes, before Clarabel starts: two dense PSD cones of size
/// `3n` (the trace couplings join every pair, so there is no chordal structure), each a dense
/// `svec x svec` block of the KKT system, by the calibrated model of
/// [`crate::relax::multiple::predict_relax_multiple`]; the dense `3n x 3n` matrices of the
/// rounding and of the verification are added (memory: the larger; time: both).
pub fn predict_relax_simultaneous(n: usize) -> SdpPrediction {
    let d = 3.0 * n as f64;
    let svec = d * (d + 1.0) / 2.0;
    let (block_entries, multiply_adds) = (2.0 * svec * svec, 2.0 * svec * svec * svec / 3.0);
    SdpPrediction {
        bytes: (SDP_BYTES_PER_BLOCK_ENTRY * block_entries).max(8.0 * 8.0 * d * d),
        seconds: SDP_ITERATIONS * multiply_adds / SDP_MULTIPLY_ADD_RATE
            + 4.0 * 10.0 * d * d * d / SDP_MULTIPLY_ADD_RATE,
        largest_clique: n,
        cliques: 2,
    }
}

/// Checks the two graphs share their node count.
fn check_sizes(right: &MultipleProblem, left: &MultipleProblem) -> Result<usize> {
    let n = right.num_rotations();
    if left.num_rotations() != n || n < 2 {
        return Err(Error::InvalidSettings {
            name: "simultaneous problem".into(),
            reason: format!(
                "the two view graphs must have the same number (at least 2) of nodes, got {} and {}",
                n,
                left.num_rotations()
            ),
        });
    }
    Ok(n)
}

/// Solves the dual `[H14]` with Clarabel (two dense PSD cones of size `3n`; variables the
/// `12n` upper-triangle entries of the `Lambda_a` and the `n (n - 1) / 2` couplings
/// `gamma_ij`), cost scaled by the mean weighted degree `[P4]`.
/// Errors: graphs of different sizes, a setup failure; a non-converged solve is a status.
///
/// ```
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::relax::simultaneous::relax_simultaneous;
/// use rotavg::relax::SdpSettings;
/// use rotavg::so3::exp;
/// use nalgebra::Vector3;
/// // rotations about different axes (with a common axis, S would be determined only up to a
/// // rotation about it)
/// let rs: Vec<_> = [[0.0, 0.0, 0.0], [0.4, 0.0, 0.1], [0.0, 0.6, -0.2], [0.3, -0.3, 0.8]]
///     .iter()
///     .map(|v| exp(&Vector3::from(*v)))
///     .collect();
/// let s = exp(&Vector3::new(0.2, -0.5, 0.4));
/// let pairs = [(0, 1), (1, 2), (2, 3), (3, 0), (0, 2)];
/// let e = |i: usize, j: usize, rotation| Edge { i, j, rotation, weight: 1.0 };
/// let right: Vec<_> = pairs.iter().map(|&(i, j)| e(i, j, rs[j] * rs[i].inverse())).collect();
/// let left: Vec<_> = right.iter().map(|x| e(x.i, x.j, s * x.rotation * s.inverse())).collect();
/// let (right, left) = (MultipleProblem::new(4, right)?, MultipleProblem::new(4, left)?);
/// let sol = relax_simultaneous(&right, &left, &SdpSettings::default())?;
/// assert!(sol.status.converged());
/// assert_eq!((sol.lambdas.len(), sol.couplings.len()), (8, 6)); // 2n blocks, n(n-1)/2 pairs
/// // noise-free: the rounding recovers the planted point (joint cost ~0)
/// assert!(sol.rounded.cost < 1e-6);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn relax_simultaneous(
    right: &MultipleProblem,
    left: &MultipleProblem,
    settings: &SdpSettings,
) -> Result<SimultaneousRelaxation> {
    settings.validate()?;
    let start = Instant::now();
    let n = check_sizes(right, left)?;
    let total: f64 = right
        .edges()
        .iter()
        .chain(left.edges())
        .map(|e| e.weight)
        .sum();
    let scale = total / n as f64; // [P4]: mean weighted degree over 2n nodes
    let dim = 3 * n;
    let len = svec_len(dim);
    let b = laplacian_rows(right, left, scale, len);
    let pairs = n * (n - 1) / 2;
    let nv = 12 * n + pairs;
    let (c, trip) = dual_columns(n, len);
    let a = csc(2 * len, nv, trip);
    let conic = solve_conic(
        &c,
        a,
        &b,
        &[Cone::Psd(dim), Cone::Psd(dim)],
        settings,
        settings.chordal_merge.clarabel_name(n, pairs),
    )?;
    let (lambdas, couplings) = read_multipliers(&conic.x, n, scale);
    let gram = |cone: usize| {
        conic
            .z
            .get(cone * len..(cone + 1) * len)
            .and_then(|z| smat(z, dim))
            .ok_or_else(|| Error::Solver {
                message: "Clarabel returned a dual vector of the wrong length".into(),
            })
    };
    let (rounded, x_top_eigenvalues) = round(&gram(0)?, &gram(1)?, right, left)?;
    Ok(SimultaneousRelaxation {
        status: conic.status,
        lambdas,
        couplings,
        x_top_eigenvalues,
        rounded,
        iterations: conic.iterations,
        solver_seconds: conic.solve_seconds,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The dual's right-hand side: the rows `svec(Q_R)`, then `svec(Q_C)`, scaled by `1 / scale`
/// (`len` rows each).
fn laplacian_rows(
    right: &MultipleProblem,
    left: &MultipleProblem,
    scale: f64,
    len: usize,
) -> Vec<f64> {
    let mut b = vec![0.0; 2 * len];
    for (cone, p) in [right, left].into_iter().enumerate() {
        for t in connection_laplacian_triplets(p) {
            if t.row <= t.col {
                b[cone * len + svec_index(t.row, t.col)] +=
                    t.val / scale * svec_weight(t.row, t.col);
            }
        }
    }
    b
}

/// The dual's objective and constraint columns: the variables are 6 per diagonal block (`n`
/// right, then `n` left; objective `-tr(Lambda_a)`), then one per pair `gamma_ij`;
/// `Z_R = Q_R - ... - gamma E_ij`, `Z_C = Q_C - ... + gamma E_ij`, `b - A x = svec(Z)`.
fn dual_columns(n: usize, len: usize) -> (Vec<f64>, Vec<(usize, usize, f64)>) {
    let pairs = n * (n - 1) / 2;
    let mut c = vec![0.0; 12 * n + pairs];
    let mut trip = Vec::with_capacity(12 * n + 6 * pairs);
    for a in 0..2 * n {
        let (cone, node) = (a / n, a % n);
        for col in 0..3 {
            for row in 0..=col {
                let k = 6 * a + svec_index(row, col);
                if row == col {
                    c[k] = -1.0;
                }
                let entry = cone * len + svec_index(3 * node + row, 3 * node + col);
                trip.push((entry, k, svec_weight(row, col)));
            }
        }
    }
    for (k, (i, j)) in coupling_pairs(n).enumerate() {
        for d in 0..3 {
            let (r, cc) = (3 * i + d, 3 * j + d);
            let v = 0.5 * svec_weight(r, cc);
            trip.push((svec_index(r, cc), 12 * n + k, v));
            trip.push((len + svec_index(r, cc), 12 * n + k, -v));
        }
    }
    (c, trip)
}

/// The multipliers `Lambda_a` (symmetrised) and couplings `gamma_ij` of the dual solution `x`,
/// unscaled (`NaN` where the solver's value is not finite).
fn read_multipliers(x: &[f64], n: usize, scale: f64) -> (Vec<Matrix3<f64>>, Vec<f64>) {
    let finite = |v: f64| if v.is_finite() { v * scale } else { f64::NAN };
    let lambdas = (0..2 * n)
        .map(|a| {
            let l = Matrix3::from_fn(|r, cc| finite(x[6 * a + svec_index(r, cc)]));
            (l + l.transpose()) * 0.5
        })
        .collect();
    let couplings = (0..n * (n - 1) / 2)
        .map(|k| finite(x[12 * n + k]))
        .collect();
    (lambdas, couplings)
}

/// Rounding: `Y = V_3 diag(sqrt(lambda_1..3))` from the top eigenpairs of `X_R` and of `X_C`
/// (the global reflection fixed by the majority of block determinants), blocks projected to
/// SO(3), gauge `R_0 = I`; the two factors have independent gauges, so `S` is the conjugate
/// average of the gauge-free pairs `(C_i C_0^T, R_i R_0^T)` (identity when that problem is
/// degenerate: the rounding is only a candidate, judged by its cost).
fn round(
    x_r: &Mat<f64>,
    x_c: &Mat<f64>,
    right: &MultipleProblem,
    left: &MultipleProblem,
) -> Result<(JointRotations, Vec<f64>)> {
    let n = x_r.nrows() / 3;
    let blocks = |x| -> Result<(Vec<Rotation>, Vec<f64>)> {
        let (y, top) = top_three_blocks(x, n)?;
        let b: Vec<Rotation> = y
            .iter()
            .map(|b| project_to_so3(b).unwrap_or_else(Rotation::identity))
            .collect();
        let g = b[0].inverse();
        Ok((b.iter().map(|r| r * g).collect(), top))
    };
    let (rotations, top) = blocks(x_r)?;
    let (ls, _) = blocks(x_c)?;
    let pairs: Vec<_> = (1..n)
        .map(|i| ConjugatePair::new(ls[i], rotations[i]))
        .collect();
    let s = ConjugateProblem::new(pairs)
        .and_then(|p| solve_conjugate(&p, &ConjugateSettings::default()))
        .map(|c| c.estimate)
        .unwrap_or_else(|_| Rotation::identity());
    let cost = joint_cost(right, left, &rotations, &s);
    Ok((JointRotations { rotations, s, cost }, top))
}
