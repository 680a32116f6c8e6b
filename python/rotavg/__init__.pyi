"""Type stubs of rotavg (the compiled module rotavg._rotavg, re-exported by the package)."""

import os
from typing import Any, Dict, List, Optional, Protocol, Union, overload

import numpy as np
import numpy.typing as npt

__version__: str

class _HasAsMatrix(Protocol):
    def as_matrix(self) -> npt.ArrayLike: ...

#: (N, 3, 3) rotation matrices: an array-like or a scipy.spatial.transform.Rotation.
Rotations = Union[npt.ArrayLike, _HasAsMatrix]
#: One (3, 3) rotation matrix (or a single scipy Rotation).
Rotation3 = Union[npt.ArrayLike, _HasAsMatrix]
FloatArray = npt.NDArray[np.float64]

class Error(ValueError):
    """Bad input or settings; the message is the library's (item, file and line)."""

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

class Result:
    """An estimate with its cost, solver report and certificate."""

    @property
    def problem(self) -> str: ...
    @property
    def estimate(self) -> FloatArray: ...
    @property
    def cost(self) -> float: ...
    @property
    def chordal_cost(self) -> Optional[float]: ...
    @property
    def num_rotations(self) -> int: ...
    @property
    def num_measurements(self) -> int: ...
    @property
    def solver(self) -> Optional[SolverReport]: ...
    @property
    def certificate(self) -> Optional[Certificate]: ...
    def to_dict(self) -> Dict[str, Any]:
        """The object ``rotavg SUBCOMMAND --json`` prints."""
    def to_json(self) -> str: ...

class Graph:
    """A view graph read by ``read_graph``; ``n, i, j, rel, weights`` feed ``average_multiple``."""

    @property
    def n(self) -> int: ...
    @property
    def i(self) -> npt.NDArray[np.int64]: ...
    @property
    def j(self) -> npt.NDArray[np.int64]: ...
    @property
    def rel(self) -> FloatArray: ...
    @property
    def weights(self) -> FloatArray: ...
    @property
    def node_ids(self) -> npt.NDArray[np.uint64]: ...
    @property
    def initial(self) -> Optional[FloatArray]: ...
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

def average_single(
    rotations: Rotations,
    weights: Optional[npt.ArrayLike] = None,
    metric: str = "chordal",
    p: int = 2,
) -> Result:
    """L^p mean of rotations under the chordal, quaternion or geodesic metric, certified."""

@overload
def average_multiple(
    n: int,
    i: npt.ArrayLike,
    j: npt.ArrayLike,
    rel: Rotations,
    weights: Optional[npt.ArrayLike] = None,
    loss: str = "chordal",
    certify: str = "auto",
    *,
    loss_threshold: float = 5.0,
    init: Optional[Rotations] = None,
) -> Result: ...
@overload
def average_multiple(
    n: Graph,
    *,
    loss: str = "chordal",
    certify: str = "auto",
    loss_threshold: float = 5.0,
    init: Optional[Rotations] = None,
) -> Result: ...
@overload
def certify_multiple(
    n: int,
    i: npt.ArrayLike,
    j: npt.ArrayLike,
    rel: Rotations,
    estimate: Rotations,
    weights: Optional[npt.ArrayLike] = None,
    *,
    certify: str = "auto",
) -> Result: ...
@overload
def certify_multiple(n: Graph, *, estimate: Rotations, certify: str = "auto") -> Result: ...
def average_conjugate(
    left: Rotations,
    right: Rotations,
    weights: Optional[npt.ArrayLike] = None,
    *,
    metric: str = "chordal",
    loss: str = "l2",
    certify: str = "auto",
    loss_threshold: float = 5.0,
) -> Result:
    """Hand-eye rotation S with right[k] ~ S^-1 left[k] S, certified by a 10x10 SDP."""

def certify_conjugate(
    left: Rotations,
    right: Rotations,
    estimate: Rotation3,
    weights: Optional[npt.ArrayLike] = None,
) -> Result:
    """Certify a hand-eye rotation computed elsewhere, without changing it."""

def certify_single(
    rotations: Rotations,
    estimate: Rotation3,
    weights: Optional[npt.ArrayLike] = None,
) -> Result:
    """Certify a chordal L2 mean computed elsewhere, without changing it."""

def read_graph(
    path: Union[str, "os.PathLike[str]"],
    format: str = "auto",
    weights: str = "file",
    largest_component: bool = False,
) -> Graph:
    """Read a g2o, 1DSfM or JSON view graph with the library's readers."""
