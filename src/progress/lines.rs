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
    /// When the message was set (a phase's predicted time counts from there).
    set_at: Instant,
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
                set_at: Instant::now(),
                written: None,
                stopped: false,
            }),
        }
    }

    /// Replace the message.
    pub fn set(&self, message: String) {
        if let Ok(mut s) = self.state.lock()
            && s.message != message
        {
            s.message = message;
            s.set_at = Instant::now();
        }
    }

    /// The message as a line would show it now: with the time left of a proof's prediction
    /// ([`with_time_left`]); the terminal's spinner shows it.
    ///
    /// ```
    /// use rotavg::progress::ProgressLines;
    /// let lines = ProgressLines::new();
    /// lines.set("certify: grounded (predicted 100.00 s)".into());
    /// assert!(lines.current().starts_with("certify: grounded (predicted 100.00 s, about 10"));
    /// ```
    pub fn current(&self) -> String {
        self.state.lock().map_or_else(
            |_| String::new(),
            |s| with_time_left(&s.message, s.set_at.elapsed().as_secs_f64()),
        )
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
            let text = with_time_left(&s.message, s.set_at.elapsed().as_secs_f64());
            let _ = writeln!(out, "rotavg: [{t:.1} s] {text}");
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

/// A message naming its phase's predicted time, `... (predicted 11.19 s)`, with the time
/// left after `elapsed` seconds in it: `... (predicted 11.19 s, about 4.0 s left)` (`past its
/// prediction` beyond it); any other message as it is.
///
/// ```
/// use rotavg::progress::with_time_left;
/// assert_eq!(with_time_left("certify: grounded (predicted 10.00 s)", 4.0),
///            "certify: grounded (predicted 10.00 s, about 6.0 s left)");
/// assert_eq!(with_time_left("certify: grounded (predicted 1.00 s)", 4.0),
///            "certify: grounded (predicted 1.00 s, past its prediction)");
/// assert_eq!(with_time_left("solve: iteration 3", 4.0), "solve: iteration 3");
/// ```
pub fn with_time_left(message: &str, elapsed: f64) -> String {
    let predicted = message
        .strip_suffix(" s)")
        .and_then(|m| m.rsplit_once("(predicted "))
        .and_then(|(head, x)| Some((head, x.parse::<f64>().ok()?)));
    match predicted {
        Some((head, p)) if p.is_finite() => {
            let left = p - elapsed;
            let tail = if left >= 0.0 {
                format!("about {left:.1} s left")
            } else {
                "past its prediction".to_string()
            };
            format!("{head}(predicted {p:.2} s, {tail})")
        }
        _ => message.to_string(),
    }
}

impl Observer for ProgressLines {
    fn notify(&self, event: &Event) {
        self.set(event.to_string());
    }
}
