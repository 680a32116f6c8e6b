//! Python bindings of `rotavg` (the extension module `rotavg._rotavg`; the package is
//! `python/rotavg/`, its stubs `python/rotavg/__init__.pyi`).
//!
//! Every function copies its numpy inputs while holding the GIL, then releases the GIL to
//! validate them with the library's checks, run the library's pipeline (`average_*`) or
//! certifier (`certify_*`) and build the library's typed report, the same report the command
//! line prints with `--json`. Library errors become `rotavg.Error` (a `ValueError`) or one of
//! its subclasses, with messages that name Python keywords (`errors.rs`); a panic (a bug)
//! becomes a `RuntimeError`, never an abort.

mod convert;
mod errors;
mod gravity;
mod handeye;
mod output;
mod progress;
mod rig;
mod truth;
mod types;

use convert::{Matrices, indices, matrices, matrix, vector};
pub use errors::Error;
use errors::{argument_error, error};
use handeye::HandEyeData;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use rotavg::certify::{CertifyMode, CertifySettings};
use rotavg::conjugate::{ConjugatePair, ConjugateProblem, ConjugateSettings};
use rotavg::io::detect::{ComponentSelection, GraphFormat, LoadedGraph, ReadOptions, WeightSource};
use rotavg::io::input::{
    LoadedEstimate, LoadedProblem, MultipleInput, load_estimate_for, load_ground_truth,
    load_view_graph,
};
use rotavg::io::json::Estimate;
use rotavg::io::names::{LossKind, MultipleLoss};
use rotavg::multiple::anisotropic::Information;
use rotavg::multiple::robust_scale::ScaleRule;
use rotavg::multiple::{Edge, Initialisation, MultipleProblem, MultipleSettings};
use rotavg::pipeline::{AverageSettings, average_conjugate, average_multiple, average_single};
use rotavg::report::{CertifyReport, ConjugateReport, MultipleReport, SingleReport};
use rotavg::single::{SingleProblem, SingleSettings};
use rotavg::{Loss, Metric, Objective, Rotation};
use std::panic::{AssertUnwindSafe, catch_unwind};
use types::{Certificate, Graph, Report, RunResult, SolverReport};

/// Run `f` without the GIL; a library error becomes a `rotavg` exception, a panic a
/// `RuntimeError`.
pub(crate) fn detached<T: Send>(
    py: Python<'_>,
    f: impl FnOnce() -> rotavg::Result<T> + Send,
) -> PyResult<T> {
    match py.detach(|| catch_unwind(AssertUnwindSafe(f))) {
        Ok(result) => result.map_err(error),
        Err(payload) => {
            let message = payload
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| payload.downcast_ref::<&str>().copied())
                .unwrap_or("unknown panic");
            Err(PyRuntimeError::new_err(format!(
                "rotavg internal error (a bug, please report it): {message}"
            )))
        }
    }
}

/// Parse a name of one of the library's choices (`chordal`, `auto`, ...) given as the keyword
/// argument `keyword` (which an unknown name's error names).
pub(crate) fn parse_named<T: std::str::FromStr<Err = rotavg::Error>>(
    name: &str,
    keyword: &str,
) -> PyResult<T> {
    name.parse().map_err(|e| match e {
        rotavg::Error::InvalidSettings { reason, .. } => error(rotavg::Error::InvalidSettings {
            name: keyword.into(),
            reason,
        }),
        other => error(other),
    })
}

/// Edge data copied out of Python, validated later by [`EdgeArrays::graph`].
struct EdgeArrays {
    n: i64,
    i: Vec<i64>,
    j: Vec<i64>,
    rel: Matrices,
    weights: Option<Vec<f64>>,
    information: Option<Matrices>,
}

impl EdgeArrays {
    /// Copy `n, i, j, rel, weights, information`, checking the shapes.
    fn copy(
        n: &Bound<'_, PyAny>,
        i: &Bound<'_, PyAny>,
        j: &Bound<'_, PyAny>,
        rel: &Bound<'_, PyAny>,
        weights: Option<&Bound<'_, PyAny>>,
        information: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let n: i64 = n
            .extract()
            .map_err(|_| argument_error("n must be an integer (the number of rotations)"))?;
        let (i, j, rel) = (indices(i, "i")?, indices(j, "j")?, matrices(rel, "rel")?);
        if i.len() != rel.len() || j.len() != rel.len() {
            return Err(argument_error(format!(
                "i, j and rel must have one entry per edge: got {}, {} and {}",
                i.len(),
                j.len(),
                rel.len()
            )));
        }
        let weights = weights
            .filter(|w| !w.is_none())
            .map(|w| vector(w, "weights", rel.len()))
            .transpose()?;
        let information = optional_matrices(information, "information")?;
        match &information {
            Some(_) if weights.is_some() => {
                return Err(argument_error(
                    "pass weights or information (one 3x3 matrix per edge), not both",
                ));
            }
            Some(h) if h.len() != rel.len() => {
                return Err(argument_error(format!(
                    "information must have one 3x3 matrix per edge: got {} for {} edges",
                    h.len(),
                    rel.len()
                )));
            }
            _ => {}
        }
        Ok(EdgeArrays {
            n,
            i,
            j,
            rel,
            weights,
            information,
        })
    }

    /// The validated view graph (library checks: rotations, indices, self loops, weights), as a
    /// loaded graph of `n` nodes with ids `0..n` (format `json`: the contract's data model).
    fn graph(self) -> rotavg::Result<LoadedGraph> {
        let n = usize::try_from(self.n).map_err(|_| rotavg::Error::InvalidSettings {
            name: "n".into(),
            reason: format!("{} is negative", self.n),
        })?;
        // As the JSON reader: nothing sized from an unchecked count. More than 2m + 1 nodes
        // means a node without edges (a disconnected graph) and could be an absurd number.
        let m = self.rel.len();
        if n > 2 * m + 1 {
            return Err(rotavg::Error::InvalidSettings {
                name: "n".into(),
                reason: format!("n = {n}, but {m} edges touch at most {} nodes", 2 * m),
            });
        }
        let rel = self.rel.rotations()?;
        let read = ReadOptions {
            rotation_tolerance: self.rel.tolerance(),
            ..Default::default()
        };
        let mut edges = Vec::with_capacity(m);
        for (k, rotation) in rel.into_iter().enumerate() {
            let node = |v: i64| {
                usize::try_from(v).map_err(|_| rotavg::Error::InvalidSettings {
                    name: "i, j".into(),
                    reason: format!(
                        "edge {k} refers to node {v}, but there are only {n} nodes (0..{n})"
                    ),
                })
            };
            edges.push(Edge {
                i: node(self.i[k])?,
                j: node(self.j[k])?,
                rotation,
                weight: self.weights.as_ref().map_or(1.0, |w| w[k]),
            });
        }
        let reversed = edges.iter().filter(|e| e.i > e.j).count();
        let mut problem = MultipleProblem::new(n, edges)?;
        if let Some(h) = &self.information {
            let info = h
                .matrices()
                .into_iter()
                .enumerate()
                .map(|(k, m)| {
                    Information::new(m).map_err(|e| match e {
                        rotavg::Error::InvalidInformation { reason, .. } => {
                            rotavg::Error::InvalidInformation {
                                item: format!("information[{k}]"),
                                reason,
                            }
                        }
                        other => other,
                    })
                })
                .collect::<rotavg::Result<Vec<_>>>()?;
            problem = problem.with_information(info)?;
        }
        Ok(LoadedGraph {
            reversed,
            ..LoadedGraph::from_problem(problem).read_with(&read)
        })
    }
}

