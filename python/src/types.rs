//! The Python result types: `Result` (an estimate with its cost, solver report and
//! certificate), `Certificate`, `SolverReport` and `Graph`. Each keeps the library's typed value;
//! `to_dict()` / `to_json()` serialise it with serde, so they are exactly the objects the command
//! line prints with `--json`.

use crate::convert::{matrices_array, optional_rotations_array, rotation_array, rotations_array};
use crate::truth::Accuracy;
use pyo3::prelude::*;
use pyo3::types::PyList;
use rotavg::Rotation;
use rotavg::io::detect::{ComponentSelection, LoadedGraph};
use rotavg::io::json::Estimate;
use rotavg::report::{CertifyReport, ConjugateReport, MultipleReport, SingleReport};
use rotavg::{Certificate as RCertificate, SolverReport as RSolverReport};
use serde::Serialize;
use std::borrow::Cow;

/// `json.loads(serde_json::to_string(value))`: a typed value as Python dicts, lists and numbers.
pub fn to_python<'py, T: Serialize>(py: Python<'py>, value: &T) -> PyResult<Bound<'py, PyAny>> {
    let text = to_json(value)?;
    py.import("json")?.call_method1("loads", (text,))
}

/// A typed value as one line of JSON (the command line's `--json` text).
pub fn to_json<T: Serialize>(value: &T) -> PyResult<String> {
    serde_json::to_string(value)
        .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(format!("serialising: {e}")))
}

/// A Python string literal (`'text'`) for a `repr`.
fn quoted(s: &str) -> String {
    format!("'{}'", s.replace('\\', "\\\\").replace('\'', "\\'"))
}

/// `repr` of an optional float (`None` or Python's shortest round-trip form).
fn opt(x: Option<f64>) -> String {
    x.map_or("None".into(), |x| format!("{x:?}"))
}

/// A certificate: a proven lower bound on the global minimum of the cost it is about, the gap of
/// the estimate to it, and the verdict (``"certified"`` when the gap is within the stated
/// tolerance, ``"gap_reported"`` or ``"inconclusive"`` otherwise).
///
/// Attributes: ``verdict``, ``certified`` (bool), ``upper_bound`` (the estimate's cost),
/// ``lower_bound``, ``gap``, ``relative_gap``, ``min_eigenvalue`` (None when unavailable),
/// ``method`` (``"theory"``, ``"dual"``, ``"sdp"``, ``"staircase"`` or
/// ``"branch_and_bound"``), ``allowed_gap``
/// (the tolerance that applied), ``explanation`` and ``seconds``.
/// ``to_dict()`` is the ``certificate`` object of the command line's ``--json`` output.
#[pyclass(name = "Certificate", module = "rotavg", frozen)]
pub struct Certificate {
    pub inner: RCertificate,
}

#[pymethods]
impl Certificate {
    /// ``"certified"``, ``"gap_reported"`` or ``"inconclusive"``.
    #[getter]
    fn verdict(&self) -> String {
        self.inner.verdict.to_string()
    }
    /// True when the verdict is ``"certified"``: the estimate is globally optimal up to the
    /// stated tolerance.
    #[getter]
    fn certified(&self) -> bool {
        self.inner.is_certified()
    }
    /// The cost of the estimate (chordal L2).
    #[getter]
    fn upper_bound(&self) -> f64 {
        self.inner.upper_bound
    }
    /// A proven lower bound on the global minimum, or None.
    #[getter]
    fn lower_bound(&self) -> Option<f64> {
        self.inner.lower_bound
    }
    /// ``upper_bound - lower_bound``, or None.
    #[getter]
    fn gap(&self) -> Option<f64> {
        self.inner.gap
    }
    /// ``gap / max(|upper_bound|, 1e-12)``, or None.
    #[getter]
    fn relative_gap(&self) -> Option<f64> {
        self.inner.relative_gap
    }
    /// The minimum eigenvalue of the certificate matrix (an estimate), or None.
    #[getter]
    fn min_eigenvalue(&self) -> Option<f64> {
        self.inner.min_eigenvalue
    }
    /// Which argument produced the bound: ``"theory"``, ``"dual"``, ``"sdp"``, ``"staircase"``
    /// or ``"branch_and_bound"``.
    #[getter]
    fn method(&self) -> String {
        self.inner.method.to_string()
    }
    /// The largest gap that counts as certified for this estimate (the tolerance that applied).
    #[getter]
    fn allowed_gap(&self) -> f64 {
        self.inner.tolerance.allowed_gap(self.inner.upper_bound)
    }
    /// Why the verdict is what it is, in words.
    #[getter]
    fn explanation(&self) -> String {
        self.inner.explanation.clone()
    }
    /// Time spent certifying, in seconds.
    #[getter]
    fn seconds(&self) -> f64 {
        self.inner.seconds
    }
    /// The certificate as a dict: the ``certificate`` object of the ``--json`` output.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner)
    }
    fn __repr__(&self) -> String {
        let c = &self.inner;
        format!(
            "Certificate(verdict={}, upper_bound={:?}, lower_bound={}, gap={}, relative_gap={}, method={}, seconds={:?})",
            quoted(&c.verdict.to_string()),
            c.upper_bound,
            opt(c.lower_bound),
            opt(c.gap),
            opt(c.relative_gap),
            quoted(&c.method.to_string()),
            c.seconds
        )
    }
    fn __str__(&self) -> String {
        self.inner.to_string()
    }
}

