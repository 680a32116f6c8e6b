"""Multiple rotation averaging: planted solutions, certificates, the GIL, and the same costs and
certificates as the `rotavg` command line on the shared benchmark graphs."""

import json
import threading
import time

import numpy as np
import pytest

import rotavg
from conftest import synthetic_graph, untimed

#: Shared graphs (relative to the data folder) compared with the command line.
SHARED_GRAPHS = [
    "g2o/3d/sesync/tinyGrid3D.g2o",
    "g2o/3d/sesync/smallGrid3D.g2o",
    "g2o/3d/sesync/sphere2500.g2o",
    "g2o/3d/sesync/parking-garage.g2o",
    "g2o/3d/gtsam/Klaus3.g2o",
    "1dsfm/Madrid_Metropolis/EGs.txt",
]


def test_noise_free_graph_is_solved_exactly_and_certified(rng):
    truth, i, j, rel = synthetic_graph(rng, 40, 120, 0.0)
    res = rotavg.average_multiple(40, i, j, rel)
    assert res.cost < 1e-20 and res.chordal_cost < 1e-20
    assert res.certificate.certified
    assert np.allclose(res.estimate, truth @ truth[0].T, atol=1e-9)


def test_linear_algebra_counts_are_reported(rng):
    # a small graph: the direct solver, one numeric factorisation per Newton step at most
    # (the LM damping may refactorise), no CG; a robust loss reports none
    truth, i, j, rel = synthetic_graph(rng, 40, 120, 0.01)
    d = rotavg.average_multiple(40, i, j, rel).to_dict()
    la = d["linear_algebra"]
    assert la["solver"] == "sparse Cholesky"
    assert la["cg_iterations"] == 0
    assert 1 <= la["numeric_factorizations"] and la["symbolic_analyses"] == 2
    assert d["solver"]["iterations"] <= la["numeric_factorizations"] + 1
    assert rotavg.average_multiple(40, i, j, rel, loss="huber").to_dict()["linear_algebra"] is None


def test_budget_and_randomized_bound(rng):
    # no factorisation fits 1 KiB: inconclusive, with the Monte Carlo bound [D16] beside it
    _, i, j, rel = synthetic_graph(rng, 40, 120, 0.05)
    best = rotavg.average_multiple(40, i, j, rel)
    res = rotavg.certify_multiple(40, i, j, rel, best.estimate, max_memory=1024, randomized_seed=9)
    c = res.to_dict()["certificate"]
    assert c["verdict"] == "inconclusive" and c["lower_bound"] is None
    r = c["randomized"]
    assert r["seed"] == 9 and r["within_tolerance"] and r["failure_probability"] <= 1e-12
    assert r["lower_bound"] <= best.chordal_cost
    assert r["lower_bound"] == pytest.approx(best.certificate.lower_bound, rel=1e-6)
    off = rotavg.average_multiple(40, i, j, rel, max_memory=1024, randomized=False).to_dict()
    assert off["certificate"]["verdict"] == "inconclusive"
    assert "randomized" not in off["certificate"]
    with pytest.raises(rotavg.Error, match="max_memory|max_seconds"):
        rotavg.average_multiple(40, i, j, rel, max_seconds=-1.0)


def test_cost_convention_rel_times_r_i_is_r_j(rng):
    truth, i, j, rel = synthetic_graph(rng, 25, 70, 0.05)
    w = rng.uniform(0.5, 2.0, size=len(i))
    res = rotavg.average_multiple(25, i, j, rel, w)
    r = res.estimate
    cost = np.sum(w * np.sum((r[j] - rel @ r[i]) ** 2, axis=(1, 2)))
    assert res.chordal_cost == pytest.approx(cost, rel=1e-10)
    c = res.certificate
    assert c.certified and c.lower_bound <= c.upper_bound + c.allowed_gap
    assert c.upper_bound == pytest.approx(res.chordal_cost, rel=1e-12)
    assert c.gap == pytest.approx(c.upper_bound - c.lower_bound)


