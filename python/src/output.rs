//! `write_estimate`: an estimate of a graph written as `rotavg multiple --output` writes it
//! (`rotavg::io::output`: JSON with node ids, g2o, a COLMAP sparse model).

use crate::convert::matrices;
use crate::errors::argument_error;
use crate::{detached, parse_named};
use pyo3::prelude::*;
use rotavg::io::output::{EstimateFile, OutputFormat, OutputSource, prepare_output};

use crate::types::{Graph, RunResult};

/// Write an estimate of ``graph``'s nodes to ``path``, exactly as ``rotavg multiple FILE
/// --output PATH`` writes it.
///
/// Args:
///     graph: the ``Graph`` the estimate is of (from ``read_graph``): its node ids (and image
///         names) go into the file, and a g2o output of a g2o input keeps the input's lines
///         with the vertex rotations replaced.
///     estimate: ``(n, 3, 3)`` rotations ``R_i`` (world-to-camera), one per node of the graph.
///     path: ``*.json`` (``{"node_ids": [...], "rotations": [...]}``), ``*.g2o``, a folder
///         (``.../``: a COLMAP sparse model, ``images.txt``, ``cameras.txt``, ``points3D.txt``)
///         or ``*images.txt``; other names are JSON.
///     format: ``"auto"`` (from the path), ``"json"``, ``"g2o"`` or ``"colmap"``.
///
/// Raises:
///     rotavg.Error: an estimate of the wrong size or not of rotations, a format the path
///         cannot take; rotavg.FileError: the file or folder cannot be written (a folder this
///         call created is removed again).
#[pyfunction]
#[pyo3(signature = (graph, estimate, path, format="auto"))]
pub fn write_estimate(
    py: Python<'_>,
    graph: &Graph,
    estimate: &Bound<'_, PyAny>,
    path: std::path::PathBuf,
    format: &str,
) -> PyResult<()> {
    let format: OutputFormat = parse_named(format, "format")?;
    let rotations = matrices(estimate, "estimate")?
        .rotations()
        .map_err(crate::errors::error)?;
    let loaded = &graph.loaded;
    if rotations.len() != loaded.node_ids.len() {
        return Err(argument_error(format!(
            "the estimate has {} rotations, the graph has {} nodes",
            rotations.len(),
            loaded.node_ids.len()
        )));
    }
    let path = path.to_string_lossy().into_owned();
    detached(py, move || {
        let plan = prepare_output(&path, format)?;
        let source = OutputSource {
            input: &graph.name,
            format: loaded.format,
        };
        let file = EstimateFile {
            problem: &loaded.problem,
            rotations: &rotations,
            node_ids: &loaded.node_ids,
            node_names: &loaded.node_names,
        };
        plan.cleaned(file.write_planned(&plan, &source))
    })
}

/// Write the per-edge residuals of a robust ``average_multiple`` result of ``graph``, exactly as
/// ``rotavg multiple FILE --loss cauchy --edges-output PATH`` writes them: one row per edge
/// ``i, j, residual_deg, weight, inlier`` with the graph's node ids, JSON for ``*.json``,
/// otherwise CSV.
///
/// Raises:
///     rotavg.Error: the result has no residuals (not a robust run: ``loss="auto"`` may have
///         kept least squares) or is not of this graph; rotavg.FileError: it cannot be written.
#[pyfunction]
#[pyo3(signature = (graph, result, path))]
pub fn write_edges(
    py: Python<'_>,
    graph: &Graph,
    result: &RunResult,
    path: std::path::PathBuf,
) -> PyResult<()> {
    let residuals = result
        .multiple()
        .and_then(|r| r.result.solution.residuals.as_ref())
        .ok_or_else(|| {
            argument_error(
                "the result has no per-edge residuals: a robust average_multiple (loss \
                 \"cauchy\", \"huber\" or \"l1\", or \"auto\" when it chose cauchy) has them",
            )
        })?;
    let loaded = &graph.loaded;
    if residuals.residual_deg.len() != loaded.problem.num_edges() {
        return Err(argument_error(format!(
            "the result has residuals of {} edges, the graph has {}: not a result of this graph",
            residuals.residual_deg.len(),
            loaded.problem.num_edges()
        )));
    }
    let path = path.to_string_lossy().into_owned();
    detached(py, move || {
        let plan = prepare_output(&path, OutputFormat::Json)?;
        let text = rotavg::io::output::edges_file_text(
            &path,
            &loaded.problem,
            residuals,
            &loaded.node_ids,
        );
        plan.write_text(&text)
    })
}

