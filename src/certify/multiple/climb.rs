//! The climb of one certification of multiple averaging `[D12]`: the points whose multipliers
//! are verified (the given estimate, its refinement, the SDP's multipliers and polished
//! rounding, the staircase's lifted point), the best bound so far, and the log of every rung of
//! the ladder at each point ([`crate::certify::ladder`]).

use super::dual::{DualDiagnosis, attach_randomized, diagnosis_text, dual_certificate_at};
use super::grounded::hopeless;
use super::multipliers::{multipliers, stationarity_residual};
use super::randomized::RandomizedBound;
use super::staircase;
use super::verify::{Verification, lower_bound_from_multipliers};
use crate::certify::certificate::{BoundMethod, Certificate};
use crate::certify::certification::{
    CertifyDetails, Improvement, ImprovementSource, MethodRun, SdpSummary,
};
use crate::certify::ladder::{Attempt, Outcome, Point, Prediction, Refusal, Rung};
use crate::certify::settings::{CertifyMode, CertifySettings};
use crate::certify::spectrum::certificate_spectrum;
use crate::error::Result;
use crate::multiple::{
    Initialisation, MultipleProblem, MultipleSettings, MultipleSolution, solve_multiple,
};
use crate::relax::{predict_relax_multiple, relax_multiple};
use crate::so3::Rotation;
use nalgebra::Matrix3;
use std::time::Instant;

/// When the dual certificate fails, the estimate is refined once with the local solver's
/// default gradient tolerance multiplied by this factor, and the dual certificate is tried at
/// the refined point.
pub const REFINE_FACTOR: f64 = 1e-6;

/// The best verified bound seen so far.
pub(super) struct Best {
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
/// way (refinement, SDP rounding).
pub(super) struct Current {
    pub rotations: Vec<Rotation>,
    pub cost: f64,
    pub label: Point,
    /// `Some` when it is not the given estimate.
    pub solution: Option<(MultipleSolution, ImprovementSource)>,
}

/// What one dual certificate said.
#[derive(Debug, Clone)]
pub(super) struct DualRun {
    pub diagnosis: DualDiagnosis,
    /// The randomized bound `[D16]`, when no deterministic proof fit the budget.
    pub randomized: Option<RandomizedBound>,
}

/// One certification's state.
pub(super) struct Climb<'a> {
    pub problem: &'a MultipleProblem,
    pub settings: &'a CertifySettings,
    pub start: Instant,
    /// The given estimate's cost.
    pub cost: f64,
    pub best: Option<Best>,
    pub current: Current,
    /// The point where the `conv(SO(3))` dual certificate last ran, if it did.
    pub conv_dual_at: Option<Point>,
    /// Some edge's `M` is indefinite: the `O(3)` relaxation can prefer reflections `[A5]`, and
    /// the `conv(SO(3))` dual certificate `[A11]` applies.
    reflective: bool,
    pub details: CertifyDetails,
}

impl<'a> Climb<'a> {
    pub fn new(
        problem: &'a MultipleProblem,
        rotations: &[Rotation],
        cost: f64,
        settings: &'a CertifySettings,
        start: Instant,
    ) -> Self {
        Climb {
            problem,
            settings,
            start,
            cost,
            best: None,
            conv_dual_at: None,
            reflective: problem
                .information()
                .is_some_and(|info| info.iter().any(|h| h.chordal_matrix_indefinite())),
            current: Current {
                rotations: rotations.to_vec(),
                cost,
                label: Point::Given,
                solution: None,
            },
            details: CertifyDetails {
                mode: settings.mode,
                ..Default::default()
            },
        }
    }

    /// Keep `cand` when its bound is the largest so far.
    fn offer(&mut self, cand: Best) {
        if self
            .best
            .as_ref()
            .is_none_or(|b| cand.lower_bound > b.lower_bound)
        {
            self.best = Some(cand);
        }
    }

