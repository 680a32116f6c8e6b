//! The state of one verification of multipliers `Lambda` (`paper-notes/certificates.md`
//! `[D4]`-`[D8]`, `[D13]`, `[D15]`): the certificate matrix `S = Q - blkdiag(Lambda)`, the gap the
//! verdict allows, the one clock, the analyses the checks share (each computed once, whichever
//! check asks first), the best verified bound and the log. The checks are the rungs of its
//! climb ([`super::verify`]).

use super::multipliers::{
    FirstOrder, GaugeTerms, TraceBound, certificate_diagonal_blocks, check_lambdas,
    checked_certificate_matrix, entry_terms, forming_margins, gauge_terms,
};
use super::scalar::{SPARSIFIED_EDGES_PER_NODE, ScalarAnalysis, subgraph_regions};
use super::verified::VerifiedBound;
use crate::certify::budget::{Budget, Deadline};
use crate::certify::log::{Attempt, Outcome, Point, Prediction, Refusal};
use crate::certify::proof::Proof;
use crate::certify::rung::{Climb, Plan};
use crate::certify::settings::CertifySettings;
use crate::error::Result;
use crate::linalg::{LanczosResult, inf_norm};
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use faer::sparse::SparseColMat;
use nalgebra::Matrix3;
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

/// Where a verification runs: which point's multipliers, inside which proof, on which clock.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Scope {
    /// The point the multipliers belong to (the log's `point`).
    pub point: Point,
    /// The proof whose multipliers are verified (the log's `within`).
    pub within: Proof,
    /// The certification's clock.
    pub deadline: Deadline,
    /// The predicted seconds of a dual certificate at the point, when its refinement and the
    /// refined point's certificate follow a finding that the point is not a critical point
    /// (the given estimate in the multiple ladder). The checks of `lambda_min(S)` predicted to
    /// cost more than that and more than `DualSettings::give_way_above_seconds` then refuse
    /// ([`Check::cut_by_not_critical`]): the refinement is what certifies such a point (issue
    /// 35: a 10^6-node lattice spent 15 s on a shifted Cholesky that proved too little there).
    /// Cheaper checks still run: at a point only slightly off critical the shifted Cholesky
    /// often certifies it (a perturbed sphere2500 optimum: 20 ms, against 50 ms for the
    /// refinement).
    pub refinement_follows: Option<f64>,
}

