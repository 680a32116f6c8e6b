//! The dual certificate of chordal L2 multiple rotation averaging (contract section 3,
//! `paper-notes/certificates.md` `[D3]`-`[D9]`): the multipliers of an estimate
//! ([`mod@super::multipliers`]), the verified bound from them ([`super::verify`], the ladder of
//! proofs), the verdict, and why it is what it is ([`DualDiagnosis`]).
//!
//! - [`dual_certificate`]: the dual certificate of an estimate (any rotations, critical point or
//!   not); [`certify_with_multipliers`]: an estimate against multipliers obtained elsewhere.

use super::check::Scope;
use super::diagnosis::{DualDiagnosis, diagnose, diagnosis_text, over_budget};
use super::multipliers::{FirstOrder, check_lambdas, check_rotations, stationarity_residual};
use super::state::{Best, DualRun, State};
use super::verified::{RandomizedBound, VerifiedBound};
use super::verify::{verify, verify_own};
use crate::certify::budget::Deadline;
use crate::certify::certificate::{Certificate, RandomizedLowerBound};
use crate::certify::certification::ImprovementSource;
use crate::certify::log::{Outcome, Point, Prediction, Refusal};
use crate::certify::proof::{BoundMethod, Proof};
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifySettings;
use crate::error::Result;
use crate::multiple::MultipleProblem;
use crate::multiple::{Initialisation, MultipleSettings, solve_multiple};
use crate::so3::Rotation;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Instant;

/// The dual certificate of an estimate: the common [`Certificate`] plus diagnostics.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DualCertificate {
    /// Verdict, bounds, gap (method [`BoundMethod::Dual`]).
    pub certificate: Certificate,
    /// How the bound was obtained.
    pub bound: VerifiedBound,
    /// Why the verdict is what it is.
    pub diagnosis: DualDiagnosis,
    /// How the bound was proven, in words (the explanation without the verdict sentence).
    pub proof: String,
    /// First-order (stationarity) residual `sqrt(sum_i ||(Q Y)_i - Lambda_i R_i||_F^2)`: zero at a
    /// critical point `[D3]`. Equals `sqrt(sum_i ||skew((Q Y)_i R_i^T)||_F^2)`.
    pub stationarity_residual: f64,
}

impl fmt::Display for DualCertificate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}; stationarity residual {:.3e}",
            self.certificate, self.stationarity_residual
        )
    }
}

/// The dual certificate of an estimate of chordal L2 multiple rotation averaging (contract section
/// 3), with no escalation (see [`super::certify_multiple`] for the whole method): multipliers
/// from the first-order conditions `[D3]`, the verified bound `[D4]`, and the verdict from
/// `Certificate::from_bounds(f(Y), Some(lb), ..)`. Works for any rotations: at a point that is
/// not critical the bound is still valid but weaker, and the verdict is `Certified` only if the
/// gap is within tolerance. The estimate is never changed.
///
/// ```
/// use rotavg::certify::multiple::dual_certificate;
/// use rotavg::certify::CertifySettings;
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, gt) = SyntheticGraph { num_rotations: 20, num_edges: 40, noise_sigma: 0.0, ..Default::default() }.generate();
/// let c = dual_certificate(&p, &gt, &CertifySettings::default()).unwrap();
/// assert!(c.certificate.is_certified());
/// ```
pub fn dual_certificate(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
) -> Result<DualCertificate> {
    settings.validate()?;
    check_rotations(problem, rotations)?;
    let first = FirstOrder::at(problem, rotations)?;
    let scope = Scope {
        point: Point::Given,
        within: Proof::DualCertificate,
        deadline: Deadline::start(&settings.budget),
        refinement_follows: None,
    };
    let cost = problem.chordal_cost(rotations);
    dual_certificate_with(problem, rotations, cost, &first, settings, scope)
}

