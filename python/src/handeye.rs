//! Hand-eye data: pairs `(L_k, R_k)` formed from absolute robot and camera poses as OpenCV's
//! `calibrateHandEye` forms them (`hand_eye_pairs`, `hand_eye`), or read from the files the
//! command line reads (`read_handeye`: `rotavg::io::input::load_conjugate_with`), held by the
//! `HandEyeData` class that `average_conjugate` and `certify_conjugate` accept.
//!
//! The convention (contract section 1): `R_k ~ S^-1 L_k S`, i.e. `L_k S = S R_k`, OpenCV's
//! `A X = X B` with `A = L` (the gripper motion), `B = R` (the camera motion) and
//! `X = S = R_cam2gripper`. For stations `i < j` (every pair, as OpenCV's Tsai, Park, Horaud,
//! Andreff and Daniilidis methods form them):
//! `L = rot(Hg_j^-1 Hg_i)`, `R = rot(Hc_j Hc_i^-1)`, with `Hg` = base-from-gripper
//! (`R_gripper2base`) and `Hc` = camera-from-target (`R_target2cam`).

use crate::convert::{Matrices, pose_rotations, rotations_array};
use crate::errors::argument_error;
use crate::parse_named;
use crate::{detached, types::to_python};
use pyo3::prelude::*;
use rotavg::conjugate::{ConjugatePair, ConjugateProblem};
use rotavg::io::detect::{ReadOptions, WeightSource};
use rotavg::io::handeye::{MotionSettings, MotionStats, QuaternionOrder};
use rotavg::io::input::{HandEyeOptions, LoadedConjugate, load_conjugate_with};
use rotavg::io::names::ConjugateFormat;
use rotavg::so3::angle;

/// Pairs of relative motions ``(left[k], right[k])`` with ``right[k] ~ S^-1 left[k] S``, formed
/// from absolute poses (``hand_eye_pairs``) or read from hand-eye files (``read_handeye``).
/// Pass it to ``average_conjugate(data)`` / ``certify_conjugate(data, estimate=S)``: for files
/// these are exactly ``rotavg conjugate PATH`` / ``rotavg certify``.
///
/// Attributes: ``left``, ``right`` (``(P, 3, 3)`` float64, read-only), ``weights`` (``(P,)``),
/// ``num_pairs``, ``format`` (``"poses"``, ``"json"``, ``"tabb"`` or ``"eth"``), ``source``
/// (where the pairs came from, in words), ``motion`` (a dict: ``poses``, ``pairs``,
/// ``skipped_small``, ``unmatched``, ``hand``, ``camera``, ``settings``, as
/// ``to_dict()["motion"]`` of the result; None for pairs read as such) and ``path``.
#[pyclass(name = "HandEyeData", module = "rotavg", frozen)]
pub struct HandEyeData {
    pub problem: ConjugateProblem,
    pub source: String,
    pub motion: Option<(MotionStats, MotionSettings)>,
    pub name: String,
    format: String,
    /// The hand (gripper) motions ``L_k``, ``(P, 3, 3)``.
    #[pyo3(get)]
    left: Py<PyAny>,
    /// The camera motions ``R_k``, ``(P, 3, 3)``.
    #[pyo3(get)]
    right: Py<PyAny>,
    /// The weight of each pair, ``(P,)``.
    #[pyo3(get)]
    weights: Py<PyAny>,
}

impl HandEyeData {
    fn new(
        py: Python<'_>,
        problem: ConjugateProblem,
        source: String,
        motion: Option<(MotionStats, MotionSettings)>,
        name: String,
        format: &str,
    ) -> PyResult<Self> {
        use crate::convert::read_only;
        use numpy::PyArray1;
        let pairs = problem.pairs();
        let left: Vec<_> = pairs.iter().map(|p| p.left).collect();
        let right: Vec<_> = pairs.iter().map(|p| p.right).collect();
        let w: Vec<f64> = pairs.iter().map(|p| p.weight).collect();
        let arr = |a: Bound<'_, PyAny>| read_only(a).map(Bound::unbind);
        Ok(HandEyeData {
            left: arr(rotations_array(py, &left)?)?,
            right: arr(rotations_array(py, &right)?)?,
            weights: arr(PyArray1::from_vec(py, w).into_any())?,
            problem,
            source,
            motion,
            name,
            format: format.to_string(),
        })
    }

