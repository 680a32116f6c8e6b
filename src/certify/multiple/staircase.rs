//! Riemannian staircase (Burer-Monteiro) for the multiple-rotation SDP `[D11]`
//! (`paper-notes/certificates.md`): when the dual certificate of an estimate fails, solve the
//! rank-lifted problem `min tr(Y^T Q Y)` over `Y_i` in `St(3, p)` (3 x p, orthonormal rows),
//! `p = 3, 4, ...`, escaping saddles along the negative eigenvector of `S`; the multipliers of
//! the final lifted point are verified exactly like any other multipliers
//! ([`super::lower_bound_from_multipliers`]), so the bound is proven whatever the
//! optimiser achieved, and approaches the SDP optimum when the optimiser converges.
//!
//! Each rank is solved by the Riemannian trust-region method of [`crate::relax::lifted`]
//! (truncated conjugate gradients on Hessian-vector products with the sparse `S`, polar
//! retraction), warm-started from the previous rank's point, first to
//! [`ESCAPE_GRADIENT_TOLERANCE`]: a negative Rayleigh quotient of a Lanczos estimate there is a
//! direction of descent, and the next rank starts along it without a verification. Otherwise the
//! rank is solved to [`StaircaseSettings::gradient_tolerance`] and its multipliers verified;
//! ranks grow while the verification finds a negative eigenvector, until the verified bound and
//! the lifted cost bracket the relaxation's value within [`StaircaseSettings::bracket_tolerance`]
//! of the gap, up to [`StaircaseSettings::max_rank`] and the time budget. The best verified
//! bound over the ranks is reported.

use super::check::{CurvatureHint, Scope};
use super::multipliers::{certificate_matrix, check_rotations};
use super::state::{Best, State};
use super::verified::VerifiedBound;
use super::verify::multipliers_bound;
use crate::certify::budget::Deadline;
use crate::certify::certificate::Certificate;
use crate::certify::certification::ImprovementSource;
pub use crate::certify::evidence::StaircaseStep;
use crate::certify::log::{Point, Prediction, Refusal};
use crate::certify::proof::BoundMethod;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifyMode;
use crate::certify::settings::CertifySettings;
pub use crate::certify::settings::StaircaseSettings;
use crate::certify::tolerance::GapTolerance;
use crate::error::Result;
use crate::linalg::cholesky::sparse_matvec;
use crate::linalg::two_pass_lanczos::{TwoPassSettings, two_pass_smallest};
use crate::linalg::{LanczosResult, LanczosStop, inf_norm, rayleigh_quotient};
use crate::multiple::MultipleProblem;
use crate::multiple::{Initialisation, MultipleSettings, MultipleSolution, solve_multiple};
use crate::relax::lifted::{
    Block, TrustRegionResult, TrustRegionSettings, lifted_cost, lifted_multipliers, polar,
    trust_region_until,
};
use crate::so3::Rotation;
use faer::sparse::SparseColMatRef;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Why the staircase stopped.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum StaircaseStop {
    /// The certificate matrix of the rank-`rank` point has no negative eigenvalue estimate
    /// below the shift budget: the bound is as good as the verification.
    Verified {
        /// The rank.
        rank: usize,
        /// The Lanczos estimate of `lambda_min(S)` at that point.
        min_eigenvalue_estimate: Option<f64>,
    },
    /// The rank limit was reached with a negative eigenvalue left.
    MaxRank {
        /// The limit ([`StaircaseSettings::max_rank`]).
        max_rank: usize,
        /// The negative eigenvalue estimate left.
        min_eigenvalue_estimate: Option<f64>,
    },
    /// The verified bound and the lifted cost bracket the relaxation's value within
    /// [`StaircaseSettings::bracket_tolerance`]: a higher rank cannot improve the bound by more.
    Bracketed {
        /// The rank.
        rank: usize,
        /// The lifted cost `F(Y)` minus the verified bound.
        bracket: f64,
    },
    /// Moving along the negative eigenvector did not decrease the lifted cost (40 halvings).
    EscapeFailed {
        /// The rank at which it failed.
        rank: usize,
        /// The negative eigenvalue estimate.
        min_eigenvalue_estimate: Option<f64>,
    },
}

