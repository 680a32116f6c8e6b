//! Verified factorisations and sparse helpers for certificate matrices (`paper-notes/certificates.md`).
//!
//! - [`ShiftedCholesky`]: the *verification* step `[D5]`. A sparse Cholesky factorisation of
//!   `A = S + sigma I` (symbolic analysis done once, numeric factorisation per shift) that, when it
//!   succeeds, proves `lambda_min(S) >= -sigma - eps`, with `eps` a rigorous floating-point margin
//!   computed from the computed factor (`[D6]`).
//! - [`lanczos_extreme`](crate::linalg::lanczos::lanczos_extreme): the *estimation* step `[D7]`. Lanczos with full reorthogonalisation on
//!   any symmetric operator (the sparse matrix itself, or `(S + sigma I)^-1` through the
//!   factorisation: shift-invert). Its numbers are estimates and never enter a bound by themselves.
//!
//! Nothing here forms a dense `3n x 3n` matrix.
//!
//! ```
//! use faer::sparse::{SparseColMat, Triplet};
//! use rotavg::linalg::{lanczos_extreme, sparse_matvec, Extreme, LanczosSettings, ShiftedCholesky};
//! // S = tridiag(-1, 2, -1) of size 10: lambda_min = 2 - 2 cos(pi / 11) (closed form).
//! let n = 10;
//! let mut t = Vec::new();
//! for i in 0..n {
//!     t.push(Triplet::new(i, i, 2.0));
//!     if i + 1 < n {
//!         t.push(Triplet::new(i, i + 1, -1.0));
//!         t.push(Triplet::new(i + 1, i, -1.0));
//!     }
//! }
//! let s = SparseColMat::try_new_from_triplets(n, n, &t).unwrap();
//! let exact = 2.0 - 2.0 * (std::f64::consts::PI / 11.0).cos();
//! // Estimation (never a bound by itself): Lanczos.
//! let est = lanczos_extreme(n, |x, y| sparse_matvec(s.as_ref(), x, y), Extreme::Smallest, 4.0, &LanczosSettings::default(), None);
//! assert!((est.value - exact).abs() < 1e-8);
//! // Verification: S - 0.9 lambda_min I factorises, which proves lambda_min(S) >= 0.9 lambda_min - margin.
//! let mut ch = ShiftedCholesky::new(s, 2)?;
//! let f = ch.factor(-0.9 * exact, 0.0).expect("positive definite");
//! assert!(f.verified_lower_bound() <= exact && f.verified_lower_bound() > 0.89 * exact);
//! // Shifting past lambda_min: the factorisation fails, and nothing is claimed.
//! drop(f);
//! assert!(ch.factor(-1.1 * exact, 0.0).is_none());
//! # Ok::<(), rotavg::Error>(())
//! ```

use super::compensated::{two_prod, two_sum};
use crate::error::{Error, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, LltRef, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
    supernodal::{SupernodalLltRef, SymbolicSupernodalCholesky},
};
use faer::sparse::linalg::{SupernodalThreshold, amd};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

/// Unit roundoff of `f64`: `u = 2^-53`.
pub const UNIT_ROUNDOFF: f64 = f64::EPSILON / 2.0;

/// Factor size (stored values) up to which the residual-based margin `[D6]` (2) is computed
/// (it holds the factor's columns and rows as `(index, value)` pairs: 32 more bytes per value).
pub const RESIDUAL_FACTOR_LIMIT: usize = 20_000_000;

/// Multiply-adds of the factorisation ([`factor_multiply_adds`]) up to which the
/// residual-based margin `[D6]` (2) is computed: its double-double products are as many as the
/// factorisation's, unblocked, about 5e-9 s each on the 2-core reference machine (a 2n x 2n
/// SO(2) certificate matrix of a 4000-camera expander: 7.3e9 multiply-adds, 36 s of residual
/// after a 0.37 s factorisation, not interruptible by the time limit). At this limit it takes
/// about 1 s; above it the a-priori margin (1) is used.
pub const RESIDUAL_MAX_MULTIPLY_ADDS: f64 = 2e8;

/// `gamma_k = k u / (1 - k u)` (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed.,
/// Lemma 3.1): the relative error bound of a sum or inner product of `k` terms. Returns
/// `+inf` when `k u >= 1/2` (the bound is then useless and no verification succeeds).
pub fn gamma(k: usize) -> f64 {
    let ku = k as f64 * UNIT_ROUNDOFF;
    if ku >= 0.5 {
        f64::INFINITY
    } else {
        ku / (1.0 - ku)
    }
}

/// The dense matrix of a sparse one (duplicate entries summed): for eigenvalues of small
/// matrices, as estimates or as the independent reference of tests.
pub(crate) fn to_dense(a: SparseColMatRef<'_, usize, f64>) -> nalgebra::DMatrix<f64> {
    let mut m = nalgebra::DMatrix::zeros(a.nrows(), a.ncols());
    let (cp, ri, v) = (a.col_ptr(), a.row_idx(), a.val());
    for c in 0..a.ncols() {
        for k in cp[c]..cp[c + 1] {
            m[(ri[k], c)] += v[k];
        }
    }
    m
}

/// `s` without the block row and column of node `g`, blocks of `size` rows and columns (the
/// grounded bounds `[D15]`, `paper-notes/gravity.md` `[G17]`). Errors: `s` not compressed and
/// square, or `g`'s block outside it.
pub fn without_block(
    s: &SparseColMat<usize, f64>,
    g: usize,
    size: usize,
) -> Result<SparseColMat<usize, f64>> {
    let (first, end) = (size * g, size * g + size);
    if s.symbolic().col_nnz().is_some() || s.nrows() < end || s.ncols() != s.nrows() {
        return Err(Error::Solver {
            message: "the grounded certificate matrix needs a compressed square S".into(),
        });
    }
    Ok(restricted(s, |k| k < first || k >= end))
}

/// `s` (symmetric, both triangles stored) without its rows and columns whose stored values are
/// all zero: an exactly zero row adds nothing to `x^T s x`, so a lower bound on what remains
/// bounds `x^T s x` by the other coordinates of `x` (the grounded bound `[D15]` "Coordinates
/// no edge sees").
pub fn without_zero_rows(s: SparseColMat<usize, f64>) -> SparseColMat<usize, f64> {
    let (cp, val) = (s.col_ptr(), s.val());
    let zero: Vec<bool> = (0..s.ncols())
        .map(|c| val[cp[c]..cp[c + 1]].iter().all(|v| *v == 0.0))
        .collect();
    if !zero.contains(&true) || s.nrows() != s.ncols() || s.symbolic().col_nnz().is_some() {
        return s;
    }
    restricted(&s, |k| !zero[k])
}

