"""Type stubs of rotavg (the compiled module rotavg._rotavg, re-exported by the package).

Every function, class, attribute and keyword argument that the module exports is declared
here; python/tests/test_stubs.py checks the declarations against the compiled module, and
.ci/run type-checks python/tests/typecheck_usage.py (every documented call) against them with
mypy --strict.
"""

import os
from typing import Any, Callable, Dict, List, Optional, Protocol, Sequence, TextIO, Union, final, overload

import numpy as np
import numpy.typing as npt

__version__: str
__all__ = [
    "Accuracy",
    "Certificate",
    "DegenerateError",
    "DisconnectedError",
    "Error",
    "FileError",
    "Graph",
    "HandEyeData",
    "ParseError",
    "Result",
    "SolverError",
    "SolverReport",
    "__version__",
    "accuracy",
    "average_conjugate",
    "average_multiple",
    "average_rig",
    "average_rig_file",
    "certify_rig_file",
    "average_single",
    "certify_conjugate",
    "certify_multiple",
    "certify_rig",
    "certify_single",
    "hand_eye",
    "hand_eye_pairs",
    "read_graph",
    "read_ground_truth",
    "read_handeye",
    "set_progress",
    "write_edges",
    "write_estimate",
    "write_figure",
    "write_output",
    "progress_bar",
]

class _HasAsMatrix(Protocol):
    def as_matrix(self) -> npt.ArrayLike: ...

#: (N, 3, 3) rotation matrices: an array-like or a scipy.spatial.transform.Rotation.
_Rotations = Union[npt.ArrayLike, _HasAsMatrix]
#: One (3, 3) rotation matrix (or a single scipy Rotation).
_Rotation3 = Union[npt.ArrayLike, _HasAsMatrix]
#: (N, 4, 4) homogeneous transforms or (N, 3, 3) rotations (or a scipy Rotation).
_Poses = Union[npt.ArrayLike, _HasAsMatrix]
#: A file or directory path.
_PathLike = Union[str, "os.PathLike[str]"]
_FloatArray = npt.NDArray[np.float64]

class Error(ValueError):
    """Bad input or settings (a ValueError), and the base of every rotavg exception."""

class ParseError(Error):
    """A malformed input file: ``path`` and ``line`` (1-based, or None)."""

    path: Optional[str]
    line: Optional[int]

class FileError(Error):
    """A file or directory that cannot be read: ``path``."""

    path: str

class DisconnectedError(Error):
    """A view graph that is not connected: ``component_sizes``, largest first."""

    component_sizes: List[int]

class DegenerateError(Error):
    """Data that do not determine the answer (e.g. parallel hand-eye rotation axes)."""

class SolverError(Error):
    """A numerical solver could not be set up or failed without a result."""

@final
class Certificate:
    """A proven lower bound on the global minimum, the gap of the estimate to it, the verdict."""

    @property
    def verdict(self) -> str: ...
    @property
    def certified(self) -> bool: ...
    @property
    def upper_bound(self) -> float: ...
    @property
    def lower_bound(self) -> Optional[float]: ...
    @property
    def gap(self) -> Optional[float]: ...
    @property
    def relative_gap(self) -> Optional[float]: ...
    @property
    def min_eigenvalue(self) -> Optional[float]: ...
    @property
    def method(self) -> str: ...
    @property
    def allowed_gap(self) -> float: ...
    @property
    def explanation(self) -> str: ...
    @property
    def seconds(self) -> float: ...
    def to_dict(self) -> Dict[str, Any]: ...

@final
class SolverReport:
    """What the local solver did: name, iterations, why it stopped, wall time."""

    @property
    def name(self) -> str: ...
    @property
    def iterations(self) -> int: ...
    @property
    def termination(self) -> str: ...
    @property
    def termination_detail(self) -> str: ...
    @property
    def converged(self) -> bool: ...
    @property
    def seconds(self) -> float: ...
    def to_dict(self) -> Dict[str, Any]: ...

@final
class Accuracy:
    """Angular errors (degrees) of an estimate against ground truth after alignment."""

    @property
    def mean_deg(self) -> float: ...
    @property
    def median_deg(self) -> float: ...
    @property
    def rmse_deg(self) -> float: ...
    @property
    def max_deg(self) -> float: ...
    @property
    def num_compared(self) -> int: ...
    @property
    def alignment(self) -> _FloatArray: ...
    @property
    def robust_mean_deg(self) -> float: ...
    @property
    def robust_median_deg(self) -> float: ...
    @property
    def robust_max_deg(self) -> float: ...
    @property
    def robust_alignment(self) -> _FloatArray: ...
    def to_dict(self) -> Dict[str, Any]:
        """The ``accuracy`` object of ``rotavg multiple --ground-truth GT --json``."""
    def to_json(self) -> str: ...