impl std::fmt::Display for StaircaseStop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let est = |e: &Option<f64>| e.map_or("n/a".to_string(), |v| format!("{v:.3e}"));
        match self {
            StaircaseStop::Verified {
                rank,
                min_eigenvalue_estimate,
            } => write!(
                f,
                "certificate S of the rank-{rank} point verified (no negative eigenvector; lambda_min estimate {})",
                est(min_eigenvalue_estimate)
            ),
            StaircaseStop::MaxRank {
                max_rank,
                min_eigenvalue_estimate,
            } => write!(
                f,
                "maximum rank {max_rank} reached (lambda_min estimate {} < 0)",
                est(min_eigenvalue_estimate)
            ),
            StaircaseStop::Bracketed { rank, bracket } => write!(
                f,
                "the relaxation's value is bracketed at rank {rank}: the lifted cost is {bracket:.3e} \
                 above the verified bound"
            ),
            StaircaseStop::EscapeFailed {
                rank,
                min_eigenvalue_estimate,
            } => write!(
                f,
                "escape along the negative eigenvector at rank {rank} did not decrease the cost (lambda_min estimate {})",
                est(min_eigenvalue_estimate)
            ),
        }
    }
}

/// Result of [`staircase_bound`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StaircaseResult {
    /// Certificate of the given estimate with the staircase bound (method `Staircase`).
    pub certificate: Certificate,
    /// The verified bound from the final lifted point's multipliers.
    pub bound: VerifiedBound,
    /// Final rank `p`.
    pub rank: usize,
    /// Cost `F(Y)` of the final lifted point (an estimate of the SDP optimum from above).
    pub lifted_cost: f64,
    /// Total trust-region iterations.
    pub iterations: usize,
    /// Hessian-vector products with `S` (the work of the trust-region subproblems).
    #[serde(default)]
    pub hessian_products: usize,
    /// Why the staircase stopped.
    pub stop_reason: StaircaseStop,
    /// Every rank that ran, in order.
    #[serde(default)]
    pub steps: Vec<StaircaseStep>,
    /// The final lifted point rounded to rotations ([`round_lifted`]): an upper bound on the
    /// global minimum, to be polished by the local solver.
    #[serde(with = "crate::so3::serde_rows::rotations", default)]
    pub rounded: Vec<Rotation>,
    /// Blocks of the rounding still reflected after the global flip ([`round_lifted`]): the
    /// `O(3)` relaxation prefers reflections there (anisotropic costs, `[A5]`).
    #[serde(default)]
    pub reflected_blocks: usize,
}

/// Rounding of a lifted point `Y` (blocks `Y_i`, `3 x p`), as SE-Sync rounds its staircase:
/// the top three right singular vectors `V` of the stacked `Y` (eigenvectors of
/// `sum_i Y_i^T Y_i`), the global reflection fixed by the majority of `det(Y_i V)`, each block
/// `Y_i V` projected to SO(3), gauge `R_0 = I`. At a rank-3 point this returns the point itself
/// (up to the gauge).
pub fn round_lifted(y: &[Block]) -> Vec<Rotation> {
    round_lifted_counted(y).0
}

/// [`round_lifted`] and the number of blocks `Y_i V` still reflected (`det < 0`) after the
/// global flip: the lifted point prefers reflections there (anisotropic costs, `[A5]`).
pub(crate) fn round_lifted_counted(y: &[Block]) -> (Vec<Rotation>, usize) {
    let p = y.first().map_or(3, |b| b.ncols());
    let mut gram = nalgebra::DMatrix::<f64>::zeros(p, p);
    for b in y {
        gram += b.transpose() * b;
    }
    let eig = nalgebra::SymmetricEigen::new(gram);
    let mut order: Vec<usize> = (0..p).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let mut v = nalgebra::DMatrix::<f64>::zeros(p, 3);
    for (c, &k) in order.iter().take(3).enumerate() {
        v.set_column(c, &eig.eigenvectors.column(k));
    }
    let blocks: Vec<nalgebra::Matrix3<f64>> = y
        .iter()
        .map(|b| {
            let m = b * &v;
            nalgebra::Matrix3::from_fn(|r, c| m[(r, c)])
        })
        .collect();
    crate::relax::multiple::project_blocks(blocks)
}

/// Bound the global minimum by a Riemannian staircase started at `rotations` `[D11]`, and
/// certify `rotations` against it (method [`BoundMethod::Staircase`]). The bound is verified
/// exactly like any multipliers (`[D4]`-`[D8]`): it is valid whatever the descent achieved.
///
/// ```
/// use rotavg::certify::multiple::staircase::staircase_bound;
/// use rotavg::certify::CertifySettings;
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, gt) = SyntheticGraph { num_rotations: 8, num_edges: 14, noise_sigma: 0.0, ..Default::default() }.generate();
/// let r = staircase_bound(&p, &gt, &CertifySettings::default()).unwrap();
/// assert!(r.certificate.lower_bound.unwrap() <= p.chordal_cost(&gt) + 1e-12);
/// ```
pub fn staircase_bound(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    certify: &CertifySettings,
) -> Result<StaircaseResult> {
    certify.validate()?;
    staircase_within(
        problem,
        rotations,
        certify,
        Deadline::start(&certify.budget),
    )
}

