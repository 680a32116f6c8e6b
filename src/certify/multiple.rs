//! Dual certificate for chordal L2 multiple rotation averaging (SPEC section 3,
//! `paper-notes/certificates.md`).
//!
//! - [`multipliers`]: `Lambda_i = sym((Q Y)_i R_i^T)` `[D3]`, edge-wise (no dense `Q`).
//! - [`certificate_matrix`]: `S = Q - blkdiag(Lambda)` (sparse).
//! - [`lower_bound_from_multipliers`]: the verified bound `sum tr(Lambda_i) + 3n min(mu, 0)`
//!   `[D4]` from *any* multipliers, with `mu` a verified lower bound on `lambda_min(S)` `[D5]`-`[D8]`.
//! - [`certify_multiple`]: the certificate of an estimate (any rotations, critical point or not).

use crate::certificate::{BoundMethod, Certificate, GapTolerance};
use crate::certify::eigen::{
    Extreme, LanczosResult, LanczosSettings, ShiftedCholesky, gamma, gershgorin_lower_bound,
    inf_norm, lanczos_extreme, rayleigh_quotient, sparse_matvec,
};
use crate::certify::scalar::{ScalarAnalysis, scalar_comparison};
use crate::error::{Error, Result};
use crate::multiple::MultipleProblem;
use crate::multiple::laplacian::connection_laplacian_triplets;
use crate::so3::Rotation;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Instant;

/// Settings of [`certify_multiple`] and [`lower_bound_from_multipliers`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CertifySettings {
    /// Gap tolerance for the verdict.
    pub tolerance: GapTolerance,
    /// Fraction of the gap tolerance spent on the first Cholesky shift:
    /// `delta_0 = fraction * max(abs_tol, rel_tol |f|) / (3n)` (so that a verified
    /// `lambda_min >= -delta_0` costs at most this fraction of the tolerance). In `(0, 1)`.
    pub shift_budget_fraction: f64,
    /// Maximum number of numeric Cholesky factorisations tried.
    pub max_factorizations: usize,
    /// Lanczos settings for the eigenvalue *estimates* (never used as bounds by themselves).
    pub lanczos: LanczosSettings,
    /// Largest Cholesky factor (stored values) attempted: a guard on memory and time
    /// (`8 * max_factor_nonzeros` bytes). Graphs with good separators (pose graphs, grids) fill
    /// little; random expander graphs fill badly (a 10^4-node random graph with 3 10^4 edges
    /// needs ~1.1e8 values, 7.7 s on an idle 2-core machine; the scalar comparison `[D13]`
    /// usually avoids it). Above the cap no factorisation is tried: the bound falls
    /// back to Gershgorin (valid, weak) and the explanation says so.
    pub max_factor_nonzeros: usize,
    /// Also estimate `lambda_min(S)` (shift-invert Lanczos) when the first shift already
    /// verifies. Costs a few triangular solves; the estimate is reported, not used in the bound.
    pub estimate_when_verified: bool,
    /// Try the scalar comparison `[D13]` first when the `3n x 3n` Cholesky factor of `S` would
    /// have more than this many stored values (estimated as 9 x the scalar factor). The scalar
    /// proof needs one factorisation of an `n x n` matrix (about 27 x fewer flops on graphs
    /// that fill); when it does not succeed within the gap budget the `3n` factorisation runs as
    /// usual. `0`: always try it first; `usize::MAX`: never. Only used when the estimate's
    /// rotations are known ([`certify_multiple`], [`certify_with_multipliers`]).
    pub scalar_comparison_above: usize,
}

impl Default for CertifySettings {
    fn default() -> Self {
        CertifySettings {
            tolerance: GapTolerance::default(),
            shift_budget_fraction: 0.1,
            max_factorizations: 24,
            max_factor_nonzeros: 200_000_000,
            lanczos: LanczosSettings::default(),
            estimate_when_verified: true,
            scalar_comparison_above: 1_000_000,
        }
    }
}

