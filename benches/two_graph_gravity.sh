#!/bin/bash
# Gravity priors on two view graphs (docs/benchmarks.md "Gravity priors on two view graphs"):
# a generated pair of FRAMES frames (`rig_pair`, NOISE rad per axis) and priors of GDEG degrees
# on 90 % of its frames (`gravity_priors`), run without priors, held and soft of weight W; prints
# the frames' median / mean error after the optimal rotation onto the truth, S's error, the
# verdict and the whole process's seconds. Needs `cargo build --release --examples` and python3
# with numpy.
#
#   bash benches/two_graph_gravity.sh FRAMES SEED NOISE GDEG W
set -euo pipefail
B=${ROTAVG_TARGET:-target/release}
N=$1 S=$2 NOISE=$3 GDEG=$4 W=$5
D=$(mktemp -d)
"$B/examples/rig_pair" "$N" 0 "$S" "$D" "$NOISE"
"$B/examples/gravity_priors" "$D/truth.json" "$GDEG" 0.1 "$S" > "$D/gravity.txt"
for mode in none held soft; do
  case $mode in
    none) g=();;
    held) g=(--gravity "$D/gravity.txt");;
    soft) g=(--gravity "$D/gravity.txt" --gravity-weight "$W");;
  esac
  start=$(date +%s.%N)
  "$B/rotavg" rig "$D/right.json" "$D/left.json" "${g[@]}" --json --quiet --output "$D/est.json" > "$D/out.json" || true
  end=$(date +%s.%N)
  python3 - "$D" "$mode" "$N" "$S" "$start" "$end" <<'PY'
import json, sys
import numpy as np
d, mode, n, seed, t0, t1 = sys.argv[1:]
t, e, v = (json.load(open(f"{d}/{f}.json")) for f in ("truth", "est", "out"))
T, E = np.array(t["frames"]), np.array(e.get("rotations", e.get("frames")))
S = np.array(e["sensor_from_rig"] if "sensor_from_rig" in e else e["sensors_from_rig"][1])
u, _, vt = np.linalg.svd(sum(a.T @ b for a, b in zip(E, T)))
G = u @ np.diag([1, 1, np.linalg.det(u @ vt)]) @ vt
deg = lambda r: np.degrees(np.arccos(np.clip((np.trace(r) - 1) / 2, -1, 1)))
err = [deg((a @ G).T @ b) for a, b in zip(E, T)]
print(f"{n} frames, seed {seed}, {mode}: frames {np.median(err):.3f} / {np.mean(err):.3f} deg, "
      f"S {deg(S.T @ np.array(t['s'])):.3f} deg, {v['verdict']['verdict']} "
      f"{v['verdict']['problem']['kind']}, {float(t1) - float(t0):.2f} s")
PY
done
rm -rf "$D"
