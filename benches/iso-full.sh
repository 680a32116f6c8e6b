#!/bin/bash
# `--information full` against scalar weights on every shared g2o file: the certify seconds of
# `rotavg multiple FILE [--information full] --json`, 3 interleaved runs each, their medians
# and the verdict (docs/benchmarks.md "`--information full` on exactly isotropic information").
#   bash benches/iso-full.sh [BINARY]      # default target/release/rotavg
# DATA: the shared data folder (default ../shared/data beside the repository; fetch it with
# benches/fetch-data.sh). Files that are missing are skipped.
set -euo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
B="${1:-$REPO/target/release/rotavg}"
DATA="${DATA:-$REPO/../shared/data}"
runs=$(mktemp)
trap 'rm -f "$runs"' EXIT
for f in "$DATA"/g2o/3d/*/*.g2o "$DATA"/g2o/2d/sesync/*.g2o; do
  [[ -f "$f" ]] || { echo "skipped: $f is missing" >&2; continue; }
  for _ in 1 2 3; do
    for mode in scalar full; do
      opts=()
      [[ $mode == full ]] && opts=(--information full)
      "$B" multiple "$f" "${opts[@]}" --json 2>/dev/null | python3 -c "
import json, sys
d = json.load(sys.stdin)
i = d.get('information') or {}
print('$(basename "$f")', '$mode', d['pipeline']['certify_seconds'], d['certificate']['verdict'],
      'yes' if i.get('scalar_weights') or '$mode' == 'scalar' else 'no')" >> "$runs"
    done
  done
done
python3 - "$runs" <<'EOF'
import collections, statistics, sys
t, v = collections.defaultdict(list), {}
for line in open(sys.argv[1]):
    f, mode, s, verdict, scalar = line.split()
    t[(f, mode)].append(float(s))
    v[(f, mode)] = (verdict, scalar)
print("| file | scalar weights | `--information full` | full / scalar | verdict (full) | solved as scalar weights |")
print("|---|---|---|---|---|---|")
for f in sorted({k[0] for k in t}):
    a, b = statistics.median(t[(f, "scalar")]), statistics.median(t[(f, "full")])
    print(f"| {f} | {a:.4f} | {b:.4f} | {b / a:.2f} | {v[(f, 'full')][0]} | {v[(f, 'full')][1]} |")
EOF