impl CertifySettings {
    pub(crate) fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: &str| {
            Err(Error::InvalidSettings {
                name: name.into(),
                reason: reason.into(),
            })
        };
        if !(self.shift_budget_fraction > 0.0 && self.shift_budget_fraction < 1.0) {
            return bad("shift_budget_fraction", "must be in (0, 1)");
        }
        if !(self.tolerance.relative >= 0.0 && self.tolerance.absolute >= 0.0) {
            return bad("tolerance", "must be finite and nonnegative");
        }
        if self.max_factorizations == 0 {
            return bad("max_factorizations", "must be at least 1");
        }
        if self.lanczos.max_iterations == 0
            || self.lanczos.tolerance.is_nan()
            || self.lanczos.tolerance <= 0.0
        {
            return bad("lanczos", "needs max_iterations >= 1 and tolerance > 0");
        }
        Ok(())
    }
}

/// How the lower bound on `lambda_min(S)` was verified.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verification {
    /// A successful sparse Cholesky factorisation of `S + shift I` `[D5]`, `[D6]`.
    Cholesky,
    /// Gershgorin discs `[D8]` (no factorisation succeeded; usually a weak bound).
    Gershgorin,
    /// The scalar comparison `[D13]`: one `LDL^T` factorisation of an `n x n` scalar matrix with
    /// a verified inertia, plus rigorous bounds on the residuals of the estimate.
    ScalarComparison,
}

/// A verified lower bound from multipliers `Lambda` `[D4]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct VerifiedBound {
    /// The proven lower bound on the global minimum of the chordal cost (over `O(3)^n`, hence
    /// over `SO(3)^n`): `sum tr(Lambda_i) + 3n min(mu_verified, 0)` minus rounding margins.
    pub lower_bound: f64,
    /// `sum_i tr(Lambda_i)` (as computed).
    pub trace: f64,
    /// Verified lower bound `mu` on `lambda_min(S)`.
    pub verified_min_eigenvalue: f64,
    /// Which argument verified `mu`.
    pub verification: Verification,
    /// The Cholesky shift that verified `mu` (`mu = -shift - fp_margin`), if any.
    pub shift: Option<f64>,
    /// The rigorous floating-point margin included in `mu` `[D6]`.
    pub fp_margin: f64,
    /// Iterative *estimate* of `lambda_min(S)` (Lanczos), if computed.
    pub min_eigenvalue_estimate: Option<f64>,
    /// Ritz residual of that estimate.
    pub estimate_residual: Option<f64>,
    /// Unit eigenvector estimate for `lambda_min(S)` when the estimate is negative (length `3n`):
    /// the direction of descent for a rank-lifted (staircase) solve.
    pub negative_eigenvector: Option<Vec<f64>>,
    /// Lanczos iterations (all runs).
    pub lanczos_iterations: usize,
    /// Numeric Cholesky factorisations attempted.
    pub factorizations: usize,
    /// Stored values of the Cholesky factor (fill indicator).
    pub factor_nonzeros: usize,
    /// `true` when the factor exceeded `max_factor_nonzeros` and no factorisation was tried.
    pub factorization_skipped: bool,
}

/// The dual certificate of an estimate: the common [`Certificate`] plus diagnostics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MultipleCertificate {
    /// Verdict, bounds, gap (method [`BoundMethod::Dual`]).
    pub certificate: Certificate,
    /// How the bound was obtained.
    pub bound: VerifiedBound,
    /// First-order (stationarity) residual `sqrt(sum_i ||(Q Y)_i - Lambda_i R_i||_F^2)`: zero at a
    /// critical point `[D3]`. Equals `sqrt(sum_i ||skew((Q Y)_i R_i^T)||_F^2)`.
    pub stationarity_residual: f64,
}

impl fmt::Display for MultipleCertificate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}; stationarity residual {:.3e}",
            self.certificate, self.stationarity_residual
        )
    }
}