/// The rows and columns `k` of the compressed square `s` with `keep(k)`, in order (sorted rows
/// stay sorted).
fn restricted(
    s: &SparseColMat<usize, f64>,
    keep: impl Fn(usize) -> bool,
) -> SparseColMat<usize, f64> {
    let dim = s.ncols();
    let (cp, ri, val) = (s.col_ptr(), s.row_idx(), s.val());
    // each kept coordinate's new index
    let mut index = vec![usize::MAX; dim];
    let mut kept = 0;
    for k in (0..dim).filter(|&k| keep(k)) {
        index[k] = kept;
        kept += 1;
    }
    let mut col_ptr = Vec::with_capacity(kept + 1);
    let (mut rows, mut vals) = (Vec::with_capacity(val.len()), Vec::with_capacity(val.len()));
    col_ptr.push(0);
    for col in (0..dim).filter(|&c| keep(c)) {
        for p in cp[col]..cp[col + 1] {
            if keep(ri[p]) {
                rows.push(index[ri[p]]);
                vals.push(val[p]);
            }
        }
        col_ptr.push(rows.len());
    }
    let symbolic =
        faer::sparse::SymbolicSparseColMat::new_unsorted_checked(kept, kept, col_ptr, None, rows);
    SparseColMat::new(symbolic, vals)
}

/// `y = A x` for a sparse matrix with both triangles stored (column-major traversal).
pub fn sparse_matvec(a: SparseColMatRef<'_, usize, f64>, x: &[f64], y: &mut [f64]) {
    y.iter_mut().for_each(|v| *v = 0.0);
    let cp = a.col_ptr();
    let ri = a.row_idx();
    let val = a.val();
    for c in 0..a.ncols() {
        let xc = x[c];
        if xc == 0.0 {
            continue;
        }
        for k in cp[c]..cp[c + 1] {
            y[ri[k]] += val[k] * xc;
        }
    }
}

/// Stored values above which [`symmetric_matvec`] splits its rows over the available threads.
const PARALLEL_MATVEC_THRESHOLD: usize = 1_000_000;

/// `y = A x` for a **symmetric** sparse matrix with both triangles stored: column `c` is row
/// `c`, so each `y_c` is gathered from one column (no scattered writes) and the rows are split
/// over the available threads above 10^6 stored values. Each `y_c` sums the same products as
/// [`sparse_matvec`] (in another order), so the rounding bound `gamma(p) |A| |x|` (`p` stored
/// values in the row) is the same.
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use rotavg::linalg::{sparse_matvec, symmetric_matvec};
/// let t = [Triplet::new(0, 0, 2.0), Triplet::new(1, 0, -1.0), Triplet::new(0, 1, -1.0), Triplet::new(1, 1, 3.0)];
/// let a = SparseColMat::<usize, f64>::try_new_from_triplets(2, 2, &t).unwrap();
/// let (mut y, mut z) = (vec![0.0; 2], vec![0.0; 2]);
/// symmetric_matvec(a.as_ref(), &[1.0, 2.0], &mut y);
/// sparse_matvec(a.as_ref(), &[1.0, 2.0], &mut z);
/// assert_eq!(y, vec![0.0, 5.0]);
/// assert_eq!(y, z);
/// ```
pub fn symmetric_matvec(a: SparseColMatRef<'_, usize, f64>, x: &[f64], y: &mut [f64]) {
    let cp = a.col_ptr();
    let ri = a.row_idx();
    let val = a.val();
    let rows = |first: usize, out: &mut [f64]| {
        for (k, yc) in out.iter_mut().enumerate() {
            let c = first + k;
            let mut s = 0.0;
            for p in cp[c]..cp[c + 1] {
                s += val[p] * x[ri[p]];
            }
            *yc = s;
        }
    };
    let n = a.ncols().min(y.len());
    let parallel = val.len() >= PARALLEL_MATVEC_THRESHOLD;
    super::threads::in_chunks(&mut y[..n], parallel, rows);
}

/// Rayleigh quotient `rho = v^T A v` of a unit vector `v` and its residual `||A v - rho v||`
/// (an eigenvalue of the symmetric `A` lies within the residual of `rho`).
pub fn rayleigh_quotient(a: SparseColMatRef<'_, usize, f64>, v: &[f64]) -> (f64, f64) {
    let mut y = vec![0.0; v.len()];
    sparse_matvec(a, v, &mut y);
    let rq: f64 = y.iter().zip(v).map(|(a, b)| a * b).sum();
    let residual = y
        .iter()
        .zip(v)
        .map(|(a, b)| (a - rq * b).powi(2))
        .sum::<f64>()
        .sqrt();
    (rq, residual)
}

/// One column of a sparse Cholesky-type factor as stored: rows `first..` for the `leading`
/// values (a supernode's own rows, the diagonal first), then the rows `rows` for the `below`
/// values.
pub(crate) struct FactorColumn<'a> {
    /// The column.
    pub col: usize,
    first: usize,
    leading: &'a [f64],
    rows: &'a [usize],
    below: &'a [f64],
}

impl FactorColumn<'_> {
    /// `(row, value)` of every stored entry, the diagonal among them.
    #[inline]
    pub(crate) fn entries(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        (self.first..)
            .zip(self.leading.iter().copied())
            .chain(self.rows.iter().copied().zip(self.below.iter().copied()))
    }
}

/// Calls `f` with every column of a sparse Cholesky-type factor (lower triangle, diagonal
/// included) computed with `symbolic`, in either layout, columns ascending. The `LL^T` and
/// `LDL^T` factors share faer's storage layout (for `LDL^T` the diagonal holds `D`, and `L` has
/// an implicit unit diagonal), so this serves both. A supernode's values are stored by columns:
/// each column is two slices (no bounds check per entry; 2e7 entries per pass in a region's
/// factor at 10^4 cameras), and a visitor may read a column twice while it is in cache.
pub(crate) fn for_each_factor_column(
    symbolic: &SymbolicCholesky<usize>,
    values: &[f64],
    mut f: impl FnMut(&FactorColumn<'_>),
) {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(sym) => {
            let (cp, ri) = (sym.col_ptr(), sym.row_idx());
            for c in 0..symbolic.nrows() {
                let range = cp[c]..cp[c + 1];
                f(&FactorColumn {
                    col: c,
                    first: 0,
                    leading: &[],
                    rows: &ri[range.clone()],
                    below: &values[range],
                });
            }
        }
        SymbolicCholeskyRaw::Supernodal(sym) => {
            let llt = SupernodalLltRef::<usize, f64>::new(sym, values);
            let mut copy = Vec::new();
            for s in 0..sym.n_supernodes() {
                let node = llt.supernode(s);
                let (start, pattern, m) = (node.start(), node.pattern(), node.val());
                let ncols = m.ncols();
                for jc in 0..ncols {
                    let col: &[f64] = match m.col(jc).try_as_col_major() {
                        Some(col) => col.as_slice(),
                        None => {
                            copy.clear();
                            copy.extend(m.col(jc).iter().copied());
                            &copy
                        }
                    };
                    f(&FactorColumn {
                        col: start + jc,
                        first: start + jc,
                        leading: &col[jc..ncols],
                        rows: pattern,
                        below: &col[ncols..],
                    });
                }
            }
        }
    }
}

/// Calls `f(row, col, value)` for every stored entry of a sparse Cholesky-type factor
/// ([`for_each_factor_column`]'s columns, entry by entry).
pub(crate) fn for_each_factor_entry(
    symbolic: &SymbolicCholesky<usize>,
    values: &[f64],
    mut f: impl FnMut(usize, usize, f64),
) {
    for_each_factor_column(symbolic, values, |column| {
        column.entries().for_each(|(r, v)| f(r, column.col, v));
    });
}

