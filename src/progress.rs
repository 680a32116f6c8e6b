//! Progress of long runs, for whoever asks. The library prints nothing: it emits [`Event`]s
//! (which phase runs, each solver or SDP iteration with its cost and stopping measure) to the
//! [`Observer`] installed with [`set_observer`], if any; building an event costs nothing when
//! none is installed. The command line installs one that draws a progress line on a terminal,
//! or writes [`ProgressLines`] to a log.
//!
//! ```
//! use rotavg::progress::{set_observer, Event, Observer, Phase};
//! use std::sync::{Arc, Mutex};
//! struct Phases(Mutex<Vec<Phase>>);
//! impl Observer for Phases {
//!     fn notify(&self, event: &Event) {
//!         if let Event::Phase { phase, .. } = event {
//!             self.0.lock().unwrap().push(*phase);
//!         }
//!     }
//! }
//! let seen = Arc::new(Phases(Mutex::new(Vec::new())));
//! set_observer(Some(seen.clone()));
//! let (p, _) = rotavg::multiple::synthetic::SyntheticGraph::default().generate();
//! rotavg::pipeline::average_multiple(&p, &Default::default())?;
//! set_observer(None);
//! let phases = seen.0.lock().unwrap();
//! assert!(phases.contains(&Phase::Solve) && phases.contains(&Phase::Certify));
//! # Ok::<(), rotavg::Error>(())
//! ```

mod lines;

pub use lines::{LINE_DELAY, LINE_INTERVAL, LINE_REPEAT, ProgressLines, with_time_left};
use std::fmt;
use std::sync::{Arc, RwLock};

/// The phases of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Reading an input file.
    Read,
    /// The initial estimate (spanning tree, spectral, closed form).
    Initialise,
    /// The local solver.
    Solve,
    /// A certificate (which proof: in the event's detail).
    Certify,
    /// Refining an estimate before certifying it again.
    Refine,
    /// The SDP relaxation (Clarabel).
    Sdp,
    /// The Riemannian staircase.
    Staircase,
}

impl fmt::Display for Phase {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Phase::Read => "read",
            Phase::Initialise => "initialise",
            Phase::Solve => "solve",
            Phase::Certify => "certify",
            Phase::Refine => "refine",
            Phase::Sdp => "SDP",
            Phase::Staircase => "staircase",
        })
    }
}

/// What happened.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// A phase starts.
    Phase {
        /// Which.
        phase: Phase,
        /// What exactly (sizes, which proof).
        detail: String,
    },
    /// One iteration of a phase.
    Iteration {
        /// Which phase.
        phase: Phase,
        /// Iteration number.
        iteration: usize,
        /// Current cost (SDP: primal objective of the scaled problem).
        cost: f64,
        /// The stopping measure (solvers: relative gradient norm; SDP: relative gap).
        measure: f64,
    },
}

impl fmt::Display for Event {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Event::Phase { phase, detail } if detail.is_empty() => write!(f, "{phase}"),
            Event::Phase { phase, detail } => write!(f, "{phase}: {detail}"),
            Event::Iteration {
                phase: Phase::Sdp,
                iteration,
                cost,
                measure,
            } => write!(
                f,
                "SDP: iteration {iteration}, objective {cost:.6e}, relative gap {measure:.1e}"
            ),
            Event::Iteration {
                phase,
                iteration,
                cost,
                measure,
            } => write!(
                f,
                "{phase}: iteration {iteration}, cost {cost:.6e}, gradient {measure:.1e}"
            ),
        }
    }
}

/// Receives the events of the whole process (from any thread).
pub trait Observer: Send + Sync {
    /// One event.
    fn notify(&self, event: &Event);
}

static OBSERVER: RwLock<Option<Arc<dyn Observer>>> = RwLock::new(None);

/// Install (or, with `None`, remove) the process-wide observer; returns the previous one.
pub fn set_observer(observer: Option<Arc<dyn Observer>>) -> Option<Arc<dyn Observer>> {
    match OBSERVER.write() {
        Ok(mut slot) => std::mem::replace(&mut *slot, observer),
        Err(poisoned) => std::mem::replace(&mut *poisoned.into_inner(), observer),
    }
}

/// Send the event built by `event` to the observer, if one is installed (else `event` is not
/// called).
pub(crate) fn emit(event: impl FnOnce() -> Event) {
    let observer = match OBSERVER.read() {
        Ok(slot) => slot.clone(),
        Err(_) => None,
    };
    if let Some(o) = observer {
        o.notify(&event());
    }
}

/// [`emit`] a phase start.
pub(crate) fn phase(phase: Phase, detail: impl FnOnce() -> String) {
    emit(|| Event::Phase {
        phase,
        detail: detail(),
    });
}