/// `(Q Y)_i` for every node, edge-wise `[D3]`:
/// `(Q Y)_i = d_i R_i - sum_{(i,j)} w R_ij^T R_j - sum_{(j,i)} w R_ji R_j`.
pub fn laplacian_times(problem: &MultipleProblem, rotations: &[Rotation]) -> Vec<Matrix3<f64>> {
    let n = problem.num_rotations();
    let mut qy = vec![Matrix3::zeros(); n];
    for e in problem.edges() {
        let r = e.rotation.matrix();
        let (ri, rj) = (rotations[e.i].matrix(), rotations[e.j].matrix());
        qy[e.i] += e.weight * (ri - r.transpose() * rj);
        qy[e.j] += e.weight * (rj - r * ri);
    }
    qy
}

/// The multipliers `Lambda_i = sym((Q Y)_i R_i^T)` of an estimate `[D3]` (SPEC section 3).
/// Errors if the estimate does not have one rotation per node.
///
/// ```
/// use rotavg::certify::multiple::multipliers;
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, gt) = SyntheticGraph { num_rotations: 5, num_edges: 8, noise_sigma: 0.0, ..Default::default() }.generate();
/// let l = multipliers(&p, &gt).unwrap();
/// // noise-free: every Lambda_i is zero (Q Y = 0)
/// assert!(l.iter().all(|m| m.norm() < 1e-12));
/// ```
pub fn multipliers(problem: &MultipleProblem, rotations: &[Rotation]) -> Result<Vec<Matrix3<f64>>> {
    problem.check_estimate(rotations)?;
    Ok(laplacian_times(problem, rotations)
        .iter()
        .zip(rotations)
        .map(|(g, r)| {
            let m = g * r.matrix().transpose();
            0.5 * (m + m.transpose())
        })
        .collect())
}

/// `sqrt(sum_i ||(Q Y)_i - Lambda_i R_i||_F^2)` with `Lambda` from [`multipliers`]: the
/// first-order residual (zero exactly at a critical point of the cost on `O(3)^n`).
pub fn stationarity_residual(problem: &MultipleProblem, rotations: &[Rotation]) -> Result<f64> {
    problem.check_estimate(rotations)?;
    Ok(laplacian_times(problem, rotations)
        .iter()
        .zip(rotations)
        .map(|(g, r)| {
            let m = g * r.matrix().transpose();
            (0.5 * (m - m.transpose())).norm_squared()
        })
        .sum::<f64>()
        .sqrt())
}

/// One finite rotation per node.
pub(crate) fn check_rotations(problem: &MultipleProblem, rotations: &[Rotation]) -> Result<()> {
    problem.check_estimate(rotations)?;
    for (i, r) in rotations.iter().enumerate() {
        if !r.matrix().iter().all(|x| x.is_finite()) {
            return Err(Error::NonFinite {
                item: format!("estimate rotation {i}"),
            });
        }
    }
    Ok(())
}

fn check_lambdas(problem: &MultipleProblem, lambdas: &[Matrix3<f64>]) -> Result<()> {
    if lambdas.len() != problem.num_rotations() {
        return Err(Error::InvalidSettings {
            name: "multipliers".into(),
            reason: format!(
                "{} blocks given, the problem has {} nodes",
                lambdas.len(),
                problem.num_rotations()
            ),
        });
    }
    for (i, l) in lambdas.iter().enumerate() {
        if !l.iter().all(|x| x.is_finite()) {
            return Err(Error::NonFinite {
                item: format!("multiplier block {i}"),
            });
        }
    }
    Ok(())
}

