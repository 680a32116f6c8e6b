"""What the command line has, from Python: figures (``write_figure``, as ``--plot``), a progress
line (``progress_bar``), rotation tolerances and budgets for single and conjugate problems, and
their estimates given as files."""

import io
import json

import numpy as np
import pytest

import rotavg
from conftest import random_rotations, small_rotations, synthetic_graph


def conjugate_pairs(rng, n, sigma):
    s = random_rotations(rng, 1)[0]
    right = random_rotations(rng, n)
    return s, s @ right @ s.T, small_rotations(rng, n, sigma) @ right


def test_write_figure_draws_the_residuals_of_a_graph_and_of_hand_eye_pairs(rng, tmp_path):
    _, i, j, rel = synthetic_graph(rng, 20, 60, 0.02)
    g = rotavg.read_graph(str(_write_graph(tmp_path, i, j, rel)))
    ours = rotavg.average_multiple(g)
    rotavg.write_figure(g, ours, tmp_path / "multiple.svg")
    svg = (tmp_path / "multiple.svg").read_text()
    assert svg.startswith("<svg") and "residual angles of 60 edges" in svg
    certified = rotavg.certify_multiple(g, estimate=ours.estimate)
    rotavg.write_figure(g, certified, tmp_path / "certify.svg")
    assert "residual angles of 60 edges" in (tmp_path / "certify.svg").read_text()
    _, left, right = conjugate_pairs(rng, 10, 0.01)
    conj = rotavg.average_conjugate(left, right)
    with pytest.raises(rotavg.Error, match="must be a Graph"):
        rotavg.write_figure(left, conj, tmp_path / "x.svg")
    with pytest.raises(rotavg.Error, match="not an estimate of this graph"):
        rotavg.write_figure(g, conj, tmp_path / "x.svg")


def _write_graph(tmp_path, i, j, rel):
    path = tmp_path / "graph.json"
    edges = [
        {"i": int(a), "j": int(b), "rotation": r.tolist()} for a, b, r in zip(i, j, rel)
    ]
    path.write_text(json.dumps({"num_rotations": 20, "edges": edges}))
    return path


def test_write_figure_of_hand_eye_data(tmp_path, data_dir):
    folder = data_dir / "handeye" / "tabb_rwhe_dataset1"
    if not folder.is_dir():
        pytest.skip(f"{folder} not present")
    data = rotavg.read_handeye(str(folder))
    res = rotavg.average_conjugate(data)
    rotavg.write_figure(data, res, tmp_path / "conjugate.svg")
    assert "pairs" in (tmp_path / "conjugate.svg").read_text()
    single = rotavg.average_single(np.eye(3)[None].repeat(3, axis=0))
    with pytest.raises(rotavg.Error, match="not a hand-eye rotation"):
        rotavg.write_figure(data, single, tmp_path / "y.svg")


def test_progress_bar_shows_messages_on_one_line_and_clears_it(rng):
    _, i, j, rel = synthetic_graph(rng, 200, 1000, 0.05)
    out = io.StringIO()
    with rotavg.progress_bar(stream=out, min_interval=0.0):
        res = rotavg.average_multiple(200, i, j, rel)
    text = out.getvalue()
    assert res.certificate.certified
    assert text.startswith("\r") and text.endswith("\r"), text[:80]
    assert "\n" not in text
    # every message was written over the previous one, then blanked
    assert text.rstrip("\r").split("\r")[-1].strip() == ""
    # the callback is removed on exit: nothing more is written
    rotavg.average_multiple(200, i, j, rel)
    assert out.getvalue() == text


def test_rotation_tolerance_for_single_and_conjugate_samples(rng):
    samples = small_rotations(rng, 10, 0.1)
    loose = samples.copy()
    loose[3] = loose[3] * (1 + 1e-4)  # ||R^T R - I||_F ~ 3.5e-4
    with pytest.raises(rotavg.Error, match="not a rotation"):
        rotavg.average_single(loose)
    res = rotavg.average_single(loose, rotation_tolerance=1e-3)
    assert res.certificate.certified
    assert rotavg.certify_single(loose, res.estimate, rotation_tolerance=1e-3).certificate.certified
    _, left, right = conjugate_pairs(rng, 12, 0.01)
    right[2] = right[2] * (1 + 1e-4)
    with pytest.raises(rotavg.Error, match="not a rotation"):
        rotavg.average_conjugate(left, right)
    conj = rotavg.average_conjugate(left, right, rotation_tolerance=1e-3)
    again = rotavg.certify_conjugate(left, right, conj.estimate, rotation_tolerance=1e-3)
    assert again.certificate.certified
    with pytest.raises(rotavg.Error, match="rotation_tolerance must be positive"):
        rotavg.average_single(samples, rotation_tolerance=0.0)


def test_single_and_conjugate_estimates_from_files_and_budgets(rng, tmp_path):
    samples = small_rotations(rng, 10, 0.1)
    mean = rotavg.average_single(samples).estimate
    path = tmp_path / "mean.json"
    path.write_text(json.dumps({"rotation": mean.tolist()}))
    from_file = rotavg.certify_single(samples, path, max_seconds=30.0)
    from_array = rotavg.certify_single(samples, mean)
    assert from_file.cost == from_array.cost
    assert from_file.to_dict()["certificate"]["verdict"] == "certified"
    np.save(tmp_path / "s.npy", mean)
    assert rotavg.certify_single(samples, str(tmp_path / "s.npy")).cost == from_array.cost
    _, left, right = conjugate_pairs(rng, 12, 0.01)
    s = rotavg.average_conjugate(left, right).estimate
    path = tmp_path / "s.json"
    path.write_text(json.dumps({"rotation": s.tolist()}))
    a = rotavg.certify_conjugate(left, right, path, max_memory=1 << 30)
    b = rotavg.certify_conjugate(left, right, s)
    assert a.cost == b.cost and a.certificate.certified
    with pytest.raises(rotavg.FileError, match="missing.json"):
        rotavg.certify_single(samples, tmp_path / "missing.json")


