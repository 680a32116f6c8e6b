//! The crate's single error type.
//!
//! `Err` is returned only when a call cannot run meaningfully: bad input, bad settings, I/O,
//! solver setup. Iteration limits, inexact solves and failed certificates are `Ok` results whose
//! status says so.

use std::fmt;

/// Where in an input an offending item sits: a file (or `-` for stdin), a 1-based line, and an
/// item index (sample, edge or pair number, 0-based) when known.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Location {
    /// File name as given by the user (`-` for standard input), if the data came from a file.
    pub file: Option<String>,
    /// 1-based line number in that file.
    pub line: Option<usize>,
}

impl fmt::Display for Location {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match (&self.file, self.line) {
            (Some(file), Some(line)) => write!(f, "{file}:{line}: "),
            (Some(file), None) => write!(f, "{file}: "),
            (None, Some(line)) => write!(f, "line {line}: "),
            (None, None) => Ok(()),
        }
    }
}

/// Everything that can go wrong in `rotavg`.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// A matrix given as a rotation is not one within the tolerance.
    NotARotation {
        /// Which input item (sample, edge, pair), 0-based, with its description.
        item: String,
        /// `||R^T R - I||_F` of the offending matrix.
        orthogonality_error: f64,
        /// Its determinant.
        determinant: f64,
        /// The tolerance that was applied.
        tolerance: f64,
    },
    /// A NaN or infinite number where a finite one is required.
    NonFinite {
        /// What held the value.
        item: String,
    },
    /// A weight outside `[1e-100, 1e100]` ([`crate::validate::MIN_WEIGHT`], [`crate::validate::MAX_WEIGHT`]):
    /// not finite, not positive, or so extreme that squares of costs would over/underflow.
    InvalidWeight {
        /// Which input item, 0-based.
        item: String,
        /// The weight given.
        weight: f64,
    },
    /// An edge's 3x3 information matrix is not finite, not exactly symmetric, not positive
    /// semidefinite, or has a trace outside the weight window
    /// ([`crate::multiple::anisotropic::Information::new`]).
    InvalidInformation {
        /// Which input item, 0-based, with its description.
        item: String,
        /// What is wrong with it.
        reason: String,
    },
    /// No data where at least some are needed.
    Empty {
        /// What was empty.
        what: String,
    },
    /// A node index outside `0..num_rotations`.
    IndexOutOfRange {
        /// Edge number, 0-based.
        edge: usize,
        /// The offending index.
        index: usize,
        /// Number of rotations in the problem.
        num_rotations: usize,
    },
    /// An edge from a node to itself.
    SelfLoop {
        /// Edge number, 0-based.
        edge: usize,
        /// The node.
        node: usize,
    },
    /// A view graph that is not connected; the sizes of its components, largest first.
    Disconnected {
        /// Number of nodes in each connected component, largest first.
        component_sizes: Vec<usize>,
    },
    /// Data that do not determine the answer (e.g. all hand-eye rotation axes parallel).
    Degenerate {
        /// What is degenerate and why it matters.
        reason: String,
    },
    /// A settings value out of its valid range.
    InvalidSettings {
        /// Name of the setting.
        name: String,
        /// What is wrong with it.
        reason: String,
    },
    /// A malformed input file.
    Parse {
        /// Where (file and line).
        location: Location,
        /// What was wrong.
        message: String,
    },
    /// An I/O failure.
    Io {
        /// The path involved.
        path: String,
        /// The operating system's message.
        message: String,
    },
    /// A step whose predicted memory is over the budget, refused before it allocated.
    OverBudget {
        /// The step and its size.
        what: String,
        /// Its predicted memory, bytes.
        predicted_bytes: f64,
        /// The budget, bytes.
        max_memory_bytes: u64,
    },
    /// A numerical solver could not be set up or failed in a way that leaves no result.
    Solver {
        /// What happened.
        message: String,
    },
}

/// `Result` with [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::NotARotation {
                item,
                orthogonality_error,
                determinant,
                tolerance,
            } => write!(
                f,
                "{item} is not a rotation: ||R^T R - I||_F = {orthogonality_error:.3e}, det = {determinant:.6} (tolerance {tolerance:.1e})"
            ),
            Error::NonFinite { item } => write!(f, "{item} contains NaN or infinity"),
            Error::InvalidWeight { item, weight } => {
                write!(
                    f,
                    "{item} has weight {weight:e}; weights must lie in [1e-100, 1e100] (they are relative: rescale them)"
                )
            }
            Error::InvalidInformation { item, reason } => write!(f, "{item}: information {reason}"),
            Error::Empty { what } => write!(f, "{what} is empty"),
            Error::IndexOutOfRange {
                edge,
                index,
                num_rotations,
            } => write!(
                f,
                "edge {edge} refers to node {index}, but there are only {num_rotations} nodes (0..{num_rotations})"
            ),
            Error::SelfLoop { edge, node } => {
                write!(f, "edge {edge} is a self loop at node {node}")
            }
            Error::Disconnected { component_sizes } => write!(
                f,
                "the view graph is not connected: {} components of sizes {:?}; solve the largest component instead (e.g. `--largest-component`)",
                component_sizes.len(),
                component_sizes
            ),
            Error::Degenerate { reason } => write!(f, "degenerate data: {reason}"),
            Error::InvalidSettings { name, reason } => {
                write!(f, "invalid setting `{name}`: {reason}")
            }
            Error::Parse { location, message } => write!(f, "{location}{message}"),
            Error::Io { path, message } => write!(f, "{path}: {message}"),
            Error::OverBudget {
                what,
                predicted_bytes,
                max_memory_bytes,
            } => write!(
                f,
                "{what} would need about {:.2} GiB, over the memory budget of {:.2} GiB; nothing \
                 was allocated",
                predicted_bytes / (1u64 << 30) as f64,
                *max_memory_bytes as f64 / (1u64 << 30) as f64
            ),
            Error::Solver { message } => write!(f, "solver failure: {message}"),
        }
    }
}

impl std::error::Error for Error {}

impl Error {
    /// A parse error at `file:line`.
    ///
    /// ```
    /// let e = rotavg::Error::parse(Some("graph.g2o"), Some(12), "expected 7 numbers");
    /// assert_eq!(e.to_string(), "graph.g2o:12: expected 7 numbers");
    /// ```
    pub fn parse(file: Option<&str>, line: Option<usize>, message: impl Into<String>) -> Self {
        Error::Parse {
            location: Location {
                file: file.map(str::to_owned),
                line,
            },
            message: message.into(),
        }
    }

    /// Attach a file name (and line, if absent) to a data error raised while reading a file, so
    /// that validation errors found after parsing still name their source.
    ///
    /// ```
    /// use rotavg::Error;
    /// // A validation error found after parsing becomes a parse error that names the file.
    /// let e = Error::Empty { what: "the list of rotations".into() }.in_file("samples.json", None);
    /// assert_eq!(e.to_string(), "samples.json: the list of rotations is empty");
    /// ```
    pub fn in_file(self, file: &str, line: Option<usize>) -> Self {
        match self {
            Error::Parse {
                mut location,
                message,
            } => {
                if location.file.is_none() {
                    location.file = Some(file.to_owned());
                }
                if location.line.is_none() {
                    location.line = line;
                }
                Error::Parse { location, message }
            }
            Error::Io { .. } => self,
            other => Error::Parse {
                location: Location {
                    file: Some(file.to_owned()),
                    line,
                },
                message: other.to_string(),
            },
        }
    }
}