    /// Past the time budget: say why `step` is not run.
    pub fn over_time(&mut self, step: &str) -> bool {
        match self.settings.budget.max_seconds {
            Some(limit) if self.start.elapsed().as_secs_f64() > limit => {
                self.details.skipped_reason = Some(format!(
                    "{step} not run: the time budget of {limit} s is spent"
                ));
                true
            }
            _ => false,
        }
    }

    /// The given estimate's first diagnosis: its own dual certificate, unless a cheap test shows
    /// that no bound from its own multipliers can be within the tolerance (its stationarity
    /// residual against the largest curvature of `S`, `[D15]`); then the ladder at it is
    /// skipped (issue 24: its refinement's certificate bounds it as well, in a fraction of the
    /// time). `None` in that case.
    pub fn given(&mut self) -> Result<Option<DualRun>> {
        let since = Instant::now();
        let rotations = self.current.rotations.clone();
        let lambdas = multipliers(self.problem, &rotations)?;
        let gap = self
            .settings
            .tolerance
            .resolve(self.problem.min_weight())
            .allowed_gap(self.cost);
        let residual = stationarity_residual(self.problem, &rotations)?;
        self.details.given_stationarity_residual = Some(residual);
        if let Some(reason) = hopeless(self.problem, &rotations, &lambdas, gap) {
            self.details.ladder.push(Attempt {
                rung: Rung::Grounded,
                point: Point::Given,
                predicted: None,
                outcome: Outcome::Refused(Refusal::NotApplicable { reason }),
                seconds: since.elapsed().as_secs_f64(),
            });
            return Ok(None);
        }
        self.dual().map(Some)
    }

    /// Dual certificate at the current point: records the run, offers its bound, returns its
    /// diagnosis (certified against the point's own cost). `PrecisionLimited`: the point is a
    /// critical point and `S` is PSD up to the verification's floating-point margin `[D6]`,
    /// `[D15]`: the SDP / staircase multipliers (verified the same way, at the same optimum)
    /// cannot do better.
    pub fn dual(&mut self) -> Result<DualRun> {
        let label = self.current.label;
        crate::progress::phase(crate::progress::Phase::Certify, || {
            format!(
                "dual certificate at {label} ({} nodes)",
                self.problem.num_rotations()
            )
        });
        let c = dual_certificate_at(self.problem, &self.current.rotations, self.settings, label)?;
        self.details.ladder.extend(c.bound.ladder.iter().cloned());
        let over = matches!(c.diagnosis, DualDiagnosis::OverBudget { .. });
        let note = format!(
            "dual certificate at {label}: {}{}",
            diagnosis_text(&c.diagnosis, self.problem),
            match (over, &c.bound.randomized) {
                (true, Some(r)) => format!("; {r}"),
                _ => String::new(),
            }
        );
        self.details.methods.push(MethodRun {
            method: BoundMethod::Dual,
            lower_bound: (!over).then_some(c.bound.lower_bound),
            seconds: c.certificate.seconds,
            note,
        });
        if let DualDiagnosis::OverBudget { reason, .. } = &c.diagnosis {
            // no proof fits: the Gershgorin bound is not offered (no lower bound is claimed)
            self.details.skipped_reason = Some(reason.clone());
        } else {
            self.details.stationarity_residual = Some(c.stationarity_residual);
            let lambdas = Some(multipliers(self.problem, &self.current.rotations)?);
            self.offer(Best {
                lower_bound: c.bound.lower_bound,
                method: BoundMethod::Dual,
                point: label,
                min_eigenvalue: c.certificate.min_eigenvalue,
                explanation: c.proof.clone(),
                verified_min_eigenvalue: c.bound.verified_min_eigenvalue,
                // the grounded bound [D15] verifies no shift of S, but its lambda_min bound
                // makes S + (-mu) I positive semidefinite: the same shift-invert hint
                shift: c.bound.shift.or_else(|| {
                    (c.bound.verification == Verification::Grounded)
                        .then_some((-c.bound.verified_min_eigenvalue).max(0.0))
                }),
                lambdas,
            });
        }
        Ok(DualRun {
            diagnosis: c.diagnosis,
            randomized: c.bound.randomized,
        })
    }