def test_certify_an_estimate_from_elsewhere(rng):
    _, i, j, rel = synthetic_graph(rng, 30, 90, 0.05)
    best = rotavg.average_multiple(30, i, j, rel)
    # Same estimate in another gauge: same cost, certified.
    g = rotavg.average_single(rel[:1]).estimate
    res = rotavg.certify_multiple(30, i, j, rel, best.estimate @ g)
    assert res.certificate.certified and res.solver is None
    assert res.cost == pytest.approx(best.chordal_cost, rel=1e-9)
    # A corrupted estimate: never certified, its gap bounded by a valid lower bound.
    bad = best.estimate.copy()
    bad[5] = bad[5] @ np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]])
    res = rotavg.certify_multiple(30, i, j, rel, bad, certify="dual")
    assert not res.certificate.certified
    lb = res.certificate.lower_bound
    assert lb is None or lb <= best.chordal_cost * (1 + 1e-9)


def test_robust_losses_have_no_certificate(rng):
    _, i, j, rel = synthetic_graph(rng, 20, 60, 0.02)
    for loss in ["geodesic", "l1", "huber", "cauchy"]:
        res = rotavg.average_multiple(20, i, j, rel, loss=loss)
        assert res.certificate is None and res.to_dict()["loss"] == loss
    res = rotavg.average_multiple(20, i, j, rel, certify="none")
    assert res.certificate is None and res.to_dict()["certificate"] is None


def test_robust_losses_report_inliers_and_certify_the_inlier_graph(rng):
    truth, i, j, rel = synthetic_graph(rng, 30, 150, 0.01)
    bad = np.array([0, 7, 19])  # three edges replaced by a 90-degree turn about z
    rel = rel.copy()
    rel[bad] = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]) @ rel[bad]
    for loss in ["l1", "huber", "cauchy"]:
        d = rotavg.average_multiple(30, i, j, rel, loss=loss).to_dict()
        rob = d["robust"]
        assert d["certificate"] is None and rob["reported_estimate"] == "robust"
        assert (rob["num_inliers"], rob["num_outliers"]) == (147, 3)
        cert = rob["inlier_graph"]["certificate"]
        assert cert["verdict"] == "certified"
        assert cert["certified_problem"]["kind"] == "chordal_l2_inliers"
        assert cert["certified_problem"]["num_edges"] == 147
    d = rotavg.average_multiple(30, i, j, rel, loss="huber", certify="none").to_dict()
    assert d["robust"]["inlier_graph"] is None and d["robust"]["num_outliers"] == 3
    # the default loss follows the data: the residuals of least squares show the three outliers,
    # so the run is the Cauchy run, and its verdict is the inlier graph's, named
    res = rotavg.average_multiple(30, i, j, rel)
    d = res.to_dict()
    assert d["loss"] == "cauchy" and d["pipeline"]["loss_choice"]["diagnosis"]["suspected"] >= 3
    # its Cauchy scale follows the data: 1.5 times the median residual at the L1 solution, the
    # inlier threshold 3 times (0.01 rad of noise per axis: the median inlier angle about 0.88 deg)
    scale = d["pipeline"]["loss_choice"]["scale"]
    assert 1.0 < scale["scale_deg"] < 1.6 and scale["scale_deg"] == d["pipeline"]["loss_choice"]["chosen"]["loss"]["scale_deg"]
    assert 2.0 < scale["inlier_threshold_deg"] < 3.2 and scale["inlier_threshold_deg"] == d["robust"]["inlier_threshold_deg"]
    cauchy = rotavg.average_multiple(30, i, j, rel, loss="cauchy", loss_threshold=scale["scale_deg"])
    assert np.allclose(res.estimate, cauchy.estimate, rtol=0, atol=1e-9)
    given = rotavg.average_multiple(30, i, j, rel, loss_threshold=5.0).to_dict()["pipeline"]["loss_choice"]
    assert given["scale"] is None and given["chosen"]["loss"]["scale_deg"] == 5.0
    assert res.certificate is None and res.verdict == "certified"
    assert d["verdict"]["problem"]["kind"] == "chordal_l2_inliers"
    assert d["verdict"]["estimate"] == "inlier_graph"
    least_squares = rotavg.average_multiple(30, i, j, rel, loss="chordal")
    assert least_squares.to_dict()["robust"] is None and least_squares.verdict == "certified"
    assert least_squares.to_dict()["verdict"]["problem"]["kind"] == "chordal_l2"
    d = rotavg.average_multiple(30, i, j, rel, loss="l1", loss_threshold=2.0).to_dict()
    assert d["robust"]["inlier_threshold_deg"] == 2.0  # as `rotavg multiple --loss-threshold 2`


