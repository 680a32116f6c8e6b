//! Verifying a lower bound from multipliers `Lambda`: the ladder of proofs that
//! `S = Q - blkdiag(Lambda)` is (nearly) positive semidefinite (`paper-notes/certificates.md`
//! `[D4]`-`[D8]`, `[D12]`, `[D13]`, `[D15]`, `[D16]`; the ladder: [`crate::certify::ladder`]).
//!
//! The rungs are the grounded bound `[D15]` ([`super::grounded`]), the shifted Cholesky
//! factorisation of `S` `[D5]` (`shifted.rs`) and the scalar comparison `[D13]` on the
//! whole graph, a subgraph or a split (`scalar/rungs.rs`). Each predicts its time and
//! memory from the problem; those that fit the [`crate::certify::Budget`] run in the order of
//! their predicted time (the strongest first when all are cheap), and the first whose bound
//! leaves at least half of the tolerance for the rest of the gap ends the climb. When none
//! proves anything, Gershgorin's discs `[D8]` give the (weak, valid) bound; when none could even
//! start (every factorisation over the budget), no bound is claimed and the randomized test
//! `[D16]` reports a labelled estimate beside the `inconclusive` verdict.

use super::grounded::{GroundedBound, GroundedProof};
use super::multipliers::{
    bound_from_mu, bound_with_deficit, certificate_matrix, entry_terms, forming_margin,
};
use super::randomized::{ComplementEstimate, RandomizedBound, over_budget_estimates};
use super::scalar::ScalarComparison;
use super::scalar::rungs::ScalarFamily;
use super::shifted::ShiftedProof;
use crate::certify::ladder::{Attempt, Outcome, Point, Prediction, Refusal, Rung};
use crate::certify::settings::{CertifySettings, DualProof};
use crate::error::Result;
use crate::linalg::{LanczosResult, gamma, gershgorin_lower_bound, inf_norm};
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use faer::sparse::SparseColMat;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::cell::RefCell;
use std::time::Instant;

/// Stored values of the `3n` supernodal factor per value of the scalar one, for the time
/// predicted before its own analysis (measured 20 on a 15k-node grid, 2026-11-26: 2.4e6 against
/// 1.2e5; the block structure alone gives 9).
pub const THREE_N_PER_SCALAR_VALUE: f64 = 20.0;

/// Multiply-adds of the `3n` factorisation per counted multiply-add of the scalar one
/// ([`crate::linalg::cholesky::factor_multiply_adds`]): every supernode of `k` columns and `r`
/// rows below becomes one of `3k` and `3r`, and each term of the count is cubic.
pub const THREE_N_PER_SCALAR_MULTIPLY_ADD: f64 = 27.0;

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
    /// The grounded bound `[D15]`: the gauge null space deflated by removing one node's block;
    /// `S` without it verified positive definite by a sparse Cholesky factorisation.
    Grounded,
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
    /// Numeric factorisations attempted (all rungs).
    pub factorizations: usize,
    /// Stored values of the factor of the proof that gave the bound (fill indicator).
    pub factor_nonzeros: usize,
    /// The scalar comparison's quantities, when `verification` is `ScalarComparison` `[D13]`
    /// (among them how many edges its factorised subgraph dropped).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scalar_comparison: Option<ScalarComparison>,
    /// `true` when nothing was proved and a proof was kept out by the budget (then no lower
    /// bound is claimed: the verdict is `inconclusive` with [`VerifiedBound::budget_exceeded`]).
    pub factorization_skipped: bool,
    /// The grounded bound's quantities, when `verification` is `Grounded` `[D15]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub grounded: Option<GroundedBound>,
    /// The estimate is too far from a critical point for a bound within the tolerance (its
    /// stationarity residual `rho` against the largest possible curvature `c`, `[D15]`).
    #[serde(default)]
    pub not_critical: bool,
    /// Why no proof was tried when none fitted the budget ([`crate::certify::Budget`]); the
    /// bound is then Gershgorin's, and no lower bound is claimed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub budget_exceeded: Option<String>,
    /// When no proof fit the budget and the rotations were known: the estimate of
    /// `lambda_min(S)` on the complement of the gauge directions (never a proof).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub complement_estimate: Option<ComplementEstimate>,
    /// When no proof fit the budget: the randomized Chebyshev test `[D16]` on the complement
    /// of the gauge directions (a Monte Carlo bound, never a proof).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub randomized: Option<RandomizedBound>,
    /// Every rung of the ladder this verification considered, in order, with its prediction
    /// and outcome ([`crate::certify::ladder`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ladder: Vec<Attempt>,
}

