#!/usr/bin/env bash
# Peer comparison driver: runs the peer tools of ../shared/peers (GTSAM Shonan, cvxpy SDP,
# OpenCV hand-eye, SciPy mean) and rotavg's example binaries / CLI on the same inputs, and writes
# $WORK/results/*.json plus $WORK/results/TABLES.md (see BENCHMARKS.md for a run).
#
#   bash benches/peers/run.sh                 # everything (stages: setup gen peers proc ours table)
#   bash benches/peers/run.sh ours table      # only some stages
#   bash benches/peers/run.sh setup aniso     # GTSAM full noise models vs rotavg, anisotropic
#                                             # graphs (not in the default set; ~1 min)
#   bash benches/peers/run.sh certifiable     # GTSAM's 2026 certifiable staircase vs rotavg on
#                                             # every shared 3-D file and generated graphs (not
#                                             # in the default set; ~5 min; CERT.md)
#   bash benches/peers/run.sh setup scale     # the scale comparison (not in the default set;
#                                             # ~1 h; writes $WORK/results/scale/ and SCALE.md)
#   WORK=/tmp/rotavg-peers FORCE=1 JOB_TIMEOUT=600 bash benches/peers/run.sh
#
# The peer code is never copied into this repository: it is copied from PEERS_SRC into
# $WORK/peers (the shared folder is read-only) and its virtualenv is created there once.
# Peer results are cached ($WORK/results/*.json is not recomputed unless FORCE=1); ours are
# always recomputed. SKIP_BIG=1 skips the n=5000 synthetic graph.
# Stage `scale` (never cached): the README's `pipeline_scale` graphs written as g2o
# (SCALE_KINDS, default "chain grid random"; SCALE_SIZES, default "1000 10000 100000"), each
# solved by `rotavg multiple`, GTSAM chordal+LM and GTSAM Shonan, one process per job under
# /usr/bin/time -v and `timeout SCALE_TIMEOUT` (default JOB_TIMEOUT); SCALE_EXTRA adds jobs
# ("chain:1000000 ..."); SCALE_SHONAN_MAX_N (default 10^5) skips Shonan above that size; the
# GTSAM processes run under `ulimit -v` of SCALE_PEER_MEM_GIB (default 8) GiB, so that a
# factorisation that fills cannot take the machine's memory (rotavg has its own 4 GiB budget). The 10^3 graphs are also cross-checked: GTSAM's
# own cost() of the ground truth and of rotavg's solution against rotavg's costs.
set -uo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
PEERS_SRC="${PEERS_SRC:-}"
if [[ -z "$PEERS_SRC" ]]; then
  for d in "$REPO/../shared/peers" /work/shared/peers; do [[ -d "$d" ]] && { PEERS_SRC="$d"; break; }; done
fi
DATA="${DATA:-}"
if [[ -z "$DATA" ]]; then
  for d in "$REPO/../shared/data" /work/shared/data; do [[ -d "$d" ]] && { DATA="$d"; break; }; done
fi
WORK="${WORK:-/tmp/rotavg-peers}"
T="${JOB_TIMEOUT:-600}"
P="$WORK/peers"; PY="$P/.venv/bin/python"; INST="$WORK/inst"; RES="$WORK/results"
HPY="$PY"; [[ -x "$HPY" ]] || HPY=python3   # runs the harness's own JSON helpers
BIN="$REPO/target/release"
STAGES="${*:-setup gen peers proc ours table}"
has() { [[ " $STAGES " == *" $1 "* ]]; }
log() { echo "[peers $(date -u +%H:%M:%S)] $*" >&2; }
mkdir -p "$WORK" "$INST" "$RES"

# ---- setup: copy the peer harness and create its venv (once) ----
if has setup; then
  [[ -n "$PEERS_SRC" ]] || { echo "peers folder not found (set PEERS_SRC)" >&2; exit 1; }
  if [[ ! -x "$PY" ]]; then
    mkdir -p "$P"
    cp -r "$PEERS_SRC"/. "$P"/
    rm -rf "$P/.venv" "$P/results" "$P/instances"
    bash "$P/setup.sh"
  fi
  (cd "$REPO" && cargo build --release --bin rotavg --example certify_g2o --example single --example conjugate --example multiple)
