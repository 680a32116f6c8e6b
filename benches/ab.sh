#!/usr/bin/env bash
# A/B benchmark of two rotavg binaries, interleaved (issue 35): every case runs A, B, A, B, ...
# (K repetitions each), and a Markdown table gives per case the medians of the whole run (wall
# clock of the process), the solve (`solver.seconds`), the certify phase
# (`pipeline.certify_seconds`; `certificate.seconds` for the `certify` verb), the ratio B/A,
# the certify/solve ratio, the verdict, and the proof ladder of each binary
# (`pipeline.certify.ladder`, absent from binaries older than the ladder).
#
#   cargo build --release --bin rotavg            # B: this checkout
#   git worktree add /tmp/old 97813a7 && (cd /tmp/old && cargo build --release --bin rotavg)
#   bash benches/ab.sh /tmp/old/target/release/rotavg target/release/rotavg > /tmp/ab.md
#
# Cases (each skipped with a notice when its file is missing; a clone without ../shared runs
# the generated ones only):
#   - every g2o file of $DATA/g2o/{3d/sesync,3d/mrob,2d/sesync} and those of 3d/gtsam with more
#     than 20 nodes: `multiple FILE --json`, and again with `--information full`;
#   - the 1DSfM Madrid_Metropolis EGs.txt: default loss and `--loss cauchy`;
#   - random expander graphs (benches/gen_graph.py, standard-library Python): n in $EXPANDERS,
#     average degree $DEGREE, noise $SIGMA rad per axis, seeded;
#   - SLAM-like chains (gen_graph.py chain): n in $CHAINS, 2 % loop closures, noise $CHAIN_SIGMA,
#     3-D (`chain-N`) and planar (`planar-chain-N`, the smallest n only); SLAM-like lattices
#     (gen_graph.py grid): n in $GRIDS, half of the row-to-row closures, noise $CHAIN_SIGMA;
#   - perturbed estimates: `certify FILE --estimate EST --json`, EST the optimum (B's
#     `multiple --output`) with every rotation turned by $PERTURB_DEG degrees about a random
#     axis, for the graphs of $PERTURB.
# A case one binary cannot run (an option it does not have) shows `-` for that binary.
#
# Environment: K (repetitions, default 5), DATA (default ../shared/data beside the repository),
# WORK (scratch, default /tmp/rotavg-ab), EXPANDERS ("1000 3000 10000"), DEGREE (7), SIGMA
# (0.05), CHAINS ("5000 50000"), GRIDS ("5000"), CHAIN_SIGMA (0.01), PERTURB_DEG (1e-4),
# PERTURB (case labels, default "sphere2500 mrob-sphere expander-3000 chain-5000"), ONLY (a
# regular expression: run only the cases whose label matches), TIMEOUT (seconds per run,
# default 900), A_LABEL / B_LABEL (the commits, printed in the header; default: the binaries'
# paths and `--version`), REPORT_ONLY=1 (print the table of the runs already in WORK, with the
# same K, without running anything), CALLGRIND=1 (also run every case once per binary under
# valgrind's callgrind and report the instructions executed inside
# `rotavg::certify::multiple::certify_multiple`, a count the machine's load does not change;
# about 50x slower than a plain run, so only for the cases whose median run took at most
# CALLGRIND_MAX_SECONDS, default 1, with both binaries).
set -uo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [[ $# -lt 2 ]]; then
  echo "usage: $0 A_BIN B_BIN [K]   (see the comment at the top)" >&2
  exit 2
fi
A_BIN="$(realpath "$1")"
B_BIN="$(realpath "$2")"
for b in "$A_BIN" "$B_BIN"; do
  [[ -x "$b" ]] || { echo "not an executable: $b" >&2; exit 2; }
done
K="${3:-${K:-5}}"
DATA="${DATA:-$REPO/../shared/data}"
WORK="${WORK:-/tmp/rotavg-ab}"
EXPANDERS="${EXPANDERS:-1000 3000 10000}"
DEGREE="${DEGREE:-7}"
SIGMA="${SIGMA:-0.05}"
PERTURB_DEG="${PERTURB_DEG:-1e-4}"
PERTURB="${PERTURB:-sphere2500 mrob-sphere expander-3000 chain-5000}"
CHAINS="${CHAINS:-5000 50000}"
CHAIN_SIGMA="${CHAIN_SIGMA:-0.01}"
GRIDS="${GRIDS:-5000}"
ONLY="${ONLY:-.}"
TIMEOUT="${TIMEOUT:-900}"
A_LABEL="${A_LABEL:-$A_BIN ($("$A_BIN" --version 2>/dev/null))}"
B_LABEL="${B_LABEL:-$B_BIN ($("$B_BIN" --version 2>/dev/null))}"
GEN="$REPO/benches/gen_graph.py"
command -v python3 >/dev/null || { echo "python3 is needed (standard library only)" >&2; exit 2; }
mkdir -p "$WORK/json" "$WORK/graphs"
note() { echo "ab.sh: $*" >&2; }

if [[ -z "${REPORT_ONLY:-}" ]]; then
rm -f "$WORK"/json/*
# --- the cases: "label|verb|file|extra arguments" ---------------------------------------------
CASES=()
add() { [[ "$1" =~ $ONLY ]] && CASES+=("$1|$2|$3|${4:-}"); }
nodes() { # distinct vertex ids of a g2o file (vertex lines and edge endpoints)
  awk '/^VERTEX/ {ids[$2]=1} /^EDGE/ {ids[$2]=1; ids[$3]=1} END {print length(ids)}' "$1"
}
g2o_case() { # label file
  add "$1" multiple "$2"
  add "$1 full" multiple "$2" "--information full"
}
if [[ -d "$DATA/g2o" ]]; then
  for f in "$DATA"/g2o/3d/sesync/*.g2o; do g2o_case "$(basename "$f" .g2o)" "$f"; done
  for f in "$DATA"/g2o/3d/mrob/*.g2o; do g2o_case "mrob-$(basename "$f" .g2o)" "$f"; done
  for f in "$DATA"/g2o/3d/gtsam/*; do
    [[ -f "$f" ]] || continue
    if [[ "$(nodes "$f")" -gt 20 ]]; then
      g2o_case "gtsam-$(basename "${f%.*}")" "$f"
    fi
  done
  for f in "$DATA"/g2o/2d/sesync/*.g2o; do g2o_case "2d-$(basename "$f" .g2o)" "$f"; done
else
  note "no $DATA/g2o: the g2o cases are skipped (set DATA to the shared data folder)"
fi
MADRID="$DATA/1dsfm/Madrid_Metropolis/EGs.txt"
if [[ -f "$MADRID" ]]; then
  add madrid multiple "$MADRID"
  add "madrid cauchy" multiple "$MADRID" "--loss cauchy"
else
  note "no $MADRID: the 1DSfM cases are skipped"
fi
for n in $EXPANDERS; do
  g="$WORK/graphs/expander_${n}_${DEGREE}_${SIGMA}.json"
  [[ "expander-$n" =~ $ONLY || " $PERTURB " == *" expander-$n "* ]] || continue
  if [[ ! -s "$g" ]]; then
    python3 "$GEN" expander "$n" "$DEGREE" "$SIGMA" "$n" "$g" || { note "generator failed for n = $n"; continue; }
  fi
  add "expander-$n" multiple "$g"
done
first=1
for n in $CHAINS; do
  for kind in chain planar-chain; do
    [[ $kind == planar-chain && $first -eq 0 ]] && continue
    g="$WORK/graphs/${kind}_${n}_${CHAIN_SIGMA}.json"
    [[ "$kind-$n" =~ $ONLY || " $PERTURB " == *" $kind-$n "* ]] || continue
    if [[ ! -s "$g" ]]; then
      python3 "$GEN" chain "$n" 0.02 "$CHAIN_SIGMA" "$n" "$g" $([[ $kind == planar-chain ]] && echo planar) ||
        { note "generator failed for $kind n = $n"; continue; }
    fi
    add "$kind-$n" multiple "$g"
  done
  first=0
done
for n in $GRIDS; do
  g="$WORK/graphs/grid_${n}_${CHAIN_SIGMA}.json"
  [[ "grid-$n" =~ $ONLY ]] || continue
  if [[ ! -s "$g" ]]; then
    python3 "$GEN" grid "$n" 0.5 "$CHAIN_SIGMA" "$n" "$g" || { note "generator failed for grid n = $n"; continue; }
  fi
  add "grid-$n" multiple "$g"
done
# perturbed estimates: the optimum from B, turned by PERTURB_DEG degrees per node
for label in $PERTURB; do
  file=""
  for c in "${CASES[@]}" ; do
    IFS='|' read -r l verb f extra <<<"$c"
    [[ "$l" == "$label" && -z "$extra" ]] && file="$f"
  done
  if [[ -z "$file" ]]; then
    case "$label" in
      expander-*) file="$WORK/graphs/expander_${label#expander-}_${DEGREE}_${SIGMA}.json" ;;
      chain-*) file="$WORK/graphs/chain_${label#chain-}_${CHAIN_SIGMA}.json" ;;
      mrob-*) file="$DATA/g2o/3d/mrob/${label#mrob-}.g2o" ;;
      *) file="$DATA/g2o/3d/sesync/$label.g2o" ;;
    esac
  fi
  [[ -f "$file" ]] || { note "no file for the perturbed case $label: skipped"; continue; }
  [[ "$label perturbed" =~ $ONLY ]] || continue
  opt="$WORK/graphs/${label}_optimum.json"
  est="$WORK/graphs/${label}_perturbed.json"
  if [[ ! -s "$est" ]]; then
    "$B_BIN" multiple "$file" --output "$opt" --quiet >/dev/null 2>&1 &&
      python3 "$GEN" perturb "$opt" "$PERTURB_DEG" 1 "$est" ||
      { note "could not write the perturbed estimate of $label: skipped"; continue; }
  fi
  add "$label perturbed" certify "$file" "--estimate $est"
done

# --- the interleaved runs -----------------------------------------------------------------------
load_before="$(cut -d' ' -f1-3 /proc/loadavg)"
note "${#CASES[@]} cases x $K repetitions x 2 binaries; load before: $load_before"
run() { # side label verb file extra rep
  local out="$WORK/json/$2.$1.$6" t0 t1 rc
  # shellcheck disable=SC2086 # the extra arguments are words
  t0=$EPOCHREALTIME
  timeout "$TIMEOUT" "$( [[ $1 == A ]] && echo "$A_BIN" || echo "$B_BIN")" "$3" "$4" $5 --json \
    >"$out.json" 2>"$out.err"
  rc=$?
  t1=$EPOCHREALTIME
  printf '{"rc": %d, "wall": %s}\n' "$rc" "$(awk -v a="$t0" -v b="$t1" 'BEGIN {print b - a}')" >"$out.meta"
}
CALLGRIND="${CALLGRIND:-}"
if [[ -n "$CALLGRIND" ]] && ! command -v valgrind >/dev/null; then
  note "CALLGRIND=1 but no valgrind: instruction counts skipped"
  CALLGRIND=""
fi
CALLGRIND_MAX_SECONDS="${CALLGRIND_MAX_SECONDS:-1}"
quick() { # key: every run of the case (both binaries) has a median wall time within the limit
  python3 - "$WORK/json" "$1" "$CALLGRIND_MAX_SECONDS" <<'PY'
import glob, json, statistics, sys
root, key, limit = sys.argv[1], sys.argv[2], float(sys.argv[3])
for side in "AB":
    walls = [json.load(open(f))["wall"] for f in glob.glob(f"{root}/{key}.{side}.*.meta")]
    if walls and statistics.median(walls) > limit:
        sys.exit(1)
PY
}
count() { # side key verb file extra: instructions inside certify_multiple, one run
  local out="$WORK/json/$2.$1"
  # shellcheck disable=SC2086 # the extra arguments are words
  timeout "$((TIMEOUT * 60))" valgrind --tool=callgrind --callgrind-out-file="$out.callgrind" \
    --toggle-collect='rotavg::certify::multiple::certify_multiple' \
    "$( [[ $1 == A ]] && echo "$A_BIN" || echo "$B_BIN")" "$3" "$4" $5 --json >/dev/null 2>&1 &&
    awk '/^(summary|totals):/ {print $2; exit}' "$out.callgrind" >"$out.ir"
  rm -f "$out.callgrind"
}
i=0
for c in "${CASES[@]}"; do
  IFS='|' read -r label verb file extra <<<"$c"
  key="$(printf '%03d' "$i")"
  echo "$label" >"$WORK/json/$key.label"
  i=$((i + 1))
  note "[$i/${#CASES[@]}] $label"
  for ((r = 0; r < K; r++)); do
    run A "$key" "$verb" "$file" "$extra" "$r"
    run B "$key" "$verb" "$file" "$extra" "$r"
  done
  if [[ -n "$CALLGRIND" ]] && quick "$key"; then
    count A "$key" "$verb" "$file" "$extra"
    count B "$key" "$verb" "$file" "$extra"
  fi
done
load_after="$(cut -d' ' -f1-3 /proc/loadavg)"
printf '%s\n%s\n%s\n' "$load_before" "$load_after" "$(date -u '+%Y-%m-%d %H:%M UTC')" >"$WORK/json/run.info"
fi
{ read -r load_before; read -r load_after; read -r run_date; } <"$WORK/json/run.info"

# --- the table --------------------------------------------------------------------------------
cpu="$(awk -F': ' '/^model name/ {print $2; exit}' /proc/cpuinfo)"
echo "A/B benchmark (benches/ab.sh), $run_date; $(nproc) cores, ${cpu:-unknown CPU};"
echo "K = $K interleaved repetitions (A, B, A, B, ...), medians; load average (1, 5, 15 min) before"
echo "$load_before, after $load_after."
echo
echo "- A: $A_LABEL"
echo "- B: $B_LABEL"
echo
python3 - "$WORK/json" "$K" <<'PY'
import glob, json, os, statistics, sys

root, k = sys.argv[1], int(sys.argv[2])


def load(key, side):
    runs = []
    for r in range(k):
        base = f"{root}/{key}.{side}.{r}"
        meta = json.load(open(base + ".meta"))
        try:
            doc = json.load(open(base + ".json"))
        except (OSError, ValueError):
            doc = None
        runs.append((meta, doc))
    return runs


def get(doc, *path):
    for p in path:
        if not isinstance(doc, dict) or doc.get(p) is None:
            return None
        doc = doc[p]
    return doc


def certified(doc):
    """The part of the output that holds the certificate: the inlier graph's for robust losses."""
    inliers = get(doc, "robust", "inlier_graph")
    if get(doc, "certificate") is None and isinstance(inliers, dict):
        return inliers
    return doc


def ladder_steps(doc):
    """The ladder: `pipeline.certify.ladder` (`multiple`) or `pipeline.ladder` (`certify`)."""
    part = certified(doc)
    steps = get(part, "pipeline", "certify", "ladder")
    return steps if steps is not None else get(part, "pipeline", "ladder")


def certify_seconds(doc):
    v = get(doc, "pipeline", "certify_seconds")
    return v if v is not None else get(doc, "certificate", "seconds")


def instructions(key, side):
    try:
        return int(open(f"{root}/{key}.{side}.ir").read().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def median(values):
    values = [v for v in values if v is not None]
    return statistics.median(values) if values else None


def ok(runs):
    return [d for m, d in runs if m["rc"] == 0 and d is not None]


def fmt(v, unit=""):
    if v is None:
        return "-"
    return f"{v:.4f}{unit}" if v < 0.1 else f"{v:.3f}{unit}" if v < 10 else f"{v:.1f}{unit}"


def ratio(b, a):
    return "-" if a is None or b is None or a <= 0 else f"{b / a:.2f}"


def rung_name(r):
    if not isinstance(r, dict):
        return str(r)
    rest = ",".join(f"{k}={v}" for k, v in r.items() if k != "proof")
    return r.get("proof", "?") + (f"({rest})" if rest else "")


def outcome(o):
    if not isinstance(o, dict):
        return str(o)
    name = o.get("outcome", "?")
    if name == "proved":
        return "proved" if o.get("sufficient", True) else "proved (weak)"
    if name == "failed":
        return "FAILED: " + str(o.get("reason", ""))[:60]
    if name == "refused":
        return "refused: " + str(o.get("refusal", ""))[:40]
    return name


def ladder(doc):
    steps = ladder_steps(doc)
    if not isinstance(steps, list):
        return None
    parts = []
    for s in steps:
        pred = get(s, "predicted", "seconds")
        p = "" if pred is None else f", pred {pred:.4f}"
        if get(s, "outcome", "refusal") == "not_needed":
            continue
        parts.append(f"{rung_name(s.get('rung'))}@{s.get('point', '?')} "
                     f"{outcome(s.get('outcome'))} ({s.get('seconds', 0):.4f} s{p})")
    total = certify_seconds(doc)
    if total is not None:
        rest = total - sum(s.get("seconds", 0) for s in steps)
        parts.append(f"outside the rungs {rest:.4f} s")
    return "; ".join(parts)


def proved_by(doc):
    """The rung that proved: the ladder's last sufficient proof, or (binaries without a ladder)
    the proof the explanation names."""
    steps = ladder_steps(doc)
    if isinstance(steps, list):
        done = [s for s in steps if get(s, "outcome", "outcome") == "proved"]
        return rung_name(done[-1]["rung"]) if done else "nothing"
    text = get(certified(doc), "certificate", "explanation") or ""
    for needle, name in (("[D15]", "grounded"), ("[D13]", "scalar"),
                         ("Cholesky factorisation of S +", "shifted_cholesky"),
                         ("Gershgorin", "gershgorin")):
        if needle in text:
            return name + "*"
    return "?"


def proof(doc):
    c = get(certified(doc), "certificate")
    if c is None:
        return "none"
    inliers = " of the inliers" if certified(doc) is not doc else ""
    return f"{c.get('verdict')}{inliers} ({c.get('method')})"


rows, ladders, info, irs = [], [], {}, []
for path in sorted(glob.glob(f"{root}/*.label")):
    key = os.path.basename(path)[:-6]
    label = open(path).read().strip()
    a, b = load(key, "A"), load(key, "B")
    oa, ob = ok(a), ok(b)
    cell = {}
    for side, runs, good in (("A", a, oa), ("B", b, ob)):
        cell[side] = dict(
            wall=median([m["wall"] for m, d in runs if m["rc"] == 0]),
            solve=median([get(d, "solver", "seconds") for d in good]),
            cert=median([certify_seconds(d) for d in good]),
            verdict=proof(good[0]) if good else f"exit {runs[0][0]['rc']}",
            by=proved_by(good[0]) if good else "-",
            ladder=ladder(good[len(good) // 2]) if good else None,
            doc=good[0] if good else None,
            ir=instructions(key, side),
        )
    doc = cell["B"]["doc"] or cell["A"]["doc"]
    n, m = get(doc, "num_rotations"), get(doc, "num_measurements")
    loss = get(doc, "loss")
    verdict = cell["A"]["verdict"] if cell["A"]["verdict"] == cell["B"]["verdict"] else \
        f"A {cell['A']['verdict']} / B {cell['B']['verdict']}"
    cs = lambda s: ratio(cell[s]["cert"], cell[s]["solve"])
    rows.append(f"| {label} | {n} | {m} | {loss or '-'} | {verdict} | "
                f"{fmt(cell['A']['wall'])} | {fmt(cell['B']['wall'])} | "
                f"{ratio(cell['B']['wall'], cell['A']['wall'])} | "
                f"{fmt(cell['A']['solve'])} | {fmt(cell['B']['solve'])} | "
                f"{fmt(cell['A']['cert'])} | {fmt(cell['B']['cert'])} | "
                f"**{ratio(cell['B']['cert'], cell['A']['cert'])}** | {cs('A')} | {cs('B')} | "
                f"{cell['A']['by']} | {cell['B']['by']} |")
    for side in ("A", "B"):
        if cell[side]["ladder"]:
            ladders.append(f"| {label} | {side} | {cell[side]['ladder']} |")
    info[label] = cell
    if cell["A"]["ir"] or cell["B"]["ir"]:
        mi = lambda v: "-" if v is None else f"{v / 1e6:.1f}"
        irs.append(f"| {label} | {mi(cell['A']['ir'])} | {mi(cell['B']['ir'])} | "
                   f"{ratio(cell['B']['ir'], cell['A']['ir'])} |")

print("Times in seconds (medians). run: the process's wall clock; solve: `solver.seconds`;")
print("certify: `pipeline.certify_seconds` (`certificate.seconds` for `certify`); cert/solve:")
print("certify over solve of the same binary. `-`: the binary could not run the case. proved by:")
print("the rung that proved (the ladder's; `*`: named by the explanation of a binary without one).")
print()
print("| case | n | edges | loss | verdict (method) | run A | run B | B/A | solve A | solve B "
      "| certify A | certify B | certify B/A | cert/solve A | cert/solve B | proved by A | proved by B |")
print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
print("\n".join(rows))
if irs:
    print()
    print("Instructions executed inside `certify_multiple` (millions, callgrind, one run each):")
    print()
    print("| case | A | B | B/A |")
    print("|---|---|---|---|")
    print("\n".join(irs))
pairs = [(l, l + " full") for l in info if l + " full" in info]
if pairs:
    print()
    print("`--information full` against the default (scalar kappa) weights, same binary:")
    print("certify seconds (medians) and full / default; anisotropy: the largest ratio of an")
    print("information matrix's eigenvalues (`information.max_anisotropy`, 1: isotropic).")
    print()
    print("| graph | anisotropy | A default | A full | A full/default | B default | B full "
          "| B full/default | B instructions full/default |")
    print("|---|---|---|---|---|---|---|---|---|")
    for d, f in pairs:
        c = [info[d]["A"]["cert"], info[f]["A"]["cert"], info[d]["B"]["cert"], info[f]["B"]["cert"]]
        doc = info[f]["B"]["doc"] or info[f]["A"]["doc"]
        an = get(doc, "information", "max_anisotropy")
        an = "-" if an is None else f"{an:.3g}"
        print(f"| {d} | {an} | {fmt(c[0])} | {fmt(c[1])} | {ratio(c[1], c[0])} | {fmt(c[2])} | "
              f"{fmt(c[3])} | {ratio(c[3], c[2])} | "
              f"{ratio(info[f]['B']['ir'], info[d]['B']['ir'])} |")
if ladders:
    print()
    print("Proof ladders (`pipeline.certify.ladder` of the middle run: rung@point outcome "
          "(measured s, predicted s); rungs refused as not needed left out; outside the rungs:")
    print("the certify time the rungs do not account for (multipliers, S, Lanczos, refinement):")
    print()
    print("| case | binary | rungs in order |")
    print("|---|---|---|")
    print("\n".join(ladders))
PY
