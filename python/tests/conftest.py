"""Shared fixtures: the shared benchmark data, the `rotavg` command line, seeded rotations."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

REPO = Path(__file__).resolve().parents[2]

#: Keys whose values are wall times: they differ between any two runs.


def untimed(value):
    """`value` (a --json object) without its wall times (every key containing `seconds`, as
    the command line's JSON contract test removes them) and without its `input` record (the
    paths it names differ between a file read by the command line and arrays given in
    Python), for exact comparisons."""
    if isinstance(value, dict):
        return {
            k: untimed(v) for k, v in value.items() if "seconds" not in k and k != "input"
        }
    if isinstance(value, list):
        return [untimed(v) for v in value]
    return value


def skip(reason):
    """Skip with a notice that shows in the output even without -rs."""
    print(f"SKIPPED: {reason}", file=sys.stderr)
    pytest.skip(reason)


@pytest.fixture(scope="session")
def data_dir():
    """The shared benchmark data (../shared/data beside the repository, or /work/shared/data)."""
    for d in (REPO.parent / "shared" / "data", Path("/work/shared/data")):
        if d.is_dir():
            return d
    skip("shared data absent (looked in ../shared/data and /work/shared/data)")


@pytest.fixture(scope="session")
def cli():
    """Run the `rotavg` command line with --json and return its parsed output.

    The binary is $ROTAVG_CLI, else target/release/rotavg of this repository, else `rotavg` on
    PATH.
    """
    required = os.environ.get("ROTAVG_CLI")
    if required and not Path(required).is_file():
        pytest.fail(f"ROTAVG_CLI={required} does not exist")
    candidates = [required, str(REPO / "target" / "release" / "rotavg")]
    exe = next((c for c in candidates if c and Path(c).is_file()), None) or shutil.which("rotavg")
    if exe is None:
        skip("rotavg command line not built (cargo build --release, or set ROTAVG_CLI)")

    def run(*args):
        out = subprocess.run([exe, *map(str, args), "--json"], capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        return json.loads(out.stdout)

    return run


@pytest.fixture
def rng():
    return np.random.default_rng(20261125)


def random_rotations(rng, n):
    """`n` uniformly random rotations (normalised Gaussian quaternions), shape (n, 3, 3)."""
    q = rng.normal(size=(n, 4))
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


def small_rotations(rng, n, sigma):
    """`n` rotations exp(v) with v ~ N(0, sigma^2 I) (Rodrigues), shape (n, 3, 3)."""
    v = rng.normal(scale=sigma, size=(n, 3))
    theta = np.linalg.norm(v, axis=1)
    k = v / np.maximum(theta, 1e-300)[:, None]
    kx = np.zeros((n, 3, 3))
    kx[:, 0, 1], kx[:, 0, 2], kx[:, 1, 2] = -k[:, 2], k[:, 1], -k[:, 0]
    kx -= kx.transpose(0, 2, 1)
    s, c = np.sin(theta)[:, None, None], np.cos(theta)[:, None, None]
    return np.eye(3) + s * kx + (1 - c) * kx @ kx


def synthetic_graph(rng, n, m, sigma):
    """A connected view graph (a random spanning tree plus random edges) of `n` nodes and `m`
    edges with noise `sigma` (rad): truth (n, 3, 3) and i, j, rel with rel[k] @ R_i = R_j."""
    truth = random_rotations(rng, n)
    tree_j = np.arange(1, n)
    tree_i = np.array([rng.integers(0, k) for k in tree_j])
    extra = m - (n - 1)
    i = rng.integers(0, n, size=extra)
    j = (i + rng.integers(1, n, size=extra)) % n
    i, j = np.concatenate([tree_i, i]), np.concatenate([tree_j, j])
    rel = small_rotations(rng, m, sigma) @ truth[j] @ truth[i].transpose(0, 2, 1)
    return truth, i, j, rel
