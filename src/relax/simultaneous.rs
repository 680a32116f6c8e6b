//! The SDP relaxation of the simultaneous problem `[H12]` (`paper-notes/conjugate.md`): two
//! view graphs over the same `n` nodes, right edges `R_ij` (`R_ij R_i = R_j`) and left edges
//! `L_ij ~ S R_ij S^T`, with unknown absolutes `R_i` and hand-eye rotation `S`.
//!
//! With `C_i = S R_i`, `Y = [R_1; ...; R_n; C_1; ...; C_n]` (`6n x 3`) and `X = Y Y^T`, the
//! joint cost is `tr(blkdiag(Q_R, Q_L) X)` (two connection Laplacians), every diagonal block is
//! `I_3`, and `X_{C_i, R_i} = C_i R_i^T = S` for every `i`: the `9 (n - 1)` linear equalities
//! `X_{C_i, R_i} = X_{C_0, R_0}` (`i >= 1`). The dual, solved here with Clarabel:
//!
//! `max sum_a tr(Lambda_a)` s.t. `Q - blkdiag(Lambda) - sum_i E(Gamma_i)` PSD,
//!
//! `E(Gamma_i)` the symmetric matrix with `Gamma_i` in block `(C_i, R_i)` and `-Gamma_i` in
//! `(C_0, R_0)` (and their transposes). [`relax_simultaneous`] returns the multipliers; a bound
//! is only what [`crate::certify::simultaneous::verify_simultaneous_bound`] proves from them.

