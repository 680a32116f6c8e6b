//! Errors that speak Python: the library's typed errors as `rotavg.Error` and its subclasses,
//! with messages that name the Python keyword or function to use (never a command-line flag)
//! and no Rust type names.
//!
//! | library error | Python exception | extra attributes |
//! |---|---|---|
//! | `Parse` (a malformed file) | `rotavg.ParseError` | `path`, `line` (or None) |
//! | `Io` (a file that cannot be read) | `rotavg.FileError` | `path` |
//! | `Disconnected` | `rotavg.DisconnectedError` | `component_sizes` |
//! | `Degenerate` | `rotavg.DegenerateError` | |
//! | `Solver` | `rotavg.SolverError` | |
//! | any other (bad values, bad settings) | `rotavg.Error` | |
//!
//! All are subclasses of `rotavg.Error`, itself a `ValueError`.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyList;

pyo3::create_exception!(
    rotavg,
    Error,
    PyValueError,
    "Bad input or settings (a subclass of ValueError), and the base class of every rotavg \
     exception. The message names the offending item (e.g. ``rel[3]``), the keyword argument, \
     or the file and line."
);
pyo3::create_exception!(
    rotavg,
    ParseError,
    Error,
    "A malformed input file. ``path`` is the file, ``line`` the 1-based line (None when the \
     error is about the whole file)."
);
pyo3::create_exception!(
    rotavg,
    FileError,
    Error,
    "A file or directory that cannot be read (missing, unreadable, too large, not a \
     directory). ``path`` is the path."
);
pyo3::create_exception!(
    rotavg,
    DisconnectedError,
    Error,
    "The view graph is not connected: ``component_sizes`` lists the sizes of its components, \
     largest first. Solve the largest one with ``average_multiple(..., \
     largest_component=True)`` or ``read_graph(path, largest_component=True)``."
);
pyo3::create_exception!(
    rotavg,
    DegenerateError,
    Error,
    "Data that do not determine the answer (e.g. hand-eye motions whose rotation axes are all \
     parallel, or fewer robot poses than camera poses)."
);
pyo3::create_exception!(
    rotavg,
    SolverError,
    Error,
    "A numerical solver could not be set up or failed without a result."
);

/// What to say instead of the command line's `--largest-component`.
const LARGEST_COMPONENT: &str = "solve the largest component instead \
     (`average_multiple(..., largest_component=True)`, or \
     `read_graph(path, largest_component=True)` for a file)";

/// The library's phrases that name command-line flags, and what a Python user passes instead.
/// Applied before the generic rule of [`python_flags`].
const PHRASES: &[(&str, &str)] = &[
    (
        "solve the largest component instead (e.g. `--largest-component`)",
        LARGEST_COMPONENT,
    ),
    (
        "pass --format g2o|1dsfm|json",
        "pass format=\"g2o\", \"1dsfm\" or \"json\"",
    ),
    (
        "Name the files with --hand FILE and --camera FILE",
        "Name the files with hand=PATH and camera=PATH",
    ),
    (
        "or name both files with --hand and --camera",
        "or name both files with hand=PATH and camera=PATH",
    ),
    ("or --hand and --camera", "or hand=PATH and camera=PATH"),
];

/// The library's setting names (field paths of its settings structs, or the command line's
/// words) as the Python keyword arguments that set them.
fn keyword(name: &str) -> &str {
    match name {
        "budget.max_memory_bytes" => "max_memory",
        "budget.max_seconds" => "max_seconds",
        "mode" | "certify.mode" | "certify mode" => "certify",
        "hand/camera" => "hand, camera",
        "quaternion order" => "quaternion_order",
        "objective" => "metric, loss",
        other => other,
    }
}