/// What the local solver did: ``name``, ``iterations``, ``termination`` (``"closed_form"``,
/// ``"converged"``, ``"iteration_limit"``, ``"stalled"``, ``"time_limit"`` or
/// ``"numerical_failure"``),
/// ``termination_detail`` (with the measured value and its threshold) and ``seconds``.
/// ``to_dict()`` is the ``solver`` object of the command line's ``--json`` output.
#[pyclass(name = "SolverReport", module = "rotavg", frozen)]
pub struct SolverReport {
    pub inner: RSolverReport,
}

#[pymethods]
impl SolverReport {
    /// The solver's name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }
    /// Iterations run.
    #[getter]
    fn iterations(&self) -> usize {
        self.inner.iterations
    }
    /// Why it stopped, as a short name.
    #[getter]
    fn termination(&self) -> String {
        self.inner.termination.name().to_string()
    }
    /// Why it stopped, with the measured value and its threshold.
    #[getter]
    fn termination_detail(&self) -> String {
        self.inner.termination.to_string()
    }
    /// True when the solver converged (or used a closed form).
    #[getter]
    fn converged(&self) -> bool {
        self.inner.termination.is_converged()
    }
    /// Wall time of the solve, in seconds.
    #[getter]
    fn seconds(&self) -> f64 {
        self.inner.seconds
    }
    /// The report as a dict: the ``solver`` object of the ``--json`` output.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        to_python(py, &self.inner)
    }
    fn __repr__(&self) -> String {
        format!(
            "SolverReport(name={}, iterations={}, termination={}, seconds={:?})",
            quoted(&self.inner.name),
            self.inner.iterations,
            quoted(self.inner.termination.name()),
            self.inner.seconds
        )
    }
    fn __str__(&self) -> String {
        self.inner.to_string()
    }
}

/// The library's report behind a [`RunResult`].
// One value per call, moved once into its `RunResult`: the variants' sizes do not matter.
#[allow(clippy::large_enum_variant)]
pub enum Report {
    Single(SingleReport),
    Multiple(MultipleReport),
    Conjugate(ConjugateReport),
    Certify(CertifyReport),
    Rig(rotavg::report::RigReport),
    RigFile(rotavg::report::RigFileReport),
}

impl Report {
    fn serialize_json(&self) -> PyResult<String> {
        match self {
            Report::Single(r) => to_json(r),
            Report::Multiple(r) => to_json(r),
            Report::Conjugate(r) => to_json(r),
            Report::Certify(r) => to_json(r),
            Report::Rig(r) => to_json(r),
            Report::RigFile(r) => to_json(r),
        }
    }

    fn text(&self) -> String {
        match self {
            Report::Single(r) => r.to_string(),
            Report::Multiple(r) => r.to_string(),
            Report::Conjugate(r) => r.to_string(),
            Report::Certify(r) => r.to_string(),
            Report::Rig(r) => r.to_string(),
            Report::RigFile(r) => r.to_string(),
        }
    }
}