    /// Re-solve (chordal) from the current point with the default gradient tolerance times
    /// [`REFINE_FACTOR`]; adopts the result when its cost is not higher. Returns whether it did.
    pub fn refine(&mut self) -> bool {
        let t = Instant::now();
        crate::progress::phase(crate::progress::Phase::Refine, String::new);
        let local = MultipleSettings {
            init: Initialisation::Given(self.current.rotations.clone()),
            gradient_tolerance: MultipleSettings::default().gradient_tolerance * REFINE_FACTOR,
            ..Default::default()
        };
        let adopted = match solve_multiple(self.problem, &local) {
            Ok(r) => self.adopt(r, ImprovementSource::Refinement, Point::Refined),
            Err(_) => false,
        };
        self.details.refine_seconds += t.elapsed().as_secs_f64();
        adopted
    }

    /// Adopt `candidate` as the current point when its chordal cost is not higher.
    fn adopt(
        &mut self,
        candidate: MultipleSolution,
        source: ImprovementSource,
        label: Point,
    ) -> bool {
        if candidate.chordal_cost > self.current.cost {
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

    /// The SDP rung: predicted from the graph (`[P6]`), refused over the budget (the staircase
    /// then takes its place); otherwise solved, its multipliers verified (never its objective)
    /// and its rounding polished, which becomes the current point (and is certified) when it is
    /// cheaper.
    pub fn sdp(&mut self) -> Result<()> {
        self.sdp_rung(true)
    }

    /// Mode `auto`: the staircase first (it solves the same relaxation: on a 40-node graph with
    /// 20 % outliers its verified bound matched the SDP's to 4e-9 relative in 0.07 s against
    /// 10.3 s), then the SDP only when the staircase stopped short of a verified point (rank
    /// limit, failed escape, or a proven bound below the lifted cost) and the bound is not yet
    /// enough for the verdict.
    pub fn staircase_then_sdp(&mut self) -> Result<()> {
        let verified = self.staircase()?;
        if verified || self.best_certifies() || self.over_time("SDP") {
            return Ok(());
        }
        self.sdp_rung(false)
    }

    /// The `conv(SO(3))` rung `[A6]`: for anisotropic problems of at most
    /// [`crate::relax::conv_so3::CONV_MAX_NODES`] nodes whose bound does not yet certify the
    /// current point (the `O(3)` relaxation can prefer reflections, `[A5]`), the strengthened SDP,
    /// predicted and refused over the budget like every rung, its multipliers verified by
    /// [`super::conv_bound`].
    pub fn conv_sdp(&mut self) -> Result<()> {
        let n = self.problem.num_rotations();
        if !self.problem.is_anisotropic()
            || n > crate::relax::conv_so3::CONV_MAX_NODES
            || self.best_certifies()
            || self.over_time("conv(SO(3)) SDP")
        {
            return Ok(());
        }
        let since = Instant::now();
        let p = crate::relax::conv_so3::predict_relax_multiple_conv(self.problem);
        let predicted = Prediction {
            seconds: p.seconds,
            bytes: p.bytes,
        };
        if let Err(reason) = self.fits(&predicted) {
            let why = format!("conv(SO(3)) SDP not run: {reason}");
            self.details.methods.push(MethodRun {
                method: BoundMethod::Sdp,
                lower_bound: None,
                seconds: since.elapsed().as_secs_f64(),
                note: why.clone(),
            });
            let outcome = Outcome::Refused(Refusal::OverBudget { reason: why });
            self.log(Rung::ConvSdp, Some(predicted), outcome, since);
            return Ok(());
        }
        let relaxation = crate::relax::conv_so3::relax_multiple_conv(
            self.problem,
            &self
                .settings
                .sdp_within_budget(self.start.elapsed().as_secs_f64()),
        )?;
        let bound = super::conv_bound(self.problem, &relaxation)?;
        let explanation = format!(
            "bound from the conv(SO(3)) relaxation's multipliers [A6] (Clarabel {:?}, {} \
             iterations), verified independently: lambda_min(S) >= {:.3e}",
            relaxation.status, relaxation.iterations, bound.verified_min_eigenvalue
        );
        self.offer(Best {
            lower_bound: bound.lower_bound,
            method: BoundMethod::Sdp,
            point: Point::ConvSdp,
            min_eigenvalue: Some(bound.verified_min_eigenvalue),
            explanation: explanation.clone(),
            verified_min_eigenvalue: bound.verified_min_eigenvalue,
            shift: None,
            lambdas: None,
        });
        let outcome = Outcome::Proved {
            lower_bound: bound.lower_bound,
            sufficient: false,
        };
        self.log(Rung::ConvSdp, Some(predicted), outcome, since);
        self.details.methods.push(MethodRun {
            method: BoundMethod::Sdp,
            lower_bound: Some(bound.lower_bound),
            seconds: since.elapsed().as_secs_f64(),
            note: explanation,
        });
        Ok(())
    }

    /// The `conv(SO(3))` dual certificate `[A11]` at the current point, once per point: modes
    /// `auto` and `dual`, anisotropic problems with some indefinite `M` (on definite data a
    /// failed `O(3)` certificate is outliers or noise far more often; the dense SDP of small
    /// graphs, `[A6]`, is the rung there) not yet certified, any size. The search for its
    /// multipliers may spend `dual.conv.time_fraction` of the time left (its memory is
    /// predicted and refused over the budget); the surrogate's bound is verified by the `O(3)`
    /// ladder, whose rungs are logged at [`Point::ConvDual`].
    pub fn conv_dual(&mut self) -> Result<()> {
        let conv = &self.settings.dual.conv;
        if !self.reflective
            || !conv.enabled
            || !matches!(self.settings.mode, CertifyMode::Auto | CertifyMode::Dual)
            || self.best_certifies()
            || self.over_time("conv(SO(3)) dual certificate")
        {
            return Ok(());
        }
        if self.conv_dual_at == Some(self.current.label) {
            return Ok(());
        }
        self.conv_dual_at = Some(self.current.label);
        let since = Instant::now();
        crate::progress::phase(crate::progress::Phase::Certify, || {
            format!(
                "conv(SO(3)) dual certificate at {} ({} nodes)",
                self.current.label,
                self.problem.num_rotations()
            )
        });
        let predicted = super::conv_dual::predict_search(self.problem, conv);
        if let Err(reason) = self.fits(&predicted) {
            let why = format!("conv(SO(3)) dual certificate not run: {reason}");
            self.details.methods.push(MethodRun {
                method: BoundMethod::Dual,
                lower_bound: None,
                seconds: since.elapsed().as_secs_f64(),
                note: why.clone(),
            });
            let outcome = Outcome::Refused(Refusal::OverBudget { reason: why });
            self.log(Rung::ConvDual, Some(predicted), outcome, since);
            return Ok(());
        }
        let deadline = self.settings.budget.max_seconds.map(|limit| {
            let left = (limit - self.start.elapsed().as_secs_f64()).max(0.0);
            since + std::time::Duration::from_secs_f64(left * conv.time_fraction)
        });
        let b = super::conv_dual::conv_dual_bound(
            self.problem,
            &self.current.rotations,
            self.settings,
            Point::ConvDual,
            deadline,
        )?;
        self.details
            .ladder
            .extend(b.surrogate.ladder.iter().cloned());
        let explanation = format!(
            "bound from the conv(SO(3)) multipliers recovered at {} [A11] ({} rounds of their \
             search, {} cuts, stopped: {}): the O(3) certificate of the penalised surrogate, \
             lambda_min(S') >= {:.3e}, minus its verified offsets {:.6e}",
            self.current.label,
            b.search.rounds,
            b.search.cuts,
            b.search.stop,
            b.surrogate.verified_min_eigenvalue,
            b.offset
        );
        self.offer(Best {
            lower_bound: b.lower_bound,
            method: BoundMethod::Dual,
            point: Point::ConvDual,
            min_eigenvalue: b
                .surrogate
                .min_eigenvalue_estimate
                .or(Some(b.surrogate.verified_min_eigenvalue)),
            explanation: explanation.clone(),
            verified_min_eigenvalue: b.surrogate.verified_min_eigenvalue,
            shift: None,
            lambdas: None,
        });
        let tolerance = self.settings.tolerance.resolve(self.problem.min_weight());
        let outcome = Outcome::Proved {
            lower_bound: b.lower_bound,
            sufficient: self.current.cost - b.lower_bound
                <= tolerance.allowed_gap(self.current.cost),
        };
        self.log(Rung::ConvDual, Some(predicted), outcome, since);
        self.details.methods.push(MethodRun {
            method: BoundMethod::Dual,
            lower_bound: Some(b.lower_bound),
            seconds: since.elapsed().as_secs_f64(),
            note: explanation,
        });
        Ok(())
    }

    /// The best bound so far certifies the current point.
    pub fn best_certifies(&self) -> bool {
        let tolerance = self.settings.tolerance.resolve(self.problem.min_weight());
        self.best.as_ref().is_some_and(|b| {
            self.current.cost - b.lower_bound <= tolerance.allowed_gap(self.current.cost)
        })
    }

    /// The SDP rung; over the budget, the staircase takes its place when `fallback` is set.
    fn sdp_rung(&mut self, fallback: bool) -> Result<()> {
        let since = Instant::now();
        let p = predict_relax_multiple(self.problem)?;
        let predicted = Prediction {
            seconds: p.seconds,
            bytes: p.bytes,
        };
        if let Err(reason) = self.fits(&predicted) {
            let why = format!(
                "SDP not run: {reason} (predicted from {} cliques of up to {} nodes)",
                p.cliques, p.largest_clique
            );
            self.details.skipped_reason = Some(why.clone());
            self.details.methods.push(MethodRun {
                method: BoundMethod::Sdp,
                lower_bound: None,
                seconds: since.elapsed().as_secs_f64(),
                note: if fallback {
                    format!("{why}; the staircase solves the same relaxation instead")
                } else {
                    why.clone()
                },
            });
            self.log(
                Rung::Sdp,
                Some(predicted),
                Outcome::Refused(Refusal::OverBudget { reason: why }),
                since,
            );
            // the next rung: the staircase solves the same relaxation by its low-rank factors
            return if fallback {
                self.staircase().map(|_| ())
            } else {
                Ok(())
            };
        }
        if let Some(polished) = self.run_sdp(predicted, since)?
            && polished.chordal_cost < self.current.cost
            && self.adopt(polished, ImprovementSource::SdpRounding, Point::Sdp)
        {
            self.dual()?;
        }
        Ok(())
    }

    /// `Err(reason)` when `predicted` does not fit the memory budget or the time left.
    fn fits(&self, predicted: &Prediction) -> std::result::Result<(), String> {
        let elapsed = self.start.elapsed().as_secs_f64();
        self.settings.budget.prediction_fits(predicted, elapsed)
    }

    /// Log one rung of this climb's own (the SDP, the staircase).
    fn log(&mut self, rung: Rung, predicted: Option<Prediction>, outcome: Outcome, since: Instant) {
        self.details.ladder.push(Attempt {
            rung,
            point: self.current.label,
            predicted,
            outcome,
            seconds: since.elapsed().as_secs_f64(),
        });
    }

    /// Run the SDP and verify its multipliers; returns the SDP's rounding polished by the local
    /// solver.
    fn run_sdp(
        &mut self,
        predicted: Prediction,
        since: Instant,
    ) -> Result<Option<MultipleSolution>> {
        crate::progress::phase(crate::progress::Phase::Sdp, || {
            format!("{} nodes", self.problem.num_rotations())
        });
        let sdp = relax_multiple(
            self.problem,
            &self
                .settings
                .sdp_within_budget(self.start.elapsed().as_secs_f64()),
        )?;
        let n = self.problem.num_rotations();
        let usable = sdp.multipliers.len() == n
            && sdp
                .multipliers
                .iter()
                .all(|l| l.iter().all(|x| x.is_finite()));
        let bound = if usable {
            Some(lower_bound_from_multipliers(
                self.problem,
                &sdp.multipliers,
                self.settings,
            )?)
        } else {
            None
        };
        let polished = (sdp.rounded.len() == n)
            .then(|| {
                let local = MultipleSettings {
                    init: Initialisation::Given(sdp.rounded.clone()),
                    ..Default::default()
                };
                solve_multiple(self.problem, &local).ok()
            })
            .flatten();
        let eigenvalue_ratio = match sdp.x_top_eigenvalues.as_slice() {
            [_, _, l3, l4, ..] if *l3 > 0.0 => l4.max(0.0) / l3,
            _ => f64::NAN,
        };
        self.details.sdp = Some(SdpSummary {
            status: sdp.status,
            iterations: sdp.iterations,
            seconds: sdp.seconds,
            eigenvalue_ratio,
            rounded_cost: Some(sdp.rounded_cost),
            polished_cost: polished.as_ref().map(|p| p.chordal_cost),
        });
        let reflections = (sdp.reflected_blocks > 0).then(|| {
            format!(
                "; {} of {n} blocks of the SDP's rank-3 factor are reflections (det < 0): the O(3) \
                 relaxation prefers them, so its bound can lie below every rotation estimate",
                sdp.reflected_blocks
            )
        });
        let note = format!(
            "Clarabel SDP ({:?}, {} iterations, {:.3} s); multipliers verified{}; rounding cost {:.9e}{}{}",
            sdp.status,
            sdp.iterations,
            sdp.solver_seconds,
            bound
                .as_ref()
                .map(|b| format!(
                    ": lambda_min(Q - blkdiag(Lambda)) >= {:.3e}",
                    b.verified_min_eigenvalue
                ))
                .unwrap_or_else(|| " (unusable multipliers)".into()),
            sdp.rounded_cost,
            polished
                .as_ref()
                .map(|p| format!(", polished {:.9e}", p.chordal_cost))
                .unwrap_or_default(),
            reflections.unwrap_or_default()
        );
        let outcome = match &bound {
            Some(b) => Outcome::Proved {
                lower_bound: b.lower_bound,
                sufficient: false,
            },
            None => Outcome::Failed {
                reason: format!("Clarabel {:?}: unusable multipliers", sdp.status),
            },
        };
        if let Some(b) = &bound {
            self.details.ladder.extend(b.ladder.iter().cloned());
            self.offer(Best {
                lower_bound: b.lower_bound,
                method: BoundMethod::Sdp,
                point: Point::Sdp,
                min_eigenvalue: b
                    .min_eigenvalue_estimate
                    .or(Some(b.verified_min_eigenvalue)),
                explanation: format!(
                    "bound from the SDP relaxation's multipliers (Clarabel {:?}), verified \
                     independently: lambda_min(Q - blkdiag(Lambda)) >= {:.3e}",
                    sdp.status, b.verified_min_eigenvalue
                ),
                verified_min_eigenvalue: b.verified_min_eigenvalue,
                shift: b.shift,
                lambdas: Some(sdp.multipliers.clone()),
            });
        }
        self.log(Rung::Sdp, Some(predicted), outcome, since);
        self.details.methods.push(MethodRun {
            method: BoundMethod::Sdp,
            lower_bound: bound.map(|b| b.lower_bound),
            seconds: since.elapsed().as_secs_f64(),
            note,
        });
        Ok(polished)
    }

    /// The staircase rung `[D11]`: a bound from the lifted point's multipliers.
    pub fn staircase(&mut self) -> Result<bool> {
        let since = Instant::now();
        crate::progress::phase(crate::progress::Phase::Staircase, String::new);
        let r = staircase::staircase_bound(self.problem, &self.current.rotations, self.settings)?;
        // "verified" only when the proven bound reaches the lifted point's own cost: the stop
        // reason rests on a Lanczos estimate, which misses a negative eigenvector orthogonal to
        // its start (a 3-cycle with loop angle pi: lifted cost 7 at rank 4, estimate -2e-16,
        // proven bound -1, while the SDP certifies 6), and then the SDP must still run
        let tolerance = self.settings.tolerance.resolve(self.problem.min_weight());
        // (a bracketed stop rests on the proven bound and the lifted cost alone: the SDP could
        // raise the bound by at most `staircase.bracket_tolerance` of the gap)
        let verified = match r.stop_reason {
            staircase::StaircaseStop::Verified { .. } => {
                r.lifted_cost - r.bound.lower_bound <= tolerance.allowed_gap(r.lifted_cost)
            }
            staircase::StaircaseStop::Bracketed { .. } => true,
            _ => false,
        };
        self.details.ladder.extend(r.bound.ladder.iter().cloned());
        self.details.staircase_steps.extend(r.steps.iter().cloned());
        self.offer(Best {
            lower_bound: r.bound.lower_bound,
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
        let outcome = Outcome::Proved {
            lower_bound: r.bound.lower_bound,
            sufficient: false,
        };
        self.log(Rung::Staircase, None, outcome, since);
        // its rounding, polished, becomes the current point when cheaper (then certified)
        let local = MultipleSettings {
            init: Initialisation::Given(r.rounded.clone()),
            ..Default::default()
        };
        let polished = (r.rounded.len() == self.problem.num_rotations())
            .then(|| solve_multiple(self.problem, &local).ok())
            .flatten();
        let polished_cost = polished.as_ref().map(|p| p.chordal_cost);
        self.details.methods.push(MethodRun {
            method: BoundMethod::Staircase,
            lower_bound: Some(r.bound.lower_bound),
            seconds: since.elapsed().as_secs_f64(),
            note: format!(
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
            ),
        });
        // the rounding's own dual certificate cannot beat a verified or bracketed staircase
        // (every dual bound is at most the relaxation's value, at most the lifted cost)
        if let Some(p) = polished
            && p.chordal_cost < self.current.cost
            && self.adopt(p, ImprovementSource::StaircaseRounding, Point::Staircase)
            && !verified
        {
            self.dual()?;
        }
        Ok(verified)
    }

    /// The certificate of the given estimate from the best bound (and the improvement, when a
    /// cheaper point was found); with `settings.spectrum` set, also the smallest-eigenvalue
    /// estimates of that bound's certificate matrix `[D14]`. The explanation states the verdict
    /// for the given estimate (`first`: its diagnosis), the better estimate found if any, and
    /// how the bound was proven.
    pub fn certificate(&mut self, first: &DualDiagnosis, last: Option<&DualRun>) -> Certificate {
        let seconds = self.start.elapsed().as_secs_f64();
        let tolerance = self.settings.tolerance.resolve(self.problem.min_weight());
        let mut c = match self.best.take() {
            None => Certificate::from_bounds(
                self.cost,
                None,
                BoundMethod::Dual,
                None,
                tolerance,
                format!(
                    "no lower bound could be computed; {}",
                    diagnosis_text(first, self.problem)
                ),
                seconds,
            ),
            Some(b) => self.certificate_of(b, first, seconds),
        };
        // a Monte Carlo bound [D16] is a bound on the global minimum whatever point gave it
        let randomized = attach_randomized(&mut c, last.and_then(|l| l.randomized));
        c.explanation.push_str(&randomized);
        c
    }

    fn certificate_of(&self, b: Best, first: &DualDiagnosis, seconds: f64) -> Certificate {
        let tolerance = self.settings.tolerance.resolve(self.problem.min_weight());
        let mut c = Certificate::from_bounds(
            self.cost,
            Some(b.lower_bound),
            b.method,
            b.min_eigenvalue,
            tolerance,
            String::new(),
            seconds,
        );
        let mut verdict = if c.is_certified() && matches!(b.point, Point::ConvSdp | Point::ConvDual)
        {
            format!(
                "certified globally optimal for the anisotropic chordal L2 cost of its {} edges \
                 (a bound over conv(SO(3)) Gram blocks, hence over SO(3)^n: on these data the \
                 O(3) relaxation can prefer reflections)",
                self.problem.num_edges()
            )
        } else if c.is_certified() {
            diagnosis_text(&DualDiagnosis::Certified, self.problem)
        } else {
            match first {
                // the estimate's own dual certificate would certify, but a bound from another
                // point is what was kept: say it plainly
                DualDiagnosis::Certified => "not certified within the tolerance".to_string(),
                d => diagnosis_text(d, self.problem),
            }
        };
        verdict.push_str(&self.improvement_text(&b, &tolerance));
        c.explanation = format!(
            "{verdict}; bound ({}, at {}): {}",
            b.method, b.point, b.explanation
        );
        c.verified_min_eigenvalue = Some(b.verified_min_eigenvalue);
        c.bound_from = Some(b.point);
        if let (Some(sp), Some(l)) = (self.settings.spectrum.as_ref(), &b.lambdas) {
            // an estimate for a figure: its failure never fails the certification
            c.smallest_eigenvalues = certificate_spectrum(self.problem, l, sp, b.shift).ok();
        }
        c
    }

    /// The better estimate found, in words, and whether the bound certifies it.
    fn improvement_text(&self, b: &Best, tolerance: &crate::certify::GapTolerance) -> String {
        let Some((s, source)) = &self.current.solution else {
            return String::new();
        };
        let better = s.chordal_cost;
        if better >= self.cost {
            return String::new();
        }
        let certified =
            b.lower_bound.is_finite() && better - b.lower_bound <= tolerance.allowed_gap(better);
        format!(
            "; a better estimate was found ({}: cost {better:.9e}){}",
            match source {
                ImprovementSource::Refinement => "the estimate refined by the local solver",
                ImprovementSource::SdpRounding => "the SDP rounding polished by the local solver",
                ImprovementSource::BranchAndBound => "a local solve from a branch-and-bound cell",
                ImprovementSource::StaircaseRounding => {
                    "the staircase rounding polished by the local solver"
                }
            },
            if certified {
                ", which the bound below certifies globally optimal"
            } else {
                ""
            }
        )
    }

    /// The improvement, when strictly cheaper than the given estimate (recorded in the details).
    pub fn improvement(&mut self) -> Option<MultipleSolution> {
        match self.current.solution.take() {
            Some((s, source)) if self.cost - s.chordal_cost > 1e-15 * self.cost.abs() => {
                self.details.improvement = Some(Improvement {
                    source,
                    cost: s.chordal_cost,
                });
                Some(s)
            }
            _ => None,
        }
    }

    /// The escalation mode: the SDP (`Some(true)`), the staircase (`Some(false)`) or neither.
    pub fn wants_sdp(&self) -> Option<bool> {
        match self.settings.mode {
            CertifyMode::Auto => Some(self.problem.num_rotations() <= self.settings.sdp_max_nodes),
            CertifyMode::Sdp => Some(true),
            CertifyMode::Staircase => Some(false),
            _ => None,
        }
    }
}