impl VerifiedBound {
    /// A bound from a proven `mu <= lambda_min(S)` by `verification` `[D4]`, with nothing else
    /// known yet.
    pub(super) fn from_mu(cx: &Check<'_>, mu: f64, verification: Verification) -> Self {
        VerifiedBound {
            lower_bound: bound_from_mu(cx.problem, cx.lambdas, mu),
            trace: cx.lambdas.iter().map(|l| l.trace()).sum(),
            verified_min_eigenvalue: mu,
            verification,
            shift: None,
            fp_margin: 0.0,
            min_eigenvalue_estimate: None,
            estimate_residual: None,
            negative_eigenvector: None,
            lanczos_iterations: 0,
            factorizations: 0,
            factor_nonzeros: 0,
            scalar_comparison: None,
            factorization_skipped: false,
            grounded: None,
            not_critical: false,
            budget_exceeded: None,
            complement_estimate: None,
            randomized: None,
            ladder: Vec::new(),
        }
    }
}

/// What the rungs of one verification share: the data, `S`, the gap the verdict allows, and
/// the estimates the rungs leave for the diagnosis (never part of a bound).
pub(super) struct Check<'a> {
    pub problem: &'a MultipleProblem,
    pub lambdas: &'a [Matrix3<f64>],
    /// The estimate whose multipliers these are, when known (the scalar comparison and the
    /// grounded bound need it).
    pub rotations: Option<&'a [Rotation]>,
    /// `S = Q - blkdiag(sym Lambda)`, as stored.
    pub s: SparseColMat<usize, f64>,
    /// `||S||_inf`.
    pub norm: f64,
    /// Rounded operations that formed an entry of `S` (the forming error `[D6]`(b)).
    pub terms: usize,
    /// The further forming error of anisotropic blocks `[A3]` ([`forming_margin`]; 0 for
    /// isotropic data): subtracted from every proven `lambda_min`.
    pub forming: f64,
    /// The gap the verdict allows at the cost: the tolerance.
    pub gap: f64,
    pub settings: &'a CertifySettings,
    pub point: Point,
    /// Estimates of `lambda_min(S)` made before the verification (the staircase's): the
    /// shifted Cholesky rung places its shift from them instead of estimating again. Estimates
    /// only: the shift they suggest is still proved by a factorisation.
    pub hint: Option<CurvatureHint>,
    started: Instant,
    shared: RefCell<Shared>,
    /// Every rung considered so far, in order.
    log: RefCell<Vec<Attempt>>,
    /// The estimates the rungs found on the way.
    notes: RefCell<Notes>,
}

/// Estimates of `lambda_min(S)` handed to a verification ([`Check::hint`]).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct CurvatureHint {
    /// A pessimistic estimate (value; `residual` as its uncertainty; a direction of negative
    /// curvature when one is known): the shift above it is expected to verify.
    pub low: LanczosResult,
    /// An optimistic estimate (a Rayleigh quotient, at least `lambda_min`): the first shift
    /// `delta_0` is skipped only when this too is clearly below `-delta_0`.
    pub high: f64,
}

