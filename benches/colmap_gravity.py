"""rotavg and COLMAP's rotation averaging (pycolmap.run_rotation_averaging: the global
mapper's stage, with `use_gravity`) side by side, without and with gravity priors, on one
scene written by `cargo run --release --example gravity_scene -- FOLDER ...` (or
examples/data/gravity: graph.json, a priors file, truth.txt).

    python benches/colmap_gravity.py FOLDER [PRIORS_FILE] [ROTAVG_BINARY] [GRAVITY_WEIGHT]

With GRAVITY_WEIGHT rotavg also runs with the priors as soft terms of that weight
(`--gravity-weight`, paper-notes/gravity.md [G10]).

Needs `pip install pycolmap numpy` (tested with pycolmap 4.2.1). COLMAP gets every edge with
`num_matches = 100` (uniform weights; a JSON view graph carries no correspondences) and the
priors with `gravity_dir = (0, 0, 1)`, the scene's world down direction (rotavg's default);
`cam2_from_cam1 = R_ij` (R_ij R_i = R_j); a pair measured twice gets its first measurement
(COLMAP's pose graph has one edge per pair). Errors: angle of `R_i G` against the truth after the
optimal alignment `G` (least squares over all cameras), degrees. Prints a Markdown table.
"""

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pycolmap as p


def load(folder, priors_name):
    graph = json.loads((folder / "graph.json").read_text())
    truth = np.loadtxt(folder / "truth.txt", comments="#")[:, 1:].reshape(-1, 3, 3)
    priors = {}
    for line in (folder / priors_name).read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            k, *g = line.split()
            priors[int(k)] = np.array([float(x) for x in g])
    return graph, truth, priors


def colmap(graph, priors, use_gravity):
    n = graph["num_rotations"]
    rec = p.Reconstruction()
    rec.add_camera_with_trivial_rig(
        p.Camera(camera_id=1, model="SIMPLE_PINHOLE", width=640, height=480, params=[500, 320, 240])
    )
    for i in range(n):
        rec.add_image_with_trivial_frame(p.Image(name=f"{i}.jpg", camera_id=1, image_id=i + 1))
    pose_graph = p.PoseGraph()
    for e in graph["edges"]:
        if pose_graph.has_edge(e["i"] + 1, e["j"] + 1):
            continue  # COLMAP keeps one measurement per pair: the first
        pose = np.hstack([np.array(e["rotation"], dtype=float), [[0.0], [0.0], [1.0]]])
        edge = p.PoseGraphEdge(p.Rigid3d(pose))
        edge.num_matches = 100
        pose_graph.add_edge(e["i"] + 1, e["j"] + 1, edge)
    pose_priors = []
    for k, g in priors.items() if use_gravity else []:
        prior = p.PosePrior()
        prior.corr_data_id = p.data_t(p.sensor_t(p.SensorType.CAMERA, 1), k + 1)
        prior.gravity = g
        pose_priors.append(prior)
    options = p.RotationEstimatorOptions()
    options.use_gravity = use_gravity
    options.gravity_dir = np.array([0.0, 0.0, 1.0])
    start = time.time()
    ok = p.run_rotation_averaging(options, pose_graph, rec, pose_priors)
    seconds = time.time() - start
    poses = [rec.frame(i + 1).rig_from_world for i in range(n)]
    rotations = [None if pose is None else pose.rotation.matrix() for pose in poses]
    return ok, seconds, rotations


def errors(est, truth):
    keep = [i for i, r in enumerate(est) if r is not None]
    m = sum(est[i].T @ truth[i] for i in keep)
    u, _, vt = np.linalg.svd(m)
    g = u @ np.diag([1, 1, np.linalg.det(u @ vt)]) @ vt
    cos = [(np.trace((est[i] @ g).T @ truth[i]) - 1) / 2 for i in keep]
    return np.degrees(np.arccos(np.clip(cos, -1, 1))), len(keep)


def rotavg(binary, folder, priors_name, use_gravity, weight=None):
    args = [binary, "multiple", str(folder / "graph.json"), "--json"]
    if use_gravity:
        args += ["--gravity", str(folder / priors_name)]
    if weight is not None:
        args += ["--gravity-weight", str(weight)]
    start = time.time()
    out = json.loads(subprocess.run(args, capture_output=True, text=True, check=True).stdout)
    seconds = time.time() - start
    verdict = out["verdict"]["verdict"] if out.get("verdict") else "none"
    return verdict, seconds, [np.array(r) for r in out["estimate"]]


def main():
    folder = Path(sys.argv[1])
    priors_name = sys.argv[2] if len(sys.argv) > 2 else "gravity.txt"
    binary = sys.argv[3] if len(sys.argv) > 3 else "target/release/rotavg"
    graph, truth, priors = load(folder, priors_name)
    print(f"{folder}: {graph['num_rotations']} cameras, {len(graph['edges'])} edges, "
          f"{len(priors)} priors\n")
    print("| tool | priors | median error (deg) | mean error (deg) | seconds | verdict |")
    print("|---|---|---|---|---|---|")
    for use_gravity in (False, True):
        verdict, seconds, est = rotavg(binary, folder, priors_name, use_gravity)
        e, _ = errors(est, truth)
        label = "held" if use_gravity else "none"
        print(f"| rotavg (whole process) | {label} | {np.median(e):.3f} | {e.mean():.3f} | "
              f"{seconds:.3f} | {verdict} |")
        ok, seconds, est = colmap(graph, priors, use_gravity)
        e, k = errors(est, truth)
        label = "use_gravity" if use_gravity else "none"
        print(f"| COLMAP rotation averaging | {label} | {np.median(e):.3f} | {e.mean():.3f} | "
              f"{seconds:.3f} | {'ok' if ok else 'failed'} ({k} posed) |")
    if len(sys.argv) > 4:
        weight = float(sys.argv[4])
        verdict, seconds, est = rotavg(binary, folder, priors_name, True, weight)
        e, _ = errors(est, truth)
        print(f"| rotavg (whole process) | soft, weight {weight:g} | {np.median(e):.3f} | "
              f"{e.mean():.3f} | {seconds:.3f} | {verdict} |")


if __name__ == "__main__":
    main()