use crate::error::{Error, Result};
use crate::multiple::laplacian::connection_laplacian_triplets;
use crate::multiple::{Edge, MultipleProblem};
use crate::relax::clarabel::{Cone, csc, solve_conic};
use crate::relax::multiple::{
    SDP_MULTIPLY_ADD_RATE, SdpPrediction, predict_relax_multiple, top_three_blocks,
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
    /// `Gamma_i`, `i = 1..n` (index `i - 1`), unscaled.
    pub gammas: Vec<Matrix3<f64>>,
    /// Largest eigenvalues of `X` (up to 6), descending: tight when the fourth is negligible.
    pub x_top_eigenvalues: Vec<f64>,
    /// The rounding of `X`: top three eigenvectors, blocks projected to SO(3), `S` the polar
    /// factor of `sum_i C_i R_i^T`, gauge `R_0 = I`; its joint cost is an upper bound.
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

/// The sparsity of the relaxation as a view graph on `2n` nodes (right nodes `0..n`, left nodes
/// `n..2n`, a coupling edge `(i, n + i)` and `(0, n + i)` per node): the SDP's cliques are this
/// graph's, so [`predict_relax_multiple`] predicts its cost; the dense `6n x 6n` matrices of the
/// rounding and of the verification are added (memory: the larger of the two; time: both).
pub fn predict_relax_simultaneous(
    right: &MultipleProblem,
    left: &MultipleProblem,
) -> Result<SdpPrediction> {
    let n = right.num_rotations();
    let id = Rotation::identity();
    let edge = |i, j| Edge {
        i,
        j,
        rotation: id,
        weight: 1.0,
    };
    let mut edges: Vec<Edge> = right.edges().iter().map(|e| edge(e.i, e.j)).collect();
    edges.extend(left.edges().iter().map(|e| edge(n + e.i, n + e.j)));
    for i in 0..n {
        edges.push(edge(i, n + i));
        if i > 0 {
            edges.push(edge(0, n + i));
            edges.push(edge(i, n));
        }
    }
    let p = predict_relax_multiple(&MultipleProblem::new(2 * n, edges)?)?;
    // the dense 6n x 6n matrices outside Clarabel: X and its eigenvectors (rounding), the
    // certificate matrix M and its magnitudes (verification), each a symmetric eigenproblem
    let dim = 6.0 * n as f64;
    Ok(SdpPrediction {
        bytes: p.bytes.max(4.0 * 8.0 * dim * dim),
        seconds: p.seconds + 2.0 * 10.0 * dim * dim * dim / SDP_MULTIPLY_ADD_RATE,
        ..p
    })
}

/// The upper-triangle entries of `blkdiag(Q_R, Q_L)` (`6n x 6n`).
fn cost_upper(right: &MultipleProblem, left: &MultipleProblem) -> Vec<(usize, usize, f64)> {
    let n3 = 3 * right.num_rotations();
    let mut out = Vec::new();
    for (offset, p) in [(0, right), (n3, left)] {
        for t in connection_laplacian_triplets(p) {
            if t.row <= t.col {
                out.push((offset + t.row, offset + t.col, t.val));
            }
        }
    }
    out
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

/// Solves the dual `[H12]` with Clarabel (one PSD cone of size `6n`, chordal decomposition as
/// in [`crate::relax::relax_multiple`]), cost scaled by the mean weighted degree `[P4]`.
/// Errors: graphs of different sizes, a setup failure; a non-converged solve is a status.
///
/// ```
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::relax::simultaneous::relax_simultaneous;
/// use rotavg::relax::SdpSettings;
/// use rotavg::so3::exp;
/// use nalgebra::Vector3;
/// let rs: Vec<_> = (0..4).map(|k| exp(&Vector3::new(0.3 * k as f64, -0.2, 0.1 * k as f64))).collect();
/// let s = exp(&Vector3::new(0.2, -0.5, 0.4));
/// let pairs = [(0, 1), (1, 2), (2, 3), (3, 0), (0, 2)];
/// let e = |i: usize, j: usize, rotation| Edge { i, j, rotation, weight: 1.0 };
/// let right: Vec<_> = pairs.iter().map(|&(i, j)| e(i, j, rs[j] * rs[i].inverse())).collect();
/// let left: Vec<_> = right.iter().map(|x| e(x.i, x.j, s * x.rotation * s.inverse())).collect();
/// let (right, left) = (MultipleProblem::new(4, right)?, MultipleProblem::new(4, left)?);
/// let sol = relax_simultaneous(&right, &left, &SdpSettings::default())?;
/// assert!(sol.status.converged());
/// assert_eq!((sol.lambdas.len(), sol.gammas.len()), (8, 3)); // 2n blocks, n - 1 couplings
/// // the rounding is a feasible joint point: its cost is an upper bound, finite and >= 0
/// assert!(sol.rounded.cost.is_finite() && sol.rounded.cost >= 0.0);
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
    let dim = 6 * n;
    let mut b = vec![0.0; svec_len(dim)];
    for (r, c, v) in cost_upper(right, left) {
        b[svec_index(r, c)] += v / scale * svec_weight(r, c);
    }
    // variables: 6 per diagonal block (2n blocks), then 9 per Gamma_i (i = 1..n)
    let nv = 12 * n + 9 * (n - 1);
    let mut c = vec![0.0; nv];
    let mut trip = Vec::with_capacity(12 * n + 18 * (n - 1));
    for a in 0..2 * n {
        for col in 0..3 {
            for row in 0..=col {
                let k = 6 * a + svec_index(row, col);
                if row == col {
                    c[k] = -1.0;
                }
                let entry = svec_index(3 * a + row, 3 * a + col);
                trip.push((entry, k, svec_weight(row, col)));
            }
        }
    }
    for i in 1..n {
        for (r, cc) in (0..3).flat_map(|r| (0..3).map(move |cc| (r, cc))) {
            let k = 12 * n + 9 * (i - 1) + 3 * r + cc;
            // Gamma_i[r][cc] at (C_i row r, R_i column cc), minus it at (C_0, R_0)
            let (ci, ri, c0) = (3 * (n + i) + r, 3 * i + cc, 3 * n + r);
            trip.push((svec_index(ri, ci), k, svec_weight(ri, ci)));
            trip.push((svec_index(cc, c0), k, -svec_weight(cc, c0)));
        }
    }
    let a = csc(svec_len(dim), nv, trip);
    let merge = settings
        .chordal_merge
        .clarabel_name(2 * n, right.num_edges() + left.num_edges());
    let conic = solve_conic(&c, a, &b, &[Cone::Psd(dim)], settings, merge)?;
    let x = &conic.x;
    let finite = |v: f64| if v.is_finite() { v * scale } else { f64::NAN };
    let lambdas = (0..2 * n)
        .map(|a| {
            let l = Matrix3::from_fn(|r, cc| finite(x[6 * a + svec_index(r, cc)]));
            (l + l.transpose()) * 0.5
        })
        .collect();
    let gammas = (1..n)
        .map(|i| Matrix3::from_fn(|r, cc| finite(x[12 * n + 9 * (i - 1) + 3 * r + cc])))
        .collect();
    let xm = smat(&conic.z, dim).ok_or_else(|| Error::Solver {
        message: "Clarabel returned a dual vector of the wrong length".into(),
    })?;
    let (rounded, x_top_eigenvalues) = round(&xm, right, left)?;
    Ok(SimultaneousRelaxation {
        status: conic.status,
        lambdas,
        gammas,
        x_top_eigenvalues,
        rounded,
        iterations: conic.iterations,
        solver_seconds: conic.solve_seconds,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// Rounding: `Y = V_3 diag(sqrt(lambda_1..3))` from the top eigenpairs of `X`, the global
/// reflection fixed by the majority of block determinants, blocks projected to SO(3), `S` the
/// rotation nearest `sum_i C_i R_i^T`, then the gauge `R_0 = I`.
fn round(
    x: &Mat<f64>,
    right: &MultipleProblem,
    left: &MultipleProblem,
) -> Result<(JointRotations, Vec<f64>)> {
    let n = x.nrows() / 6;
    let (y, top) = top_three_blocks(x, 2 * n)?;
    let blocks: Vec<Rotation> = y
        .iter()
        .map(|b| project_to_so3(b).unwrap_or_else(Rotation::identity))
        .collect();
    let (rs, cs) = blocks.split_at(n);
    let sum: Matrix3<f64> = cs
        .iter()
        .zip(rs)
        .map(|(c, r)| c.matrix() * r.matrix().transpose())
        .sum();
    let s_hat = project_to_so3(&sum).unwrap_or_else(Rotation::identity);
    let g = rs[0].inverse();
    let rotations: Vec<Rotation> = rs.iter().map(|r| r * g).collect();
    let cost = joint_cost(right, left, &rotations, &s_hat);
    Ok((
        JointRotations {
            rotations,
            s: s_hat,
            cost,
        },
        top,
    ))
}