/// What one rung's prediction tells another's.
#[derive(Default)]
struct Shared {
    /// The `3n` factorisations (of `S` and of `S_{-g}`, one block row and column apart) are
    /// over the budget: the second is not analysed again (its analysis alone costs seconds on
    /// 10^6 nodes).
    three_n_refused: Option<Refusal>,
    /// The ordering's prediction of the whole graph's scalar factor `[D13]`: the `3n` factor of
    /// the same graph holds about 9 times as many values.
    scalar_values: Option<usize>,
    /// The counted multiply-adds of the whole graph's scalar factor, when it was analysed: the
    /// `3n` factor of the same graph (3 x 3 blocks, every front three times as wide) takes
    /// about 27 times as many.
    scalar_multiply_adds: Option<f64>,
    /// A cheap test found the estimate too far from a critical point for any rung.
    not_critical: bool,
}

/// Estimates the rungs found on the way (for the diagnosis and the staircase; never bounds).
#[derive(Default)]
pub(super) struct Notes {
    pub estimate: Option<LanczosResult>,
    pub lanczos_iterations: usize,
    pub factorizations: usize,
    pub not_critical: bool,
    /// Why a rung proved nothing without trying (e.g. the estimate predicts a bound below 0).
    pub skipped: Option<String>,
}

/// One rung of the verification.
pub(super) trait Proof {
    /// Which proof (for the report).
    fn rung(&self) -> Rung;
    /// Its predicted cost (after the analyses it needs, kept for the attempt), or why it does
    /// not start. `Err` only for errors of the caller's data.
    fn predict(&mut self, cx: &Check<'_>) -> Result<std::result::Result<Prediction, Refusal>>;
    /// Run it, logging what it tried ([`Check::log`]; a family of shapes logs each); `Some`
    /// with a verified bound, `None` when it proved nothing.
    fn attempt(&mut self, cx: &Check<'_>) -> Result<Option<VerifiedBound>>;
}

impl<'a> Check<'a> {
    /// The verification of `lambdas` (of the estimate `rotations`, when known) for a cost
    /// `scale` (whose tolerance is the gap budget); `point` labels the log.
    pub fn new(
        problem: &'a MultipleProblem,
        lambdas: &'a [Matrix3<f64>],
        rotations: Option<&'a [Rotation]>,
        scale: f64,
        settings: &'a CertifySettings,
        point: Point,
    ) -> Result<Self> {
        let s = certificate_matrix(problem, lambdas)?;
        let norm = inf_norm(s.as_ref()).max(f64::MIN_POSITIVE);
        Ok(Check {
            problem,
            lambdas,
            rotations,
            s,
            norm,
            terms: entry_terms(problem),
            forming: forming_margin(problem, lambdas),
            gap: settings
                .tolerance
                .resolve(problem.min_weight())
                .allowed_gap(scale),
            settings,
            point,
            hint: None,
            started: Instant::now(),
            shared: RefCell::new(Shared::default()),
            log: RefCell::new(Vec::new()),
            notes: RefCell::new(Notes::default()),
        })
    }
}

impl Check<'_> {
    /// The time left of the budget, seconds (`None`: no limit).
    pub fn seconds_left(&self) -> Option<f64> {
        self.settings
            .budget
            .max_seconds
            .map(|limit| limit - self.started.elapsed().as_secs_f64())
    }

    /// Record that the `3n` factorisations do not fit (`refusal`).
    pub fn note_three_n_refused(&self, refusal: &Refusal) {
        self.shared.borrow_mut().three_n_refused = Some(refusal.clone());
    }

    /// Record the ordering's prediction of the whole graph's scalar factor, and its counted
    /// multiply-adds when it was analysed.
    pub fn note_scalar_values(&self, values: usize, multiply_adds: Option<f64>) {
        let mut shared = self.shared.borrow_mut();
        shared.scalar_values = Some(values);
        shared.scalar_multiply_adds = multiply_adds;
    }

    /// Record that the estimate is not a critical point.
    pub fn mark_not_critical(&self) {
        self.shared.borrow_mut().not_critical = true;
    }

    /// The prediction of a `dim x dim` factorisation of the `3n` family (`factorisations` of
    /// them) before its own analysis, from the whole graph's scalar factor of `v` values (the
    /// same graph's `3 x 3` blocks), or why it does not start: the other one was refused, or
    /// even `9 v` values (the blocks of the scalar factor, a lower estimate) are over the
    /// budget. The time is predicted for [`THREE_N_PER_SCALAR_VALUE`]` v` values (supernodal
    /// storage). `None` when nothing is known yet (the scalar comparison is not on the ladder):
    /// the rung analyses its own matrix.
    pub fn three_n_predicted(
        &self,
        dim: usize,
        factorisations: f64,
    ) -> Option<std::result::Result<Prediction, Refusal>> {
        let shared = self.shared.borrow();
        if let Some(r) = &shared.three_n_refused {
            return Some(Err(r.clone()));
        }
        let v = shared.scalar_values?;
        let blocks = v.saturating_mul(9).saturating_sub(dim);
        if let Some(Refusal::OverBudget { reason }) = ordering_refusal(self.settings, blocks, dim) {
            let reason = format!("at least 9 x the scalar factor: {reason}");
            return Some(Err(Refusal::OverBudget { reason }));
        }
        let typical = (v as f64 * THREE_N_PER_SCALAR_VALUE) as usize;
        let one = match shared.scalar_multiply_adds {
            Some(m) => crate::certify::Budget::predicted_factor_seconds(
                THREE_N_PER_SCALAR_MULTIPLY_ADD * m + per_value_multiply_adds(typical),
                typical,
            ),
            None => crate::certify::Budget::predicted_seconds(typical, dim),
        };
        Some(Ok(Prediction {
            seconds: factorisations * one,
            bytes: crate::certify::Budget::factorisation_bytes(typical),
        }))
    }

    /// The bound with no deficit: what a perfect proof would give.
    fn ceiling(&self) -> f64 {
        bound_with_deficit(self.problem, self.lambdas, 0.0)
    }

    /// `bound` leaves at least half of the tolerance for the rest of the gap: the climb stops.
    pub fn sufficient(&self, bound: &VerifiedBound) -> bool {
        self.ceiling() - bound.lower_bound <= 0.5 * self.gap
    }

    /// Log one rung: `rung` at this point, started at `since`.
    pub fn log(&self, rung: Rung, predicted: Option<Prediction>, outcome: Outcome, since: Instant) {
        let attempt = self.record(rung, predicted, outcome, since);
        self.log.borrow_mut().push(attempt);
    }

    /// The estimates the rungs leave (for the diagnosis).
    pub fn notes(&self) -> std::cell::RefMut<'_, Notes> {
        self.notes.borrow_mut()
    }