def test_init_is_used(rng):
    truth, i, j, rel = synthetic_graph(rng, 20, 60, 0.0)
    res = rotavg.average_multiple(20, i, j, rel, init=truth)
    assert res.solver.iterations <= 2 and res.certificate.certified
    with pytest.raises(rotavg.Error, match="3 rotations given for 20 nodes"):
        rotavg.average_multiple(20, i, j, rel, init=truth[:3])


def test_the_gil_is_released_while_solving(rng):
    # While a solve runs in another thread, this thread keeps running Python code: the longest
    # pause it sees is much shorter than the solve (with the GIL held it would be all of it).
    _, i, j, rel = synthetic_graph(rng, 3000, 9000, 0.05)
    out = {}
    worker = threading.Thread(target=lambda: out.update(r=rotavg.average_multiple(3000, i, j, rel)))
    longest, last = 0.0, time.perf_counter()
    start = last
    worker.start()
    while worker.is_alive():
        now = time.perf_counter()
        longest, last = max(longest, now - last), now
    elapsed = time.perf_counter() - start
    assert out["r"].certificate is not None
    assert elapsed > 0.05, "solve too fast to tell"
    assert longest < 0.5 * elapsed, (longest, elapsed)


@pytest.mark.parametrize("name", SHARED_GRAPHS)
def test_same_costs_and_certificates_as_the_command_line(name, data_dir, cli, tmp_path):
    path = data_dir / name
    if not path.is_file():
        pytest.skip(f"{path} absent")
    theirs = cli("multiple", path)
    g = rotavg.read_graph(path)
    # A Graph is solved exactly as the command line solves the file: the same --json object.
    from_graph = rotavg.average_multiple(g)
    assert untimed(from_graph.to_dict()) == untimed(theirs)
    assert from_graph.cost == theirs["cost"]
    assert np.array_equal(from_graph.estimate, np.array(theirs["estimate"]))
    # The arrays n, i, j, rel, weights give the same answer up to rounding (each rel[k] is
    # validated and re-orthonormalised again on the way in).
    from_arrays = rotavg.average_multiple(g.n, g.i, g.j, g.rel, g.weights)
    c, t = from_arrays.certificate, theirs["certificate"]
    assert from_arrays.cost == pytest.approx(theirs["cost"], rel=1e-9, abs=1e-12)
    # the default loss follows the data (Madrid's outliers choose Cauchy: no certificate of
    # its cost, the verdict is the inlier graph's)
    assert from_arrays.verdict == theirs["verdict"]["verdict"]
    assert (c is None) == (t is None)
    if c is not None:
        assert (c.verdict, c.method) == (t["verdict"], t["method"])
        assert c.lower_bound == pytest.approx(t["lower_bound"], rel=1e-8, abs=1e-10)
    # certify: the same report for the command line's own estimate.
    est = tmp_path / "estimate.json"
    est.write_text(json.dumps({"estimate": theirs["estimate"]}))
    certified = rotavg.certify_multiple(g, estimate=np.array(theirs["estimate"]))
    assert untimed(certified.to_dict()) == untimed(cli("certify", path, "--estimate", est))


