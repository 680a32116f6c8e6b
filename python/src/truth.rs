//! Ground truth and accuracy: `read_ground_truth` (the command line's `--ground-truth` readers,
//! `rotavg::io::input::load_ground_truth`), `accuracy` (`rotavg::multiple::accuracy`) and the
//! `Accuracy` report.
//!
//! Ground truth is an `(n, 3, 3)` float64 array, one rotation per node; a node without ground
//! truth has a matrix of NaN.

use crate::convert::{matrices, optional_rotations_array};
use crate::detached;
use crate::errors::argument_error;
use crate::types::{Graph, to_json, to_python};
use pyo3::prelude::*;
use rotavg::io::detect::ReadOptions;
use rotavg::io::input::load_ground_truth;
use rotavg::multiple::accuracy::{AccuracyReport, align_and_compare};

/// Angular errors of an estimate against ground truth, after the optimal global alignment
/// (estimates are defined up to ``R_i -> R_i G``; ``G`` minimises
/// ``sum_i ||R_i G - T_i||_F^2`` over the nodes with ground truth), in degrees.
///
/// Attributes: ``mean_deg``, ``median_deg``, ``rmse_deg``, ``max_deg``, ``num_compared`` (nodes
/// with ground truth), ``alignment`` (``G``, ``(3, 3)``); ``robust_mean_deg``,
/// ``robust_median_deg``, ``robust_max_deg`` and ``robust_alignment``: the same after the
/// robust alignment ``G_1`` minimising ``sum_i theta(R_i G_1, T_i)`` (outliers do not pull it).
/// ``to_dict()`` is the ``accuracy`` object of ``rotavg multiple FILE --ground-truth GT
/// --json``; ``str()`` the line the command line prints.
#[pyclass(name = "Accuracy", module = "rotavg", frozen)]
pub struct Accuracy {
    pub inner: AccuracyReport,
}

#[pymethods]
impl Accuracy {
    /// Mean angular error, degrees.
    #[getter]
    fn mean_deg(&self) -> f64 {
        self.inner.mean_deg
    }
    /// Median angular error, degrees.
    #[getter]
    fn median_deg(&self) -> f64 {
        self.inner.median_deg
    }
    /// Root mean square angular error, degrees.
    #[getter]
    fn rmse_deg(&self) -> f64 {
        self.inner.rmse_deg
    }
    /// Largest angular error, degrees.
    #[getter]
    fn max_deg(&self) -> f64 {
        self.inner.max_deg
    }
    /// Number of nodes compared (those with ground truth).
    #[getter]
    fn num_compared(&self) -> usize {
        self.inner.num_compared
    }
    /// The alignment ``G`` (``estimate[i] @ G`` is compared with ``truth[i]``), ``(3, 3)``.
    #[getter]
    fn alignment<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::rotation_array(py, &self.inner.alignment)
    }
    /// Mean angular error after the robust (L1) alignment, degrees.
    #[getter]
    fn robust_mean_deg(&self) -> f64 {
        self.inner.robust.mean_deg
    }
    /// Median angular error after the robust (L1) alignment, degrees.
    #[getter]
    fn robust_median_deg(&self) -> f64 {
        self.inner.robust.median_deg
    }
    /// Largest angular error after the robust (L1) alignment, degrees.
    #[getter]
    fn robust_max_deg(&self) -> f64 {
        self.inner.robust.max_deg
    }
    /// The robust alignment ``G_1``, ``(3, 3)``.
    #[getter]
    fn robust_alignment<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        crate::convert::rotation_array(py, &self.inner.robust.alignment)
    }
    /// The report as a dict: the ``accuracy`` object of the ``--json`` output.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner)
    }
    /// The report as one line of JSON.
    fn to_json(&self) -> PyResult<String> {
        to_json(&self.inner)
    }
    fn __repr__(&self) -> String {
        let a = &self.inner;
        format!(
            "Accuracy(num_compared={}, mean_deg={:?}, median_deg={:?}, rmse_deg={:?}, max_deg={:?})",
            a.num_compared, a.mean_deg, a.median_deg, a.rmse_deg, a.max_deg
        )
    }
    fn __str__(&self) -> String {
        self.inner.to_string()
    }
}