/// What the checks of one verification share: the data, `S`, the gap the verdict allows, the
/// clock, the analyses computed once, the best bound and the log.
pub(crate) struct Check<'a> {
    pub problem: &'a MultipleProblem,
    pub lambdas: &'a [Matrix3<f64>],
    /// The estimate whose multipliers these are, when known (the scalar comparison and the
    /// grounded bound need it).
    pub rotations: Option<&'a [Rotation]>,
    /// `S = Q - blkdiag(sym Lambda)`, as stored, and `||S||_inf`: made when a rung first asks
    /// ([`Self::s`], [`Self::norm`]; the block comparison never does, 0.08 s and 30 MB at 10^4
    /// cameras and 10^5 edges).
    s: std::cell::OnceCell<(SparseColMat<usize, f64>, f64)>,
    /// Rounded operations that formed an entry of `S` (the forming error `[D6]`(b)).
    pub terms: usize,
    /// The further forming error of anisotropic blocks `[A3]` (`forming_margin`; 0 for
    /// isotropic data): subtracted from every proven `lambda_min`.
    pub forming: f64,
    /// The same by rows (`[D6]` (3)): three times the sum of the per-node margins of `[A3]`,
    /// the trace of a diagonal majorant of that error (0 for isotropic data).
    pub forming_sum: f64,
    /// The gap the verdict allows at the cost: the tolerance.
    pub gap: f64,
    pub settings: &'a CertifySettings,
    pub point: Point,
    /// The proof whose multipliers are verified (the log's `within`).
    pub within: Proof,
    /// [`Scope::refinement_follows`].
    pub refinement_follows: Option<f64>,
    /// Estimates of `lambda_min(S)` made before the verification (the staircase's): the
    /// shifted Cholesky rung places its shift from them instead of estimating again. Estimates
    /// only: the shift they suggest is still proved by a factorisation.
    pub hint: Option<CurvatureHint>,
    /// The certification's clock.
    pub deadline: Deadline,
    /// The whole graph's scalar analysis `[D13]` (the factor, or the ordering's predicted size
    /// when over the budget; `None` inside when the scalar comparison is not on the ladder),
    /// made when the check is created, or, on dense graphs ([`defers_the_whole`]), when first
    /// asked ([`Self::scalar`]): the scalar rung runs it, the `3n` rungs predict from it (no
    /// `3n` analysis then).
    scalar: std::cell::OnceCell<Option<std::result::Result<ScalarAnalysis, usize>>>,
    /// On dense graphs, the sparsest subgraph's analysis, made instead of the whole graph's
    /// (handed to the scalar rung, [`Self::take_deferred`]), and its factor's size (a lower
    /// estimate of the whole graph's, for the `3n` rungs' budget).
    deferred: RefCell<Option<ScalarAnalysis>>,
    deferred_values: Option<usize>,
    /// The regions the subgraphs are grouped in ([`subgraph_regions`]), made once.
    regions: std::cell::OnceCell<Option<Vec<usize>>>,
    /// The deferred subgraph's family has not finished: the `3n` rungs wait for it
    /// ([`Self::three_n_waits`]) rather than analyse the whole graph to predict themselves.
    deferred_open: std::cell::Cell<bool>,
    /// The length of the log when the block comparison's family planned its first attempt
    /// ([`Self::block_runs_first`]): the `3n` rungs wait while nothing was logged since.
    block_first: std::cell::Cell<Option<usize>>,
    /// The `3n` factorisations (of `S` and of `S_{-g}`, one block row and column apart) are
    /// over the budget (found by whichever analysed first): the other is not analysed again.
    three_n_refused: RefCell<Option<Refusal>>,
    /// The first-order quantities of the estimate, when the multipliers are its own (their
    /// gauge terms are made once for every check that needs them).
    pub first: Option<&'a FirstOrder>,
    /// The gauge terms when there is no `first`, made on the first request.
    gauge: std::cell::OnceCell<GaugeTerms>,
    /// The terms every bound from these multipliers shares, made once.
    trace_bound: std::cell::OnceCell<TraceBound>,
    /// The best verified bound so far.
    pub best: Option<VerifiedBound>,
    /// Gershgorin's bound when a check was kept out by the budget: reported, never claimed.
    pub unclaimed: Option<VerifiedBound>,
    /// The estimates the rungs found on the way.
    notes: RefCell<Notes>,
    /// Every rung considered so far, in order.
    log: RefCell<Vec<Attempt>>,
}

/// Estimates of `lambda_min(S)` handed to a verification ([`Check::hint`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct CurvatureHint {
    /// A pessimistic estimate (value; `residual` as its uncertainty; a direction of negative
    /// curvature when one is known): the shift above it is expected to verify.
    pub low: LanczosResult,
    /// An optimistic estimate (a Rayleigh quotient, at least `lambda_min`): the first shift
    /// `delta_0` is skipped only when this too is clearly below `-delta_0`.
    pub high: f64,
}

/// Estimates the rungs found on the way (for the diagnosis and the staircase; never bounds).
#[derive(Default)]
pub(super) struct Notes {
    pub estimate: Option<LanczosResult>,
    pub lanczos_iterations: usize,
    pub factorizations: usize,
    pub not_critical: bool,
    /// A check gave way to the refinement ([`Check::cut_by_not_critical`]).
    pub cut: bool,
    /// Why a rung proved nothing without trying (e.g. the estimate predicts a bound below 0).
    pub skipped: Option<String>,
}