/// Maximum absolute row sum `||A||_inf` (for a symmetric matrix an upper bound on `||A||_2`).
pub fn inf_norm(a: SparseColMatRef<'_, usize, f64>) -> f64 {
    abs_row_sums(a).into_iter().fold(0.0, f64::max)
}

/// The absolute row sums `sum_j |A_ij|` of a sparse matrix (its stored entries).
fn abs_row_sums(a: SparseColMatRef<'_, usize, f64>) -> Vec<f64> {
    let mut rows = vec![0.0f64; a.nrows()];
    let cp = a.col_ptr();
    let ri = a.row_idx();
    let val = a.val();
    for c in 0..a.ncols() {
        for k in cp[c]..cp[c + 1] {
            rows[ri[k]] += val[k].abs();
        }
    }
    rows
}

/// Per row of a sparse matrix (both triangles stored): stored entries, diagonal, and the sum of
/// the off-diagonal magnitudes.
fn gershgorin_rows(a: SparseColMatRef<'_, usize, f64>) -> (Vec<usize>, Vec<f64>, Vec<f64>) {
    let n = a.nrows();
    let mut diag = vec![0.0f64; n];
    let mut off = vec![0.0f64; n];
    let mut count = vec![0usize; n];
    let cp = a.col_ptr();
    let ri = a.row_idx();
    let val = a.val();
    for c in 0..a.ncols() {
        for k in cp[c]..cp[c + 1] {
            let r = ri[k];
            count[r] += 1;
            if r == c {
                diag[r] += val[k];
            } else {
                off[r] += val[k].abs();
            }
        }
    }
    (count, diag, off)
}

/// A Gershgorin lower bound on `lambda_min(A)`: `min_r (A_rr - sum_{c != r} |A_rc|)`, minus the
/// rounding error of evaluating it (`[D8]`). Rigorous for the floating-point matrix `A`.
pub fn gershgorin_lower_bound(a: SparseColMatRef<'_, usize, f64>) -> f64 {
    let (count, diag, off) = gershgorin_rows(a);
    let mut lb = f64::INFINITY;
    for r in 0..diag.len() {
        // the evaluated difference has error <= gamma(count+1) (|diag| + off)
        let err = gamma(count[r] + 2) * (diag[r].abs() + off[r]);
        lb = lb.min(diag[r] - off[r] - err);
    }
    if diag.is_empty() { 0.0 } else { lb }
}

/// A Gershgorin upper bound on `lambda_max(A)` with the rounding of its evaluation, and the
/// largest number of stored entries in a row (for the rounding bound `gamma(p)` of a product).
pub(crate) fn gershgorin_upper_bound(a: SparseColMatRef<'_, usize, f64>) -> (f64, usize) {
    let (count, diag, off) = gershgorin_rows(a);
    let upper = (0..diag.len())
        .map(|r| diag[r] + off[r] + gamma(count[r] + 2) * (diag[r].abs() + off[r]))
        .fold(0.0f64, f64::max);
    (upper, count.into_iter().max().unwrap_or(0))
}

/// The verification engine `[D5]`: symbolic Cholesky analysis of a symmetric sparse matrix `S`
/// (AMD ordering, done once), then numeric factorisations of `S + sigma I` for trial shifts.
pub struct ShiftedCholesky {
    /// `S` itself (both triangles stored; only the lower one is read by the factorisation).
    /// [`ShiftedCholesky::factor`] adds the shift to its diagonal in place and restores the
    /// saved diagonal exactly afterwards (no second copy of `S`: 16 bytes per stored entry).
    s: SparseColMat<usize, f64>,
    /// Value index of each diagonal entry of `S` (every diagonal entry must be stored).
    diag_pos: Vec<usize>,
    symbolic: SymbolicCholesky<usize>,
    /// Bound on the number of rounded operations that produced each entry of `S` (for the
    /// forming error `[D6]`, part (b)).
    entry_terms: usize,
}

/// A successful factorisation of `S + sigma I` with its rigorous margin.
pub struct PositiveFactor<'a> {
    owner: &'a ShiftedCholesky,
    values: Vec<f64>,
    /// The shift `sigma` that was factorised.
    pub shift: f64,
    /// Rigorous margin: `lambda_min(S_exact) >= -shift - margin` `[D6]`.
    pub margin: f64,
    /// Rigorous margin by rows `[D6]` (3): `S_exact >= -shift I - D` for a nonnegative
    /// diagonal `D` with `tr(D) <= margin_sum` (and every `D_rr <= margin`). A bound
    /// `sum tr(Lambda_i) - 3n shift - margin_sum` then holds where one row (a hub) would
    /// make `3n margin` large.
    pub margin_sum: f64,
    /// Smallest diagonal entry of the computed factor (squared: the smallest pivot).
    pub min_pivot: f64,
}

/// The symbolic Cholesky analysis of a symmetric `pattern` (both triangles stored) in the
/// approximate-minimum-degree ordering, refused *before* its column counts when AMD predicts a
/// factor of more than `max_values` stored values: `Ok(Err(predicted))` then.
///
/// The symbolic analysis itself costs time proportional to the factor's size (its column
/// counts visit every entry of `L`): on a random graph of 10^5 nodes, 40 s for a factor that
/// could never be stored. AMD's own count (`n + ` its divisions, the entries of `L` below the
/// diagonal for this ordering) is near-linear to obtain and decides first. The prediction only
/// decides whether to try; nothing is claimed from it.
pub fn symbolic_cholesky_within(
    pattern: SymbolicSparseColMatRef<'_, usize>,
    max_values: usize,
) -> Result<std::result::Result<SymbolicCholesky<usize>, usize>> {
    Ok(symbolic_cholesky_counted_within(pattern, max_values)?.map(|(s, _)| s))
}

/// [`symbolic_cholesky_within`] with the ordering's own count of the factor's values (below
/// the diagonal and on it; no relaxed supernodes' explicit zeros), the currency in which
/// factors of different graphs compare.
pub(crate) fn symbolic_cholesky_counted_within(
    pattern: SymbolicSparseColMatRef<'_, usize>,
    max_values: usize,
) -> Result<std::result::Result<(SymbolicCholesky<usize>, usize), usize>> {
    let n = pattern.nrows();
    let failed = |what: &str, e: faer::sparse::FaerError| Error::Solver {
        message: format!("{what} failed: {e:?}"),
    };
    let blocks = quotient_of_blocks(pattern);
    let params = CholeskySymbolicParams {
        supernodal_flop_ratio_threshold: match blocks {
            Some(_) => BLOCK_SUPERNODAL_THRESHOLD,
            None => SupernodalThreshold::AUTO,
        },
        ..Default::default()
    };
    let (perm, perm_inv, predicted) = match blocks {
        Some(quotient) => {
            let (p, pinv, below) = amd_order(quotient.symbolic())?;
            let nb = quotient.nrows();
            // each block of the quotient's `L` is 9 values, each diagonal block 6
            let predicted = below.saturating_mul(9).saturating_add(6 * nb);
            let expand = |q: &[usize]| {
                q.iter()
                    .flat_map(|&b| (0..BLOCK).map(move |r| BLOCK * b + r))
                    .collect::<Vec<usize>>()
            };
            (expand(&p), expand(&pinv), predicted)
        }
        None => {
            let (p, pinv, below) = amd_order(pattern)?;
            (p, pinv, below.saturating_add(n))
        }
    };
    if predicted > max_values {
        return Ok(Err(predicted));
    }
    let ordering = PermRef::new_checked(&perm, &perm_inv, n);
    factorize_symbolic_cholesky(
        pattern,
        Side::Lower,
        SymmetricOrdering::Custom(ordering),
        params,
    )
    .map(|s| Ok((s, predicted)))
    .map_err(|e| failed("symbolic Cholesky analysis", e))
}