fi

# ---- gen: deterministic synthetic instances ----
if has gen; then
  S="$PY $P/synth.py"
  $S mra --n 1000 --degree 8 --sigma-deg 2 --seed 0 --g2o --out "$INST/mra_n1000_d8_s2" >/dev/null
  [[ -n "${SKIP_BIG:-}" ]] || $S mra --n 5000 --degree 6 --sigma-deg 2 --seed 0 --g2o --out "$INST/mra_n5000_d6_s2" >/dev/null
  $S mra --n 40 --degree 6 --sigma-deg 2 --seed 0 --g2o --out "$INST/sdp_n40_d6_s2" >/dev/null
  for m in 100 1000; do $S single --m $m --sigma-deg 5 --seed 0 --out "$INST/single_m${m}_s5" >/dev/null; done
  $S single --m 100 --sigma-deg 5 --outlier-frac 0.2 --seed 0 --out "$INST/single_m100_s5_o20" >/dev/null
  for N in 5 15; do   # poses mode: N(N-1)/2 pairs = 10 and 105, exactly what OpenCV forms
    for s in 0.5 2 10; do
      $S conj --mode poses --poses $N --sigma-deg $s --seed 0 --out "$INST/conj_N${N}_s${s}" >/dev/null
    done
  done
  # outliers replace camera poses: 10 % of 15 poses; for 5 poses 10 % rounds to none, so 20 % (1 pose)
  $S conj --mode poses --poses 15 --sigma-deg 2 --outlier-frac 0.1 --seed 0 --out "$INST/conj_N15_s2_o10" >/dev/null
  $S conj --mode poses --poses 5 --sigma-deg 2 --outlier-frac 0.2 --seed 0 --out "$INST/conj_N5_s2_o20" >/dev/null
  tabb="$DATA/handeye/tabb_rwhe_dataset1"
  [[ -d "$tabb" ]] && "$PY" "$P/tabb2conj.py" "$tabb" --out "$INST/conj_tabb1" >/dev/null
  # ROTAVG_CONJ PAIR lines (L, R with R ~ S^T L S, our convention) -> our JSON format
  for f in "$INST"/conj_*.txt; do
    case "$f" in *.gt.txt) continue;; esac
    "$PY" - "$f" "${f%.txt}.json" <<'PYEOF'
import json, sys
pairs = []
for line in open(sys.argv[1]):
    t = line.split()
    if t and t[0] == "PAIR":
        v = [float(x) for x in t[2:20]]
        rows = lambda a: [a[0:3], a[3:6], a[6:9]]
        pairs.append({"left": rows(v[:9]), "right": rows(v[9:])})
json.dump({"pairs": pairs}, open(sys.argv[2], "w"))
PYEOF
  done
fi

peer() {  # peer OUT.json script args...   (cached)
  local out="$1"; shift
  if [[ -s "$out" && -z "${FORCE:-}" ]]; then log "cached $(basename "$out")"; return; fi
  log "$*"
  (cd "$P" && timeout "$T" "$PY" "$@" --out "$out" >/dev/null 2>"${out%.json}.stderr")
  local rc=$?
  if [[ $rc -ne 0 ]]; then
    echo "{\"error\": \"exit code $rc (124 = timeout ${T}s)\"}" > "$out"
  fi
  [[ -s "${out%.json}.stderr" ]] || rm -f "${out%.json}.stderr"
}

stamp() {  # stamp OUT.json T0 T1 RC: OUT.json.tmp (the command's JSON) + wall time -> OUT.json
  local out="$1"
  "$HPY" - "$out.tmp" "$out" "$2" "$3" "$4" <<'PYEOF'
import json, sys
src, dst, t0, t1, rc = sys.argv[1], sys.argv[2], float(sys.argv[3]), float(sys.argv[4]), int(sys.argv[5])
try:
    d = json.load(open(src))
except Exception as e:
    d = {"error": f"exit code {rc} (124 = timeout); no JSON ({e})"}
d["process_wall_seconds"] = t1 - t0
d["exit_code"] = rc
json.dump(d, open(dst, "w"), indent=1)
PYEOF
  rm -f "$out.tmp"
  [[ -s "${out%.json}.stderr" ]] || rm -f "${out%.json}.stderr"
}