impl<'a> Check<'a> {
    /// The verification of `lambdas` (of the estimate `rotations`, when known) for a cost
    /// `scale` (whose tolerance is the gap budget) in `scope`.
    pub fn new(
        problem: &'a MultipleProblem,
        lambdas: &'a [Matrix3<f64>],
        rotations: Option<&'a [Rotation]>,
        scale: f64,
        settings: &'a CertifySettings,
        scope: Scope,
    ) -> Result<Self> {
        check_lambdas(problem, lambdas)?;
        let regions = std::cell::OnceCell::new();
        let (scalar, deferred) = scalar_analyses(problem, rotations, settings, &regions)?;
        let deferred_values = deferred.as_ref().map(ScalarAnalysis::factor_len);
        // [A3] per node (empty for isotropic data): the largest, and by rows [D6] (3)
        let forming = forming_margins(problem, lambdas).unwrap_or_default();
        Ok(Check {
            problem,
            lambdas,
            rotations,
            s: std::cell::OnceCell::new(),
            terms: entry_terms(problem),
            forming: forming.iter().copied().fold(0.0, f64::max),
            forming_sum: 3.0 * forming.iter().sum::<f64>(),
            gap: settings
                .tolerance
                .resolve(problem.min_weight())
                .allowed_gap(scale),
            settings,
            point: scope.point,
            within: scope.within,
            refinement_follows: scope.refinement_follows,
            hint: None,
            deadline: scope.deadline,
            scalar,
            deferred_open: std::cell::Cell::new(deferred.is_some()),
            block_first: std::cell::Cell::new(None),
            deferred: RefCell::new(deferred),
            deferred_values,
            regions,
            three_n_refused: RefCell::new(None),
            first: None,
            gauge: std::cell::OnceCell::new(),
            trace_bound: std::cell::OnceCell::new(),
            best: None,
            unclaimed: None,
            notes: RefCell::new(Notes::default()),
            log: RefCell::new(Vec::new()),
        })
    }

    /// `S = Q - blkdiag(sym Lambda)`, as stored (made on the first call).
    pub fn s(&self) -> &SparseColMat<usize, f64> {
        &self.s_and_norm().0
    }

    /// The diagonal blocks of `S` as [`Self::s`] stores them (without forming `S`).
    pub fn diagonal_blocks(&self) -> Vec<Matrix3<f64>> {
        certificate_diagonal_blocks(self.problem, self.lambdas)
    }

    /// `3n`, the order of `S`.
    pub fn dim(&self) -> usize {
        3 * self.problem.num_rotations()
    }

    /// `||S||_inf` (at least the smallest positive number).
    pub fn norm(&self) -> f64 {
        self.s_and_norm().1
    }

    fn s_and_norm(&self) -> &(SparseColMat<usize, f64>, f64) {
        self.s.get_or_init(|| {
            let s = checked_certificate_matrix(self.problem, self.lambdas);
            let norm = inf_norm(s.as_ref()).max(f64::MIN_POSITIVE);
            (s, norm)
        })
    }

    /// The terms every bound from these multipliers shares (`[D4]`), made once.
    pub fn trace_bound(&self) -> &TraceBound {
        self.trace_bound
            .get_or_init(|| TraceBound::new(self.problem, self.lambdas))
    }

    /// The gauge terms of `S Y` at the estimate `rotations` these multipliers belong to
    /// (`[D15]`): the first-order quantities' when the check has them, else made once here.
    pub fn gauge_terms(&self, rotations: &[Rotation]) -> &GaugeTerms {
        match self.first {
            Some(f) => f.gauge_terms(rotations),
            None => self
                .gauge
                .get_or_init(|| gauge_terms(self.problem, rotations, self.lambdas)),
        }
    }

    /// The whole graph's scalar analysis ([`Self::scalar`] field), analysed now if it was
    /// deferred; `None` when the scalar comparison is not on the ladder.
    pub fn scalar(&self) -> Result<Option<&std::result::Result<ScalarAnalysis, usize>>> {
        if self.scalar.get().is_none() {
            let max_values = self.max_factor_values();
            let whole = ScalarAnalysis::new(self.problem, max_values)?;
            let _ = self.scalar.set(Some(whole));
        }
        Ok(self.scalar.get().and_then(Option::as_ref))
    }

    /// The largest factor (values) the memory budget allows for this problem's size.
    pub fn max_factor_values(&self) -> usize {
        self.settings
            .budget
            .max_factor_values(self.problem.num_rotations())
    }

    /// The regions of the subgraphs (`scalar::subgraph_regions`; `None`: no split), made on
    /// the first request.
    pub fn subgraph_regions(&self) -> Option<&[usize]> {
        let problem = self.problem;
        self.regions
            .get_or_init(|| subgraph_regions(problem))
            .as_deref()
    }

    /// The sparsest subgraph's analysis made instead of the whole graph's (taken: once).
    pub fn take_deferred(&self) -> Option<ScalarAnalysis> {
        self.deferred.borrow_mut().take()
    }

