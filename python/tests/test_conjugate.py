"""Conjugate (hand-eye) averaging: planted S, certificates, scipy inputs, and the same output
as `rotavg conjugate` / `rotavg certify` on the same pairs."""

import json

import numpy as np
import pytest

import rotavg
from conftest import random_rotations, small_rotations, untimed


def pairs(rng, n, sigma):
    """Planted S and pairs with right[k] ~ S^-1 left[k] S (noise sigma rad on right)."""
    s = random_rotations(rng, 1)[0]
    right = random_rotations(rng, n)
    left = s @ right @ s.T
    return s, left, small_rotations(rng, n, sigma) @ right


def test_planted_hand_eye_rotation_is_found_and_certified(rng):
    s, left, right = pairs(rng, 12, 0.0)
    res = rotavg.average_conjugate(left, right)
    assert res.estimate.shape == (3, 3)
    assert np.allclose(res.estimate, s, atol=1e-9)
    assert res.certificate.certified and res.certificate.method == "sdp"
    # The cost is sum_k w_k ||S right_k - left_k S||_F^2.
    s_hat = res.estimate
    cost = np.sum((s_hat @ right - left @ s_hat) ** 2)
    assert res.chordal_cost == pytest.approx(cost, abs=1e-18)


def test_noisy_pairs_weights_and_certify(rng):
    s, left, right = pairs(rng, 30, 0.02)
    w = rng.uniform(0.5, 2.0, size=30)
    res = rotavg.average_conjugate(left, right, w)
    assert res.certificate.certified
    assert np.linalg.norm(res.estimate - s) < 0.05
    same = rotavg.certify_conjugate(left, right, res.estimate, w)
    assert same.certificate.certified and same.solver is None
    assert same.cost == pytest.approx(res.chordal_cost, rel=1e-12)
    worse = small_rotations(rng, 1, 0.2)[0] @ res.estimate
    bad = rotavg.certify_conjugate(left, right, worse, w)
    assert not bad.certificate.certified
    assert bad.certificate.lower_bound <= res.chordal_cost * (1 + 1e-9)


def test_scipy_rotations_accepted(rng):
    Rotation = pytest.importorskip("scipy.spatial.transform").Rotation
    _, left, right = pairs(rng, 10, 0.01)
    a = rotavg.average_conjugate(Rotation.from_matrix(left), Rotation.from_matrix(right))
    b = rotavg.average_conjugate(left, right)
    assert np.allclose(a.estimate, b.estimate, atol=1e-10)
    c = rotavg.certify_conjugate(left, right, Rotation.from_matrix(b.estimate))
    assert c.certificate.certified


def test_parallel_axes_do_not_determine_s():
    def rz(t):
        return np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]])

    rs = np.stack([rz(0.3), rz(0.7), rz(1.1)])
    with pytest.raises(rotavg.Error, match="degenerate"):
        rotavg.average_conjugate(rs, rs)


def test_same_output_as_the_command_line(rng, cli, tmp_path):
    _, left, right = pairs(rng, 20, 0.01)
    w = rng.uniform(0.5, 2.0, size=20)
    path = tmp_path / "pairs.json"
    path.write_text(json.dumps({"pairs": [
        {"left": l.tolist(), "right": r.tolist(), "weight": float(x)}
        for l, r, x in zip(left, right, w)
    ]}))
    ours = rotavg.average_conjugate(left, right, w)
    assert untimed(ours.to_dict()) == untimed(cli("conjugate", path))
    est = tmp_path / "s.json"
    est.write_text(json.dumps({"rotation": ours.estimate.tolist()}))
    certified = rotavg.certify_conjugate(left, right, ours.estimate, w)
    assert untimed(certified.to_dict()) == untimed(cli("certify", path, "--estimate", est))