    /// The refusal of a rung predicted to need more than the time left of the budget.
    pub fn time_refusal(&self, predicted: &Prediction) -> Option<Refusal> {
        let left = self.seconds_left()?;
        (predicted.seconds > left).then(|| Refusal::OverBudget {
            reason: format!(
                "predicted {:.1} s, {:.1} s of the time budget left",
                predicted.seconds,
                left.max(0.0)
            ),
        })
    }

    /// The log entry of `rung`, started at `since`.
    pub fn record(
        &self,
        rung: Rung,
        predicted: Option<Prediction>,
        outcome: Outcome,
        since: Instant,
    ) -> Attempt {
        Attempt {
            rung,
            point: self.point,
            predicted,
            outcome,
            seconds: since.elapsed().as_secs_f64(),
        }
    }

    /// The outcome of a rung that returned `bound`.
    pub fn proved(&self, bound: &VerifiedBound) -> Outcome {
        Outcome::Proved {
            lower_bound: bound.lower_bound,
            sufficient: self.sufficient(bound),
        }
    }
}

/// A verified lower bound on the global minimum of the chordal cost from *any* multipliers
/// `Lambda` (symmetrised) `[D4]`: `sum tr(Lambda_i) + 3n min(mu, 0)`, where `mu` is a
/// verified lower bound on `lambda_min(Q - blkdiag(Lambda))` (sparse Cholesky `[D5]` with
/// the floating-point margin `[D6]`; Gershgorin `[D8]` as the fallback). Use this to verify
/// an SDP solver's multipliers: never its reported objective.
///
/// ```
/// use rotavg::certify::multiple::lower_bound_from_multipliers;
/// use rotavg::certify::CertifySettings;
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
    multipliers_bound(problem, lambdas, settings, Point::Sdp, None)
}

