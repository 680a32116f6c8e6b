//! Step 5 of the scalar comparison `[D13]`: "at most one negative eigenvalue" of every part's
//! `L'_p - diag(c_p)`, proven by the inertia of an `LDL^T` factorisation of
//! `L'_p - diag(c_p) - h I` (Sylvester), with the headroom `h` above the rigorous backward error
//! of the computed factors plus the forming error (Weyl).

use super::ScalarFailure;
use super::analysis::{ScalarAnalysis, ScalarPart};
use super::charges::EdgeCharges;
use super::split::{PencilWeights, part_charges};
use crate::linalg::cholesky::gamma;
use crate::linalg::ldlt::{FactorStorage, LdltFailure, NegativeColumn, ldlt_negative_columns};
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
    let (headroom, backward, _) =
        prove_inertia_deflating(analysis, problem, (reduced, pencil), (deg_n, d_max), 0)?;
    Ok((headroom, backward))
}

/// [`prove_inertia_deflating`] with the charges `c` (their reduced weights, degrees and largest
/// diagonal).
pub(super) fn prove_charged(
    analysis: &ScalarAnalysis,
    problem: &MultipleProblem,
    c: &EdgeCharges,
    pencil: &PencilWeights,
    most: usize,
) -> std::result::Result<(f64, f64, Vec<NegativeColumn>), ScalarFailure> {
    let reduced = (c.reduced.as_slice(), pencil);
    prove_inertia_deflating(analysis, problem, reduced, (&c.deg_n, c.d_max), most)
}