/// The block size whose structure [`symbolic_cholesky_within`] orders on the quotient (the
/// `3 x 3` blocks of rotations).
const BLOCK: usize = 3;

/// Patterns of `3 x 3` blocks take faer's supernodal factorisation from a quarter of its
/// default flop ratio (supernodal when the factorisation's flops exceed 10 times `L`'s values,
/// not 40): each block column is a supernode of 3 columns, which the supernodal kernels
/// update as a dense panel where the simplicial one recomputes each column's row pattern
/// (`ereach`) and updates it scalar by scalar. Measured 2026-12-07 (Intel Xeon, 2 cores): the
/// anisotropic L1 solve of the generated seed-1 10^4-image COLMAP scene with information, 651
/// IRLS iterations of a `3 x 10^4` block system, 33.1-33.8 s -> 21.7-22.9 s, the same
/// iterates; its factors' flop ratio is between 20 and 40 (supernodal from the thresholds 0.5
/// down). Certificates of the shared pose graphs with their full information within the runs'
/// spread (mrob sphere 0.025 -> 0.009 s).
const BLOCK_SUPERNODAL_THRESHOLD: SupernodalThreshold = SupernodalThreshold(0.25);

/// The approximate-minimum-degree ordering of `pattern` and its count of `L`'s entries below
/// the diagonal (`usize::MAX` when not finite).
fn amd_order(
    pattern: SymbolicSparseColMatRef<'_, usize>,
) -> Result<(Vec<usize>, Vec<usize>, usize)> {
    let n = pattern.nrows();
    let mut perm = vec![0usize; n];
    let mut perm_inv = vec![0usize; n];
    let mut mem = MemBuffer::try_new(amd::order_maybe_unsorted_scratch::<usize>(
        n,
        pattern.compute_nnz(),
    ))
    .map_err(|_| Error::Solver {
        message: "out of memory for the ordering of a sparse factorisation".into(),
    })?;
    let flops = amd::order_maybe_unsorted(
        &mut perm,
        &mut perm_inv,
        pattern,
        amd::Control::default(),
        MemStack::new(&mut mem),
    )
    .map_err(|e| Error::Solver {
        message: format!("minimum-degree ordering failed: {e:?}"),
    })?;
    let below = if flops.n_div.is_finite() && flops.n_div >= 0.0 {
        flops.n_div as usize
    } else {
        usize::MAX
    };
    Ok((perm, perm_inv, below))
}

/// When `pattern` (both triangles or one, no repeated entry) is made of whole `3 x 3` blocks
/// off its diagonal blocks, the pattern of its blocks (with every diagonal block): the
/// minimum-degree ordering of that quotient, each block's three columns kept together, orders
/// the blocks' pattern at a ninth of the work (2-D SLAM graphs of 1000-3500 poses spent a fifth
/// of their certificate ordering `3n` columns). `None` for any other pattern (an explicit zero
/// dropped from a block, a size not a multiple of 3).
fn quotient_of_blocks(
    pattern: SymbolicSparseColMatRef<'_, usize>,
) -> Option<SparseColMat<usize, f64>> {
    let n = pattern.nrows();
    if n == 0 || n % BLOCK != 0 || pattern.ncols() != n {
        return None;
    }
    let nb = n / BLOCK;
    let mut count = vec![0usize; nb];
    let mut triplets = Vec::with_capacity(pattern.compute_nnz() / (BLOCK * BLOCK) + nb);
    let off = |j: usize, r: usize| {
        pattern
            .row_idx_of_col_raw(BLOCK * j + r)
            .iter()
            .map(|&i| i / BLOCK)
            .filter(move |&b| b != j)
    };
    for j in 0..nb {
        triplets.push(faer::sparse::Triplet::new(j, j, 1.0));
        for r in 0..BLOCK {
            for b in off(j, r) {
                count[b] += 1;
            }
        }
        // every block seen 3 times in each of the 3 columns: whole blocks
        for b in off(j, 0) {
            match count[b] {
                0 => {}
                c if c == BLOCK * BLOCK => {
                    triplets.push(faer::sparse::Triplet::new(b, j, 1.0));
                    count[b] = 0;
                }
                _ => return None,
            }
        }
        // a block of the other two columns that the first does not hold
        if (1..BLOCK).any(|r| off(j, r).any(|b| count[b] != 0)) {
            return None;
        }
    }
    SparseColMat::try_new_from_triplets(nb, nb, &triplets).ok()
}

/// The shape of every supernode of a supernodal factor, in order: its number of columns `k`
/// and of rows below its diagonal block `r` (its front has `k + r` rows).
fn supernode_shapes(
    s: &SymbolicSupernodalCholesky<usize>,
) -> impl Iterator<Item = (usize, usize)> + '_ {
    let (begin, end, rows) = (
        s.supernode_begin(),
        s.supernode_end(),
        s.col_ptr_for_row_idx(),
    );
    (0..s.n_supernodes()).map(move |j| (end[j] - begin[j], rows[j + 1] - rows[j]))
}

/// Bytes of numeric scratch an `LDL^T` factorisation with this symbolic structure allocates
/// besides the factor (at the parallelism its size gets, [`super::factor_parallelism`]).
pub(crate) fn ldlt_scratch_bytes(symbolic: &SymbolicCholesky<usize>) -> usize {
    symbolic
        .factorize_numeric_ldlt_scratch::<f64>(
            super::factor_parallelism(symbolic.len_val()),
            Default::default(),
        )
        .size_bytes()
}

/// The multiply-adds of a numeric factorisation with this symbolic structure: per supernode of
/// `k` columns and `r` rows below its diagonal block, `k^3 / 6` (its dense `LDL^T`),
/// `r k^2 / 2` (the triangular solve below it) and `r^2 k / 2` (its update of the rest); per
/// column of a simplicial factor with `c` entries below the diagonal, `c^2 / 2`. Exact for the
/// structure faer factorises (relaxed supernodes' explicit zeros included); the time model
/// ([`crate::certify::Budget::predicted_factor_seconds`]) divides it by a measured rate.
pub fn factor_multiply_adds(symbolic: &SymbolicCholesky<usize>) -> f64 {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Supernodal(s) => supernode_shapes(s)
            .map(|(k, r)| {
                let (k, r) = (k as f64, r as f64);
                k * k * k / 6.0 + r * k * k / 2.0 + r * r * k / 2.0
            })
            .sum(),
        SymbolicCholeskyRaw::Simplicial(s) => {
            let cp = s.col_ptr();
            (0..s.ncols())
                .map(|j| {
                    let c = (cp[j + 1] - cp[j]).saturating_sub(1) as f64;
                    c * c / 2.0
                })
                .sum()
        }
    }
}

