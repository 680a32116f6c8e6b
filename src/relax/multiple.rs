//! The SDP relaxation of chordal L2 multiple rotation averaging (contract section 3,
//! `paper-notes/sdp.md`):
//!
//! - primal `[P2]`: `min tr(Q X)` s.t. `X` PSD (`3n x 3n`), `X_ii = I_3`;
//! - dual `[P3]`: `max sum_i tr(Lambda_i)` s.t. `Q - blkdiag(Lambda)` PSD, `Lambda_i` symmetric.
//!
//! [`relax_multiple`] solves either with Clarabel, returns the multipliers `Lambda_i` (from which
//! a *verified* lower bound must be computed elsewhere: the solver's objectives are not bounds),
//! the primal `X` and the rounded estimate `[P5]`.

use crate::error::{Error, Result};
use crate::multiple::MultipleProblem;
use crate::multiple::laplacian::connection_laplacian;
use crate::relax::clarabel::{Cone, ConicSolution, csc, solve_conic};
use crate::relax::settings::{SdpForm, SdpSettings, SdpStatus};
use crate::relax::svec::{smat, svec_index, svec_len, svec_weight};
use crate::so3::{Rotation, project_to_so3};
use faer::{Mat, Side};
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Result of [`relax_multiple`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MultipleRelaxation {
    /// Solver outcome.
    pub status: SdpStatus,
    /// Formulation that was solved.
    pub form: SdpForm,
    /// Dual multipliers `Lambda_i` (symmetrised), in the units of the cost `f`. Feed them to an
    /// independent verification to get a rigorous lower bound; they are only approximately
    /// dual feasible.
    pub multipliers: Vec<Matrix3<f64>>,
    /// Dense primal `X` (`3n x 3n`, column-major) when `3n <= settings.dense_x_max_size`.
    pub x_dense: Option<Vec<f64>>,
    /// Largest eigenvalues of `X`, descending (up to 6): the relaxation is tight (rank 3) when
    /// the fourth is negligible against the third.
    pub x_top_eigenvalues: Vec<f64>,
    /// Rounded estimate `[P5]`: top-3 eigenvectors of `X`, global reflection fixed by the majority
    /// of block determinant signs, blocks projected to SO(3), gauge `R_0 = I`.
    #[serde(with = "crate::so3::serde_rows::rotations")]
    pub rounded: Vec<Rotation>,
    /// Chordal cost `f` of [`Self::rounded`] (an upper bound on the global minimum).
    pub rounded_cost: f64,
    /// Blocks of the top-3 factor of `X` with a negative determinant after the global sign
    /// choice: a tight `O(3)` solution with reflected blocks is not a point of `SO(3)^n`, and its
    /// value can lie strictly below every rotation estimate (anisotropic costs,
    /// `paper-notes/anisotropic.md` `[A5]`).
    #[serde(default)]
    pub reflected_blocks: usize,
    /// Solver's value of the primal objective `tr(Q X)`, unscaled. Informational only.
    pub primal_objective: f64,
    /// Solver's value of the dual objective `sum_i tr(Lambda_i)`, unscaled. Informational
    /// only: **never use it as a lower bound**.
    pub dual_objective: f64,
    /// Interior-point iterations.
    pub iterations: u32,
    /// Clarabel's solve time, seconds.
    pub solver_seconds: f64,
    /// Total time including problem assembly and rounding, seconds.
    pub seconds: f64,
    /// The cost scale `s` (mean weighted degree): Clarabel solved the problem for `Q / s` `[P4]`.
    pub scale: f64,
}

/// Solves the SDP relaxation of `problem` (chordal L2 cost) with Clarabel.
///
/// The cost is scaled by the mean weighted degree `s = 2 sum w / n` for conditioning and every
/// returned quantity is unscaled `[P4]`. Errors: invalid settings, a graph with no edges, or a
/// solver setup failure. A non-converged solve is *not* an error: check
/// [`MultipleRelaxation::status`].
///
/// ```
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// use rotavg::relax::{relax_multiple, SdpSettings, SdpStatus};
/// let (p, _) = SyntheticGraph { num_rotations: 5, num_edges: 8, noise_sigma: 0.0, ..Default::default() }.generate();
/// let sol = relax_multiple(&p, &SdpSettings::default()).unwrap();
/// assert_eq!(sol.status, SdpStatus::Solved);
/// assert!(sol.rounded_cost < 1e-8); // noise free: the SDP recovers the planted rotations
/// ```
pub fn relax_multiple(
    problem: &MultipleProblem,
    settings: &SdpSettings,
) -> Result<MultipleRelaxation> {
    settings.validate()?;
    let start = Instant::now();
    let n = problem.num_rotations();
    if problem.num_edges() == 0 || n == 0 {
        return Err(Error::Empty {
            what: "view graph (edges)".into(),
        });
    }
    let scale = cost_scale(problem);
    let q = connection_laplacian(problem);
    // upper-triangle entries of Q / s
    let mut q_upper: Vec<(usize, usize, f64)> = Vec::new();
    for col in 0..q.ncols() {
        let rows = q.as_ref().row_idx_of_col_raw(col);
        let vals = q.as_ref().val_of_col(col);
        for (&r, &v) in rows.iter().zip(vals) {
            if r <= col && v != 0.0 {
                q_upper.push((r, col, v / scale));
            }
        }
    }
    let merge = settings.chordal_merge.clarabel_name(n, problem.num_edges());
    let raw = match settings.form {
        SdpForm::Dual => solve_dual(&Scaled {
            n,
            q_upper: &q_upper,
            settings,
            merge,
        })?,
        SdpForm::Primal => solve_primal(&Scaled {
            n,
            q_upper: &q_upper,
            settings,
            merge,
        })?,
    };
    let multipliers = raw
        .lambda_scaled
        .iter()
        .map(|l| {
            let l = l * scale;
            (l + l.transpose()) * 0.5
        })
        .collect();
    let (rounded, x_top_eigenvalues, reflected_blocks) = round(&raw.x, n)?;
    let rounded_cost = problem.chordal_cost(&rounded);
    let dim = 3 * n;
    let x_dense = (dim <= settings.dense_x_max_size)
        .then(|| (0..dim * dim).map(|k| raw.x[(k % dim, k / dim)]).collect());
    Ok(MultipleRelaxation {
        status: raw.conic.status,
        form: settings.form,
        multipliers,
        x_dense,
        x_top_eigenvalues,
        rounded,
        rounded_cost,
        reflected_blocks,
        primal_objective: raw.conic.primal_objective * scale,
        dual_objective: raw.conic.dual_objective * scale,
        iterations: raw.conic.iterations,
        solver_seconds: raw.conic.solve_seconds,
        seconds: start.elapsed().as_secs_f64(),
        scale,
    })
}

/// The cost of the SDP relaxation predicted from the graph before Clarabel starts (issue 25):
/// the chordal decomposition's cliques are modelled by the fronts of the scalar Laplacian's
/// symbolic Cholesky factor (AMD order, as Clarabel's own decomposition), each a PSD cone of
/// dimension `d = 3 x` its nodes; an interior-point iteration on a cone of `t = d (d + 1) / 2`
/// svec entries holds a dense `t x t` block of the KKT system and its factor, and factorises it
/// in about `t^3 / 3` multiply-adds. Calibration and measurements: `paper-notes/sdp.md` `[P6]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SdpPrediction {
    /// Predicted peak memory, bytes.
    pub bytes: f64,
    /// Predicted wall time, seconds.
    pub seconds: f64,
    /// Nodes of the largest clique (front) of the model.
    pub largest_clique: usize,
    /// Cliques of the model.
    pub cliques: usize,
}