/// [`staircase_bound`] on a certification's clock: the ranks stop once half of the time left
/// at its start is spent.
pub(crate) fn staircase_within(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    certify: &CertifySettings,
    deadline: Deadline,
) -> Result<StaircaseResult> {
    let mut stairs = Staircase::new(problem, rotations, certify, deadline)?;
    loop {
        let end = stairs.climb_rank()?;
        if let Some(stop) = stairs.stop_or_escape(&end) {
            return stairs.finish(end.lifted, stop, end.verified);
        }
    }
}

/// The staircase between ranks (`[D11]`): the lifted point, its rank, the work counted and the
/// ranks that ran, with what every rank shares (the data, the settings, the clock).
struct Staircase<'a> {
    problem: &'a MultipleProblem,
    certify: &'a CertifySettings,
    scope: Scope,
    /// Half of the time left at the start: no new rank after it.
    half: Deadline,
    start: Instant,
    /// The trust region to [`StaircaseSettings::gradient_tolerance`] (before a verification).
    strict: TrustRegionSettings,
    /// The trust region to [`ESCAPE_GRADIENT_TOLERANCE`] at least (ranks that may escape).
    loose: TrustRegionSettings,
    /// The given estimate's cost.
    cost: f64,
    tolerance: GapTolerance,
    y: Vec<Block>,
    rank: usize,
    iterations: usize,
    products: usize,
    steps: Vec<StaircaseStep>,
}

/// How one rank ended: its lifted cost, the direction of negative curvature to escape along
/// (none: the verification found none) and the verified bound when the rank was verified.
struct RankEnd {
    lifted: f64,
    direction: Option<Vec<f64>>,
    verified: Option<VerifiedBound>,
}

impl<'a> Staircase<'a> {
    /// Rank 3 at `rotations`, no work done yet.
    fn new(
        problem: &'a MultipleProblem,
        rotations: &[Rotation],
        certify: &'a CertifySettings,
        deadline: Deadline,
    ) -> Result<Self> {
        let start = Instant::now();
        check_rotations(problem, rotations)?;
        let half = deadline.share(0.5);
        let scope = Scope {
            point: Point::Staircase,
            within: Proof::Staircase,
            deadline,
            refinement_follows: None,
        };
        let settings = &certify.staircase;
        let strict = TrustRegionSettings {
            max_iterations: settings.max_iterations,
            gradient_tolerance: settings.gradient_tolerance,
            ..Default::default()
        };
        // the intermediate ranks only need a direction of negative curvature: a looser
        // tolerance first, the strict one before a verification
        let loose = TrustRegionSettings {
            gradient_tolerance: settings.gradient_tolerance.max(ESCAPE_GRADIENT_TOLERANCE),
            ..strict
        };
        let y = rotations
            .iter()
            .map(|r| Block::from_column_slice(r.matrix().as_slice()))
            .collect();
        Ok(Staircase {
            problem,
            certify,
            scope,
            half,
            start,
            strict,
            loose,
            cost: problem.chordal_cost(rotations),
            tolerance: certify.tolerance.resolve(problem.min_weight()),
            y,
            rank: 3,
            iterations: 0,
            products: 0,
            steps: Vec::new(),
        })
    }

    /// The relaxation's value lies in `[bound, F(Y)]`: close enough, a higher rank cannot help.
    fn bracketed(&self, lifted: f64, bound: f64) -> bool {
        lifted - bound
            <= self
                .tolerance
                .allowed_gap(self.cost)
                .max(self.certify.staircase.bracket_tolerance * (self.cost - bound))
    }

    /// A negative Rayleigh quotient from an estimate (matrix-vector products only) is a
    /// direction of descent: escape at once unless the estimated bound already brackets the
    /// relaxation's value.
    fn escapes(&self, e: &CurvatureEstimate, lifted: f64) -> bool {
        e.complement.value < -escape_threshold(lifted, self.problem, self.certify)
            && !self.bracketed(lifted, e.estimated_bound)
    }

    /// One trust-region solve of the current rank from `y`, its work counted.
    fn solve(&mut self, settings: TrustRegionSettings) -> TrustRegionResult {
        let until = self.scope.deadline.instant();
        let mut r = trust_region_until(self.problem, std::mem::take(&mut self.y), &settings, until);
        self.y = std::mem::take(&mut r.y);
        self.iterations += r.iterations;
        self.products += r.hessian_products;
        r
    }

