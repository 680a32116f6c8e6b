"""Anisotropic measurements from Python: `information=` (M, 3, 3), the cost checked against a
NumPy evaluation of the closed form 4 (1 - cos theta) u^T H u, H = w I equal to weights=w, and
the errors that name the offending matrix. The Python block of docs/guides/anisotropic.md runs."""

import re

import numpy as np
import pytest

import rotavg
from conftest import REPO, random_rotations


def rotation_log(r):
    """The rotation vector of each rotation in `r` (angles below pi)."""
    theta = np.arccos(np.clip((np.trace(r, axis1=1, axis2=2) - 1) / 2, -1, 1))
    axial = np.stack([r[:, 2, 1] - r[:, 1, 2], r[:, 0, 2] - r[:, 2, 0], r[:, 1, 0] - r[:, 0, 1]], -1)
    scale = np.where(theta > 1e-12, theta / (2 * np.sin(np.maximum(theta, 1e-300))), 0.5)
    return axial * scale[:, None]


def anisotropic_graph(rng, n, m, sigma, ratio, weak_axes=1):
    """Truth, i, j, rel and H of a random connected graph with noise of standard deviations
    sigma, sigma, ratio * sigma along random axes (R_j R_i^T = rel exp([e]x)); with
    weak_axes=2, sigma, ratio * sigma, ratio * sigma (one well-determined axis)."""
    truth = random_rotations(rng, n)
    i = list(range(n - 1)) + list(rng.integers(0, n, size=m - n + 1))
    j = list(range(1, n)) + list(rng.integers(0, n, size=m - n + 1))
    keep = [k for k in range(m) if i[k] != j[k]]
    i, j = np.array(i)[keep], np.array(j)[keep]
    frames = random_rotations(rng, len(i))
    stds = np.array([sigma, sigma if weak_axes == 1 else ratio * sigma, ratio * sigma])
    info = frames @ np.diag(1 / stds**2) @ frames.transpose(0, 2, 1)
    info = 0.5 * (info + info.transpose(0, 2, 1))
    e = np.einsum("kab,kb->ka", frames, rng.normal(size=(len(i), 3)) * stds)
    noise = small_rotations_from(e)
    rel = truth[j] @ truth[i].transpose(0, 2, 1) @ noise.transpose(0, 2, 1)
    return truth, i, j, rel, info