/// The certificate matrix `S = Q - blkdiag(Lambda)` (3n x 3n, sparse, both triangles stored,
/// every diagonal entry stored). Each `Lambda_i` is symmetrised first (the bound only depends on
/// the symmetric part).
pub fn certificate_matrix(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
) -> Result<SparseColMat<usize, f64>> {
    check_lambdas(problem, lambdas)?;
    let n3 = 3 * problem.num_rotations();
    let mut t = connection_laplacian_triplets(problem);
    t.reserve(9 * lambdas.len());
    for (i, l) in lambdas.iter().enumerate() {
        let l = symmetrize(l);
        for a in 0..3 {
            for b in 0..3 {
                t.push(Triplet::new(3 * i + a, 3 * i + b, -l[(a, b)]));
            }
        }
    }
    SparseColMat::try_new_from_triplets(n3, n3, &t).map_err(|e| Error::Solver {
        message: format!("could not assemble the certificate matrix: {e:?}"),
    })
}

fn symmetrize(l: &Matrix3<f64>) -> Matrix3<f64> {
    0.5 * (l + l.transpose())
}

/// Largest number of rounded operations that formed an entry of `S` from the data: the degree
/// sum on the diagonal (and multi-edge sums off it), plus the multiplier subtraction.
fn entry_terms(problem: &MultipleProblem) -> usize {
    let mut deg = vec![0usize; problem.num_rotations()];
    for e in problem.edges() {
        deg[e.i] += 1;
        deg[e.j] += 1;
    }
    deg.into_iter().max().unwrap_or(0) + 3
}

/// A verified lower bound on the global minimum of the chordal cost from *any* multipliers
/// `Lambda` (symmetrised) `[D4]`: `sum tr(Lambda_i) + 3n min(mu, 0)`, where `mu` is a
/// verified lower bound on `lambda_min(Q - blkdiag(Lambda))` (sparse Cholesky `[D5]` with
/// the floating-point margin `[D6]`; Gershgorin `[D8]` as the fallback). Use this to verify
/// an SDP solver's multipliers: never its reported objective.
///
/// The first shift tried is `delta_0 = fraction * max(abs_tol, rel_tol |sum tr Lambda|) / (3n)`.
///
/// ```
/// use rotavg::certify::multiple::{lower_bound_from_multipliers, CertifySettings};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// use nalgebra::Matrix3;
/// let (p, _) = SyntheticGraph { num_rotations: 6, num_edges: 10, noise_sigma: 0.1, ..Default::default() }.generate();
/// // Lambda = 0 is dual feasible (Q is PSD): the bound is ~0 (below every cost).
/// let b = lower_bound_from_multipliers(&p, &vec![Matrix3::zeros(); 6], &CertifySettings::default()).unwrap();
/// assert!(b.lower_bound <= 0.0 && b.lower_bound > -1e-6);
/// ```
pub fn lower_bound_from_multipliers(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    settings: &CertifySettings,
) -> Result<VerifiedBound> {
    settings.validate()?;
    let trace: f64 = lambdas.iter().map(|l| l.trace()).sum();
    verify(problem, lambdas, None, trace.abs(), settings)
}

