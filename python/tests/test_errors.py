"""Errors that speak Python: the exception classes, their attributes, and messages that name
Python keywords and functions (never a command-line flag) and no Rust type names."""

import json
import re

import numpy as np
import pytest

import rotavg
from conftest import random_rotations

I3 = np.eye(3)
#: A command-line flag such as `--largest-component`.
FLAG = re.compile(r"(?<![\w-])--[a-z]")
#: Rust type names and paths that must not reach Python users.
RUST = re.compile(
    r"\b(struct|enum|f64|f32|usize|u64|u32|i64|i32|Vec|Option|Rotation3|Matrix3|PyString|PyAny|"
    r"PyErr|MotionSettings|CertifySettings|HandEyeOptions|ReadOptions|ConjugatePair)\b|::"
)


def message(exception_type, f, *args, **kwargs):
    """The message of the exception `f(*args, **kwargs)` raises, checked for flags and Rust."""
    with pytest.raises(exception_type) as info:
        f(*args, **kwargs)
    text = str(info.value)
    assert not FLAG.search(text), text
    assert not RUST.search(text), text
    return info.value, text


def triangle_and_pair():
    """A triangle 0-1-2 and a separate edge 3-4 (two components)."""
    truth = random_rotations(np.random.default_rng(5), 5)
    i, j = np.array([0, 1, 2, 3]), np.array([1, 2, 0, 4])
    return truth, i, j, truth[j] @ truth[i].transpose(0, 2, 1)


def test_exception_classes():
    for name in ["ParseError", "FileError", "DisconnectedError", "DegenerateError", "SolverError"]:
        cls = getattr(rotavg, name)
        assert issubclass(cls, rotavg.Error) and issubclass(cls, ValueError), name
        assert cls.__module__ == "rotavg" and cls.__doc__
    assert issubclass(rotavg.Error, ValueError)


def test_disconnected_graph_names_the_python_way(tmp_path):
    _, i, j, rel = triangle_and_pair()
    err, text = message(rotavg.DisconnectedError, rotavg.average_multiple, 5, i, j, rel)
    assert err.component_sizes == [3, 2]
    assert "largest_component=True" in text and "largest-component" not in text
    assert "2 components of sizes [3, 2]" in text
    # what the message says works
    res = rotavg.average_multiple(5, i, j, rel, largest_component=True)
    assert res.certificate.certified and list(res.node_ids) == [0, 1, 2]
    path = tmp_path / "two.g2o"
    path.write_text("EDGE3 0 1 0 0 0 0 0 0.1\nEDGE3 1 2 0 0 0 0 0 0.2\nEDGE3 5 7 0 0 0 0 0 0\n")
    message(rotavg.DisconnectedError, rotavg.average_multiple, rotavg.read_graph(path))
    assert rotavg.average_multiple(rotavg.read_graph(path), largest_component=True).num_rotations == 3
    assert rotavg.average_multiple(rotavg.read_graph(path, largest_component=True)).num_rotations == 3


def test_settings_name_the_keyword_argument():
    truth, i, j, rel = triangle_and_pair()
    i, j, rel = i[:3], j[:3], rel[:3]
    cases = [
        (dict(max_memory=0), "invalid setting `max_memory`"),
        (dict(max_seconds=0.0), "invalid setting `max_seconds`"),
        (dict(certify="maybe"), "invalid setting `certify`: unknown name `maybe`"),
        (dict(loss="l3"), "invalid setting `loss`: unknown name `l3`"),
        (dict(init=truth[:2]), "invalid setting `init`: 2 rotations given for 3 nodes"),
    ]
    for kwargs, expected in cases:
        _, text = message(rotavg.Error, rotavg.average_multiple, 3, i, j, rel, **kwargs)
        assert expected in text, text
    _, text = message(rotavg.Error, rotavg.average_single, [I3], metric="euclid")
    assert "invalid setting `metric`" in text
    _, text = message(rotavg.Error, rotavg.average_conjugate, rel, rel, certify="dual")
    assert "invalid setting `certify`: certify mode `dual` does not apply" in text
    _, text = message(rotavg.Error, rotavg.average_conjugate, rel, rel, max_seconds=-1.0)
    assert "`max_seconds`" in text
    _, text = message(rotavg.Error, rotavg.read_graph, "x.g2o", format="xyz")
    assert "invalid setting `format`" in text
    _, text = message(rotavg.Error, rotavg.read_graph, "x.g2o", weights="unit", information="full")
    assert "invalid setting `information`: the full information cannot be read with unit weights" in text


def test_hand_eye_settings_and_files(tmp_path):
    (tmp_path / "empty").mkdir()
    err, text = message(rotavg.FileError, rotavg.read_handeye, tmp_path / "empty")
    assert "hand=PATH and camera=PATH" in text and err.path.endswith("empty")
    pairs = tmp_path / "pairs.json"
    pairs.write_text("{}")
    _, text = message(rotavg.FileError, rotavg.read_handeye, pairs, format="eth")
    assert "hand=PATH and camera=PATH" in text
    _, text = message(rotavg.Error, rotavg.read_handeye, tmp_path, quaternion_order="wxzy")
    assert "invalid setting `quaternion_order`" in text
    for kwargs, name in [(dict(stride=0), "stride"), (dict(subsample=0), "subsample"),
                         (dict(max_gap=-1.0), "max_gap"), (dict(min_angle=-1.0), "min_angle")]:
        _, text = message(rotavg.Error, rotavg.read_handeye, tmp_path / "empty", **kwargs)
        assert f"invalid setting `{name}`" in text, text
    _, text = message(rotavg.Error, rotavg.read_handeye)
    assert "needs a path, or both hand and camera" in text


def test_file_errors_carry_path_and_line(tmp_path):
    odd = tmp_path / "odd.txt"
    odd.write_text("1 2 3\n")
    err, text = message(rotavg.ParseError, rotavg.read_graph, odd)
    assert (err.path, err.line) == (str(odd), 1)
    assert 'pass format="g2o", "1dsfm" or "json"' in text
    missing = tmp_path / "missing.g2o"
    err, _ = message(rotavg.FileError, rotavg.read_graph, missing)
    assert err.path == str(missing)


def test_json_errors_speak_json(tmp_path):
    bad = {
        "pairs.json": ('{"pairs": [1]}', rotavg.read_handeye, "expected a pair"),
        "graph.json": ('{"num_rotations": "a", "edges": []}', rotavg.read_graph,
                       "expected a non-negative integer"),
        "weights.json": (json.dumps({"pairs": [{"left": I3.tolist(), "right": I3.tolist(),
                                                "weight": "heavy"}]}),
                         rotavg.read_handeye, "expected a number"),
    }
    for name, (text, reader, expected) in bad.items():
        path = tmp_path / name
        path.write_text(text)
        err, msg = message(rotavg.ParseError, reader, path)
        assert expected in msg and err.path == str(path), msg


def test_degenerate_data():
    z = np.array([[[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]]
                  for t in [0.3, 0.7, 1.1]])
    _, text = message(rotavg.DegenerateError, rotavg.average_conjugate, z, z)
    assert text.startswith("degenerate data:")


def test_argument_types_raise_type_errors_without_rust_names():
    for kwargs in [dict(metric=3), dict(p="2")]:
        message(TypeError, rotavg.average_single, [I3], **kwargs)
    _, i, j, rel = triangle_and_pair()
    message(TypeError, rotavg.average_multiple, 3, i[:3], j[:3], rel[:3], max_memory="4G")
    message(OverflowError, rotavg.average_multiple, 3, i[:3], j[:3], rel[:3], max_memory=-1)
