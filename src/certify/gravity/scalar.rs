//! The scalar comparison `[D13]` for the SO(2) certificate matrix of the full-gravity problem
//! (`paper-notes/gravity.md`, `[G9]`): `lambda_min(S)` proven from one `n x n` scalar
//! factorisation instead of the `2n x 2n` real form's, which fills on expander view graphs
//! (10^4 cameras, 4 edges each: 3.5 s against 0.2 s of solve).
//!
//! The embedding: each entry `H_ij = re + i im` becomes an edge of weight `w = |H_ij|` and
//! relative rotation `Rz(phi)`, `(cos phi, sin phi) = (-re, im) / w`, of a multiple-averaging
//! problem on the same nodes; the estimate becomes `Rz(theta_i)` and the multipliers
//! `diag(d_i - s_i, d_i - s_i, 0)`, `d_i` the node's weight sum. Its certificate matrix is
//! (up to a permutation) the direct sum of `S`'s real form and the scalar Laplacian of the
//! weights, which is positive semidefinite; so `[D13]`'s bound on its smallest eigenvalue
//! bounds `S`'s, once the rounding of the embedding and of `S`'s entries is charged.

use super::planar::{PlanarBound, PlanarForm};
use crate::certify::budget::{Budget, Deadline};
use crate::certify::multiple::scalar::SECONDS_PER_EDGE;
use crate::certify::multiple::scalar::{ScalarAnalysis, scalar_comparison};
use crate::certify::settings::CertifySettings;
use crate::error::Result;
use crate::linalg::cholesky::gamma;
use crate::multiple::{Edge, MultipleProblem};
use crate::so3::Rotation;
use nalgebra::Matrix3;

/// The rotation by `(c, s) = (cos t, sin t)` about `e_3`.
fn rz(c: f64, s: f64) -> Rotation {
    Rotation::from_matrix_unchecked(Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0))
}

/// The embedded problem, estimate and multipliers, and the bound on `||S - S_emb||_2` (the
/// embedding's rounding and the forming error of `S`'s entries, as `[D6]`(b) charges it).
struct Embedding {
    problem: MultipleProblem,
    rotations: Vec<Rotation>,
    lambdas: Vec<Matrix3<f64>>,
    rounding: f64,
}

/// Embed `S = H - diag(lambda)` at phases `x` (`[G9]`); `None` when the problem cannot be
/// formed (no edge with a nonzero entry).
fn embed(form: &PlanarForm, x: &[(f64, f64)]) -> Option<Embedding> {
    let n = form.len();
    let s = form.certificate_diagonal(x);
    let (mut weight, mut row_abs, mut degree) = (vec![0.0; n], vec![0.0; n], vec![0usize; n]);
    let mut edges = Vec::with_capacity(form.entries().len());
    for &(i, j, re, im) in form.entries() {
        let w = re.hypot(im);
        for k in [i, j] {
            weight[k] += w;
            row_abs[k] += re.abs() + im.abs();
            degree[k] += 1;
        }
        if w > 0.0 {
            let rotation = rz(-re / w, im / w);
            edges.push(Edge {
                i,
                j,
                rotation,
                weight: w,
            });
        }
    }
    let problem = MultipleProblem::new(n, edges).ok()?;
    let lambdas = (0..n)
        .map(|i| {
            let l = weight[i] - s[i];
            Matrix3::from_diagonal(&nalgebra::Vector3::new(l, l, 0.0))
        })
        .collect();
    let rotations = x.iter().map(|&(c, s)| rz(c, s)).collect();
    // every entry of S and of S_emb is formed from at most 31 d_max + 24 operations on
    // exact data; each row's magnitudes are at most |s_i| + sum |re| + |im| + 2 d_i
    let max_degree = degree.into_iter().max().unwrap_or(0);
    let row = (0..n)
        .map(|i| s[i].abs() + row_abs[i] + 2.0 * weight[i])
        .fold(0.0, f64::max);
    let rounding = gamma(31 * max_degree + 24) * row * (1.0 + 1e-12);
    Some(Embedding {
        problem,
        rotations,
        lambdas,
        rounding,
    })
}

/// The scalar comparison runs first when the `2n x 2n` factor it avoids is predicted to take
/// more than this many seconds (its factor has `~4x` the values and `~8x` the flops of the
/// scalar one); below it the shifted Cholesky `[G3]`, which proves `lambda_min(S)` itself
/// rather than a sufficient condition, is cheap enough.
pub const SCALAR_FIRST_ABOVE_SECONDS: f64 = 0.1;

/// `[G3]`'s bound at phases `x` with `lambda_min(S)` proven by the scalar comparison `[D13]`
/// on the embedding `[G9]`. `Ok(None)` when the `2n` factor is cheap
/// ([`SCALAR_FIRST_ABOVE_SECONDS`]); `Some(Err)` with the reason when the scalar factor is
/// over the memory budget or past the time left, or the comparison does not prove.
pub(super) fn verify_planar_scalar(
    form: &PlanarForm,
    x: &[(f64, f64)],
    (allowed_gap, graph_defect): (f64, f64),
    settings: &CertifySettings,
    deadline: &Deadline,
) -> Result<Option<std::result::Result<PlanarBound, String>>> {
    let Some(e) = embed(form, x) else {
        return Ok(None);
    };
    let max_values = settings.budget.max_factor_values(form.len());
    let analysis = match ScalarAnalysis::new(&e.problem, max_values)? {
        Ok(a) => a,
        Err(predicted) => {
            let why = format!("its factor ({predicted} values) is over the memory budget");
            return Ok(Some(Err(why)));
        }
    };
    // the 2n x 2n factor it avoids: ~4x the values, ~8x the flops
    let (adds, len) = (analysis.factor_multiply_adds(), analysis.factor_len());
    if Budget::predicted_factor_seconds(8.0 * adds, 4 * len) <= SCALAR_FIRST_ABOVE_SECONDS {
        return Ok(None);
    }
    let predicted = Budget::predicted_factor_seconds(adds, len)
        + SECONDS_PER_EDGE * e.problem.num_edges() as f64;
    if deadline.left().is_some_and(|l| l < predicted) {
        let why = format!("predicted at {predicted:.2e} s, past the time left");
        return Ok(Some(Err(why)));
    }
    let found = prove(&e, &analysis, allowed_gap)?;
    Ok(Some(found.map(|mu| PlanarBound {
        lower_bound: form.bound_at(graph_defect, x, mu),
        verified_min_eigenvalue: mu,
    })))
}

/// `lambda_min(S) >= mu` proven on the embedding `e` (its rounding charged), with the
/// comparison's target `|mu|` a quarter of `allowed_gap` over the `n` nodes.
fn prove(
    e: &Embedding,
    analysis: &ScalarAnalysis,
    allowed_gap: f64,
) -> Result<std::result::Result<f64, String>> {
    let n = e.rotations.len().max(1) as f64;
    let target = 0.25 * allowed_gap / n;
    let found = scalar_comparison(&e.problem, analysis, &e.rotations, &e.lambdas, target)?;
    Ok(match found {
        Ok(c) => Ok(c.verified_min_eigenvalue - e.rounding),
        Err(why) => Err(format!("the scalar comparison did not prove ({why:?})")),
    })
}

#[cfg(test)]
mod tests;
