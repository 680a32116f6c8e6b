//! `set_progress`: the library's progress events (`rotavg::progress`) delivered to a Python
//! callable, as the command line draws them on its progress line.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use rotavg::progress::{Event, Observer, set_observer};
use std::sync::Arc;

/// Calls a Python callable with each event (the GIL taken for the call).
struct Callback(Py<PyAny>);

impl Observer for Callback {
    fn notify(&self, event: &Event) {
        Python::attach(|py| {
            let call = || -> PyResult<()> {
                let d = PyDict::new(py);
                d.set_item("message", event.to_string())?;
                match event {
                    Event::Phase { phase, detail } => {
                        d.set_item("event", "phase")?;
                        d.set_item("phase", phase.to_string())?;
                        d.set_item("detail", detail)?;
                    }
                    Event::Iteration {
                        phase,
                        iteration,
                        cost,
                        measure,
                    } => {
                        d.set_item("event", "iteration")?;
                        d.set_item("phase", phase.to_string())?;
                        d.set_item("iteration", iteration)?;
                        d.set_item("cost", cost)?;
                        d.set_item("measure", measure)?;
                    }
                }
                self.0.call1(py, (d,)).map(|_| ())
            };
            // a failing callback cannot stop the solver: Python reports it as unraisable
            if let Err(e) = call() {
                e.write_unraisable(py, Some(self.0.bind(py)));
            }
        });
    }
}

/// Receive the progress of every following call (process-wide): ``callback(event)`` with a
/// dict ``{"event": "phase" | "iteration", "phase": ..., "message": ...}``; phases add
/// ``"detail"`` (sizes, which proof), iterations ``"iteration"``, ``"cost"`` and ``"measure"``
/// (solvers: relative gradient norm; the SDP: relative gap). ``message`` is the line the
/// command line shows. ``None`` stops it. The callback runs on the solving thread with the
/// GIL held; an exception it raises is reported (``sys.unraisablehook``) and the solve goes on.
///
/// Raises:
///     rotavg.Error: ``callback`` is neither callable nor None.
#[pyfunction]
#[pyo3(signature = (callback))]
pub fn set_progress(py: Python<'_>, callback: Option<Py<PyAny>>) -> PyResult<()> {
    let observer: Option<Arc<dyn Observer>> = match callback {
        Some(c) if c.bind(py).is_callable() => Some(Arc::new(Callback(c))),
        Some(_) => {
            return Err(crate::errors::argument_error(
                "set_progress takes a callable (or None)",
            ));
        }
        None => None,
    };
    set_observer(observer);
    Ok(())
}
