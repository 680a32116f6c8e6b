//! Rigs from Python (`average_rig`, `certify_rig`, `average_rig_file`): the reports of
//! `rotavg rig RIGHT LEFT`, `rotavg certify --left` and `rotavg rig FILE`.

use crate::convert::{matrices, matrix};
use crate::gravity::GravityInput;
use crate::types::{Graph, Report, RunResult};
use crate::{certify_settings, detached, parse_named};
use pyo3::prelude::*;
use rotavg::certify::CertifyMode;
use rotavg::pipeline::rig::RigLoss;
use rotavg::report::rig_two_graphs::{certify_two_graphs, needs_rig_form, two_graph_rig};
use rotavg::report::{RigFileReport, RigReport};

/// A two-sensor rig: the frames and the second sensor's ``sensor_from_rig`` rotation ``S``,
/// estimated jointly from two view graphs over the same frames and certified, exactly as
/// ``rotavg rig RIGHT LEFT``.
///
/// Args:
///     right: the reference sensor's ``Graph`` (``read_graph``): its rotations are the frames'.
///     left: the other sensor's ``Graph`` over the same node ids (``L_ij ~ S R_ij S^T``).
///     sensor_from_rig: a known ``(3, 3)`` rotation ``S`` to hold, as ``rotavg rig
///         --sensor-from-rig``: only the frames are estimated, on one view graph, and certified
///         by the multiple-averaging ladder (``paper-notes/conjugate.md`` [H18]).
///     loss: ``"auto"`` (least squares, the Cauchy loss instead when the residuals look like
///         outliers), ``"chordal"`` or ``"cauchy"`` (then the inlier edges' problem is returned
///         and certified, ``paper-notes/conjugate.md`` [H20], [H22]), as ``rotavg rig RIGHT
///         LEFT --loss``; with ``sensor_from_rig``, least squares (``"cauchy"`` is an error).
///     loss_threshold: the Cauchy loss's scale and the inlier threshold, degrees; ``None``:
///         both from the data with ``"auto"`` (``paper-notes/conjugate.md`` [H20] "The
///         scale"), 5 with ``"cauchy"``.
///     certify: ``"auto"``, ``"dual"``, ``"sdp"`` or ``"none"``.
///     max_memory, max_seconds: the run's budget, as for ``average_multiple`` (one clock for
///         the joint solve and the certificate).
///     gravity, world_down, gravity_weight: gravity priors on the frames, as ``rotavg rig RIGHT
///         LEFT --gravity``: an ``(n, 3)`` or ``(n, 4)`` array in ``right``'s node order (NaN
///         rows: none) or a priors file keyed as ``average_multiple`` keys ``right``'s nodes;
///         held, or soft of ``gravity_weight`` (``paper-notes/gravity.md`` [G14] "Two view
///         graphs": the rig of two sensors, reported as ``average_rig_file`` reports a rig with
///         priors; scalar weights only).
///
/// Returns:
///     Result: ``estimate`` is the frames ``(n, 3, 3)`` (gauge ``estimate[0] = I``; with held
///         priors, the frame nearest ``I`` that keeps its prior);
///     ``to_dict()["sensor_from_rig"]`` is ``S``; ``to_dict()`` equals ``rotavg rig ... --json``.
///
/// Graphs whose edges carry information matrices (``read_graph(..., information="full")``, or
/// JSON ``"information"``), and any two graphs with ``gravity``, are the rig of two sensors they
/// describe, solved and reported as
/// ``average_rig_file`` reports a rig file (``to_dict()["sensors_from_rig"][1]`` is ``S``;
/// ``paper-notes/conjugate.md`` [H22] "Information").
///
/// Raises:
///     rotavg.Error: graphs over different node ids, a ``sensor_from_rig`` that is not a
///         rotation.
#[pyfunction]
#[pyo3(name = "average_rig", signature = (right, left, *, sensor_from_rig=None, loss="auto", loss_threshold=None, certify="auto", max_memory=None, max_seconds=600.0, gravity=None, world_down=None, gravity_weight=None))]
#[allow(clippy::too_many_arguments)]
pub fn average_rig(
    py: Python<'_>,
    right: PyRef<'_, Graph>,
    left: PyRef<'_, Graph>,
    sensor_from_rig: Option<&Bound<'_, PyAny>>,
    loss: &str,
    loss_threshold: Option<f64>,
    certify: &str,
    max_memory: Option<u64>,
    max_seconds: Option<f64>,
    gravity: Option<&Bound<'_, PyAny>>,
    world_down: Option<[f64; 3]>,
    gravity_weight: Option<f64>,
) -> PyResult<RunResult> {
    let gravity = GravityInput::from_py(gravity)?;
    let (loss, robust) = rig_loss(loss, loss_threshold)?;
    let mode: CertifyMode = parse_named(certify, "certify")?;
    let certify = certify_settings(mode, max_memory, max_seconds, true, None)?;
    let held = match sensor_from_rig.filter(|s| !s.is_none()) {
        Some(s) => Some(matrix(s, "sensor_from_rig")?),
        None => None,
    };
    let (r, l) = (right.loaded.clone(), left.loaded.clone());
    let selection = right.selection.clone();
    let names = [right.name.clone(), left.name.clone()];
    let report = detached(py, move || {
        let held = held.map(one_rotation).transpose()?;
        let max_seconds = certify.budget.max_seconds;
        let loss = loss.with_sensor_held(held.is_some())?;
        if needs_rig_form(&r, &l) || gravity.is_some() {
            let priors =
                |g: GravityInput| g.node_priors((&r, &selection), world_down, gravity_weight);
            let rig = two_graph_rig(&r, &l, held, gravity.map(priors).transpose()?)?;
            let input = names.join(" and ");
            let both = (loss, robust);
            let report = RigFileReport::average(input, rig, both, certify, max_seconds)?;
            return Ok(Report::RigFile(report));
        }
        let graphs = (&r, &l);
        Ok(Report::Rig(match held {
            Some(_) => RigReport::average(names, graphs, held, certify, max_seconds)?,
            None => {
                RigReport::average_with_loss(names, graphs, (loss, robust), certify, max_seconds)?
            }
        }))
    })?;
    RunResult::new(py, report)
}

