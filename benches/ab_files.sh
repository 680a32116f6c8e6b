#!/usr/bin/env bash
# A/B of two rotavg binaries on view-graph files, interleaved (A, B, A, B per file, K rounds):
# one line per run with the solve and certify seconds (`solver.seconds`,
# `pipeline.certify_seconds`), the verdict, the wall clock and peak RSS of the process, and the
# scalar comparison's proving shape, with the relative gap. Used for the grouped subgraphs (docs/benchmarks.md,
# "Grouped subgraphs in regions"):
#
#   python3 benches/gen_graph.py expander 30000 20 0.1 30000 /tmp/ex30k.json
#   bash benches/ab_files.sh OLD/target/release/rotavg target/release/rotavg /tmp/ex30k.json
#
# Environment: K (rounds, default 2).
set -uo pipefail
if [[ $# -lt 3 ]]; then
  echo "usage: $0 A_BIN B_BIN FILE..." >&2
  exit 2
fi
A="$1"; B="$2"; shift 2
K="${K:-2}"
out="$(mktemp)"; err="$(mktemp)"
trap 'rm -f "$out" "$err"' EXIT
for f in "$@"; do
  for k in $(seq "$K"); do
    for lab in A B; do
      bin=$A; [[ $lab == B ]] && bin=$B
      /usr/bin/time -f "%e %M" "$bin" multiple "$f" --json > "$out" 2> "$err"
      python3 - "$f" "$lab" "$k" "$out" "$err" <<'PY'
import json, sys
f, lab, k, out, err = sys.argv[1:]
d = json.load(open(out))
wall, rss = open(err).read().split()[-2:]
p = d["pipeline"]
# the certificate of the problem the verdict names (the robust default's: its inlier graph's)
cert = d.get("certificate") or ((d.get("robust") or {}).get("inlier_graph") or {}).get("certificate") or {}
proved = [a.get("note", "") for a in (p.get("certify") or {}).get("ladder", [])
          if a["outcome"].get("outcome") == "proved" and a["rung"]["proof"] == "scalar_comparison"]
print(f.split("/")[-1], lab, k, "solve %.3f certify %.3f" % (d["solver"]["seconds"], p["certify_seconds"]),
      (d.get("verdict") or {}).get("verdict", "?"),
      "rel_gap %.2e" % (cert.get("relative_gap") if cert.get("relative_gap") is not None else float("nan")),
      "wall", wall, "rss_MB", int(rss) // 1024, "|",
      (proved[0] if proved else "-")[:90], flush=True)
PY
    done
  done
done
