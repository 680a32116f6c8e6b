//! Why a dual certificate has its verdict `[D9]` ([`DualDiagnosis`]), decided from the
//! certificate and the verified bound, and said in words.

use super::verified::ComplementEstimate;
use super::verified::VerifiedBound;
use crate::certify::certificate::Certificate;
use crate::certify::proof::Proof;
use crate::multiple::MultipleProblem;
use serde::{Deserialize, Serialize};

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
    /// No proof fits the budget ([`crate::certify::budget::Budget`]): no lower bound is claimed.
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

/// Why a dual certificate has its verdict: certified; the estimate is not a critical point (the
/// grounded bound said so, or its deficit dominates); `S` is indefinite (a negative eigenvalue
/// estimate beyond the verification's precision); or the precision ran out.
pub(crate) fn diagnose(
    certificate: &Certificate,
    bound: &VerifiedBound,
    residual: f64,
) -> DualDiagnosis {
    if certificate.is_certified() {
        return DualDiagnosis::Certified;
    }
    // found not critical (which may have cut the checks short, `Scope::refinement_follows`):
    // the refinement is what can certify, whether or not a check fitted the budget
    if bound.not_critical {
        return DualDiagnosis::NotCritical { residual };
    }
    if let Some(reason) = over_budget(bound) {
        return DualDiagnosis::OverBudget {
            reason,
            min_eigenvalue_estimate: bound.min_eigenvalue_estimate,
            complement_estimate: bound.complement_estimate.clone(),
        };
    }
    let gap = certificate.gap.unwrap_or(f64::INFINITY);
    if bound
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
pub(crate) fn over_budget(bound: &VerifiedBound) -> Option<String> {
    (bound.verification == Proof::Gershgorin)
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
