//! Certificates of chordal L2 multiple rotation averaging (SPEC section 3,
//! `paper-notes/certificates.md`, `[D3]`-`[D14]`).
//!
//! - [`certify_multiple`]: the whole method for an estimate: the dual certificate `[D3]`-`[D9]`
//!   (at the estimate, or at its refinement when the estimate is not an accurate critical
//!   point), then, when that fails and the mode allows, the SDP relaxation (multipliers verified
//!   `[D4]`, rounding polished) or the Riemannian staircase `[D11]`. The largest verified bound
//!   wins `[D12]`.
//! - [`dual`]: the dual certificate and the verified bound from *any* multipliers.
//! - [`randomized`]: the randomized Chebyshev test `[D16]`: a Monte Carlo bound reported
//!   beside an `inconclusive` verdict when no deterministic proof fits the budget.
//! - [`scalar`]: the scalar comparison `[D13]`: a proof that `S` is positive semidefinite from
//!   one factorisation of an `n x n` scalar matrix (fast on graphs whose `3n x 3n` factor fills).
//! - [`staircase`]: the Riemannian staircase (rank-lifted Burer-Monteiro descent).

pub mod dual;
pub mod randomized;
pub mod scalar;
pub mod staircase;

pub use dual::{
    ComplementEstimate, DualCertificate, DualDiagnosis, GroundedBound, Verification, VerifiedBound,
    certificate_matrix, certify_with_multipliers, dual_certificate, laplacian_times,
    lower_bound_from_multipliers, multipliers, stationarity_residual,
};
pub use randomized::RandomizedBound;

use super::certificate::{BoundMethod, Certificate};
use super::certification::{
    Certification, CertifyDetails, Improvement, ImprovementSource, MethodRun, SdpSummary,
};
use super::settings::{CertifyMode, CertifySettings};
use super::spectrum::certificate_spectrum;
use crate::error::Result;
use crate::multiple::{
    Initialisation, MultipleProblem, MultipleSettings, MultipleSolution, solve_multiple,
};
use crate::relax::relax_multiple;
use crate::so3::Rotation;
use dual::{attach_randomized, check_rotations, diagnosis_text};
use nalgebra::Matrix3;
use std::time::Instant;

/// When the dual certificate fails, the estimate is refined once with the local solver's
/// default gradient tolerance multiplied by this factor, and the dual certificate is tried at
/// the refined point.
pub const REFINE_FACTOR: f64 = 1e-6;

const MARGIN_LIMITED: &str = "SDP / staircase skipped: the estimate is a critical point whose \
certificate matrix is PSD up to the floating-point precision of the verification; the gap is that \
precision, which other multipliers cannot improve (mode sdp or staircase runs them anyway)";

/// The best verified bound seen so far.
struct Best {
    lower_bound: f64,
    method: BoundMethod,
    min_eigenvalue: Option<f64>,
    explanation: String,
    /// Verified lower bound on `lambda_min` of this bound's certificate matrix.
    verified_min_eigenvalue: f64,
    /// The Cholesky shift that verified it, if any (a shift-invert hint for the spectrum).
    shift: Option<f64>,
    /// The multipliers of this bound's certificate matrix (`None` for the staircase).
    lambdas: Option<Vec<Matrix3<f64>>>,
}

impl Best {
    fn offer(slot: &mut Option<Best>, cand: Best) {
        if slot
            .as_ref()
            .is_none_or(|b| cand.lower_bound > b.lower_bound)
        {
            *slot = Some(cand);
        }
    }
}

/// The point whose multipliers are verified: the estimate, or a better solution found on the
/// way (refinement, SDP rounding).
struct Point {
    rotations: Vec<Rotation>,
    cost: f64,
    /// `Some` when it is not the given estimate.
    solution: Option<(MultipleSolution, ImprovementSource)>,
}

impl Point {
    /// Adopt `candidate` when its chordal cost is not higher.
    fn offer(&mut self, candidate: MultipleSolution, source: ImprovementSource) -> bool {
        if candidate.chordal_cost <= self.cost {
            self.rotations = candidate.rotations.clone();
            self.cost = candidate.chordal_cost;
            self.solution = Some((candidate, source));
            true
        } else {
            false
        }
    }
}