/// `--some-flag` as `some_flag` (the keyword argument of the same meaning), everywhere in
/// `text`, after the known phrases of [`PHRASES`].
fn python_flags(text: &str) -> String {
    let mut text = text.to_string();
    for (cli, python) in PHRASES {
        text = text.replace(cli, python);
    }
    let mut out = String::with_capacity(text.len());
    let mut rest = text.as_str();
    while let Some(at) = rest.find("--") {
        let after = &rest[at + 2..];
        let flag_len = after
            .char_indices()
            .find(|&(_, c)| !(c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-'))
            .map_or(after.len(), |(k, _)| k);
        let starts_flag = after.starts_with(|c: char| c.is_ascii_lowercase());
        let preceded = rest[..at]
            .chars()
            .next_back()
            .is_none_or(|c| !c.is_alphanumeric() && c != '-');
        out.push_str(&rest[..at]);
        if starts_flag && preceded {
            out.push_str(&after[..flag_len].trim_end_matches('-').replace('-', "_"));
            rest = &after[flag_len..];
        } else {
            out.push_str("--");
            rest = after;
        }
    }
    out.push_str(rest);
    out
}

/// serde's words for Rust types in JSON errors (`expected struct ConjugatePair`, `expected
/// f64`) as words about JSON.
fn json_words(text: &str) -> String {
    const EXPECTED: &str = "expected ";
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find(EXPECTED) {
        out.push_str(&rest[..at + EXPECTED.len()]);
        rest = &rest[at + EXPECTED.len()..];
        let word = |s: &str| {
            s.find(|c: char| !(c.is_alphanumeric() || c == '_'))
                .unwrap_or(s.len())
        };
        // `struct Name`, `tuple struct Name`, `enum Name`: skip the type's name
        let kinds = [
            ("struct ", "a JSON object"),
            ("tuple struct ", "a JSON array"),
            ("enum ", "one of the names"),
        ];
        if let Some((kind, words)) = kinds.iter().find(|(k, _)| rest.starts_with(k)) {
            let name = &rest[kind.len()..];
            out.push_str(words);
            rest = &name[word(name)..];
            continue;
        }
        let w = &rest[..word(rest)];
        let replacement = match w {
            "f64" | "f32" => Some("a number"),
            "u8" | "u16" | "u32" | "u64" | "u128" | "usize" => Some("a non-negative integer"),
            "i8" | "i16" | "i32" | "i64" | "i128" | "isize" => Some("an integer"),
            _ => None,
        };
        if let Some(r) = replacement {
            out.push_str(r);
            rest = &rest[w.len()..];
        }
    }
    out.push_str(rest);
    out
}

/// The message of a library error for Python users.
pub fn python_message(e: &rotavg::Error) -> String {
    let text = match e {
        rotavg::Error::Disconnected { component_sizes } => format!(
            "the view graph is not connected: {} components of sizes {:?}; {LARGEST_COMPONENT}",
            component_sizes.len(),
            component_sizes
        ),
        rotavg::Error::InvalidSettings { name, reason } => {
            format!("invalid setting `{}`: {reason}", keyword(name))
        }
        other => other.to_string(),
    };
    json_words(&python_flags(&text))
}

/// A library error as the `rotavg` exception of its kind, with its attributes.
pub fn error(e: rotavg::Error) -> PyErr {
    let message = python_message(&e);
    Python::attach(|py| {
        let (err, attributes): (PyErr, Vec<(&str, Py<PyAny>)>) = match &e {
            rotavg::Error::Parse { location, .. } => (
                ParseError::new_err(message),
                vec![
                    ("path", location.file.clone().into_pyobject(py)?.unbind()),
                    ("line", location.line.into_pyobject(py)?.unbind()),
                ],
            ),
            rotavg::Error::Io { path, .. } => (
                FileError::new_err(message),
                vec![("path", path.clone().into_pyobject(py)?.into_any().unbind())],
            ),
            rotavg::Error::Disconnected { component_sizes } => (
                DisconnectedError::new_err(message),
                vec![(
                    "component_sizes",
                    PyList::new(py, component_sizes)?.into_any().unbind(),
                )],
            ),
            rotavg::Error::Degenerate { .. } => (DegenerateError::new_err(message), vec![]),
            rotavg::Error::Solver { .. } => (SolverError::new_err(message), vec![]),
            _ => (Error::new_err(message), vec![]),
        };
        let value = err.value(py);
        for (name, v) in attributes {
            value.setattr(name, v)?;
        }
        Ok::<_, PyErr>(err)
    })
    .unwrap_or_else(|e| e)
}

/// An error about a Python argument (shapes, types, names), as `rotavg.Error`.
pub fn argument_error(message: impl Into<String>) -> PyErr {
    Error::new_err(message.into())
}

/// Register the exception classes in the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add("ParseError", py.get_type::<ParseError>())?;
    m.add("FileError", py.get_type::<FileError>())?;
    m.add("DisconnectedError", py.get_type::<DisconnectedError>())?;
    m.add("DegenerateError", py.get_type::<DegenerateError>())?;
    m.add("SolverError", py.get_type::<SolverError>())?;
    Ok(())
}
