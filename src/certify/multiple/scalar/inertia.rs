//! Step 5 of the scalar comparison `[D13]`: "at most one negative eigenvalue" of every part's
//! `L'_p - diag(c_p)`, proven by the inertia of an `LDL^T` factorisation of
//! `L'_p - diag(c_p) - h I` (Sylvester), with the headroom `h` above the rigorous backward error
//! of the computed factors plus the forming error (Weyl).

use super::ScalarFailure;
use super::analysis::{ScalarAnalysis, ScalarPart};
use super::split::{PencilWeights, part_charges};
use crate::linalg::cholesky::gamma;
use crate::linalg::ldlt::{LdltFailure, ldlt_inertia};
use crate::multiple::MultipleProblem;

/// Step 5 for every part (one part, with the charges `w`, for the whole graph or a subgraph):
/// `(largest headroom, largest backward error)` when every part shows exactly one negative
/// pivot within its headroom. `h` starts at `1e-6 d_max / P` (it only needs to exceed the
/// backward error, ~1e-10 d_max at 10^4 nodes) and is retried once at 4 times the error.
pub(super) fn prove_inertia(
    analysis: &ScalarAnalysis,
    problem: &MultipleProblem,
    reduced: &[f64],
    pencil: &PencilWeights,
    deg_n: &[usize],
    d_max: f64,
) -> std::result::Result<(f64, f64), ScalarFailure> {
    let num_parts = analysis.parts.len().max(1);
    let mut headroom = 0.0f64;
    let mut backward = 0.0f64;
    for (p, part) in analysis.parts.iter().enumerate() {
        let charges = match pencil.shares.get(p) {
            Some(f) => part_charges(&pencil.weights, f, num_parts),
            None => pencil.weights.clone(),
        };
        let mut h = 1e-6 * d_max.max(f64::MIN_POSITIVE) / num_parts as f64;
        let mut retried = false;
        let bound = loop {
            let bound =
                factor_inertia(part, problem, &analysis.copies, reduced, &charges, h, deg_n)?;
            if bound <= h {
                break bound;
            }
            if retried {
                return Err(ScalarFailure::BackwardError);
            }
            retried = true;
            h = 4.0 * bound;
        };
        headroom = headroom.max(h);
        backward = backward.max(bound);
    }
    Ok((headroom, backward))
}

/// `LDL^T` of `A = L'_p - diag(delta) - h I` without pivoting (AMD order), `L'_p` the Laplacian
/// of `part`'s edges with the weights `reduced / copies` (any sign). Returns a rigorous bound on
/// `||A_exact - P^T L D L^T P||_2` when exactly one pivot is negative and none is zero; a
/// failure otherwise.
pub(super) fn factor_inertia(
    part: &ScalarPart,
    problem: &MultipleProblem,
    copies: &[u32],
    reduced: &[f64],
    delta: &[f64],
    h: f64,
    deg_n: &[usize],
) -> std::result::Result<f64, ScalarFailure> {
    let n = delta.len();
    let mut a = part.pattern.clone();
    // row sums of the magnitudes of the terms that form each entry (the forming error)
    let mut magnitude = vec![0.0f64; n];
    {
        let val = a.val_mut();
        val.iter_mut().for_each(|v| *v = 0.0);
        let edges = problem.edges();
        for &(k, p_ij, p_ji) in &part.edges {
            let e = &edges[k];
            // a shared edge's even share (one division: its rounding is in the forming error)
            let w = reduced[k] / copies[k].max(1) as f64;
            val[p_ij] -= w;
            val[p_ji] -= w;
            val[part.diag_pos[e.i]] += w;
            val[part.diag_pos[e.j]] += w;
            magnitude[e.i] += 2.0 * w.abs();
            magnitude[e.j] += 2.0 * w.abs();
        }
        for i in 0..n {
            val[part.diag_pos[i]] -= delta[i] + h;
            magnitude[i] += delta[i] + h;
        }
    }
    let inertia = ldlt_inertia(&part.symbolic, a.as_ref()).map_err(|f| match f {
        LdltFailure::Numerical => ScalarFailure::Numerical,
    })?;
    let negative = inertia.negative;
    if negative != 1 {
        return Err(ScalarFailure::Inertia {
            negative_pivots: negative,
        });
    }
    // every entry of A is a sum of at most deg + 3 rounded terms; a row's entries err by at
    // most gamma(terms + 2) times the magnitudes of their terms
    // (one more rounding for the division of a shared edge's weight)
    let terms = deg_n.iter().copied().max().unwrap_or(0) + 4;
    let forming = gamma(terms + 2) * magnitude.iter().copied().fold(0.0, f64::max);
    // doubled to cover the rounding in evaluating the bounds themselves
    let bound = inertia.backward_error + 2.0 * forming;
    if !bound.is_finite() {
        return Err(ScalarFailure::Numerical);
    }
    Ok(bound)
}