/// The core of `[D4]`-`[D8]`: `scale` is the cost scale for the shift budget.
fn verify(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    rotations: Option<&[Rotation]>,
    scale: f64,
    settings: &CertifySettings,
) -> Result<VerifiedBound> {
    let s = certificate_matrix(problem, lambdas)?;
    let n3 = s.nrows();
    let dim = n3 as f64;
    let norm = inf_norm(s.as_ref()).max(f64::MIN_POSITIVE);
    let tol = settings.tolerance;
    let budget = tol.absolute.max(tol.relative * scale.max(1e-12));
    let delta0 = settings.shift_budget_fraction * budget / dim;
    if let Some(rs) = rotations
        && let Some(b) = try_scalar_comparison(problem, rs, lambdas, &s, norm, budget, settings)?
    {
        return Ok(b);
    }
    let terms = entry_terms(problem);
    // a floating-point margin below this costs at most 5% of the gap budget: no need to
    // compute the tighter (more expensive) residual-based margin [D6] (2)
    let margin_target = 0.05 * budget / dim;
    // Gershgorin fallback [D8]: rigorous for S_fl; the forming error of S_fl vs the exact S
    // is bounded as in [D6](b).
    let gersh = gershgorin_lower_bound(s.as_ref()) - 2.0 * gamma(terms + 1) * norm;
    let s_copy = s.clone();
    let mut ch = ShiftedCholesky::new(s, terms)?;
    let factor_nonzeros = ch.factor_len();
    let mut factorizations = 0usize;
    let mut lanczos_iterations = 0usize;
    let mut estimate: Option<LanczosResult> = None;
    // (shift, margin) of the best verified factorisation
    let mut best: Option<(f64, f64)> = None;
    let mut lz = settings.lanczos;
    lz.max_iterations = lz.max_iterations.min(n3.max(1));

    // Shift-invert estimate with a successful factor: largest eigenvalue theta of
    // (S + sigma I)^-1 gives lambda_min(S) ~ 1/theta - sigma [D7].
    let shift_invert = |f: &crate::certify::eigen::PositiveFactor<'_>,
                        start: Option<&[f64]>,
                        lz: &LanczosSettings|
     -> LanczosResult {
        let mut r = lanczos_extreme(
            n3,
            |x, y| {
                y.copy_from_slice(x);
                f.solve_in_place(y);
            },
            Extreme::Largest,
            0.0,
            lz,
            start,
        );
        // residual of (S + sigma I)^-1 x = theta x  =>  S x - (1/theta - sigma) x has norm
        // about residual / theta^2 * ... ; report the Rayleigh-quotient residual on S instead.
        let value = 1.0 / r.value - f.shift;
        r.value = value;
        r
    };
    let rq_residual = |r: &mut LanczosResult, s: &faer::sparse::SparseColMat<usize, f64>| {
        (r.value, r.residual) = rayleigh_quotient(s.as_ref(), &r.vector);
    };

    let skipped = factor_nonzeros > settings.max_factor_nonzeros;
    if skipped {
        let r = lanczos_extreme(
            n3,
            |x, y| sparse_matvec(s_copy.as_ref(), x, y),
            Extreme::Smallest,
            norm,
            &lz,
            None,
        );
        lanczos_iterations += r.iterations;
        estimate = Some(r);
    } else {
        factorizations += 1;
        if let Some(f) = ch.factor(delta0, margin_target) {
            best = Some((f.shift, f.margin));
            if settings.estimate_when_verified {
                let mut lz2 = lz;
                lz2.max_iterations = lz2.max_iterations.min(40);
                let mut r = shift_invert(&f, None, &lz2);
                lanczos_iterations += r.iterations;
                rq_residual(&mut r, &s_copy);
                estimate = Some(r);
            }
        } else {
            // Estimate lambda_min(S) by Lanczos on S itself, then search upward for a shift whose
            // factorisation succeeds.
            let mut r = lanczos_extreme(
                n3,
                |x, y| sparse_matvec(s_copy.as_ref(), x, y),
                Extreme::Smallest,
                norm,
                &lz,
                None,
            );
            lanczos_iterations += r.iterations;
            let base = (-r.value).max(0.0);
            let step0 = delta0.max(r.residual).max(1e-12 * norm);
            let gersh_shift = (-gersh).max(0.0);
            let mut j = 0i32;
            while factorizations < settings.max_factorizations {
                let sigma = base + step0 * 4f64.powi(j);
                j += 1;
                factorizations += 1;
                let Some(f) = ch.factor(sigma, margin_target) else {
                    if sigma > gersh_shift {
                        break;
                    }
                    continue;
                };
                best = Some((f.shift, f.margin));
                // refine the estimate by shift-invert from the Lanczos vector
                let mut r2 = shift_invert(&f, Some(&r.vector), &lz);
                lanczos_iterations += r2.iterations;
                rq_residual(&mut r2, &s_copy);
                drop(f);
                if r2.value < r.value || r2.residual < r.residual {
                    r = r2;
                }
                break;
            }
            // tighten: try just above the refined estimate
            if let Some((shift, _)) = best {
                let mut margin = delta0.max(1e-9 * r.value.abs()).max(r.residual);
                while factorizations < settings.max_factorizations {
                    let sigma = (-r.value).max(0.0) + margin;
                    if sigma >= shift {
                        break;
                    }
                    factorizations += 1;
                    if let Some(f) = ch.factor(sigma, margin_target) {
                        best = Some((f.shift, f.margin));
                        break;
                    }
                    margin *= 10.0;
                }
            }
            estimate = Some(r);
        }
    }

    let (verification, mu, shift, fp_margin) = match best {
        Some((shift, margin)) if -shift - margin >= gersh => {
            (Verification::Cholesky, -shift - margin, Some(shift), margin)
        }
        _ => (Verification::Gershgorin, gersh, None, 0.0),
    };
    let lower_bound = bound_from_mu(lambdas, mu);
    let negative_eigenvector = estimate
        .as_ref()
        .filter(|r| r.value < 0.0 && r.value < -delta0)
        .map(|r| r.vector.clone());
    Ok(VerifiedBound {
        lower_bound,
        trace: lambdas.iter().map(|l| l.trace()).sum(),
        verified_min_eigenvalue: mu,
        verification,
        shift,
        fp_margin,
        min_eigenvalue_estimate: estimate.as_ref().map(|r| r.value),
        estimate_residual: estimate.as_ref().map(|r| r.residual),
        negative_eigenvector,
        lanczos_iterations,
        factorizations,
        factor_nonzeros,
        factorization_skipped: skipped,
    })
}