    /// Solve the rank strictly (about to verify), counted in `step`.
    fn solve_strictly(&mut self, step: &mut StaircaseStep) {
        let r = self.solve(self.strict);
        (step.iterations, step.lifted_cost) = (step.iterations + r.iterations, r.cost);
        step.strict = true;
    }

    /// One rank: the loose solve, then the escape or the verification ([`Self::verify`]),
    /// recorded as a step.
    fn climb_rank(&mut self) -> Result<RankEnd> {
        let rank = self.rank;
        crate::progress::phase(crate::progress::Phase::Staircase, || format!("rank {rank}"));
        let r = self.solve(self.loose);
        let mut step = StaircaseStep {
            rank: self.rank,
            iterations: r.iterations,
            strict: self.loose.gradient_tolerance <= self.strict.gradient_tolerance,
            lifted_cost: r.cost,
            estimate: 0.0,
            estimate_residual: 0.0,
            full_estimate: 0.0,
            verified_bound: None,
            seconds: 0.0,
        };
        let (direction, verified) = self.verify(&mut step)?;
        step.seconds = self.start.elapsed().as_secs_f64();
        let lifted = step.lifted_cost;
        self.steps.push(step);
        Ok(RankEnd {
            lifted,
            direction,
            verified,
        })
    }

    /// The escape direction of the current point, or its verification: escape along a
    /// negative estimate ([`Self::escapes`]). Otherwise verify the bound: at once when the
    /// estimated bound brackets the relaxation's value, after solving the rank strictly when it
    /// does not (or when the loose point's verified bound falls short); the verification's
    /// eigenvector decides.
    fn verify(
        &mut self,
        step: &mut StaircaseStep,
    ) -> Result<(Option<Vec<f64>>, Option<VerifiedBound>)> {
        let (problem, certify, scope) = (self.problem, self.certify, self.scope);
        loop {
            let lifted = step.lifted_cost;
            let lambdas = lifted_multipliers(problem, &self.y);
            let e = curvature_estimate(problem, &self.y, &lambdas)?;
            (step.estimate, step.estimate_residual, step.full_estimate) =
                (e.complement.value, e.complement.residual, e.full.value);
            if self.escapes(&e, lifted) {
                return Ok((Some(e.complement.vector), None));
            }
            if !step.strict && !self.bracketed(lifted, e.estimated_bound) {
                // about to verify: converge at this rank first
                self.solve_strictly(step);
                continue;
            }
            let hint = CurvatureHint {
                low: e.full.clone(),
                high: e.optimistic,
            };
            let b = multipliers_bound(problem, &lambdas, certify, scope, Some(hint))?;
            let short = !self.bracketed(lifted, b.lower_bound) && b.negative_eigenvector.is_none();
            if !step.strict && short {
                // the estimate promised more than the loose point's multipliers proved
                self.solve_strictly(step);
                continue;
            }
            let b = if short {
                // short of the bracket with no direction to climb along: the verification's own
                // estimates (shift-invert through its factor) look for one
                multipliers_bound(problem, &lambdas, certify, scope, None)?
            } else {
                b
            };
            step.verified_bound = Some(b.lower_bound);
            return Ok((b.negative_eigenvector.clone(), Some(b)));
        }
    }

    /// Why the staircase stops after a rank, or `None` after escaping to the next rank.
    fn stop_or_escape(&mut self, end: &RankEnd) -> Option<StaircaseStop> {
        if let Some(b) = end
            .verified
            .as_ref()
            .filter(|b| self.bracketed(end.lifted, b.lower_bound))
        {
            return Some(StaircaseStop::Bracketed {
                rank: self.rank,
                bracket: end.lifted - b.lower_bound,
            });
        }
        let estimate = end
            .verified
            .as_ref()
            .and_then(|b| b.min_eigenvalue_estimate)
            .or(self.steps.last().map(|s| s.full_estimate));
        let Some(v) = &end.direction else {
            return Some(StaircaseStop::Verified {
                rank: self.rank,
                min_eigenvalue_estimate: estimate,
            });
        };
        let over_time = self.half.passed();
        let max_rank = self.certify.staircase.max_rank;
        if self.rank >= max_rank || over_time {
            return Some(StaircaseStop::MaxRank {
                max_rank: if over_time { self.rank } else { max_rank },
                min_eigenvalue_estimate: estimate,
            });
        }
        self.rank += 1;
        match escape(self.problem, &self.y, v, end.lifted) {
            Some(next) => {
                self.y = next;
                None
            }
            None => Some(StaircaseStop::EscapeFailed {
                rank: self.rank,
                min_eigenvalue_estimate: estimate,
            }),
        }
    }