def test_certify_multiple_reads_an_estimate_file_like_the_command_line(tmp_path):
    """An estimate given as a path (another tool's rotation list ``id R11 .. R33``, shuffled) is
    matched to the graph's nodes by id, as ``rotavg certify --estimate`` does."""
    import pathlib

    data = pathlib.Path(__file__).resolve().parents[2] / "examples" / "data" / "slam.g2o"
    g = rotavg.read_graph(str(data))
    best = rotavg.average_multiple(g)
    ids = [int(k) for k in g.node_ids]
    lines = [
        f"{ids[k]} " + " ".join(repr(float(x)) for x in best.estimate[k].reshape(9))
        for k in reversed(range(len(ids)))
    ]
    est = tmp_path / "theirs.txt"
    est.write_text("\n".join(lines) + "\n")
    res = rotavg.certify_multiple(g, estimate=est)
    assert np.allclose(res.estimate, best.estimate, atol=1e-12)
    assert res.certificate.certified
    missing = tmp_path / "missing.txt"
    missing.write_text("\n".join(lines[1:]) + "\n")
    with pytest.raises(rotavg.ParseError, match="1 of 400 nodes have no rotation"):
        rotavg.certify_multiple(g, estimate=str(missing))


def test_certify_a_colmap_model_with_nan_translations(tmp_path):
    """pycolmap's rotation averaging writes a model whose translations are NaN: its rotations
    are certified from Python as from the command line, the translations reported."""
    import pathlib

    from scipy.spatial.transform import Rotation

    data = pathlib.Path(__file__).resolve().parents[2] / "examples" / "data" / "slam.g2o"
    g = rotavg.read_graph(data)
    est = rotavg.average_multiple(g, loss="chordal").estimate
    x, y, z, w = Rotation.from_matrix(est).as_quat().T  # COLMAP's cam_from_world is R_i
    lines = [
        f"{int(k)} {w[n]} {x[n]} {y[n]} {z[n]} nan nan nan 1 img{int(k)}.jpg\n\n"
        for n, k in enumerate(g.node_ids)
    ]
    model = tmp_path / "images.txt"
    model.write_text("".join(lines))
    res = rotavg.certify_multiple(g, estimate=model)
    d = res.to_dict()
    assert res.certificate.certified
    assert [x["code"] for x in d["warnings"]] == ["translations_not_finite"]
    assert d["warnings"][0]["count"] == g.n


def test_certify_multiple_judges_an_estimate_on_its_inlier_graph(rng, cli, tmp_path):
    """``loss="cauchy"``: the truth of noise-free inliers is certified on the chordal L2 problem
    of its inlier graph (three planted outliers left out), as ``rotavg certify --loss cauchy``
    says; on all edges it is not."""
    truth, i, j, rel = synthetic_graph(rng, 20, 80, 0.0)
    rel = rel.copy()
    bad = np.array([2, 30, 61])  # edges off the spanning tree (the first 19)
    rel[bad] = np.array([[0.0, -1, 0], [1, 0, 0], [0, 0, 1]]) @ rel[bad]
    res = rotavg.certify_multiple(20, i, j, rel, truth, loss="cauchy")
    d = res.to_dict()
    assert d["loss"] == "cauchy" and not res.certificate.certified
    assert d["verdict"]["verdict"] == "certified" and d["verdict"]["estimate"] == "given"
    problem = d["verdict"]["problem"]
    assert problem["kind"] == "chordal_l2_inliers" and problem["num_edges"] == 80 - 3
    assert d["inlier_graph"]["residuals"]["num_outliers"] == 3
    assert np.array_equal(res.estimate, truth)  # unchanged
    path = tmp_path / "graph.json"
    edges = [{"i": int(a), "j": int(b), "rotation": r.tolist()} for a, b, r in zip(i, j, rel)]
    path.write_text(json.dumps({"num_rotations": 20, "edges": edges}))
    est = tmp_path / "truth.json"
    est.write_text(json.dumps({"rotations": truth.tolist()}))
    theirs = cli("certify", path, "--estimate", est, "--loss", "cauchy")
    ours = rotavg.certify_multiple(20, i, j, rel, est, loss="cauchy").to_dict()
    assert untimed(ours)["verdict"] == untimed(theirs)["verdict"]
    assert untimed(ours)["inlier_graph"]["certificate"] == untimed(theirs)["inlier_graph"]["certificate"]
    with pytest.raises(rotavg.Error, match="not with auto"):
        rotavg.certify_multiple(20, i, j, rel, truth, loss="auto")
    with pytest.raises(rotavg.Error, match="inlier_threshold"):
        rotavg.certify_multiple(20, i, j, rel, truth, loss="l1", inlier_threshold=-1.0)


