"""rotavg and COLMAP's global-mapper rotation averaging (pycolmap.run_rotation_averaging) on the
same COLMAP database, one written by `cargo run --release --example colmap_scene -- FOLDER ...`
(keypoints, matches and two-view geometries estimated from noisy correspondences, with twisted
pairs, repeated structure and near-pure rotations; ground truth in FOLDER/truth).

    python benches/colmap_scene.py FOLDER [ROTAVG_BINARY] [--weights-1-only]

`--weights-1-only` skips the `--information full` runs (at 10^3 cameras and more their
certificate alone takes minutes; see docs/benchmarks.md).

Needs `pip install pycolmap numpy` (tested with pycolmap 4.2.1). COLMAP gets every two-view
geometry with a relative pose (`cam2_from_cam1 = R_ij`, R_ij R_i = R_j; panoramic pairs with
t = 0) and its inlier count as `num_matches`, default `RotationEstimatorOptions` (its L1 then
IRLS averaging). rotavg runs are whole processes (read, solve, certify): the default
(`--loss auto`) with weights 1 and with `--information full` (each pair's information from its
correspondences), Cauchy, and least squares. Errors: angle of `R_i G` against the truth after the
optimal alignment `G` (least squares over all posed cameras), and the median after the robust
alignment (the geodesic L1 mean of the differences, as `rotavg --ground-truth` reports it),
degrees. Prints a Markdown table.
"""

import json
import sqlite3
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pycolmap as p

PAIR_BASE = 2147483647


def quat_to_matrix(w, x, y, z):
    n = np.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


def load_truth(folder):
    truth = {}
    for line in (folder / "truth" / "images.txt").read_text().splitlines():
        fields = line.split()
        if len(fields) >= 10 and not line.startswith("#"):
            truth[int(fields[0])] = quat_to_matrix(*map(float, fields[1:5]))
    return truth


def load_geometries(db):
    con = sqlite3.connect(f"file:{db}?mode=ro", uri=True)
    images = dict(con.execute("SELECT image_id, name FROM images"))
    pairs = []
    for pair_id, rows, qvec in con.execute(
            "SELECT pair_id, rows, qvec FROM two_view_geometries WHERE qvec IS NOT NULL"):
        b = pair_id % PAIR_BASE
        a = (pair_id - b) // PAIR_BASE
        w, x, y, z = np.frombuffer(qvec, dtype="<f8")[:4]
        pairs.append((int(a), int(b), quat_to_matrix(w, x, y, z), int(rows)))
    return images, pairs


def colmap(images, pairs):
    rec = p.Reconstruction()
    rec.add_camera_with_trivial_rig(
        p.Camera(camera_id=1, model="SIMPLE_PINHOLE", width=640, height=480, params=[700, 320, 240]))
    for image_id, name in sorted(images.items()):
        rec.add_image_with_trivial_frame(p.Image(name=name, camera_id=1, image_id=image_id))
    graph = p.PoseGraph()
    for a, b, r, inliers in pairs:
        edge = p.PoseGraphEdge(p.Rigid3d(np.hstack([r, [[0.0], [0.0], [1.0]]])))
        edge.num_matches = inliers
        graph.add_edge(a, b, edge)
    start = time.time()
    ok = p.run_rotation_averaging(p.RotationEstimatorOptions(), graph, rec, [])
    seconds = time.time() - start
    est = {}
    for image_id in images:
        pose = rec.frame(image_id).rig_from_world
        if pose is not None:
            est[image_id] = pose.rotation.matrix()
    return ("ok" if ok else "failed"), seconds, est


def angles(est, truth, keep, g):
    cos = [(np.trace((est[k] @ g).T @ truth[k]) - 1) / 2 for k in keep]
    return np.degrees(np.arccos(np.clip(cos, -1, 1)))