/// [`lower_bound_from_multipliers`] with `point` labelling the ladder (the SDP's multipliers, the
/// staircase's) and, when known, an estimate of `lambda_min(S)` for the shifts.
pub(super) fn multipliers_bound(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    settings: &CertifySettings,
    point: Point,
    hint: Option<CurvatureHint>,
) -> Result<VerifiedBound> {
    let trace: f64 = lambdas.iter().map(|l| l.trace()).sum();
    verify(problem, lambdas, None, trace.abs(), settings, point, hint)
}

/// Climb the ladder for `lambdas` (and the estimate `rotations` they belong to, when known):
/// `scale` is the cost whose tolerance is the gap budget; `point` labels the log.
pub(super) fn verify(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    rotations: Option<&[Rotation]>,
    scale: f64,
    settings: &CertifySettings,
    point: Point,
    hint: Option<CurvatureHint>,
) -> Result<VerifiedBound> {
    let mut cx = Check::new(problem, lambdas, rotations, scale, settings, point)?;
    cx.hint = hint;
    // predicted in this order: the scalar analysis (n x n) first, so that the 3n ones can be
    // refused from it without their own ordering; climbed in the order of their predictions
    let mut rungs: Vec<Box<dyn Proof>> = Vec::new();
    let enabled = |p: DualProof| settings.dual.proofs.contains(&p);
    if enabled(DualProof::ScalarComparison) {
        rungs.push(Box::new(ScalarFamily::default()));
    }
    if enabled(DualProof::Grounded) {
        rungs.push(Box::new(GroundedProof::default()));
    }
    if enabled(DualProof::ShiftedCholesky) {
        rungs.push(Box::new(ShiftedProof::default()));
    }
    let planned = plan(&cx, &mut rungs)?;
    let mut best: Option<VerifiedBound> = None;
    let mut ran = false;
    for (k, predicted) in planned {
        let since = Instant::now();
        let rung = rungs[k].rung();
        if best.as_ref().is_some_and(|b| cx.sufficient(b)) {
            cx.log(
                rung,
                Some(predicted),
                Outcome::Refused(Refusal::NotNeeded),
                since,
            );
            continue;
        }
        if let Some(refusal) = cx.time_refusal(&predicted).filter(|_| ran) {
            cx.log(rung, Some(predicted), Outcome::Refused(refusal), since);
            continue;
        }
        ran = true;
        if let Some(b) = rungs[k].attempt(&cx)?
            && best.as_ref().is_none_or(|x| b.lower_bound > x.lower_bound)
        {
            best = Some(b);
        }
    }
    let refused = cx.log.borrow().iter().any(over_budget);
    Ok(finish(&cx, best, !ran || refused))
}

/// Predict every rung; the refused ones are logged, the others returned (index, prediction) in
/// the order of the climb: predicted time, the strongest first among the cheap ones.
fn plan(cx: &Check<'_>, rungs: &mut [Box<dyn Proof>]) -> Result<Vec<(usize, Prediction)>> {
    let mut planned = Vec::new();
    for (k, r) in rungs.iter_mut().enumerate() {
        let since = Instant::now();
        match r.predict(cx)? {
            Ok(p) => planned.push((k, p)),
            Err(refusal) => cx.log(r.rung(), None, Outcome::Refused(refusal), since),
        }
    }
    planned.sort_by(|(a, p), (b, q)| {
        p.order_key().total_cmp(&q.order_key()).then(
            rungs[*a]
                .rung()
                .strength()
                .cmp(&rungs[*b].rung().strength()),
        )
    });
    Ok(planned)
}

