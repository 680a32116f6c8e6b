//! The state of one certification of multiple averaging `[D12]`: the points whose multipliers
//! are verified (the given estimate, its refinement, the SDP's and the staircase's polished
//! roundings), the best verified bound so far, what the rungs found that later rungs read (the
//! given estimate's diagnosis, the staircase's stop), and the one log. The rungs are in their
//! own files; the verdict is [`super::verdict`]'s.

use super::diagnosis::DualDiagnosis;
use super::verified::RandomizedBound;
use crate::certify::budget::{Budget, Deadline};
use crate::certify::certification::{ImprovementSource, SdpSummary};
use crate::certify::evidence::StaircaseStep;
use crate::certify::log::{Attempt, Outcome, Point, Refusal};
use crate::certify::proof::{BoundMethod, Proof};
use crate::certify::rung::Climb;
use crate::certify::settings::{CertifyMode, CertifySettings};
use crate::multiple::{MultipleProblem, MultipleSolution};
use crate::so3::Rotation;
use nalgebra::Matrix3;

/// The given estimate is not refined (nor its refinement certified) when its certificate
/// matrix's negative eigenvalue estimate is at least this many times its stationarity residual
/// (both in units of the edge weights): refining moves the point, and `S`, by about the
/// residual. On a 10^4-node graph with 20 % outliers (`lambda_min ~ -1.6`, residual 1.4e-4)
/// the refinement's certificate took 15 s and found the same.
pub const REFINE_INDEFINITE_RATIO: f64 = 1e3;

/// The best verified bound seen so far.
pub(crate) struct Best {
    pub lower_bound: f64,
    pub method: BoundMethod,
    pub point: Point,
    pub min_eigenvalue: Option<f64>,
    pub explanation: String,
    /// Verified lower bound on `lambda_min` of this bound's certificate matrix.
    pub verified_min_eigenvalue: f64,
    /// The Cholesky shift that verified it, if any (a shift-invert hint for the spectrum).
    pub shift: Option<f64>,
    /// The multipliers of this bound's certificate matrix (`None` for the staircase).
    pub lambdas: Option<Vec<Matrix3<f64>>>,
}

/// The point whose multipliers are verified: the estimate, or a better solution found on the
/// way (refinement, SDP rounding, staircase rounding).
pub(crate) struct Current {
    pub rotations: Vec<Rotation>,
    pub cost: f64,
    pub label: Point,
    /// `Some` when it is not the given estimate.
    pub solution: Option<(MultipleSolution, ImprovementSource)>,
}

/// What one dual certificate said.
#[derive(Debug, Clone)]
pub(crate) struct DualRun {
    pub diagnosis: DualDiagnosis,
    /// The randomized bound `[D16]`, when no deterministic proof fit the budget.
    pub randomized: Option<RandomizedBound>,
}

/// One certification's state.
pub(crate) struct State<'a> {
    pub problem: &'a MultipleProblem,
    pub settings: &'a CertifySettings,
    pub deadline: Deadline,
    /// The given estimate's cost.
    pub cost: f64,
    pub best: Option<Best>,
    pub current: Current,
    /// Some edge's `M` is indefinite: the `O(3)` relaxation can prefer reflections `[A5]`, and
    /// the `conv(SO(3))` dual certificate `[A11]` applies.
    pub reflective: bool,
    /// The points whose dual certificate ran (or was found hopeless), and whose `conv(SO(3))`
    /// dual certificate ran.
    pub dual_at: Vec<Point>,
    pub conv_dual_at: Vec<Point>,
    /// The given estimate's diagnosis (set once its dual certificate ran, or was found
    /// hopeless: then [`DualDiagnosis::NotCritical`]).
    pub first: Option<DualDiagnosis>,
    /// The last dual certificate's run.
    pub last: Option<DualRun>,
    /// The refinement was tried.
    pub refined: bool,
    /// The stationarity residual `[D3]` of the given estimate, and of the last point verified.
    pub given_stationarity_residual: Option<f64>,
    pub stationarity_residual: Option<f64>,
    /// The staircase ran: `Some(true)` when it stopped at a verified or bracketed point (the
    /// relaxation's value is then known: the SDP cannot do better).
    pub staircase_verified: Option<bool>,
    /// The SDP ran; the SDP was refused (over the budget: in mode `sdp` the staircase, which
    /// solves the same relaxation by its low-rank factors, takes its place).
    pub sdp_ran: bool,
    pub sdp_refused: bool,
    pub sdp: Option<SdpSummary>,
    pub staircase_steps: Vec<StaircaseStep>,
    pub refine_seconds: f64,
    pub log: Vec<Attempt>,
}

impl<'a> State<'a> {
    /// The state of certifying `rotations` (cost `cost`), its clock started at `deadline`.
    pub fn new(
        problem: &'a MultipleProblem,
        rotations: &[Rotation],
        cost: f64,
        settings: &'a CertifySettings,
        deadline: Deadline,
    ) -> Self {
        State {
            problem,
            settings,
            deadline,
            cost,
            best: None,
            current: Current {
                rotations: rotations.to_vec(),
                cost,
                label: Point::Given,
                solution: None,
            },
            reflective: problem
                .information()
                .is_some_and(|info| info.iter().any(|h| h.chordal_matrix_indefinite())),
            dual_at: Vec::new(),
            conv_dual_at: Vec::new(),
            first: None,
            last: None,
            refined: false,
            given_stationarity_residual: None,
            stationarity_residual: None,
            staircase_verified: None,
            sdp_ran: false,
            sdp_refused: false,
            sdp: None,
            staircase_steps: Vec::new(),
            refine_seconds: 0.0,
            log: Vec::new(),
        }
    }