/// The maximal cliques of the chordal extension that the factor's elimination order makes, by
/// size (nodes): the fronts of the supernodes (columns plus the rows below them); for a
/// simplicial factor, the columns whose clique `{j} + rows(L_j)` is not inside a child's (a
/// child `c` of `j` contains it exactly when its column count is `j`'s plus one).
pub fn front_sizes(symbolic: &SymbolicCholesky<usize>) -> Vec<usize> {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Supernodal(s) => supernode_shapes(s).map(|(k, r)| k + r).collect(),
        SymbolicCholeskyRaw::Simplicial(s) => {
            let (cp, ri) = (s.col_ptr(), s.row_idx());
            let n = s.ncols();
            // the column's clique: the column and its rows below the diagonal
            let clique = |j: usize| (cp[j]..cp[j + 1]).filter(|&p| ri[p] != j).count() + 1;
            let mut maximal = vec![true; n];
            for c in 0..n {
                // the parent: the first row below the diagonal
                let parent = (cp[c]..cp[c + 1]).map(|p| ri[p]).filter(|&r| r > c).min();
                if let Some(j) = parent
                    && clique(c) == clique(j) + 1
                {
                    maximal[j] = false;
                }
            }
            (0..n).filter(|&j| maximal[j]).map(clique).collect()
        }
    }
}

impl ShiftedCholesky {
    /// Analyse `s` (square, symmetric, both triangles stored, every diagonal entry stored).
    /// `entry_terms` bounds the number of floating-point operations (terms summed) that formed any
    /// entry of `s` from the exact data, e.g. the maximum node degree plus 3 for `Q - blkdiag(L)`.
    pub fn new(s: SparseColMat<usize, f64>, entry_terms: usize) -> Result<Self> {
        match Self::new_within(s, entry_terms, usize::MAX)? {
            Ok(ch) => Ok(ch),
            Err(predicted) => Err(Error::Solver {
                message: format!("factor of {predicted} values cannot be analysed"),
            }),
        }
    }

    /// [`ShiftedCholesky::new`], refused before the symbolic analysis when the factor is
    /// predicted to hold more than `max_values` values: `Ok(Err(predicted))`
    /// ([`symbolic_cholesky_within`]).
    pub fn new_within(
        s: SparseColMat<usize, f64>,
        entry_terms: usize,
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        let n = s.nrows();
        if s.ncols() != n {
            return Err(Error::Degenerate {
                reason: "certificate matrix is not square".into(),
            });
        }
        let cp = s.symbolic().col_ptr().to_vec();
        let ri = s.symbolic().row_idx().to_vec();
        if s.symbolic().col_nnz().is_some() {
            return Err(Error::Degenerate {
                reason: "certificate matrix must be in compressed (non-padded) form".into(),
            });
        }
        let mut diag_pos = Vec::with_capacity(n);
        for c in 0..n {
            match (cp[c]..cp[c + 1]).find(|&k| ri[k] == c) {
                Some(k) => diag_pos.push(k),
                None => {
                    return Err(Error::Degenerate {
                        reason: format!("certificate matrix has no stored diagonal entry {c}"),
                    });
                }
            }
        }
        let symbolic = match symbolic_cholesky_within(s.symbolic(), max_values)? {
            Ok(symbolic) => symbolic,
            Err(predicted) => return Ok(Err(predicted)),
        };
        Ok(Ok(ShiftedCholesky {
            s,
            diag_pos,
            symbolic,
            entry_terms,
        }))
    }

