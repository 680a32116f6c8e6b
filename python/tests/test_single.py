"""Single rotation averaging: agreement with SciPy's chordal L2 mean, costs, certificates,
input forms, and parity with `rotavg single --json`."""

import json

import numpy as np
import pytest

import rotavg
from conftest import random_rotations, small_rotations, untimed

Rotation = pytest.importorskip("scipy.spatial.transform").Rotation


def angle(a, b):
    """Rotation angle of a^T b, accurate near 0: 2 asin(||a - b||_F / sqrt(8))."""
    return float(2 * np.arcsin(min(np.linalg.norm(a - b) / np.sqrt(8), 1.0)))


@pytest.mark.parametrize("spread", [0.1, 1.0, 3.0])
def test_chordal_l2_mean_agrees_with_scipy(rng, spread):
    # Around a random centre with small to nearly uniform spread, weighted.
    center = random_rotations(rng, 1)[0]
    samples = small_rotations(rng, 40, spread) @ center
    weights = rng.uniform(0.1, 3.0, size=40)
    ours = rotavg.average_single(samples, weights)
    theirs = Rotation.from_matrix(samples).mean(weights=weights).as_matrix()
    assert ours.estimate.shape == (3, 3)
    assert angle(ours.estimate, theirs) < 1e-9
    assert ours.certificate.certified and ours.certificate.method == "theory"
    # The cost is sum_i w_i ||R_i - R||_F^2.
    cost = float(np.sum(weights * np.sum((samples - ours.estimate) ** 2, axis=(1, 2))))
    assert ours.cost == pytest.approx(cost, rel=1e-12)


def test_scipy_rotation_accepted_as_input(rng):
    r = Rotation.from_matrix(small_rotations(rng, 25, 0.3))
    from_object = rotavg.average_single(r)
    from_array = rotavg.average_single(r.as_matrix())
    assert np.array_equal(from_object.estimate, from_array.estimate)
    assert angle(from_object.estimate, r.mean().as_matrix()) < 1e-9


def test_other_metrics_and_l1(rng):
    samples = small_rotations(rng, 30, 0.2)
    for metric, p in [("geodesic", 2), ("geodesic", 1), ("quaternion", 2), ("chordal", 1)]:
        res = rotavg.average_single(samples, metric=metric, p=p)
        d = res.to_dict()
        assert (d["metric"], d["p"]) == (metric, p)
        assert res.solver.converged and res.chordal_cost is None
        c = res.certificate
        assert c.lower_bound <= res.cost * (1 + 1e-12)
        # Closed forms and the pi/2-ball theorem certify; chordal L1 has only a convexity bound,
        # so `auto` falls back to the branch and bound over SO(3), which certifies it.
        assert c.certified
        assert c.method == ("branch_and_bound" if (metric, p) == ("chordal", 1) else "theory")


def test_l1_mean_ignores_an_outlier():
    # README example: I, I and a 60-degree rotation about z; the geodesic L1 mean is I.
    c, s = 0.5, np.sqrt(3) / 2
    samples = [np.eye(3), np.eye(3), [[c, -s, 0], [s, c, 0], [0, 0, 1]]]
    res = rotavg.average_single(samples, metric="geodesic", p=1)
    assert angle(res.estimate, np.eye(3)) < 1e-9


def test_certify_single_never_changes_the_estimate(rng):
    samples = small_rotations(rng, 20, 0.3)
    best = rotavg.average_single(samples)
    same = rotavg.certify_single(samples, best.estimate)
    assert same.solver is None and same.certificate.certified
    assert same.cost == pytest.approx(best.cost, rel=1e-12)
    worse = small_rotations(rng, 1, 0.5)[0] @ best.estimate
    res = rotavg.certify_single(samples, worse)
    assert not res.certificate.certified
    assert res.certificate.lower_bound <= best.cost * (1 + 1e-12)
    assert np.allclose(res.estimate, worse, atol=1e-12)


def test_same_output_as_the_command_line(rng, cli, tmp_path):
    samples = small_rotations(rng, 15, 0.4)
    weights = rng.uniform(0.5, 2.0, size=15)
    path = tmp_path / "single.json"
    path.write_text(json.dumps({"rotations": samples.tolist(), "weights": weights.tolist()}))
    for metric, p in [("chordal", 2), ("geodesic", 1)]:
        ours = rotavg.average_single(samples, weights, metric=metric, p=p).to_dict()
        theirs = cli("single", path, "--metric", metric, "--p", p)
        assert untimed(ours) == untimed(theirs)
    # certify: the estimate written as JSON is read back exactly (shortest round-trip floats).
    estimate = rotavg.average_single(samples, weights).estimate
    est_path = tmp_path / "estimate.json"
    est_path.write_text(json.dumps({"rotation": estimate.tolist()}))
    ours = rotavg.certify_single(samples, estimate, weights).to_dict()
    assert untimed(ours) == untimed(cli("certify", path, "--estimate", est_path))
