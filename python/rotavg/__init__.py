"""rotavg: certifiably optimal rotation averaging, with numpy in and out.

Three problems (Hartley, Trumpf, Dai & Li, "Rotation Averaging", IJCV 2013):

* ``average_single(rotations, weights=None, metric="chordal", p=2)``: the L^p mean of rotations;
* ``average_multiple(n, i, j, rel, weights=None, loss="chordal", certify="auto")``: absolute
  rotations ``R_0..R_{n-1}`` from relative ones, ``rel[k] @ R_i = R_j`` for edge
  ``(i[k], j[k])``; ``certify_multiple(...)`` certifies an estimate from any other solver;
* ``average_conjugate(left, right, weights=None)``: hand-eye ``S`` with ``right[k] ~ S^-1 left[k] S``;
  ``certify_conjugate(...)`` certifies an ``S`` from elsewhere; ``hand_eye(robot_poses,
  camera_poses)`` forms the pairs from absolute poses as OpenCV's ``calibrateHandEye`` does.

Rotations are float64 arrays of shape ``(N, 3, 3)`` (a ``scipy.spatial.transform.Rotation`` is
accepted wherever rotations are). Files are read with the command line's readers:
``read_graph(path)`` (g2o, 1DSfM and JSON view graphs), ``read_ground_truth(path, graph)`` and
``read_handeye(path)`` (conjugate JSON, Tabb, ETH / motion-capture pose streams), and written
with its writers: ``write_estimate(graph, estimate, path)`` (JSON, g2o, a COLMAP model, as
``rotavg multiple --output``) and ``write_edges(graph, result, path)`` (``--edges-output``);
``accuracy`` compares an estimate with ground truth. Every solver call returns a ``Result`` with the
estimate, its cost, the solver's report and a ``Certificate`` (a proven lower bound on the
global minimum and the gap to it); ``to_dict()`` is the object the ``rotavg`` command line
prints with ``--json``. Bad input raises ``rotavg.Error`` (a ``ValueError``) or one of its
subclasses (``ParseError``, ``FileError``, ``DisconnectedError``, ``DegenerateError``,
``SolverError``) with the library's message. The GIL is released while solving;
``set_progress(callback)`` receives the progress events of long runs.
"""

from ._rotavg import (
    Accuracy,
    Certificate,
    DegenerateError,
    DisconnectedError,
    Error,
    FileError,
    Graph,
    HandEyeData,
    ParseError,
    Result,
    SolverError,
    SolverReport,
    __version__,
    accuracy,
    average_conjugate,
    average_multiple,
    average_rig,
    average_single,
    certify_conjugate,
    certify_multiple,
    certify_rig,
    certify_single,
    hand_eye,
    hand_eye_pairs,
    read_graph,
    read_ground_truth,
    read_handeye,
    set_progress,
    write_edges,
    write_estimate,
)

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
]