    /// The result at the final point: its verified bound (verified now when the last rank
    /// escaped), the certificate of the given estimate and the rounding.
    fn finish(
        self,
        lifted: f64,
        stop_reason: StaircaseStop,
        bound: Option<VerifiedBound>,
    ) -> Result<StaircaseResult> {
        let bound = match bound {
            Some(b) => b,
            None => multipliers_bound(
                self.problem,
                &lifted_multipliers(self.problem, &self.y),
                self.certify,
                self.scope,
                None,
            )?,
        };
        let rank = self.rank;
        let certificate = Certificate::from_bounds(
            self.cost,
            Some(bound.lower_bound),
            BoundMethod::Staircase,
            bound.min_eigenvalue_estimate,
            self.tolerance,
            format!(
                "Riemannian staircase: rank {rank}, lifted cost {lifted:.9e}; {stop_reason}; bound \
                 verified from the lifted multipliers (lambda_min(S) >= {:.3e})",
                bound.verified_min_eigenvalue
            ),
            self.start.elapsed().as_secs_f64(),
        );
        let (rounded, reflected_blocks) = round_lifted_counted(&self.y);
        Ok(StaircaseResult {
            certificate,
            bound,
            rank,
            lifted_cost: lifted,
            iterations: self.iterations,
            hessian_products: self.products,
            stop_reason,
            steps: self.steps,
            rounded,
            reflected_blocks,
        })
    }
}

/// What the staircase estimates of the curvature at a lifted point (estimates: they choose
/// where to escape and where to place the verification's shift; no bound rests on them).
struct CurvatureEstimate {
    /// `lambda_min(S)` on the orthogonal complement of the columns of `Y`, by two-pass Lanczos
    /// (matrix-vector products only), and its vector: a negative value is a direction of
    /// descent whether or not the estimate has converged.
    complement: LanczosResult,
    /// `lambda_min(S)` on the whole space ([`StaircaseStep::full_estimate`]), its residual the
    /// complement's, its vector the complement's.
    full: LanczosResult,
    /// `sum tr(Lambda_i) + 3n min(full, 0)`: the bound a verification would give.
    estimated_bound: f64,
    /// `min(lambda_min(B^T S B), complement)`: Rayleigh quotients, so at least `lambda_min(S)`
    /// (the full estimate, without the coupling, is at most it when the complement's is exact).
    optimistic: f64,
}

/// The curvature of `S = Q - blkdiag(Lambda)` at the lifted point `Y` (`[D11]`). The `p`
/// columns of `Y` (stacked `3n` vectors, orthonormalised to `B`) span the null space of `S` at
/// a critical point: Lanczos runs on their orthogonal complement, where the smallest eigenvalue
/// is the negative curvature the next rank escapes along, not a Ritz value mixing it with the
/// null space's zeros (at 10^4 nodes plain Lanczos returned +1e-4 where the shift-invert
/// estimate found -8e-4). Away from a critical point `B` is only nearly null: the whole-space
/// estimate couples `lambda_min(B^T S B)` to the complement's through `||S B - B (B^T S B)||_F`.
fn curvature_estimate(
    problem: &MultipleProblem,
    y: &[Block],
    lambdas: &[nalgebra::Matrix3<f64>],
) -> Result<CurvatureEstimate> {
    let s = certificate_matrix(problem, lambdas)?;
    let null = null_space_basis(y);
    let complement = complement_estimate(s.as_ref(), &null);
    let (mu, coupling) = null_space_block(s.as_ref(), &null);
    let theta = complement.value;
    let whole = if mu.is_finite() {
        0.5 * (mu + theta) - (0.25 * (theta - mu).powi(2) + coupling * coupling).sqrt()
    } else {
        theta
    };
    // the vector goes with the hint only when it is a direction of negative curvature
    let full = LanczosResult {
        value: whole,
        vector: if complement.value < 0.0 {
            complement.vector.clone()
        } else {
            Vec::new()
        },
        ..complement.clone()
    };
    let estimated_bound =
        lambdas.iter().map(|l| l.trace()).sum::<f64>() + 3.0 * y.len() as f64 * whole.min(0.0);
    Ok(CurvatureEstimate {
        optimistic: mu.min(complement.value),
        complement,
        full,
        estimated_bound,
    })
}