ours() {  # ours OUT.json cmd args...   (stdout must be one JSON object; wall time measured here)
  local out="$1"; shift
  log "$*"
  local t0 t1 rc
  t0=$(date +%s.%N)
  timeout "$T" "$@" > "$out.tmp" 2>"${out%.json}.stderr"
  rc=$?
  t1=$(date +%s.%N)
  stamp "$out" "$t0" "$t1" "$rc"
}

REAL=(g2o/3d/sesync/sphere2500.g2o g2o/3d/sesync/parking-garage.g2o g2o/3d/sesync/smallGrid3D.g2o
      g2o/3d/sesync/tinyGrid3D.g2o g2o/3d/mrob/sphere.g2o)
tag_of() { basename "$1" .g2o; }
SYN=(mra_n1000_d8_s2); [[ -n "${SKIP_BIG:-}" ]] || SYN+=(mra_n5000_d6_s2)

if has peers; then
  for f in "${REAL[@]}"; do
    [[ -f "$DATA/$f" ]] || continue
    peer "$RES/mra__$(tag_of "$f")__gtsam.json" shonan.py "$DATA/$f" --weights file \
      --methods shonan,chordal,chordal_lm --native-run-max-n 0
  done
  for b in "${SYN[@]}"; do
    peer "$RES/mra__${b}__gtsam.json" shonan.py "$INST/$b.txt" --weights file \
      --methods shonan,chordal,chordal_lm --native-run-max-n 0
    if grep -q '"error": "exit code' "$RES/mra__${b}__gtsam.json"; then  # Shonan timed out:
      peer "$RES/mra__${b}__gtsamlm.json" shonan.py "$INST/$b.txt" --weights file \
        --methods chordal_lm --no-cert --native-run-max-n 0   # keep GTSAM chordal+LM cost
    fi
  done
  peer "$RES/sdp__sdp_n40_d6_s2__cvxpy.json" sdp_cvxpy.py "$INST/sdp_n40_d6_s2.txt" --solvers CLARABEL,SCS
  for f in "$INST"/single_*.txt; do
    case "$f" in *.gt.txt) continue;; esac
    peer "$RES/single__$(basename "$f" .txt)__scipy.json" single_scipy.py "$f"
  done
  for f in "$INST"/conj_*.txt; do
    case "$f" in *.gt.txt) continue;; esac
    peer "$RES/conj__$(basename "$f" .txt)__opencv.json" handeye_opencv.py "$f"
  done
fi

# ---- proc: GTSAM Shonan alone in its own process, wall-timed like ours (interpreter start,
# imports, file parsing, graph construction, solve; no extra certificate, no other method) ----
peerproc() {  # peerproc OUT.json script args...   (always recomputed; records process wall time)
  local out="$1"; shift
  log "process: $*"
  local t0 t1 rc
  t0=$(date +%s.%N)
  (cd "$P" && timeout "$T" "$PY" "$@" --out "$out.tmp" >/dev/null 2>"${out%.json}.stderr")
  rc=$?
  t1=$(date +%s.%N)
  stamp "$out" "$t0" "$t1" "$rc"
}
if has proc; then
  for f in "${REAL[@]}"; do
    [[ -f "$DATA/$f" ]] || continue
    peerproc "$RES/mra__$(tag_of "$f")__gtsamproc.json" shonan.py "$DATA/$f" --weights file \
      --methods shonan --no-cert --native-run-max-n 0
  done
  for b in "${SYN[@]}"; do
    # the n = 5000 Shonan run exceeds the job timeout: not repeated (reported from 'peers')
    grep -q '"error": "exit code' "$RES/mra__${b}__gtsam.json" 2>/dev/null && continue
    peerproc "$RES/mra__${b}__gtsamproc.json" shonan.py "$INST/$b.txt" --weights file \
      --methods shonan --no-cert --native-run-max-n 0
  done