    /// Whether the `3n` rungs wait ([`crate::certify::rung::Plan::Wait`]): for the block
    /// comparison's first subgraph ([`Self::block_runs_first`]), or for the scalar
    /// family to try the deferred sparsest subgraph and its denser ones: on dense graphs their
    /// prediction needs the whole graph's scalar analysis (a 10^4-node random graph of 10^5
    /// edges: 0.17 s of a 1.4 s certificate), which a subgraph's proof makes unnecessary. Their
    /// factors are at least `9 x` the subgraph's, so they would not run before it.
    pub fn three_n_waits(&self) -> bool {
        let block_first = self.block_first.get() == Some(self.log.borrow().len());
        block_first || (self.deferred_open.get() && self.scalar.get().is_none())
    }

    /// The block comparison's family plans its first subgraph (`[A15]`; planned before the
    /// `3n` rungs): they wait for its attempt rather than analyse `S` to predict themselves (at
    /// 10^4 cameras and 10^5 edges two analyses of about 0.5 s each, while the subgraph proves
    /// in 4 s and theirs are predicted at 120 and 180 s), until anything is logged (its
    /// attempt, or its refusal by the budget).
    pub fn block_runs_first(&self) {
        self.block_first.set(Some(self.log.borrow().len()));
    }

    /// The scalar family is done with the deferred subgraph (proved, failed, or refused): the
    /// `3n` rungs plan again ([`Self::three_n_waits`]).
    pub fn close_deferred(&self) {
        self.deferred_open.set(false);
    }

    /// Record that the `3n` factorisations do not fit (`refusal`).
    pub fn note_three_n_refused(&self, refusal: &Refusal) {
        *self.three_n_refused.borrow_mut() = Some(refusal.clone());
    }

    /// The prediction of a `dim x dim` factorisation of the `3n` family (`factorisations` of
    /// them) before its own analysis, from the whole graph's scalar factor (the same graph's
    /// `3 x 3` blocks), or why it does not start: the other one was refused, or even `9 v`
    /// values (the blocks of the scalar factor, a lower estimate) are over the budget. The time
    /// is predicted for [`THREE_N_PER_SCALAR_VALUE`]` v` values (supernodal storage), the memory
    /// for the `9 v` (the rung's own analysis then checks the exact factor);
    /// [`ThreeN::Wait`] while the deferred subgraph is pending ([`Self::three_n_waits`]);
    /// [`ThreeN::Unknown`] when there is no scalar analysis (the rung analyses its own matrix).
    pub fn three_n_predicted(&self, dim: usize, factorisations: f64) -> ThreeN {
        if let Some(refusal) = self.three_n_refused_early(dim) {
            return ThreeN::Known(Err(refusal));
        }
        if self.three_n_waits() {
            return ThreeN::Wait;
        }
        match self.three_n_from_scalar(dim, factorisations) {
            Some(p) => ThreeN::Known(p),
            None => ThreeN::Unknown,
        }
    }

    /// The refusal known without the whole graph's analysis: the other `3n` factorisation was
    /// refused, or nine times the deferred subgraph's factor is already over the budget.
    fn three_n_refused_early(&self, dim: usize) -> Option<Refusal> {
        if let Some(r) = &*self.three_n_refused.borrow() {
            return Some(r.clone());
        }
        let v = self
            .deferred_values
            .filter(|_| self.scalar.get().is_none())?;
        let blocks = v.saturating_mul(9).saturating_sub(dim);
        match ordering_refusal(self.settings, blocks, dim) {
            Some(Refusal::OverBudget { reason }) => Some(Refusal::OverBudget {
                reason: format!(
                    "at least 9 x the scalar factor of a subgraph (the whole graph's is larger): \
                     {reason}"
                ),
            }),
            _ => None,
        }
    }

    /// [`Self::three_n_predicted`] from the whole graph's scalar analysis (made now if it was
    /// deferred); `None` when the scalar comparison is not on the ladder.
    fn three_n_from_scalar(
        &self,
        dim: usize,
        factorisations: f64,
    ) -> Option<std::result::Result<Prediction, Refusal>> {
        let (v, multiply_adds) = match self.scalar().ok().flatten()? {
            Ok(a) => (a.factor_len(), Some(a.factor_multiply_adds())),
            Err(predicted) => (*predicted, None),
        };
        let blocks = v.saturating_mul(9).saturating_sub(dim);
        if let Some(Refusal::OverBudget { reason }) = ordering_refusal(self.settings, blocks, dim) {
            let reason = format!("at least 9 x the scalar factor: {reason}");
            return Some(Err(Refusal::OverBudget { reason }));
        }
        let typical = (v as f64 * THREE_N_PER_SCALAR_VALUE) as usize;
        let one = match multiply_adds {
            Some(m) => Budget::predicted_factor_seconds(
                THREE_N_PER_SCALAR_MULTIPLY_ADD * m + per_value_multiply_adds(typical),
                typical,
            ),
            None => Budget::predicted_seconds(typical, dim),
        };
        // memory from the lower estimate: the attempt's own analysis checks the exact factor
        // against the budget before any numeric work, and the typical 20 x refused a 10^6-node
        // lattice whose grounded factor fitted (predicted 4.5 GB against 4.3 GB; 97813a7
        // certified it in 4.1 GB)
        Some(Ok(Prediction::new(
            factorisations * one,
            Budget::factorisation_bytes(blocks.max(dim)),
        )))
    }

