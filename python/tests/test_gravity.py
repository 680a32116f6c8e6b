"""Gravity priors (``gravity=``, ``world_down=``): the same result as ``rotavg multiple
--gravity`` on the committed example, priors as arrays (NaN rows: none) held by the estimate,
``certify_multiple`` of the gravity problem, and the errors."""

import json

import numpy as np
import pytest

import rotavg
from conftest import REPO, untimed

EXAMPLE = REPO / "examples" / "data" / "gravity"


def test_same_result_as_the_command_line(cli):
    graph = rotavg.read_graph(EXAMPLE / "graph.json")
    ours = rotavg.average_multiple(graph, gravity=EXAMPLE / "gravity.txt")
    theirs = cli("multiple", EXAMPLE / "graph.json", "--gravity", EXAMPLE / "gravity.txt")
    assert untimed(ours.to_dict()) == untimed(theirs)
    assert ours.to_dict()["verdict"]["problem"]["kind"] == "chordal_l2_gravity"


def test_priors_as_arrays_are_held_and_certified():
    graph = rotavg.read_graph(EXAMPLE / "graph.json")
    truth = np.loadtxt(EXAMPLE / "truth.txt", comments="#")[:, 1:].reshape(-1, 3, 3)
    g = truth[:, :, 2].copy()  # R_i e_3: exact priors
    result = rotavg.average_multiple(graph, gravity=g)
    assert result.verdict == "certified"
    est = np.asarray(result.estimate)
    assert np.abs(est[:, :, 2] - g).max() < 1e-9
    d = result.to_dict()["pipeline"]["gravity"]
    assert (d["kind"], d["num_with_prior"]) == ("full", 200)
    # certify_multiple: the estimate certified for the gravity problem
    c = rotavg.certify_multiple(graph, estimate=est, gravity=g)
    assert c.verdict == "certified"
    assert c.to_dict()["verdict"]["problem"]["kind"] == "chordal_l2_gravity"
    # some images without a prior (NaN rows): mixed, every given prior held
    g[::3] = np.nan
    mixed = rotavg.average_multiple(graph, gravity=g)
    est = np.asarray(mixed.estimate)
    keep = ~np.isnan(g[:, 0])
    assert np.abs(est[keep, :, 2] - g[keep]).max() < 1e-9
    assert mixed.to_dict()["pipeline"]["gravity"]["kind"] == "mixed"


def test_another_world_down_direction():
    graph = rotavg.read_graph(EXAMPLE / "graph.json")
    truth = np.loadtxt(EXAMPLE / "truth.txt", comments="#")[:, 1:].reshape(-1, 3, 3)
    w = np.array([0.0, 1.0, 0.0])
    g = truth @ w
    result = rotavg.average_multiple(graph, gravity=g, world_down=w)
    est = np.asarray(result.estimate)
    assert np.abs(est @ w - g).max() < 1e-9


def test_errors():
    graph = rotavg.read_graph(EXAMPLE / "graph.json")
    with pytest.raises(rotavg.Error, match="geodesic"):
        rotavg.average_multiple(graph, loss="geodesic", gravity=np.tile([0.0, 0.0, 1.0], (200, 1)))
    with pytest.raises(rotavg.Error, match=r"shape \(N, 3\) or \(N, 4\)"):
        rotavg.average_multiple(graph, gravity=np.zeros((200, 2)))
    with pytest.raises(rotavg.Error, match="gravity"):
        rotavg.average_multiple(graph, gravity=np.full((200, 3), np.nan))
    with pytest.raises(rotavg.Error, match="norm"):
        rotavg.average_multiple(graph, gravity=np.zeros((200, 3)))