/// Read ground truth for the nodes of a graph with the command line's readers
/// (``rotavg multiple FILE --ground-truth GT``), matched to the nodes by the file's ids.
///
/// Formats (as ``--ground-truth``): g2o vertex lines (``.g2o``, or a first token that is a
/// tag), Bundler ``.out``, COLMAP ``images.txt`` / ``images.bin`` (matched by image name, or
/// id), a JSON estimate (``{"rotations": [...]}`` in node order), or a rotation list (9 numbers
/// per line, line ``k`` = file id ``k``, or ``id R11 .. R33`` per line). An all-zero rotation
/// means "no ground truth for this camera".
///
/// Args:
///     path: the ground-truth file (str or path-like).
///     graph: the ``Graph`` from ``read_graph`` the truth is for. The file is matched against
///         the graph as read (a node-order JSON file lists every node of the file); with
///         ``largest_component=True`` the entries of the kept nodes are returned.
///
/// Returns:
///     ``(graph.n, 3, 3)`` float64 array: ``truth[k]`` is node ``k``'s rotation ``R_k`` (this
///     crate's convention, as the estimate), NaN where the file has none.
///
/// Raises:
///     rotavg.FileError: unreadable file. rotavg.ParseError: malformed content, or a node
///         count that does not match the graph.
#[pyfunction]
#[pyo3(signature = (path, graph))]
pub fn read_ground_truth<'py>(
    py: Python<'py>,
    path: std::path::PathBuf,
    graph: &Bound<'py, Graph>,
) -> PyResult<Bound<'py, PyAny>> {
    let g = graph.get();
    let name = path.to_string_lossy().into_owned();
    let as_read = g.as_read();
    let selection = &g.selection;
    let truth = detached(py, move || {
        let truth = load_ground_truth(&name, &as_read, &ReadOptions::default())?;
        selection.select(&truth).ok_or_else(|| {
            rotavg::Error::parse(
                Some(&name),
                None,
                format!(
                    "ground truth has {} entries, the graph has {} nodes",
                    truth.len(),
                    selection.num_read
                ),
            )
        })
    })?;
    optional_rotations_array(py, &truth)
}

/// The accuracy of an estimate against ground truth after the optimal global alignment (the
/// report ``rotavg multiple --ground-truth`` prints; ``rotavg::multiple::accuracy``).
///
/// Args:
///     estimate: ``(n, 3, 3)`` rotations ``R_i`` (any gauge), e.g. ``result.estimate``.
///     truth: ``(n, 3, 3)`` ground truth in the same convention (``R_ij R_i = R_j``); a matrix
///         of NaN (as ``read_ground_truth`` returns) marks a node without ground truth.
///
/// Returns:
///     Accuracy: angular errors in degrees after the least-squares and the robust alignment.
///
/// Raises:
///     rotavg.Error: shapes that differ, a matrix that is not a rotation, no node with ground
///         truth.
#[pyfunction]
#[pyo3(signature = (estimate, truth))]
pub fn accuracy(
    py: Python<'_>,
    estimate: &Bound<'_, PyAny>,
    truth: &Bound<'_, PyAny>,
) -> PyResult<Accuracy> {
    let estimate = matrices(estimate, "estimate")?;
    let truth = matrices(truth, "truth")?;
    if estimate.len() != truth.len() {
        return Err(argument_error(format!(
            "estimate and truth must have one rotation per node: got {} and {}",
            estimate.len(),
            truth.len()
        )));
    }
    let inner = detached(py, move || {
        align_and_compare(&estimate.rotations()?, &truth.optional_rotations()?)
    })?;
    Ok(Accuracy { inner })
}