    /// The bound with no deficit: what a perfect proof would give.
    pub fn ceiling(&self) -> f64 {
        self.trace_bound().with_deficit(0.0)
    }

    /// `bound` leaves at least half of the tolerance for the rest of the gap: the climb stops.
    pub fn sufficient(&self, bound: &VerifiedBound) -> bool {
        self.ceiling() - bound.lower_bound <= 0.5 * self.gap
    }

    /// Keep `bound` when it is the best so far; its outcome for the log.
    pub fn offer(&mut self, bound: VerifiedBound) -> Outcome {
        let outcome = self.proved(&bound);
        if self
            .best
            .as_ref()
            .is_none_or(|b| bound.lower_bound > b.lower_bound)
        {
            self.best = Some(bound);
        }
        outcome
    }

    /// The plan of a rung from its last prediction (or refusal): run, unless the estimate's
    /// refinement follows and the prediction is too dear for that ([`Self::cut_by_not_critical`]).
    pub fn plan_from(&self, planned: Option<std::result::Result<Prediction, Refusal>>) -> Plan {
        match planned {
            Some(Ok(p)) => match self.cut_by_not_critical(p.seconds) {
                Some(refusal) => Plan::Refuse(refusal, Some(p)),
                None => Plan::Run(p),
            },
            Some(Err(refusal)) => Plan::Refuse(refusal, None),
            None => Plan::Done,
        }
    }

    /// Log one try inside a rung (a family of shapes logs each): `rung` at this point, started
    /// at `since`, with `note`.
    pub fn log(
        &self,
        rung: Proof,
        predicted: Option<Prediction>,
        outcome: Outcome,
        since: Instant,
    ) {
        self.log.borrow_mut().push(Attempt {
            rung,
            point: self.point,
            predicted,
            outcome,
            seconds: since.elapsed().as_secs_f64(),
            note: String::new(),
            within: Some(self.within),
        });
    }

    /// [`Self::log`] with a note (a shape of a family, in words).
    pub fn log_with_note(
        &self,
        rung: Proof,
        predicted: Option<Prediction>,
        outcome: Outcome,
        since: Instant,
        note: String,
    ) {
        self.log(rung, predicted, outcome, since);
        if let Some(last) = self.log.borrow_mut().last_mut() {
            last.note = note;
        }
    }

    /// The log so far (taken).
    pub fn take_log(&self) -> Vec<Attempt> {
        self.log.take()
    }

    /// Record that the estimate is not a critical point (no check's bound can be within the
    /// tolerance: the shifted Cholesky rung does not search then).
    pub fn mark_not_critical(&self) {
        self.notes.borrow_mut().not_critical = true;
    }

    /// Why a check predicted to take `seconds` does not start: the point was found not
    /// critical and its refinement, predicted cheaper, follows ([`Scope::refinement_follows`]).
    pub fn cut_by_not_critical(&self, seconds: f64) -> Option<Refusal> {
        let refinement = self.refinement_follows?;
        let floor = self.settings.dual.give_way_above_seconds.max(refinement);
        let mut notes = self.notes.borrow_mut();
        let cut = notes.not_critical && seconds > floor;
        notes.cut |= cut;
        cut.then(|| Refusal::NotApplicable {
            reason: format!(
                "not a critical point (found by an earlier check): its refinement comes \
                     first (this check predicted at {seconds:.2e} s, above {floor:.2e} s)"
            ),
        })
    }

    /// The estimates the rungs left (taken).
    pub fn take_notes(&self) -> Notes {
        self.notes.take()
    }