/// `lambda_min(S)` on the orthogonal complement of `null` (orthonormal vectors) and its
/// vector: dense up to [`DENSE_ESTIMATE_DIMENSION`], two-pass Lanczos above; value 0 when the
/// vector is zero.
fn complement_estimate(s: SparseColMatRef<'_, usize, f64>, null: &[Vec<f64>]) -> LanczosResult {
    let norm = inf_norm(s).max(f64::MIN_POSITIVE);
    let dim = s.nrows();
    let mut complement = if dim <= DENSE_ESTIMATE_DIMENSION {
        dense_complement(s, null, norm)
    } else {
        two_pass_smallest(
            dim,
            |x, out| sparse_matvec(s, x, out),
            norm,
            &TwoPassSettings::default(),
            null,
        )
    };
    if complement.vector.iter().all(|x| *x == 0.0) {
        complement.value = 0.0;
    }
    complement
}

/// The complement's estimate for a small `S`: the dense eigenvalues of
/// `P S P + (||S|| + 1) B B^T` (the deflated directions moved above the spectrum), exact.
fn dense_complement(
    s: SparseColMatRef<'_, usize, f64>,
    null: &[Vec<f64>],
    norm: f64,
) -> LanczosResult {
    let dim = s.nrows();
    let mut dense = nalgebra::DMatrix::<f64>::zeros(dim, dim);
    let mut unit = vec![0.0; dim];
    let mut out = vec![0.0; dim];
    for j in 0..dim {
        unit[j] = 1.0;
        sparse_matvec(s, &unit, &mut out);
        unit[j] = 0.0;
        dense.set_column(j, &nalgebra::DVector::from_column_slice(&out));
    }
    let mut proj = nalgebra::DMatrix::<f64>::identity(dim, dim);
    let mut lift = nalgebra::DMatrix::<f64>::zeros(dim, dim);
    for u in null {
        let u = nalgebra::DVector::from_column_slice(u);
        let uu = &u * u.transpose();
        proj -= &uu;
        lift += uu;
    }
    let shifted = &proj * &dense * &proj + (norm + 1.0) * lift;
    let eig = nalgebra::SymmetricEigen::new(0.5 * (&shifted + shifted.transpose()));
    let k = (0..dim)
        .min_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]))
        .unwrap_or(0);
    let vector: Vec<f64> = eig.eigenvectors.column(k).iter().copied().collect();
    let value = if vector.is_empty() {
        0.0
    } else {
        rayleigh_quotient(s, &vector).0
    };
    LanczosResult {
        value,
        vector,
        residual: 0.0,
        iterations: 0,
        stop: LanczosStop::InvariantSubspace { dimension: dim },
    }
}

/// `lambda_min(B^T S B)` (infinite when `B` is empty) and the coupling
/// `||S B - B B^T S B||_F` of the null-space block `B` (`null`) to its complement.
fn null_space_block(s: SparseColMatRef<'_, usize, f64>, null: &[Vec<f64>]) -> (f64, f64) {
    let k = null.len();
    let sb: Vec<Vec<f64>> = null
        .iter()
        .map(|b| {
            let mut out = vec![0.0; b.len()];
            sparse_matvec(s, b, &mut out);
            out
        })
        .collect();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let m = nalgebra::DMatrix::<f64>::from_fn(k, k, |i, j| {
        0.5 * (dot(&null[i], &sb[j]) + dot(&null[j], &sb[i]))
    });
    let mut coupling = 0.0;
    for (j, sbj) in sb.iter().enumerate() {
        let mut r = sbj.clone();
        for (i, bi) in null.iter().enumerate() {
            let c = m[(i, j)];
            r.iter_mut().zip(bi).for_each(|(x, b)| *x -= c * b);
        }
        coupling += dot(&r, &r);
    }
    let mu = if k > 0 {
        m.symmetric_eigenvalues().min()
    } else {
        f64::INFINITY
    };
    (mu, coupling.sqrt())
}

/// An orthonormal basis of the column space of `Y` (blocks `3 x p` stacked into `3n` vectors):
/// `Y^T v_k / sigma_k` for the eigenpairs `(sigma_k^2, v_k)` of `sum_i Y_i^T Y_i` with
/// `sigma_k >= 1e-4 sigma_1`. Directions of smaller singular values are left out: dividing by
/// `sigma_k` would amplify the point's stationarity residual `S Y^T` into a false coupling.
fn null_space_basis(y: &[Block]) -> Vec<Vec<f64>> {
    let p = y.first().map_or(0, |b| b.ncols());
    let mut gram = nalgebra::DMatrix::<f64>::zeros(p, p);
    for b in y {
        gram += b.transpose() * b;
    }
    let eig = nalgebra::SymmetricEigen::new(gram);
    let top = eig.eigenvalues.iter().copied().fold(0.0f64, f64::max);
    (0..p)
        .filter(|&k| eig.eigenvalues[k] >= 1e-8 * top && eig.eigenvalues[k] > 0.0)
        .map(|k| {
            let v = eig.eigenvectors.column(k);
            let sigma = eig.eigenvalues[k].sqrt();
            y.iter()
                .flat_map(|b| {
                    let col = b * v;
                    [col[0] / sigma, col[1] / sigma, col[2] / sigma]
                })
                .collect()
        })
        .collect()
}

