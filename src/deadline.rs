//! The crate's one clock, [`Deadline`]: a certification's (`crate::certify::Deadline`, with
//! the budget's constructor) and the local solvers' time limit (the command line's
//! `--max-seconds`, the `max_seconds` field
//! of [`crate::multiple::MultipleSettings`], [`crate::single::SingleSettings`],
//! [`crate::conjugate::ConjugateSettings`] and
//! [`crate::pipeline::simultaneous::SimultaneousSettings`]): one shape for every iteration
//! loop. A loop takes its [`Deadline`] when it starts and asks [`limit_reached`] before each
//! iteration; a loop that calls another solver passes it [`remaining`]. The limit is therefore
//! kept to within one iteration of the innermost loop (and any step that is not interrupted:
//! an initialisation, a closed form).

use crate::termination::Termination;
use std::time::{Duration, Instant};

/// A clock: when it started and its time limit in seconds from then (`None`: never). The one
/// clock of a local solve, and of a certification ([`crate::certify::Deadline`] is this type,
/// with the budget's constructor and checks).
#[derive(Debug, Clone, Copy)]
pub struct Deadline {
    start: Instant,
    limit: Option<f64>,
}

impl Deadline {
    /// A clock started at `start` with the time limit `limit` seconds.
    pub fn started_at(start: Instant, limit: Option<f64>) -> Self {
        Deadline { start, limit }
    }

    /// A loop's clock: `seconds` from now; `None` without a limit.
    pub(crate) fn after(seconds: Option<f64>) -> Option<Deadline> {
        seconds.map(|s| Deadline::started_at(Instant::now(), Some(s)))
    }

    /// Seconds since the start.
    pub fn elapsed(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    /// The time limit, seconds from the start.
    pub fn limit(&self) -> Option<f64> {
        self.limit
    }

    /// Seconds left (`None`: no limit; negative once passed).
    pub fn left(&self) -> Option<f64> {
        self.limit.map(|l| l - self.elapsed())
    }

    /// The limit is passed.
    pub fn passed(&self) -> bool {
        self.left().is_some_and(|l| l <= 0.0)
    }

    /// A clock that ends when `fraction` of the time now left is spent (the share of a step
    /// inside a rung); the same clock without a limit.
    pub fn share(&self, fraction: f64) -> Deadline {
        match self.left() {
            Some(left) => Deadline::started_at(Instant::now(), Some(left.max(0.0) * fraction)),
            None => *self,
        }
    }

    /// The instant the limit is reached, if any (`None` also for a limit too far to
    /// represent, e.g. `--max-seconds 1e300`: no limit in practice).
    pub fn instant(&self) -> Option<Instant> {
        let limit = Duration::try_from_secs_f64(self.limit?.max(0.0)).ok()?;
        self.start.checked_add(limit)
    }
}

/// What is left at `start.elapsed()` of a limit of `max_seconds` counted from `start` (at
/// least 0; `None` stays `None`).
pub(crate) fn remaining(max_seconds: Option<f64>, start: Instant) -> Option<f64> {
    max_seconds.map(|t| (t - start.elapsed().as_secs_f64()).max(0.0))
}

/// Why an iteration loop stops before its next iteration, if it does: `max_iterations` done
/// ([`Termination::IterationLimit`]), or its `deadline` passed ([`Termination::TimeLimit`]).
/// `value` and `threshold`: its stopping quantity at the last iterate and the tolerance.
pub(crate) fn limit_reached(
    iterations: usize,
    max_iterations: usize,
    deadline: Option<Deadline>,
    (value, threshold): (f64, f64),
) -> Option<Termination> {
    if iterations >= max_iterations {
        return Some(Termination::IterationLimit {
            iterations,
            value,
            threshold,
        });
    }
    let deadline = deadline?;
    deadline.passed().then_some(Termination::TimeLimit {
        seconds: deadline.limit().unwrap_or(f64::INFINITY),
        value,
        threshold,
    })
}

/// Check a time limit setting: `None`, or finite and `>= 0` seconds.
pub(crate) fn validate_max_seconds(max_seconds: Option<f64>) -> crate::Result<()> {
    match max_seconds {
        Some(t) if !(t.is_finite() && t >= 0.0) => Err(crate::Error::InvalidSettings {
            name: "max_seconds".into(),
            reason: format!("must be finite and >= 0, got {t}"),
        }),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_zero_limit_stops_before_the_first_iteration_and_none_never_does() {
        let stop = limit_reached(0, 10, Deadline::after(Some(0.0)), (1.0, 0.5));
        assert!(matches!(stop, Some(Termination::TimeLimit { seconds, .. }) if seconds == 0.0));
        assert_eq!(
            limit_reached(3, 10, Deadline::after(None), (1.0, 0.5)),
            None
        );
        assert_eq!(
            limit_reached(3, 10, Deadline::after(Some(1e300)), (1.0, 0.5)),
            None
        );
        let it = limit_reached(10, 10, Deadline::after(Some(0.0)), (1.0, 0.5));
        assert!(matches!(
            it,
            Some(Termination::IterationLimit { iterations: 10, .. })
        ));
        assert_eq!(remaining(Some(0.0), Instant::now()), Some(0.0));
        let far = Deadline::started_at(Instant::now(), Some(1e300));
        assert!(far.instant().is_none() && !far.passed());
        assert!(validate_max_seconds(Some(f64::NAN)).is_err());
        assert!(validate_max_seconds(Some(-1.0)).is_err());
        assert!(validate_max_seconds(None).is_ok() && validate_max_seconds(Some(0.0)).is_ok());
    }
}
