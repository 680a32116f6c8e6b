//! The `k` smallest eigenvalues of a certificate matrix, as **estimates** (for figures and
//! diagnostics, `paper-notes/certificates.md` `[D14]`).
//!
//! Nothing computed here is a proof: the only proven statement about the spectrum of `S` is the
//! Cholesky-verified lower bound on `lambda_min(S)` of [`crate::certify::multiple`] (`[D5]`,
//! `[D6]`). The values here are Ritz values (Rayleigh quotients on `S`) with their residuals
//! `||S x - lambda x||` (some eigenvalue of `S` lies within the residual of each value).
//!
//! - dimension `<= dense_max_dim`: a dense symmetric eigen-decomposition (nalgebra);
//! - larger, with a shift `sigma` known to make `S + sigma I` positive definite (the verified
//!   Cholesky shift): block Lanczos with full reorthogonalisation on `(S + sigma I)^-1`
//!   (shift-invert, the `k` largest eigenvalues of the inverse are the `k` smallest of `S`);
//! - otherwise block Lanczos with full reorthogonalisation on `S` itself (slow convergence
//!   for clustered small eigenvalues: the residuals say how far it got).
//!
//! The block size (default 3) matches the multiplicity-3 structure of rotation averaging (`S`
//! is similar to `L (x) I_3` at a noise-free optimum): single-vector Lanczos finds only one
//! copy of a multiple eigenvalue.

pub use crate::certify::evidence::{SpectrumEstimate, SpectrumMethod};
use crate::certify::multiple::multipliers::certificate_matrix;
pub use crate::certify::settings::SpectrumSettings;
use crate::error::{Error, Result};
use crate::linalg::{
    Extreme, LanczosSettings, ShiftedCholesky, inf_norm, lanczos, rayleigh_quotient, sparse_matvec,
};
use crate::multiple::MultipleProblem;
use faer::sparse::{SparseColMat, SparseColMatRef};
use nalgebra::{DMatrix, Matrix3, SymmetricEigen};

use std::time::Instant;

