//! The certificate object shared by all problems (SPEC section 3): an upper bound (the cost of
//! the returned estimate), a proven lower bound on the global minimum, the gap, and a verdict.
//!
//! Soundness rule: [`Verdict::Certified`] is only produced by [`Certificate::from_bounds`] from a
//! lower bound that the caller has *verified independently* of any solver's own report (see
//! `paper-notes/certificates.md`). A certificate without a lower bound is never certified.

use serde::{Deserialize, Serialize};
use std::fmt;

/// Default tolerance on the relative gap `(f - lb) / max(|f|, 1e-12)` for a `Certified` verdict.
pub const DEFAULT_RELATIVE_GAP_TOLERANCE: f64 = 1e-6;
/// Default tolerance on the absolute gap `f - lb` (used for costs near zero, e.g. noise-free data).
pub const DEFAULT_ABSOLUTE_GAP_TOLERANCE: f64 = 1e-9;

/// The outcome of certification.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The estimate is globally optimal up to the stated gap tolerance.
    Certified,
    /// A proven lower bound exists, but the gap exceeds the tolerance.
    GapReported,
    /// No decision: no lower bound, or the numerical evidence is too imprecise to decide.
    Inconclusive,
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Verdict::Certified => "certified",
            Verdict::GapReported => "gap_reported",
            Verdict::Inconclusive => "inconclusive",
        })
    }
}

/// Which argument produced the lower bound.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoundMethod {
    /// A theorem (closed form, or a convexity argument).
    Theory,
    /// The dual certificate of the local solution (multipliers from first-order conditions).
    Dual,
    /// Multipliers from an SDP solve (Clarabel), verified by an independent eigenvalue check.
    Sdp,
    /// A rank-lifted (Riemannian staircase) solve of the SDP, with its own dual certificate.
    Staircase,
}

impl fmt::Display for BoundMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            BoundMethod::Theory => "theory",
            BoundMethod::Dual => "dual",
            BoundMethod::Sdp => "sdp",
            BoundMethod::Staircase => "staircase",
        })
    }
}

/// Tolerances for the verdict: certified when `gap <= max(abs_tol, rel_tol * max(|f|, 1e-12))`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GapTolerance {
    /// Relative gap tolerance.
    pub relative: f64,
    /// Absolute gap tolerance.
    pub absolute: f64,
}

impl Default for GapTolerance {
    fn default() -> Self {
        GapTolerance {
            relative: DEFAULT_RELATIVE_GAP_TOLERANCE,
            absolute: DEFAULT_ABSOLUTE_GAP_TOLERANCE,
        }
    }
}

/// A certificate of (sub)optimality for an estimate (SPEC sections 3 and 5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Certificate {
    /// The verdict.
    pub verdict: Verdict,
    /// Cost of the returned estimate.
    pub upper_bound: f64,
    /// A proven lower bound on the global minimum of the same cost, if one is available.
    pub lower_bound: Option<f64>,
    /// `upper_bound - lower_bound` (>= 0 up to rounding).
    pub gap: Option<f64>,
    /// `gap / max(|upper_bound|, 1e-12)`.
    pub relative_gap: Option<f64>,
    /// Smallest eigenvalue of the certificate matrix, where there is one.
    pub min_eigenvalue: Option<f64>,
    /// Which argument produced the bound.
    pub method: BoundMethod,
    /// The tolerance applied for the verdict.
    pub tolerance: GapTolerance,
    /// A sentence explaining the verdict (why certified, or why not).
    pub explanation: String,
    /// Time spent certifying, in seconds.
    pub seconds: f64,
    /// A **proven** lower bound on `lambda_min` of the certificate matrix whose multipliers gave
    /// `lower_bound` (Cholesky-verified with a floating-point margin, or Gershgorin, `[D5]`-`[D8]`;
    /// dense eigenvalues minus a rounding margin for the conjugate 10x10 matrix `[H8]`), where
    /// known. Omitted from JSON when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verified_min_eigenvalue: Option<f64>,
    /// **Estimates** (not bounds) of the smallest eigenvalues of that certificate matrix,
    /// computed only on request (e.g. the CLI's `--plot`), `[D14]`. Omitted from JSON when
    /// absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smallest_eigenvalues: Option<crate::certify::spectrum::SpectrumEstimate>,
}