def test_certify_multiple_reads_numpy_files(rng, tmp_path):
    """``np.save`` / ``np.savez`` files (C or Fortran order, float32) are estimates, in node
    order; ``np.savez_compressed`` is refused with what to do."""
    _, i, j, rel = synthetic_graph(rng, 12, 30, 0.02)
    est = rotavg.average_multiple(12, i, j, rel).estimate
    expected = rotavg.certify_multiple(12, i, j, rel, est).cost
    files = {
        "c.npy": lambda p: np.save(p, est),
        "f.npy": lambda p: np.save(p, np.asfortranarray(est)),
        "nine.npy": lambda p: np.save(p, est.reshape(12, 9)),
        "named.npz": lambda p: np.savez(p, rotations=est, other=np.zeros(2)),
        "one.npz": lambda p: np.savez(p, est),
    }
    for name, save in files.items():
        path = tmp_path / name
        save(path)
        res = rotavg.certify_multiple(12, i, j, rel, path)
        assert res.cost == pytest.approx(expected, rel=1e-12), name
        assert np.allclose(res.estimate, est, atol=1e-12), name
    single = tmp_path / "single.npy"
    np.save(single, est.astype(np.float32))
    assert rotavg.certify_multiple(12, i, j, rel, single).cost == pytest.approx(expected, rel=1e-3)
    packed = tmp_path / "packed.npz"
    np.savez_compressed(packed, est)
    with pytest.raises(rotavg.Error, match="savez_compressed"):
        rotavg.certify_multiple(12, i, j, rel, packed)


def test_write_estimate_writes_what_the_command_line_writes(cli, tmp_path):
    """``write_estimate`` writes the files of ``rotavg multiple --output`` byte for byte (JSON
    with node ids, g2o keeping the input's lines, a COLMAP sparse model), and they read back as
    estimates of the same graph."""
    import pathlib

    data = pathlib.Path(__file__).resolve().parents[2] / "examples" / "data" / "slam.g2o"
    g = rotavg.read_graph(data)
    theirs = tmp_path / "cli"
    ours = tmp_path / "py"
    names = ["est.json", "est.g2o", "model/"]
    for name in names:  # (a trailing "/" means a folder: joined as text, which keeps it)
        d = cli("multiple", data, "--loss", "chordal", "--output", f"{theirs}/{name}")
        rotavg.write_estimate(g, np.array(d["estimate"]), f"{ours}/{name}")
    for name in ["est.json", "est.g2o", "model/images.txt", "model/cameras.txt"]:
        assert (ours / name).read_bytes() == (theirs / name).read_bytes(), name
    est = np.array(d["estimate"])
    back = rotavg.certify_multiple(g, estimate=ours / "est.json")
    assert np.allclose(back.estimate, est, atol=1e-12)
    with pytest.raises(rotavg.Error, match="the graph has 400 nodes"):
        rotavg.write_estimate(g, est[:-1], tmp_path / "short.json")
    with pytest.raises(rotavg.Error, match="format"):
        rotavg.write_estimate(g, est, tmp_path / "x.json", format="png")
    assert not (tmp_path / "short.json").exists()


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_set_progress_delivers_the_events_of_a_run(rng):
    """``set_progress`` receives the phases and iterations the command line shows; a failing
    callback does not stop the solve; ``None`` stops the events."""
    _, i, j, rel = synthetic_graph(rng, 40, 120, 0.05)
    events = []
    rotavg.set_progress(events.append)
    try:
        res = rotavg.average_multiple(40, i, j, rel, loss="chordal")
    finally:
        rotavg.set_progress(None)
    phases = {e["phase"] for e in events if e["event"] == "phase"}
    assert {"solve", "certify"} <= phases, phases
    # every rung of the certificate's ladder is announced with its predicted time
    rungs = [e["detail"] for e in events if e["event"] == "phase" and e["phase"] == "certify"]
    assert any("predicted" in d for d in rungs), rungs
    iterations = [e for e in events if e["event"] == "iteration"]
    assert iterations and all(e["cost"] >= 0 and "message" in e for e in iterations)
    assert res.certificate.certified

    def boom(event):
        raise RuntimeError("a broken callback")

    rotavg.set_progress(boom)
    try:
        again = rotavg.average_multiple(40, i, j, rel, loss="chordal")
    finally:
        rotavg.set_progress(None)
    assert again.cost == pytest.approx(res.cost, rel=1e-12)
    before = len(events)
    rotavg.average_multiple(40, i, j, rel, loss="chordal")
    assert len(events) == before
    with pytest.raises(rotavg.Error, match="callable"):
        rotavg.set_progress(3)  # type: ignore[arg-type]


