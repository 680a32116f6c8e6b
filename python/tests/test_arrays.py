"""numpy in and out: dtypes, layouts and array-likes accepted; arrays returned; error messages
for bad shapes, NaN, non-rotations, indices out of range and bad names."""

import re

import numpy as np
import pytest

import rotavg
from conftest import random_rotations, small_rotations, synthetic_graph

I3 = np.eye(3)


def triangle():
    """A noise-free triangle: n, i, j, rel with rel[k] @ R_i = R_j."""
    rng = np.random.default_rng(3)
    truth = random_rotations(rng, 3)
    i, j = np.array([0, 1, 2]), np.array([1, 2, 0])
    return 3, i, j, truth[j] @ truth[i].transpose(0, 2, 1)


def test_estimate_round_trip_and_layout(rng):
    truth, i, j, rel = synthetic_graph(rng, 30, 90, 0.0)
    res = rotavg.average_multiple(30, i, j, rel)
    est = res.estimate
    assert est.dtype == np.float64 and est.shape == (30, 3, 3)
    assert est.flags.c_contiguous and est.flags.writeable
    # Gauge R_0 = I; the estimate is the truth up to R_i -> R_i G.
    assert np.allclose(est[0], I3, atol=1e-12)
    aligned = truth @ truth[0].T
    assert np.allclose(est, aligned, atol=1e-8)
    # Feeding the estimate back: certify returns it as given.
    cert = rotavg.certify_multiple(30, i, j, rel, est)
    assert np.allclose(cert.estimate, est, atol=1e-15)
    assert cert.certificate.certified


def test_dtypes_layouts_and_lists_give_the_same_answer(rng):
    truth, i, j, rel = synthetic_graph(rng, 20, 60, 0.02)
    reference = rotavg.average_multiple(20, i, j, rel).estimate
    fortran = np.asfortranarray(rel)
    strided = np.repeat(rel, 2, axis=0)[::2]  # a non-contiguous view holding rel
    assert not strided.flags.c_contiguous
    variants = [
        (i.astype(np.int32), j.astype(np.uint16), rel),
        (i.tolist(), j.tolist(), rel.tolist()),
        (i, j, fortran),
        (i, j, strided),
    ]
    for a, b, r in variants:
        est = rotavg.average_multiple(np.int64(20), a, b, r).estimate
        assert np.allclose(est, reference, atol=1e-12)


def test_scipy_rotations_as_edges(rng):
    Rotation = pytest.importorskip("scipy.spatial.transform").Rotation
    _, i, j, rel = synthetic_graph(rng, 10, 25, 0.01)
    # from_matrix re-orthonormalises (to rounding), so the answers agree to rounding.
    a = rotavg.average_multiple(10, i, j, Rotation.from_matrix(rel))
    b = rotavg.average_multiple(10, i, j, rel)
    assert np.allclose(a.estimate, b.estimate, atol=1e-10)


def test_graph_arrays_are_read_only(tmp_path):
    path = tmp_path / "triangle.g2o"
    path.write_text("EDGE3 0 1 0 0 0 0 0 0.1\nEDGE3 1 2 0 0 0 0 0 0.2\nEDGE3 2 0 0 0 0 0 0 -0.25\n")
    g = rotavg.read_graph(path)
    assert (g.n, g.num_edges, g.format, len(g)) == (3, 3, "g2o", 3)
    assert g.i.dtype == np.int64 and g.rel.shape == (3, 3, 3) and g.weights.shape == (3,)
    with pytest.raises(ValueError):
        g.rel[0, 0, 0] = 2.0
    assert "triangle.g2o" in repr(g)


def error(match, f, *args, **kwargs):
    with pytest.raises(rotavg.Error, match=match) as info:
        f(*args, **kwargs)
    assert isinstance(info.value, ValueError)
    return str(info.value)


def test_bad_shapes():
    n, i, j, rel = triangle()
    error(re.escape("rel must have shape (N, 3, 3), got (3, 3)"), rotavg.average_multiple, n, i, j, rel[0])
    error(re.escape("got (3, 3, 4)"), rotavg.average_multiple, n, i, j, np.zeros((3, 3, 4)))
    error("one entry per edge: got 2, 3 and 3", rotavg.average_multiple, n, i[:2], j, rel)
    error(re.escape("weights must have shape (3,), got (2,)"), rotavg.average_multiple, n, i, j, rel, [1, 1])
    error(re.escape("i must be a 1-D array"), rotavg.average_multiple, n, i[None, :], j, rel)
    error(re.escape("rotations must have shape (N, 3, 3), got (3, 3)"), rotavg.average_single, I3)
    error(re.escape("estimate must have shape (3, 3)"), rotavg.certify_single, [I3], [I3, I3])
    error("left and right must have one rotation per pair", rotavg.average_conjugate, [I3], [I3, I3])
    error("a view graph needs n, i, j and rel", rotavg.average_multiple, 3)
    error("needs an estimate", rotavg.certify_multiple, n, i, j, rel)