/// The result of an ``average_*`` or ``certify_*`` call.
///
/// Attributes: ``problem`` (``"single"``, ``"multiple"`` or ``"conjugate"``), ``estimate``
/// (a float64 array: ``(N, 3, 3)`` for multiple averaging with ``R_0 = I``, ``(3, 3)``
/// otherwise), ``cost`` (under the chosen objective), ``chordal_cost`` (multiple and
/// conjugate: the chordal L2 cost that the certificate bounds; None for single averaging),
/// ``num_rotations``, ``num_measurements``, ``solver``
/// (a ``SolverReport``; None for ``certify_*``, which never change the estimate),
/// ``certificate`` (a ``Certificate``, or None when none was computed), ``verdict`` (the
/// certificate's, or a robust run's inlier graph's; None without one), ``accuracy`` (an
/// ``Accuracy`` against the ground truth given to ``average_multiple``, else None) and
/// ``node_ids`` (``average_multiple``: the file's id of each node of the estimate, uint64;
/// else None).
///
/// ``to_dict()`` / ``to_json()`` give exactly the object ``rotavg SUBCOMMAND --json`` prints for
/// the same problem; ``str(result)`` the text the command line prints.
#[pyclass(name = "Result", module = "rotavg", frozen)]
pub struct RunResult {
    /// ``"single"``, ``"multiple"`` or ``"conjugate"``.
    #[pyo3(get)]
    problem: String,
    /// The estimate as a float64 array.
    #[pyo3(get)]
    estimate: Py<PyAny>,
    /// The cost of the estimate under the chosen objective.
    #[pyo3(get)]
    cost: f64,
    /// The chordal L2 cost of the estimate (what the certificate bounds); None for single
    /// averaging, whose certificate bounds the chosen objective itself.
    #[pyo3(get)]
    chordal_cost: Option<f64>,
    /// Number of rotations estimated (1 for single and conjugate).
    #[pyo3(get)]
    num_rotations: usize,
    /// Number of samples, edges or pairs.
    #[pyo3(get)]
    num_measurements: usize,
    /// The local solver's report, or None (``certify_*``).
    #[pyo3(get)]
    solver: Option<Py<SolverReport>>,
    /// The certificate, or None when none was computed.
    #[pyo3(get)]
    certificate: Option<Py<Certificate>>,
    /// The run's verdict (``"certified"``, ``"gap_reported"``, ``"inconclusive"``), or None:
    /// the certificate's, or for a robust ``average_multiple`` (whose cost has none) its
    /// inlier graph's; ``to_dict()["verdict"]`` names the problem it is about.
    #[pyo3(get)]
    verdict: Option<String>,
    /// The accuracy against ground truth (``average_multiple`` with ground truth), or None.
    #[pyo3(get)]
    accuracy: Option<Py<Accuracy>>,
    /// The file's id of each node of the estimate (``average_multiple``), or None.
    #[pyo3(get)]
    node_ids: Option<Py<PyAny>>,
    report: Report,
}