/// [`dual_certificate`] of `rotations` (cost `cost`) with their first-order quantities
/// already computed, in `scope` (the point and the clock of a certification).
pub(crate) fn dual_certificate_with(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    cost: f64,
    first: &FirstOrder,
    settings: &CertifySettings,
    scope: Scope,
) -> Result<DualCertificate> {
    let start = Instant::now();
    let stationarity = first.stationarity;
    let bound = verify_own(problem, rotations, first, cost.abs(), settings, scope)?;
    let min_eig = bound
        .min_eigenvalue_estimate
        .or(Some(bound.verified_min_eigenvalue));
    let mut certificate = Certificate::from_bounds(
        cost,
        over_budget(&bound).is_none().then_some(bound.lower_bound),
        BoundMethod::Dual,
        min_eig,
        settings.tolerance.resolve(problem.min_weight()),
        String::new(),
        0.0,
    );
    let diagnosis = diagnose(&certificate, &bound, stationarity);
    let randomized = attach_randomized(&mut certificate, bound.randomized);
    let proof = format!(
        "{}{}{randomized}",
        proof_text(&bound),
        estimate_text(&bound)
    );
    certificate.explanation = format!("{}; {proof}", diagnosis_text(&diagnosis, problem));
    certificate.verified_min_eigenvalue = Some(bound.verified_min_eigenvalue);
    certificate.seconds = start.elapsed().as_secs_f64();
    Ok(DualCertificate {
        certificate,
        bound,
        diagnosis,
        proof,
        stationarity_residual: stationarity,
    })
}

/// How the bound was proven, in words.
fn proof_text(bound: &VerifiedBound) -> String {
    match (bound.verification, bound.shift) {
        (Proof::ShiftedCholesky, Some(s)) => format!(
            "lambda_min(S) >= {:.3e} verified by a sparse Cholesky factorisation of S + {:.3e} I \
             ({:.2e} factor values; floating-point margin {:.1e})",
            bound.verified_min_eigenvalue, s, bound.factor_nonzeros as f64, bound.fp_margin
        ),
        (Proof::ScalarComparison, _) => scalar_text(bound),
        (Proof::BlockComparison, _) => format!(
            "lambda_min(S) >= {:.3e} verified by the block comparison [A15] (inertia of one \
             LDL^T factorisation of a 3n x 3n block Laplacian, {} values{}; backward error \
             {:.1e})",
            bound.verified_min_eigenvalue,
            bound.factor_nonzeros,
            match &bound.block_comparison {
                Some(c) if c.dropped_edges > 0 => format!(
                    ", of the graph without {} edges whose residuals stay charged",
                    c.dropped_edges
                ),
                _ => String::new(),
            },
            bound.fp_margin
        ),
        (Proof::Grounded, _) => match &bound.grounded {
            Some(g) => format!(
                "gauge null space deflated [D15]: S without node {}'s block >= {:.3e} I verified \
                 by a sparse Cholesky factorisation ({:.2e} factor values; floating-point margin \
                 {:.1e}); ||S Y|| <= {:.1e}, Y^T S Y >= -{:.1e} I; deficit {:.1e}",
                g.ground, g.c, bound.factor_nonzeros as f64, bound.fp_margin, g.rho, g.h, g.deficit
            ),
            None => "gauge null space deflated [D15]".into(),
        },
        _ if bound.factorization_skipped => format!(
            "{}; only the Gershgorin bound lambda_min(S) >= {:.3e} is proven",
            bound
                .budget_exceeded
                .clone()
                .unwrap_or_else(|| "no factorisation fits the budget".into()),
            bound.verified_min_eigenvalue
        ),
        _ => format!(
            "no factorisation proved it; Gershgorin bound lambda_min(S) >= {:.3e}",
            bound.verified_min_eigenvalue
        ),
    }
}