def small_rotations_from(v):
    """exp([v]x) for each row of v (Rodrigues)."""
    theta = np.linalg.norm(v, axis=1)
    k = v / np.maximum(theta, 1e-300)[:, None]
    kx = np.zeros((len(v), 3, 3))
    kx[:, 0, 1], kx[:, 0, 2], kx[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    kx -= kx.transpose(0, 2, 1)
    s, c = np.sin(theta)[:, None, None], np.cos(theta)[:, None, None]
    return np.eye(3) + s * kx + (1 - c) * kx @ kx


def closed_form_cost(estimate, i, j, rel, info):
    """sum 4 (1 - cos theta) u^T H u with theta u = log(rel^T R_j R_i^T)."""
    v = rotation_log(rel.transpose(0, 2, 1) @ estimate[j] @ estimate[i].transpose(0, 2, 1))
    theta = np.linalg.norm(v, axis=1)
    u = v / np.maximum(theta, 1e-300)[:, None]
    return float(np.sum(4 * (1 - np.cos(theta)) * np.einsum("ka,kab,kb->k", u, info, u)))


def test_anisotropic_arrays_are_solved_and_certified(rng):
    truth, i, j, rel, info = anisotropic_graph(rng, 40, 160, np.radians(0.5), 10.0)
    res = rotavg.average_multiple(40, i, j, rel, information=info, ground_truth=truth)
    assert res.certificate.verdict == "certified"
    assert res.cost == pytest.approx(closed_form_cost(res.estimate, i, j, rel, info), rel=1e-9)
    d = res.to_dict()
    assert d["information"]["edges"] == len(i)
    assert d["information"]["max_anisotropy"] == pytest.approx(100.0, rel=1e-6)
    assert "anisotropic" in res.certificate.explanation
    # the certificate of the same estimate, computed from the arrays again
    again = rotavg.certify_multiple(40, i, j, rel, res.estimate, information=info)
    assert again.certificate.verdict == "certified"


def test_one_well_determined_axis_is_certified_over_conv_so3(rng):
    """Every M indefinite (standard deviations 0.5, 5, 5 degrees): the O(3) relaxation prefers
    reflections, the conv(SO(3)) dual certificate [A11] certifies; the cost is the closed form."""
    truth, i, j, rel, info = anisotropic_graph(rng, 60, 240, np.radians(0.5), 10.0, weak_axes=2)
    res = rotavg.average_multiple(60, i, j, rel, information=info)
    assert res.cost == pytest.approx(closed_form_cost(res.estimate, i, j, rel, info), rel=1e-9)
    cert = res.to_dict()["certificate"]
    assert cert["verdict"] == "certified", cert["explanation"]
    assert cert["bound_from"] == "conv_dual"
    assert "conv(SO(3))" in cert["explanation"]
    assert cert["lower_bound"] <= closed_form_cost(truth, i, j, rel, info)


def test_isotropic_information_equals_weights(rng):
    truth, i, j, rel, info = anisotropic_graph(rng, 20, 60, 0.05, 1.0)
    w = rng.uniform(0.5, 2.0, size=len(i))
    a = rotavg.average_multiple(20, i, j, rel, weights=w)
    b = rotavg.average_multiple(20, i, j, rel, information=w[:, None, None] * np.eye(3))
    assert b.cost == pytest.approx(a.cost, rel=1e-9)
    assert b.certificate.lower_bound == pytest.approx(a.certificate.lower_bound, rel=1e-8)


def test_bad_information_is_refused(rng):
    _, i, j, rel, info = anisotropic_graph(rng, 10, 20, 0.05, 3.0)
    bad = info.copy()
    bad[3, 0, 1] += 1e-3
    with pytest.raises(rotavg.Error, match=r"information\[3\].*not symmetric"):
        rotavg.average_multiple(10, i, j, rel, information=bad)
    with pytest.raises(rotavg.Error, match="weights or information"):
        rotavg.average_multiple(10, i, j, rel, weights=np.ones(len(i)), information=info)
    with pytest.raises(rotavg.Error, match="one 3x3 matrix per edge"):
        rotavg.average_multiple(10, i, j, rel, information=info[:-1])


def test_the_guide_runs(monkeypatch):
    text = (REPO / "docs" / "guides" / "anisotropic.md").read_text()
    blocks = re.findall(r"```python\n(.*?)```", text, re.S)
    assert blocks, "docs/guides/anisotropic.md has no Python example"
    monkeypatch.chdir(REPO)
    for code in blocks:
        exec(compile(code, "<anisotropic guide>", "exec"), {"__name__": "__main__"})


def test_geodesic_and_robust_losses_apply_to_the_mahalanobis_angle(rng):
    """loss="geodesic" minimises sum e^T H e, loss="huber" the Huber loss of the Mahalanobis
    angle theta_H = sqrt(e^T H e / wbar), wbar = tr(H)/3, weighted by wbar (NumPy closed forms)."""
    truth, i, j, rel, info = anisotropic_graph(rng, 30, 120, np.radians(0.5), 10.0)

    def residuals(estimate):
        v = rotation_log(rel.transpose(0, 2, 1) @ estimate[j] @ estimate[i].transpose(0, 2, 1))
        return np.einsum("ka,kab,kb->k", v, info, v), np.trace(info, axis1=1, axis2=2) / 3

    g = rotavg.average_multiple(30, i, j, rel, information=info, loss="geodesic")
    quad, _ = residuals(g.estimate)
    assert g.cost == pytest.approx(float(np.sum(quad)), rel=1e-9)
    h = rotavg.average_multiple(30, i, j, rel, information=info, loss="huber", loss_threshold=2.0)
    quad, wbar = residuals(h.estimate)
    t, c = np.sqrt(quad / wbar), np.radians(2.0)
    rho = np.where(t <= c, t**2, 2 * c * t - c**2)
    assert h.cost == pytest.approx(float(np.sum(wbar * rho)), rel=1e-9)


def test_information_built_as_jt_w_j_is_accepted(rng):
    """``J.T @ W @ J`` in numpy is symmetric only to rounding: accepted (its symmetric part),
    with the same result as the symmetrised matrices and a warning that says so."""
    _, i, j, rel, _ = anisotropic_graph(rng, 10, 24, 0.05, 3.0)
    jac = rng.normal(size=(len(i), 5, 3))
    w = np.einsum("ka,ab->kab", rng.uniform(0.5, 2.0, size=(len(i), 5)), np.eye(5))
    info = jac.transpose(0, 2, 1) @ w @ jac
    asym = np.abs(info - info.transpose(0, 2, 1)).max()
    sym = 0.5 * (info + info.transpose(0, 2, 1))
    a = rotavg.average_multiple(10, i, j, rel, information=info, loss="chordal")
    b = rotavg.average_multiple(10, i, j, rel, information=sym, loss="chordal")
    assert a.cost == pytest.approx(b.cost, rel=1e-12)
    # (random pairs may be measured twice: `duplicates_disagree` is not this test's)
    codes = [w["code"] for w in a.to_dict()["warnings"] if w["code"] != "duplicates_disagree"]
    assert codes == (["information_symmetrized"] if asym > 0 else [])
    codes = [w["code"] for w in b.to_dict()["warnings"]]
    assert "information_symmetrized" not in codes