/// The scalar comparison `[D13]` as a first attempt: `Some(bound)` when it is tried (the
/// estimated `3n` factor is above `settings.scalar_comparison_above`) and proves
/// `lambda_min(S) >= -budget / (6n)` (at most half the gap budget); `None` otherwise (the caller
/// then factorises `S`).
fn try_scalar_comparison(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    s: &SparseColMat<usize, f64>,
    norm: f64,
    budget: f64,
    settings: &CertifySettings,
) -> Result<Option<VerifiedBound>> {
    if settings.scalar_comparison_above == usize::MAX {
        return Ok(None);
    }
    let analysis = ScalarAnalysis::new(problem)?;
    if analysis.factor_len().saturating_mul(9) <= settings.scalar_comparison_above {
        return Ok(None);
    }
    let target = 0.5 * budget / s.nrows().max(1) as f64;
    let proof = match scalar_comparison(problem, &analysis, rotations, lambdas, target)? {
        Ok(p) if p.verified_min_eigenvalue >= -target => p,
        _ => return Ok(None),
    };
    let n3 = s.nrows();
    let mut estimate = None;
    let mut lanczos_iterations = 0;
    if settings.estimate_when_verified {
        let mut lz = settings.lanczos;
        lz.max_iterations = lz.max_iterations.min(40).min(n3.max(1));
        let r = lanczos_extreme(
            n3,
            |x, y| sparse_matvec(s.as_ref(), x, y),
            Extreme::Smallest,
            norm,
            &lz,
            None,
        );
        lanczos_iterations = r.iterations;
        estimate = Some(r);
        // the gauge directions (columns of Y) are near-null vectors at a critical point: their
        // Rayleigh quotients are upper bounds on lambda_min too, often far better than a short
        // Lanczos run in the cluster at 0
        for a in 0..3 {
            let mut v: Vec<f64> = rotations
                .iter()
                .flat_map(|r| (0..3).map(move |b| r.matrix()[(b, a)]))
                .collect();
            let nv = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if nv == 0.0 || !nv.is_finite() {
                continue;
            }
            v.iter_mut().for_each(|x| *x /= nv);
            let (rq, res) = rayleigh_quotient(s.as_ref(), &v);
            if let Some(e) = estimate.as_mut()
                && rq < e.value
            {
                *e = LanczosResult {
                    value: rq,
                    vector: v,
                    residual: res,
                    iterations: e.iterations,
                    converged: e.converged,
                };
            }
        }
    }
    let mu = proof.verified_min_eigenvalue;
    Ok(Some(VerifiedBound {
        lower_bound: bound_from_mu(lambdas, mu),
        trace: lambdas.iter().map(|l| l.trace()).sum(),
        verified_min_eigenvalue: mu,
        verification: Verification::ScalarComparison,
        shift: None,
        fp_margin: proof.backward_error,
        min_eigenvalue_estimate: estimate.as_ref().map(|r| r.value),
        estimate_residual: estimate.as_ref().map(|r| r.residual),
        negative_eigenvector: None,
        lanczos_iterations,
        factorizations: 1,
        factor_nonzeros: proof.factor_nonzeros,
        factorization_skipped: false,
    }))
}

