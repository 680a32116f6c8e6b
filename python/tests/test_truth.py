"""Ground truth and accuracy from Python: the command line's --ground-truth readers, the
accuracy report against an independent numpy computation, and the same `accuracy` object as
`rotavg multiple FILE --ground-truth GT --json`."""

import json

import numpy as np
import pytest

import rotavg
from conftest import synthetic_graph, untimed

Rotation = pytest.importorskip("scipy.spatial.transform").Rotation


def write_graph(path, n, i, j, rel):
    """The JSON problem format (rotation = R_ij with R_ij R_i = R_j)."""
    edges = [
        {"i": int(a), "j": int(b), "rotation": r.tolist()} for a, b, r in zip(i, j, rel)
    ]
    path.write_text(json.dumps({"num_rotations": n, "edges": edges}))


def rotation_list(truth, unknown=()):
    """A rotation list: 9 numbers per line, line k = node k, 9 zeros where unknown."""
    rows = [
        " ".join(["0"] * 9) if k in unknown else " ".join(repr(float(v)) for v in t.ravel())
        for k, t in enumerate(truth)
    ]
    return "\n".join(rows) + "\n"


def g2o_vertices(truth):
    """g2o vertex lines: W_k = R_k^T (world-from-body), quaternion x y z w (and a chain of
    edges, which a g2o file must have; their values do not matter here)."""
    q = Rotation.from_matrix(truth.transpose(0, 2, 1)).as_quat()
    vertices = "".join(
        f"VERTEX_SE3:QUAT {k} 0 0 0 " + " ".join(repr(float(v)) for v in qk) + "\n"
        for k, qk in enumerate(q)
    )
    edges = "".join(f"EDGE3 {k} {k + 1} 0 0 0 0 0 0\n" for k in range(len(truth) - 1))
    return vertices + edges


def aligned_errors_deg(estimate, truth):
    """Independent accuracy: G = SVD projection of sum_k R_k^T T_k (det-corrected), errors
    theta(R_k G, T_k) in degrees."""
    m = np.einsum("kji,kjl->il", estimate, truth)
    u, _, vt = np.linalg.svd(m)
    d = np.diag([1.0, 1.0, np.sign(np.linalg.det(u @ vt))])
    g = u @ d @ vt
    diff = (estimate @ g).transpose(0, 2, 1) @ truth
    cos = np.clip((np.trace(diff, axis1=1, axis2=2) - 1) / 2, -1, 1)
    return np.degrees(np.arccos(cos)), g


@pytest.fixture
def graph_files(rng, tmp_path):
    truth, i, j, rel = synthetic_graph(rng, 30, 90, 0.02)
    path = tmp_path / "graph.json"
    write_graph(path, 30, i, j, rel)
    return truth, i, j, rel, path


def test_ground_truth_formats_read_the_same_rotations(graph_files, tmp_path):
    truth, _, _, _, path = graph_files
    g = rotavg.read_graph(path)
    files = {
        "gt.txt": rotation_list(truth),
        "gt.g2o": g2o_vertices(truth),
        "gt.json": json.dumps({"rotations": truth.tolist()}),
    }
    for name, text in files.items():
        (tmp_path / name).write_text(text)
        read = rotavg.read_ground_truth(tmp_path / name, g)
        assert read.shape == (30, 3, 3) and read.dtype == np.float64
        assert np.allclose(read, truth, atol=1e-9), name
    # unknown rotations (9 zeros) are NaN
    (tmp_path / "partial.txt").write_text(rotation_list(truth, unknown={3, 7}))
    partial = rotavg.read_ground_truth(tmp_path / "partial.txt", g)
    known = ~np.isnan(partial).any(axis=(1, 2))
    assert known.sum() == 28 and not known[3] and not known[7]
    assert np.isnan(partial[3]).all()


def test_accuracy_against_an_independent_computation(graph_files, tmp_path):
    truth, i, j, rel, path = graph_files
    res = rotavg.average_multiple(30, i, j, rel)
    acc = rotavg.accuracy(res.estimate, truth)
    errors, g = aligned_errors_deg(res.estimate, truth)
    assert acc.num_compared == 30
    assert acc.mean_deg == pytest.approx(errors.mean(), abs=1e-9)
    assert acc.max_deg == pytest.approx(errors.max(), abs=1e-9)
    assert acc.median_deg == pytest.approx(np.median(errors), abs=1e-9)
    assert acc.rmse_deg == pytest.approx(np.sqrt(np.mean(errors**2)), abs=1e-9)
    assert np.allclose(acc.alignment, g, atol=1e-9)
    assert acc.robust_median_deg <= acc.max_deg and acc.robust_alignment.shape == (3, 3)
    d = acc.to_dict()
    assert d["num_compared"] == 30 and d["robust"]["median_deg"] == acc.robust_median_deg
    assert str(acc).startswith("accuracy vs ground truth (30 nodes, after global alignment)")
    # a gauge change of the estimate changes nothing; a node without truth is skipped
    g0 = Rotation.from_rotvec([0.3, -1.0, 2.0]).as_matrix()
    assert rotavg.accuracy(res.estimate @ g0, truth).max_deg == pytest.approx(acc.max_deg, abs=1e-9)
    partial = truth.copy()
    partial[4] = np.nan
    assert rotavg.accuracy(res.estimate, partial).num_compared == 29