/// Write the SVG figure of a result, as the command line's ``--plot PATH`` draws it: the
/// histogram of the residual angles (degrees) of the problem's edges or pairs at the result's
/// estimate, with its certificate (and the certificate matrix's smallest eigenvalues when the
/// certificate has them).
///
/// Args:
///     problem: the ``Graph`` (``average_multiple`` / ``certify_multiple`` results of it) or
///         the ``HandEyeData`` (``average_conjugate`` / ``certify_conjugate`` results) the
///         result is of.
///     result: the ``Result``.
///     path: the SVG file to write.
///
/// Raises:
///     rotavg.Error: a result of another kind or size than the problem (single-rotation
///         results have no figure, as on the command line); rotavg.FileError: the file cannot
///         be written.
#[pyfunction]
#[pyo3(signature = (problem, result, path))]
pub fn write_figure(
    py: Python<'_>,
    problem: &Bound<'_, PyAny>,
    result: &RunResult,
    path: std::path::PathBuf,
) -> PyResult<()> {
    let path = path.to_string_lossy().into_owned();
    let (rotations, certificate) = result.figure_parts();
    if let Ok(graph) = problem.cast::<Graph>() {
        let graph = graph.get();
        let rotations = rotations
            .filter(|r| r.len() == graph.loaded.problem.num_rotations())
            .ok_or_else(|| argument_error("the result is not an estimate of this graph"))?;
        let input = graph.name.clone();
        return detached(py, || {
            rotavg::plot::write_multiple_figure(
                &path,
                &graph.loaded.problem,
                &rotations,
                certificate.as_ref(),
                &input,
            )
        });
    }
    if let Ok(data) = problem.cast::<crate::handeye::HandEyeData>() {
        let data = data.get();
        let s = match (result.problem(), rotations.as_deref()) {
            ("conjugate", Some([s])) => *s,
            _ => return Err(argument_error("the result is not a hand-eye rotation")),
        };
        return detached(py, || {
            rotavg::plot::write_conjugate_figure(
                &path,
                &data.problem,
                &s,
                certificate.as_ref(),
                &data.name,
            )
        });
    }
    Err(argument_error(
        "problem must be a Graph (read_graph) or HandEyeData (read_handeye, hand_eye_pairs)",
    ))
}

/// Write what the command line's ``--output PATH`` writes for the verb of ``result``:
/// ``average_single`` / ``average_conjugate`` (and their ``certify_*``) results
/// ``{"rotation": R}`` (what ``certify --estimate`` and ``init`` read back), ``average_rig``
/// results the frames with ``node_ids`` and ``"sensor_from_rig"`` (``rotavg rig --output``,
/// what ``certify_rig`` reads back). View-graph results need their graph:
/// ``write_estimate(graph, result.estimate, path)``.
///
/// Raises:
///     rotavg.Error: a view-graph result; rotavg.FileError: the file cannot be written.
#[pyfunction]
#[pyo3(signature = (result, path))]
pub fn write_output(py: Python<'_>, result: &RunResult, path: std::path::PathBuf) -> PyResult<()> {
    let text = match (
        result.rig_output(),
        result.problem(),
        result.figure_parts().0,
    ) {
        (Some(text), _, _) => text,
        (None, "single" | "conjugate", Some(r)) if r.len() == 1 => {
            rotavg::io::json::write_rotation_json(&r[0])
        }
        _ => {
            return Err(argument_error(
                "a view graph's estimate is written with its graph: write_estimate(graph, \
                 result.estimate, path)",
            ));
        }
    };
    let path = path.to_string_lossy().into_owned();
    detached(py, move || rotavg::io::output::write_text(&path, &text))
}