/// Bytes per squared svec entry of a cone (the dense KKT block, its factor and copies).
/// Calibrated on random view graphs (`examples/sdp_predict`, 2026-11-26, 2-core machine,
/// Clarabel 0.11, default settings): peak RSS 0.39, 1.49, 0.52, 1.56 and 4.94 GB for
/// `(n, m)` = (40, 160), (60, 240), (150, 225), (200, 300), (80, 320), which this predicts as
/// 0.47, 2.0, 0.51, 1.6 and 7.8 GB (at least the measurement but once, within 4 %).
pub const SDP_BYTES_PER_BLOCK_ENTRY: f64 = 56.0;
/// Multiply-adds per second of the dense KKT work (with [`SDP_ITERATIONS`]: 5.3, 29.6, 10.2,
/// 51 and 267 s measured for the graphs above, predicted 6.2, 58, 5.5, 37 and 419 s). Clarabel's
/// own time limit enforces the budget; the prediction decides whether to start.
pub const SDP_MULTIPLY_ADD_RATE: f64 = 1e10;
/// Interior-point iterations assumed by the time model (9 to 12 measured).
pub const SDP_ITERATIONS: f64 = 20.0;

/// The cost scale `s` of the SDPs `[P4]`: the mean weighted degree `2 sum w / n` (> 0: weights are
/// validated positive; for anisotropic edges `w = tr(H) / 3`).
pub(crate) fn cost_scale(problem: &MultipleProblem) -> f64 {
    let total_weight: f64 = problem.edges().iter().map(|e| e.weight).sum();
    (2.0 * total_weight / problem.num_rotations().max(1) as f64).max(f64::MIN_POSITIVE)
}

