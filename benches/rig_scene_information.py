"""`rotavg rig` on generated rig scenes with correspondences, with weights 1 and with each
pair's information (`--information kappa` / `full`): the frames' and the sensors' errors against
the truth, the time and the verdict. Scenes: `cargo run --release --example colmap_scene -- DIR
--cameras N --rig-sensors K [--seed S] [--rig-known]` (its `truth/rig.json` holds the planted
frames and `sensors_from_rig`).

    python benches/rig_scene_information.py ROTAVG_BINARY DIR [DIR ...]

Each cell is one whole process, `rotavg rig DIR/database.db --json --information I`. Errors:
frames, the median angle of `F_f G` against the truth after the least-squares alignment `G`
over the frames; sensors, the largest angle of an estimated `S_s` against the truth (sensor 0,
the reference, fixes their gauge). Prints a Markdown table (docs/benchmarks.md, "Rigs with
their information"). Needs numpy.
"""

import json
import subprocess
import sys
import time

import numpy as np


def angle(a, b):
    return np.degrees(np.arccos(np.clip((np.trace(a.T @ b) - 1) / 2, -1, 1)))


def errors(report, truth):
    frames = [np.array(r) for r in report["estimate"]]
    true = [np.array(truth["frames"][f - 1]) for f in report["frame_ids"]]
    u, _, vt = np.linalg.svd(sum(e.T @ t for e, t in zip(frames, true)))
    g = u @ np.diag([1, 1, np.linalg.det(u @ vt)]) @ vt
    frame = float(np.median([angle(e @ g, t) for e, t in zip(frames, true)]))
    sensors = [np.array(s) for s in report["sensors_from_rig"]]
    true_s = [np.array(truth["sensors_from_rig"][s - 1]) for s in report["sensor_ids"]]
    return frame, max(angle(e, t) for e, t in zip(sensors, true_s))


def cell(binary, folder, information):
    start = time.time()
    out = subprocess.run(
        [binary, "rig", f"{folder}/database.db", "--json", "--information", information],
        capture_output=True, text=True)
    if out.returncode != 0:
        return "error: " + out.stderr.strip().splitlines()[-1]
    report = json.loads(out.stdout)
    truth = json.load(open(f"{folder}/truth/rig.json"))
    frame, sensor = errors(report, truth)
    verdict = (report.get("verdict") or {}).get("status") or report["certificate"]["verdict"]
    return f"{frame:.4f} / {sensor:.4f}, {verdict} ({time.time() - start:.1f} s)"


def main():
    binary, folders = sys.argv[1], sys.argv[2:]
    print("| scene | weights 1 (`--information kappa`) | information (`--information full`) |")
    print("|---|---|---|")
    for folder in folders:
        cells = [cell(binary, folder, i) for i in ("kappa", "full")]
        print(f"| {folder} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
