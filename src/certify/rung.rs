//! What a proof is to a climb: a [`Rung`] plans (a predicted cost, or why it does not start)
//! and attempts (a verified bound, a failure, or a labelled estimate); a [`Climb`] is the state
//! the rungs of one climb share: the clock, the budget, the point worked on, the best bound so
//! far, and the one log. The order of the rungs is the ladder's ([`crate::certify::ladder`]).

use super::budget::{Budget, Deadline};
use super::log::{Attempt, Outcome, Point, Prediction, Refusal};
use super::proof::Proof;
use crate::error::Result;

/// What a rung says before the climb picks the next one.
#[derive(Debug, Clone, PartialEq)]
pub enum Plan {
    /// It can run now, at this predicted cost.
    Run(Prediction),
    /// It can run, but only as the last resort: when no rung is left to [`Plan::Run`].
    Fallback(Prediction),
    /// It does not start (over the budget, or not applicable): logged once, then dropped.
    Refuse(Refusal, Option<Prediction>),
    /// It does not start here (not applicable at the current point): logged, and kept for a
    /// later point. The rung must not say it again at the same point.
    Skip(Refusal),
    /// Nothing to do now (e.g. it already ran at the current point): kept, not logged.
    Wait,
    /// Nothing more to do: dropped, not logged.
    Done,
}

/// What an attempt found: its outcome and what it did, in words.
#[derive(Debug, Clone, PartialEq)]
pub struct Found {
    /// Proved (a verified bound), failed, refused on the way, or estimated.
    pub outcome: Outcome,
    /// What it did, in words (the report's sentence).
    pub note: String,
    /// The rung logged its own tries (a family of shapes, each an entry): the ladder adds none.
    pub logged: bool,
    /// The point it ended up working on, when not the one it started at (a refinement).
    pub point: Option<Point>,
}

impl Found {
    /// A verified lower bound (`sufficient`: enough for the verdict).
    pub fn proved(lower_bound: f64, sufficient: bool, note: impl Into<String>) -> Self {
        Found {
            outcome: Outcome::Proved {
                lower_bound,
                sufficient,
            },
            note: note.into(),
            logged: false,
            point: None,
        }
    }

    /// Nothing usable proved, and why.
    pub fn failed(reason: impl Into<String>) -> Self {
        let reason = reason.into();
        Found {
            outcome: Outcome::Failed {
                reason: reason.clone(),
            },
            note: reason,
            logged: false,
            point: None,
        }
    }

    /// Not started after all (found over the budget once it looked closer).
    pub fn refused(refusal: Refusal) -> Self {
        Found {
            note: String::new(),
            outcome: Outcome::Refused(refusal),
            logged: false,
            point: None,
        }
    }

    /// `outcome` with `note`.
    pub fn new(outcome: Outcome, note: impl Into<String>) -> Self {
        Found {
            outcome,
            note: note.into(),
            logged: false,
            point: None,
        }
    }

    /// The same, at `point` (where the rung ended up working).
    pub fn at(self, point: Point) -> Self {
        Found {
            point: Some(point),
            ..self
        }
    }

    /// `outcome`, already in the log (the rung logged its own tries).
    pub fn logged(outcome: Outcome) -> Self {
        Found {
            outcome,
            note: String::new(),
            logged: true,
            point: None,
        }
    }
}

/// The state of one climb, as the ladder sees it.
pub trait Climb {
    /// The certification's clock (one for every climb inside it).
    fn deadline(&self) -> &Deadline;
    /// The memory and time budget.
    fn budget(&self) -> &Budget;
    /// The point the next attempt works on (for the log); the given estimate unless the state
    /// moves between points.
    fn point(&self) -> Point {
        Point::Given
    }
    /// The proof whose multipliers this climb verifies; `None` (the default) for a
    /// certification's own.
    fn within(&self) -> Option<Proof> {
        None
    }
    /// The best bound so far is enough: the climb stops.
    fn enough(&self) -> bool;
    /// Append one attempt to the log.
    fn record(&mut self, attempt: Attempt);
}

/// One proof of a climb over the state `C`.
pub trait Rung<C: ?Sized> {
    /// Which proof.
    fn proof(&self) -> Proof;
    /// Its predicted cost in the state as it is now, or why it does not start now. `Err` only
    /// for errors of the caller's data.
    fn plan(&mut self, cx: &C) -> Result<Plan>;
    /// Run it; it offers what it proves to the state itself (`C`'s own methods).
    fn attempt(&mut self, cx: &mut C) -> Result<Found>;
}

/// What a rung that runs once with a certification handed in by its entry point keeps (the
/// gravity and rig rungs that certify a view graph, a soft problem or two graphs): whether it
/// ran, and the certifier ([`GraphCertifier`], [`JointCertifier`], ...).
pub(crate) struct Handed<F> {
    pub done: bool,
    pub certify: F,
}

impl<F> Handed<F> {
    /// Not run yet, certifying with `certify`.
    pub(crate) fn new(certify: F) -> Self {
        Handed {
            done: false,
            certify,
        }
    }
}

/// A view graph's certification handed to a rung by its entry point (the rungs sit below the
/// entry points, `tests/suite/certify_layers.rs`): the certificate of an estimate of `graph`
/// (in practice [`crate::certify::multiple::graph_certificate`]).
pub(crate) type GraphCertifier = fn(
    &crate::multiple::MultipleProblem,
    &[crate::so3::Rotation],
    &super::settings::CertifySettings,
) -> Result<super::certificate::Certificate>;

/// A gravity problem's certification handed to a rung by its entry point (as
/// [`GraphCertifier`]; in practice [`crate::certify::gravity::gravity_certificate`]).
pub(crate) type GravityCertifier = fn(
    &crate::multiple::gravity::GravityProblem,
    &[crate::so3::Rotation],
    &super::settings::CertifySettings,
) -> Result<super::certificate::Certificate>;

/// The simultaneous problem's certification handed to a rung by its entry point (as
/// [`GraphCertifier`]): the certificate of a joint estimate `(R, S)` of two view graphs (in
/// practice [`crate::certify::simultaneous::joint_certificate`]).
pub(crate) type JointCertifier = fn(
    &crate::multiple::MultipleProblem,
    &crate::multiple::MultipleProblem,
    &[crate::so3::Rotation],
    &crate::so3::Rotation,
    &super::settings::CertifySettings,
) -> Result<super::certificate::Certificate>;