/// [`SdpPrediction`] of [`relax_multiple`] on `problem` (never errors on a valid problem).
pub fn predict_relax_multiple(problem: &MultipleProblem) -> Result<SdpPrediction> {
    let n = problem.num_rotations();
    let mut t = Vec::with_capacity(2 * problem.num_edges() + n);
    for e in problem.edges() {
        t.push(faer::sparse::Triplet::new(e.i, e.j, 1.0));
        t.push(faer::sparse::Triplet::new(e.j, e.i, 1.0));
    }
    for i in 0..n {
        t.push(faer::sparse::Triplet::new(i, i, 1.0));
    }
    let pattern = faer::sparse::SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &t)
        .map_err(|e| Error::Solver {
            message: format!("could not assemble the view graph's pattern: {e:?}"),
        })?;
    let symbolic =
        match crate::linalg::cholesky::symbolic_cholesky_within(pattern.symbolic(), usize::MAX)? {
            Ok(s) => s,
            Err(_) => unreachable!("no limit"),
        };
    let fronts = crate::linalg::cholesky::front_sizes(&symbolic);
    let (mut block_entries, mut multiply_adds) = (0.0f64, 0.0f64);
    for &c in &fronts {
        let d = 3.0 * c as f64;
        let svec = d * (d + 1.0) / 2.0;
        block_entries += svec * svec;
        multiply_adds += svec * svec * svec / 3.0;
    }
    Ok(SdpPrediction {
        bytes: SDP_BYTES_PER_BLOCK_ENTRY * block_entries,
        seconds: SDP_ITERATIONS * multiply_adds / SDP_MULTIPLY_ADD_RATE,
        largest_clique: fronts.iter().copied().max().unwrap_or(0),
        cliques: fronts.len(),
    })
}

/// The scaled problem `[P4]` handed to a formulation, and how Clarabel runs it.
struct Scaled<'a> {
    /// Nodes.
    n: usize,
    /// The upper-triangle entries of `Q / s`.
    q_upper: &'a [(usize, usize, f64)],
    settings: &'a SdpSettings,
    /// The clique merge method of the chordal decomposition.
    merge: &'a str,
}

/// What each formulation hands back (scaled problem).
struct RawSolution {
    lambda_scaled: Vec<Matrix3<f64>>,
    x: Mat<f64>,
    /// Status, iterations, time, and the objectives of the primal `[P2]` / dual `[P3]` (scaled).
    conic: ConicSolution,
}

/// The upper-triangle entries `(r, c, v)` of a `dim x dim` matrix as a vector in `svec` order,
/// each times `weight(r, c)`.
fn upper_svec(
    upper: &[(usize, usize, f64)],
    dim: usize,
    weight: impl Fn(usize, usize) -> f64,
) -> Vec<f64> {
    let mut out = vec![0.0; svec_len(dim)];
    for &(r, c, v) in upper {
        out[svec_index(r, c)] = v * weight(r, c);
    }
    out
}