/// A rung refused over the budget.
fn over_budget(a: &Attempt) -> bool {
    matches!(a.outcome, Outcome::Refused(Refusal::OverBudget { .. }))
}

/// The verified bound: the best proof's, with the estimates of the climb; or, when nothing was
/// proved, Gershgorin's. That is claimed only when no proof was kept out by the budget (then
/// the rungs that ran say the matrix is not provably PSD); otherwise (`budget_limited`) no
/// lower bound is claimed: the budget's reasons and the labelled estimates `[D7]`, `[D16]`.
fn finish(cx: &Check<'_>, best: Option<VerifiedBound>, budget_limited: bool) -> VerifiedBound {
    let mut bound = match best {
        Some(b) => b,
        None => {
            let since = Instant::now();
            let gersh = gershgorin_lower_bound(cx.s.as_ref())
                - 2.0 * gamma(cx.terms + 1) * cx.norm
                - cx.forming;
            let mut b = VerifiedBound::from_mu(cx, gersh, Verification::Gershgorin);
            if budget_limited {
                b.factorization_skipped = true;
                b.budget_exceeded = Some(refusals(&cx.log.borrow()));
            } else {
                cx.log(Rung::Gershgorin, None, cx.proved(&b), since);
            }
            if budget_limited && let Some(rs) = cx.rotations {
                let since = Instant::now();
                let (complement, randomized) = over_budget_estimates(cx, rs);
                let outcome = match randomized.as_ref().and_then(|r| r.lower_bound) {
                    Some(lower_bound) => Outcome::Estimated {
                        lower_bound,
                        failure_probability: cx.settings.dual.randomized.failure_probability,
                    },
                    None => Outcome::Failed {
                        reason: randomized.as_ref().map_or_else(
                            || "not run (no converged positive estimate to test)".into(),
                            |r| r.to_string(),
                        ),
                    },
                };
                cx.log(Rung::Randomized, None, outcome, since);
                b.min_eigenvalue_estimate =
                    Some(complement.value.min(complement.gauge_rayleigh_quotient));
                b.estimate_residual = Some(complement.residual);
                b.lanczos_iterations += complement.iterations;
                b.complement_estimate = Some(complement);
                b.randomized = randomized;
            }
            b
        }
    };
    let notes = cx.notes.take();
    if let Some(e) = notes.estimate {
        if bound.min_eigenvalue_estimate.is_none() {
            bound.min_eigenvalue_estimate = Some(e.value);
            bound.estimate_residual = Some(e.residual);
        }
        bound.negative_eigenvector =
            (e.value < 0.0 && e.value < -first_shift(cx) && !e.vector.is_empty())
                .then_some(e.vector);
    }
    bound.lanczos_iterations += notes.lanczos_iterations;
    bound.factorizations = bound.factorizations.max(notes.factorizations);
    bound.not_critical |= notes.not_critical || cx.shared.borrow().not_critical;
    bound.ladder = cx.log.take();
    bound
}

/// The shifts of `[D5]` start at this: a verified `lambda_min >= -delta_0` costs a fraction
/// `dual.shift_budget_fraction` of the gap budget.
pub(super) fn first_shift(cx: &Check<'_>) -> f64 {
    cx.settings.dual.shift_budget_fraction * cx.gap / cx.s.nrows().max(1) as f64
}

/// The budget's reasons of the rungs refused over it, joined (the `inconclusive` reason).
fn refusals(log: &[Attempt]) -> String {
    let reasons: Vec<String> = log
        .iter()
        .filter_map(|a| match &a.outcome {
            Outcome::Refused(Refusal::OverBudget { reason }) => {
                Some(format!("{}: {reason}", a.rung))
            }
            Outcome::Failed { reason } => Some(format!("{}: {reason}", a.rung)),
            _ => None,
        })
        .collect();
    if reasons.is_empty() {
        "no proof fits the budget".into()
    } else {
        reasons.join("; ")
    }
}