/// The scalar comparison's proof `[D13]` in words: its factorisations and its graph.
fn scalar_text(bound: &VerifiedBound) -> String {
    let comparison = bound.scalar_comparison.as_ref();
    let factors = match comparison.map_or(1, |c| c.parts) {
        1 => format!(
            "inertia of one LDL^T factorisation of an n x n matrix, {} values",
            bound.factor_nonzeros
        ),
        p => format!(
            "inertia of {p} LDL^T factorisations of n x n matrices, one per part of a split, each \
             proving its share; the largest {} values",
            bound.factor_nonzeros
        ),
    };
    let edges = match comparison {
        Some(c) if c.dropped_edges > 0 => format!(
            ", of the graph without {} edges whose residuals stay charged",
            c.dropped_edges
        ),
        Some(c) if c.shared_edges > 0 => {
            format!(", {} edges shared by several parts", c.shared_edges)
        }
        _ => String::new(),
    };
    let edges = match comparison {
        Some(c) if c.deflated > 0 => format!(
            "{edges}; the factor's columns at its {} negative pivots deflated",
            c.deflated
        ),
        _ => edges,
    };
    format!(
        "lambda_min(S) >= {:.3e} verified by the scalar comparison [D13] ({factors}{edges}; \
         backward error {:.1e})",
        bound.verified_min_eigenvalue, bound.fp_margin
    )
}

/// The estimate of `lambda_min(S)` beside the proof (never part of it).
fn estimate_text(bound: &VerifiedBound) -> String {
    bound
        .min_eigenvalue_estimate
        .map(|e| match bound.verification {
            Proof::Grounded | Proof::ScalarComparison => {
                format!("; gauge-direction estimate lambda_min(S) ~ {e:.3e}")
            }
            _ => format!("; Lanczos estimate lambda_min(S) ~ {e:.3e}"),
        })
        .unwrap_or_default()
}

/// The randomized bound `[D16]` of `bound`, when the verdict is not certified: attached to the
/// certificate (when the test passed) and returned as a sentence for the explanation.
pub(crate) fn attach_randomized(
    certificate: &mut Certificate,
    randomized: Option<RandomizedBound>,
) -> String {
    let Some(r) = randomized.filter(|_| !certificate.is_certified()) else {
        return String::new();
    };
    certificate.randomized = r.lower_bound.map(|lb| {
        RandomizedLowerBound::new(
            certificate.upper_bound,
            lb,
            &certificate.tolerance,
            r.outcome.failure_probability,
            r.seed,
        )
    });
    match &certificate.randomized {
        Some(c) => format!("; {r}; {c}"),
        None => format!("; {r}"),
    }
}