def log_so3(r):
    """The rotation vector of `r` (angles below pi - 1e-6; an alignment step never nears pi)."""
    t = np.arccos(np.clip((np.trace(r) - 1) / 2, -1, 1))
    w = np.array([r[2, 1] - r[1, 2], r[0, 2] - r[2, 0], r[1, 0] - r[0, 1]]) / 2
    return w if t < 1e-12 else w * t / np.sin(t)


def exp_so3(w):
    t = np.linalg.norm(w)
    k = np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])
    if t < 1e-12:
        return np.eye(3) + k
    return np.eye(3) + np.sin(t) / t * k + (1 - np.cos(t)) / t**2 * k @ k


def errors(est, truth):
    """Errors after the least-squares alignment `G` (the projection of sum R_i^T T_i) and after
    the robust one (the geodesic L1 mean of R_i^T T_i by Weiszfeld steps from `G`, as
    `rotavg --ground-truth` reports it: a few cameras far off do not turn the others)."""
    keep = [k for k in est if k in truth]
    m = sum(est[k].T @ truth[k] for k in keep)
    u, _, vt = np.linalg.svd(m)
    g = u @ np.diag([1, 1, np.linalg.det(u @ vt)]) @ vt
    d = [est[k].T @ truth[k] for k in keep]
    g1 = g
    for _ in range(200):
        v = [log_so3(g1.T @ x) for x in d]
        w = [1 / max(np.linalg.norm(x), 1e-9) for x in v]
        step = sum(wi * vi for wi, vi in zip(w, v)) / sum(w)
        g1 = g1 @ exp_so3(step)
        if np.linalg.norm(step) < 1e-12:
            break
    return angles(est, truth, keep, g), angles(est, truth, keep, g1), len(keep)


def rotavg(binary, db, args):
    start = time.time()
    run = subprocess.run([binary, "multiple", str(db), "--json", *args], capture_output=True, text=True)
    seconds = time.time() - start
    if run.returncode not in (0, 3):
        return f"error: {run.stderr.strip()[-120:]}", seconds, {}
    out = json.loads(run.stdout)
    v = out.get("verdict") or {}
    kind = (v.get("problem") or {}).get("kind", "")
    verdict = f"{v.get('verdict', 'none')} ({kind})"
    est = {int(i): np.array(r) for i, r in zip(out["node_ids"], out["estimate"])}
    return verdict, seconds, est


RUNS = [
    ("rotavg default, weights 1", []),
    ("rotavg default, --information full", ["--information", "full"]),
    ("rotavg --loss cauchy, weights 1", ["--loss", "cauchy"]),
    ("rotavg --loss cauchy, --information full", ["--loss", "cauchy", "--information", "full"]),
    ("rotavg --loss chordal, weights 1", ["--loss", "chordal"]),
    ("rotavg --loss chordal, --information full", ["--loss", "chordal", "--information", "full"]),
]


def main():
    flags = [a for a in sys.argv[1:] if a.startswith("--")]
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    folder = Path(args[0])
    binary = args[1] if len(args) > 1 else "target/release/rotavg"
    runs = [(label, a) for label, a in RUNS if "--weights-1-only" not in flags or "full" not in a]
    db = folder / "database.db"
    truth = load_truth(folder)
    images, pairs = load_geometries(db)
    print(f"{folder}: {len(images)} images, {len(pairs)} two-view geometries with a pose\n")
    print("| run | median error (deg) | mean error (deg) | median, robust alignment | posed | seconds "
          "| verdict (problem) |")
    print("|---|---|---|---|---|---|---|")
    rows = [(label, *rotavg(binary, db, a)) for label, a in runs]
    rows.append(("COLMAP rotation averaging (pycolmap)", *colmap(images, pairs)))
    for label, verdict, seconds, est in rows:
        if not est:
            print(f"| {label} | - | - | - | 0 | {seconds:.2f} | {verdict} |")
            continue
        e, r, k = errors(est, truth)
        print(f"| {label} | {np.median(e):.3f} | {e.mean():.3f} | {np.median(r):.3f} | {k} "
              f"| {seconds:.2f} | {verdict} |")


if __name__ == "__main__":
    main()