def test_rotation_tolerance_is_a_keyword(rng, tmp_path):
    """Matrices orthonormal to 2e-4 only are refused at the default tolerance (1e-5, the command
    line's) and accepted with ``rotation_tolerance=1e-3``, from arrays and from files."""
    _, i, j, rel = synthetic_graph(rng, 10, 30, 0.01)
    rel = rel.copy()
    rel[4] = rel[4] * 1.0001
    with pytest.raises(rotavg.Error, match="rel\\[4\\]"):
        rotavg.average_multiple(10, i, j, rel)
    res = rotavg.average_multiple(10, i, j, rel, rotation_tolerance=1e-3)
    assert res.to_dict()["input"]["read"]["rotation_tolerance"] == 1e-3
    assert np.allclose(res.estimate[0], np.eye(3))
    est = res.estimate.copy()
    est[2] = est[2] * 1.0001
    with pytest.raises(rotavg.Error, match="rel\\[4\\]"):
        rotavg.certify_multiple(10, i, j, rel, est)
    rotavg.certify_multiple(10, i, j, rel, est, rotation_tolerance=1e-3)
    path = tmp_path / "g.json"
    edges = [{"i": int(a), "j": int(b), "rotation": r.tolist()} for a, b, r in zip(i, j, rel)]
    path.write_text(json.dumps({"num_rotations": 10, "edges": edges}))
    with pytest.raises(rotavg.ParseError):
        rotavg.read_graph(path)
    g = rotavg.read_graph(path, rotation_tolerance=1e-3)
    assert g.n == 10
    with pytest.raises(rotavg.Error, match="rotation_tolerance"):
        rotavg.average_multiple(10, i, j, rel, rotation_tolerance=0.0)


def test_robust_outputs_are_the_command_lines(cli, tmp_path):
    """``write_edges`` and ``write_estimate(graph, result.inlier_estimate, ...)`` write the files
    of ``--edges-output`` and ``--inlier-output`` byte for byte; a least-squares result has no
    residuals to write."""
    import pathlib

    data = pathlib.Path(__file__).resolve().parents[2] / "examples" / "data" / "sfm_outliers.txt"
    g = rotavg.read_graph(data)
    res = rotavg.average_multiple(g, loss="cauchy")
    assert res.inlier_estimate is not None and res.inlier_estimate.shape == (g.n, 3, 3)
    cli(
        "multiple", data, "--loss", "cauchy",
        "--edges-output", tmp_path / "cli_edges.csv",
        "--inlier-output", tmp_path / "cli_inliers.json",
    )
    rotavg.write_edges(g, res, tmp_path / "py_edges.csv")
    rotavg.write_estimate(g, res.inlier_estimate, tmp_path / "py_inliers.json")
    for name in ["edges.csv", "inliers.json"]:
        assert (tmp_path / f"py_{name}").read_bytes() == (tmp_path / f"cli_{name}").read_bytes()
    rotavg.write_edges(g, res, tmp_path / "edges.json")
    assert json.loads((tmp_path / "edges.json").read_text())
    plain = rotavg.average_multiple(g, loss="chordal")
    assert plain.inlier_estimate is None
    with pytest.raises(rotavg.Error, match="no per-edge residuals"):
        rotavg.write_edges(g, plain, tmp_path / "none.csv")