/// [`prove_inertia`], and with one part showing more negative pivots than expected but at most
/// `most`, the factor's columns at every negative pivot (the leading-block deflation (D0) of
/// `[A16]` without a border: `L D L^T = A + Delta` is positive semidefinite off them, so `A >=
/// (h - b) I` there; `paper-notes/certificates.md` `[D13]`, "Deflated components").
pub(super) fn prove_inertia_deflating(
    analysis: &ScalarAnalysis,
    problem: &MultipleProblem,
    (reduced, pencil): (&[f64], &PencilWeights),
    (deg_n, d_max): (&[usize], f64),
    most: usize,
) -> std::result::Result<(f64, f64, Vec<NegativeColumn>), ScalarFailure> {
    let num_parts = analysis.parts.len().max(1);
    let most = if num_parts == 1 { most } else { 0 };
    let mut headroom = 0.0f64;
    let mut backward = 0.0f64;
    let mut deflated = Vec::new();
    // one factor storage for every part's factorisations (`ldlt::FactorStorage`)
    let mut storage = FactorStorage::default();
    for (p, part) in analysis.parts.iter().enumerate() {
        let charges = match pencil.shares.get(p) {
            Some(f) => part_charges(&pencil.weights, f, num_parts),
            None => pencil.weights.clone(),
        };
        let mut h = 1e-6 * d_max.max(f64::MIN_POSITIVE) / num_parts as f64;
        let mut retried = false;
        let bound = loop {
            let expected = analysis.expected_negative_pivots();
            let (bound, columns) = factor_inertia(
                part,
                problem,
                (&analysis.copies, reduced),
                &charges,
                (h, expected, most),
                deg_n,
                &mut storage,
            )?;
            if bound <= h {
                deflated = columns;
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
    Ok((headroom, backward, deflated))
}

/// `LDL^T` of `A = L'_p - diag(delta) - h I` without pivoting (AMD order), `L'_p` the Laplacian
/// of `part`'s edges with the weights `reduced / copies` (any sign). Returns a rigorous bound on
/// `||A_exact - P^T L D L^T P||_2` when exactly `expected` pivots are negative (one, or one per
/// component of a grouped comparison's pattern) and none is zero, or when more but at most
/// `most` are, with the factor's columns at all of them; a failure otherwise.
pub(super) fn factor_inertia(
    part: &ScalarPart,
    problem: &MultipleProblem,
    (copies, reduced): (&[u32], &[f64]),
    delta: &[f64],
    (h, expected, most): (f64, usize, usize),
    deg_n: &[usize],
    storage: &mut FactorStorage,
) -> std::result::Result<(f64, Vec<NegativeColumn>), ScalarFailure> {
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
    let nodes = independent_negative_diagonal(a.as_ref(), &part.diag_pos, h);
    if nodes > expected.max(most) {
        return Err(ScalarFailure::NegativeDiagonal { nodes });
    }
    let numerical = |f| match f {
        LdltFailure::Numerical => ScalarFailure::Numerical,
    };
    // columns only when more than `expected` but at most `most` pivots are negative
    let (inertia, pivots) =
        ldlt_negative_columns(&part.symbolic, a.as_ref(), (expected, most), storage)
            .map_err(numerical)?;
    let columns = pivots.columns;
    let negative = inertia.negative;
    // another count deflates only when asked to, and with every negative pivot's column
    if negative != expected && (most <= expected || columns.len() != negative) {
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
    Ok((bound, columns))
}

/// The size of a set of nodes, pairwise not adjacent, whose diagonal entries of `a` (a
/// symmetric pattern with both triangles; `diag_pos[i]` the position of `a_ii`) are below
/// `-h`: chosen greedily in node order, `O(n + m)`. On the plane of two such nodes `a` is
/// `diag(a_ii, a_jj) < -h I` (their entry is structurally zero), so for any `dA` with
/// `||dA||_2 <= h` the second eigenvalue of `a + dA` is negative (Weyl): two such nodes show
/// that no factorisation the proof would accept (backward error at most the headroom `h`,
/// exactly one negative pivot) exists, and the factorisation is not run (a rig's coupled graph
/// of 20,000 images: 20 such nodes, 8.1 s of `LDL^T` before its 1586 negative pivots,
/// 2026-12-02). A forecast that saves time, never part of a proof.
fn independent_negative_diagonal(
    a: faer::sparse::SparseColMatRef<'_, usize, f64>,
    diag_pos: &[usize],
    h: f64,
) -> usize {
    let (col_ptr, row_idx, val) = (a.col_ptr(), a.row_idx(), a.val());
    let mut blocked = vec![false; diag_pos.len()];
    let mut chosen = 0;
    for (i, &d) in diag_pos.iter().enumerate() {
        if blocked[i] || val[d] >= -h {
            continue;
        }
        chosen += 1;
        for &j in &row_idx[col_ptr[i]..col_ptr[i + 1]] {
            blocked[j] = true;
        }
    }
    chosen
}

#[cfg(test)]
mod tests {
    use super::independent_negative_diagonal;
    use faer::sparse::{SparseColMat, Triplet};
    use nalgebra::DMatrix;
    use rand::{Rng, SeedableRng};

    /// Whenever the greedy choice finds `k` nodes, the `k`-th smallest eigenvalue of the
    /// matrix, computed densely, is below `-h` (Cauchy interlacing on those nodes' principal
    /// submatrix, which is diagonal): on random Laplacians of weights of either sign less
    /// random diagonals; and the choice found at least two nodes on some of them.
    #[test]
    fn the_nodes_found_are_negative_eigenvalues() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let mut twice = 0;
        for _ in 0..200 {
            let n = rng.random_range(2..25);
            let mut dense = DMatrix::<f64>::zeros(n, n);
            for _ in 0..rng.random_range(1..3 * n) {
                let (i, j) = (rng.random_range(0..n), rng.random_range(0..n));
                if i != j {
                    let w = rng.random_range(-0.3..1.0);
                    dense[(i, j)] -= w;
                    dense[(j, i)] -= w;
                    dense[(i, i)] += w;
                    dense[(j, j)] += w;
                }
            }
            for i in 0..n {
                dense[(i, i)] -= rng.random_range(0.0..1.5);
            }
            let h = rng.random_range(0.0..0.1);
            let mut triplets = Vec::new();
            for j in 0..n {
                for i in 0..n {
                    if i == j || dense[(i, j)] != 0.0 {
                        triplets.push(Triplet::new(i, j, dense[(i, j)]));
                    }
                }
            }
            let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets).unwrap();
            let diag_pos: Vec<usize> = (0..n)
                .map(|j| {
                    let rows = &a.row_idx()[a.col_ptr()[j]..a.col_ptr()[j + 1]];
                    a.col_ptr()[j] + rows.iter().position(|&i| i == j).unwrap()
                })
                .collect();
            let k = independent_negative_diagonal(a.as_ref(), &diag_pos, h);
            if k == 0 {
                continue;
            }
            twice += usize::from(k >= 2);
            let ev = crate::certify::spectrum::dense_eigenvalues(&dense);
            assert!(ev[k - 1] < -h, "{k} nodes, eigenvalues {ev:?}, h {h}");
        }
        assert!(twice > 10, "{twice}");
    }
}
