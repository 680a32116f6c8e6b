//! The local solvers' time limit (the command line's `--max-seconds`, the `max_seconds` field
//! of [`crate::multiple::MultipleSettings`], [`crate::single::SingleSettings`],
//! [`crate::conjugate::ConjugateSettings`] and
//! [`crate::pipeline::simultaneous::SimultaneousSettings`]): one shape for every iteration
//! loop. A loop takes its [`Deadline`] when it starts and asks [`limit_reached`] before each
//! iteration; a loop that calls another solver passes it [`remaining`]. The limit is therefore
//! kept to within one iteration of the innermost loop (and any step that is not interrupted:
//! an initialisation, a closed form).

use crate::termination::Termination;
use std::time::{Duration, Instant};

/// When a loop's time limit ends, and how many seconds it was given.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Deadline {
    seconds: f64,
    at: Instant,
}

impl Deadline {
    /// `seconds` from now; `None` without a limit (or one too far to represent: no limit).
    pub(crate) fn after(seconds: Option<f64>) -> Option<Deadline> {
        let seconds = seconds?;
        let at = Instant::now().checked_add(Duration::try_from_secs_f64(seconds).ok()?)?;
        Some(Deadline { seconds, at })
    }

    /// Whether the limit has passed.
    pub(crate) fn passed(&self) -> bool {
        Instant::now() >= self.at
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
        seconds: deadline.seconds,
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
        assert!(validate_max_seconds(Some(f64::NAN)).is_err());
        assert!(validate_max_seconds(Some(-1.0)).is_err());
        assert!(validate_max_seconds(None).is_ok() && validate_max_seconds(Some(0.0)).is_ok());
    }
}