fi

if has ours; then
  for f in "${REAL[@]}"; do
    [[ -f "$DATA/$f" ]] || continue
    ours "$RES/mra__$(tag_of "$f")__rotavg.json" "$BIN/examples/certify_g2o" "$DATA/$f" --json
    ours "$RES/mra__$(tag_of "$f")__rotavgtight.json" "$BIN/examples/certify_g2o" "$DATA/$f" --json \
      --gradient-tolerance 1e-12
  done
  for b in "${SYN[@]}"; do
    ours "$RES/mra__${b}__rotavg.json" "$BIN/examples/certify_g2o" "$INST/$b.g2o" --json
  done
  ours "$RES/sdp__sdp_n40_d6_s2__rotavg.json" "$BIN/examples/certify_g2o" "$INST/sdp_n40_d6_s2.g2o" --sdp --json
  for f in "$INST"/single_*.txt; do
    case "$f" in *.gt.txt) continue;; esac
    ours "$RES/single__$(basename "$f" .txt)__rotavg.json" "$BIN/examples/single" --file "$f" --json
  done
  for f in "$INST"/conj_*.json; do
    ours "$RES/conj__$(basename "$f" .json)__rotavg.json" "$BIN/rotavg" conjugate "$f" --json
  done
fi

# ---- scale: the README's pipeline_scale graphs (same generator, seed and noise) as g2o files,
# rotavg multiple vs GTSAM chordal+LM and GTSAM Shonan; one process per job, wall time, exit
# code and peak RSS measured here (/usr/bin/time -v around `timeout`), load average recorded ----
ST="${SCALE_TIMEOUT:-$T}"
timed() {  # timed OUT.json cmd args...   (stdout must be one JSON object)
  local out="$1"; shift
  local load t0 t1 rc
  load=$(cut -d' ' -f1-3 /proc/loadavg)
  log "[load $load] $*"
  t0=$(date +%s.%N)
  (if [[ -n "${MEMLIMIT_KB:-}" ]]; then ulimit -v "$MEMLIMIT_KB"; fi
   exec /usr/bin/time -v -o "${out%.json}.time" timeout "$ST" "$@" > "$out.tmp" 2>"${out%.json}.stderr")
  rc=$?
  t1=$(date +%s.%N)
  stamp "$out" "$t0" "$t1" "$rc"
  "$HPY" - "$out" "${out%.json}.time" "$load" "$(cut -d' ' -f1-3 /proc/loadavg)" "$*" <<'PYEOF'
import json, re, sys
out, timef, load0, load1, cmd = sys.argv[1:6]
d = json.load(open(out))
try:
    err = open(out[:-5] + ".stderr").read().strip().splitlines()
    if err and d.get("exit_code"):
        d["stderr_tail"] = err[-3:]
except OSError:
    pass
try:
    m = re.search(r"Maximum resident set size \(kbytes\): (\d+)", open(timef).read())
    d["peak_rss_kb"] = int(m.group(1)) if m else None
except OSError:
    d["peak_rss_kb"] = None
d["load_before"], d["load_after"], d["command"] = load0, load1, cmd
json.dump(d, open(out, "w"), indent=1)
PYEOF
  rm -f "${out%.json}.time"
}
if has scale; then
  SD="$RES/scale"; SI="$INST/scale"; mkdir -p "$SD" "$SI"
  (cd "$REPO" && cargo build --release --bin rotavg --example pipeline_scale) || exit 1
  PEER_MEM_KB=$(( ${SCALE_PEER_MEM_GIB:-8} * 1024 * 1024 ))
  jobs=()
  for n in ${SCALE_SIZES:-1000 10000 100000}; do
    for kind in ${SCALE_KINDS:-chain grid random}; do jobs+=("$kind:$n"); done
  done
  for job in "${jobs[@]}" ${SCALE_EXTRA:-}; do
      kind="${job%%:*}"; n="${job##*:}"
      tag="${kind}_n${n}"; g="$SI/$tag.g2o"
      # writes $g and ${g%.g2o}_gt.g2o, reads both back and compares the ground truth's cost
      "$BIN/examples/pipeline_scale" "$kind" "$n" --write-g2o "$g" > "$SD/${tag}__written.txt" || exit 1
      log "$(cat "$SD/${tag}__written.txt")"
      timed "$SD/${tag}__rotavg.json" "$BIN/rotavg" multiple "$g" --weights unit --json --max-seconds "$ST"
      MEMLIMIT_KB=$PEER_MEM_KB timed "$SD/${tag}__lm.json" "$PY" "$P/shonan.py" "$g" --weights unit \
        --methods chordal_lm --no-cert --native-run-max-n 0
      if (( n <= ${SCALE_SHONAN_MAX_N:-100000} )); then
        MEMLIMIT_KB=$PEER_MEM_KB timed "$SD/${tag}__shonan.json" "$PY" "$P/shonan.py" "$g" --weights unit \
          --methods shonan --no-cert --native-run-max-n 0
      fi
      if (( n <= 1000 )); then  # cross-check of the conventions: GTSAM's own cost() (untimed)
        "$BIN/rotavg" multiple "$g" --weights unit --quiet --output "$SD/${tag}__rotavg_solution.g2o" >/dev/null 2>&1
        "$PY" - "$P" "$g" "${g%.g2o}_gt.g2o" "$SD/${tag}__rotavg_solution.g2o" "$SD/${tag}__rotavg.json" \
          "$SD/${tag}__written.txt" > "$SD/${tag}__check.json" <<'PYEOF'