/// A view graph given either as a `Graph` (in place of `n`) or as `n, i, j, rel, weights`.
enum GraphInput {
    /// A graph read from a file: the graph, its selection, the path, its ground truth.
    Loaded(
        LoadedGraph,
        ComponentSelection,
        String,
        Option<Vec<Option<Rotation>>>,
    ),
    Arrays(EdgeArrays),
}

impl GraphInput {
    /// Edge arrays checked as rotations with `tolerance` (a graph read from a file was
    /// checked by its reader, with `read_graph`'s own `rotation_tolerance`).
    fn within(self, tolerance: f64) -> Self {
        match self {
            GraphInput::Arrays(a) => GraphInput::Arrays(EdgeArrays {
                rel: a.rel.within(tolerance),
                ..a
            }),
            loaded => loaded,
        }
    }

    fn copy(
        n: &Bound<'_, PyAny>,
        i: Option<&Bound<'_, PyAny>>,
        j: Option<&Bound<'_, PyAny>>,
        rel: Option<&Bound<'_, PyAny>>,
        weights: Option<&Bound<'_, PyAny>>,
        information: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        if let Ok(g) = n.cast::<Graph>() {
            if i.is_some()
                || j.is_some()
                || rel.is_some()
                || weights.is_some()
                || information.is_some()
            {
                return Err(argument_error(
                    "pass either a Graph or n, i, j, rel (and weights or information), not both",
                ));
            }
            let g = g.get();
            return Ok(GraphInput::Loaded(
                g.loaded.clone(),
                g.selection.clone(),
                g.name.clone(),
                g.truth.clone(),
            ));
        }
        match (i, j, rel) {
            (Some(i), Some(j), Some(rel)) => Ok(GraphInput::Arrays(EdgeArrays::copy(
                n,
                i,
                j,
                rel,
                weights,
                information,
            )?)),
            _ => Err(argument_error(
                "a view graph needs n, i, j and rel (or a Graph from read_graph)",
            )),
        }
    }

    /// The validated graph as `rotavg multiple` solves it: restricted to its largest component
    /// when asked (a graph read with `largest_component=True` is already), with the ground
    /// truth `truth` (one entry per node of the graph as given, or per kept node; NaN where
    /// unknown) or else the graph's own.
    fn into_input(
        self,
        largest_component: bool,
        truth: Option<Matrices>,
    ) -> rotavg::Result<MultipleInput> {
        let (graph, selection, name, own_truth) = match self {
            GraphInput::Loaded(g, s, name, t) => (g, s, name, t),
            GraphInput::Arrays(a) => {
                let g = a.graph()?;
                let n = g.problem.num_rotations();
                (
                    g,
                    ComponentSelection::whole(n),
                    "<arrays>".to_string(),
                    None,
                )
            }
        };
        let (graph, selection, own_truth) = if largest_component && selection.is_whole() {
            let (graph, selection) = graph.largest_component();
            let truth = own_truth.and_then(|t| selection.select(&t));
            (graph, selection, truth)
        } else {
            (graph, selection, own_truth)
        };
        let truth = match truth {
            Some(t) => Some(for_kept(
                t.optional_rotations()?,
                &selection,
                "ground_truth",
            )?),
            None => own_truth,
        };
        Ok(MultipleInput {
            name,
            graph,
            selection,
            truth,
            init: None,
        })
    }
}

/// Per-node values given for every node of the graph as given (restricted to the kept ones) or
/// for the kept nodes only; another count is an error naming the keyword `what`.
pub(crate) fn for_kept<T: Clone>(
    values: Vec<T>,
    selection: &ComponentSelection,
    what: &str,
) -> rotavg::Result<Vec<T>> {
    let kept = selection.kept.len();
    if values.len() == kept {
        return Ok(values);
    }
    selection
        .select(&values)
        .ok_or_else(|| rotavg::Error::InvalidSettings {
            name: what.into(),
            reason: format!("{} rotations given for {kept} nodes", values.len()),
        })
}