    /// The matrix `S`.
    pub fn matrix(&self) -> SparseColMatRef<'_, usize, f64> {
        self.s.as_ref()
    }

    /// The stored values of `S`, to be overwritten by those of another matrix of the same
    /// pattern (the analysis is re-used; the forming bound `entry_terms` is the caller's).
    pub fn values_mut(&mut self) -> &mut [f64] {
        self.s.val_mut()
    }

    /// Dimension of `S`.
    pub fn dim(&self) -> usize {
        self.s.nrows()
    }

    /// A shift-invert Lanczos *estimate* of `lambda_min(S)` (`[D7]`: the largest eigenvalue of
    /// `S^-1` through the unshifted factor; 30 iterations at most, relative tolerance `1e-3`,
    /// `settings`' seed) and the iterations it took. `None` when a pivot is not positive or the
    /// estimate is not positive and finite. Never a bound: it only picks shifts to verify.
    pub fn shift_invert_estimate(
        &mut self,
        settings: &super::LanczosSettings,
    ) -> Option<(f64, usize)> {
        let dim = self.dim();
        let f = self.factor(0.0, f64::INFINITY)?;
        let settings = super::LanczosSettings {
            max_iterations: 30,
            tolerance: 1e-3,
            ..*settings
        };
        let r = super::lanczos_extreme(
            dim,
            |x, y| {
                y.copy_from_slice(x);
                f.solve_in_place(y);
            },
            super::Extreme::Largest,
            0.0,
            &settings,
            None,
        );
        let estimate = 1.0 / r.value;
        (estimate.is_finite() && estimate > 0.0).then_some((estimate, r.iterations))
    }

    /// Number of stored values of the Cholesky factor (memory/fill indicator).
    pub fn factor_len(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Multiply-adds of one numeric factorisation ([`factor_multiply_adds`]).
    pub fn multiply_adds(&self) -> f64 {
        factor_multiply_adds(&self.symbolic)
    }

    /// Bytes of the numeric factorisation's work space (faer's scratch for the supernodal
    /// fronts; about half a byte per factor value on grid and chain graphs).
    pub fn scratch_bytes(&self) -> usize {
        self.symbolic
            .factorize_numeric_llt_scratch::<f64>(self.parallelism(), Default::default())
            .size_bytes()
    }

    /// Large supernodal factorisations use all threads (the margin `[D6]` holds for any
    /// summation order); small ones stay sequential and deterministic.
    fn parallelism(&self) -> Par {
        super::factor_parallelism(self.symbolic.len_val())
    }

    /// Factorise `S + shift I`. `None` when a pivot is not positive or not finite (no conclusion:
    /// the matrix is then *probably* not positive definite), or when the computed margin is not
    /// finite. `Some(factor)` proves `lambda_min(S) >= -shift - factor.margin` `[D6]`.
    ///
    /// `margin_target`: when the cheap a-priori margin `[D6]` (1) is already below it, the more
    /// expensive residual-based margin `[D6]` (2) is not computed (pass 0 to always compute it
    /// when the factor is small enough).
    pub fn factor(&mut self, shift: f64, margin_target: f64) -> Option<PositiveFactor<'_>> {
        if !shift.is_finite() {
            return None;
        }
        // S + shift I in place; the diagonal is restored exactly below, whatever happens
        let diagonal: Vec<f64> = {
            let val = self.s.val_mut();
            self.diag_pos
                .iter()
                .map(|&k| {
                    let d = val[k];
                    val[k] = d + shift;
                    d
                })
                .collect()
        };
        let result = self.factor_shifted(margin_target);
        let val = self.s.val_mut();
        for (&k, &d) in self.diag_pos.iter().zip(&diagonal) {
            val[k] = d;
        }
        let (values, margins, min_pivot) = result?;
        Some(PositiveFactor {
            owner: self,
            values,
            shift,
            margin: margins.max,
            margin_sum: margins.sum,
            min_pivot,
        })
    }

    /// The numeric factorisation of the (already shifted) matrix held in `self.s`, with the
    /// margin `[D6]`: `(factor values, margin, smallest pivot)`, or `None` as in
    /// [`ShiftedCholesky::factor`].
    fn factor_shifted(&self, margin_target: f64) -> Option<(Vec<f64>, Margins, f64)> {
        let mut values = vec![0.0f64; self.symbolic.len_val()];
        let par = self.parallelism();
        let req = self
            .symbolic
            .factorize_numeric_llt_scratch::<f64>(par, Default::default());
        let mut mem = MemBuffer::try_new(req).ok()?;
        let ok = self
            .symbolic
            .factorize_numeric_llt::<f64>(
                &mut values,
                self.s.as_ref(),
                Side::Lower,
                LltRegularization::default(),
                par,
                MemStack::new(&mut mem),
                Default::default(),
            )
            // Soundness: `LltRegularization::default()` has delta = epsilon = 0, and faer only
            // regularises pivots when both are > 0 (faer 0.24, llt/factor.rs), so a success is a
            // plain Cholesky factor of S + shift I; a non-positive pivot is an error.
            .is_ok();
        if !ok || !values.iter().all(|v| v.is_finite()) {
            return None;
        }
        let (backward, min_pivot) = self.backward_error_bound(&values, margin_target / 2.0);
        // (b) forming error: every entry of S + shift I is the rounded result of at most
        // entry_terms + 1 operations on exact data, so |E_1| <= gamma(entry_terms + 1) |S + shift I|
        // entrywise and ||E_1||_2 <= gamma(...) || |S + shift I| ||_inf; by rows (3), the row
        // sums of that symmetric nonnegative majorant.
        let rows = abs_row_sums(self.s.as_ref());
        let g = gamma(self.entry_terms + 2);
        let forming = Margins {
            max: g * rows.iter().copied().fold(0.0, f64::max),
            sum: g * rows.iter().sum::<f64>(),
        };
        // Factor 2 covers the rounding in evaluating these bounds themselves (they are sums of
        // nonnegative terms of the same order, each computed with relative error << 1).
        let margins = Margins {
            max: 2.0 * (backward.max + forming.max),
            sum: 2.0 * (backward.sum + forming.sum),
        };
        if !(margins.max.is_finite() && margins.sum.is_finite()) {
            return None;
        }
        Some((values, margins, min_pivot))
    }

    /// `[D6]` part (a). Two rigorous bounds on `||A - P^T L L^T P||_2` (`L` the computed
    /// factor, exact numbers), the smaller is used:
    /// 1. Higham Thm 10.3: a Cholesky factorisation that runs to completion gives
    ///    `L L^T = A + dA`, `|dA| <= gamma(k+1) |L| |L|^T`, `k` = the largest number of nonzero
    ///    terms in an inner product, at most the largest row count of `L`; then
    ///    `||dA||_2 <= gamma(k+1) || |L| |L|^T ||_inf`, the row sums being `sum_m |L_im| c_m`
    ///    with `c_m = sum_j |L_jm|`.
    /// 2. (factors up to `RESIDUAL_FACTOR_LIMIT` values and `RESIDUAL_MAX_MULTIPLY_ADDS`
    ///    multiply-adds) the residual `R = A - L L^T` evaluated
    ///    on the filled pattern in double-double arithmetic (error-free products and sums),
    ///    `||R||_2 <= ||R||_inf`, plus the evaluation error `2 gamma(k+2)^2 || |L||L|^T ||_inf`
    ///    (Ogita-Rump-Oishi, Dot2), inflated by 1%.
    ///
    /// Both are entrywise bounds by symmetric nonnegative matrices, so their row sums also
    /// bound `dA` by rows (`[D6]` (3): `x^T dA x <= sum_r b_r x_r^2` for row sums `b_r`): the
    /// smaller of the two row sums, row by row, gives [`Margins::sum`].
    ///
    /// Returns (bounds, smallest pivot).
    fn backward_error_bound(&self, values: &[f64], target: f64) -> (Margins, f64) {
        let l = self.factor_norms(values);
        let g1 = gamma(l.k + 1);
        let llt_norm = l.rowsum.iter().copied().fold(0.0, f64::max);
        let higham = Margins {
            max: g1 * llt_norm,
            sum: g1 * l.rowsum.iter().sum::<f64>(),
        };
        if self.symbolic.len_val() > RESIDUAL_FACTOR_LIMIT
            || self.multiply_adds() > RESIDUAL_MAX_MULTIPLY_ADDS
            || higham.max <= target
        {
            return (higham, l.min_pivot);
        }
        let (cols, rows) = self.factor_lists(values);
        // Dekker's TwoProduct is exact without overflow (a non-finite sum: Higham's bound
        // alone) and within 1e-322 per product under underflow (1e-300 per row covers 1e20 of
        // them)
        let Some(abs_rowsum) = self
            .residual_row_sums(&cols, &rows)
            .filter(|sums| sums.iter().all(|v| v.is_finite()))
        else {
            return (higham, l.min_pivot);
        };
        let g = gamma(l.k + 2);
        let by_row = |r: usize| 1.01 * abs_rowsum[r] + 1e-300 + 2.0 * g * g * l.rowsum[r];
        let residual_max =
            1.01 * abs_rowsum.iter().copied().fold(0.0, f64::max) + 1e-300 + 2.0 * g * g * llt_norm;
        let sum = (0..abs_rowsum.len())
            .map(|r| by_row(r).min(g1 * l.rowsum[r]))
            .sum::<f64>();
        let margins = Margins {
            max: higham.max.min(residual_max),
            sum: higham.sum.min(sum),
        };
        (margins, l.min_pivot)
    }

    /// What Higham's bound needs of the factor `L` (`values`): `|| |L| |L|^T ||_inf`, the largest
    /// row count `k`, and the smallest pivot `min L_ii^2`.
    fn factor_norms(&self, values: &[f64]) -> FactorNorms {
        let n = self.dim();
        let mut colsum = vec![0.0f64; n];
        let mut rowcount = vec![0usize; n];
        let mut min_pivot = f64::INFINITY;
        let mut rowsum = vec![0.0f64; n];
        // one pass: a column's sum is complete before its entries are added to their rows
        for_each_factor_column(&self.symbolic, values, |column| {
            let c = column.col;
            column.entries().for_each(|(r, v)| {
                colsum[c] += v.abs();
                rowcount[r] += 1;
                if r == c {
                    min_pivot = min_pivot.min(v * v);
                }
            });
            column
                .entries()
                .for_each(|(r, v)| rowsum[r] += v.abs() * colsum[c]);
        });
        FactorNorms {
            k: rowcount.iter().copied().max().unwrap_or(0),
            rowsum,
            min_pivot,
        }
    }

    /// The nonzero entries of the factor `L` (`values`) by columns and by rows (of `L^T`), in
    /// permuted coordinates; rows ascending within each column.
    #[allow(clippy::type_complexity)]
    fn factor_lists(&self, values: &[f64]) -> (Vec<Vec<(usize, f64)>>, Vec<Vec<(usize, f64)>>) {
        let n = self.dim();
        let mut cols: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
        let mut rows: Vec<Vec<(usize, f64)>> = vec![Vec::new(); n];
        for_each_factor_entry(&self.symbolic, values, |r, c, v| {
            if v != 0.0 {
                cols[c].push((r, v));
                rows[r].push((c, v));
            }
        });
        // rows ascending within each column (the partition_point of the residual relies on it)
        for col in cols.iter_mut() {
            if !col.is_sorted_by_key(|e| e.0) {
                col.sort_unstable_by_key(|e| e.0);
            }
        }
        (cols, rows)
    }

    /// The row sums of `|A - L L^T|` (`A` permuted as the factor), each entry evaluated on the
    /// filled pattern in double-double arithmetic from the factor's columns `cols` and rows
    /// `rows`; `None` when an entry of `A` lies outside the factor's pattern (cannot happen for
    /// a correct symbolic analysis).
    fn residual_row_sums(
        &self,
        cols: &[Vec<(usize, f64)>],
        rows: &[Vec<(usize, f64)>],
    ) -> Option<Vec<f64>> {
        let n = self.dim();
        let (fwd, inv): (Vec<usize>, Vec<usize>) = match self.symbolic.perm() {
            Some(p) => {
                let (f, i) = p.arrays();
                (f.to_vec(), i.to_vec())
            }
            None => ((0..n).collect(), (0..n).collect()),
        };
        let a = self.s.as_ref();
        let (acp, ari, aval) = (a.col_ptr(), a.row_idx(), a.val());
        let mut hi = vec![0.0f64; n];
        let mut lo = vec![0.0f64; n];
        let mut touched = vec![false; n];
        let mut list: Vec<usize> = Vec::new();
        let mut abs_rowsum = vec![0.0f64; n];
        for j in 0..n {
            // -(L L^T)_{ij} for i >= j, in double-double
            for &(m, ljm) in &rows[j] {
                let col = &cols[m];
                // rows within a column are ascending (ensured by factor_lists)
                let first = col.partition_point(|&(i, _)| i < j);
                for &(i, lim) in &col[first..] {
                    // exact: -lim*ljm = p + pe (inline TwoProduct, not the software `fma`)
                    let (p, pe) = two_prod(-lim, ljm);
                    let (sh, se) = two_sum(hi[i], p);
                    hi[i] = sh;
                    lo[i] += se + pe;
                    if !touched[i] {
                        touched[i] = true;
                        list.push(i);
                    }
                }
            }
            // + A_{ij} (permuted: column j of P A P^T is column fwd[j] of A)
            let c = fwd[j];
            for kk in acp[c]..acp[c + 1] {
                let i = inv[ari[kk]];
                if i < j {
                    continue;
                }
                if !touched[i] {
                    return None;
                }
                let (sh, se) = two_sum(hi[i], aval[kk]);
                hi[i] = sh;
                lo[i] += se;
            }
            for &i in &list {
                let r = (hi[i] + lo[i]).abs();
                abs_rowsum[i] += r;
                if i != j {
                    abs_rowsum[j] += r;
                }
                hi[i] = 0.0;
                lo[i] = 0.0;
                touched[i] = false;
            }
            list.clear();
        }
        Some(abs_rowsum)
    }
}