/// Up to this dimension of `S` the curvature estimate is a dense eigendecomposition (exact);
/// above it, two-pass Lanczos (a few stored vectors).
const DENSE_ESTIMATE_DIMENSION: usize = 300;

/// The trust-region gradient tolerance (`||grad F|| / (w_min + F)`) at ranks that escape: a point
/// near enough to a critical point for Lanczos to find its direction of negative curvature.
/// Before a verification the rank is solved to [`StaircaseSettings::gradient_tolerance`].
pub const ESCAPE_GRADIENT_TOLERANCE: f64 = 1e-6;

/// A negative eigenvalue estimate below minus this is worth a new rank: a tenth of the
/// tolerance spread over the `3n` coordinates (a smaller one changes the bound
/// `sum tr(Lambda) + 3n lambda_min` by less than that).
fn escape_threshold(cost: f64, problem: &MultipleProblem, certify: &CertifySettings) -> f64 {
    let gap = certify
        .tolerance
        .resolve(problem.min_weight())
        .allowed_gap(cost);
    0.1 * gap / (3 * problem.num_rotations()) as f64
}

/// The saddle escape: a new column `alpha v_i` on every block (`v` the negative eigenvector of
/// `S`, the second-order decrease is about `alpha^2 lambda_min`), retracted, with `alpha` halved
/// from 1 until the lifted cost falls below `f` (40 halvings at most); `None` when it never does.
fn escape(problem: &MultipleProblem, y: &[Block], v: &[f64], f: f64) -> Option<Vec<Block>> {
    let rank = y.first().map_or(3, |b| b.ncols()) + 1;
    let lift = |alpha: f64| -> Option<Vec<Block>> {
        y.iter()
            .enumerate()
            .map(|(i, yi)| {
                let mut b = yi.clone().insert_column(rank - 1, 0.0);
                for a in 0..3 {
                    b[(a, rank - 1)] = alpha * v[3 * i + a];
                }
                polar(&b)
            })
            .collect()
    };
    let mut alpha = 1.0;
    for _ in 0..40 {
        if let Some(c) = lift(alpha)
            && lifted_cost(problem, &c) < f
        {
            return Some(c);
        }
        alpha *= 0.5;
    }
    None
}

#[cfg(test)]
mod tests {
    use crate::certify::settings::StaircaseSettings;

    /// Every setting is validated, the bracket included (0 is allowed: climb while a negative
    /// eigenvector is left).
    #[test]
    fn settings_are_validated() {
        assert!(StaircaseSettings::default().validate().is_ok());
        let zero = StaircaseSettings {
            bracket_tolerance: 0.0,
            ..Default::default()
        };
        assert!(zero.validate().is_ok());
        for bad in [-1e-3, 1.0, f64::NAN, f64::INFINITY] {
            let s = StaircaseSettings {
                bracket_tolerance: bad,
                ..Default::default()
            };
            let e = s.validate().unwrap_err().to_string();
            assert!(e.contains("staircase.bracket_tolerance"), "{e}");
        }
        let low_rank = StaircaseSettings {
            max_rank: 2,
            ..Default::default()
        };
        assert!(low_rank.validate().is_err());
    }
}

/// Seconds per edge and rank predicted for the staircase (its trust-region solves and curvature
/// estimates: measured 0.07 s for a 40-node graph with 20 % outliers; 12.4 s for 3000 nodes and
/// 12,000 edges at ranks 4-9; 108 s for 10^4 nodes and 4x10^4 edges at ranks 4-12).
pub const STAIRCASE_SECONDS_PER_EDGE_RANK: f64 = 2.5e-4;

/// The staircase as a rung of a certification (modes `auto` and `staircase`), once, after the
/// dual certificates of the given estimate and its refinement: a bound from the lifted point's
/// multipliers; its rounding, polished by the local solver, becomes the current point when it
/// is cheaper.
#[derive(Default)]
pub(crate) struct StaircaseRung {
    done: bool,
}

impl<'a> Rung<State<'a>> for StaircaseRung {
    fn proof(&self) -> Proof {
        Proof::Staircase
    }

