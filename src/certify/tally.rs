//! What one certification of a problem with many unknowns (gravity, rig, simultaneous) keeps
//! while it climbs, in one shape for the three: the budget's clock, the estimate's cost and the
//! gap its verdict allows there, the best verified bound and the one log. Each problem's state
//! holds a [`Tally`] beside its problem and estimate, caps the bounds its rungs offer by its
//! own rule and hands them to [`Tally::keep`]; `climb_by_tally!` makes the state a
//! [`Climb`](super::rung::Climb).
//! (`one_rotation.rs` is the same idea for one unknown rotation, whose bounds carry more.)

use super::budget::Deadline;
use super::certificate::Certificate;
use super::certification::CertifyDetails;
use super::log::Attempt;
use super::proof::{BoundMethod, Proof};
use super::settings::CertifySettings;
use super::tolerance::GapTolerance;

/// The best verified bound so far.
pub(crate) struct Best {
    pub lower_bound: f64,
    pub proof: Proof,
    /// The smallest eigenvalue of the certificate matrix the proof verified, if it has one.
    pub verified_min_eigenvalue: Option<f64>,
    pub note: String,
}

/// One certification's clock, cost, allowed gap, best bound and log.
pub(crate) struct Tally<'a> {
    pub settings: &'a CertifySettings,
    pub deadline: Deadline,
    /// The estimate's cost (never changed) and the gap the verdict allows there.
    pub cost: f64,
    pub allowed_gap: f64,
    tolerance: GapTolerance,
    pub best: Option<Best>,
    pub log: Vec<Attempt>,
}

impl<'a> Tally<'a> {
    /// The tally of certifying an estimate of cost `cost` of a problem whose smallest weight
    /// is `min_weight` (the tolerance's weight scale), on the clock `deadline`.
    pub fn new(
        settings: &'a CertifySettings,
        deadline: Deadline,
        cost: f64,
        min_weight: f64,
    ) -> Self {
        let tolerance = settings.tolerance.resolve(min_weight);
        Tally {
            settings,
            deadline,
            cost,
            allowed_gap: tolerance.allowed_gap(cost),
            tolerance,
            best: None,
            log: Vec::new(),
        }
    }

    /// `lower_bound` certifies the estimate.
    pub fn certifies(&self, lower_bound: f64) -> bool {
        self.cost - lower_bound <= self.allowed_gap
    }

    /// The best bound so far certifies the estimate.
    pub fn enough(&self) -> bool {
        self.best
            .as_ref()
            .is_some_and(|b| self.certifies(b.lower_bound))
    }

    /// Keep `lower_bound`, already capped by the problem's rule, when it is the best so far;
    /// it again. A bound that is not finite is not kept.
    pub fn keep(&mut self, lower_bound: f64, proof: Proof, mu: Option<f64>, note: &str) -> f64 {
        if lower_bound.is_finite()
            && self
                .best
                .as_ref()
                .is_none_or(|b| lower_bound > b.lower_bound)
        {
            self.best = Some(Best {
                lower_bound,
                proof,
                verified_min_eigenvalue: mu,
                note: note.to_string(),
            });
        }
        lower_bound
    }

    /// The certification's time left (`None`: no limit), never negative.
    pub fn left(&self) -> Option<f64> {
        self.deadline.left().map(|l| l.max(0.0))
    }

    /// The details from the log and the estimate's certificate from the best bound (its family
    /// `method(proof)`; without a bound `none`, the last rung's note the reason).
    pub fn finish(
        self,
        none: BoundMethod,
        method: impl FnOnce(Proof) -> BoundMethod,
    ) -> (Certificate, CertifyDetails) {
        let details =
            CertifyDetails::from_log(self.settings.mode, self.log, self.deadline.elapsed());
        let best = self.best.map(|b| {
            let family = method(b.proof);
            (b.lower_bound, family, b.verified_min_eigenvalue, b.note)
        });
        let certificate = details.certificate_of(self.cost, best, none, self.tolerance);
        (certificate, details)
    }
}

/// [`Climb`](super::rung::Climb) for a certification state with a field `tally`
/// ([`Tally`]): the gravity, rig and simultaneous problems' states.
macro_rules! climb_by_tally {
    ($state:ident) => {
        impl $crate::certify::rung::Climb for $state<'_> {
            fn deadline(&self) -> &$crate::certify::budget::Deadline {
                &self.tally.deadline
            }
            fn budget(&self) -> &$crate::certify::budget::Budget {
                &self.tally.settings.budget
            }
            fn enough(&self) -> bool {
                self.tally.enough()
            }
            fn record(&mut self, attempt: $crate::certify::log::Attempt) {
                self.tally.log.push(attempt);
            }
        }
    };
}
pub(crate) use climb_by_tally;