/// Estimates of the `settings.count` smallest eigenvalues of the symmetric sparse matrix `s`
/// (both triangles stored, as [`certificate_matrix`] builds it). `shift_hint`: a shift
/// `sigma` for which `S + sigma I` is known to be positive definite (e.g.
/// [`crate::certify::multiple::VerifiedBound::shift`]); enables shift-invert for large `s`.
///
/// ```
/// use faer::sparse::{SparseColMat, Triplet};
/// use rotavg::certify::spectrum::{smallest_eigenvalues, SpectrumSettings};
/// // diag(3, 1, 2): smallest two are 1, 2
/// let t = [Triplet::new(0, 0, 3.0), Triplet::new(1, 1, 1.0), Triplet::new(2, 2, 2.0)];
/// let s = SparseColMat::<usize, f64>::try_new_from_triplets(3, 3, &t).unwrap();
/// let e = smallest_eigenvalues(&s, &SpectrumSettings { count: 2, ..Default::default() }, None).unwrap();
/// assert!((e.values[0] - 1.0).abs() < 1e-12 && (e.values[1] - 2.0).abs() < 1e-12);
/// ```
pub fn smallest_eigenvalues(
    matrix: &SparseColMat<usize, f64>,
    settings: &SpectrumSettings,
    shift_hint: Option<f64>,
) -> Result<SpectrumEstimate> {
    let start = Instant::now();
    let s = matrix.as_ref();
    settings.validate()?;
    let n = s.nrows();
    if s.ncols() != n {
        return Err(Error::Degenerate {
            reason: "spectrum of a non-square matrix".into(),
        });
    }
    if !s.val().iter().all(|v| v.is_finite()) {
        return Err(Error::NonFinite {
            item: "certificate matrix".into(),
        });
    }
    let k = settings.count.min(n);
    let mut out = if n <= settings.dense_max_dim {
        dense(s, k)
    } else {
        let norm = inf_norm(s).max(f64::MIN_POSITIVE);
        let mut result = None;
        if let Some(h) = shift_hint.filter(|h| h.is_finite()) {
            // a little more than the verified shift: still positive definite, and the
            // inverse is not so ill-conditioned that rounding pollutes the other directions
            let mut sigma = h.max(0.0) + 1e-6 * norm;
            let mut ch = ShiftedCholesky::new(matrix.clone(), 1)?;
            for _ in 0..4 {
                if let Some(f) = ch.factor(sigma, f64::INFINITY) {
                    let r = block_lanczos(
                        s,
                        n,
                        k,
                        settings,
                        norm,
                        |x, y| {
                            y.copy_from_slice(x);
                            f.solve_in_place(y);
                        },
                        true,
                    );
                    result = Some(SpectrumEstimate {
                        method: SpectrumMethod::ShiftInvertLanczos,
                        shift: Some(sigma),
                        ..r
                    });
                    break;
                }
                sigma *= 10.0;
            }
        }
        match result {
            Some(r) => r,
            None => block_lanczos(
                s,
                n,
                k,
                settings,
                norm,
                |x, y| sparse_matvec(s, x, y),
                false,
            ),
        }
    };
    out.seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

/// [`smallest_eigenvalues`] of the certificate matrix `S = Q - blkdiag(Lambda)` of `problem`
/// and multipliers `lambdas` ([`certificate_matrix`]).
///
/// ```
/// use rotavg::certify::multiple::multipliers;
/// use rotavg::certify::spectrum::{certificate_spectrum, SpectrumSettings};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, gt) = SyntheticGraph { num_rotations: 8, num_edges: 16, noise_sigma: 0.0, ..Default::default() }.generate();
/// let l = multipliers(&p, &gt).unwrap();
/// let e = certificate_spectrum(&p, &l, &SpectrumSettings::default(), None).unwrap();
/// // noise-free optimum: the three gauge directions span the null space
/// assert!(e.values[..3].iter().all(|v| v.abs() < 1e-9) && e.values[3] > 1e-3);
/// ```
pub fn certificate_spectrum(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    settings: &SpectrumSettings,
    shift_hint: Option<f64>,
) -> Result<SpectrumEstimate> {
    let s: SparseColMat<usize, f64> = certificate_matrix(problem, lambdas)?;
    smallest_eigenvalues(&s, settings, shift_hint)
}

/// All eigenvalues of a small dense symmetric matrix, ascending (nalgebra's symmetric
/// eigen-decomposition of the symmetric part). Used for the 10x10 conjugate certificate.
///
/// ```
/// let m = nalgebra::DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
/// let e = rotavg::certify::spectrum::dense_eigenvalues(&m);
/// assert!((e[0] - 1.0).abs() < 1e-12 && (e[1] - 3.0).abs() < 1e-12);
/// ```
pub fn dense_eigenvalues(m: &DMatrix<f64>) -> Vec<f64> {
    if m.nrows() != m.ncols() || m.is_empty() {
        return Vec::new();
    }
    let sym = (m + m.transpose()) * 0.5;
    let mut v: Vec<f64> = SymmetricEigen::new(sym)
        .eigenvalues
        .iter()
        .copied()
        .collect();
    v.sort_by(f64::total_cmp);
    v
}

fn dense(s: SparseColMatRef<'_, usize, f64>, k: usize) -> SpectrumEstimate {
    let n = s.nrows();
    let a = crate::linalg::cholesky::to_dense(s);
    let a = (&a + a.transpose()) * 0.5;
    let eig = SymmetricEigen::new(a.clone());
    let mut idx: Vec<usize> = (0..n).collect();
    idx.sort_by(|&p, &q| eig.eigenvalues[p].total_cmp(&eig.eigenvalues[q]));
    let mut values = Vec::with_capacity(k);
    let mut residuals = Vec::with_capacity(k);
    for &i in idx.iter().take(k) {
        let x = eig.eigenvectors.column(i);
        let l = eig.eigenvalues[i];
        values.push(l);
        residuals.push((&a * x - x * l).norm());
    }
    SpectrumEstimate {
        values,
        residuals,
        method: SpectrumMethod::Dense,
        shift: None,
        stop: None,
        subspace_dim: n,
        seconds: 0.0,
    }
}

/// Block Lanczos `[D14]` ([`crate::linalg::lanczos`]) on `op`: `S` (`invert = false`,
/// target: smallest Ritz values) or `(S + sigma I)^-1` (`invert = true`, target: largest). The
/// reported values are Rayleigh quotients on `S` of the Ritz vectors, with residuals
/// `||S x - value x||` (computed with `S`), ascending.
fn block_lanczos(
    s: SparseColMatRef<'_, usize, f64>,
    n: usize,
    k: usize,
    settings: &SpectrumSettings,
    norm: f64,
    op: impl FnMut(&[f64], &mut [f64]),
    invert: bool,
) -> SpectrumEstimate {
    let lz = LanczosSettings {
        max_iterations: settings.max_subspace.max(k + settings.block_size),
        tolerance: settings.tolerance,
        seed: settings.seed,
        block_size: settings.block_size,
    };
    let (which, scale) = if invert {
        // relative to each Ritz value of the inverse
        (Extreme::Largest, 0.0)
    } else {
        (Extreme::Smallest, norm)
    };
    let e = lanczos(n, op, which, k, scale, &lz, &[], None);
    let mut pairs: Vec<(f64, f64)> = e.vectors.iter().map(|x| rayleigh_quotient(s, x)).collect();
    pairs.sort_by(|p, q| p.0.total_cmp(&q.0));
    SpectrumEstimate {
        values: pairs.iter().map(|p| p.0).collect(),
        residuals: pairs.iter().map(|p| p.1).collect(),
        method: SpectrumMethod::Lanczos,
        shift: None,
        stop: Some(e.stop),
        subspace_dim: e.subspace_dim,
        seconds: 0.0,
    }
}