    fn plan(&mut self, cx: &State<'a>) -> Result<Plan> {
        if self.done {
            return Ok(Plan::Done);
        }
        // mode sdp: only in the place of an SDP refused over the budget
        if cx.settings.mode == CertifyMode::Sdp && !cx.sdp_refused {
            return Ok(Plan::Wait);
        }
        Ok(match cx.escalation() {
            Err(reason) => Plan::Refuse(Refusal::NotApplicable { reason }, None),
            Ok(false) => Plan::Wait,
            Ok(true) => {
                // a few ranks above 3 (Barvinok-Pataki: about sqrt(12 n) at most)
                let ranks = 4.0;
                let seconds =
                    STAIRCASE_SECONDS_PER_EDGE_RANK * cx.problem.num_edges() as f64 * ranks / 4.0;
                Plan::Run(Prediction::new(seconds, 0.0))
            }
        })
    }

    fn attempt(&mut self, cx: &mut State<'a>) -> Result<Found> {
        self.done = true;
        crate::progress::phase(crate::progress::Phase::Staircase, String::new);
        let r = staircase_within(cx.problem, &cx.current.rotations, cx.settings, cx.deadline)?;
        // "verified" only when the proven bound reaches the lifted point's own cost: the stop
        // reason rests on a Lanczos estimate, which misses a negative eigenvector orthogonal to
        // its start (a 3-cycle with loop angle pi: lifted cost 7 at rank 4, estimate -2e-16,
        // proven bound -1, while the SDP certifies 6), and then the SDP must still run; a
        // bracketed stop rests on the proven bound and the lifted cost alone: the SDP could
        // raise the bound by at most `staircase.bracket_tolerance` of the gap
        let verified = match r.stop_reason {
            StaircaseStop::Verified { .. } => {
                r.lifted_cost - r.bound.lower_bound <= cx.allowed_gap(r.lifted_cost)
            }
            StaircaseStop::Bracketed { .. } => true,
            _ => false,
        };
        cx.staircase_verified = Some(verified);
        cx.log.extend(r.bound.ladder.iter().cloned());
        cx.staircase_steps.extend(r.steps.iter().cloned());
        let lower_bound = r.bound.lower_bound;
        cx.offer(Best {
            lower_bound,
            method: BoundMethod::Staircase,
            point: Point::Staircase,
            min_eigenvalue: r
                .bound
                .min_eigenvalue_estimate
                .or(Some(r.bound.verified_min_eigenvalue)),
            explanation: r.certificate.explanation.clone(),
            verified_min_eigenvalue: r.bound.verified_min_eigenvalue,
            shift: r.bound.shift,
            lambdas: None,
        });
        let polished = polish(cx.problem, &r.rounded, &cx.deadline);
        let note = staircase_note(&r, polished.as_ref().map(|p| p.chordal_cost));
        let sufficient = cx.certifies(lower_bound);
        // its rounding, polished, becomes the current point when cheaper (then certified by
        // the dual rung, unless the staircase was verified: the rounding's own dual certificate
        // cannot beat it)
        if let Some(p) = polished
            && p.chordal_cost < cx.current.cost
        {
            cx.adopt(p, ImprovementSource::StaircaseRounding, Point::Staircase);
        }
        Ok(Found::proved(lower_bound, sufficient, note))
    }
}

/// `rounded` polished by the local solver (chordal), when it is a whole estimate, within the
/// certification's time left (`deadline`).
pub(crate) fn polish(
    problem: &MultipleProblem,
    rounded: &[Rotation],
    deadline: &Deadline,
) -> Option<MultipleSolution> {
    let local = MultipleSettings {
        init: Initialisation::Given(rounded.to_vec()),
        max_seconds: deadline.left().map(|l| l.max(0.0)),
        ..Default::default()
    };
    (rounded.len() == problem.num_rotations())
        .then(|| solve_multiple(problem, &local).ok())
        .flatten()
}

/// What the staircase did, in words.
fn staircase_note(r: &StaircaseResult, polished_cost: Option<f64>) -> String {
    format!(
        "Riemannian staircase: rank {}, {} iterations, lifted cost {:.9e}; {}{}{}",
        r.rank,
        r.iterations,
        r.lifted_cost,
        r.stop_reason,
        polished_cost
            .map(|c| format!("; rounding polished to {c:.9e}"))
            .unwrap_or_default(),
        match r.reflected_blocks {
            0 => String::new(),
            k => format!(
                "; {k} of {} blocks of the rounding are reflections (det < 0): the O(3) \
                 relaxation prefers them, so its bound can lie below every rotation estimate",
                r.rounded.len()
            ),
        }
    )
}