def test_certify_multiple_takes_the_nearest_rotations_of_a_mirrored_estimate(rng):
    """A relaxation solver's mirror image (every det -1, orthogonal to 1e-6 only) is refused
    without ``nearest_rotations`` and certified with it, as ``rotavg certify
    --nearest-rotations``; the cost is the test's own cost of the test's own polar factors."""
    truth, i, j, rel = synthetic_graph(rng, 30, 90, 0.05)
    best = rotavg.average_multiple(30, i, j, rel)
    skew = np.eye(3) + 1e-6 * rng.standard_normal((30, 3, 3))
    mirrored = -best.estimate @ skew
    with pytest.raises(rotavg.Error, match="with `nearest_rotations`, certify takes"):
        rotavg.certify_multiple(30, i, j, rel, mirrored)
    res = rotavg.certify_multiple(30, i, j, rel, mirrored, nearest_rotations=True)
    u, _, vt = np.linalg.svd(-mirrored)
    polar = u @ vt
    assert np.all(np.linalg.det(polar) > 0)
    cost = sum(float(np.sum((polar[b] - r @ polar[a]) ** 2)) for a, b, r in zip(i, j, rel))
    assert res.cost == pytest.approx(cost, rel=1e-12)
    assert res.certificate.certified
    (w,) = [w for w in res.to_dict()["warnings"] if w["code"] == "estimate_projected"]
    assert w["count"] == 30 and "negated" in w["message"]
    # one reflection among rotations is no estimate up to sign
    mixed = best.estimate.copy()
    mixed[4] = -mixed[4]
    with pytest.raises(rotavg.Error, match="1 of its 30 matrices are reflections"):
        rotavg.certify_multiple(30, i, j, rel, mixed, nearest_rotations=True)


def test_a_colmap_database_is_read_with_its_information_by_default(cli):
    """``read_graph(information="auto")`` (the default) reads the committed scene's two-view
    information from its correspondences: the command line's default run to the last digit;
    ``information="kappa"`` reads weights 1."""
    import pathlib

    db = pathlib.Path(__file__).resolve().parents[2] / "examples" / "data" / "colmap_scene" / "database.db"
    ours = rotavg.average_multiple(rotavg.read_graph(db), certify="none").to_dict()
    theirs = cli("multiple", db, "--certify", "none")
    assert ours["information"] and ours["information"] == theirs["information"]
    assert ours["cost"] == theirs["cost"]
    assert theirs["input"]["read"]["full_information"] is True
    plain = rotavg.average_multiple(rotavg.read_graph(db, information="kappa"), certify="none")
    assert not plain.to_dict().get("information")


def test_a_graph_shows_the_information_it_was_read_with():
    """``Graph.information``: the ``(M, 3, 3)`` matrices read from the committed database
    (symmetric, positive semidefinite), the same problem as the graph itself when passed as
    arrays; None with weights 1."""
    import pathlib

    db = pathlib.Path(__file__).resolve().parents[2] / "examples" / "data" / "colmap_scene" / "database.db"
    g = rotavg.read_graph(db)
    h = g.information
    assert h is not None and h.shape == (g.num_edges, 3, 3) and not h.flags.writeable
    assert np.allclose(h, np.transpose(h, (0, 2, 1)), rtol=0, atol=1e-9 * np.abs(h).max())
    assert np.linalg.eigvalsh(h).min() >= -1e-9 * np.abs(h).max()
    whole = rotavg.average_multiple(g, loss="chordal", certify="none")
    arrays = rotavg.average_multiple(g.n, g.i, g.j, g.rel, information=h, loss="chordal", certify="none")
    assert arrays.cost == whole.cost
    assert rotavg.read_graph(db, information="kappa").information is None
