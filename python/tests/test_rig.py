"""Two-sensor rigs from Python (``average_rig``, ``certify_rig``): the command line's report,
the planted ``sensor_from_rig`` recovered, a given estimate certified unchanged."""

import json

import numpy as np
import pytest

import rotavg
from conftest import REPO, untimed

RIG = REPO / "examples" / "data" / "rig"


def angle(a, b):
    return np.degrees(np.arccos(np.clip((np.trace(a.T @ b) - 1) / 2, -1, 1)))


def test_same_result_as_the_command_line(cli):
    right, left = rotavg.read_graph(RIG / "right.json"), rotavg.read_graph(RIG / "left.json")
    ours = rotavg.average_rig(right, left)
    theirs = cli("rig", RIG / "right.json", RIG / "left.json")
    assert untimed(ours.to_dict()) == untimed(theirs)
    assert ours.problem == "rig" and ours.verdict == "certified"
    truth = json.loads((RIG / "truth.json").read_text())
    s = np.array(ours.to_dict()["sensor_from_rig"])
    assert angle(s, np.array(truth["sensor_from_rig"])) < 0.2


def test_certify_rig_keeps_the_estimate():
    right, left = rotavg.read_graph(RIG / "right.json"), rotavg.read_graph(RIG / "left.json")
    solved = rotavg.average_rig(right, left)
    s = np.array(solved.to_dict()["sensor_from_rig"])
    checked = rotavg.certify_rig(right, left, solved.estimate, s)
    assert checked.verdict == "certified"
    assert checked.cost == pytest.approx(solved.cost, rel=1e-12)
    assert np.array_equal(np.asarray(checked.estimate), np.asarray(solved.estimate))
    with pytest.raises(rotavg.Error, match="same frames"):
        rotavg.certify_rig(right, rotavg.read_graph(REPO / "examples" / "data" / "gravity" / "graph.json"),
                           solved.estimate, s)