impl RunResult {
    /// The Python result of a library report.
    pub fn new(py: Python<'_>, report: Report) -> PyResult<Self> {
        let (problem, estimate, cost, chordal_cost, n, m, solver, certificate) = match &report {
            Report::Single(r) => {
                let s = &r.result.solution;
                (
                    "single",
                    rotation_array(py, &s.estimate)?,
                    s.cost,
                    None,
                    1,
                    s.num_samples,
                    Some(&s.report),
                    r.result.certificate.as_ref(),
                )
            }
            Report::Multiple(r) => {
                let s = &r.result.solution;
                (
                    "multiple",
                    rotations_array(py, &s.rotations)?,
                    s.cost,
                    Some(s.chordal_cost),
                    s.rotations.len(),
                    r.num_edges,
                    Some(&s.report),
                    r.result.certificate.as_ref(),
                )
            }
            Report::Conjugate(r) => {
                let s = &r.result.solution;
                (
                    "conjugate",
                    rotation_array(py, &s.estimate)?,
                    s.cost,
                    Some(s.chordal_cost),
                    1,
                    r.num_pairs,
                    Some(&s.report),
                    r.result.certificate.as_ref(),
                )
            }
            Report::Rig(r) => {
                let s = &r.result.solution;
                (
                    "rig",
                    rotations_array(py, &s.rotations)?,
                    s.cost,
                    None,
                    s.rotations.len(),
                    r.num_edges[0] + r.num_edges[1],
                    Some(&s.report),
                    r.result.certificate.as_ref(),
                )
            }
            Report::RigFile(r) => {
                let s = &r.result.solution;
                (
                    "rig",
                    rotations_array(py, &s.frames)?,
                    s.cost,
                    None,
                    s.frames.len(),
                    r.rig.problem.edges().len(),
                    Some(&s.report),
                    r.result.certificate.as_ref(),
                )
            }
            Report::Certify(r) => (
                match r.problem {
                    rotavg::report::ProblemKind::Single => "single",
                    rotavg::report::ProblemKind::Multiple => "multiple",
                    rotavg::report::ProblemKind::Conjugate => "conjugate",
                },
                match &r.estimate {
                    Estimate::Single(s) => rotation_array(py, s)?,
                    Estimate::Multiple(rs) => rotations_array(py, rs)?,
                },
                r.cost,
                Some(r.cost),
                r.num_rotations,
                r.num_measurements,
                None,
                Some(&r.certificate),
            ),
        };
        let solver = solver
            .map(|s| Py::new(py, SolverReport { inner: s.clone() }))
            .transpose()?;
        let certificate = certificate
            .map(|c| Py::new(py, Certificate { inner: c.clone() }))
            .transpose()?;
        let (accuracy, node_ids) = match &report {
            Report::Multiple(r) => (
                r.accuracy
                    .as_ref()
                    .map(|a| Py::new(py, Accuracy { inner: a.clone() }))
                    .transpose()?,
                Some(
                    crate::convert::read_only(
                        numpy::PyArray1::from_slice(py, &r.node_ids).into_any(),
                    )?
                    .unbind(),
                ),
            ),
            _ => (None, None),
        };
        let verdict = match &report {
            Report::Multiple(r) => r.verdict(),
            _ => certificate.as_ref().map(|c| c.get().inner.verdict),
        }
        .map(|v| v.to_string());
        Ok(RunResult {
            accuracy,
            node_ids,
            verdict,
            problem: problem.to_string(),
            estimate: estimate.unbind(),
            cost,
            chordal_cost,
            num_rotations: n,
            num_measurements: m,
            solver,
            certificate,
            report,
        })
    }
}

impl RunResult {
    /// ``"single"``, ``"multiple"``, ``"conjugate"`` or ``"rig"``.
    pub fn problem(&self) -> &str {
        &self.problem
    }

    /// The estimate's rotations (one for single and conjugate results) and the certificate,
    /// for a figure; no rotations for a rig.
    pub fn figure_parts(&self) -> (Option<Vec<Rotation>>, Option<rotavg::Certificate>) {
        match &self.report {
            Report::Single(r) => (
                Some(vec![r.result.solution.estimate]),
                r.result.certificate.clone(),
            ),
            Report::Multiple(r) => (
                Some(r.result.solution.rotations.clone()),
                r.result.certificate.clone(),
            ),
            Report::Conjugate(r) => (
                Some(vec![r.result.solution.estimate]),
                r.result.certificate.clone(),
            ),
            Report::Certify(r) => {
                let rotations = match &r.estimate {
                    Estimate::Multiple(rs) => rs.clone(),
                    Estimate::Single(one) => vec![*one],
                };
                (Some(rotations), Some(r.certificate.clone()))
            }
            Report::Rig(_) | Report::RigFile(_) => (None, None),
        }
    }

    /// The file `rotavg rig --output` writes for a rig result, else None.
    pub fn rig_output(&self) -> Option<String> {
        match &self.report {
            Report::Rig(r) => {
                let s = &r.result.solution;
                Some(rotavg::io::json::write_rig_json(
                    &s.rotations,
                    &r.node_ids,
                    &s.s,
                ))
            }
            Report::RigFile(r) => {
                let s = &r.result.solution;
                Some(rotavg::io::rig::write_rig_estimate_json(
                    &s.frames, &s.sensors, &r.rig,
                ))
            }
            _ => None,
        }
    }

    /// The multiple-averaging report, if this is one.
    pub fn multiple(&self) -> Option<&MultipleReport> {
        match &self.report {
            Report::Multiple(r) => Some(r),
            _ => None,
        }
    }
}