def test_read_graph_information_full_and_init_method_match_the_command_line(cli):
    import pathlib

    slam = pathlib.Path(__file__).resolve().parents[2] / "examples" / "data" / "slam.g2o"
    g = rotavg.read_graph(slam, information="full")
    res = rotavg.average_multiple(g, init_method="tree")
    theirs = cli("multiple", str(slam), "--information", "full", "--init-method", "tree")
    assert res.to_dict()["information"] == theirs["information"]
    assert res.cost == pytest.approx(theirs["cost"], rel=1e-12)
    assert not rotavg.average_multiple(rotavg.read_graph(slam)).to_dict().get("information")
    with pytest.raises(rotavg.Error, match='information must be "auto", "kappa" or "full"'):
        rotavg.read_graph(slam, information="diagonal")
    with pytest.raises(rotavg.Error, match="init"):
        rotavg.average_multiple(g, init_method="random")


def test_inlier_threshold_as_the_command_line(cli, tmp_path):
    import pathlib

    sfm = pathlib.Path(__file__).resolve().parents[2] / "examples" / "data" / "sfm_outliers.txt"
    g = rotavg.read_graph(sfm)
    res = rotavg.average_multiple(g, loss="cauchy", inlier_threshold=3.0)
    theirs = cli("multiple", str(sfm), "--loss", "cauchy", "--inlier-threshold", "3")
    ours = res.to_dict()["robust"]
    keys = ["inlier_threshold_deg", "num_inliers", "num_outliers", "median_deg"]
    assert [ours[k] for k in keys] == [theirs["robust"][k] for k in keys]
    assert ours["inlier_graph"]["certified_problem"] == theirs["robust"]["inlier_graph"]["certified_problem"]
    loose = rotavg.average_multiple(g, loss="cauchy", inlier_threshold=10.0).to_dict()["robust"]
    assert loose["num_inliers"] > ours["num_inliers"]
    with pytest.raises(rotavg.Error, match="inlier_threshold needs a robust loss"):
        rotavg.average_multiple(g, loss="chordal", inlier_threshold=3.0)


def test_write_output_writes_what_output_writes(rng, tmp_path, cli):
    samples = small_rotations(rng, 10, 0.1)
    res = rotavg.average_single(samples)
    rotavg.write_output(res, tmp_path / "mean.json")
    back = json.loads((tmp_path / "mean.json").read_text())
    assert np.array_equal(np.array(back["rotation"]), res.estimate)
    assert rotavg.certify_single(samples, tmp_path / "mean.json").certificate.certified
    import pathlib

    rig = pathlib.Path(__file__).resolve().parents[2] / "examples" / "data" / "rig"
    right, left = rotavg.read_graph(rig / "right.json"), rotavg.read_graph(rig / "left.json")
    ours = rotavg.average_rig(right, left)
    rotavg.write_output(ours, tmp_path / "rig.json")
    written = json.loads((tmp_path / "rig.json").read_text())
    assert np.allclose(np.array(written["sensor_from_rig"]), ours.to_dict()["sensor_from_rig"])
    # the command line certifies it as rotavg rig --output wrote it
    theirs = cli("certify", rig / "right.json", "--left", rig / "left.json", "--estimate", tmp_path / "rig.json")
    assert theirs["cost"] == pytest.approx(ours.cost, rel=1e-12)
    # and Python reads it back too
    again = rotavg.certify_rig(right, left, tmp_path / "rig.json")
    assert again.cost == pytest.approx(ours.cost, rel=1e-12)
    with pytest.raises(rotavg.Error, match="leave the argument out"):
        rotavg.certify_rig(right, left, tmp_path / "rig.json", np.eye(3))
    with pytest.raises(rotavg.Error, match="needs sensor_from_rig"):
        rotavg.certify_rig(right, left, ours.estimate)
    _, i, j, rel = synthetic_graph(rng, 10, 30, 0.01)
    with pytest.raises(rotavg.Error, match="write_estimate"):
        rotavg.write_output(rotavg.average_multiple(10, i, j, rel), tmp_path / "x.json")


def test_average_single_stops_at_max_seconds() -> None:
    """``max_seconds=1e-6`` stops the iterative mean before its first iteration (``time_limit``),
    at a rotation; the default runs it to convergence."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(3)
    axes = rng.normal(size=(2000, 3))
    angles = np.where(np.arange(2000) % 5 == 0, 1.5, 0.1)[:, None]
    vecs = axes / np.linalg.norm(axes, axis=1, keepdims=True) * angles
    samples = Rotation.from_rotvec(vecs).as_matrix()
    full = rotavg.average_single(samples, metric="geodesic", p=1).to_dict()
    assert full["solver"]["termination"]["status"] == "converged"
    cut = rotavg.average_single(samples, metric="geodesic", p=1, max_seconds=1e-6)
    d = cut.to_dict()
    assert d["solver"]["termination"]["status"] == "time_limit", d["solver"]
    r = cut.estimate
    assert np.allclose(r.T @ r, np.eye(3), atol=1e-12) and np.linalg.det(r) > 0