import json, re, sys
import numpy as np
sys.path.insert(0, sys.argv[1])
import gtsam
from common import load_gt_for, load_mra, mra_cost
from shonan import build_measurements, to_values_rot3
prob, gtf, solf, oursf, writtenf = sys.argv[2:7]
P = load_mra(prob)
sh = gtsam.ShonanAveraging3(build_measurements(P, np.ones(P.m)))  # unit weights, as the runs
ours = json.load(open(oursf))
written = open(writtenf).read()
rust_gt = float(re.search(r"cost (\S+) in memory", written).group(1))
d = {"n": P.n, "m": P.m, "file_weights_max_dev_from_1": float(np.abs(P.w - 1.0).max()),
     "rotavg_gt_cost": rust_gt}
for name, f in (("gt", gtf), ("rotavg_solution", solf)):
    R, mask = load_gt_for(P, f)
    assert mask.all(), name
    d[name + "_gtsam_cost"] = sh.cost(to_values_rot3(R))
    d[name + "_numpy_cost"] = mra_cost(R, P)
d["rotavg_solution_cost"] = ours["cost"]
d["rel_diff_gt_gtsam_vs_rotavg"] = abs(d["gt_gtsam_cost"] - rust_gt) / rust_gt
d["rel_diff_solution_gtsam_vs_rotavg"] = (abs(d["rotavg_solution_gtsam_cost"] - d["rotavg_solution_cost"])
                                         / d["rotavg_solution_cost"])
print(json.dumps(d, indent=1))
PYEOF
        log "check $tag: $(tr -d '\n' < "$SD/${tag}__check.json")"
      fi
  done
  "$PY" "$REPO/benches/peers/tables.py" --scale "$RES" "$INST" > "$RES/SCALE.md" && log "wrote $RES/SCALE.md"
fi

# ---- aniso (not in the default set): GTSAM with full 3x3 noise models against rotavg on the
# anisotropic graphs of examples/anisotropic_table.rs (ANISO_MAX_NODES, default 1000), one row
# each: benches/peers/gtsam_anisotropic.py; table in $RES/aniso/ANISO.md ----
if has aniso; then
  AD="$RES/aniso"; mkdir -p "$AD"
  (cd "$REPO" && cargo build --release --bin rotavg --example anisotropic_table) || exit 1
  "$BIN/examples/anisotropic_table" --export "$INST/aniso" "${ANISO_MAX_NODES:-1000}" || exit 1
  for g in "$INST"/aniso/aniso_*[0-9].json; do
    tag=$(basename "$g" .json)
    log "aniso $tag"
    timeout "$T" "$PY" "$REPO/benches/peers/gtsam_anisotropic.py" "$g" "${g%.json}_truth.txt" "$BIN/rotavg" > "$AD/$tag.json" \
      || log "aniso $tag failed"
  done
  "$PY" "$REPO/benches/peers/gtsam_anisotropic.py" --table "$AD" > "$AD/ANISO.md" && log "wrote $AD/ANISO.md"
