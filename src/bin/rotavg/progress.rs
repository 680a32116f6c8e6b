//! The progress display on stderr, fed by the library's [`rotavg::progress`] events (read,
//! initialise, solve with iteration / cost / gradient, certify with the proof tried and its
//! predicted time, SDP with iteration / gap): SPEC section 5, a run longer than ~2 s shows
//! progress unless `--quiet`, or `--json` without a terminal, asks otherwise.
//!
//! - stderr a terminal: a spinner line with the elapsed time and the time left of a proof's
//!   prediction, shown once the run has lasted a second and cleared when the run ends, so the
//!   report is all that remains on the screen;
//! - otherwise (a log file, a pipe): the library's [`ProgressLines`], the first after 2 s.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rotavg::progress::{Event, Observer, ProgressLines, set_observer};
use std::io::IsTerminal;
use std::sync::{Arc, Mutex};
use std::time::Duration;

/// Where the events go: the spinner (stderr a terminal) or plain lines.
enum Display {
    Bar(ProgressBar, Arc<ProgressLines>),
    Lines(Arc<ProgressLines>),
}

/// Install the display unless `quiet`, or `json` without a terminal (SPEC section 5), for a
/// verb with `(quiet, json)` options; it lasts until [`finish`].
pub fn install(options: Option<(bool, bool)>) {
    let terminal = std::io::stderr().is_terminal();
    if options.is_none_or(|(quiet, json)| quiet || (json && !terminal)) {
        return;
    }
    let display = Arc::new(if terminal {
        let lines = Arc::new(ProgressLines::new());
        Display::Bar(spinner(lines.clone()), lines)
    } else {
        let lines = Arc::new(ProgressLines::new());
        lines.spawn(ProgressLines::delay_from_env());
        Display::Lines(lines)
    });
    set_observer(Some(display.clone()));
    if let Ok(mut slot) = CURRENT.lock() {
        *slot = Some(display);
    }
}

/// The spinner, drawn only once the run has lasted a second, its message `lines`' (never
/// written as lines: they give the time left of a proof's prediction), refreshed every 200 ms.
fn spinner(lines: Arc<ProgressLines>) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
    let style = ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_msg}")
        .unwrap_or_else(|_| ProgressStyle::default_spinner());
    bar.set_style(style);
    bar.set_message("read: input");
    let shown = bar.clone();
    std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs(1));
        if !shown.is_finished() {
            shown.set_draw_target(ProgressDrawTarget::stderr());
            shown.enable_steady_tick(Duration::from_millis(120));
        }
        while !shown.is_finished() {
            shown.set_message(lines.current());
            std::thread::sleep(Duration::from_millis(200));
        }
    });
    bar
}

/// The installed display, if any.
static CURRENT: Mutex<Option<Arc<Display>>> = Mutex::new(None);

/// Remove the display, if one is installed, and clear its line (or stop its lines): called
/// before a report is printed and when the run ends.
pub fn finish() {
    if let Some(d) = CURRENT.lock().ok().and_then(|mut slot| slot.take()) {
        set_observer(None);
        match d.as_ref() {
            Display::Bar(bar, _) => bar.finish_and_clear(),
            Display::Lines(lines) => lines.stop(),
        }
    }
}

impl Observer for Display {
    fn notify(&self, event: &Event) {
        say(format_args!("{event}"));
    }
}

/// Show `message` on the display, if one is installed.
pub fn say(message: std::fmt::Arguments<'_>) {
    if let Ok(slot) = CURRENT.lock() {
        match slot.as_deref() {
            Some(Display::Bar(bar, lines)) => {
                lines.set(message.to_string());
                bar.set_message(lines.current());
            }
            Some(Display::Lines(lines)) => lines.set(message.to_string()),
            None => {}
        }
    }
}