    /// The data of a file, as the command line read it.
    fn loaded(py: Python<'_>, loaded: LoadedConjugate) -> PyResult<Self> {
        let source = loaded.to_string();
        let format = loaded.format.to_string();
        let motion = loaded.motion.map(|m| (m, loaded.motion_settings));
        HandEyeData::new(py, loaded.problem, source, motion, loaded.name, &format)
    }
}

#[pymethods]
impl HandEyeData {
    /// Number of pairs.
    #[getter]
    fn num_pairs(&self) -> usize {
        self.problem.num_pairs()
    }
    /// ``"poses"`` (``hand_eye_pairs``), ``"json"``, ``"tabb"`` or ``"eth"`` (pose streams).
    #[getter]
    fn format(&self) -> String {
        self.format.clone()
    }
    /// Where the pairs came from, in words (the first line of ``str(result)``).
    #[getter]
    fn source(&self) -> String {
        self.source.clone()
    }
    /// How the pairs were formed from poses (counts and settings), or None.
    #[getter]
    fn motion<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        #[derive(serde::Serialize)]
        struct Motion<'a> {
            #[serde(flatten)]
            stats: &'a MotionStats,
            settings: &'a MotionSettings,
        }
        self.motion
            .as_ref()
            .map(|(stats, settings)| to_python(py, &Motion { stats, settings }))
            .transpose()
    }
    /// The path read (``"<arrays>"`` for ``hand_eye_pairs``).
    #[getter]
    fn path(&self) -> String {
        self.name.clone()
    }
    fn __len__(&self) -> usize {
        self.problem.num_pairs()
    }
    fn __repr__(&self) -> String {
        format!(
            "HandEyeData(format='{}', num_pairs={}, source={:?})",
            self.format,
            self.problem.num_pairs(),
            self.source
        )
    }
}

/// Which pairs of stations form motions.
#[derive(Clone, Copy, PartialEq, Eq)]
enum PairSet {
    /// Every `i < j` (OpenCV).
    All,
    /// `(k, k + 1)`.
    Consecutive,
}

/// The pose arrays copied out of Python, not yet validated.
struct PoseArrays {
    robot: Matrices,
    camera: Matrices,
    /// Camera poses are camera-from-target (`target2cam`); else target-from-camera.
    camera_from_target: bool,
    pairs: PairSet,
    min_angle: f64,
}

impl PoseArrays {
    /// The pairs and their counts (runs without the GIL).
    fn pairs(self) -> rotavg::Result<(ConjugateProblem, MotionStats, MotionSettings)> {
        let hg = self.robot.rotations()?;
        let mut hc = self.camera.rotations()?;
        if !self.camera_from_target {
            hc.iter_mut().for_each(|c| *c = c.inverse());
        }
        let n = hg.len();
        let settings = MotionSettings {
            min_angle: self.min_angle,
            ..match self.pairs {
                PairSet::All => MotionSettings::default(),
                PairSet::Consecutive => MotionSettings {
                    stride: 1,
                    subsample: 1,
                    ..Default::default()
                },
            }
        };
        settings.validate()?;
        let mut stats = MotionStats {
            poses: n,
            ..Default::default()
        };
        let mut pairs = Vec::new();
        let mut push = |i: usize, j: usize| {
            // OpenCV: Hgij = Hg[j]^-1 Hg[i], Hcij = Hc[j] Hc[i]^-1; Hgij X = X Hcij
            let l = hg[j].inverse() * hg[i];
            let r = hc[j] * hc[i].inverse();
            if angle(&l) < settings.min_angle && angle(&r) < settings.min_angle {
                stats.skipped_small += 1;
            } else {
                pairs.push(ConjugatePair::new(l, r));
                stats.pairs += 1;
            }
        };
        match self.pairs {
            PairSet::All => (0..n).for_each(|i| (i + 1..n).for_each(|j| push(i, j))),
            PairSet::Consecutive => (1..n).for_each(|j| push(j - 1, j)),
        }
        if pairs.is_empty() {
            return Err(rotavg::Error::Degenerate {
                reason: format!(
                    "{n} poses give no pair of stations whose robot or camera motion rotates by at least min_angle = {} deg",
                    settings.min_angle.to_degrees()
                ),
            });
        }
        Ok((ConjugateProblem::new(pairs)?, stats, settings))
    }
}