@final
class Result:
    """An estimate with its cost, solver report and certificate."""

    @property
    def problem(self) -> str: ...
    @property
    def estimate(self) -> _FloatArray: ...
    @property
    def cost(self) -> float: ...
    @property
    def chordal_cost(self) -> Optional[float]: ...
    @property
    def inlier_estimate(self) -> Optional[_FloatArray]: ...
    @property
    def num_rotations(self) -> int: ...
    @property
    def num_measurements(self) -> int: ...
    @property
    def solver(self) -> Optional[SolverReport]: ...
    @property
    def certificate(self) -> Optional[Certificate]: ...
    @property
    def verdict(self) -> Optional[str]: ...
    @property
    def accuracy(self) -> Optional[Accuracy]: ...
    @property
    def node_ids(self) -> Optional[npt.NDArray[np.uint64]]: ...
    def to_dict(self) -> Dict[str, Any]:
        """The object ``rotavg SUBCOMMAND --json`` prints."""
    def to_json(self) -> str: ...

@final
class Graph:
    """A view graph read by ``read_graph``; ``n, i, j, rel, weights`` feed ``average_multiple``."""

    @property
    def n(self) -> int: ...
    @property
    def i(self) -> npt.NDArray[np.int64]: ...
    @property
    def j(self) -> npt.NDArray[np.int64]: ...
    @property
    def rel(self) -> _FloatArray: ...
    @property
    def weights(self) -> _FloatArray: ...
    @property
    def node_ids(self) -> npt.NDArray[np.uint64]: ...
    @property
    def initial(self) -> Optional[_FloatArray]: ...
    @property
    def truth(self) -> Optional[_FloatArray]: ...
    @property
    def information(self) -> Optional[_FloatArray]: ...
    @property
    def num_edges(self) -> int: ...
    @property
    def format(self) -> str: ...
    @property
    def warnings(self) -> List[str]: ...
    @property
    def other_components(self) -> List[int]: ...
    @property
    def path(self) -> str: ...
    def __len__(self) -> int: ...

@final
class HandEyeData:
    """Pairs (left[k], right[k]) with right[k] ~ S^-1 left[k] S, from poses or hand-eye files."""

    @property
    def left(self) -> _FloatArray: ...
    @property
    def right(self) -> _FloatArray: ...
    @property
    def weights(self) -> _FloatArray: ...
    @property
    def num_pairs(self) -> int: ...
    @property
    def format(self) -> str: ...
    @property
    def source(self) -> str: ...
    @property
    def motion(self) -> Optional[Dict[str, Any]]: ...
    @property
    def path(self) -> str: ...
    def __len__(self) -> int: ...

def average_single(
    rotations: _Rotations,
    weights: Optional[npt.ArrayLike] = None,
    metric: str = "chordal",
    p: int = 2,
    *,
    rotation_tolerance: float = 1e-5,
    max_seconds: Optional[float] = 600.0,
) -> Result:
    """L^p mean of rotations under the chordal, quaternion or geodesic metric, certified."""

@overload
def average_multiple(
    n: int,
    i: npt.ArrayLike,
    j: npt.ArrayLike,
    rel: _Rotations,
    weights: Optional[npt.ArrayLike] = None,
    loss: str = "auto",
    certify: str = "auto",
    *,
    loss_threshold: Optional[float] = None,
    init: Optional[_Rotations] = None,
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
    randomized: bool = True,
    randomized_seed: Optional[int] = None,
    largest_component: bool = False,
    ground_truth: Optional[npt.ArrayLike] = None,
    information: Optional[npt.ArrayLike] = None,
    rotation_tolerance: float = 1e-5,
    gravity: Union[npt.ArrayLike, str, os.PathLike[str], None] = None,
    world_down: Optional[Sequence[float]] = None,
    init_method: str = "spectral",
    inlier_threshold: Optional[float] = None,
    gravity_weight: Optional[float] = None,
) -> Result:
    """Absolute rotations from relative ones (rel[k] @ R_i = R_j), certified."""

@overload
def average_multiple(
    n: Graph,
    i: None = None,
    j: None = None,
    rel: None = None,
    weights: None = None,
    loss: str = "auto",
    certify: str = "auto",
    *,
    loss_threshold: Optional[float] = None,
    init: Optional[_Rotations] = None,
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
    randomized: bool = True,
    randomized_seed: Optional[int] = None,
    largest_component: bool = False,
    ground_truth: Optional[npt.ArrayLike] = None,
    information: None = None,
    rotation_tolerance: float = 1e-5,
    gravity: Union[npt.ArrayLike, str, os.PathLike[str], None] = None,
    world_down: Optional[Sequence[float]] = None,
    init_method: str = "spectral",
    inlier_threshold: Optional[float] = None,
    gravity_weight: Optional[float] = None,
) -> Result:
    """A graph from ``read_graph``, solved as ``rotavg multiple FILE`` solves it."""