def test_same_accuracy_as_the_command_line(graph_files, tmp_path, cli):
    truth, i, j, rel, path = graph_files
    gt = tmp_path / "gt.txt"
    gt.write_text(rotation_list(truth, unknown={5}))
    g = rotavg.read_graph(path, ground_truth=gt)
    assert g.truth is not None and np.isnan(g.truth[5]).all()
    res = rotavg.average_multiple(g)
    assert res.accuracy is not None and res.accuracy.num_compared == 29
    theirs = cli("multiple", path, "--ground-truth", gt)
    assert untimed(res.to_dict()) == untimed(theirs)
    assert res.accuracy.to_dict() == theirs["accuracy"]
    # the same report from the arrays, from accuracy(), and from read_ground_truth
    again = rotavg.average_multiple(g.n, g.i, g.j, g.rel, g.weights, ground_truth=g.truth)
    for key in ["mean_deg", "median_deg", "rmse_deg", "max_deg"]:
        assert getattr(again.accuracy, key) == pytest.approx(getattr(res.accuracy, key), abs=1e-9)
    direct = rotavg.accuracy(res.estimate, rotavg.read_ground_truth(gt, g))
    assert direct.to_dict() == res.accuracy.to_dict()
    # no ground truth: no accuracy
    assert rotavg.average_multiple(30, i, j, rel).accuracy is None


def test_largest_component_keeps_the_truth_of_its_nodes(rng, tmp_path, cli):
    truth, i, j, rel = synthetic_graph(rng, 20, 50, 0.01)
    # two extra nodes 20, 21 joined to each other only
    extra = Rotation.from_rotvec([[0.1, 0.2, 0.3], [0.0, 1.0, 0.0]]).as_matrix()
    truth = np.concatenate([truth, extra])
    i, j = np.append(i, 20), np.append(j, 21)
    rel = np.concatenate([rel, [extra[1] @ extra[0].T]])
    path = tmp_path / "two.json"
    write_graph(path, 22, i, j, rel)
    gt = tmp_path / "gt.json"
    gt.write_text(json.dumps({"rotations": truth.tolist()}))
    with pytest.raises(rotavg.DisconnectedError) as info:
        rotavg.average_multiple(rotavg.read_graph(path))
    assert info.value.component_sizes == [20, 2]
    g = rotavg.read_graph(path, largest_component=True, ground_truth=gt)
    assert g.n == 20 and g.other_components == [2]
    assert np.allclose(g.truth, truth[:20], atol=1e-12)
    assert np.allclose(rotavg.read_ground_truth(gt, g), truth[:20], atol=1e-12)
    res = rotavg.average_multiple(g)
    theirs = cli("multiple", path, "--largest-component", "--ground-truth", gt)
    assert untimed(res.to_dict()) == untimed(theirs)
    # arrays: largest_component=True, ground truth for every node of the arrays
    arrays = rotavg.average_multiple(22, i, j, rel, largest_component=True, ground_truth=truth)
    assert list(arrays.node_ids) == list(range(20))
    assert arrays.to_dict()["other_components"] == [2]
    assert arrays.accuracy.max_deg == pytest.approx(res.accuracy.max_deg, abs=1e-9)


def test_ground_truth_errors(graph_files, tmp_path):
    truth, i, j, rel, path = graph_files
    g = rotavg.read_graph(path)
    with pytest.raises(rotavg.FileError) as info:
        rotavg.read_ground_truth(tmp_path / "missing.txt", g)
    assert info.value.path.endswith("missing.txt")
    short = tmp_path / "short.json"
    short.write_text(json.dumps({"rotations": truth[:5].tolist()}))
    with pytest.raises(rotavg.ParseError, match="ground truth has 5 rotations, the graph has 30 nodes"):
        rotavg.read_graph(path, ground_truth=short)
    with pytest.raises(rotavg.Error, match="one rotation per node: got 30 and 5"):
        rotavg.accuracy(truth, truth[:5])
    with pytest.raises(rotavg.Error, match="no node has one"):
        rotavg.accuracy(truth, np.full_like(truth, np.nan))
    half = truth.copy()
    half[2, 0, 0] = np.nan
    with pytest.raises(rotavg.Error, match=r"truth\[2\] contains NaN"):
        rotavg.accuracy(truth, half)
    with pytest.raises(rotavg.Error, match="`ground_truth`: 4 rotations given for 30 nodes"):
        rotavg.average_multiple(30, i, j, rel, ground_truth=truth[:4])