/// A rig of any number of sensors read from a file, solved and certified, exactly as ``rotavg
/// rig FILE`` (``paper-notes/conjugate.md`` [H19]).
///
/// Args:
///     path: a JSON rig file (``{"num_frames", "sensors", "images", "edges"}``) or a COLMAP
///         database with a rig configuration (tables rigs, rig_sensors, frames, frame_data).
///     loss: ``"auto"`` (least squares, the Cauchy loss instead when the residuals look like
///         outliers), ``"chordal"`` or ``"cauchy"`` (then the inlier edges' problem is returned
///         and certified), as ``rotavg rig FILE --loss``.
///     loss_threshold: the Cauchy loss's scale and the inlier threshold, degrees; ``None``:
///         both from the data with ``"auto"`` (``paper-notes/conjugate.md`` [H20] "The
///         scale"), 5 with ``"cauchy"``.
///     certify: ``"auto"``, ``"dual"`` or ``"none"``.
///     max_memory, max_seconds: the run's budget, as for ``average_multiple``.
///     rotation_tolerance: how far a rotation in a JSON rig file may be from SO(3).
///     gravity, world_down, gravity_weight: gravity priors on the rig's images
///         (``paper-notes/gravity.md`` [G14]; sensors to estimate are calibrated without them
///         first, ``to_dict()["calibration"]``, refined by soft priors [G15]
///         (``["calibration"]["refined_sensors_from_rig"]``), then held, and the joint problem
///         with the sensors free certified too, ``["pipeline"]["rig_joint"]``, [G16]), as
///         ``rotavg rig FILE --gravity``: an ``(I, 3)`` or ``(I, 4)`` array in image order (NaN rows: none) or
///         a priors file keyed by image id or name; held, or soft of ``gravity_weight``.
///         ``to_dict()["gravity"]`` has their checks.
///     information: ``"auto"`` (default), ``"kappa"`` or ``"full"``, as ``--information``:
///         a COLMAP database's pairs with their rotation information from their
///         correspondences (``"full"``: an anisotropic rig, [H24]) or weights 1 (``"auto"``,
///         ``"kappa"``; a JSON rig file's ``"information"`` is always read).
///
/// Returns:
///     Result: ``estimate`` is the frames ``(F, 3, 3)`` (``estimate[0] = I``);
///     ``to_dict()["sensors_from_rig"]`` every sensor's ``sensor_from_rig`` (the known ones as
///     given), ``to_dict()["sensors_held"]`` which were held; ``to_dict()`` equals ``rotavg rig
///     FILE --json``.
///
/// Raises:
///     rotavg.ParseError / FileError: a file that cannot be read (naming it); rotavg.Error: a
///         rig that is not valid (an image out of range, a sensor no edge places).
#[pyfunction]
#[pyo3(name = "average_rig_file", signature = (path, *, loss="auto", loss_threshold=None, certify="auto", max_memory=None, max_seconds=600.0, rotation_tolerance=1e-5, gravity=None, world_down=None, gravity_weight=None, information="auto"))]
#[allow(clippy::too_many_arguments)]
pub fn average_rig_file(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    loss: &str,
    loss_threshold: Option<f64>,
    certify: &str,
    max_memory: Option<u64>,
    max_seconds: Option<f64>,
    rotation_tolerance: f64,
    gravity: Option<&Bound<'_, PyAny>>,
    world_down: Option<[f64; 3]>,
    gravity_weight: Option<f64>,
    information: &str,
) -> PyResult<RunResult> {
    let full_information = crate::full_information(information)?;
    let gravity = GravityInput::from_py(gravity)?;
    let mode: CertifyMode = parse_named(certify, "certify")?;
    let certify = certify_settings(mode, max_memory, max_seconds, true, None)?;
    let path = crate::convert::path_of(path)
        .ok_or_else(|| crate::errors::argument_error("path must be a str or os.PathLike"))?;
    let (loss, robust) = rig_loss(loss, loss_threshold)?;
    let report = detached(py, move || {
        let options = rotavg::io::detect::ReadOptions {
            rotation_tolerance,
            full_information,
            ..Default::default()
        };
        let rig = rotavg::io::rig::load_rig(std::path::Path::new(&path), &options)?;
        let rig = match gravity {
            Some(g) => g.apply_to_rig(rig, world_down, gravity_weight)?,
            None => rig,
        };
        let max_seconds = certify.budget.max_seconds;
        RigFileReport::average(path, rig, (loss, robust), certify, max_seconds)
    })?;
    RunResult::new(py, Report::RigFile(report))
}