def test_nan_and_non_rotations_name_the_item():
    n, i, j, rel = triangle()
    bad = rel.copy()
    bad[2, 1, 1] = np.nan
    error(re.escape("rel[2] contains NaN or infinity"), rotavg.average_multiple, n, i, j, bad)
    bad = rel.copy()
    bad[1] *= 1.01
    error(re.escape("rel[1] is not a rotation"), rotavg.average_multiple, n, i, j, bad)
    reflection = np.diag([1.0, 1.0, -1.0])
    msg = error(re.escape("rotations[1] is not a rotation"), rotavg.average_single, [I3, reflection])
    assert "det = -1" in msg
    error("weight", rotavg.average_single, [I3, I3], [1.0, -2.0])
    error("weight", rotavg.average_multiple, n, i, j, rel, [1.0, np.inf, 1.0])
    error(re.escape("estimate[0] contains NaN"), rotavg.certify_multiple, n, i, j, rel, np.full((3, 3, 3), np.nan))
    error(re.escape("the estimate has 2 rotations, the problem has 3 nodes"), rotavg.certify_multiple, n, i, j, rel, rel[:2])
    error("expected real numbers", rotavg.average_single, [[["a"] * 3] * 3])


def test_indices_out_of_range_self_loops_and_types():
    n, i, j, rel = triangle()
    error(re.escape("edge 1 refers to node 7, but there are only 3 nodes (0..3)"),
          rotavg.average_multiple, n, i, np.array([1, 7, 0]), rel)
    error(re.escape("edge 0 refers to node -1"), rotavg.average_multiple, n, np.array([-1, 1, 2]), j, rel)
    error("self loop", rotavg.average_multiple, n, np.array([0, 2, 2]), j, rel)
    error("expected integers", rotavg.average_multiple, n, i.astype(float), j, rel)
    error("n must be an integer", rotavg.average_multiple, "three", i, j, rel)
    error("not connected", rotavg.average_multiple, 5, i, j, rel)
    error("3 edges touch at most 6 nodes", rotavg.average_multiple, 10**12, i, j, rel)
    error("n = -1 is negative|is negative", rotavg.average_multiple, -1, i, j, rel)


def test_graph_or_arrays_not_both(tmp_path):
    path = tmp_path / "chain.g2o"
    path.write_text("EDGE3 0 1 0 0 0 0 0 0.1\nEDGE3 1 2 0 0 0 0 0 0.2\n")
    g = rotavg.read_graph(path)
    error("pass either a Graph", rotavg.average_multiple, g, g.i, g.j, g.rel)


def test_bad_names():
    n, i, j, rel = triangle()
    error("unknown name `euclid`", rotavg.average_single, [I3], metric="euclid")
    error("p must be 1 or 2", rotavg.average_single, [I3], p=3)
    error("unknown name `l3`", rotavg.average_multiple, n, i, j, rel, loss="l3")
    error("certify", rotavg.average_multiple, n, i, j, rel, certify="maybe")
    error("does not apply to conjugate", rotavg.average_conjugate, rel, rel, certify="dual")


def test_file_errors_name_file_and_line(tmp_path):
    missing = tmp_path / "missing.g2o"
    error(re.escape(str(missing)), rotavg.read_graph, missing)
    bad = tmp_path / "bad.g2o"
    bad.write_text("EDGE3 0 1 0 0 0 0 0 0.1\nEDGE3 1 2 0 0 zz 0 0 0.2\n")
    msg = error("bad.g2o:2:", rotavg.read_graph, bad)
    assert "zz" in msg


def test_reprs_docstrings_and_dicts(rng):
    _, i, j, rel = synthetic_graph(rng, 10, 30, 0.01)
    res = rotavg.average_multiple(10, i, j, rel)
    assert repr(res).startswith("Result(problem='multiple', estimate=<array (10, 3, 3)>, cost=")
    assert repr(res.certificate).startswith("Certificate(verdict='certified', upper_bound=")
    assert repr(res.solver).startswith("SolverReport(name='riemannian-newton-lm', iterations=")
    assert str(res).startswith("<arrays>: json format, 10 nodes, 30 edges")
    d = res.to_dict()
    assert d["certificate"] == res.certificate.to_dict() and d["solver"] == res.solver.to_dict()
    assert res.to_json().startswith('{"problem":"multiple","num_rotations":10,')
    for key in ["verdict", "upper_bound", "lower_bound", "gap", "relative_gap", "method", "seconds"]:
        assert key in d["certificate"]
    for name in rotavg.__all__:
        if name != "__version__":
            assert getattr(rotavg, name).__doc__, name
