//! The state of certifying one unknown rotation (the single mean, the conjugate `S`): one shape
//! for both problems. Its rungs are the theorems ([`crate::certify::single`]), the SDP
//! ([`crate::certify::conjugate`]) and the branch and bound over SO(3)
//! ([`crate::certify::branch_and_bound`]); every bound is of a cost that is a sum of
//! nonnegative terms, capped at the estimate's cost
//! (`nonnegative_bound_at_most`).

use super::budget::{Budget, Deadline};
use super::certificate::{Certificate, nonnegative_bound_at_most};
use super::certification::{
    Certification, CertifyDetails, Improvement, ImprovementSource, SdpSummary,
};
use super::evidence::BranchAndBoundStats;
use super::evidence::SpectrumEstimate;
use super::log::Attempt;
use super::proof::Proof;
use super::rung::Climb;
use super::settings::CertifySettings;
use super::tolerance::GapTolerance;
use crate::so3::Rotation;

/// The best verified bound so far, and what the certificate says of it.
pub(crate) struct Bound {
    pub lower_bound: f64,
    pub proof: Proof,
    pub explanation: String,
    /// The smallest eigenvalue of the certificate matrix (the conjugate SDP's), if any.
    pub min_eigenvalue: Option<f64>,
    pub verified_min_eigenvalue: Option<f64>,
    pub spectrum: Option<SpectrumEstimate>,
}

/// One certification of a single or conjugate estimate (`S`: the problem's solution type).
pub(crate) struct RotationState<'a, S> {
    pub settings: &'a CertifySettings,
    pub deadline: Deadline,
    pub estimate: Rotation,
    /// The estimate's cost (never changed).
    pub cost: f64,
    pub tolerance: GapTolerance,
    pub best: Option<Bound>,
    /// A solution of lower cost found while bounding, its cost and where it came from.
    pub improvement: Option<(S, f64, ImprovementSource)>,
    pub branch_and_bound: Option<BranchAndBoundStats>,
    pub sdp: Option<SdpSummary>,
    pub log: Vec<Attempt>,
}

impl<'a, S> RotationState<'a, S> {
    /// The state of certifying `estimate` (cost `cost`) of a problem whose smallest weight is
    /// `min_weight`.
    pub fn new(
        settings: &'a CertifySettings,
        deadline: Deadline,
        estimate: Rotation,
        cost: f64,
        min_weight: f64,
    ) -> Self {
        RotationState {
            settings,
            deadline,
            estimate,
            cost,
            tolerance: settings.tolerance.resolve(min_weight),
            best: None,
            improvement: None,
            branch_and_bound: None,
            sdp: None,
            log: Vec::new(),
        }
    }

    /// `lower_bound` certifies the estimate.
    pub fn certifies(&self, lower_bound: f64) -> bool {
        self.cost - lower_bound <= self.tolerance.allowed_gap(self.cost)
    }

    /// Keep `bound` (capped: at least 0, at most the cost) when it is the best so far; its
    /// capped value.
    pub fn offer(&mut self, mut bound: Bound) -> f64 {
        bound.lower_bound = nonnegative_bound_at_most(bound.lower_bound, self.cost);
        let lb = bound.lower_bound;
        if self.best.as_ref().is_none_or(|b| lb > b.lower_bound) {
            self.best = Some(bound);
        }
        lb
    }

    /// Keep `solution` (cost `cost`) when it beats the estimate and any earlier improvement
    /// beyond rounding (a tie is no improvement).
    pub fn improve(&mut self, solution: S, cost: f64, source: ImprovementSource) {
        let beats = self.cost - cost > 1e-12 * self.cost.abs().max(1e-300)
            && self.improvement.as_ref().is_none_or(|(_, c, _)| cost < *c);
        if beats {
            self.improvement = Some((solution, cost, source));
        }
    }

    /// The certification: the certificate of the estimate from the best bound (or none: the
    /// family and the sentence of `none`), the details from the log, the improvement.
    pub fn finish(self, none: impl FnOnce(&CertifyDetails) -> (Proof, String)) -> Certification<S> {
        let seconds = self.deadline.elapsed();
        let mut details = CertifyDetails::from_log(self.settings.mode, self.log, seconds);
        details.branch_and_bound = self.branch_and_bound;
        details.sdp = self.sdp;
        details.improvement = self
            .improvement
            .as_ref()
            .map(|(_, cost, source)| Improvement {
                source: *source,
                cost: *cost,
            });
        let certificate = match self.best {
            Some(b) => {
                let mut c = Certificate::from_bounds(
                    self.cost,
                    Some(b.lower_bound),
                    b.proof.method(),
                    b.min_eigenvalue,
                    self.tolerance,
                    b.explanation,
                    seconds,
                );
                c.verified_min_eigenvalue = b.verified_min_eigenvalue;
                c.smallest_eigenvalues = b.spectrum;
                c.branch_and_bound = details.branch_and_bound;
                c
            }
            None => {
                let (proof, why) = none(&details);
                let mut c = Certificate::from_bounds(
                    self.cost,
                    None,
                    proof.method(),
                    None,
                    self.tolerance,
                    why,
                    seconds,
                );
                c.branch_and_bound = details.branch_and_bound;
                c
            }
        };
        Certification {
            certificate,
            details,
            improvement: self.improvement.map(|(s, _, _)| s),
        }
    }
}

impl<S> Climb for RotationState<'_, S> {
    fn deadline(&self) -> &Deadline {
        &self.deadline
    }

    fn budget(&self) -> &Budget {
        &self.settings.budget
    }

    fn enough(&self) -> bool {
        self.best
            .as_ref()
            .is_some_and(|b| self.certifies(b.lower_bound))
    }

    fn record(&mut self, attempt: Attempt) {
        self.log.push(attempt);
    }
}