/// Hand-eye pairs from absolute poses, formed as OpenCV's ``calibrateHandEye`` forms them.
///
/// Convention: the pairs satisfy ``right[k] ~ S^-1 left[k] S`` with ``S = R_cam2gripper``
/// (OpenCV's output: the rotation from camera to gripper coordinates, the gripper-from-camera
/// rotation). For stations ``i < j``, with ``Hg`` the robot poses (base-from-gripper, OpenCV's
/// ``R_gripper2base``) and ``Hc`` the camera poses (camera-from-target, OpenCV's
/// ``R_target2cam``, e.g. from ``solvePnP``): ``left = rot(Hg_j^-1 Hg_i)`` (the gripper motion,
/// OpenCV's ``A``) and ``right = rot(Hc_j Hc_i^-1)`` (the camera motion, ``B``); OpenCV's
/// ``A X = X B`` is ``left S = S right``. Translations are not used (``S`` is a rotation).
/// Eye-to-hand (camera fixed, target on the gripper): pass the inverse robot poses
/// (base2gripper), as for OpenCV; ``S`` is then the camera-to-base rotation.
///
/// Args:
///     robot_poses: ``(N, 4, 4)`` homogeneous transforms or ``(N, 3, 3)`` rotations (or a scipy
///         ``Rotation``): the gripper's pose in the robot base, base-from-gripper.
///     camera_poses: ``(N, 4, 4)`` or ``(N, 3, 3)``: the camera's view of the target at the same
///         stations, camera-from-target (``camera="target2cam"``), or the camera's pose in the
///         target (world) frame, target-from-camera (``camera="cam2target"``).
///     camera: ``"target2cam"`` (default) or ``"cam2target"``.
///     pairs: ``"all"`` (every ``i < j``: OpenCV's choice, ``N (N - 1) / 2`` pairs) or
///         ``"consecutive"`` (``(k, k + 1)``).
///     min_angle: skip a pair whose two motions both rotate by less than this many degrees
///         (default 0.573, the command line's ``--min-angle``; 0 keeps every pair, as OpenCV).
///
/// Returns:
///     HandEyeData: for ``average_conjugate``, ``certify_conjugate`` or ``hand_eye``.
///
/// Raises:
///     rotavg.Error: shapes, a matrix that is not a rotation, a last row that is not
///         ``0 0 0 1``, unknown names. rotavg.DegenerateError: no pair left.
#[pyfunction]
#[pyo3(signature = (robot_poses, camera_poses, *, camera="target2cam", pairs="all", min_angle=None))]
pub fn hand_eye_pairs(
    py: Python<'_>,
    robot_poses: &Bound<'_, PyAny>,
    camera_poses: &Bound<'_, PyAny>,
    camera: &str,
    pairs: &str,
    min_angle: Option<f64>,
) -> PyResult<HandEyeData> {
    let arrays = pose_arrays(robot_poses, camera_poses, camera, pairs, min_angle)?;
    let n = arrays.robot.len();
    let (problem, stats, settings) = detached(py, move || arrays.pairs())?;
    let source = format!(
        "<arrays>: {n} robot and camera poses, {} pairs ({} skipped: rotation < {:.2} deg)",
        stats.pairs,
        stats.skipped_small,
        settings.min_angle.to_degrees()
    );
    HandEyeData::new(
        py,
        problem,
        source,
        Some((stats, settings)),
        "<arrays>".into(),
        "poses",
    )
}

/// Copy and check the arguments of [`hand_eye_pairs`].
fn pose_arrays(
    robot_poses: &Bound<'_, PyAny>,
    camera_poses: &Bound<'_, PyAny>,
    camera: &str,
    pairs: &str,
    min_angle: Option<f64>,
) -> PyResult<PoseArrays> {
    let camera_from_target = match camera {
        "target2cam" => true,
        "cam2target" => false,
        other => {
            return Err(argument_error(format!(
                "camera must be \"target2cam\" (camera-from-target, OpenCV's R_target2cam) or \"cam2target\" (the camera's pose in the target frame), got {other:?}"
            )));
        }
    };
    let pairs = match pairs {
        "all" => PairSet::All,
        "consecutive" => PairSet::Consecutive,
        other => {
            return Err(argument_error(format!(
                "pairs must be \"all\" or \"consecutive\", got {other:?}"
            )));
        }
    };
    let robot = pose_rotations(robot_poses, "robot_poses")?;
    let camera = pose_rotations(camera_poses, "camera_poses")?;
    if robot.len() != camera.len() {
        return Err(argument_error(format!(
            "robot_poses and camera_poses must have one pose per station: got {} and {}",
            robot.len(),
            camera.len()
        )));
    }
    let min_angle = min_angle.map_or(MotionSettings::default().min_angle, f64::to_radians);
    Ok(PoseArrays {
        robot,
        camera,
        camera_from_target,
        pairs,
        min_angle,
    })
}