@overload
def certify_multiple(
    n: int,
    i: npt.ArrayLike,
    j: npt.ArrayLike,
    rel: _Rotations,
    estimate: Union[_Rotations, str, os.PathLike[str]],
    weights: Optional[npt.ArrayLike] = None,
    *,
    certify: str = "auto",
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
    randomized: bool = True,
    randomized_seed: Optional[int] = None,
    information: Optional[npt.ArrayLike] = None,
    loss: str = "chordal",
    loss_threshold: float = 5.0,
    inlier_threshold: Optional[float] = None,
    rotation_tolerance: float = 1e-5,
    gravity: Union[npt.ArrayLike, str, os.PathLike[str], None] = None,
    world_down: Optional[Sequence[float]] = None,
    nearest_rotations: bool = False,
    gravity_weight: Optional[float] = None,
) -> Result:
    """Certify an estimate from any other solver, without changing it."""

@overload
def certify_multiple(
    n: Graph,
    i: None = None,
    j: None = None,
    rel: None = None,
    *,
    estimate: Union[_Rotations, str, os.PathLike[str]],
    certify: str = "auto",
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
    randomized: bool = True,
    randomized_seed: Optional[int] = None,
    information: None = None,
    loss: str = "chordal",
    loss_threshold: float = 5.0,
    inlier_threshold: Optional[float] = None,
    rotation_tolerance: float = 1e-5,
    gravity: Union[npt.ArrayLike, str, os.PathLike[str], None] = None,
    world_down: Optional[Sequence[float]] = None,
    nearest_rotations: bool = False,
    gravity_weight: Optional[float] = None,
) -> Result:
    """Certify an estimate for a graph from ``read_graph``."""

@overload
def average_conjugate(
    left: _Rotations,
    right: _Rotations,
    weights: Optional[npt.ArrayLike] = None,
    *,
    metric: str = "chordal",
    loss: str = "l2",
    certify: str = "auto",
    loss_threshold: float = 5.0,
    init: Optional[_Rotation3] = None,
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
    rotation_tolerance: float = 1e-5,
) -> Result:
    """Hand-eye rotation S with right[k] ~ S^-1 left[k] S, certified by a 10x10 SDP."""

@overload
def average_conjugate(
    left: HandEyeData,
    right: None = None,
    weights: None = None,
    *,
    metric: str = "chordal",
    loss: str = "l2",
    certify: str = "auto",
    loss_threshold: float = 5.0,
    init: Optional[_Rotation3] = None,
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
    rotation_tolerance: float = 1e-5,
) -> Result:
    """Pairs from ``hand_eye_pairs`` or ``read_handeye`` (``rotavg conjugate PATH``)."""

@overload
def certify_conjugate(
    left: _Rotations,
    right: _Rotations,
    estimate: Union[_Rotation3, str, os.PathLike[str]],
    weights: Optional[npt.ArrayLike] = None,
    *,
    rotation_tolerance: float = 1e-5,
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
) -> Result:
    """Certify a hand-eye rotation computed elsewhere, without changing it."""

@overload
def certify_conjugate(
    left: HandEyeData,
    right: None = None,
    *,
    estimate: Union[_Rotation3, str, os.PathLike[str]],
    rotation_tolerance: float = 1e-5,
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
) -> Result:
    """Certify a hand-eye rotation (e.g. OpenCV's R_cam2gripper) for ``HandEyeData``."""

def certify_single(
    rotations: _Rotations,
    estimate: Union[_Rotation3, str, os.PathLike[str]],
    weights: Optional[npt.ArrayLike] = None,
    *,
    rotation_tolerance: float = 1e-5,
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
) -> Result:
    """Certify a chordal L2 mean computed elsewhere, without changing it."""

def average_rig(
    right: Graph,
    left: Graph,
    *,
    sensor_from_rig: Optional[npt.ArrayLike] = None,
    loss: str = "auto",
    loss_threshold: Optional[float] = None,
    certify: str = "auto",
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
    gravity: Union[npt.ArrayLike, str, os.PathLike[str], None] = None,
    world_down: Optional[Sequence[float]] = None,
    gravity_weight: Optional[float] = None,
) -> Result:
    """A two-sensor rig's frames and sensor_from_rig, jointly from two view graphs, certified."""

def average_rig_file(
    path: _PathLike,
    *,
    loss: str = "auto",
    loss_threshold: Optional[float] = None,
    certify: str = "auto",
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
    rotation_tolerance: float = 1e-5,
    gravity: Union[npt.ArrayLike, str, os.PathLike[str], None] = None,
    world_down: Optional[Sequence[float]] = None,
    gravity_weight: Optional[float] = None,
    information: str = "auto",
) -> Result:
    """A rig of any number of sensors from a JSON rig file or a COLMAP rig configuration."""

