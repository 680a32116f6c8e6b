"""rotavg and COLMAP's rotation averaging on rigs (pycolmap.run_rotation_averaging, the global
mapper's stage, which expands rigs and estimates unknown cam_from_rig rotations) side by side, on
one rig in the JSON rig format (`rotavg rig FILE`) with its truth (`truth.json`: "frames" and
"sensors_from_rig", as `examples/data/rig_sensors/` or `tests/suite/example_data.rs` write them).

    python benches/colmap_rig.py FOLDER [ROTAVG_BINARY] [PRIORS_FILE [GRAVITY_WEIGHT]]

Needs `pip install pycolmap numpy` (tested with pycolmap 4.2.1). COLMAP gets one rig (sensor 0
the reference; sensors with a known `sensor_from_rig` given it, the others unknown), one frame
per rig frame, every edge with `num_matches = 100` (uniform weights) and `cam2_from_cam1 = R_ab`
(`R_ab X_a = X_b`, image ids a + 1); a pair measured twice gets its first measurement. Errors:
frames, the angle of `F_f G` against the truth after the optimal alignment `G` (least squares
over all frames); sensors, the angle of `S_s` against the truth (the reference sensor fixes
their gauge). Prints a Markdown row per tool.

With PRIORS_FILE (`IMAGE gx gy gz` lines, the image's index in rig.json, as `cargo run --release
--example rig_gravity -- write` writes; every sensor known), each tool also runs with the priors:
rotavg `--gravity PRIORS_FILE` (soft with `--gravity-weight GRAVITY_WEIGHT` when given,
paper-notes/gravity.md [G14]), COLMAP with a `PosePrior` per image (`gravity = g`,
`use_gravity`, `gravity_dir = (0, 0, 1)`, the world down direction of the priors).
"""

import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pycolmap as p


def angle(a, b):
    return np.degrees(np.arccos(np.clip((np.trace(a.T @ b) - 1) / 2, -1, 1)))


def frame_errors(est, truth):
    keep = [f for f, r in enumerate(est) if r is not None]
    m = sum(est[f].T @ truth[f] for f in keep)
    u, _, vt = np.linalg.svd(m)
    g = u @ np.diag([1, 1, np.linalg.det(u @ vt)]) @ vt
    return np.array([angle(est[f] @ g, truth[f]) for f in keep]), len(keep)


def reconstruction(rig):
    rec, r = p.Reconstruction(), p.Rig(rig_id=1)
    for s, sensor in enumerate(rig["sensors"]):
        rec.add_camera(p.Camera(camera_id=s + 1, model="SIMPLE_PINHOLE", width=640, height=480,
                                params=[500, 320, 240]))
        sid = p.sensor_t(p.SensorType.CAMERA, s + 1)
        if s == 0:
            r.add_ref_sensor(sid)
        else:
            known = sensor.get("sensor_from_rig")
            r.add_sensor(sid, None if known is None else
                         p.Rigid3d(p.Rotation3d(np.array(known)), np.zeros(3)))
    rec.add_rig(r)
    for f in range(rig["num_frames"]):
        frame = p.Frame(frame_id=f + 1, rig_id=1)
        for a, im in enumerate(rig["images"]):
            if im["frame"] == f:
                frame.add_data_id(p.data_t(p.sensor_t(p.SensorType.CAMERA, im["sensor"] + 1), a + 1))
        rec.add_frame(frame)
    for a, im in enumerate(rig["images"]):
        image = p.Image(name=f"{a}.jpg", camera_id=im["sensor"] + 1, image_id=a + 1)
        image.frame_id = im["frame"] + 1
        rec.add_image(image)
    return rec


def colmap(rig, priors=None):
    rec, graph = reconstruction(rig), p.PoseGraph()
    for e in rig["edges"]:
        i, j, rot = e["i"] + 1, e["j"] + 1, np.array(e["rotation"], dtype=float)
        if i > j:
            i, j, rot = j, i, rot.T
        if graph.has_edge(i, j):
            continue
        edge = p.PoseGraphEdge(p.Rigid3d(np.hstack([rot, [[0.0], [0.0], [1.0]]])))
        edge.num_matches = 100
        graph.add_edge(i, j, edge)
    options, pose_priors = p.RotationEstimatorOptions(), []
    for a, g in (priors or {}).items():
        prior = p.PosePrior()
        sensor = p.sensor_t(p.SensorType.CAMERA, rig["images"][a]["sensor"] + 1)
        prior.corr_data_id = p.data_t(sensor, a + 1)
        prior.gravity = g
        pose_priors.append(prior)
    if priors:
        options.use_gravity = True
        options.gravity_dir = np.array([0.0, 0.0, 1.0])
    start = time.time()
    ok = p.run_rotation_averaging(options, graph, rec, pose_priors)
    seconds = time.time() - start
    poses = [rec.frame(f + 1).rig_from_world for f in range(rig["num_frames"])]
    frames = [None if q is None else q.rotation.matrix() for q in poses]
    sensors = [np.eye(3)]
    for s in range(1, len(rig["sensors"])):
        q = rec.rig(1).sensor_from_rig(p.sensor_t(p.SensorType.CAMERA, s + 1))
        sensors.append(None if q is None else q.rotation.matrix())
    return ("ok" if ok else "failed"), seconds, frames, sensors


def rotavg(binary, path, gravity=()):
    start = time.time()
    out = subprocess.run([binary, "rig", str(path), "--json", *gravity], capture_output=True,
                         text=True, check=True)
    seconds = time.time() - start
    v = json.loads(out.stdout)
    verdict = v["verdict"]["verdict"] + " (" + v["verdict"]["problem"]["kind"] + ")"
    return (verdict, seconds, [np.array(r) for r in v["estimate"]],
            [np.array(r) for r in v["sensors_from_rig"]])


def read_priors(path):
    priors = {}
    for line in path.read_text().splitlines():
        if line.strip() and not line.startswith("#"):
            k, *g = line.split()
            priors[int(k)] = np.array([float(x) for x in g[:3]])
    return priors


def main():
    folder = Path(sys.argv[1])
    binary = sys.argv[2] if len(sys.argv) > 2 else "target/release/rotavg"
    rig = json.loads((folder / "rig.json").read_text())
    truth = json.loads((folder / "truth.json").read_text())
    tf = [np.array(r) for r in truth["frames"]]
    ts = [np.array(r) for r in truth["sensors_from_rig"]]
    runs = [("rotavg rig (whole process)", lambda: rotavg(binary, folder / "rig.json")),
            ("COLMAP rotation averaging", lambda: colmap(rig))]
    if len(sys.argv) > 3:
        gravity = ["--gravity", str(folder / sys.argv[3])]
        if len(sys.argv) > 4:
            gravity += ["--gravity-weight", sys.argv[4]]
        priors = read_priors(folder / sys.argv[3])
        name = "rotavg rig --gravity" + (f" (weight {sys.argv[4]})" if len(sys.argv) > 4 else "")
        runs += [(name, lambda: rotavg(binary, folder / "rig.json", gravity)),
                 ("COLMAP, use_gravity", lambda: colmap(rig, priors))]
    for name, run in runs:
        verdict, seconds, frames, sensors = run()
        e, k = frame_errors(frames, tf)
        s = max(angle(a, b) for a, b in zip(sensors, ts) if a is not None)
        print(f"| {folder.name} | {name} | {np.median(e):.3f} | {e.mean():.3f} | {s:.3f} | "
              f"{seconds:.3f} | {verdict}, {k} frames posed |")


if __name__ == "__main__":
    main()