/// `[D4]` with rounding: `sum tr(Lambda_i) + 3n min(mu, 0)`, minus the rounding error of
/// evaluating it: the trace sum of `3n` terms has error `<= gamma(3n) sum |Lambda_aa|`, the
/// product and final subtraction `<= gamma(3n + 2) (sum |Lambda_aa| + 3n |mu|)`; doubled.
fn bound_from_mu(lambdas: &[Matrix3<f64>], mu: f64) -> f64 {
    let n3 = 3 * lambdas.len();
    let trace: f64 = lambdas.iter().map(|l| l.trace()).sum();
    let abs_trace: f64 = lambdas
        .iter()
        .map(|l| l[(0, 0)].abs() + l[(1, 1)].abs() + l[(2, 2)].abs())
        .sum();
    let neg = (-mu).max(0.0);
    let err = 2.0 * gamma(n3 + 4) * (abs_trace + n3 as f64 * neg);
    trace - n3 as f64 * neg - err
}

/// Certify an estimate of chordal L2 multiple rotation averaging (SPEC section 3): multipliers
/// from the first-order conditions `[D3]`, the verified bound `[D4]`, and the verdict from
/// `Certificate::from_bounds(f(Y), Some(lb), ..)`. Works for any rotations: at a point that is
/// not critical the bound is still valid but weaker, and the verdict is `Certified` only if the
/// gap is within tolerance. The estimate is never changed.
///
/// ```
/// use rotavg::certify::multiple::{certify_multiple, CertifySettings};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, gt) = SyntheticGraph { num_rotations: 20, num_edges: 40, noise_sigma: 0.0, ..Default::default() }.generate();
/// let c = certify_multiple(&p, &gt, &CertifySettings::default()).unwrap();
/// assert!(c.certificate.is_certified());
/// ```
pub fn certify_multiple(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
) -> Result<MultipleCertificate> {
    let start = Instant::now();
    settings.validate()?;
    check_rotations(problem, rotations)?;
    let cost = problem.chordal_cost(rotations);
    let lambdas = multipliers(problem, rotations)?;
    let stationarity = stationarity_residual(problem, rotations)?;
    let bound = verify(problem, &lambdas, Some(rotations), cost.abs(), settings)?;
    let how = match (bound.verification, bound.shift) {
        (Verification::Cholesky, Some(s)) => format!(
            "lambda_min(S) >= {:.3e} verified by a sparse Cholesky factorisation of S + {:.3e} I \
             (floating-point margin {:.1e})",
            bound.verified_min_eigenvalue, s, bound.fp_margin
        ),
        (Verification::ScalarComparison, _) => format!(
            "lambda_min(S) >= {:.3e} verified by the scalar comparison [D13] (inertia of one \
             LDL^T factorisation of an n x n matrix, {} values; backward error {:.1e})",
            bound.verified_min_eigenvalue, bound.factor_nonzeros, bound.fp_margin
        ),
        _ if bound.factorization_skipped => format!(
            "Cholesky factor too large ({} values > max_factor_nonzeros); only the Gershgorin \
             bound lambda_min(S) >= {:.3e} is verified",
            bound.factor_nonzeros, bound.verified_min_eigenvalue
        ),
        _ => format!(
            "no Cholesky shift verified; Gershgorin bound lambda_min(S) >= {:.3e}",
            bound.verified_min_eigenvalue
        ),
    };
    let est = bound
        .min_eigenvalue_estimate
        .map(|e| format!("; Lanczos estimate lambda_min(S) ~ {e:.3e}"))
        .unwrap_or_default();
    let min_eig = bound
        .min_eigenvalue_estimate
        .or(Some(bound.verified_min_eigenvalue));
    let mut certificate = Certificate::from_bounds(
        cost,
        Some(bound.lower_bound),
        BoundMethod::Dual,
        min_eig,
        settings.tolerance,
        String::new(),
        0.0,
    );
    let verdict_text = if certificate.is_certified() {
        "certified globally optimal (over O(3)^n, hence SO(3)^n)"
    } else if stationarity > 1e-6 * (cost.abs() + 1.0) {
        "not certified: the estimate is not a critical point (stationarity residual large); the bound is valid but weak"
    } else {
        "not certified: the dual certificate S is not positive semidefinite (a local minimum or saddle of the nonconvex problem, or a non-tight relaxation)"
    };
    certificate.explanation = format!("{verdict_text}; {how}{est}");
    certificate.verified_min_eigenvalue = Some(bound.verified_min_eigenvalue);
    certificate.seconds = start.elapsed().as_secs_f64();
    Ok(MultipleCertificate {
        certificate,
        bound,
        stationarity_residual: stationarity,
    })
}