def certify_rig_file(
    path: _PathLike,
    frames: Union[_Rotations, str, os.PathLike[str]],
    sensors_from_rig: Optional[_Rotations] = None,
    *,
    certify: str = "auto",
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
    rotation_tolerance: float = 1e-5,
    gravity: Union[npt.ArrayLike, str, os.PathLike[str], None] = None,
    world_down: Optional[Sequence[float]] = None,
    gravity_weight: Optional[float] = None,
    information: str = "auto",
) -> Result:
    """Certify a rig file's estimate computed elsewhere, without changing it."""

def certify_rig(
    right: Graph,
    left: Graph,
    frames: Union[_Rotations, str, os.PathLike[str]],
    sensor_from_rig: Optional[npt.ArrayLike] = None,
    *,
    certify: str = "auto",
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
    gravity: Union[npt.ArrayLike, str, os.PathLike[str], None] = None,
    world_down: Optional[Sequence[float]] = None,
    gravity_weight: Optional[float] = None,
) -> Result:
    """Certify a rig estimate computed elsewhere, without changing it."""

def read_graph(
    path: _PathLike,
    format: str = "auto",
    weights: str = "file",
    largest_component: bool = False,
    *,
    ground_truth: Optional[_PathLike] = None,
    rotation_tolerance: float = 1e-5,
    information: str = "auto",
) -> Graph:
    """Read a g2o, 1DSfM or JSON view graph with the library's readers."""

def read_ground_truth(path: _PathLike, graph: Graph) -> _FloatArray:
    """Ground truth for a graph's nodes (NaN where unknown), the CLI's --ground-truth formats."""

def set_progress(callback: Optional[Callable[[Dict[str, Any]], object]]) -> None:
    """Receive every following call's progress events (process-wide); None stops it."""

def write_figure(problem: Union[Graph, HandEyeData], result: Result, path: _PathLike) -> None:
    """Write the SVG figure of a result as the command line's ``--plot PATH`` draws it."""

def write_output(result: Result, path: _PathLike) -> None:
    """Write what ``--output`` writes for a single, conjugate or rig result."""

class progress_bar:
    """Show the progress of the calls inside a ``with`` block on one line of stderr."""

    def __init__(self, stream: Optional[TextIO] = None, min_interval: float = 0.1) -> None: ...
    def __enter__(self) -> progress_bar: ...
    def __call__(self, event: Dict[str, Any]) -> None: ...
    def __exit__(self, *exc: object) -> None: ...

def write_edges(graph: Graph, result: Result, path: _PathLike) -> None:
    """Write a robust result's per-edge residuals as ``rotavg multiple --edges-output``."""

def write_estimate(
    graph: Graph, estimate: _Rotations, path: _PathLike, format: str = "auto"
) -> None:
    """Write an estimate of the graph's nodes as ``rotavg multiple --output`` writes it."""

def accuracy(estimate: _Rotations, truth: npt.ArrayLike) -> Accuracy:
    """Angular errors of an estimate against ground truth after the optimal alignment."""

def hand_eye_pairs(
    robot_poses: _Poses,
    camera_poses: _Poses,
    *,
    camera: str = "target2cam",
    pairs: str = "all",
    min_angle: Optional[float] = None,
) -> HandEyeData:
    """Relative motions from absolute poses, formed as OpenCV's calibrateHandEye forms them."""

def hand_eye(
    robot_poses: _Poses,
    camera_poses: _Poses,
    *,
    camera: str = "target2cam",
    pairs: str = "all",
    min_angle: Optional[float] = None,
    metric: str = "chordal",
    loss: str = "l2",
    certify: str = "auto",
    loss_threshold: float = 5.0,
    init: Optional[_Rotation3] = None,
    max_memory: Optional[int] = None,
    max_seconds: Optional[float] = 600.0,
) -> Result:
    """R_cam2gripper from base-from-gripper and camera-from-target poses, certified."""

def read_handeye(
    path: Optional[_PathLike] = None,
    *,
    format: str = "auto",
    hand: Optional[_PathLike] = None,
    camera: Optional[_PathLike] = None,
    stride: Optional[int] = None,
    subsample: Optional[int] = None,
    max_gap: Optional[float] = None,
    time_offset: float = 0.0,
    min_angle: Optional[float] = None,
    quaternion_order: str = "xyzw",
    weights: str = "file",
) -> HandEyeData:
    """Hand-eye pairs from the files ``rotavg conjugate`` reads (JSON, Tabb, pose streams)."""