/// Rotations of an optional estimate or initial value.
fn optional_matrices(obj: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<Option<Matrices>> {
    obj.filter(|o| !o.is_none())
        .map(|o| matrices(o, what))
        .transpose()
}

/// Single rotation averaging: the L^p mean ``argmin_R sum_k w_k d(R_k, R)^p`` of
/// ``rotations`` and its certificate (closed forms and convexity theorems).
///
/// Args:
///     rotations: ``(N, 3, 3)`` array-like of rotation matrices, or a
///         ``scipy.spatial.transform.Rotation`` (anything with ``as_matrix()``).
///     weights: ``(N,)`` positive weights (default all 1).
///     metric: ``"chordal"``, ``"quaternion"`` or ``"geodesic"`` (the angle).
///     p: 1 or 2 (quaternion only with 2).
///     rotation_tolerance: the tolerance on ``||R^T R - I||_F`` and ``|det R - 1|`` of every
///         sample (default 1e-5); the samples are used as given, and the certificate subtracts
///         their defect.
///     max_seconds: the run's time budget, seconds (default 600; ``None``: no limit), one
///         clock for the iterative mean (which stops at it: termination ``"time_limit"``, its
///         last iterate) and the certificate, as ``rotavg single --max-seconds``.
///
/// Returns:
///     Result: ``estimate`` is the ``(3, 3)`` mean; ``to_dict()`` equals
///     ``rotavg single FILE --json``.
///
/// Raises:
///     rotavg.Error: bad shapes, NaN, a matrix that is not a rotation (``rotation_tolerance``),
///         a weight that is not positive, an unknown metric or p.
#[pyfunction]
#[pyo3(name = "average_single", signature = (rotations, weights=None, metric="chordal", p=2, *, rotation_tolerance=1e-5, max_seconds=600.0))]
fn average_single_py(
    py: Python<'_>,
    rotations: &Bound<'_, PyAny>,
    weights: Option<&Bound<'_, PyAny>>,
    metric: &str,
    p: i64,
    rotation_tolerance: f64,
    max_seconds: Option<f64>,
) -> PyResult<RunResult> {
    let certify = certify_settings(CertifyMode::Auto, None, max_seconds, true, None)?;
    let tolerance = convert::rotation_tolerance(rotation_tolerance)?;
    let rotations = matrices(rotations, "rotations")?.within(tolerance);
    let weights = optional_vector(weights, rotations.len())?;
    let metric: Metric = parse_named(metric, "metric")?;
    let loss = match p {
        1 => Loss::L1,
        2 => Loss::L2,
        _ => return Err(argument_error(format!("p must be 1 or 2, got {p}"))),
    };
    let report = detached(py, move || {
        let problem = SingleProblem::new_within(rotations.rotations()?, weights, tolerance)?
            .with_objective(Objective::new(metric, loss))?;
        let settings = AverageSettings {
            solve: SingleSettings {
                max_seconds,
                ..Default::default()
            },
            certify,
        };
        let result = average_single(&problem, &settings)?;
        Ok(SingleReport::new(result))
    })?;
    RunResult::new(py, Report::Single(report))
}

/// `weights` as a vector of `len` entries, or None.
fn optional_vector(weights: Option<&Bound<'_, PyAny>>, len: usize) -> PyResult<Option<Vec<f64>>> {
    weights
        .filter(|w| !w.is_none())
        .map(|w| vector(w, "weights", len))
        .transpose()
}

/// Multiple rotation averaging on a view graph, with a certificate of global optimality (or a
/// proven bound on the gap) for the chordal L2 cost
/// ``sum_k w_k ||R_j - rel[k] R_i||_F^2`` over edges ``(i, j) = (i[k], j[k])``.
///
/// Args:
///     n: number of rotations, or a ``Graph`` from ``read_graph`` (then leave out i, j, rel,
///         weights; the result is then exactly the command line's for that file).
///     i, j: ``(M,)`` integer arrays of node indices in ``0..n``.
///     rel: ``(M, 3, 3)`` relative rotations with ``rel[k] @ R_i = R_j``.
///     weights: ``(M,)`` positive edge weights (default all 1).
///     loss: ``"auto"`` (default, as the command line: ``"chordal"`` unless the least-squares
///         residuals show outliers, then ``"cauchy"``; ``to_dict()["pipeline"]["loss_choice"]``
///         says which and why), ``"chordal"`` (L2, certified), ``"geodesic"`` (L2), ``"l1"``,
///         ``"huber"``, ``"cauchy"`` (the last four on the residual angle; no certificate of
///         their cost: for ``"l1"``, ``"huber"`` and ``"cauchy"``, ``to_dict()["robust"]`` has
///         the inlier counts and residual quantiles, and unless ``certify="none"`` the
///         certificate of the chordal L2 problem on the inlier graph,
///         ``["robust"]["inlier_graph"]["certificate"]``). ``result.verdict`` and
///         ``to_dict()["verdict"]`` name the problem certified.
///     certify: ``"auto"``, ``"dual"``, ``"sdp"``, ``"staircase"`` or ``"none"``.
///     loss_threshold: Huber threshold / Cauchy scale in degrees (default 5), and the
///         inlier threshold (an edge is an inlier iff its residual is at most this many
///         degrees); given, also ``"auto"``'s Cauchy scale and inlier threshold, which are
///         otherwise from the data (1.5 and 3 times the median residual at the L1 solution,
///         ``[D20]``; ``to_dict()["pipeline"]["loss_choice"]["scale"]``).
///     init: optional ``(n, 3, 3)`` initial estimate (default: spectral initialisation).
///     max_memory: the certificate's memory budget per factorisation, bytes (default 4 GiB).
///     max_seconds: the run's time budget, seconds (default 600; ``None``: no limit), one
///         clock for the local solve (which stops at it: termination ``"time_limit"``, its
///         last iterate) and the certificate (what the solve left). A proof that does not
///         fit is not started: the verdict is ``"inconclusive"`` with the reason.
///     randomized: run the randomized Chebyshev test [D16] when no proof fits (default
///         True): a Monte Carlo lower bound in ``to_dict()["certificate"]["randomized"]``,
///         beside the verdict and never as its proof.
///     randomized_seed: its seed (default: a fresh one, reported).
///     largest_component: solve only the largest connected component of a disconnected graph
///         (``result.node_ids`` says which nodes; ``to_dict()["other_components"]`` the sizes
///         of the others). Default False: a disconnected graph raises
///         ``rotavg.DisconnectedError``.
///     ground_truth: optional ``(n, 3, 3)`` ground truth (NaN matrices where unknown): then
///         ``result.accuracy`` (and ``to_dict()["accuracy"]``) reports the estimate's errors
///         after the optimal alignment. Default: the ground truth the ``Graph`` was read with.
///     information: optional ``(M, 3, 3)`` symmetric positive semidefinite information
///         matrices ``H`` (instead of ``weights``) for the residual ``e`` of
///         ``R_j R_i^T = rel[k] expm([e]x)``: the anisotropic chordal cost (certified) for
///         ``loss="chordal"``, ``sum e^T H e`` for ``"geodesic"``, and the robust losses of the
///         Mahalanobis angle ``sqrt(e^T H e / (tr H / 3))`` (contract section 1;
///         ``to_dict()["information"]`` summarises them).
///     rotation_tolerance: the tolerance on ``||R^T R - I||_F`` and ``|det R - 1|`` of every
///         matrix given as a rotation (``rel``, ``init``) (default 1e-5, the command line's); beyond it, an error.
///     gravity: optional gravity priors held as hard constraints, ``R_i world_down = g[i]``
///         (``g[i]`` the world's down direction in camera ``i``'s frame): an ``(n, 3)`` array
///         (a row of NaN: no prior for that image), ``(n, 4)`` with each prior's relative
///         weight fourth (soft priors weigh ``gravity_weight`` times it; NaN: 1), or the path
///         of a priors file as ``rotavg multiple --gravity`` reads it (JSON, ``KEY gx gy gz
///         [relative weight]`` lines, a COLMAP database). Least squares only (``loss`` ``"auto"`` or ``"chordal"``); every image
///         with a prior: the SO(2) certificate; some: the tilted soft surrogate's [G12].
///         ``to_dict()["pipeline"]["gravity"]`` has the priors' check.
///     world_down: the world's down direction the priors refer to (default ``(0, 0, 1)``,
///         the file's, or COLMAP's ``(0, 1, 0)``).
///     gravity_weight: the priors as soft terms of this weight instead of constraints
///         (``rotavg multiple --gravity-weight``): each adds ``2 w ||R_i world_down - g_i||^2``
///         to the chordal cost, like an edge of weight ``w`` for a tilt error; certified with
///         the view graph (every image with a prior or some).
///     init_method: the local solver's start without ``init``: ``"spectral"`` (default) or
///         ``"tree"`` (the maximum-weight spanning tree), as ``--init-method``.
///     inlier_threshold: robust losses: an edge is an inlier iff its residual angle at the
///         robust estimate is at most this many degrees (default ``loss_threshold``; for
///         ``"auto"`` without it, from the data as above), as
///         ``--inlier-threshold``; the inlier graph is refined and certified.
///
/// Returns:
///     Result: ``estimate`` is ``(n, 3, 3)`` with the gauge ``estimate[0] = I`` (with
///     ``gravity``: ``estimate[0]`` the rotation nearest to ``I`` that keeps its prior);
///     ``to_dict()`` equals ``rotavg multiple FILE --json``.
///
/// Raises:
///     rotavg.Error: bad shapes, NaN, non-rotations, indices out of range, self loops,
///         bad weights, unknown names. rotavg.DisconnectedError: a disconnected graph.
#[pyfunction]
#[pyo3(name = "average_multiple", signature = (n, i=None, j=None, rel=None, weights=None, loss="auto", certify="auto", *, loss_threshold=None, init=None, max_memory=None, max_seconds=600.0, randomized=true, randomized_seed=None, largest_component=false, ground_truth=None, information=None, rotation_tolerance=1e-5, gravity=None, world_down=None, init_method="spectral", inlier_threshold=None, gravity_weight=None))]
#[allow(clippy::too_many_arguments)]
fn average_multiple_py(
    py: Python<'_>,
    n: &Bound<'_, PyAny>,
    i: Option<&Bound<'_, PyAny>>,
    j: Option<&Bound<'_, PyAny>>,
    rel: Option<&Bound<'_, PyAny>>,
    weights: Option<&Bound<'_, PyAny>>,
    loss: &str,
    certify: &str,
    loss_threshold: Option<f64>,
    init: Option<&Bound<'_, PyAny>>,
    max_memory: Option<u64>,
    max_seconds: Option<f64>,
    randomized: bool,
    randomized_seed: Option<u64>,
    largest_component: bool,
    ground_truth: Option<&Bound<'_, PyAny>>,
    information: Option<&Bound<'_, PyAny>>,
    rotation_tolerance: f64,
    gravity: Option<&Bound<'_, PyAny>>,
    world_down: Option<[f64; 3]>,
    init_method: &str,
    inlier_threshold: Option<f64>,
    gravity_weight: Option<f64>,
) -> PyResult<RunResult> {
    let tolerance = convert::rotation_tolerance(rotation_tolerance)?;
    let init_method: Initialisation = parse_named(init_method, "init_method")?;
    let gravity = gravity::GravityInput::from_py(gravity)?;
    if gravity.is_some() && loss == "geodesic" {
        return Err(argument_error(
            "gravity priors are solved with the chordal L2 loss or a robust loss (l1, huber, \
             cauchy), not loss=\"geodesic\"",
        ));
    }
    let budget = certify_settings(
        CertifyMode::Auto,
        max_memory,
        max_seconds,
        randomized,
        randomized_seed,
    )?;
    let graph = GraphInput::copy(n, i, j, rel, weights, information)?.within(tolerance);
    let loss = parse_named::<MultipleLoss>(loss, "loss")?;
    if inlier_threshold.is_some() && matches!(loss, MultipleLoss::Chordal | MultipleLoss::Geodesic)
    {
        return Err(argument_error(format!(
            "inlier_threshold needs a robust loss (\"l1\", \"huber\", \"cauchy\" or \"auto\"), not \"{loss}\""
        )));
    }
    let (loss_threshold, robust_scale) = ScaleRule::of(loss_threshold);
    let objective = loss.objective(loss_threshold);
    let mode: CertifyMode = parse_named(certify, "certify")?;
    let init = optional_matrices(init, "init")?.map(|m| m.within(tolerance));
    let truth = optional_matrices(ground_truth, "ground_truth")?;
    let report = detached(py, move || {
        let input = graph.into_input(largest_component, truth)?;
        let problem = input.graph.problem.clone().with_objective(objective)?;
        let init = match init {
            Some(m) => Initialisation::Given(for_kept(m.rotations()?, &input.selection, "init")?),
            None => init_method,
        };
        let settings = AverageSettings {
            solve: MultipleSettings {
                init,
                // as the command line: --inlier-threshold, else for L1 --loss-threshold
                inlier_threshold_deg: loss.inlier_threshold_deg(loss_threshold, inlier_threshold),
                robust_on_outliers: loss.robust_on_outliers(loss_threshold),
                robust_scale,
                // one clock for the solve and the certificate, as the command line
                max_seconds: budget.budget.max_seconds,
                ..Default::default()
            },
            certify: CertifySettings { mode, ..budget },
        };
        let (result, warnings) = match gravity {
            Some(g) => {
                let (p, w) =
                    g.problem(&input.graph, &input.selection, world_down, gravity_weight)?;
                (rotavg::pipeline::average_with_gravity(&p, &settings)?, w)
            }
            None => (average_multiple(&problem, &settings)?, Vec::new()),
        };
        let mut report = MultipleReport::new(&input, result)?;
        report.run_warnings.extend(warnings);
        Ok(report)
    })?;
    RunResult::new(py, Report::Multiple(report))
}

/// Certify an estimate of a view graph computed elsewhere (any solver), **without changing
/// it**: its chordal L2 cost and either a certificate of global optimality or a proven bound on
/// its gap.
///
/// Args:
///     n, i, j, rel, weights: the view graph as for ``average_multiple`` (or a ``Graph`` as n).
///     information: optional ``(M, 3, 3)`` information matrices, as for ``average_multiple``.
///     estimate: ``(n, 3, 3)`` rotations ``R_i`` (any gauge), or the path (``str`` or
///         ``os.PathLike``) of another tool's estimate in any format ``rotavg certify
///         --estimate`` reads: JSON, g2o vertices (GTSAM), a COLMAP sparse model folder
///         (GLOMAP, pycolmap), ``images.bin`` / ``images.txt``, Bundler ``.out``, a rotation
///         list; matched to the nodes by id, or by image name for a graph read from a COLMAP
///         database.
///     certify: ``"auto"`` (dual certificate, then the SDP or the staircase), ``"dual"``,
///         ``"sdp"`` or ``"staircase"`` (``"none"`` means ``"dual"``, as on the command line).
///     max_memory, max_seconds, randomized, randomized_seed, rotation_tolerance: as for
///         ``average_multiple`` (the tolerance also applies to an estimate read from a path).
///     loss: ``"chordal"`` (default: the chordal L2 problem on all edges), or ``"l1"``,
///         ``"huber"``, ``"cauchy"``: also judge the estimate, unchanged, on the chordal L2
///         problem of its own inlier graph (the edges whose residual at the estimate is at
///         most the inlier threshold, their largest connected component); the verdict
///         (``to_dict()["verdict"]``) is then that problem's, and ``to_dict()["inlier_graph"]``
///         states the inlier set and its certificate. The time budget is shared (half for all
///         edges).
///     loss_threshold: the inlier threshold in degrees unless ``inlier_threshold`` is given.
///     inlier_threshold: the inlier threshold in degrees.
///     gravity, world_down, gravity_weight: gravity priors as for ``average_multiple``: the
///         estimate is then certified for the chordal L2 problem with the priors held (it must
///         satisfy them to 1e-6 rad) or, with ``gravity_weight``, with the priors' soft terms;
///         not with ``loss``.
///     nearest_rotations: certify the nearest rotations of an estimate whose matrices are
///         rotations only approximately (beyond ``rotation_tolerance``) or all reflections
///         (det -1, as a relaxation's rounding may return: negated first, the chordal cost
///         unchanged), with the warning ``estimate_projected``; ``rotavg certify
///         --nearest-rotations``. Without it such an estimate raises ``rotavg.Error``.
///
/// Returns:
///     Result: ``solver`` is None; ``to_dict()`` equals
///     ``rotavg certify FILE --estimate EST --json`` (with the same ``--loss``). A graph read
///     from a COLMAP database by ``read_graph`` with ``information="auto"`` carries its pairs'
///     information where ``rotavg certify`` reads weights 1 (certifying the least-squares
///     problem of every pair with their information is slow and rarely tight): read it with
///     ``information="kappa"`` for the command line's problem.
///
/// Raises:
///     rotavg.Error: as ``average_multiple``, an estimate of the wrong size, and (a path) a node
///         the file lacks or a file that cannot be read (``rotavg.ParseError``, naming the file).
#[pyfunction]
#[pyo3(name = "certify_multiple", signature = (n, i=None, j=None, rel=None, estimate=None, weights=None, *, certify="auto", max_memory=None, max_seconds=600.0, randomized=true, randomized_seed=None, information=None, loss="chordal", loss_threshold=5.0, inlier_threshold=None, rotation_tolerance=1e-5, gravity=None, world_down=None, nearest_rotations=false, gravity_weight=None))]
#[allow(clippy::too_many_arguments)]
fn certify_multiple_py(
    py: Python<'_>,
    n: &Bound<'_, PyAny>,
    i: Option<&Bound<'_, PyAny>>,
    j: Option<&Bound<'_, PyAny>>,
    rel: Option<&Bound<'_, PyAny>>,
    estimate: Option<&Bound<'_, PyAny>>,
    weights: Option<&Bound<'_, PyAny>>,
    certify: &str,
    max_memory: Option<u64>,
    max_seconds: Option<f64>,
    randomized: bool,
    randomized_seed: Option<u64>,
    information: Option<&Bound<'_, PyAny>>,
    loss: &str,
    loss_threshold: f64,
    inlier_threshold: Option<f64>,
    rotation_tolerance: f64,
    gravity: Option<&Bound<'_, PyAny>>,
    world_down: Option<[f64; 3]>,
    nearest_rotations: bool,
    gravity_weight: Option<f64>,
) -> PyResult<RunResult> {
    let tolerance = convert::rotation_tolerance(rotation_tolerance)?;
    let graph = GraphInput::copy(n, i, j, rel, weights, information)?.within(tolerance);
    // the estimate's matrices are checked by `project_estimate` with nearest_rotations
    let estimate_tolerance = if nearest_rotations {
        f64::INFINITY
    } else {
        tolerance
    };
    let gravity = gravity::GravityInput::from_py(gravity)?;
    let loss: MultipleLoss = parse_named(loss, "loss")?;
    let threshold = loss
        .certify_inlier_threshold_deg(loss_threshold, inlier_threshold)
        .map_err(error)?;
    // a path (str or os.PathLike) is read as `rotavg certify --estimate PATH` reads it
    let path = estimate.filter(|e| !e.is_none()).and_then(convert::path_of);
    let estimate = match path {
        Some(p) => EstimateInput::Path(p),
        None => EstimateInput::Arrays(
            optional_matrices(estimate, "estimate")?
                .ok_or_else(|| argument_error("certify_multiple needs an estimate"))?
                .within(estimate_tolerance),
        ),
    };
    let mode = match parse_named(certify, "certify")? {
        CertifyMode::None => CertifyMode::Dual,
        m => m,
    };
    let settings = certify_settings(mode, max_memory, max_seconds, randomized, randomized_seed)?;
    let report = detached(py, move || {
        let input = graph.into_input(false, None)?;
        let read = || -> rotavg::Result<LoadedEstimate> {
            Ok(match estimate {
                EstimateInput::Arrays(m) => LoadedEstimate {
                    name: "estimate".into(),
                    estimate: Estimate::Multiple(m.rotations()?),
                    warnings: Vec::new(),
                },
                EstimateInput::Path(p) => {
                    let options = ReadOptions {
                        rotation_tolerance: estimate_tolerance,
                        ..Default::default()
                    };
                    load_estimate_for(&p, &input.graph, &options)?.into_loaded()
                }
            })
        };
        let estimate = match nearest_rotations {
            true => read()?.into_nearest_rotations()?,
            false => read().map_err(rotavg::io::nearest::with_nearest_hint)?,
        };
        if let Some(g) = gravity {
            if threshold.is_some() {
                return Err(rotavg::Error::InvalidSettings {
                    name: "gravity".into(),
                    reason: "gravity priors are certified on all edges, not with loss".into(),
                });
            }
            let (p, warnings) =
                g.problem(&input.graph, &input.selection, world_down, gravity_weight)?;
            let priors = p.priors().clone();
            let mut r = CertifyReport::certify_with_gravity(
                &input.name,
                &input.graph,
                estimate,
                priors,
                &settings,
            )?;
            r.warnings.extend(warnings);
            return Ok(r);
        }
        let problem = LoadedProblem::Multiple(input.graph);
        match threshold {
            None => CertifyReport::certify(&input.name, &problem, estimate, &settings),
            Some(t) => CertifyReport::certify_on_inliers(
                &input.name,
                &problem,
                estimate,
                &loss.to_string(),
                t,
                &settings,
            ),
        }
    })?;
    RunResult::new(py, Report::Certify(report))
}

/// An estimate given as arrays or as a file path.
enum EstimateInput {
    Arrays(Matrices),
    Path(String),
}

/// Certification settings with the budget (`max_memory` bytes, default 4 GiB; `max_seconds`,
/// `None`: no limit) and the randomized test `[D16]` (`randomized`, `randomized_seed`),
/// validated.
pub(crate) fn certify_settings(
    mode: CertifyMode,
    max_memory: Option<u64>,
    max_seconds: Option<f64>,
    randomized: bool,
    randomized_seed: Option<u64>,
) -> PyResult<CertifySettings> {
    let mut s = CertifySettings::with_mode(mode);
    if let Some(m) = max_memory {
        s.budget.max_memory_bytes = m;
    }
    s.budget.max_seconds = max_seconds;
    s.dual.randomized.enabled = randomized;
    s.dual.randomized.seed = randomized_seed;
    s.validate().map_err(error)?;
    Ok(s)
}

/// Pairs `(left[k], right[k], weights[k])` copied out of Python.
struct PairArrays {
    left: Matrices,
    right: Matrices,
    weights: Option<Vec<f64>>,
}

impl PairArrays {
    fn copy(
        left: &Bound<'_, PyAny>,
        right: &Bound<'_, PyAny>,
        weights: Option<&Bound<'_, PyAny>>,
        tolerance: f64,
    ) -> PyResult<Self> {
        let (left, right) = (
            matrices(left, "left")?.within(tolerance),
            matrices(right, "right")?.within(tolerance),
        );
        if left.len() != right.len() {
            return Err(argument_error(format!(
                "left and right must have one rotation per pair: got {} and {}",
                left.len(),
                right.len()
            )));
        }
        let weights = optional_vector(weights, left.len())?;
        Ok(PairArrays {
            left,
            right,
            weights,
        })
    }

    /// The validated conjugate problem (chordal L2 objective).
    fn problem(self) -> rotavg::Result<ConjugateProblem> {
        let (left, right) = (self.left.rotations()?, self.right.rotations()?);
        let pairs = left
            .into_iter()
            .zip(right)
            .enumerate()
            .map(|(k, (left, right))| ConjugatePair {
                left,
                right,
                weight: self.weights.as_ref().map_or(1.0, |w| w[k]),
            })
            .collect();
        ConjugateProblem::new(pairs)
    }
}

/// Conjugate pairs given as arrays or as `HandEyeData`.
enum PairsInput {
    Arrays(PairArrays),
    /// The problem, the report's source line, the motion counts and settings, the path.
    Data(
        ConjugateProblem,
        String,
        Option<(
            rotavg::io::handeye::MotionStats,
            rotavg::io::handeye::MotionSettings,
        )>,
        String,
    ),
}

impl PairsInput {
    /// The pairs of `left` (a `HandEyeData`, checked by its reader) or of the arrays `left`,
    /// `right`, whose matrices must be rotations within `tolerance`.
    fn copy(
        left: &Bound<'_, PyAny>,
        right: Option<&Bound<'_, PyAny>>,
        weights: Option<&Bound<'_, PyAny>>,
        tolerance: f64,
    ) -> PyResult<Self> {
        if let Ok(d) = left.cast::<HandEyeData>() {
            if right.is_some_and(|r| !r.is_none()) || weights.is_some_and(|w| !w.is_none()) {
                return Err(argument_error(
                    "pass either HandEyeData or left, right (and weights), not both",
                ));
            }
            let d = d.get();
            return Ok(PairsInput::Data(
                d.problem.clone(),
                d.source.clone(),
                d.motion.clone(),
                d.name.clone(),
            ));
        }
        match right.filter(|r| !r.is_none()) {
            Some(right) => Ok(PairsInput::Arrays(PairArrays::copy(
                left, right, weights, tolerance,
            )?)),
            None => Err(argument_error(
                "conjugate averaging needs left and right (or HandEyeData from hand_eye_pairs or read_handeye)",
            )),
        }
    }

    /// The validated problem, the name of the input and how the report names its source.
    fn into_parts(self) -> rotavg::Result<ConjugateParts> {
        Ok(match self {
            PairsInput::Arrays(a) => ConjugateParts {
                problem: a.problem()?,
                name: "<arrays>".into(),
                source: "<arrays>: conjugate pairs".into(),
                motion: None,
            },
            PairsInput::Data(problem, source, motion, name) => ConjugateParts {
                problem,
                name,
                source,
                motion,
            },
        })
    }
}

/// A conjugate problem with what its report says about the input.
struct ConjugateParts {
    problem: ConjugateProblem,
    name: String,
    source: String,
    motion: Option<(
        rotavg::io::handeye::MotionStats,
        rotavg::io::handeye::MotionSettings,
    )>,
}

/// Conjugate (hand-eye) rotation averaging: ``S`` with ``right[k] ~ S^-1 left[k] S``, minimising
/// ``sum_k w_k ||S right[k] - left[k] S||_F^2`` (chordal L2, certified by a 10x10 SDP), or a
/// geodesic / robust cost, certified by branch and bound over SO(3).
///
/// Args:
///     left, right: ``(N, 3, 3)`` rotations ``L_k`` and ``R_k`` (or scipy Rotations); or
///         ``left`` a ``HandEyeData`` (``hand_eye_pairs``, ``read_handeye``) and no ``right``:
///         then ``to_dict()`` is exactly the command line's for those files.
///     weights: ``(N,)`` positive weights (default all 1).
///     metric: ``"chordal"``, ``"geodesic"`` or ``"quaternion"``.
///     loss: ``"l2"``, ``"l1"``, ``"huber"`` or ``"cauchy"``.
///     certify: ``"auto"``, ``"sdp"``, ``"branch_and_bound"`` or ``"none"``.
///     loss_threshold: Huber threshold / Cauchy scale in degrees.
///     init: optional ``(3, 3)`` start of the local solver (default: the quaternion closed
///         form).
///     max_memory, max_seconds: the run's budget (bytes, default 4 GiB; seconds, default 600,
///         ``None``: no limit), as for ``average_multiple``: one clock for the local solve and
///         the certificate.
///     rotation_tolerance: the tolerance on ``||R^T R - I||_F`` and ``|det R - 1|`` of every
///         matrix of ``left`` and ``right`` (default 1e-5); beyond it, an error.
///
/// Returns:
///     Result: ``estimate`` is ``S`` (3, 3); ``to_dict()`` equals
///     ``rotavg conjugate FILE --json``.
///
/// Raises:
///     rotavg.Error: bad shapes, NaN, non-rotations, bad weights, unknown names.
///     rotavg.DegenerateError: data that do not determine S (all rotation axes parallel).
#[pyfunction]
#[pyo3(name = "average_conjugate", signature = (left, right=None, weights=None, *, metric="chordal", loss="l2", certify="auto", loss_threshold=5.0, init=None, max_memory=None, max_seconds=600.0, rotation_tolerance=1e-5))]
#[allow(clippy::too_many_arguments)]
fn average_conjugate_py(
    py: Python<'_>,
    left: &Bound<'_, PyAny>,
    right: Option<&Bound<'_, PyAny>>,
    weights: Option<&Bound<'_, PyAny>>,
    metric: &str,
    loss: &str,
    certify: &str,
    loss_threshold: f64,
    init: Option<&Bound<'_, PyAny>>,
    max_memory: Option<u64>,
    max_seconds: Option<f64>,
    rotation_tolerance: f64,
) -> PyResult<RunResult> {
    let tolerance = convert::rotation_tolerance(rotation_tolerance)?;
    let pairs = PairsInput::copy(left, right, weights, tolerance)?;
    conjugate_run(
        py,
        pairs,
        ConjugateOptions {
            metric,
            loss,
            certify,
            loss_threshold,
            init,
            max_memory,
            max_seconds,
        },
    )
}

/// The keyword arguments of `average_conjugate` and `hand_eye`.
struct ConjugateOptions<'a, 'py> {
    metric: &'a str,
    loss: &'a str,
    certify: &'a str,
    loss_threshold: f64,
    init: Option<&'a Bound<'py, PyAny>>,
    max_memory: Option<u64>,
    max_seconds: Option<f64>,
}

/// Solve and certify conjugate pairs as `rotavg conjugate` does.
fn conjugate_run(
    py: Python<'_>,
    pairs: PairsInput,
    o: ConjugateOptions<'_, '_>,
) -> PyResult<RunResult> {
    let objective = Objective::new(
        parse_named(o.metric, "metric")?,
        parse_named::<LossKind>(o.loss, "loss")?.with_threshold_deg(o.loss_threshold),
    );
    let mode: CertifyMode = parse_named(o.certify, "certify")?;
    let mut certify = CertifySettings::with_mode(mode);
    if let Some(m) = o.max_memory {
        certify.budget.max_memory_bytes = m;
    }
    certify.budget.max_seconds = o.max_seconds;
    certify.validate().map_err(error)?;
    let init = o
        .init
        .filter(|i| !i.is_none())
        .map(|i| matrix(i, "init"))
        .transpose()?;
    let report =
        detached(py, move || {
            let parts = pairs.into_parts()?;
            let problem = parts.problem.with_objective(objective)?;
            let settings = AverageSettings {
                solve: ConjugateSettings {
                    init: init.map(|m| m.rotation()).transpose()?,
                    max_seconds: certify.budget.max_seconds,
                    ..Default::default()
                },
                certify,
            };
            let result = average_conjugate(&problem, &settings)?;
            let (stats, motion_settings) = match parts.motion {
                Some((s, m)) => (Some(s), m),
                None => (None, Default::default()),
            };
            Ok(ConjugateReport::new(&problem, parts.source, result)
                .with_motion(stats, motion_settings))
        })?;
    RunResult::new(py, Report::Conjugate(report))
}

/// Hand-eye calibration (rotation) from absolute poses in one call:
/// ``average_conjugate(hand_eye_pairs(robot_poses, camera_poses, ...), ...)``.
///
/// The pairs are formed as OpenCV's ``calibrateHandEye`` forms them (see ``hand_eye_pairs``):
/// ``robot_poses`` are base-from-gripper (``R_gripper2base``), ``camera_poses``
/// camera-from-target (``R_target2cam``; ``camera="cam2target"`` for target-from-camera), and
/// the estimate is ``S = R_cam2gripper`` with ``right[k] ~ S^-1 left[k] S``: the rotation that
/// OpenCV returns, certified globally optimal for the chordal cost (or with a proven gap).
///
/// Args:
///     robot_poses, camera_poses, camera, pairs, min_angle: as for ``hand_eye_pairs``.
///     metric, loss, certify, loss_threshold, init, max_memory, max_seconds: as for
///         ``average_conjugate``.
///
/// Returns:
///     Result: ``estimate`` is ``R_cam2gripper`` (3, 3); ``to_dict()["motion"]`` counts the
///     poses and pairs.
///
/// Raises:
///     rotavg.Error: as ``hand_eye_pairs`` and ``average_conjugate``.
///     rotavg.DegenerateError: motions that do not determine the rotation.
#[pyfunction]
#[pyo3(signature = (robot_poses, camera_poses, *, camera="target2cam", pairs="all", min_angle=None, metric="chordal", loss="l2", certify="auto", loss_threshold=5.0, init=None, max_memory=None, max_seconds=600.0))]
#[allow(clippy::too_many_arguments)]
fn hand_eye(
    py: Python<'_>,
    robot_poses: &Bound<'_, PyAny>,
    camera_poses: &Bound<'_, PyAny>,
    camera: &str,
    pairs: &str,
    min_angle: Option<f64>,
    metric: &str,
    loss: &str,
    certify: &str,
    loss_threshold: f64,
    init: Option<&Bound<'_, PyAny>>,
    max_memory: Option<u64>,
    max_seconds: Option<f64>,
) -> PyResult<RunResult> {
    let data = handeye::hand_eye_pairs(py, robot_poses, camera_poses, camera, pairs, min_angle)?;
    let pairs = PairsInput::Data(data.problem, data.source, data.motion, data.name);
    conjugate_run(
        py,
        pairs,
        ConjugateOptions {
            metric,
            loss,
            certify,
            loss_threshold,
            init,
            max_memory,
            max_seconds,
        },
    )
}

/// Certify a hand-eye rotation ``S`` computed elsewhere (e.g. OpenCV's ``calibrateHandEye``),
/// **without changing it**: its chordal L2 cost and a certificate or a proven gap bound.
///
/// Args:
///     left, right, weights: the pairs, as for ``average_conjugate`` (or ``left`` a
///         ``HandEyeData`` and ``estimate`` by keyword).
///     estimate: the ``(3, 3)`` rotation ``S`` (or a single scipy Rotation); for
///         ``hand_eye_pairs`` data, OpenCV's ``R_cam2gripper``; or a path, read as ``rotavg
///         certify --estimate`` reads it (JSON ``{"rotation": S}``, a NumPy ``(3, 3)`` array).
///     rotation_tolerance: as for ``average_conjugate`` (the pairs' matrices).
///     max_memory, max_seconds: the certificate's budget, as for ``average_conjugate``.
///
/// Returns:
///     Result: ``solver`` is None; ``to_dict()`` equals
///     ``rotavg certify FILE --estimate EST --json``.
///
/// Raises:
///     rotavg.Error: as ``average_conjugate``; rotavg.ParseError: an estimate file that
///         cannot be read (naming it).
#[pyfunction]
#[pyo3(name = "certify_conjugate", signature = (left, right=None, estimate=None, weights=None, *, rotation_tolerance=1e-5, max_memory=None, max_seconds=600.0))]
#[allow(clippy::too_many_arguments)]
fn certify_conjugate_py(
    py: Python<'_>,
    left: &Bound<'_, PyAny>,
    right: Option<&Bound<'_, PyAny>>,
    estimate: Option<&Bound<'_, PyAny>>,
    weights: Option<&Bound<'_, PyAny>>,
    rotation_tolerance: f64,
    max_memory: Option<u64>,
    max_seconds: Option<f64>,
) -> PyResult<RunResult> {
    let tolerance = convert::rotation_tolerance(rotation_tolerance)?;
    let pairs = PairsInput::copy(left, right, weights, tolerance)?;
    let estimate = OneEstimate::of(
        estimate
            .filter(|e| !e.is_none())
            .ok_or_else(|| argument_error("certify_conjugate needs an estimate"))?,
    )?;
    let settings = certify_settings(CertifyMode::Auto, max_memory, max_seconds, true, None)?;
    let report = detached(py, move || {
        let parts = pairs.into_parts()?;
        let problem = LoadedProblem::Conjugate(parts.problem);
        CertifyReport::certify(&parts.name, &problem, estimate.load()?, &settings)
    })?;
    RunResult::new(py, Report::Certify(report))
}

/// The estimate of a single or conjugate problem: a `(3, 3)` array, or a path.
enum OneEstimate {
    Matrix(Matrices),
    Path(String),
}

impl OneEstimate {
    /// A path (str or os.PathLike) or an array.
    fn of(estimate: &Bound<'_, PyAny>) -> PyResult<Self> {
        Ok(match convert::path_of(estimate) {
            Some(p) => OneEstimate::Path(p),
            None => OneEstimate::Matrix(matrix(estimate, "estimate")?),
        })
    }

    /// The estimate as `rotavg certify --estimate` takes it.
    fn load(self) -> rotavg::Result<LoadedEstimate> {
        match self {
            OneEstimate::Matrix(m) => Ok(LoadedEstimate {
                name: "estimate".into(),
                estimate: Estimate::Single(m.rotation()?),
                warnings: Vec::new(),
            }),
            OneEstimate::Path(p) => rotavg::io::input::load_estimate(&p, &ReadOptions::default()),
        }
    }
}

/// Certify a single-rotation chordal L2 mean computed elsewhere, **without changing it**.
///
/// Args:
///     rotations, weights, rotation_tolerance: the samples, as for ``average_single``.
///     estimate: the ``(3, 3)`` rotation to certify, or a path (as for ``certify_conjugate``).
///     max_memory, max_seconds: the certificate's budget, as for ``average_multiple``.
///
/// Returns:
///     Result: ``solver`` is None; ``to_dict()`` equals
///     ``rotavg certify FILE --estimate EST --json``.
///
/// Raises:
///     rotavg.Error: as ``average_single``.
#[pyfunction]
#[pyo3(name = "certify_single", signature = (rotations, estimate, weights=None, *, rotation_tolerance=1e-5, max_memory=None, max_seconds=600.0))]
fn certify_single_py(
    py: Python<'_>,
    rotations: &Bound<'_, PyAny>,
    estimate: &Bound<'_, PyAny>,
    weights: Option<&Bound<'_, PyAny>>,
    rotation_tolerance: f64,
    max_memory: Option<u64>,
    max_seconds: Option<f64>,
) -> PyResult<RunResult> {
    let tolerance = convert::rotation_tolerance(rotation_tolerance)?;
    let rotations = matrices(rotations, "rotations")?.within(tolerance);
    let weights = optional_vector(weights, rotations.len())?;
    let estimate = OneEstimate::of(estimate)?;
    let settings = certify_settings(CertifyMode::Auto, max_memory, max_seconds, true, None)?;
    let report = detached(py, move || {
        let samples = SingleProblem::new_within(rotations.rotations()?, weights, tolerance)?;
        let problem = LoadedProblem::Single(samples);
        CertifyReport::certify("<arrays>", &problem, estimate.load()?, &settings)
    })?;
    RunResult::new(py, Report::Certify(report))
}

/// `information=`: the command line's `--information` ([`rotavg::io::detect::information_choice`]).
pub(crate) fn full_information(information: &str) -> PyResult<Option<bool>> {
    rotavg::io::detect::information_choice(information).map_err(|e| argument_error(e.to_string()))
}

/// Read a view graph with the library's readers (the command line's): g2o / TORO, 1DSfM
/// ``EGs.txt`` or the JSON problem format, detected from the extension and the content.
///
/// Args:
///     path: the file (str or path-like).
///     format: ``"auto"``, ``"g2o"``, ``"1dsfm"`` or ``"json"``.
///     weights: ``"file"`` (the file's weights, e.g. SE-Sync's kappa for g2o) or ``"unit"``
///         (every weight 1 and no information; with ``information="full"`` an error).
///     largest_component: keep only the largest connected component (nodes renumbered).
///     rotation_tolerance: the tolerance on ``||R^T R - I||_F`` and ``|det R - 1|`` of every
///         rotation the file gives (the command line's ``--rotation-tolerance``) (default 1e-5, the command line's); beyond it, an error.
///     ground_truth: a ground-truth file for the graph's nodes (the command line's
///         ``--ground-truth``; formats: see ``read_ground_truth``): ``g.truth`` holds it, and
///         ``average_multiple(g)`` then reports ``result.accuracy``.
///     information: ``"auto"`` (default), ``"kappa"`` or ``"full"``, the command line's
///         ``--information``: g2o / TORO edges with their full 3x3 rotation information (an
///         anisotropic problem, ``"full"``) or SE-Sync's scalar kappa (``"auto"``,
///         ``"kappa"``); COLMAP databases with each pair's information from its inlier
///         correspondences and cameras (``"full"``, and ``"auto"`` where the database gives
///         it, else weights 1 with the warning ``database_without_information``) or weights 1
///         (``"kappa"``). ``g.information`` holds what was read.
///
/// Returns:
///     Graph: with ``n, i, j, rel, weights`` for ``average_multiple``.
///
/// Raises:
///     rotavg.FileError: unreadable file. rotavg.ParseError: malformed content (the message
///         names file and line).
#[pyfunction]
#[pyo3(signature = (path, format="auto", weights="file", largest_component=false, *, ground_truth=None, rotation_tolerance=1e-5, information="auto"))]
#[allow(clippy::too_many_arguments)]
fn read_graph(
    py: Python<'_>,
    path: std::path::PathBuf,
    format: &str,
    weights: &str,
    largest_component: bool,
    ground_truth: Option<std::path::PathBuf>,
    rotation_tolerance: f64,
    information: &str,
) -> PyResult<Graph> {
    let full_information = full_information(information)?;
    let tolerance = convert::rotation_tolerance(rotation_tolerance)?;
    let format: GraphFormat = parse_named(format, "format")?;
    let weights: WeightSource = parse_named(weights, "weights")?;
    let name = path.to_string_lossy().into_owned();
    let truth_path = ground_truth.map(|p| p.to_string_lossy().into_owned());
    let path_name = name.clone();
    let (loaded, selection, read, truth) = detached(py, move || {
        let options = ReadOptions {
            weights,
            rotation_tolerance: tolerance,
            full_information,
            ..Default::default()
        };
        // as rotavg::io::input::load_multiple_input, without requiring a connected graph
        // (average_multiple says how to proceed when it is not)
        let graph = load_view_graph(&path_name, format, &options)?;
        let truth = truth_path
            .as_deref()
            .map(|p| load_ground_truth(p, &graph, &options).map(|t| (p, t)))
            .transpose()?;
        let read = (graph.node_ids.clone(), graph.node_names.clone());
        let (graph, selection) = if largest_component {
            graph.largest_component()
        } else {
            let n = graph.problem.num_rotations();
            (graph, ComponentSelection::whole(n))
        };
        let truth = match truth {
            Some((file, t)) => Some(selection.select(&t).ok_or_else(|| {
                rotavg::Error::parse(
                    Some(file),
                    None,
                    format!(
                        "ground truth has {} entries, the graph has {} nodes",
                        t.len(),
                        selection.num_read
                    ),
                )
            })?),
            None => None,
        };
        Ok((graph, selection, read, truth))
    })?;
    Graph::new(py, name, (loaded, selection), read, truth)
}

/// `rotavg._rotavg`: the compiled part of the `rotavg` package.
#[pymodule]
fn _rotavg(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<RunResult>()?;
    m.add_class::<Certificate>()?;
    m.add_class::<SolverReport>()?;
    m.add_class::<Graph>()?;
    m.add_class::<truth::Accuracy>()?;
    m.add_class::<HandEyeData>()?;
    m.add_function(wrap_pyfunction!(average_single_py, m)?)?;
    m.add_function(wrap_pyfunction!(average_multiple_py, m)?)?;
    m.add_function(wrap_pyfunction!(certify_multiple_py, m)?)?;
    m.add_function(wrap_pyfunction!(average_conjugate_py, m)?)?;
    m.add_function(wrap_pyfunction!(certify_conjugate_py, m)?)?;
    m.add_function(wrap_pyfunction!(certify_single_py, m)?)?;
    m.add_function(wrap_pyfunction!(read_graph, m)?)?;
    m.add_function(wrap_pyfunction!(rig::average_rig, m)?)?;
    m.add_function(wrap_pyfunction!(rig::certify_rig, m)?)?;
    m.add_function(wrap_pyfunction!(rig::average_rig_file, m)?)?;
    m.add_function(wrap_pyfunction!(rig::certify_rig_file, m)?)?;
    m.add_function(wrap_pyfunction!(output::write_estimate, m)?)?;
    m.add_function(wrap_pyfunction!(output::write_edges, m)?)?;
    m.add_function(wrap_pyfunction!(output::write_figure, m)?)?;
    m.add_function(wrap_pyfunction!(output::write_output, m)?)?;
    m.add_function(wrap_pyfunction!(progress::set_progress, m)?)?;
    m.add_function(wrap_pyfunction!(truth::read_ground_truth, m)?)?;
    m.add_function(wrap_pyfunction!(truth::accuracy, m)?)?;
    m.add_function(wrap_pyfunction!(handeye::hand_eye_pairs, m)?)?;
    m.add_function(wrap_pyfunction!(handeye::read_handeye, m)?)?;
    m.add_function(wrap_pyfunction!(hand_eye, m)?)?;
    Ok(())
}
