"""Every documented call of the rotavg package, typed: `.ci/run` checks this file against the
stubs (python/rotavg/__init__.pyi) with `mypy --strict`, and test_stubs.py runs it (`main()`),
so the calls are also right at run time. The README examples (docs/guides/python.md and
python/README.md) are type-checked and run by test_readme.py; `readme_*` below repeat their
calls with every result's type spelt out.

Run: python python/tests/typecheck_usage.py (prints nothing; raises on a failure).
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path
from typing import Any, Dict, List, Optional

import numpy as np
import numpy.typing as npt
from scipy.spatial.transform import Rotation

import rotavg

FloatArray = npt.NDArray[np.float64]


def rotations(seed: int, n: int) -> FloatArray:
    """`n` random rotations, (n, 3, 3)."""
    matrices: FloatArray = Rotation.random(n, random_state=seed).as_matrix()
    return matrices


def transforms(rot: FloatArray, translations: FloatArray) -> FloatArray:
    """(N, 4, 4) homogeneous transforms."""
    t = np.zeros((len(rot), 4, 4))
    t[:, :3, :3] = rot
    t[:, :3, 3] = translations
    t[:, 3, 3] = 1.0
    return t


def check_certificate(c: Optional[rotavg.Certificate]) -> bool:
    """Every attribute of a Certificate, with its type."""
    assert c is not None
    verdict: str = c.verdict
    certified: bool = c.certified
    upper: float = c.upper_bound
    lower: Optional[float] = c.lower_bound
    gap: Optional[float] = c.gap
    relative: Optional[float] = c.relative_gap
    mu: Optional[float] = c.min_eigenvalue
    method: str = c.method
    allowed: float = c.allowed_gap
    why: str = c.explanation
    seconds: float = c.seconds
    d: Dict[str, Any] = c.to_dict()
    assert verdict == d["verdict"] and upper >= 0 and seconds >= 0 and allowed >= 0
    assert method and why and (lower is None or gap is not None)
    assert relative is None or relative >= -1 and (mu is None or np.isfinite(mu))
    return certified


def check_result(res: rotavg.Result) -> rotavg.Result:
    """Every attribute of a Result (and of its SolverReport), with its type."""
    problem: str = res.problem
    estimate: FloatArray = res.estimate
    cost: float = res.cost
    chordal: Optional[float] = res.chordal_cost
    n: int = res.num_rotations
    m: int = res.num_measurements
    solver: Optional[rotavg.SolverReport] = res.solver
    accuracy: Optional[rotavg.Accuracy] = res.accuracy
    node_ids: Optional[npt.NDArray[np.uint64]] = res.node_ids
    d: Dict[str, Any] = res.to_dict()
    text: str = res.to_json()
    assert d["problem"] == problem and json.loads(text)["cost"] == cost
    assert estimate.shape[-2:] == (3, 3) and n >= 1 and m >= 1
    assert chordal is None or chordal >= 0
    assert accuracy is None or accuracy.num_compared >= 1
    assert node_ids is None or len(node_ids) == n
    if solver is not None:
        name: str = solver.name
        iterations: int = solver.iterations
        termination: str = solver.termination
        detail: str = solver.termination_detail
        converged: bool = solver.converged
        seconds: float = solver.seconds
        sd: Dict[str, Any] = solver.to_dict()
        assert name and iterations >= 0 and termination == sd["termination"]["status"] and detail
        assert seconds >= 0 and isinstance(converged, bool)
    return res


def check_accuracy(a: rotavg.Accuracy) -> float:
    """Every attribute of an Accuracy, with its type."""
    mean: float = a.mean_deg
    median: float = a.median_deg
    rmse: float = a.rmse_deg
    largest: float = a.max_deg
    count: int = a.num_compared
    g: FloatArray = a.alignment
    robust: List[float] = [a.robust_mean_deg, a.robust_median_deg, a.robust_max_deg]
    g1: FloatArray = a.robust_alignment
    d: Dict[str, Any] = a.to_dict()
    text: str = a.to_json()
    assert count == d["num_compared"] and json.loads(text)["max_deg"] == largest
    assert g.shape == g1.shape == (3, 3) and min(robust) >= 0
    assert 0 <= median <= largest and 0 <= mean <= rmse <= largest + 1e-12
    return largest


def check_graph(g: rotavg.Graph) -> int:
    """Every attribute of a Graph, with its type."""
    n: int = g.n
    i: npt.NDArray[np.int64] = g.i
    j: npt.NDArray[np.int64] = g.j
    rel: FloatArray = g.rel
    weights: FloatArray = g.weights
    ids: npt.NDArray[np.uint64] = g.node_ids
    initial: Optional[FloatArray] = g.initial
    truth: Optional[FloatArray] = g.truth
    m: int = g.num_edges
    fmt: str = g.format
    warnings: List[str] = g.warnings
    others: List[int] = g.other_components
    path: str = g.path
    assert len(g) == n == len(ids) and len(i) == len(j) == len(rel) == len(weights) == m
    assert initial is None or len(initial) == n
    assert truth is None or truth.shape == (n, 3, 3)
    assert fmt and path and isinstance(warnings, list) and isinstance(others, list)
    return n


def check_handeye(d: rotavg.HandEyeData) -> int:
    """Every attribute of HandEyeData, with its type."""
    left: FloatArray = d.left
    right: FloatArray = d.right
    weights: FloatArray = d.weights
    count: int = d.num_pairs
    fmt: str = d.format
    source: str = d.source
    motion: Optional[Dict[str, Any]] = d.motion
    path: str = d.path
    assert len(d) == count == len(left) == len(right) == len(weights)
    assert fmt and source and path and (motion is None or motion["pairs"] == count)
    return count


def single() -> None:
    samples = rotations(1, 20)
    weights = np.linspace(1.0, 2.0, 20)
    for metric, p in [("chordal", 2), ("quaternion", 2), ("geodesic", 1), ("chordal", 1)]:
        res = check_result(rotavg.average_single(samples, weights, metric=metric, p=p))
        assert check_certificate(res.certificate)
    res = rotavg.average_single(Rotation.from_matrix(samples))
    same = check_result(rotavg.certify_single(samples, res.estimate))
    same = check_result(rotavg.certify_single(samples, res.estimate, weights=None))
    assert check_certificate(same.certificate)


def graph_arrays() -> tuple[int, FloatArray, npt.NDArray[np.int64], npt.NDArray[np.int64], FloatArray]:
    """A noise-free 10-node view graph: n, truth, i, j, rel (rel[k] @ R_i = R_j)."""
    truth = rotations(2, 10)
    i = np.array([0, 1, 2, 3, 4, 5, 6, 7, 8, 0, 2, 4], dtype=np.int64)
    j = np.array([1, 2, 3, 4, 5, 6, 7, 8, 9, 5, 7, 9], dtype=np.int64)
    rel: FloatArray = truth[j] @ truth[i].transpose(0, 2, 1)
    return 10, truth, i, j, rel


def multiple(folder: Path) -> None:
    n, truth, i, j, rel = graph_arrays()
    res = check_result(rotavg.average_multiple(n, i, j, rel))
    res = check_result(
        rotavg.average_multiple(
            n, i, j, rel, np.ones(len(i)), "chordal", "auto",
            loss_threshold=5.0, init=truth, max_memory=1 << 30, max_seconds=60.0,
            randomized=True, randomized_seed=7, largest_component=False, ground_truth=truth,
        )
    )
    assert res.accuracy is not None and check_accuracy(res.accuracy) < 1e-6
    for loss in ["geodesic", "l1", "huber", "cauchy"]:
        check_result(rotavg.average_multiple(n, i, j, rel, loss=loss, certify="none"))
    cert = check_result(rotavg.certify_multiple(n, i, j, rel, res.estimate))
    cert = check_result(
        rotavg.certify_multiple(
            n, i, j, rel, res.estimate, None, certify="dual", max_memory=None,
            max_seconds=None, randomized=False, randomized_seed=None,
        )
    )
    assert check_certificate(cert.certificate)
    # gravity priors: exact R_i e_3, held; the estimate certified for that problem
    down: FloatArray = truth[:, :, 2].copy()
    grav = check_result(rotavg.average_multiple(n, i, j, rel, gravity=down, world_down=[0.0, 0.0, 1.0]))
    check_result(rotavg.certify_multiple(n, i, j, rel, grav.estimate, gravity=down))
    # files: a view graph and its ground truth
    path = folder / "graph.json"
    edges = [{"i": int(a), "j": int(b), "rotation": r.tolist()} for a, b, r in zip(i, j, rel)]
    path.write_text(json.dumps({"num_rotations": n, "edges": edges}))
    gt = folder / "gt.txt"
    gt.write_text("".join(" ".join(map(repr, t.ravel().tolist())) + "\n" for t in truth))
    g = rotavg.read_graph(path)
    g = rotavg.read_graph(str(path), "auto", "file", False, ground_truth=str(gt))
    g = rotavg.read_graph(path, format="json", weights="unit", largest_component=True,
                          ground_truth=gt)
    check_graph(g)
    # a two-sensor rig: the same graph seen by both sensors (S = I)
    rig = check_result(rotavg.average_rig(g, g, certify="dual", max_seconds=60.0))
    check_result(rotavg.certify_rig(g, g, rig.estimate, np.eye(3), certify="dual"))
    check_result(rotavg.average_rig(g, g, sensor_from_rig=np.eye(3), certify="dual"))
    check_result(rotavg.average_rig_file("examples/data/rig_sensors/rig.json", certify="none", max_seconds=60.0))
    rig_file = rotavg.average_rig_file("examples/data/rig_sensors/rig.json")
    check_result(rotavg.certify_rig_file("examples/data/rig_sensors/rig.json", rig_file.estimate, np.array(rig_file.to_dict()["sensors_from_rig"]), certify="dual"))
    from_graph = check_result(rotavg.average_multiple(g))
    from_graph = check_result(rotavg.average_multiple(g, loss="chordal", certify="auto",
                                                      largest_component=True))
    assert from_graph.accuracy is not None
    check_result(rotavg.certify_multiple(g, estimate=from_graph.estimate))
    check_result(rotavg.certify_multiple(g, estimate=from_graph.estimate, certify="dual"))
    check_result(rotavg.certify_multiple(g, estimate=from_graph.estimate, loss="cauchy",
                                         loss_threshold=5.0, inlier_threshold=None))
    check_graph(rotavg.read_graph(path, rotation_tolerance=1e-4))
    check_result(rotavg.average_multiple(g, rotation_tolerance=1e-4))
    check_result(rotavg.certify_multiple(g, estimate=from_graph.estimate, rotation_tolerance=1e-4))
    seen: List[Dict[str, Any]] = []
    rotavg.set_progress(seen.append)
    rotavg.set_progress(None)
    rotavg.write_estimate(g, from_graph.estimate, folder / "written.json")
    robust = rotavg.average_multiple(g, loss="cauchy")
    inliers: Optional[FloatArray] = robust.inlier_estimate
    if inliers is not None:
        rotavg.write_estimate(g, inliers, folder / "inliers.json")
    rotavg.write_edges(g, robust, folder / "edges.csv")
    rotavg.write_estimate(g, from_graph.estimate, str(folder / "written.g2o"), format="g2o")
    t: FloatArray = rotavg.read_ground_truth(gt, g)
    acc: rotavg.Accuracy = rotavg.accuracy(from_graph.estimate, t)
    check_accuracy(acc)
    check_accuracy(rotavg.accuracy(Rotation.from_matrix(from_graph.estimate), t.tolist()))


def conjugate(folder: Path) -> None:
    s = rotations(3, 1)[0]
    right = rotations(4, 8)
    left: FloatArray = s @ right @ s.T
    res = check_result(rotavg.average_conjugate(left, right))
    res = check_result(
        rotavg.average_conjugate(
            Rotation.from_matrix(left), right, np.ones(8), metric="chordal", loss="l2",
            certify="auto", loss_threshold=5.0, init=s, max_memory=None, max_seconds=None,
        )
    )
    check_result(rotavg.certify_conjugate(left, right, res.estimate))
    check_result(rotavg.certify_conjugate(left, right, Rotation.from_matrix(s), np.ones(8)))
    # hand-eye from absolute poses (OpenCV's setting: gripper2base G, target2cam C)
    g = transforms(rotations(5, 6), np.zeros((6, 3)))
    x = transforms(rotations(6, 1), np.ones((1, 3)))[0]
    c: FloatArray = np.linalg.inv(x) @ np.linalg.inv(g) @ transforms(rotations(7, 1), np.ones((1, 3)))[0]
    data: rotavg.HandEyeData = rotavg.hand_eye_pairs(g, c)
    data = rotavg.hand_eye_pairs(g[:, :3, :3], np.linalg.inv(c), camera="cam2target",
                                 pairs="consecutive", min_angle=0.0)
    check_handeye(data)
    check_result(rotavg.average_conjugate(data))
    check_result(rotavg.average_conjugate(data, metric="geodesic", loss="l1", certify="none"))
    check_result(rotavg.certify_conjugate(data, estimate=x[:3, :3]))
    he = check_result(rotavg.hand_eye(g, c))
    he = check_result(
        rotavg.hand_eye(g, c, camera="target2cam", pairs="all", min_angle=None,
                        metric="chordal", loss="l2", certify="auto", loss_threshold=5.0,
                        init=None, max_memory=None, max_seconds=600.0)
    )
    assert np.abs(he.estimate - x[:3, :3]).max() < 1e-9
    # hand-eye files
    pairs = folder / "pairs.json"
    pairs.write_text(json.dumps({"pairs": [
        {"left": a.tolist(), "right": b.tolist()} for a, b in zip(left, right)
    ]}))
    check_handeye(rotavg.read_handeye(pairs))
    read = rotavg.read_handeye(
        pairs, format="json", hand=None, camera=None, stride=15, subsample=3, max_gap=0.05,
        time_offset=0.0, min_angle=0.5, quaternion_order="xyzw", weights="unit",
    )
    check_result(rotavg.average_conjugate(read))


def errors(folder: Path) -> None:
    n, _, i, j, rel = graph_arrays()
    try:
        rotavg.average_multiple(n + 2, np.append(i, n), np.append(j, n + 1),
                                np.concatenate([rel, rel[:1]]))
    except rotavg.DisconnectedError as e:
        sizes: List[int] = e.component_sizes
        assert sizes == [10, 2]
    else:
        raise AssertionError("a disconnected graph was solved")
    bad = folder / "bad.g2o"
    bad.write_text("EDGE3 0 1 x\n")
    try:
        rotavg.read_graph(bad)
    except rotavg.ParseError as e:
        where: Optional[str] = e.path
        line: Optional[int] = e.line
        assert where == str(bad) and line == 1
    else:
        raise AssertionError("a malformed file was read")
    try:
        rotavg.read_graph(folder / "missing.g2o")
    except rotavg.FileError as e:
        missing: str = e.path
        assert missing.endswith("missing.g2o")
    else:
        raise AssertionError("a missing file was read")
    try:
        z = Rotation.from_rotvec([[0, 0, 0.3], [0, 0, 0.7]]).as_matrix()
        rotavg.average_conjugate(z, z)
    except rotavg.DegenerateError as e:
        assert isinstance(e, rotavg.Error) and isinstance(e, ValueError)
    else:
        raise AssertionError("rotations about one axis determined S")
    exceptions: List[type[rotavg.Error]] = [rotavg.SolverError, rotavg.ParseError]
    assert all(issubclass(cls, ValueError) for cls in exceptions)


def readme_from_python(data: Path) -> None:
    """docs/guides/python.md, with the types spelt out (needs the shared data)."""
    g: rotavg.Graph = rotavg.read_graph(data / "g2o/3d/sesync/sphere2500.g2o")
    res: rotavg.Result = rotavg.average_multiple(g.n, g.i, g.j, g.rel, g.weights)
    assert res.certificate is not None
    theirs: rotavg.Result = rotavg.certify_multiple(g, estimate=res.estimate)
    samples = Rotation.from_matrix(res.estimate[:100])
    ours: rotavg.Result = rotavg.average_single(samples)
    assert theirs.certificate is not None and ours.certificate is not None


def command_line_parity(folder: Path) -> None:
    """Writers, the progress line, tolerances, budgets and estimate files (issue 38)."""
    n, truth, i, j, rel = graph_arrays()
    res = check_result(rotavg.average_multiple(n, i, j, rel, init_method="tree"))
    mirrored: FloatArray = -res.estimate
    check_result(rotavg.certify_multiple(n, i, j, rel, mirrored, nearest_rotations=True))
    path = folder / "parity.json"
    edges = [{"i": int(a), "j": int(b), "rotation": r.tolist()} for a, b, r in zip(i, j, rel)]
    path.write_text(json.dumps({"num_rotations": n, "edges": edges}))
    g = rotavg.read_graph(path, information="kappa")
    robust = check_result(rotavg.average_multiple(g, loss="cauchy", inlier_threshold=3.0))
    rotavg.write_figure(g, robust, folder / "figure.svg")
    with rotavg.progress_bar(min_interval=0.0):
        check_result(rotavg.average_multiple(g))
    samples = rotations(6, 10)
    mean = check_result(rotavg.average_single(samples, rotation_tolerance=1e-4))
    rotavg.write_output(mean, folder / "mean.json")
    check_result(rotavg.certify_single(samples, folder / "mean.json", max_seconds=30.0))
    left, right = rotations(7, 8), rotations(8, 8)
    s = check_result(rotavg.average_conjugate(left, right, rotation_tolerance=1e-4))
    check_result(rotavg.certify_conjugate(left, right, s.estimate, max_memory=1 << 30))
    rig = check_result(rotavg.average_rig(g, g, certify="dual"))
    rotavg.write_output(rig, folder / "rig.json")
    check_result(rotavg.certify_rig(g, g, folder / "rig.json", certify="dual"))
    del truth


def main() -> None:
    version: str = rotavg.__version__
    names: List[str] = rotavg.__all__
    assert version and "hand_eye" in names
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        single()
        multiple(folder)
        conjugate(folder)
        command_line_parity(folder)
        errors(folder)
    # the shared benchmark data, where conftest.py looks for it
    repo = Path(__file__).resolve().parents[2]
    for data in (repo.parent / "shared" / "data", Path("/work/shared/data")):
        if data.is_dir():
            readme_from_python(data)
            break


if __name__ == "__main__":
    main()