    /// The budget's reasons of the checks refused over it, or failed, joined (the
    /// `inconclusive` reason); `None` when no check was kept out by the budget and one ran.
    pub fn budget_limited(&self) -> Option<String> {
        let log = self.log.borrow();
        let refused = log
            .iter()
            .any(|a| matches!(a.outcome, Outcome::Refused(Refusal::OverBudget { .. })));
        let ran = log
            .iter()
            .any(|a| !matches!(a.outcome, Outcome::Refused(_)) && a.rung != Proof::Gershgorin);
        if ran && !refused {
            return None;
        }
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
        Some(if reasons.is_empty() {
            "no proof fits the budget".into()
        } else {
            reasons.join("; ")
        })
    }

    /// The estimates the rungs leave (for the diagnosis).
    pub fn notes(&self) -> std::cell::RefMut<'_, Notes> {
        self.notes.borrow_mut()
    }

    /// The refusal of a rung predicted to need more than the time left of the budget.
    pub fn time_refusal(&self, predicted: &Prediction) -> Option<Refusal> {
        let left = self.deadline.left()?;
        (predicted.seconds > left).then(|| Refusal::OverBudget {
            reason: format!(
                "predicted {:.1} s, {:.1} s of the time budget left",
                predicted.seconds,
                left.max(0.0)
            ),
        })
    }

    /// The outcome of a rung that returned `bound`.
    pub fn proved(&self, bound: &VerifiedBound) -> Outcome {
        Outcome::Proved {
            lower_bound: bound.lower_bound,
            sufficient: self.sufficient(bound),
        }
    }
}

