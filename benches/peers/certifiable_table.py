"""The table of benches/peers/run.sh stage `certifiable`: GTSAM's certifiable staircase (2026)
against rotavg, one row per file, from the JSON files of RESULTS_DIR/certifiable.

    python3 certifiable_table.py RESULTS_DIR/certifiable > CERT.md

Columns: the peer's whole process (wall, measured by run.sh) and its staircase alone (its own
timer); its `certified` flag with the minimum eigenvalue it comes from; the determinant range
and largest |M M^T - I| entry of the values it returns; the chordal cost of its values at their
nearest rotations (unit weights, its harness's sum); rotavg's whole `multiple` process, its
cost, verdict and relative gap; the cost difference (peer's nearest rotations minus rotavg's,
relative); `rotavg certify` of the peer's nearest rotations; and `rotavg certify` of the values
as returned, without `--nearest-rotations` (the error's first words) and with it.
"""
import json
import sys
from pathlib import Path

folder = Path(sys.argv[1])


def load(path):
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return None


def secs(d):
    return f"{d['process_wall_seconds']:.2f}" if d and "process_wall_seconds" in d else "-"


def verdict(d):
    if not d:
        return "-"
    if d.get("exit_code") not in (0, 3, None) or "certificate" not in d:
        return f"error (exit {d.get('exit_code')})"
    c = d["certificate"]
    return f"{c['verdict']} ({c['relative_gap']:.1e})"


def raw_without(d):
    if not d:
        return "-"
    if d.get("exit_code") == 1:
        return "refused: not a rotation"
    return verdict(d)


rows = []
for peer_file in sorted(folder.glob("*__gtsam.json")):
    tag = peer_file.name[: -len("__gtsam.json")]
    g, r = load(peer_file), load(folder / f"{tag}__rotavg.json")
    near = load(folder / f"{tag}__certify_nearest.json")
    raw, proj = load(folder / f"{tag}__certify_raw.json"), load(folder / f"{tag}__certify_raw_projected.json")
    if not g or "n" not in g:
        why = f"exit {g.get('exit_code')} after {secs(g)} s (124: timeout)" if g else "no result"
        cost_r = f"{r['cost']:.10g}" if r and "cost" in r else "-"
        rows.append(f"| {tag} | {r and r.get('num_rotations', '')} | {r and r.get('num_measurements', '')} "
                    f"| {why} | | | | | | {secs(r)} | {cost_r} | {verdict(r)} | | | |")
        continue
    det = f"{g['det_min']:.6f}..{g['det_max']:.6f}" if "det_min" in g else "-"
    orth = f"{g['orthogonality_error']:.1e}" if "orthogonality_error" in g else "-"
    cost_g = g.get("cost_nearest_rotations")
    cost_r = r.get("cost") if r else None
    if cost_g is None or cost_r is None:
        diff = "-"
    elif max(cost_g, cost_r) < 1e-20:  # both zero to rounding: a ratio says nothing
        diff = f"{cost_g - cost_r:+.0e} (abs.)"
    else:
        diff = f"{(cost_g - cost_r) / cost_r:+.1e}"
    rows.append(
        f"| {tag} | {g['n']} | {g['m']} | {secs(g)} | {g['staircase_s']:.2f} | "
        f"{g['certified']} ({g['min_eigenvalue']:.0e}) | {det} | {orth} | "
        f"{cost_g:.10g} | {secs(r)} | {cost_r:.10g} | {verdict(r)} | {diff} | "
        f"{verdict(near)} | {raw_without(raw)} / {verdict(proj)} |"
    )

print("| file | n | m | GTSAM s | staircase s | GTSAM certified (min eig) | det of its values "
      "| max abs(M M^T - I) | GTSAM cost (nearest rotations) | rotavg s | rotavg cost | rotavg verdict "
      "(rel. gap) | cost diff (rel.) | rotavg certify of GTSAM's nearest rotations | rotavg certify of GTSAM's "
      "values as returned: plain / --nearest-rotations |")
print("|" + "---|" * 15)
print("\n".join(rows))