/// The refusal of a factor of `factor_nonzeros` values over `dual.max_factor_nonzeros`.
pub(super) fn over_factor_cap(
    settings: &CertifySettings,
    factor_nonzeros: usize,
) -> Option<Refusal> {
    let cap = settings.dual.max_factor_nonzeros;
    (factor_nonzeros > cap).then(|| Refusal::OverBudget {
        reason: format!(
            "the proof would need a factor of {factor_nonzeros:.1e} values; limit \
             dual.max_factor_nonzeros = {cap:.1e}"
        ),
    })
}

/// Why `factorisations` factorisations of an analysed matrix (`factor_nonzeros` stored values,
/// `scratch_values` of numeric scratch, `multiply_adds` counted multiply-adds each,
/// [`crate::linalg::cholesky::factor_multiply_adds`]) do not start: over the
/// [`crate::certify::Budget`] or over `dual.max_factor_nonzeros`; their prediction otherwise
/// ([`crate::certify::Budget::counted_factorisations_fit`], the model of the scalar comparison:
/// the `values^2 / dim` model predicted 329 s for a 3n Cholesky of a 10^4-node random graph with
/// 20 % outliers that took 12 s).
pub(super) fn counted_factorisation_prediction(
    settings: &CertifySettings,
    factor_nonzeros: usize,
    scratch_values: usize,
    multiply_adds: f64,
    factorisations: f64,
) -> std::result::Result<Prediction, Refusal> {
    let values = factor_nonzeros.saturating_add(scratch_values);
    let total = (values as f64 * factorisations) as usize;
    let multiply_adds = multiply_adds + per_value_multiply_adds(values);
    if let Err(reason) =
        settings
            .budget
            .counted_factorisations_fit(values, factorisations * multiply_adds, total)
    {
        return Err(Refusal::OverBudget { reason });
    }
    if let Some(refusal) = over_factor_cap(settings, factor_nonzeros) {
        return Err(refusal);
    }
    Ok(Prediction {
        seconds: crate::certify::Budget::predicted_factor_seconds(
            factorisations * multiply_adds,
            total,
        ),
        bytes: crate::certify::Budget::factorisation_bytes(values),
    })
}

/// The per-value cost of a `3n` Cholesky factor of `values` values, as multiply-adds: the 3n
/// Cholesky of sparse grids and chains is mostly per value (measured 4.9 s for 1.88e8 values on
/// a 10^6-node grid), so it is charged at the dense model's 3e-8 s per value, the counted
/// model's 1e-8 s plus this difference.
fn per_value_multiply_adds(values: usize) -> f64 {
    use crate::certify::settings::{
        PREDICTED_MULTIPLY_ADD_RATE, PREDICTED_SECONDS_PER_COUNTED_VALUE,
        PREDICTED_SECONDS_PER_FACTOR_VALUE,
    };
    (PREDICTED_SECONDS_PER_FACTOR_VALUE - PREDICTED_SECONDS_PER_COUNTED_VALUE)
        * PREDICTED_MULTIPLY_ADD_RATE
        * values as f64
}

/// Why a factorisation of a `dim x dim` matrix whose factor is predicted (by the ordering, before
/// any symbolic analysis) to hold `factor_nonzeros` values does not start: over the
/// [`crate::certify::Budget`] (`values^2 / dim` time model) or over `dual.max_factor_nonzeros`.
pub(super) fn ordering_refusal(
    settings: &CertifySettings,
    factor_nonzeros: usize,
    dim: usize,
) -> Option<Refusal> {
    if let Err(reason) = settings.budget.factorisation_fits(factor_nonzeros, dim) {
        return Some(Refusal::OverBudget { reason });
    }
    over_factor_cap(settings, factor_nonzeros)
}