impl Certificate {
    /// Build a certificate from an upper bound and an (independently verified) lower bound.
    /// The verdict is `Certified` iff a lower bound is given, both bounds are finite, and
    /// `gap <= max(tol.absolute, tol.relative * max(|ub|, 1e-12))`; `GapReported` when a finite
    /// lower bound exceeds that; `Inconclusive` when there is no usable lower bound.
    ///
    /// ```
    /// use rotavg::{BoundMethod, Certificate, Verdict};
    /// use rotavg::certificate::GapTolerance;
    /// let tol = GapTolerance::default(); // relative 1e-6, absolute 1e-9
    /// // A verified lower bound within 1e-6 relative of the cost: certified.
    /// let c = Certificate::from_bounds(10.0, Some(10.0 - 5e-6), BoundMethod::Dual, None, tol, "example", 0.0);
    /// assert_eq!(c.verdict, Verdict::Certified);
    /// assert!((c.gap.unwrap() - 5e-6).abs() < 1e-12);
    /// // A lower bound 10 % below the cost: the gap is proven but too large.
    /// let c = Certificate::from_bounds(10.0, Some(9.0), BoundMethod::Sdp, None, tol, "", 0.0);
    /// assert_eq!(c.verdict, Verdict::GapReported);
    /// assert!((c.relative_gap.unwrap() - 0.1).abs() < 1e-12);
    /// // No (finite) lower bound: never certified.
    /// let c = Certificate::from_bounds(10.0, Some(f64::NAN), BoundMethod::Dual, None, tol, "", 0.0);
    /// assert_eq!(c.verdict, Verdict::Inconclusive);
    /// assert!(c.lower_bound.is_none() && !c.is_certified());
    /// ```
    pub fn from_bounds(
        upper_bound: f64,
        lower_bound: Option<f64>,
        method: BoundMethod,
        min_eigenvalue: Option<f64>,
        tolerance: GapTolerance,
        explanation: impl Into<String>,
        seconds: f64,
    ) -> Self {
        let lb = lower_bound.filter(|l| l.is_finite());
        let scale = upper_bound.abs().max(1e-12);
        let (gap, rel, verdict) = match lb {
            Some(l) if upper_bound.is_finite() => {
                let gap = upper_bound - l;
                let rel = gap / scale;
                let ok = gap <= tolerance.absolute.max(tolerance.relative * scale);
                (
                    Some(gap),
                    Some(rel),
                    if ok {
                        Verdict::Certified
                    } else {
                        Verdict::GapReported
                    },
                )
            }
            _ => (None, None, Verdict::Inconclusive),
        };
        Certificate {
            verdict,
            upper_bound,
            lower_bound: lb,
            gap,
            relative_gap: rel,
            min_eigenvalue,
            method,
            tolerance,
            explanation: explanation.into(),
            seconds,
            verified_min_eigenvalue: None,
            smallest_eigenvalues: None,
        }
    }

    /// `true` iff the verdict is [`Verdict::Certified`].
    pub fn is_certified(&self) -> bool {
        self.verdict == Verdict::Certified
    }
}

impl fmt::Display for Certificate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} (method {}): cost {:.9e}",
            self.verdict, self.method, self.upper_bound
        )?;
        match (self.lower_bound, self.gap, self.relative_gap) {
            (Some(lb), Some(g), Some(r)) => {
                write!(f, ", lower bound {lb:.9e}, gap {g:.3e} (relative {r:.3e})")?
            }
            _ => write!(f, ", no lower bound")?,
        }
        if let Some(mu) = self.min_eigenvalue {
            write!(f, ", lambda_min {mu:.3e}")?;
        }
        write!(f, "; {}", self.explanation)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts() {
        let t = GapTolerance::default();
        let c =
            Certificate::from_bounds(1.0, Some(1.0 - 1e-8), BoundMethod::Dual, None, t, "", 0.0);
        assert_eq!(c.verdict, Verdict::Certified);
        let c = Certificate::from_bounds(1.0, Some(0.9), BoundMethod::Dual, None, t, "", 0.0);
        assert_eq!(c.verdict, Verdict::GapReported);
        let c = Certificate::from_bounds(1.0, None, BoundMethod::Dual, None, t, "", 0.0);
        assert_eq!(c.verdict, Verdict::Inconclusive);
        let c = Certificate::from_bounds(1.0, Some(f64::NAN), BoundMethod::Dual, None, t, "", 0.0);
        assert_eq!(c.verdict, Verdict::Inconclusive);
        let c = Certificate::from_bounds(f64::NAN, Some(0.0), BoundMethod::Dual, None, t, "", 0.0);
        assert_eq!(c.verdict, Verdict::Inconclusive);
        // noise-free: cost ~ 0, absolute tolerance applies
        let c = Certificate::from_bounds(1e-12, Some(-1e-11), BoundMethod::Dual, None, t, "", 0.0);
        assert_eq!(c.verdict, Verdict::Certified);
    }
}