fi

# ---- certifiable (not in the default set): GTSAM's certifiable Riemannian staircase (2026,
# ../shared/peers/setup_certifiable.sh and certifiable_gtsam.py, its own venv) against rotavg on
# every shared 3-D file and the generated chain / grid / random graphs (CERT_SIZES, default
# "1000 10000"), unit weights, one process per job (wall time and peak RSS measured here). Per
# file: the peer's run (its flag, rank, minimum eigenvalue, the costs of its values as returned
# and at their nearest rotations), `rotavg multiple`, `rotavg certify` of the peer's nearest
# rotations, and of its values as returned (gtsam_raw_rounding.py): without and with
# --nearest-rotations. Table: $RES/certifiable/CERT.md (benches/peers/certifiable_table.py). ----
if has certifiable; then
  CD="$RES/certifiable"; CI="$INST/certifiable"; mkdir -p "$CD" "$CI" "$P"
  [[ -n "$PEERS_SRC" ]] || { echo "peers folder not found (set PEERS_SRC)" >&2; exit 1; }
  for f in setup_certifiable.sh certifiable_gtsam.py; do [[ -f "$P/$f" ]] || cp "$PEERS_SRC/$f" "$P/"; done
  CPY="$P/.venv-certifiable/bin/python"
  [[ -x "$CPY" ]] || bash "$P/setup_certifiable.sh" || exit 1
  (cd "$REPO" && cargo build --release --bin rotavg --example pipeline_scale) || exit 1
  files=()
  for f in "$DATA"/g2o/3d/*/*; do
    case "$f" in *.g2o|*.txt) files+=("$f");; esac
  done
  for n in ${CERT_SIZES:-1000 10000}; do
    for kind in chain grid random; do
      g="$CI/${kind}_n${n}.g2o"
      [[ -s "$g" ]] || "$BIN/examples/pipeline_scale" "$kind" "$n" --write-g2o "$g" >/dev/null || exit 1
      files+=("$g")
    done
  done
  for f in "${files[@]}"; do
    tag=$(basename "${f%.*}")
    est="$CD/${tag}__gtsam_nearest.json"; raw="$CD/${tag}__gtsam_raw.json"
    timed "$CD/${tag}__gtsam.json" "$CPY" "$P/certifiable_gtsam.py" "$f" --estimate-out "$est"
    timed "$CD/${tag}__rotavg.json" "$BIN/rotavg" multiple "$f" --weights unit --json
    if [[ -s "$est" ]]; then
      timed "$CD/${tag}__certify_nearest.json" "$BIN/rotavg" certify "$f" --weights unit --estimate "$est" --json
    fi
    timeout "$T" "$CPY" "$REPO/benches/peers/gtsam_raw_rounding.py" "$f" "$raw" > "$CD/${tag}__raw_stats.json" 2>/dev/null
    if [[ -s "$raw" ]]; then
      timed "$CD/${tag}__certify_raw.json" "$BIN/rotavg" certify "$f" --weights unit --estimate "$raw" --json
      timed "$CD/${tag}__certify_raw_projected.json" "$BIN/rotavg" certify "$f" --weights unit \
        --estimate "$raw" --nearest-rotations --json
    fi
  done
  "$HPY" "$REPO/benches/peers/certifiable_table.py" "$CD" > "$CD/CERT.md" && log "wrote $CD/CERT.md"
fi

if has table; then
  "$PY" "$REPO/benches/peers/tables.py" "$RES" "$INST" > "$RES/TABLES.md" && log "wrote $RES/TABLES.md"
fi
