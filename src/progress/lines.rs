//! Plain progress lines for a log file or a pipe (SPEC section 5: a run longer than ~2 s shows
//! progress on stderr): `rotavg: [12.3 s] certify: ...`, the first once the run has lasted the
//! delay, then at most one per [`LINE_INTERVAL`] when the message changed and one per
//! [`LINE_REPEAT`] while it stays the same, so that no phase is silent for longer.

use super::{Event, Observer};
use std::io::Write;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// Runs shorter than this write no line (unless `ROTAVG_PROGRESS_AFTER` says otherwise:
/// [`ProgressLines::delay_from_env`]).
pub const LINE_DELAY: Duration = Duration::from_secs(2);

/// At most one line per this interval (a message that changes every iteration).
pub const LINE_INTERVAL: Duration = Duration::from_secs(5);

/// A message that has not changed is written again after this long.
pub const LINE_REPEAT: Duration = Duration::from_secs(30);

/// The throttled line writer: an [`Observer`] keeping the latest message; [`ProgressLines::tick`]
/// writes it when due, [`ProgressLines::spawn`] ticks on a thread until [`ProgressLines::stop`].
///
/// ```
/// use rotavg::progress::{Event, Observer, Phase, ProgressLines};
/// let lines = ProgressLines::new();
/// lines.notify(&Event::Phase { phase: Phase::Solve, detail: "chordal l2".into() });
/// let mut out = Vec::new();
/// assert!(lines.tick(&mut out)); // the first line is due at once
/// assert!(!lines.tick(&mut out)); // the next after LINE_INTERVAL
/// assert!(String::from_utf8(out).unwrap().ends_with("s] solve: chordal l2\n"));
/// ```
pub struct ProgressLines {
    start: Instant,
    state: Mutex<State>,
}

struct State {
    message: String,
    written: Option<(String, Instant)>,
    stopped: bool,
}

impl Default for ProgressLines {
    fn default() -> Self {
        Self::new()
    }
}

impl ProgressLines {
    /// A writer whose clock starts now, with the message `read: input`.
    pub fn new() -> Self {
        ProgressLines {
            start: Instant::now(),
            state: Mutex::new(State {
                message: "read: input".into(),
                written: None,
                stopped: false,
            }),
        }
    }

    /// Replace the message.
    pub fn set(&self, message: String) {
        if let Ok(mut s) = self.state.lock() {
            s.message = message;
        }
    }

    /// Write the message to `out` when due (none written yet; changed and [`LINE_INTERVAL`]
    /// passed; or [`LINE_REPEAT`] passed) and not stopped; whether a line was written.
    pub fn tick(&self, out: &mut dyn Write) -> bool {
        let Ok(mut s) = self.state.lock() else {
            return false;
        };
        let due = !s.stopped
            && match &s.written {
                None => true,
                Some((m, at)) => {
                    let since = at.elapsed();
                    (since >= LINE_INTERVAL && *m != s.message) || since >= LINE_REPEAT
                }
            };
        if due {
            let t = self.start.elapsed().as_secs_f64();
            let _ = writeln!(out, "rotavg: [{t:.1} s] {}", s.message);
            s.written = Some((s.message.clone(), Instant::now()));
        }
        due
    }

    /// No line after this one returns (taken under the writer's lock: no line follows it).
    pub fn stop(&self) {
        if let Ok(mut s) = self.state.lock() {
            s.stopped = true;
        }
    }

    /// The delay before the first line: `ROTAVG_PROGRESS_AFTER` seconds when that is a number
    /// from 0 to 3600 (the tests' 0), else [`LINE_DELAY`].
    pub fn delay_from_env() -> Duration {
        std::env::var("ROTAVG_PROGRESS_AFTER")
            .ok()
            .and_then(|v| v.trim().parse::<f64>().ok())
            .filter(|s| (0.0..=3600.0).contains(s))
            .map_or(LINE_DELAY, Duration::from_secs_f64)
    }

    /// Tick on a thread writing to stderr, from `delay` on, every 200 ms until stopped.
    pub fn spawn(self: &Arc<Self>, delay: Duration) {
        let lines = self.clone();
        std::thread::spawn(move || {
            std::thread::sleep(delay);
            loop {
                lines.tick(&mut std::io::stderr());
                if lines.state.lock().map_or(true, |s| s.stopped) {
                    return;
                }
                std::thread::sleep(Duration::from_millis(200));
            }
        });
    }
}

impl Observer for ProgressLines {
    fn notify(&self, event: &Event) {
        self.set(event.to_string());
    }
}