/// Certify an estimate of chordal L2 multiple rotation averaging **without changing it** (modes
/// `auto`, `dual`, `sdp`, `staircase`). Upper bound: its chordal cost. Lower bound: the largest
/// verified bound among
///
/// 1. the dual certificate `[D3]`-`[D9]`, `[D15]` at the estimate, and, when that does not
///    certify, at its refinement by the local solver;
/// 2. when that does not certify and the mode allows: the SDP's verified multipliers
///    (`n <= sdp_max_nodes` in `auto`, always in `sdp`) or the Riemannian staircase `[D11]`
///    (larger graphs in `auto`, always in `staircase`).
///
/// Each is a bound on the global minimum whatever point produced it. A refined point or a
/// polished SDP rounding of lower cost than the estimate is returned as the
/// [`Certification::improvement`] (the pipeline [`crate::pipeline::average_multiple`] adopts
/// it). The gap tolerance follows `settings.tolerance` with the median edge weight (`[D12]`).
/// Objectives other than chordal L2 get an `inconclusive` certificate.
///
/// ```
/// use rotavg::certify::{certify_multiple, CertifySettings};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, gt) = SyntheticGraph { num_rotations: 20, num_edges: 40, noise_sigma: 0.0, ..Default::default() }.generate();
/// let c = certify_multiple(&p, &gt, &CertifySettings::default())?;
/// assert!(c.certificate.is_certified());
/// assert!(c.improvement.is_none()); // the ground truth of noise-free data is optimal
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn certify_multiple(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
) -> Result<Certification<MultipleSolution>> {
    let start = Instant::now();
    settings.validate()?;
    settings.mode.require(
        "multiple",
        &[
            CertifyMode::Auto,
            CertifyMode::Dual,
            CertifyMode::Sdp,
            CertifyMode::Staircase,
        ],
    )?;
    check_rotations(problem, rotations)?;
    let cost = problem.chordal_cost(rotations);
    let mut details = CertifyDetails {
        mode: settings.mode,
        ..Default::default()
    };
    let objective = problem.objective();
    if !objective.is_chordal_l2() {
        let why = format!(
            "no lower bound for the {objective} cost: the certificates bound chordal L2 only"
        );
        details.skipped_reason = Some(why.clone());
        details.seconds = start.elapsed().as_secs_f64();
        let certificate = Certificate::from_bounds(
            problem.cost(rotations),
            None,
            BoundMethod::Dual,
            None,
            settings.tolerance.resolve(problem.min_weight()),
            why,
            details.seconds,
        );
        return Ok(Certification {
            certificate,
            details,
            improvement: None,
        });
    }
    let mut best = None;
    let mut point = Point {
        rotations: rotations.to_vec(),
        cost,
        solution: None,
    };
    // The dual certificate needs an accurate critical point: its deficit is about
    // `rho^2 / c` for the stationarity residual `rho` [D15], which is also how far the cost is
    // above the nearby optimum. When it does not certify, the estimate is refined once with a
    // much tighter tolerance (Newton converges quadratically: a few iterations) and the
    // certificate is tried at the refined point.
    let first = run_dual(problem, &point, settings, &mut details, &mut best)?;
    let mut last = first.clone();
    let over_time = |details: &mut CertifyDetails, step: &str| -> bool {
        match settings.budget.max_seconds {
            Some(limit) if start.elapsed().as_secs_f64() > limit => {
                details.skipped_reason = Some(format!(
                    "{step} not run: the time budget of {limit} s is spent"
                ));
                true
            }
            _ => false,
        }
    };
    if !matches!(
        last.diagnosis,
        DualDiagnosis::Certified
            | DualDiagnosis::PrecisionLimited { .. }
            | DualDiagnosis::OverBudget { .. }
    ) && !over_time(&mut details, "refinement")
        && refine(problem, &mut point, &mut details)
    {
        last = run_dual(problem, &point, settings, &mut details, &mut best)?;
    }
    let explicit = matches!(settings.mode, CertifyMode::Sdp | CertifyMode::Staircase);
    let escalate = match last.diagnosis {
        DualDiagnosis::Certified => {
            if explicit {
                details.skipped_reason = Some(format!(
                    "{} not run: the dual certificate already certified the estimate",
                    settings.mode
                ));
            }
            false
        }
        DualDiagnosis::PrecisionLimited { .. } if !explicit => {
            details.skipped_reason = Some(MARGIN_LIMITED.into());
            false
        }
        DualDiagnosis::OverBudget { .. } => false,
        _ => !over_time(&mut details, "SDP / staircase"),
    };
    if escalate {
        match wants_sdp(
            settings.mode,
            problem.num_rotations(),
            settings.sdp_max_nodes,
        ) {
            Some(true) => {
                if let Some(p) = run_sdp(problem, settings, start, &mut details, &mut best)?
                    && p.chordal_cost < point.cost
                    && point.offer(p, ImprovementSource::SdpRounding)
                {
                    run_dual(problem, &point, settings, &mut details, &mut best)?;
                }
            }
            Some(false) => run_staircase(problem, &point, settings, &mut details, &mut best)?,
            None => {
                if settings.mode == CertifyMode::Auto {
                    details.skipped_reason = Some(format!(
                        "SDP not run: {} nodes > sdp_max_nodes {}",
                        problem.num_rotations(),
                        settings.sdp_max_nodes
                    ));
                }
            }
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    let mut certificate = final_certificate(
        problem,
        cost,
        best,
        &first.diagnosis,
        point
            .solution
            .as_ref()
            .map(|(s, src)| (s.chordal_cost, *src)),
        settings,
        seconds,
    );
    // a Monte Carlo bound [D16] is a bound on the global minimum whatever point gave it
    let randomized = attach_randomized(&mut certificate, last.randomized);
    certificate.explanation.push_str(&randomized);
    details.seconds = seconds;
    let improvement = match point.solution {
        Some((s, source)) if cost - s.chordal_cost > 1e-15 * cost.abs() => {
            details.improvement = Some(Improvement {
                source,
                cost: s.chordal_cost,
            });
            Some(s)
        }
        _ => None,
    };
    Ok(Certification {
        certificate,
        details,
        improvement,
    })
}

fn wants_sdp(mode: CertifyMode, n: usize, max_nodes: usize) -> Option<bool> {
    match mode {
        CertifyMode::Auto => Some(n <= max_nodes),
        CertifyMode::Sdp => Some(true),
        CertifyMode::Staircase => Some(false),
        _ => None,
    }
}

/// Re-solve (chordal) from the point with the default gradient tolerance times
/// [`REFINE_FACTOR`]; adopts the result when its cost is not higher. Returns whether it did.
fn refine(problem: &MultipleProblem, point: &mut Point, details: &mut CertifyDetails) -> bool {
    let t = Instant::now();
    crate::progress::phase(crate::progress::Phase::Refine, String::new);
    let local = MultipleSettings {
        init: Initialisation::Given(point.rotations.clone()),
        gradient_tolerance: MultipleSettings::default().gradient_tolerance * REFINE_FACTOR,
        ..Default::default()
    };
    let adopted = match solve_multiple(problem, &local) {
        Ok(r) => point.offer(r, ImprovementSource::Refinement),
        Err(_) => false,
    };
    details.refine_seconds += t.elapsed().as_secs_f64();
    adopted
}

/// What one dual certificate said.
#[derive(Debug, Clone)]
struct DualRun {
    diagnosis: DualDiagnosis,
    /// The randomized bound `[D16]`, when no deterministic proof fit the budget.
    randomized: Option<RandomizedBound>,
}

/// Dual certificate at the point: records the run, offers its bound, returns its diagnosis
/// (certified against the point's own cost). `PrecisionLimited`: the point is a critical point
/// and `S` is PSD up to the verification's floating-point margin `[D6]`, `[D15]`: the SDP /
/// staircase multipliers (verified the same way, at the same optimum) cannot do better.
fn run_dual(
    problem: &MultipleProblem,
    point: &Point,
    settings: &CertifySettings,
    details: &mut CertifyDetails,
    best: &mut Option<Best>,
) -> Result<DualRun> {
    crate::progress::phase(crate::progress::Phase::Certify, || {
        format!(
            "dual certificate{} ({} nodes)",
            if point.solution.is_some() {
                " at the refined estimate"
            } else {
                ""
            },
            problem.num_rotations()
        )
    });
    let c = dual_certificate(problem, &point.rotations, settings)?;
    if let DualDiagnosis::OverBudget { reason, .. } = &c.diagnosis {
        // no proof fits: the Gershgorin bound is not offered (no lower bound is claimed)
        details.skipped_reason = Some(reason.clone());
        details.methods.push(MethodRun {
            method: BoundMethod::Dual,
            lower_bound: None,
            seconds: c.certificate.seconds,
            note: format!(
                "dual certificate: {}{}",
                diagnosis_text(&c.diagnosis),
                c.bound
                    .randomized
                    .map(|r| format!("; {r}"))
                    .unwrap_or_default()
            ),
        });
        return Ok(DualRun {
            diagnosis: c.diagnosis,
            randomized: c.bound.randomized,
        });
    }
    Best::offer(
        best,
        Best {
            lower_bound: c.bound.lower_bound,
            method: BoundMethod::Dual,
            min_eigenvalue: c.certificate.min_eigenvalue,
            explanation: c.proof.clone(),
            verified_min_eigenvalue: c.bound.verified_min_eigenvalue,
            // the grounded bound [D15] verifies no shift of S, but its lambda_min bound makes
            // S + (-mu) I positive semidefinite: the same shift-invert hint for the spectrum
            shift: c.bound.shift.or_else(|| {
                (c.bound.verification == Verification::Grounded)
                    .then_some((-c.bound.verified_min_eigenvalue).max(0.0))
            }),
            // O(m), negligible next to the verification
            lambdas: Some(multipliers(problem, &point.rotations)?),
        },
    );
    details.stationarity_residual = Some(c.stationarity_residual);
    details.methods.push(MethodRun {
        method: BoundMethod::Dual,
        lower_bound: Some(c.bound.lower_bound),
        seconds: c.certificate.seconds,
        note: format!(
            "dual certificate{}: {}",
            if point.solution.is_some() {
                " at the refined estimate"
            } else {
                ""
            },
            diagnosis_text(&c.diagnosis)
        ),
    });
    Ok(DualRun {
        diagnosis: c.diagnosis,
        randomized: c.bound.randomized,
    })
}

/// Run the SDP and verify its multipliers; returns the SDP's rounding polished by the local
/// solver.
fn run_sdp(
    problem: &MultipleProblem,
    settings: &CertifySettings,
    start: Instant,
    details: &mut CertifyDetails,
    best: &mut Option<Best>,
) -> Result<Option<MultipleSolution>> {
    let t = Instant::now();
    crate::progress::phase(crate::progress::Phase::Sdp, || {
        format!("{} nodes", problem.num_rotations())
    });
    // the SDP may use what is left of the time budget
    let mut sdp_settings = settings.sdp.clone();
    if let Some(limit) = settings.budget.max_seconds {
        let left = (limit - start.elapsed().as_secs_f64()).max(1e-3);
        sdp_settings.time_limit_seconds = Some(
            sdp_settings
                .time_limit_seconds
                .map_or(left, |t| t.min(left)),
        );
    }
    let sdp = relax_multiple(problem, &sdp_settings)?;
    let bound = if sdp.multipliers.len() == problem.num_rotations()
        && sdp
            .multipliers
            .iter()
            .all(|l| l.iter().all(|x| x.is_finite()))
    {
        Some(lower_bound_from_multipliers(
            problem,
            &sdp.multipliers,
            settings,
        )?)
    } else {
        None
    };
    // round + polish with the chordal local solver
    let polished = if sdp.rounded.len() == problem.num_rotations() {
        let local = MultipleSettings {
            init: Initialisation::Given(sdp.rounded.clone()),
            ..Default::default()
        };
        solve_multiple(problem, &local).ok()
    } else {
        None
    };
    let eigenvalue_ratio = match sdp.x_top_eigenvalues.as_slice() {
        [_, _, l3, l4, ..] if *l3 > 0.0 => l4.max(0.0) / l3,
        _ => f64::NAN,
    };
    details.sdp = Some(SdpSummary {
        status: sdp.status,
        iterations: sdp.iterations,
        seconds: sdp.seconds,
        eigenvalue_ratio,
        rounded_cost: Some(sdp.rounded_cost),
        polished_cost: polished.as_ref().map(|p| p.chordal_cost),
    });
    let note = format!(
        "Clarabel SDP ({:?}, {} iterations, {:.3} s); multipliers verified{}; rounding cost {:.9e}{}",
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
            .unwrap_or_default()
    );
    if let Some(b) = &bound {
        Best::offer(
            best,
            Best {
                lower_bound: b.lower_bound,
                method: BoundMethod::Sdp,
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
            },
        );
    }
    details.methods.push(MethodRun {
        method: BoundMethod::Sdp,
        lower_bound: bound.map(|b| b.lower_bound),
        seconds: t.elapsed().as_secs_f64(),
        note,
    });
    Ok(polished)
}

fn run_staircase(
    problem: &MultipleProblem,
    point: &Point,
    settings: &CertifySettings,
    details: &mut CertifyDetails,
    best: &mut Option<Best>,
) -> Result<()> {
    let t = Instant::now();
    crate::progress::phase(crate::progress::Phase::Staircase, String::new);
    let r = staircase::staircase_bound(problem, &point.rotations, settings)?;
    Best::offer(
        best,
        Best {
            lower_bound: r.bound.lower_bound,
            method: BoundMethod::Staircase,
            min_eigenvalue: r
                .bound
                .min_eigenvalue_estimate
                .or(Some(r.bound.verified_min_eigenvalue)),
            explanation: r.certificate.explanation.clone(),
            verified_min_eigenvalue: r.bound.verified_min_eigenvalue,
            shift: r.bound.shift,
            lambdas: None,
        },
    );
    details.methods.push(MethodRun {
        method: BoundMethod::Staircase,
        lower_bound: Some(r.bound.lower_bound),
        seconds: t.elapsed().as_secs_f64(),
        note: format!(
            "Riemannian staircase: rank {}, {} iterations, lifted cost {:.9e}; {}",
            r.rank, r.iterations, r.lifted_cost, r.stop_reason
        ),
    });
    Ok(())
}

/// The certificate from the best bound; with `settings.spectrum` set, also the
/// smallest-eigenvalue estimates of that bound's certificate matrix `[D14]`. The explanation
/// states the verdict for the given estimate (`first`: the dual diagnosis there), the better
/// estimate found if any, and how the bound was proven.
fn final_certificate(
    problem: &MultipleProblem,
    cost: f64,
    best: Option<Best>,
    first: &DualDiagnosis,
    improvement: Option<(f64, ImprovementSource)>,
    settings: &CertifySettings,
    seconds: f64,
) -> Certificate {
    let tolerance = settings.tolerance.resolve(problem.min_weight());
    let Some(b) = best else {
        // say why (e.g. the budget's reason and the labelled estimate), not only that
        return Certificate::from_bounds(
            cost,
            None,
            BoundMethod::Dual,
            None,
            tolerance,
            format!(
                "no lower bound could be computed; {}",
                diagnosis_text(first)
            ),
            seconds,
        );
    };
    let mut c = Certificate::from_bounds(
        cost,
        Some(b.lower_bound),
        b.method,
        b.min_eigenvalue,
        tolerance,
        String::new(),
        seconds,
    );
    let mut verdict = if c.is_certified() {
        diagnosis_text(&DualDiagnosis::Certified)
    } else {
        match first {
            // the estimate's own dual certificate would certify, but a bound from another
            // point is what was kept: say it plainly
            DualDiagnosis::Certified => "not certified within the tolerance".to_string(),
            d => diagnosis_text(d),
        }
    };
    if let Some((better, source)) = improvement
        && better < cost
    {
        let certified =
            b.lower_bound.is_finite() && better - b.lower_bound <= tolerance.allowed_gap(better);
        verdict.push_str(&format!(
            "; a better estimate was found ({}: cost {better:.9e}){}",
            match source {
                ImprovementSource::Refinement => "the estimate refined by the local solver",
                ImprovementSource::SdpRounding => "the SDP rounding polished by the local solver",
                ImprovementSource::BranchAndBound => "a local solve from a branch-and-bound cell",
            },
            if certified {
                ", which the bound below certifies globally optimal"
            } else {
                ""
            }
        ));
    }
    c.explanation = format!("{verdict}; bound ({}): {}", b.method, b.explanation);
    c.verified_min_eigenvalue = Some(b.verified_min_eigenvalue);
    if let (Some(sp), Some(l)) = (settings.spectrum.as_ref(), &b.lambdas) {
        // an estimate for a figure: its failure never fails the certification
        c.smallest_eigenvalues = certificate_spectrum(problem, l, sp, b.shift).ok();
    }
    c
}