/// Certify an estimate against multipliers obtained elsewhere (an SDP solve, a staircase, the
/// multipliers of a better estimate): upper bound `f(rotations)`, lower bound verified from
/// `lambdas` `[D4]`-`[D8]`, verdict from `Certificate::from_bounds`, with the given `method`
/// (e.g. [`BoundMethod::Sdp`]). This is how an estimate that is not a critical point gets a useful
/// bound. The estimate is never changed.
///
/// ```
/// use rotavg::certify::multiple::{certify_with_multipliers, multipliers, CertifySettings};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// use rotavg::BoundMethod;
/// let (p, gt) = SyntheticGraph { num_rotations: 6, num_edges: 10, noise_sigma: 0.0, ..Default::default() }.generate();
/// let l = multipliers(&p, &gt).unwrap();
/// let c = certify_with_multipliers(&p, &gt, &l, BoundMethod::Sdp, &CertifySettings::default()).unwrap();
/// assert!(c.certificate.is_certified());
/// ```
pub fn certify_with_multipliers(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    method: BoundMethod,
    settings: &CertifySettings,
) -> Result<MultipleCertificate> {
    let start = Instant::now();
    settings.validate()?;
    check_rotations(problem, rotations)?;
    check_lambdas(problem, lambdas)?;
    let cost = problem.chordal_cost(rotations);
    let stationarity = stationarity_residual(problem, rotations)?;
    let bound = verify(problem, lambdas, Some(rotations), cost.abs(), settings)?;
    let explanation = format!(
        "bound from supplied multipliers ({method}): lambda_min(Q - blkdiag(Lambda)) >= {:.3e} verified by {}",
        bound.verified_min_eigenvalue,
        match bound.verification {
            Verification::Cholesky => "a sparse Cholesky factorisation",
            Verification::Gershgorin => "Gershgorin discs",
            Verification::ScalarComparison => "the scalar comparison [D13]",
        }
    );
    let min_eig = bound
        .min_eigenvalue_estimate
        .or(Some(bound.verified_min_eigenvalue));
    let mut certificate = Certificate::from_bounds(
        cost,
        Some(bound.lower_bound),
        method,
        min_eig,
        settings.tolerance,
        explanation,
        start.elapsed().as_secs_f64(),
    );
    certificate.verified_min_eigenvalue = Some(bound.verified_min_eigenvalue);
    Ok(MultipleCertificate {
        certificate,
        bound,
        stationarity_residual: stationarity,
    })
}