def test_soft_priors_match_the_command_line_and_are_certified(cli):
    graph = rotavg.read_graph(EXAMPLE / "graph.json")
    ours = rotavg.average_multiple(graph, gravity=EXAMPLE / "gravity.txt", gravity_weight=16.0)
    theirs = cli(
        "multiple", EXAMPLE / "graph.json", "--gravity", EXAMPLE / "gravity.txt",
        "--gravity-weight", "16",
    )
    assert untimed(ours.to_dict()) == untimed(theirs)
    assert ours.verdict == "certified"
    assert ours.to_dict()["verdict"]["problem"]["kind"] == "chordal_l2_gravity_soft"
    # the soft cost, written out here: the graph's chordal cost plus 2 w ||R_i e_3 - g_i||^2
    est = np.asarray(ours.estimate)
    d = ours.to_dict()
    edges = json.loads((EXAMPLE / "graph.json").read_text())["edges"]
    graph_cost = sum(
        e["weight"] * np.sum((est[e["j"]] - np.asarray(e["rotation"]) @ est[e["i"]]) ** 2)
        for e in edges
    )
    rows = np.loadtxt(EXAMPLE / "gravity.txt", comments="#")
    prior = sum(
        2.0 * 16.0 * np.sum((est[int(r[0])][:, 2] - r[1:] / np.linalg.norm(r[1:])) ** 2)
        for r in rows
    )
    assert abs(d["cost"] - (graph_cost + prior)) <= 1e-9 * d["cost"]
    c = rotavg.certify_multiple(
        graph, estimate=est, gravity=EXAMPLE / "gravity.txt", gravity_weight=16.0
    )
    assert c.verdict == "certified"
    assert abs(c.to_dict()["cost"] - d["cost"]) <= 1e-9 * d["cost"]
    with pytest.raises(rotavg.Error, match="weight"):
        rotavg.average_multiple(graph, gravity=EXAMPLE / "gravity.txt", gravity_weight=-1.0)


def test_per_image_weights_as_a_fourth_column(cli, tmp_path):
    """``(n, 4)`` priors: the fourth column is each prior's relative weight (NaN: 1); the cost
    written out here with each prior's own weight; the same as the command line with the
    same weights in a priors file; held priors warn that the weights are not used."""
    graph = rotavg.read_graph(EXAMPLE / "graph.json")
    truth = np.loadtxt(EXAMPLE / "truth.txt", comments="#")[:, 1:].reshape(-1, 3, 3)
    rng = np.random.default_rng(5)
    g = truth[:, :, 2] + 0.02 * rng.standard_normal((200, 3))
    scales = np.where(np.arange(200) % 2 == 0, 4.0, np.nan)
    rows = np.column_stack([g, scales])
    ours = rotavg.average_multiple(graph, gravity=rows, gravity_weight=3.0)
    assert ours.verdict == "certified"
    d = ours.to_dict()
    assert d["pipeline"]["gravity"]["scaled"] == 100
    est = np.asarray(ours.estimate)
    edges = json.loads((EXAMPLE / "graph.json").read_text())["edges"]
    graph_cost = sum(
        e["weight"] * np.sum((est[e["j"]] - np.asarray(e["rotation"]) @ est[e["i"]]) ** 2)
        for e in edges
    )
    w = 3.0 * np.where(np.isnan(scales), 1.0, scales)
    unit = g / np.linalg.norm(g, axis=1, keepdims=True)
    prior = np.sum(2.0 * w * np.sum((est[:, :, 2] - unit) ** 2, axis=1))
    assert abs(d["cost"] - (graph_cost + prior)) <= 1e-9 * d["cost"]
    path = tmp_path / "weighted_gravity.txt"
    path.write_text(
        "".join(
            f"{i} {float(x)!r} {float(y)!r} {float(z)!r}"
            + ("" if np.isnan(s) else f" {float(s)!r}")
            + "\n"
            for i, ((x, y, z), s) in enumerate(zip(g, scales))
        )
    )
    theirs = cli("multiple", EXAMPLE / "graph.json", "--gravity", path, "--gravity-weight", "3")
    assert abs(theirs["cost"] - d["cost"]) <= 1e-9 * d["cost"]
    held = rotavg.average_multiple(graph, gravity=rows).to_dict()
    assert any(w["code"] == "gravity_scales_unused" for w in held["warnings"])