/// Certify an estimate against multipliers obtained elsewhere (an SDP solve, a staircase, the
/// multipliers of a better estimate): upper bound `f(rotations)`, lower bound verified from
/// `lambdas` `[D4]`-`[D8]`, verdict from `Certificate::from_bounds`, with the given `method`
/// (e.g. [`BoundMethod::Sdp`]). This is how an estimate that is not a critical point gets a useful
/// bound. The estimate is never changed.
///
/// ```
/// use rotavg::certify::multiple::{certify_with_multipliers, multipliers};
/// use rotavg::certify::CertifySettings;
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
) -> Result<DualCertificate> {
    let start = Instant::now();
    settings.validate()?;
    check_rotations(problem, rotations)?;
    check_lambdas(problem, lambdas)?;
    let cost = problem.chordal_cost(rotations);
    let stationarity = stationarity_residual(problem, rotations)?;
    let scope = Scope {
        point: Point::Sdp,
        within: Proof::Sdp,
        deadline: Deadline::start(&settings.budget),
        refinement_follows: None,
    };
    let bound = verify(
        problem,
        lambdas,
        Some(rotations),
        cost.abs(),
        settings,
        scope,
        None,
    )?;
    let explanation = format!(
        "bound from supplied multipliers ({method}): lambda_min(Q - blkdiag(Lambda)) >= {:.3e} verified by {}",
        bound.verified_min_eigenvalue,
        match bound.verification {
            Proof::ShiftedCholesky => "a sparse Cholesky factorisation",
            Proof::ScalarComparison => "the scalar comparison [D13]",
            Proof::BlockComparison => "the block comparison [A15]",
            Proof::Grounded => "the grounded bound [D15]",
            _ => "Gershgorin discs",
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
        settings.tolerance.resolve(problem.min_weight()),
        String::new(),
        start.elapsed().as_secs_f64(),
    );
    let diagnosis = diagnose(&certificate, &bound, stationarity);
    let explanation = format!(
        "{explanation}{}",
        attach_randomized(&mut certificate, bound.randomized)
    );
    certificate.explanation = format!("{}; {explanation}", diagnosis_text(&diagnosis, problem));
    certificate.verified_min_eigenvalue = Some(bound.verified_min_eigenvalue);
    Ok(DualCertificate {
        certificate,
        bound,
        diagnosis,
        proof: explanation,
        stationarity_residual: stationarity,
    })
}

/// Seconds per edge predicted for a dual certificate at a point: the multipliers, `S` and the
/// cheapest check (measured 4.5e-6 s per edge for the scalar comparison's work besides its
/// factorisation; a check's own factorisation is predicted inside the verification).
pub const DUAL_SECONDS_PER_EDGE: f64 = 1e-5;

/// The predicted seconds of a dual certificate at one point ([`DUAL_SECONDS_PER_EDGE`];
/// anisotropic blocks cost about three times the scalar path, issue 35).
fn dual_seconds(problem: &MultipleProblem) -> f64 {
    let per_edge = if problem.is_anisotropic() { 3.0 } else { 1.0 } * DUAL_SECONDS_PER_EDGE;
    per_edge * problem.num_edges() as f64
}

/// The dual certificate as the rung of a certification `[D3]`-`[D9]`, at every point once: the
/// given estimate (unless a cheap test shows its own multipliers cannot certify it, `[D15]`),
/// its refinement by the local solver (when the given estimate's certificate did not settle
/// it), and every better point found by another rung (an SDP's or the staircase's polished
/// rounding).
#[derive(Default)]
pub(crate) struct DualRung;

impl<'a> Rung<State<'a>> for DualRung {
    fn proof(&self) -> Proof {
        Proof::DualCertificate
    }

    fn plan(&mut self, cx: &State<'a>) -> Result<Plan> {
        let label = cx.current.label;
        let seconds = dual_seconds(cx.problem);
        // on data where the O(3) relaxation can prefer reflections it rarely proves [A5]
        let success = if cx.reflective { 0.2 } else { 1.0 };
        if !cx.dual_at.contains(&label) {
            // a verified (or bracketed) staircase: its rounding's certificate cannot do better
            if label == Point::Staircase && cx.staircase_verified == Some(true) {
                return Ok(Plan::Wait);
            }
            return Ok(Plan::Run(
                Prediction::new(seconds, 0.0).with_success(success),
            ));
        }
        Ok(if cx.wants_refinement() {
            // the refinement's local solve and the certificate of the refined point
            Plan::Run(Prediction::new(2.0 * seconds, 0.0).with_success(success))
        } else {
            Plan::Wait
        })
    }

    fn attempt(&mut self, cx: &mut State<'a>) -> Result<Found> {
        if cx.dual_at.contains(&cx.current.label) {
            return refine_and_certify(cx);
        }
        certify_current(cx, true)
    }
}

/// `Some(why)` when the given estimate is cheaply shown not to be a critical point whose own
/// multipliers could certify it (`[D15]`): its ladder is skipped, its refinement's certificate
/// bounds it as well, in a fraction of the time (issue 24). Records nothing.
fn given_hopeless(cx: &State<'_>, first: &FirstOrder) -> Option<String> {
    let rotations = &cx.current.rotations;
    let gap = cx.allowed_gap(cx.cost);
    let terms = first.gauge_terms(rotations);
    super::grounded::hopeless(cx.problem, rotations, &first.lambdas, terms, gap)
}

/// The dual certificate at the current point: its checks logged, its bound offered, its
/// diagnosis kept (at the given estimate, `test_hopeless` first runs the cheap test of
/// [`given_hopeless`]).
fn certify_current(cx: &mut State<'_>, test_hopeless: bool) -> Result<Found> {
    let label = cx.current.label;
    crate::progress::phase(crate::progress::Phase::Certify, || {
        format!(
            "dual certificate at {label} ({} nodes)",
            cx.problem.num_rotations()
        )
    });
    if !cx.dual_at.contains(&label) {
        cx.dual_at.push(label);
    }
    let rotations = cx.current.rotations.clone();
    let first = FirstOrder::at(cx.problem, &rotations)?;
    let stationarity = first.stationarity;
    if label == Point::Given {
        cx.given_stationarity_residual = Some(stationarity);
    }
    if label == Point::Given
        && test_hopeless
        && let Some(reason) = given_hopeless(cx, &first)
    {
        // not a critical point: the refinement's certificate is what can help
        cx.first = Some(DualDiagnosis::NotCritical {
            residual: stationarity,
        });
        return Ok(Found::refused(Refusal::NotApplicable { reason }));
    }
    let scope = Scope {
        point: label,
        within: Proof::DualCertificate,
        deadline: cx.deadline,
        // the given estimate's refinement follows a finding that it is not critical (unless
        // this is the full ladder run after a refinement that found nothing cheaper)
        refinement_follows: (label == Point::Given && test_hopeless)
            .then(|| dual_seconds(cx.problem)),
    };
    let cost = cx.current.cost;
    let c = dual_certificate_with(cx.problem, &rotations, cost, &first, cx.settings, scope)?;
    cx.log.extend(c.bound.ladder.iter().cloned());
    Ok(record(cx, c, first.lambdas.clone()))
}

/// Keep what one dual certificate found: the diagnosis (the given estimate's first), its bound
/// (unless no check fitted the budget), and its outcome for the log.
fn record(cx: &mut State<'_>, c: DualCertificate, lambdas: Vec<Matrix3<f64>>) -> Found {
    let label = cx.current.label;
    // no proof fitted (or ran): only Gershgorin's bound, not claimed
    let over = over_budget(&c.bound).is_some();
    let note = format!(
        "dual certificate at {label}: {}{}",
        diagnosis_text(&c.diagnosis, cx.problem),
        match (over, &c.bound.randomized) {
            (true, Some(r)) => format!("; {r}"),
            _ => String::new(),
        }
    );
    if label == Point::Given && cx.first.is_none() {
        cx.first = Some(c.diagnosis.clone());
    }
    cx.last = Some(DualRun {
        diagnosis: c.diagnosis.clone(),
        randomized: c.bound.randomized,
    });
    if let Some(reason) = over_budget(&c.bound) {
        // no proof fits: the Gershgorin bound is not offered (no lower bound is claimed)
        let refusal = Refusal::OverBudget { reason };
        return Found::new(Outcome::Refused(refusal), note);
    }
    cx.stationarity_residual = Some(c.stationarity_residual);
    let lower_bound = c.bound.lower_bound;
    cx.offer(Best {
        lower_bound,
        method: BoundMethod::Dual,
        point: label,
        min_eigenvalue: c.certificate.min_eigenvalue,
        explanation: c.proof.clone(),
        verified_min_eigenvalue: c.bound.verified_min_eigenvalue,
        // the grounded bound [D15] verifies no shift of S, but its lambda_min bound makes
        // S + (-mu) I positive semidefinite: the same shift-invert hint
        shift: c.bound.shift.or_else(|| {
            (c.bound.verification == Proof::Grounded)
                .then_some((-c.bound.verified_min_eigenvalue).max(0.0))
        }),
        lambdas: Some(lambdas),
    });
    Found::proved(lower_bound, cx.certifies(lower_bound), note)
}

/// How much costlier than the given estimate its refinement `rotations` may be and still be
/// adopted: on data where the `O(3)` relaxation prefers reflections (the `conv(SO(3))`
/// certificate needs a critical point), a refinement at least ten times more critical may cost
/// up to half the allowed gap more, which is the rounding of costs with information of `1e9`
/// (a strongly anisotropic SLAM graph of 1500 poses: residual 0.96 -> 2.3e-3 at a cost
/// `4.9e-5` higher, 1.3e-7 of it, as evaluated; certified there, `gap_reported` before);
/// elsewhere none.
fn critical_slack(cx: &State<'_>, rotations: &[Rotation]) -> f64 {
    let given = cx.given_stationarity_residual.unwrap_or(0.0);
    let refined = stationarity_residual(cx.problem, rotations).unwrap_or(f64::INFINITY);
    if cx.reflective && refined < 0.1 * given {
        0.5 * cx.allowed_gap(cx.current.cost)
    } else {
        0.0
    }
}

/// Refine the given estimate with the local solver (the default gradient tolerance times
/// [`REFINE_FACTOR`]) and certify the refined point; when the refinement finds nothing cheaper
/// and the given estimate's own certificate was skipped (hopeless), certify the given estimate
/// after all.
fn refine_and_certify(cx: &mut State<'_>) -> Result<Found> {
    cx.refined = true;
    let t = Instant::now();
    crate::progress::phase(crate::progress::Phase::Refine, String::new);
    let local = MultipleSettings {
        init: Initialisation::Given(cx.current.rotations.clone()),
        gradient_tolerance: MultipleSettings::default().gradient_tolerance * REFINE_FACTOR,
        // within the certification's time left (one clock)
        max_seconds: cx.deadline.left().map(|l| l.max(0.0)),
        ..Default::default()
    };
    let given = (cx.current.rotations.clone(), cx.current.cost);
    let adopted = match solve_multiple(cx.problem, &local) {
        Ok(r) => {
            let slack = critical_slack(cx, &r.rotations);
            cx.adopt_within(r, ImprovementSource::Refinement, Point::Refined, slack)
        }
        Err(_) => false,
    };
    cx.refine_seconds += t.elapsed().as_secs_f64();
    // the given estimate's checks were cut short by the finding that it is not critical
    let cut = matches!(cx.first, Some(DualDiagnosis::NotCritical { .. }));
    if adopted {
        let found = certify_current(cx, true)?.at(Point::Refined);
        if cut && !cx.best_certifies() {
            given_in_full(cx, given)?;
        }
        return Ok(found);
    }
    if cx.last.is_none() || cut {
        // not a critical point, and the refinement found nothing cheaper: its own ladder
        // (skipped, or cut short by that finding), in full
        return certify_current(cx, false);
    }
    Ok(Found::failed(
        "the refinement found no point of lower cost (the given estimate's certificate stands)",
    ))
}

/// The given estimate's checks in full, after its refinement's certificate did not certify
/// (they were cut short when it was found not critical): their bound may still be the best.
/// The refined point stays the current one.
fn given_in_full(cx: &mut State<'_>, (rotations, cost): (Vec<Rotation>, f64)) -> Result<()> {
    let given = super::state::Current {
        rotations,
        cost,
        label: Point::Given,
        solution: None,
    };
    let refined = std::mem::replace(&mut cx.current, given);
    let found = certify_current(cx, false);
    cx.current = refined;
    found.map(|_| ())
}

/// When the dual certificate fails, the estimate is refined once with the local solver's
/// default gradient tolerance multiplied by this factor, and the dual certificate is tried at
/// the refined point.
pub const REFINE_FACTOR: f64 = 1e-6;