/// The upper-triangle entries of the `n` diagonal `3 x 3` blocks: `(k, a, b, e)` with
/// `k = 6 i + svec_index(a, b)` the entry's index among the blocks' six each (the multipliers of
/// `[P3]`, the constraints `X_ii = I` of `[P2]`) and `e` its index in `svec` of the `3n x 3n`
/// matrix.
fn diagonal_block_entries(n: usize) -> impl Iterator<Item = (usize, usize, usize, usize)> {
    (0..n).flat_map(|i| {
        (0..3).flat_map(move |b| {
            (0..=b).map(move |a| {
                (
                    6 * i + svec_index(a, b),
                    a,
                    b,
                    svec_index(3 * i + a, 3 * i + b),
                )
            })
        })
    })
}

/// Dual form `[P3]` in Clarabel's standard form `min c'x, b - A x in K`: `x` holds the upper
/// triangles of the `Lambda_i` (6 per node, order of [`svec_index`] on 3x3),
/// `c = -(diagonal indicators)`, `b - A x = svec(Q/s - blkdiag(Lambda))` in one PSD cone of
/// size `3n`. Clarabel's dual variable of that cone is `svec(X)` of the primal `[P2]`
/// (stationarity `A^T z = -c` is exactly `X_ii = I`).
fn solve_dual(p: &Scaled<'_>) -> Result<RawSolution> {
    let dim = 3 * p.n;
    let m = svec_len(dim);
    let b = upper_svec(p.q_upper, dim, svec_weight);
    let nv = 6 * p.n;
    let mut c = vec![0.0; nv];
    let mut trip = Vec::with_capacity(nv);
    for (k, a, bb, entry) in diagonal_block_entries(p.n) {
        if a == bb {
            c[k] = -1.0;
        }
        trip.push((entry, k, svec_weight(a, bb)));
    }
    let a = csc(m, nv, trip);
    let mut conic = solve_conic(&c, a, &b, &[Cone::Psd(dim)], p.settings, p.merge)?;
    // Clarabel minimises -sum tr(Lambda); its dual objective is -tr(Q X / s)
    (conic.primal_objective, conic.dual_objective) =
        (-conic.dual_objective, -conic.primal_objective);
    let x = &conic.x;
    let lambda_scaled = (0..p.n)
        .map(|i| {
            Matrix3::from_fn(|r, cc| {
                let v = x[6 * i + svec_index(r, cc)];
                if v.is_finite() { v } else { f64::NAN }
            })
        })
        .collect();
    let xm = smat(&conic.z, dim).ok_or_else(|| Error::Solver {
        message: "Clarabel returned a dual vector of the wrong length".into(),
    })?;
    Ok(RawSolution {
        lambda_scaled,
        x: xm,
        conic,
    })
}

/// Primal form `[P2]`: `x` = upper triangle of `X` (unscaled entries), cost `svec`-weighted
/// `Q/s` so `c'x = tr(Q X / s)`; `6n` equality rows `X_ii[a,b] = delta_ab` (zero cone) and
/// `-diag(w) x + s = 0`, `s = svec(X)` in the PSD cone. Multipliers from the equality duals
/// `y`: `Lambda_aa = -y`, `Lambda_ab = -y/2` (derivation in `paper-notes/sdp.md` `[P3]`).
fn solve_primal(p: &Scaled<'_>) -> Result<RawSolution> {
    let dim = 3 * p.n;
    let nv = svec_len(dim);
    // tr(Q X / s) counts each off-diagonal entry twice
    let c = upper_svec(p.q_upper, dim, |r, cc| if r == cc { 1.0 } else { 2.0 });
    let neq = 6 * p.n;
    let mut trip = Vec::with_capacity(neq + nv);
    let mut b = vec![0.0; neq + nv];
    for (row, a, bb, entry) in diagonal_block_entries(p.n) {
        trip.push((row, entry, 1.0));
        b[row] = if a == bb { 1.0 } else { 0.0 };
    }
    for col in 0..dim {
        for row in 0..=col {
            let k = svec_index(row, col);
            trip.push((neq + k, k, -svec_weight(row, col)));
        }
    }
    let a = csc(neq + nv, nv, trip);
    let conic = solve_conic(
        &c,
        a,
        &b,
        &[Cone::Zero(neq), Cone::Psd(dim)],
        p.settings,
        p.merge,
    )?;
    let (x, z) = (&conic.x, &conic.z);
    let lambda_scaled = (0..p.n)
        .map(|i| {
            Matrix3::from_fn(|r, cc| {
                let y = z[6 * i + svec_index(r, cc)];
                if r == cc { -y } else { -0.5 * y }
            })
        })
        .collect();
    let mut xm = Mat::zeros(dim, dim);
    for col in 0..dim {
        for row in 0..=col {
            let v = x[svec_index(row, col)];
            xm[(row, col)] = v;
            xm[(col, row)] = v;
        }
    }
    Ok(RawSolution {
        lambda_scaled,
        x: xm,
        conic,
    })
}

