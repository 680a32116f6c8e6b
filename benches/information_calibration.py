"""Is a COLMAP database's two-view information calibrated? For each correct pair of a
generated scene (`pairs.json` kind `inlier`), the Mahalanobis error `e^T H e` of its stored
rotation against the truth (`e` the right perturbation, `[F13]`), grouped by the pair's
translation-direction uncertainty `sigma_tau` (the largest marginal standard deviation of the
direction under the 5x5 Sampson Fisher information, here by finite differences). Calibrated
information gives `chi^2_3`: median 2.37, 90 % quantile 6.25.

    python benches/information_calibration.py DIR [SENSORS]

DIR from `cargo run --release --example colmap_scene -- DIR ...`; SENSORS (default 1) counts
the pairs of two images of one frame (`--rig-sensors`). Needs the Python package (`pip install
./python`), numpy and scipy. PINHOLE cameras only (the generator's).
"""

import collections
import json
import sqlite3
import sys

import numpy as np
import rotavg
from scipy.spatial.transform import Rotation


def hat(v):
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def sampson(r, t, x1, x2, f):
    e = hat(t) @ r
    l2, l1 = (e @ x1.T).T, (e.T @ x2.T).T
    den = np.sqrt(l2[:, 0] ** 2 + l2[:, 1] ** 2 + l1[:, 0] ** 2 + l1[:, 1] ** 2)
    return np.sum(x2 * l2, 1) / den * f


def sigma_tau_deg(r0, t, x1, x2, f):
    t0 = t / np.linalg.norm(t)
    b1 = np.cross(t0, [1, 0, 0] if abs(t0[0]) < 0.9 else [0, 1, 0])
    b1 /= np.linalg.norm(b1)
    b2 = np.cross(t0, b1)

    def residual(p):
        tt = t0 + p[3] * b1 + p[4] * b2
        return sampson(r0 @ Rotation.from_rotvec(p[:3]).as_matrix(), tt / np.linalg.norm(tt), x1, x2, f)

    h, base = 1e-7, residual(np.zeros(5))
    jac = np.stack([(residual(np.eye(5)[i] * h) - base) / h for i in range(5)], 1)
    cov = np.linalg.inv(jac.T @ jac)
    return np.degrees(np.sqrt(np.linalg.eigvalsh(cov[3:, 3:]).max()))


def main():
    folder, sensors = sys.argv[1], int(sys.argv[2]) if len(sys.argv) > 2 else 1
    g = rotavg.read_graph(f"{folder}/database.db", information="full",
                          ground_truth=f"{folder}/truth/images.txt")
    kinds = {(p["image_id1"], p["image_id2"]): p["kind"]
             for p in json.load(open(f"{folder}/pairs.json"))["pairs"]}
    db = sqlite3.connect(f"{folder}/database.db")
    params = {c: np.frombuffer(p, np.float64) for c, p in db.execute("select camera_id, params from cameras")}
    camera = dict(db.execute("select image_id, camera_id from images"))
    keypoints = {i: np.frombuffer(b, np.float32).reshape(r, c)[:, :2].astype(float)
                 for i, r, c, b in db.execute("select image_id, rows, cols, data from keypoints")}
    geometry = {}
    for pid, rows, data, q, t in db.execute(
            "select pair_id, rows, data, qvec, tvec from two_view_geometries where rows > 0"):
        i2 = pid % 2147483647
        geometry[((pid - i2) // 2147483647, i2)] = (
            np.frombuffer(data, np.uint32).reshape(rows, 2), np.frombuffer(q), np.frombuffer(t))

    def normalised(image, idx):
        p = params[camera[image]]
        x = keypoints[image][idx]
        return np.c_[(x[:, 0] - p[-2]) / p[0], (x[:, 1] - p[-1]) / p[1], np.ones(len(x))], p[0]

    groups = collections.defaultdict(list)
    for k in range(g.num_edges):
        a, b = int(g.node_ids[g.i[k]]), int(g.node_ids[g.j[k]])
        key = (min(a, b), max(a, b))
        if key not in geometry or kinds.get(key) != "inlier" or np.isnan(g.truth[g.i[k]]).any():
            continue
        matches, q, t = geometry[key]
        if np.linalg.norm(t) == 0:
            continue
        r0 = Rotation.from_quat([q[1], q[2], q[3], q[0]]).as_matrix()
        x1, f = normalised(key[0], matches[:, 0])
        x2, _ = normalised(key[1], matches[:, 1])
        s = sigma_tau_deg(r0, t, x1, x2, f)
        e = Rotation.from_matrix(g.rel[k].T @ g.truth[g.j[k]] @ g.truth[g.i[k]].T).as_rotvec()
        band = next(lo for lo in (20, 10, 5, 2, 1, 0) if s >= lo)
        groups[band].append((e @ g.information[k] @ e, (a - 1) // sensors == (b - 1) // sensors))
    print("| sigma_tau (deg) | pairs (of one frame) | median | 90 % | 99 % |")
    print("|---|---|---|---|---|")
    for band in sorted(groups):
        q = np.array([x[0] for x in groups[band]])
        same = sum(x[1] for x in groups[band]) if sensors > 1 else 0
        print(f"| {band}+ | {len(q)} ({same}) | {np.median(q):.2f} | {np.quantile(q, .9):.1f} | "
              f"{np.quantile(q, .99):.0f} |")


main()
