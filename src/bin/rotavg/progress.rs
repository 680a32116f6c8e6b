//! The progress display on stderr: a spinner line naming the phase (read, initialise, solve
//! with iteration / cost / gradient, certify with the proof tried, SDP with iteration / gap)
//! and the elapsed time, fed by the library's [`rotavg::progress`] events.
//!
//! It appears only for runs longer than [`DELAY`], only when stderr is a terminal, and never
//! under `--quiet` or `--json`; it is cleared when the run ends, so the report is all that
//! remains on the screen.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rotavg::progress::{Event, Observer, set_observer};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Runs shorter than this show no progress display.
pub const DELAY: Duration = Duration::from_secs(1);

/// The spinner; installed as the library's observer for the lifetime of the value.
pub struct Display {
    bar: ProgressBar,
    done: Arc<AtomicBool>,
}

impl Display {
    /// Install the display when `wanted` and stderr is a terminal (else do nothing); it lasts
    /// until [`finish`].
    pub fn install(wanted: bool) {
        if !wanted || !std::io::stderr().is_terminal() {
            return;
        }
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
        let style = ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_msg}")
            .unwrap_or_else(|_| ProgressStyle::default_spinner());
        bar.set_style(style);
        bar.set_message("read: input");
        let done = Arc::new(AtomicBool::new(false));
        let display = Arc::new(Display {
            bar: bar.clone(),
            done: done.clone(),
        });
        // show the line only once the run has lasted DELAY
        std::thread::spawn(move || {
            std::thread::sleep(DELAY);
            if !done.load(Ordering::SeqCst) {
                bar.set_draw_target(ProgressDrawTarget::stderr());
                bar.enable_steady_tick(Duration::from_millis(120));
            }
        });
        set_observer(Some(display.clone()));
        if let Ok(mut slot) = CURRENT.lock() {
            *slot = Some(display);
        }
    }
}

/// The installed display, if any.
static CURRENT: Mutex<Option<Arc<Display>>> = Mutex::new(None);

/// Remove the display, if one is installed, and clear its line: called before a report is
/// printed and when the run ends.
pub fn finish() {
    let current = CURRENT.lock().ok().and_then(|mut slot| slot.take());
    if let Some(d) = current {
        set_observer(None);
        d.done.store(true, Ordering::SeqCst);
        d.bar.finish_and_clear();
    }
}

impl Observer for Display {
    fn notify(&self, event: &Event) {
        self.bar.set_message(event.to_string());
    }
}

/// Show `message` on the display's line, if one is installed (else nothing: the display is
/// installed whenever a person is watching the terminal).
pub fn say(message: std::fmt::Arguments<'_>) {
    if let Ok(slot) = CURRENT.lock()
        && let Some(d) = slot.as_ref()
    {
        d.bar.set_message(message.to_string());
    }
}