/// Certify a rig estimate computed elsewhere, **without changing it** (its matrices taken at
/// their nearest rotations), as ``rotavg certify FILE --rig --estimate EST``.
///
/// Args:
///     path: the rig file, as for ``average_rig_file``.
///     frames: ``(F, 3, 3)`` frame rotations in the rig's order; or the path of the file
///         ``rotavg rig FILE --output`` (``write_output``) writes (then leave
///         ``sensors_from_rig`` out).
///     sensors_from_rig: ``(K, 3, 3)``, every sensor's rotation (with array frames).
///     certify, max_memory, max_seconds, rotation_tolerance, gravity, world_down,
///         gravity_weight, information: as for ``average_rig_file`` (``"none"`` means
///         ``"dual"``).
///
/// Raises:
///     rotavg.Error: counts or ids that do not match the rig, a matrix that is not a rotation,
///         ``sensors_from_rig`` missing with arrays or given with a path.
#[pyfunction]
#[pyo3(name = "certify_rig_file", signature = (path, frames, sensors_from_rig=None, *, certify="auto", max_memory=None, max_seconds=600.0, rotation_tolerance=1e-5, gravity=None, world_down=None, gravity_weight=None, information="auto"))]
#[allow(clippy::too_many_arguments)]
pub fn certify_rig_file(
    py: Python<'_>,
    path: &Bound<'_, PyAny>,
    frames: &Bound<'_, PyAny>,
    sensors_from_rig: Option<&Bound<'_, PyAny>>,
    certify: &str,
    max_memory: Option<u64>,
    max_seconds: Option<f64>,
    rotation_tolerance: f64,
    gravity: Option<&Bound<'_, PyAny>>,
    world_down: Option<[f64; 3]>,
    gravity_weight: Option<f64>,
    information: &str,
) -> PyResult<RunResult> {
    let full_information = crate::full_information(information)?;
    let gravity = GravityInput::from_py(gravity)?;
    let mode = match parse_named(certify, "certify")? {
        CertifyMode::None => CertifyMode::Dual,
        m => m,
    };
    let settings = certify_settings(mode, max_memory, max_seconds, true, None)?;
    let path = crate::convert::path_of(path)
        .ok_or_else(|| crate::errors::argument_error("path must be a str or os.PathLike"))?;
    let (text, name) = match (
        crate::convert::path_of(frames),
        sensors_from_rig.filter(|s| !s.is_none()),
    ) {
        (Some(p), None) => (None, p),
        (None, Some(s)) => {
            let rows = |m: crate::convert::Matrices| {
                m.matrices()
                    .iter()
                    .map(|r| {
                        [
                            [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
                            [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
                            [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
                        ]
                    })
                    .collect::<Vec<_>>()
            };
            let value = serde_json::json!({
                "frames": rows(matrices(frames, "frames")?),
                "sensors_from_rig": rows(matrices(s, "sensors_from_rig")?),
            });
            (Some(value.to_string()), "the arrays".to_string())
        }
        (Some(_), Some(_)) => {
            return Err(crate::errors::argument_error(
                "a rig estimate file holds sensors_from_rig: leave the argument out",
            ));
        }
        (None, None) => {
            return Err(crate::errors::argument_error(
                "certify_rig_file needs sensors_from_rig with array frames",
            ));
        }
    };
    let report = detached(py, move || {
        let options = rotavg::io::detect::ReadOptions {
            rotation_tolerance,
            full_information,
            ..Default::default()
        };
        let rig = rotavg::io::rig::load_rig(std::path::Path::new(&path), &options)?;
        let rig = match gravity {
            Some(g) => g.apply_to_rig(rig, world_down, gravity_weight)?,
            None => rig,
        };
        let text = match text {
            Some(t) => t,
            None => rotavg::io::text::read_text(&name)?,
        };
        let estimate = rotavg::io::rig::read_rig_estimate(&text, &name, &rig, &options, false)?;
        RigFileReport::certify(path, rig, estimate, &settings)
    })?;
    RunResult::new(py, Report::RigFile(report))
}

/// The rotation `sensor_from_rig` of a `(3, 3)` array.
fn one_rotation(s: crate::convert::Matrices) -> rotavg::Result<rotavg::Rotation> {
    s.rotations()?.pop().ok_or_else(|| rotavg::Error::Empty {
        what: "sensor_from_rig".into(),
    })
}

/// Certify a rig estimate computed elsewhere, **without changing it**, as ``rotavg certify
/// RIGHT --left LEFT --estimate FILE``.
///
/// Args:
///     right, left: the two ``Graph`` objects, as for ``average_rig``.
///     frames: ``(n, 3, 3)`` frame rotations in node order; or the path of a rig estimate as
///         ``rotavg rig --output`` (``write_output``) writes it, frames matched by node id and
///         ``"sensor_from_rig"`` read from it (then leave ``sensor_from_rig`` out).
///     sensor_from_rig: ``(3, 3)`` rotation ``S`` (with array frames).
///     certify, max_memory, max_seconds: as for ``average_rig`` (``"none"`` means ``"dual"``).
///     gravity, world_down, gravity_weight: priors on the frames, as for ``average_rig``
///         (the estimate's ``S`` held; ``paper-notes/gravity.md`` [G14]).
///
/// Raises:
///     rotavg.Error: ``sensor_from_rig`` missing with arrays, or given with a path;
///         rotavg.ParseError / FileError: a file that cannot be read (naming it).
#[pyfunction]
#[pyo3(name = "certify_rig", signature = (right, left, frames, sensor_from_rig=None, *, certify="auto", max_memory=None, max_seconds=600.0, gravity=None, world_down=None, gravity_weight=None))]
#[allow(clippy::too_many_arguments)]
pub fn certify_rig(
    py: Python<'_>,
    right: PyRef<'_, Graph>,
    left: PyRef<'_, Graph>,
    frames: &Bound<'_, PyAny>,
    sensor_from_rig: Option<&Bound<'_, PyAny>>,
    certify: &str,
    max_memory: Option<u64>,
    max_seconds: Option<f64>,
    gravity: Option<&Bound<'_, PyAny>>,
    world_down: Option<[f64; 3]>,
    gravity_weight: Option<f64>,
) -> PyResult<RunResult> {
    let gravity = GravityInput::from_py(gravity)?;
    let mode = match parse_named(certify, "certify")? {
        CertifyMode::None => CertifyMode::Dual,
        m => m,
    };
    let settings = certify_settings(mode, max_memory, max_seconds, true, None)?;
    let estimate = RigEstimate::of(frames, sensor_from_rig.filter(|s| !s.is_none()))?;
    let (r, l) = (right.loaded.clone(), left.loaded.clone());
    let selection = right.selection.clone();
    let names = [right.name.clone(), left.name.clone()];
    let report = detached(py, move || {
        let (frames, s) = estimate.load(&r)?;
        if needs_rig_form(&r, &l) || gravity.is_some() {
            let input = names.join(" and ");
            let priors =
                |g: GravityInput| g.node_priors((&r, &selection), world_down, gravity_weight);
            let rig = two_graph_rig(&r, &l, None, gravity.map(priors).transpose()?)?;
            let report = certify_two_graphs(input, rig, frames, s, &settings)?;
            return Ok(Report::RigFile(report));
        }
        Ok(Report::Rig(RigReport::certify(
            names, &r, &l, frames, s, &settings,
        )?))
    })?;
    RunResult::new(py, report)
}

/// A rig estimate: arrays, or a file as `rotavg rig --output` writes it.
enum RigEstimate {
    Arrays(crate::convert::Matrices, crate::convert::Matrices),
    Path(String),
}

impl RigEstimate {
    fn of(frames: &Bound<'_, PyAny>, s: Option<&Bound<'_, PyAny>>) -> PyResult<Self> {
        match (crate::convert::path_of(frames), s) {
            (Some(p), None) => Ok(RigEstimate::Path(p)),
            (None, Some(s)) => Ok(RigEstimate::Arrays(
                matrices(frames, "frames")?,
                matrix(s, "sensor_from_rig")?,
            )),
            (Some(_), Some(_)) => Err(crate::errors::argument_error(
                "a rig estimate file holds sensor_from_rig: leave the argument out",
            )),
            (None, None) => Err(crate::errors::argument_error(
                "certify_rig needs sensor_from_rig with array frames",
            )),
        }
    }

    /// The frames (in `right`'s node order) and `S`.
    fn load(
        self,
        right: &rotavg::io::detect::LoadedGraph,
    ) -> rotavg::Result<(Vec<rotavg::Rotation>, rotavg::Rotation)> {
        match self {
            RigEstimate::Arrays(frames, s) => Ok((frames.rotations()?, one_rotation(s)?)),
            RigEstimate::Path(p) => {
                let options = rotavg::io::detect::ReadOptions::default();
                let frames = rotavg::io::input::load_estimate_for(&p, right, &options)?
                    .into_loaded()
                    .into_rotations()?;
                Ok((
                    frames,
                    rotavg::io::json::read_sensor_from_rig(&p, &options)?,
                ))
            }
        }
    }
}

/// `loss` and `loss_threshold` of the rig functions: the loss and the Cauchy scale and inlier
/// threshold.
fn rig_loss(loss: &str, threshold: Option<f64>) -> PyResult<(RigLoss, rotavg::rig::RigRobust)> {
    RigLoss::named(loss, threshold).map_err(|e| crate::errors::argument_error(e.to_string()))
}