/// Rounding `[P5]`: `Y = V_3 diag(sqrt(lambda_1..3))` from the top eigenpairs of `X`; if most
/// blocks `Y_i` have negative determinant, flip the third column (global reflection); project
/// each block to SO(3); fix the gauge `R_0 = I`. Returns the rotations and the top eigenvalues.
fn round(x: &Mat<f64>, n: usize) -> Result<(Vec<Rotation>, Vec<f64>, usize)> {
    let (y, top) = top_three_blocks(x, n)?;
    let (rotations, reflected) = project_blocks(y);
    Ok((rotations, top, reflected))
}

/// The last step of every rounding `[P5]` (the SDP's rank-3 factor, the staircase's lifted
/// point): the global reflection fixed by the majority of block determinants, the blocks still
/// reflected (`det < 0`) counted (the `O(3)` relaxation preferred them: anisotropic costs,
/// `paper-notes/anisotropic.md` `[A5]`), each block projected to SO(3), gauge `R_0 = I`.
pub(crate) fn project_blocks(mut blocks: Vec<Matrix3<f64>>) -> (Vec<Rotation>, usize) {
    fix_global_reflection(&mut blocks);
    let reflected = blocks.iter().filter(|b| b.determinant() < 0.0).count();
    let mut rotations: Vec<Rotation> = blocks
        .iter()
        .map(|b| project_to_so3(b).unwrap_or_else(Rotation::identity))
        .collect();
    crate::multiple::fix_gauge(&mut rotations);
    (rotations, reflected)
}

/// The `blocks` `3 x 3` blocks of `Y = V_3 diag(sqrt(lambda_1..3))` from the top eigenpairs of
/// the `3 blocks x 3 blocks` matrix `X`, the global reflection fixed by the majority of block
/// determinants, and the largest eigenvalues of `X` (up to 6, descending): the rounding `[P5]` of every SDP of
/// this crate whose variable is a Gram matrix of rotation blocks.
pub(crate) fn top_three_blocks(
    x: &Mat<f64>,
    blocks: usize,
) -> Result<(Vec<Matrix3<f64>>, Vec<f64>)> {
    let dim = 3 * blocks;
    if !x.as_ref().is_all_finite() {
        return Err(Error::Solver {
            message: "the SDP solution contains non-finite values".into(),
        });
    }
    let evd = x
        .as_ref()
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| Error::Solver {
            message: format!("eigendecomposition of X failed: {e:?}"),
        })?;
    // ascending eigenvalues: the top three are the last
    let s = evd.S();
    let u = evd.U();
    let top: Vec<f64> = (0..dim.min(6)).map(|k| s[dim - 1 - k]).collect();
    let mut y = vec![Matrix3::<f64>::zeros(); blocks];
    for c in 0..3 {
        let col = dim - 1 - c;
        let w = s[col].max(0.0).sqrt();
        for (i, yi) in y.iter_mut().enumerate() {
            for a in 0..3 {
                yi[(a, c)] = u[(3 * i + a, col)] * w;
            }
        }
    }
    fix_global_reflection(&mut y);
    Ok((y, top))
}

/// Flip the third column of every block when most blocks have a negative determinant (`Y` and
/// `Y diag(1, 1, -1)` are factors of the same Gram matrix).
fn fix_global_reflection(blocks: &mut [Matrix3<f64>]) {
    if 2 * blocks.iter().filter(|b| b.determinant() < 0.0).count() > blocks.len() {
        for b in blocks.iter_mut() {
            b.set_column(2, &(-b.column(2)));
        }
    }
}