/// What [`ShiftedCholesky::backward_error_bound`] reads off a factor `L`: the largest row count
/// `k`, `|| |L| |L|^T ||_inf` and the smallest pivot `min L_ii^2`.
struct FactorNorms {
    k: usize,
    /// The row sums of `|L| |L|^T`.
    rowsum: Vec<f64>,
    min_pivot: f64,
}

/// A floating-point margin `[D6]`: the largest per-row bound (a bound on the spectral norm)
/// and the sum of the per-row bounds (a bound on the trace of a diagonal majorant, (3)).
#[derive(Debug, Clone, Copy)]
struct Margins {
    max: f64,
    sum: f64,
}

impl PositiveFactor<'_> {
    /// Solve `(S + shift I) x = b` in place.
    pub fn solve_in_place(&self, x: &mut [f64]) {
        let sym = &self.owner.symbolic;
        let n = x.len();
        let par = Par::Seq;
        let req = sym.solve_in_place_scratch::<f64>(1, par);
        let mut mem = MemBuffer::new(req);
        let llt = LltRef::<usize, f64>::new(sym, &self.values);
        llt.solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, 1),
            par,
            MemStack::new(&mut mem),
        );
    }

    /// The verified lower bound on `lambda_min(S)`: `-shift - margin`.
    pub fn verified_lower_bound(&self) -> f64 {
        -self.shift - self.margin
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::linalg::lanczos::{Extreme, LanczosSettings, lanczos_extreme};
    use faer::sparse::Triplet;

    /// Exactly zero rows and columns are left out, the rest kept in order.
    #[test]
    fn zero_rows_are_left_out() {
        let t = [
            (0, 0, 2.0),
            (0, 2, -1.0),
            (2, 0, -1.0),
            (2, 2, 3.0),
            (1, 1, 0.0),
        ];
        let t: Vec<_> = t.iter().map(|&(r, c, v)| Triplet::new(r, c, v)).collect();
        let s = SparseColMat::try_new_from_triplets(3, 3, &t).unwrap();
        let d = to_dense(without_zero_rows(s).as_ref());
        assert_eq!((d.nrows(), d.ncols()), (2, 2));
        assert_eq!(
            (d[(0, 0)], d[(0, 1)], d[(1, 0)], d[(1, 1)]),
            (2.0, -1.0, -1.0, 3.0)
        );
        let full = SparseColMat::try_new_from_triplets(1, 1, &[Triplet::new(0, 0, 1.0)]).unwrap();
        assert_eq!(without_zero_rows(full).nrows(), 1);
    }

    /// Path-graph Laplacian (tridiagonal 2,-1) of size n plus shift c: eigenvalues are known in
    /// closed form: c + 2 - 2 cos(k pi / (n+1)), k = 1..n.
    fn tridiag(n: usize, c: f64) -> SparseColMat<usize, f64> {
        let mut t = vec![];
        for i in 0..n {
            t.push(Triplet::new(i, i, 2.0 + c));
            if i + 1 < n {
                t.push(Triplet::new(i, i + 1, -1.0));
                t.push(Triplet::new(i + 1, i, -1.0));
            }
        }
        SparseColMat::try_new_from_triplets(n, n, &t).unwrap()
    }

    /// The pattern of whole `3 x 3` blocks of a random graph (`lower`: one triangle), with
    /// entry `(drop, drop - 1)` left out when `drop > 0`.
    fn block_graph(n: usize, edges: usize, lower: bool, drop: usize) -> SparseColMat<usize, f64> {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(5);
        let mut pairs: Vec<(usize, usize)> = (1..n).map(|i| (i - 1, i)).collect();
        while pairs.len() < edges {
            let (i, j) = (rng.random_range(0..n), rng.random_range(0..n));
            if i != j && !pairs.contains(&(i.min(j), i.max(j))) {
                pairs.push((i.min(j), i.max(j)));
            }
        }
        let mut t = vec![];
        let mut put = |r: usize, c: usize| {
            if (!lower || r >= c) && !(drop > 0 && r == drop && c == drop - 1) {
                t.push(Triplet::new(r, c, 1.0));
            }
        };
        for b in 0..n {
            for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
                put(3 * b + r, 3 * b + c);
            }
        }
        for &(i, j) in &pairs {
            for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
                put(3 * j + r, 3 * i + c);
                put(3 * i + r, 3 * j + c);
            }
        }
        SparseColMat::try_new_from_triplets(3 * n, 3 * n, &t).unwrap()
    }

    /// Block patterns (both triangles or one) are ordered on their quotient: the factor is
    /// within 10 % of the one AMD finds on the `3n` columns, and a predicted size that is the
    /// factor's when the ordering has no supernodes to relax; a pattern with one entry missing
    /// from a block is not a block pattern.
    #[test]
    fn block_patterns_are_ordered_by_their_quotient() {
        for lower in [false, true] {
            for (n, m) in [(50, 120), (300, 900), (400, 420)] {
                let a = block_graph(n, m, lower, 0);
                assert!(quotient_of_blocks(a.symbolic()).is_some());
                let by_blocks = symbolic_cholesky_within(a.symbolic(), usize::MAX)
                    .unwrap()
                    .unwrap();
                let (p, pinv, _) = amd_order(a.symbolic()).unwrap();
                let plain = factorize_symbolic_cholesky(
                    a.symbolic(),
                    Side::Lower,
                    SymmetricOrdering::Custom(PermRef::new_checked(&p, &pinv, 3 * n)),
                    // the same choice of kernel as the block path (a supernodal factor stores
                    // its relaxed supernodes' zeros)
                    CholeskySymbolicParams {
                        supernodal_flop_ratio_threshold: BLOCK_SUPERNODAL_THRESHOLD,
                        ..Default::default()
                    },
                )
                .unwrap();
                let ratio = by_blocks.len_val() as f64 / plain.len_val() as f64;
                assert!(
                    ratio < 1.1,
                    "n {n}: {} against {}",
                    by_blocks.len_val(),
                    plain.len_val()
                );
                // the refusal uses the quotient's prediction
                let refused = symbolic_cholesky_within(a.symbolic(), 10).unwrap();
                assert!(refused.is_err());
            }
        }
        let broken = block_graph(50, 120, false, 3); // (3, 2): off the diagonal blocks
        assert!(quotient_of_blocks(broken.symbolic()).is_none());
        let odd = tridiag(10, 1.0);
        assert!(quotient_of_blocks(odd.symbolic()).is_none());
    }

    #[test]
    fn lanczos_matches_closed_form() {
        let n = 60;
        let a = tridiag(n, -0.5);
        let exact_min = -0.5 + 2.0 - 2.0 * (std::f64::consts::PI / (n as f64 + 1.0)).cos();
        let exact_max =
            -0.5 + 2.0 - 2.0 * (n as f64 * std::f64::consts::PI / (n as f64 + 1.0)).cos();
        let r = lanczos_extreme(
            n,
            |x, y| sparse_matvec(a.as_ref(), x, y),
            Extreme::Smallest,
            4.0,
            &LanczosSettings::default(),
            None,
        );
        assert!(
            (r.value - exact_min).abs() < 1e-8,
            "{} vs {exact_min}",
            r.value
        );
        let r = lanczos_extreme(
            n,
            |x, y| sparse_matvec(a.as_ref(), x, y),
            Extreme::Largest,
            4.0,
            &LanczosSettings::default(),
            None,
        );
        assert!((r.value - exact_max).abs() < 1e-8);
    }

    #[test]
    fn cholesky_verification_brackets_closed_form() {
        let n = 50;
        let c = -0.3;
        let a = tridiag(n, c);
        let exact_min = c + 2.0 - 2.0 * (std::f64::consts::PI / (n as f64 + 1.0)).cos();
        let mut ch = ShiftedCholesky::new(a.clone(), 2).unwrap();
        // shift slightly above -lambda_min: must succeed and bound below the true value
        let f = ch.factor(-exact_min + 1e-9, 0.0).expect("PD");
        assert!(f.verified_lower_bound() <= exact_min);
        assert!(f.verified_lower_bound() > exact_min - 1e-8);
        assert!(f.margin < 1e-12, "margin {}", f.margin);
        // solve check
        let mut x = vec![1.0; n];
        f.solve_in_place(&mut x);
        let mut y = vec![0.0; n];
        sparse_matvec(a.as_ref(), &x, &mut y);
        for (yi, xi) in y.iter().zip(&x) {
            assert!((yi + (-exact_min + 1e-9) * xi - 1.0).abs() < 1e-5);
        }
        drop(f);
        // shift below -lambda_min: indefinite, must fail
        assert!(ch.factor(-exact_min - 1e-6, 0.0).is_none());
        assert!(gershgorin_lower_bound(a.as_ref()) <= exact_min);
    }

    /// Stress test of the margin [D6] at the decision boundary: the path-graph Laplacian has
    /// lambda_min = 0 exactly (integer entries, exact in floating point); `A = L - eps I` has
    /// lambda_min = -eps up to the rounding of its diagonal (<= 2u * 3). Whenever a shifted
    /// factorisation succeeds, the verified bound must be <= -eps (+ that rounding).
    #[test]
    fn margin_is_sound_at_the_decision_boundary() {
        for n in [10, 200, 3000] {
            for eps in [1e-15, 1e-13, 1e-11] {
                let a = tridiag(n, -eps);
                // the path Laplacian has 1 on the two end diagonals
                let mut a = a.to_dense();
                a[(0, 0)] -= 1.0;
                a[(n - 1, n - 1)] -= 1.0;
                let mut t = vec![];
                for c in 0..n {
                    for r in 0..n {
                        if a[(r, c)] != 0.0 || r == c {
                            t.push(faer::sparse::Triplet::new(r, c, a[(r, c)]));
                        }
                    }
                }
                let a = SparseColMat::try_new_from_triplets(n, n, &t).unwrap();
                let mut ch = ShiftedCholesky::new(a, 1).unwrap();
                for k in 0..=40 {
                    let shift = eps * k as f64 / 20.0;
                    if let Some(f) = ch.factor(shift, 0.0) {
                        assert!(
                            f.verified_lower_bound() <= -eps + 8.0 * UNIT_ROUNDOFF,
                            "n={n} eps={eps} shift={shift}: claimed {} > -eps",
                            f.verified_lower_bound()
                        );
                    }
                }
                // with a generous shift (here: 1e-9) the factorisation succeeds
                assert!(ch.factor(eps + 1e-9, 0.0).is_some(), "n={n} eps={eps}");
            }
        }
    }
}
