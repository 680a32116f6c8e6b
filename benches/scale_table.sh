#!/usr/bin/env bash
# The README's "whole pipeline at scale" table, one process per row (peak RSS from GNU time):
#
#   cargo build --release --example pipeline_scale && bash benches/scale_table.sh > /tmp/scale.md
#
# Each row: `target/release/examples/pipeline_scale KIND N [M SIGMA TOL MAX_MEMORY_GIB]`, then
# the same graph with ROTAVG_CERTIFY=none (the solve's own peak RSS). Prints markdown rows with
# the load average at the start of each row. ROWS="chain:1000 grid:10000" selects rows.
set -uo pipefail
REPO="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
BIN="$REPO/target/release/examples/pipeline_scale"
[[ -x "$BIN" ]] || { echo "build first: cargo build --release --example pipeline_scale" >&2; exit 1; }
ROWS="${ROWS:-chain:1000 chain:10000 chain:100000 chain:1000000 grid:10000 grid:100000 grid:1000000 torus:100000 torus:1000000 random:1000 random:10000 random:30000 random:100000:300000:0.1 random:100000:1000000:0.1}"
echo "| graph | nodes | edges | solve (Newton iterations) | certify | verdict (relative gap) | peak RSS, solve alone / whole | load |"
echo "|---|---|---|---|---|---|---|---|"
for row in $ROWS; do
  IFS=: read -r kind n m sigma <<<"$row"
  args=("$kind" "$n")
  [[ -n "${m:-}" ]] && args+=("$m")
  [[ -n "${sigma:-}" ]] && args+=("$sigma")
  load=$(cut -d' ' -f1 /proc/loadavg)
  out=$( { /usr/bin/time -f "RSS %M" "$BIN" "${args[@]}"; } 2>&1 )
  solo=$( { ROTAVG_CERTIFY=none /usr/bin/time -f "RSS %M" "$BIN" "${args[@]}"; } 2>&1 )
  line=$(grep -m1 " n [0-9]" <<<"$out")
  why=$(grep -m1 "why:" <<<"$out" | sed 's/^ *why: //')
  why=${why%%; randomized Chebyshev*}
  rss=$(grep -m1 "^RSS" <<<"$out" | awk '{printf "%.0f MiB", $2/1024}')
  rss_solo=$(grep -m1 "^RSS" <<<"$solo" | awk '{printf "%.0f MiB", $2/1024}')
  edges=$(sed -E 's/.* m ([0-9]+) .*/\1/' <<<"$line")
  solve=$(sed -E 's/.*solve ([0-9.]+) s \(([0-9]+) iterations\).*/\1 s (\2)/' <<<"$line")
  certify=$(sed -E 's/.*certify ([0-9.]+) s.*/\1 s/' <<<"$line")
  verdict=$(sed -E 's/.*verdict ([a-z_]+), relative gap ([^,]+),.*/\1 (\2)/' <<<"$line")
  [[ -n "$why" && "$verdict" != certified* ]] && verdict="$verdict: ${why#*inconclusive: }"
  # the Monte Carlo bound [D16] beside an inconclusive verdict (never the verdict itself)
  randomized=$(grep -m1 "randomized \[D16\]:" <<<"$out" | sed 's/^ *randomized \[D16\]: //')
  [[ -n "$randomized" ]] && verdict="$verdict **Randomized test [D16]: $randomized**"
  echo "| $kind${sigma:+, noise $sigma} | $n | $edges | $solve | $certify | $verdict | $rss_solo / $rss | $load |"
done
