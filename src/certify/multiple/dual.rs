//! The dual certificate of chordal L2 multiple rotation averaging (SPEC section 3,
//! `paper-notes/certificates.md` `[D3]`-`[D9]`): the multipliers of an estimate
//! ([`mod@super::multipliers`]), the verified bound from them ([`super::verify`], the ladder of
//! proofs), the verdict, and why it is what it is ([`DualDiagnosis`]).
//!
//! - [`dual_certificate`]: the dual certificate of an estimate (any rotations, critical point or
//!   not); [`certify_with_multipliers`]: an estimate against multipliers obtained elsewhere.

use super::multipliers::{check_lambdas, check_rotations, multipliers, stationarity_residual};
use super::randomized::{ComplementEstimate, RandomizedBound};
use super::verify::{Verification, VerifiedBound, verify};
use crate::certify::certificate::{BoundMethod, Certificate, RandomizedLowerBound};
use crate::certify::ladder::Point;
use crate::certify::settings::CertifySettings;
use crate::error::Result;
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Instant;

/// Why a dual certificate has its verdict `[D9]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "diagnosis", rename_all = "snake_case")]
pub enum DualDiagnosis {
    /// The gap is within the tolerance.
    Certified,
    /// The estimate is not a critical point: its stationarity residual `[D3]` is too large for
    /// a bound within the tolerance (the cost is above the nearby optimum by about
    /// `residual^2 / c`); refining it is the remedy.
    NotCritical {
        /// The stationarity residual.
        residual: f64,
    },
    /// `S` has a negative eigenvalue (estimate below): the estimate is a saddle or a non-global
    /// local minimum of the nonconvex problem, or the relaxation is not tight.
    Indefinite {
        /// The (Lanczos) estimate of `lambda_min(S)`.
        min_eigenvalue: f64,
    },
    /// `S` is positive semidefinite up to the verification's precision, but the gap that
    /// precision allows is above the tolerance.
    PrecisionLimited {
        /// The smallest gap the verification proved.
        smallest_gap: f64,
    },
    /// No proof fits the budget ([`crate::certify::Budget`]): no lower bound is claimed.
    OverBudget {
        /// What would not fit.
        reason: String,
        /// The Lanczos *estimate* of `lambda_min(S)` (never a proof), if computed.
        min_eigenvalue_estimate: Option<f64>,
        /// The estimate on the complement of the gauge directions, when the rotations were
        /// known (never a proof).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        complement_estimate: Option<ComplementEstimate>,
    },
}

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

/// The dual certificate of an estimate of chordal L2 multiple rotation averaging (SPEC section
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
    dual_certificate_at(problem, rotations, settings, Point::Given)
}

/// [`dual_certificate`] with `point` labelling its ladder (the given or the refined estimate).
pub(super) fn dual_certificate_at(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
    point: Point,
) -> Result<DualCertificate> {
    let start = Instant::now();
    settings.validate()?;
    check_rotations(problem, rotations)?;
    let cost = problem.chordal_cost(rotations);
    let lambdas = multipliers(problem, rotations)?;
    let stationarity = stationarity_residual(problem, rotations)?;
    let bound = verify(
        problem,
        &lambdas,
        Some(rotations),
        cost.abs(),
        settings,
        point,
        None,
    )?;
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
        (Verification::Cholesky, Some(s)) => format!(
            "lambda_min(S) >= {:.3e} verified by a sparse Cholesky factorisation of S + {:.3e} I \
             ({:.2e} factor values; floating-point margin {:.1e})",
            bound.verified_min_eigenvalue, s, bound.factor_nonzeros as f64, bound.fp_margin
        ),
        (Verification::ScalarComparison, _) => scalar_text(bound),
        (Verification::Grounded, _) => match &bound.grounded {
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
            Verification::Grounded | Verification::ScalarComparison => {
                format!("; gauge-direction estimate lambda_min(S) ~ {e:.3e}")
            }
            _ => format!("; Lanczos estimate lambda_min(S) ~ {e:.3e}"),
        })
        .unwrap_or_default()
}