#[pymethods]
impl RunResult {
    /// A robust ``average_multiple``'s refined inlier-graph estimate (``(n, 3, 3)``, what the
    /// command line's ``--inlier-output`` writes: ``write_estimate(graph,
    /// result.inlier_estimate, path)``), or None (no inlier graph was certified).
    #[getter]
    fn inlier_estimate<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let graph = self
            .multiple()
            .and_then(|r| r.result.details.inlier_graph.as_deref());
        graph.map(|g| rotations_array(py, &g.estimate)).transpose()
    }

    /// The result as a dict: the object ``rotavg SUBCOMMAND --json`` prints (built from the
    /// library's typed report, so keys and values are the command line's).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = self.report.serialize_json()?;
        py.import("json")?.call_method1("loads", (text,))
    }
    /// The result as one line of JSON, as ``rotavg SUBCOMMAND --json`` prints it.
    fn to_json(&self) -> PyResult<String> {
        self.report.serialize_json()
    }
    fn __repr__(&self, py: Python<'_>) -> String {
        let certificate = match &self.certificate {
            Some(c) => {
                let c = &c.get().inner;
                format!(
                    "{} (method {}, relative gap {})",
                    c.verdict,
                    c.method,
                    c.relative_gap.map_or("None".into(), |g| format!("{g:.1e}"))
                )
            }
            None => "None".into(),
        };
        let solver = match &self.solver {
            Some(s) => {
                let s = &s.get().inner;
                format!(
                    "{} ({} iterations, {})",
                    s.name,
                    s.iterations,
                    s.termination.name()
                )
            }
            None => "None".into(),
        };
        let shape: String = self
            .estimate
            .bind(py)
            .getattr("shape")
            .and_then(|s| s.repr())
            .map(|s| s.to_string())
            .unwrap_or_default();
        format!(
            "Result(problem={}, estimate=<array {shape}>, cost={:.9e}, num_measurements={}, solver={solver}, certificate={certificate})",
            quoted(&self.problem),
            self.cost,
            self.num_measurements
        )
    }
    fn __str__(&self) -> String {
        self.report.text()
    }
}

/// A view graph read from a file by ``read_graph``: ``n`` nodes, edges ``(i[k], j[k])`` with
/// relative rotations ``rel[k]`` (``rel[k] @ R_i = R_j``) and ``weights[k]``, as read-only numpy
/// arrays that feed ``average_multiple(g.n, g.i, g.j, g.rel, g.weights)``; ``node_ids`` (the
/// file's id of each node), ``format``, ``warnings``, ``initial`` (the vertex rotations of a
/// g2o file as this crate's ``R_i``, or None), ``other_components`` (sizes of components dropped by
/// ``largest_component=True``), ``truth`` (the ground truth read with
/// ``read_graph(..., ground_truth=GT)``, ``(n, 3, 3)`` with NaN where unknown, or None),
/// ``information`` (each edge's ``3 x 3`` information matrix when read with anisotropic
/// information, ``(M, 3, 3)``, else None: ``average_multiple(g.n, g.i, g.j, g.rel,
/// information=g.information)`` is then the same problem). Passing the graph itself, ``average_multiple(g)``, solves exactly what the command line
/// solves for the file (same numbers, same ``--json`` object, with the accuracy against the
/// ground truth when one was read).
#[pyclass(name = "Graph", module = "rotavg", frozen)]
pub struct Graph {
    pub loaded: LoadedGraph,
    pub selection: ComponentSelection,
    pub name: String,
    /// Ground truth of each node of [`Self::loaded`], when read.
    pub truth: Option<Vec<Option<Rotation>>>,
    /// The file's ids and names of every node of the graph as read, when a component was
    /// dropped (otherwise those of [`Self::loaded`]).
    read_ids: Vec<u64>,
    read_names: Vec<String>,
    /// Number of nodes.
    #[pyo3(get)]
    n: usize,
    /// Tail node of each edge (int64).
    #[pyo3(get)]
    i: Py<PyAny>,
    /// Head node of each edge (int64).
    #[pyo3(get)]
    j: Py<PyAny>,
    /// Relative rotation of each edge, ``(M, 3, 3)`` float64, ``rel[k] @ R_i = R_j``.
    #[pyo3(get)]
    rel: Py<PyAny>,
    /// Weight of each edge, ``(M,)`` float64.
    #[pyo3(get)]
    weights: Py<PyAny>,
    /// The file's id of each node (uint64).
    #[pyo3(get)]
    node_ids: Py<PyAny>,
    /// Vertex rotations from the file (``(n, 3, 3)``), or None.
    #[pyo3(get)]
    initial: Option<Py<PyAny>>,
    /// Ground truth of each node (``(n, 3, 3)``, NaN where unknown), or None.
    #[pyo3(get, name = "truth")]
    truth_array: Option<Py<PyAny>>,
    /// Each edge's ``3 x 3`` information matrix ``H`` (``(M, 3, 3)`` float64) when the graph
    /// was read with anisotropic information, or None (the weights are then the whole story,
    /// as for information that is exactly ``w I``).
    #[pyo3(get)]
    information: Option<Py<PyAny>>,
}