    /// Keep `cand` when its bound is the largest so far.
    pub fn offer(&mut self, cand: Best) {
        if self
            .best
            .as_ref()
            .is_none_or(|b| cand.lower_bound > b.lower_bound)
        {
            self.best = Some(cand);
        }
    }

    /// The gap the verdict allows at `cost`.
    pub fn allowed_gap(&self, cost: f64) -> f64 {
        self.settings
            .tolerance
            .resolve(self.problem.min_weight())
            .allowed_gap(cost)
    }

    /// `lower_bound` certifies the current point.
    pub fn certifies(&self, lower_bound: f64) -> bool {
        self.current.cost - lower_bound <= self.allowed_gap(self.current.cost)
    }

    /// The best bound so far certifies the current point.
    pub fn best_certifies(&self) -> bool {
        self.best
            .as_ref()
            .is_some_and(|b| self.certifies(b.lower_bound))
    }

    /// Adopt `candidate` as the current point when its chordal cost is not higher.
    pub fn adopt(
        &mut self,
        candidate: MultipleSolution,
        source: ImprovementSource,
        label: Point,
    ) -> bool {
        self.adopt_within(candidate, source, label, 0.0)
    }

    /// [`Self::adopt`] for a candidate whose cost may exceed the current one by `slack`.
    pub fn adopt_within(
        &mut self,
        candidate: MultipleSolution,
        source: ImprovementSource,
        label: Point,
        slack: f64,
    ) -> bool {
        if candidate.chordal_cost > self.current.cost + slack {
            return false;
        }
        self.current = Current {
            rotations: candidate.rotations.clone(),
            cost: candidate.chordal_cost,
            label,
            solution: Some((candidate, source)),
        };
        true
    }

    /// The dual certificates of the given estimate and of its refinement are settled: the
    /// staircase, the SDP and the `conv(SO(3))` SDP may run (`Err`: why not, or `Ok(false)`:
    /// not yet).
    pub fn escalation(&self) -> std::result::Result<bool, String> {
        let Some(last) = &self.last else {
            return Ok(false);
        };
        if self.wants_refinement() {
            return Ok(false);
        }
        let mode = self.settings.mode;
        match &last.diagnosis {
            DualDiagnosis::Certified => Err(format!(
                "the dual certificate at {} already certified it",
                self.current.label
            )),
            DualDiagnosis::PrecisionLimited { .. }
                if !matches!(mode, CertifyMode::Sdp | CertifyMode::Staircase) =>
            {
                Err(MARGIN_LIMITED.into())
            }
            DualDiagnosis::OverBudget { reason, .. } => Err(reason.clone()),
            _ => Ok(true),
        }
    }

    /// The given estimate's dual certificate ran (or was found hopeless) and did not settle it,
    /// and refining it can help (it is not clearly a saddle, `REFINE_INDEFINITE_RATIO`).
    pub fn wants_refinement(&self) -> bool {
        let Some(first) = &self.first else {
            return false;
        };
        let settled = matches!(
            first,
            DualDiagnosis::Certified
                | DualDiagnosis::PrecisionLimited { .. }
                | DualDiagnosis::OverBudget { .. }
        );
        // where the O(3) relaxation prefers reflections its `S` is indefinite at the minimum
        // too: that says nothing of a saddle, and the conv(SO(3)) certificate needs the
        // estimate critical (strongly anisotropic SLAM information: a local solve converged
        // with a residual of 0.96 against information of 1e9; `paper-notes/certificates.md`
        // "Refinement on reflective data")
        let hopeless = !self.reflective
            && matches!(first, DualDiagnosis::Indefinite { min_eigenvalue }
            if -min_eigenvalue >= REFINE_INDEFINITE_RATIO
                * self.given_stationarity_residual.unwrap_or(f64::INFINITY));
        !self.refined && !settled && !hopeless && self.current.label == Point::Given
    }
}

/// Why the SDP and the staircase do not run after a dual certificate limited by precision.
pub const MARGIN_LIMITED: &str = "SDP / staircase skipped: the estimate is a critical point whose \
certificate matrix is PSD up to the floating-point precision of the verification; the gap is that \
precision, which other multipliers cannot improve (mode sdp or staircase runs them anyway)";

impl Climb for State<'_> {
    fn deadline(&self) -> &Deadline {
        &self.deadline
    }

    fn budget(&self) -> &Budget {
        &self.settings.budget
    }

    fn point(&self) -> Point {
        self.current.label
    }

    fn within(&self) -> Option<Proof> {
        None
    }

    fn enough(&self) -> bool {
        self.best_certifies()
    }

    fn record(&mut self, attempt: Attempt) {
        if attempt.rung == Proof::Sdp
            && matches!(
                attempt.outcome,
                Outcome::Refused(Refusal::OverBudget { .. })
            )
        {
            self.sdp_refused = true;
        }
        self.log.push(attempt);
    }
}
