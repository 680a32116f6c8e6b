#!/usr/bin/env bash
# The README's hard-instance table (issue 25): random view graphs with outliers and large noise,
# each solved and certified by `rotavg multiple FILE --json` under the default budget (one
# process per row, peak RSS from GNU time), and, for the sizes they reach, the same SDP solved
# by cvxpy + SCS and cvxpy + Clarabel through ../shared/peers/sdp_cvxpy.py (never copied here).
#
#   cargo build --release --example pipeline_scale --bin rotavg
#   PEERS_PY=/tmp/rotavg-peers/peers/.venv/bin/python bash benches/hard_table.sh > /tmp/hard.md
#
# ROWS: "N:M:SIGMA_DEG:OUTLIER_FRACTION ..." (graphs from `pipeline_scale random N M SIGMA
# --outliers F --write-g2o`, seed fixed by the generator). PEER_MAX_N (default 150): the
# largest n given to cvxpy + SCS; CLARABEL_MAX_N (default 60) for cvxpy + Clarabel (its
# primal-dual KKT system grows as n^4 on dense graphs). PEER_TIMEOUT (default 900 s).
set -uo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
GEN="$REPO/target/release/examples/pipeline_scale"
BIN="$REPO/target/release/rotavg"
[[ -x "$GEN" && -x "$BIN" ]] || {
  echo "build first: cargo build --release --example pipeline_scale --bin rotavg" >&2; exit 1; }
PEERS="${PEERS:-$REPO/../shared/peers}"
PEERS_PY="${PEERS_PY:-}"
PEER_MAX_N="${PEER_MAX_N:-150}"
CLARABEL_MAX_N="${CLARABEL_MAX_N:-60}"
PEER_TIMEOUT="${PEER_TIMEOUT:-900}"
WORK="${WORK:-/tmp/rotavg-hard}"
mkdir -p "$WORK"
ROWS="${ROWS:-40:160:3:0.2 60:240:3:0.2 100:400:3:0 100:400:3:0.3 150:600:3:0.2 300:1200:3:0.2 1000:4000:3:0.1 1000:4000:30:0 1000:4000:3:0.3 3000:12000:3:0.2 10000:40000:3:0 10000:40000:3:0.2 10000:40000:10:0.3}"
echo "| n | edges | noise | outliers | rotavg: verdict (method) | cost | proven lower bound (relative gap) | solve | total | peak RSS | cvxpy + SCS: dual bound, time | cvxpy + Clarabel: dual bound, time | load |"
echo "|---|---|---|---|---|---|---|---|---|---|---|---|---|"
for row in $ROWS; do
  IFS=: read -r n m sdeg frac <<<"$row"
  sigma=$(python3 -c "import math; print(math.radians($sdeg))")
  g="$WORK/hard_${n}_${m}_${sdeg}_${frac}.g2o"
  [[ -f "$g" ]] || "$GEN" random "$n" "$m" "$sigma" --outliers "$frac" --write-g2o "$g" >/dev/null
  load=$(cut -d' ' -f1 /proc/loadavg)
  start=$(date +%s.%N)
  /usr/bin/time -f "RSS %M" -o "$WORK/rss" "$BIN" multiple "$g" --json >"$WORK/out.json" 2>/dev/null
  wall=$(python3 -c "import time; print(f'{time.time() - $start:.2f} s')")
  rss=$(awk '/^RSS/ {printf "%.0f MiB", $2/1024}' "$WORK/rss")
  ours=$(python3 - "$WORK/out.json" <<'PY'
import json, sys
v = json.load(open(sys.argv[1])); c = v["certificate"]
g, lb = c.get("relative_gap"), c.get("lower_bound")
bound = "-" if lb is None else f"{lb:.7g} ({g:.2e})"
print(f'{c["verdict"]} ({c.get("method")})|{v["cost"]:.7g}|{bound}|{v["solver"]["seconds"]:.3f} s')
PY
)
  peer() { # solver max_n
    [[ -n "$PEERS_PY" && "$n" -le "$2" ]] || { echo "not run (n > $2)"; return; }
    out="$WORK/peer_$1_$(basename "$g" .g2o).json"
    timeout "$PEER_TIMEOUT" "$PEERS_PY" "$PEERS/sdp_cvxpy.py" "$g" --solvers "$1" --weights unit \
      --max-n "$2" --max-n-clarabel "$2" --out "$out" >/dev/null 2>&1 || { echo "failed or over ${PEER_TIMEOUT} s"; return; }
    python3 - "$out" "$1" <<'PY'
import json, sys
v = json.load(open(sys.argv[1]))
r = v.get("results", v)
r = r.get(sys.argv[2], r) if isinstance(r, dict) else r
if isinstance(r, list):
    r = next((x for x in r if x.get("solver") == sys.argv[2]), r[0])
lb = r.get("dual_bound"); t = r.get("time_s")
print(f'{"-" if lb is None else f"{lb:.7g}"}, {t:.1f} s' if t is not None else str(r)[:60])
PY
  }
  scs=$(peer SCS "$PEER_MAX_N")
  cla=$(peer CLARABEL "$CLARABEL_MAX_N")
  IFS='|' read -r verdict cost bound solve <<<"$ours"
  echo "| $n | $m | ${sdeg} deg | $frac | $verdict | $cost | $bound | $solve | $wall | $rss | $scs | $cla | $load |"
done
