#!/bin/bash
# Robust averaging with gravity priors and information matrices (docs/benchmarks.md "Robust
# averaging with gravity priors and information"): a generated SfM scene with correspondences
# (`colmap_scene`, CAMERAS images, seed 1) read with `--information full`, priors of GDEG degrees
# on every image (`gravity_priors`), the default robust solve without priors, held and soft of
# weight W; `--certify none` unless CERTIFY=1. Prints the median / mean error against the truth
# (rotavg's own report after the optimal alignment), the solve's seconds and the verdict. BIN is
# the rotavg binary (an A/B runs the script twice). Needs `cargo build --release --examples`.
#
#   bash benches/gravity_information.sh CAMERAS GDEG W [BIN]
set -euo pipefail
B=${ROTAVG_TARGET:-target/release}
N=$1 GDEG=$2 W=$3 BIN=${4:-$B/rotavg}
D=${SCENE_DIR:-/tmp/rotavg-gravity-information-$N}
[ -f "$D/database.db" ] || "$B/examples/colmap_scene" "$D" --cameras "$N" --seed 1 > /dev/null
"$B/examples/gravity_priors" "$D/truth" "$GDEG" 0 1 "$D/database.db" > "$D/gravity-$GDEG.txt"
certify=(--certify none)
[ "${CERTIFY:-0}" = 1 ] && certify=()
for mode in none held soft; do
  case $mode in
    none) g=();;
    held) g=(--gravity "$D/gravity-$GDEG.txt" --world-down 0,0,-1);;
    soft) g=(--gravity "$D/gravity-$GDEG.txt" --world-down 0,0,-1 --gravity-weight "$W");;
  esac
  out=$("$BIN" multiple "$D/database.db" --information full "${g[@]}" --ground-truth "$D/truth" \
    "${certify[@]}" --max-seconds "${MAX_SECONDS:-600}" 2>&1 || true)
  acc=$(echo "$out" | grep -A1 "^accuracy" | tr '\n' ' ')
  med=$(echo "$acc" | sed 's/.*median \([0-9.]*\).*/\1/')
  mean=$(echo "$acc" | sed 's/.*mean \([0-9.]*\).*/\1/')
  times=$(echo "$out" | grep "^times" | sed 's/times: //')
  verdict=$(echo "$out" | grep "^verdict" | cut -c10- | cut -d' ' -f1 || true)
  echo "| $N | $GDEG deg $mode | $med / $mean | $times | ${verdict:--} |"
done