impl Check<'_> {
    /// A bound from a proven `mu <= lambda_min(S)` by `verification` `[D4]`, with nothing else
    /// known yet.
    pub fn bound_from_mu(&self, mu: f64, verification: Proof) -> VerifiedBound {
        VerifiedBound {
            lower_bound: self.trace_bound().at_mu(mu),
            trace: self.trace_bound().trace(),
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
            block_comparison: None,
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

impl Climb for Check<'_> {
    fn deadline(&self) -> &Deadline {
        &self.deadline
    }

    fn budget(&self) -> &Budget {
        &self.settings.budget
    }

    fn point(&self) -> Point {
        self.point
    }

    fn within(&self) -> Option<Proof> {
        Some(self.within)
    }

    fn enough(&self) -> bool {
        self.best.as_ref().is_some_and(|b| self.sufficient(b))
    }

    fn record(&mut self, attempt: Attempt) {
        self.log.get_mut().push(attempt);
    }
}

/// What the `3n` rungs know of their factorisation before their own analysis
/// ([`Check::three_n_predicted`]).
pub enum ThreeN {
    /// Predicted from the whole graph's scalar factor, or refused.
    Known(std::result::Result<Prediction, Refusal>),
    /// Wait: the scalar family is trying the deferred subgraph ([`Check::three_n_waits`]).
    Wait,
    /// Nothing known: the rung analyses its own matrix.
    Unknown,
}

/// The shifts of `[D5]` start at this: a verified `lambda_min >= -delta_0` costs a fraction
/// `dual.shift_budget_fraction` of the gap budget.
pub(crate) fn first_shift(cx: &Check<'_>) -> f64 {
    cx.settings.dual.shift_budget_fraction * cx.gap / cx.dim().max(1) as f64
}

/// Graphs with at least this many edges per node (and [`DEFER_WHOLE_MIN_EDGES`] edges) have
/// their whole graph's scalar analysis deferred until the sparsest subgraph has been tried: its
/// minimum-degree ordering alone is the largest cost of a certificate that the subgraph proves
/// (a random graph of 10^5 nodes and 10^6 edges: 1.1 s of a 6.8 s certificate, for a factor of
/// 2.4e9 values that the budget refuses anyway).
pub const DEFER_WHOLE_EDGES_PER_NODE: f64 = 4.0;

/// See [`DEFER_WHOLE_EDGES_PER_NODE`].
pub const DEFER_WHOLE_MIN_EDGES: usize = 100_000;

/// Whether the whole graph's scalar analysis waits for the sparsest subgraph
/// ([`DEFER_WHOLE_EDGES_PER_NODE`]).
pub fn defers_the_whole(problem: &MultipleProblem) -> bool {
    let (n, m) = (problem.num_rotations(), problem.num_edges());
    m >= DEFER_WHOLE_MIN_EDGES && m as f64 >= DEFER_WHOLE_EDGES_PER_NODE * n as f64
}

/// The whole graph's scalar analysis (its cell) and the deferred sparsest subgraph's.
type ScalarAnalyses = (
    std::cell::OnceCell<Option<std::result::Result<ScalarAnalysis, usize>>>,
    Option<ScalarAnalysis>,
);

/// The whole graph's scalar analysis, when the scalar comparison is on the ladder (`Some`
/// inside), or, on dense graphs, the sparsest subgraph's in its place (the cell left empty:
/// the whole graph is analysed when first asked). Which is made first decides only the cost
/// of the climb, never what is proven.
fn scalar_analyses(
    problem: &MultipleProblem,
    rotations: Option<&[Rotation]>,
    settings: &CertifySettings,
    regions: &std::cell::OnceCell<Option<Vec<usize>>>,
) -> Result<ScalarAnalyses> {
    let cell = std::cell::OnceCell::new();
    let on = settings.dual.proofs.contains(&Proof::ScalarComparison) && !problem.is_anisotropic();
    let Some(rotations) = rotations.filter(|_| on) else {
        let _ = cell.set(None);
        return Ok((cell, None));
    };
    let max_values = settings.budget.max_factor_values(problem.num_rotations());
    if settings.dual.scalar_fallbacks && defers_the_whole(problem) {
        let sparsest = SPARSIFIED_EDGES_PER_NODE[0];
        let group = regions.get_or_init(|| subgraph_regions(problem)).as_deref();
        if let Ok(sub) =
            ScalarAnalysis::in_regions(problem, rotations, sparsest, group, max_values)?
        {
            return Ok((cell, Some(sub)));
        }
    }
    let _ = cell.set(Some(ScalarAnalysis::new(problem, max_values)?));
    Ok((cell, None))
}

/// The budget's verdict on counted factorisations and their predicted time: the `largest`
/// factor (values, scratch included) must fit the memory, `total` values and `multiply_adds`
/// the time (the model of the scalar comparison: [`Budget::counted_factorisations_fit`]), the
/// stored `factor_len` the cap; `other_seconds` is the proof's work besides them.
pub(super) fn counted_prediction(
    settings: &CertifySettings,
    largest: usize,
    total: usize,
    multiply_adds: f64,
    factor_len: usize,
    other_seconds: f64,
) -> std::result::Result<Prediction, Refusal> {
    if let Err(reason) = settings
        .budget
        .counted_factorisations_fit(largest, multiply_adds, total)
    {
        return Err(Refusal::OverBudget { reason });
    }
    if let Some(refusal) = over_factor_cap(settings, factor_len) {
        return Err(refusal);
    }
    Ok(Prediction::new(
        Budget::predicted_factor_seconds(multiply_adds, total) + other_seconds,
        Budget::factorisation_bytes(largest),
    ))
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
/// [`crate::certify::budget::Budget`] or over `dual.max_factor_nonzeros`; their prediction otherwise
/// ([`Budget::counted_factorisations_fit`], the model of the scalar comparison:
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
    Ok(Prediction::new(
        Budget::predicted_factor_seconds(factorisations * multiply_adds, total),
        Budget::factorisation_bytes(values),
    ))
}

/// The per-value cost of a `3n` Cholesky factor of `values` values, as multiply-adds: the 3n
/// Cholesky of sparse grids and chains is mostly per value (measured 4.9 s for 1.88e8 values on
/// a 10^6-node grid), so it is charged at the dense model's 3e-8 s per value, the counted
/// model's 1e-8 s plus this difference.
fn per_value_multiply_adds(values: usize) -> f64 {
    use crate::certify::budget::{
        PREDICTED_MULTIPLY_ADD_RATE, PREDICTED_SECONDS_PER_COUNTED_VALUE,
        PREDICTED_SECONDS_PER_FACTOR_VALUE,
    };
    (PREDICTED_SECONDS_PER_FACTOR_VALUE - PREDICTED_SECONDS_PER_COUNTED_VALUE)
        * PREDICTED_MULTIPLY_ADD_RATE
        * values as f64
}

/// Why a factorisation of a `dim x dim` matrix whose factor is predicted (by the ordering, before
/// any symbolic analysis) to hold `factor_nonzeros` values does not start: over the
/// [`crate::certify::budget::Budget`] (`values^2 / dim` time model) or over `dual.max_factor_nonzeros`.
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