/// Read hand-eye data with the command line's readers (``rotavg conjugate PATH``,
/// ``rotavg::io::input::load_conjugate_with``): conjugate JSON pairs, a Tabb dataset directory
/// (``robot_cali.txt`` + ``cali.txt``, every station pair), or pose streams (ETH ASL CSV,
/// Vicon / motion-capture exports: a directory, or the two files named).
///
/// Conventions (as the command line): Tabb's ``L`` is the camera motion and ``R`` the robot
/// motion, ``S`` the hand-to-camera rotation ``Z``; pose streams' ``L`` is the hand motion
/// (first file, ``hand``), ``R`` the camera motion, ``S`` the camera-to-hand rotation.
///
/// Args:
///     path: a JSON file, a dataset directory, or None when both ``hand`` and ``camera`` are
///         given.
///     format: ``"auto"`` (a directory with ``robot_cali.txt`` is Tabb, another directory pose
///         streams, a file JSON), ``"json"``, ``"tabb"`` or ``"eth"``.
///     hand, camera: the pose streams (a name inside ``path``, or any path); default: found
///         in the directory by name (``base_link``, ``hand``, ``vicon`` / ``target``,
///         ``camera``).
///     stride, subsample, max_gap, time_offset, quaternion_order: how stream samples are
///         paired (the command line's ``--stride`` etc.; ``max_gap`` and ``time_offset`` in
///         seconds).
///     min_angle: skip pairs whose motions both rotate by less than this many degrees
///         (default 0.573).
///     weights: ``"file"`` or ``"unit"``.
///
/// Returns:
///     HandEyeData.
///
/// Raises:
///     rotavg.FileError, rotavg.ParseError: unreadable or malformed files (file and line).
///     rotavg.Error: bad settings.
#[pyfunction]
#[pyo3(signature = (path=None, *, format="auto", hand=None, camera=None, stride=None, subsample=None, max_gap=None, time_offset=0.0, min_angle=None, quaternion_order="xyzw", weights="file"))]
#[allow(clippy::too_many_arguments)]
pub fn read_handeye(
    py: Python<'_>,
    path: Option<std::path::PathBuf>,
    format: &str,
    hand: Option<std::path::PathBuf>,
    camera: Option<std::path::PathBuf>,
    stride: Option<usize>,
    subsample: Option<usize>,
    max_gap: Option<f64>,
    time_offset: f64,
    min_angle: Option<f64>,
    quaternion_order: &str,
    weights: &str,
) -> PyResult<HandEyeData> {
    let format: ConjugateFormat = parse_named(format, "format")?;
    let quaternion_order: QuaternionOrder = parse_named(quaternion_order, "quaternion_order")?;
    let weights: WeightSource = parse_named(weights, "weights")?;
    let text = |p: std::path::PathBuf| p.to_string_lossy().into_owned();
    let defaults = MotionSettings::default();
    let options = HandEyeOptions {
        hand: hand.map(text),
        camera: camera.map(text),
        motion: MotionSettings {
            stride: stride.unwrap_or(defaults.stride),
            subsample: subsample.unwrap_or(defaults.subsample),
            max_gap: max_gap.unwrap_or(defaults.max_gap),
            time_offset,
            min_angle: min_angle.map_or(defaults.min_angle, f64::to_radians),
            quaternion_order,
            ..defaults
        },
    };
    if path.is_none() && (options.hand.is_none() || options.camera.is_none()) {
        return Err(argument_error(
            "read_handeye needs a path, or both hand and camera",
        ));
    }
    let path = path.map(text);
    let loaded = detached(py, move || {
        let read = ReadOptions {
            weights,
            ..Default::default()
        };
        load_conjugate_with(path.as_deref(), format, &read, &options)
    })?;
    HandEyeData::loaded(py, loaded)
}