impl Graph {
    /// The Python view of a loaded graph: `loaded` is the graph as read restricted to
    /// `selection`, whose node ids and names as read are `read_ids` and `read_names` (used
    /// only when a component was dropped), with ground truth for its nodes.
    pub fn new(
        py: Python<'_>,
        name: String,
        (loaded, selection): (LoadedGraph, ComponentSelection),
        (read_ids, read_names): (Vec<u64>, Vec<String>),
        truth: Option<Vec<Option<Rotation>>>,
    ) -> PyResult<Self> {
        use crate::convert::read_only;
        use numpy::PyArray1;
        let edges = loaded.problem.edges();
        let i: Vec<i64> = edges.iter().map(|e| e.i as i64).collect();
        let j: Vec<i64> = edges.iter().map(|e| e.j as i64).collect();
        let w: Vec<f64> = edges.iter().map(|e| e.weight).collect();
        let rel: Vec<_> = edges.iter().map(|e| e.rotation).collect();
        let arr = |a: Bound<'_, PyAny>| read_only(a).map(Bound::unbind);
        let (read_ids, read_names) = if selection.is_whole() {
            (Vec::new(), Vec::new())
        } else {
            (read_ids, read_names)
        };
        Ok(Graph {
            n: loaded.problem.num_rotations(),
            i: arr(PyArray1::from_vec(py, i).into_any())?,
            j: arr(PyArray1::from_vec(py, j).into_any())?,
            rel: arr(rotations_array(py, &rel)?)?,
            weights: arr(PyArray1::from_vec(py, w).into_any())?,
            node_ids: arr(PyArray1::from_slice(py, &loaded.node_ids).into_any())?,
            initial: loaded
                .initial
                .as_ref()
                .map(|r| rotations_array(py, r).and_then(arr))
                .transpose()?,
            truth_array: truth
                .as_ref()
                .map(|t| optional_rotations_array(py, t).and_then(arr))
                .transpose()?,
            information: loaded
                .problem
                .information()
                .map(|h| matrices_array(py, h.iter().map(|h| h.matrix())).and_then(arr))
                .transpose()?,
            truth,
            read_ids,
            read_names,
            loaded,
            selection,
            name,
        })
    }

    /// The graph as read, as far as ground-truth files are concerned: its nodes' file ids
    /// and names (the kept graph's problem; `rotavg::io::input::read_ground_truth` matches
    /// by ids and names only).
    pub fn as_read(&self) -> Cow<'_, LoadedGraph> {
        if self.selection.is_whole() {
            return Cow::Borrowed(&self.loaded);
        }
        Cow::Owned(LoadedGraph {
            node_ids: self.read_ids.clone(),
            node_names: self.read_names.clone(),
            ..self.loaded.clone()
        })
    }
}

#[pymethods]
impl Graph {
    /// Number of edges.
    #[getter]
    fn num_edges(&self) -> usize {
        self.loaded.problem.num_edges()
    }
    /// The format read: ``"g2o"``, ``"one_dsfm"`` (1DSfM ``EGs.txt``) or ``"json"``.
    #[getter]
    fn format(&self) -> String {
        serde_json::to_value(self.loaded.format)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default()
    }
    /// The reader's remarks (skipped line types, missing vertices, ...).
    #[getter]
    fn warnings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        PyList::new(py, self.loaded.warnings.iter().map(|w| w.message.as_str()))
    }
    /// Sizes of the connected components not kept (``read_graph(..., largest_component=True)``).
    #[getter]
    fn other_components(&self) -> Vec<usize> {
        self.selection.other_component_sizes.clone()
    }
    /// The path the graph was read from.
    #[getter]
    fn path(&self) -> String {
        self.name.clone()
    }
    fn __repr__(&self) -> String {
        format!(
            "Graph(path={}, format={}, n={}, num_edges={})",
            quoted(&self.name),
            quoted(&self.format()),
            self.n,
            self.num_edges()
        )
    }
    fn __len__(&self) -> usize {
        self.n
    }
}
