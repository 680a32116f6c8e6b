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
``set_progress(callback)`` receives the progress events of long runs, and ``with
progress_bar(): ...`` shows them on one line of stderr as the command line does;
``write_figure(problem, result, path)`` draws the command line's ``--plot`` figure.
"""

import sys
import time
from typing import Any, Dict, Optional, TextIO

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
    average_rig_file,
    certify_rig_file,
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
    write_figure,
    write_output,
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


class progress_bar:
    """Show the progress of every call inside a ``with`` block on one line of ``stream``
    (default ``sys.stderr``), as the command line's progress line does: each event's
    ``message`` (phase, iteration, proof, predicted time), rewritten in place at most every
    ``min_interval`` seconds; the line is cleared when the block ends. It installs itself with
    ``set_progress`` (process-wide) and removes itself on exit (``set_progress(None)``).

    >>> import numpy as np, rotavg
    >>> with rotavg.progress_bar():
    ...     res = rotavg.average_single(np.eye(3)[None].repeat(3, axis=0))
    >>> res.certificate.certified
    True
    """

    def __init__(self, stream: Optional[TextIO] = None, min_interval: float = 0.1) -> None:
        self.stream = stream
        self.min_interval = min_interval
        self._last = float("-inf")
        self._width = 0

    def __enter__(self) -> "progress_bar":
        set_progress(self)
        return self

    def __call__(self, event: Dict[str, Any]) -> None:
        now = time.monotonic()
        if now - self._last < self.min_interval:
            return
        self._last = now
        line = str(event.get("message", ""))[:120]
        self._write("\r" + line.ljust(self._width))
        self._width = len(line)

    def __exit__(self, *exc: object) -> None:
        set_progress(None)
        if self._width:
            self._write("\r" + " " * self._width + "\r")
            self._width = 0

    def _write(self, text: str) -> None:
        out = self.stream if self.stream is not None else sys.stderr
        out.write(text)
        out.flush()