/// The randomized bound `[D16]` of `bound`, when the verdict is not certified: attached to the
/// certificate (when the test passed) and returned as a sentence for the explanation.
pub(super) fn attach_randomized(
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

/// Why a dual certificate has its verdict: certified; the estimate is not a critical point (the
/// grounded bound said so, or its deficit dominates); `S` is indefinite (a negative eigenvalue
/// estimate beyond the verification's precision); or the precision ran out.
fn diagnose(certificate: &Certificate, bound: &VerifiedBound, residual: f64) -> DualDiagnosis {
    if certificate.is_certified() {
        return DualDiagnosis::Certified;
    }
    if let Some(reason) = over_budget(bound) {
        return DualDiagnosis::OverBudget {
            reason,
            min_eigenvalue_estimate: bound.min_eigenvalue_estimate,
            complement_estimate: bound.complement_estimate.clone(),
        };
    }
    let gap = certificate.gap.unwrap_or(f64::INFINITY);
    if bound.not_critical
        || bound
            .grounded
            .is_some_and(|g| g.deficit >= 0.5 * gap && g.rho * g.rho / g.c >= g.h)
    {
        return DualDiagnosis::NotCritical { residual };
    }
    let precision = -(bound.verified_min_eigenvalue.min(0.0));
    match bound.min_eigenvalue_estimate {
        Some(e) if bound.grounded.is_none() && e < -2.0 * precision.max(f64::MIN_POSITIVE) => {
            DualDiagnosis::Indefinite { min_eigenvalue: e }
        }
        _ if bound.negative_eigenvector.is_some() => DualDiagnosis::Indefinite {
            min_eigenvalue: bound.min_eigenvalue_estimate.unwrap_or(f64::NAN),
        },
        _ => DualDiagnosis::PrecisionLimited { smallest_gap: gap },
    }
}

/// The budget's reason when no factorisation fit and only Gershgorin's bound is left: no
/// lower bound is claimed then (the verdict is `inconclusive`, issue 15).
fn over_budget(bound: &VerifiedBound) -> Option<String> {
    (bound.verification == Verification::Gershgorin)
        .then(|| bound.budget_exceeded.clone())
        .flatten()
}

/// The verdict sentence of a diagnosis.
pub(crate) fn diagnosis_text(d: &DualDiagnosis, problem: &MultipleProblem) -> String {
    match d {
        DualDiagnosis::Certified => format!(
            "certified globally optimal for the {}chordal L2 cost of its {} edges (over O(3)^n, \
             hence SO(3)^n)",
            if problem.is_anisotropic() {
                "anisotropic "
            } else {
                ""
            },
            problem.num_edges()
        ),
        DualDiagnosis::NotCritical { residual } => format!(
            "not certified: the estimate is not a critical point (stationarity residual {residual:.3e}): its cost is above the nearby optimum, and its bound is correspondingly weaker"
        ),
        DualDiagnosis::Indefinite { min_eigenvalue } => format!(
            "not certified: the certificate matrix S is indefinite (lambda_min(S) ~ {min_eigenvalue:.3e}): the estimate is a saddle or a non-global local minimum of the nonconvex problem, or the relaxation is not tight{}",
            if problem.is_anisotropic() {
                " (with anisotropic information the O(3) relaxation can prefer reflections)"
            } else {
                ""
            }
        ),
        DualDiagnosis::PrecisionLimited { smallest_gap } => format!(
            "not certified: precision ran out: S is positive semidefinite up to the verification's floating-point precision, and the smallest gap it can prove here is {smallest_gap:.3e}"
        ),
        DualDiagnosis::OverBudget {
            reason,
            min_eigenvalue_estimate,
            complement_estimate,
        } => match complement_estimate {
            Some(c) => format!("inconclusive: {reason}; {c}"),
            None => format!(
                "inconclusive: {reason}{}",
                min_eigenvalue_estimate
                    .map(|e| format!(
                        "; Lanczos estimate lambda_min(S) ~ {e:.3e} (an estimate, not a proof)"
                    ))
                    .unwrap_or_default()
            ),
        },
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
    let bound = verify(
        problem,
        lambdas,
        Some(rotations),
        cost.abs(),
        settings,
        Point::Sdp,
        None,
    )?;
    let explanation = format!(
        "bound from supplied multipliers ({method}): lambda_min(Q - blkdiag(Lambda)) >= {:.3e} verified by {}",
        bound.verified_min_eigenvalue,
        match bound.verification {
            Verification::Cholesky => "a sparse Cholesky factorisation",
            Verification::Gershgorin => "Gershgorin discs",
            Verification::ScalarComparison => "the scalar comparison [D13]",
            Verification::Grounded => "the grounded bound [D15]",
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
