#!/usr/bin/env python3
"""Markdown tables from the JSON results written by benches/peers/run.sh.

    python3 tables.py RESULTS_DIR INSTANCES_DIR > TABLES.md
    python3 tables.py --scale RESULTS_DIR INSTANCES_DIR > SCALE.md   # stage `scale` only

Peer JSON comes from ../shared/peers (shonan.py, sdp_cvxpy.py, single_scipy.py,
handeye_opencv.py); ours from rotavg's examples / CLI wrapped by run.sh (which adds
`process_wall_seconds`, the wall time of the whole process: start-up, file parsing, solve,
certificate, output).
"""
import glob
import json
import math
import os
import sys

import numpy as np

SCALE_ONLY = len(sys.argv) > 1 and sys.argv[1] == "--scale"
if SCALE_ONLY:
    del sys.argv[1]
RES, INST = sys.argv[1], sys.argv[2]


def load(path):
    try:
        return json.load(open(path))
    except Exception:
        return None


def f(x, d=4):
    if x is None:
        return "-"
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, (int,)) and not isinstance(x, bool):
        return str(x)
    if isinstance(x, float) and (math.isnan(x) or math.isinf(x)):
        return str(x)
    if x == 0:
        return "0"
    if abs(x) >= 1e4 or abs(x) < 1e-3:
        return f"{x:.{d}e}"
    return f"{x:.{d}g}" if abs(x) < 1 else f"{x:.{d + 2}g}"


def secs(x):
    if x is None:
        return "-"
    if x < 1e-3:
        return f"{x * 1e6:.0f} µs"
    if x < 1:
        return f"{x * 1e3:.1f} ms"
    return f"{x:.2f} s"


def ratio(x):
    return f"{x:.0f}x" if x >= 10 else f"{x:.2g}x"


def gt_err(d):
    e = d.get("gt_err") if d else None
    if isinstance(e, dict):
        for k in ("mean_deg", "mean", "median_deg", "median"):
            if k in e:
                return e[k]
    return e if isinstance(e, (int, float)) else None


def tag_of(path, suffix):
    return os.path.basename(path)[: -len(suffix)]


def mb(kb):
    return "-" if kb is None else f"{kb / 1024:.0f} MB"


def rel(a, b):
    """(a - b) / |b|, signed, as text."""
    if a is None or b is None or b == 0:
        return "-"
    return f"{(a - b) / abs(b):+.1e}"


def failed(d):
    """'timeout (600 s)' / 'exit code N' / None for a job record of run.sh's `timed`."""
    if d is None:
        return "missing"
    rc = d.get("exit_code")
    if rc == 124:
        return f"timeout ({d.get('process_wall_seconds', 0):.0f} s)"
    if rc not in (0, None):
        tail = (d.get("stderr_tail") or [""])[-1][:80].replace("|", "/")
        return f"exit code {rc}" + (f": {tail}" if tail else "")
    return None


def scale_section(p):
    sd = os.path.join(RES, "scale")
    order = {"chain": 0, "grid": 1, "random": 2}
    tags = sorted({os.path.basename(g)[: -len("__rotavg.json")]
                   for g in glob.glob(os.path.join(sd, "*__rotavg.json"))},
                  key=lambda t: (int(t.split("_n")[-1]), order.get(t.split("_n")[0], 9)))
    if not tags:
        return
    p("## Scale: synthetic chain / grid / random graphs (stage `scale`)\n")
    p("One process per job; `process` is its wall time measured by run.sh (start-up, parsing, "
      "solve, certificate, output); in parentheses the in-process times: rotavg solve / certify "
      "(JSON `pipeline`), GTSAM chordal initialisation + LM, and Shonan's staircase (with its own "
      "certification). RSS: peak resident set from `/usr/bin/time -v`. Costs are the unweighted "
      "chordal cost (every weight is 1); `vs rotavg` is (peer cost - rotavg cost) / rotavg cost. "
      "Load: 1-minute load average before the job.\n")
    p("| graph | n | m | rotavg process (solve / certify) | rotavg verdict (relative gap) | rotavg cost | rotavg RSS "
      "| chordal+LM process (chordal / LM) | chordal+LM cost vs rotavg | chordal+LM RSS "
      "| Shonan process (staircase) | Shonan p levels, GTSAM cert (lambda_min) | Shonan cost vs rotavg | Shonan RSS | load |")
    p("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for tag in tags:
        ours = load(os.path.join(sd, tag + "__rotavg.json"))
        lmj = load(os.path.join(sd, tag + "__lm.json"))
        shj = load(os.path.join(sd, tag + "__shonan.json"))
        kind, n = tag.rsplit("_n", 1)
        row = [kind]
        o = ours or {}
        det, cert = o.get("pipeline") or {}, o.get("certificate") or {}
        m = o.get("num_measurements") or (lmj or {}).get("m")
        row += [f"{int(n):,}" if not (lmj or {}).get("n") else f"{lmj['n']:,}", f"{m:,}" if m else "-"]
        why = failed(ours)
        our_cost = o.get("cost")
        loads = [(ours or {}).get("load_before")]
        if why or our_cost is None:
            row += [f"{why or 'error'} ({secs((ours or {}).get('process_wall_seconds'))})", "-", "-", mb((ours or {}).get("peak_rss_kb"))]
        else:
            row.append(f"{secs(ours['process_wall_seconds'])} ({secs(det.get('solve_seconds'))} / {secs(det.get('certify_seconds'))})")
            g = cert.get("relative_gap")
            row.append(f"{cert.get('verdict', 'none')} ({f(g, 1)})")
            row.append(f"{our_cost:.10g}")
            row.append(mb(ours.get("peak_rss_kb")))
        for j, name in ((lmj, "chordal_lm"), (shj, "shonan")):
            if j is None:
                row += ["not run", "-", "-"] if name == "chordal_lm" else ["not run", "-", "-", "-"]
                continue
            loads.append(j.get("load_before"))
            why = failed(j)
            r = (j.get("results") or {}).get(name) or {}
            if why or "cost" not in r:
                if why:
                    msg = why
                elif r.get("error") or j.get("error"):
                    msg = "error: " + str(r.get("error") or j.get("error"))[:80].replace("|", "/")
                else:  # shonan.py drops chordal_lm when its chordal initialisation raised
                    msg = f"no result: exception in the {'chordal initialisation' if name == 'chordal_lm' else 'solve'} ({secs(j.get('process_wall_seconds'))})"
                row.append(msg)
                row += (["-"] if name == "chordal_lm" else ["-", "-"]) + [mb(j.get("peak_rss_kb"))]
                continue
            if name == "chordal_lm":
                chordal = r.get("time_s_incl_chordal_init", r["time_s"]) - r["time_s"]
                row.append(f"{secs(j['process_wall_seconds'])} ({secs(chordal)} / {secs(r['time_s'])})")
                row.append(f"{r['cost']:.10g} ({rel(r['cost'], our_cost)})")
            else:
                row.append(f"{secs(j['process_wall_seconds'])} ({secs(r['time_s'])})")
                lv = r.get("p_levels") or []
                row.append(f"{lv[0]}..{lv[-1] if lv else '-'}, {f(r.get('certified'))} ({f(r.get('gtsam_min_eig'), 1)})")
                row.append(f"{r['cost']:.10g} ({rel(r['cost'], our_cost)})")
            row.append(mb(j.get("peak_rss_kb")))
        row.append(" / ".join(str(x).split()[0] for x in loads if x))
        p("| " + " | ".join(row) + " |")
    checks = sorted(glob.glob(os.path.join(sd, "*__check.json")))
    if checks:
        p("\nConvention check (n = 10^3): the chordal cost of the ground truth and of rotavg's "
          "solution (written by `rotavg multiple --output`, read back by the peer harness) by "
          "GTSAM's own `cost()`, against rotavg's values.\n")
        p("| graph | ground truth: rotavg | GTSAM cost() | rel. diff | rotavg solution: rotavg | GTSAM cost() | rel. diff |")
        p("|---|---|---|---|---|---|---|")
        for c in checks:
            d = load(c) or {}
            if "gt_gtsam_cost" not in d:
                p(f"| {os.path.basename(c)[:-len('__check.json')]} | check failed | | | | | |")
                continue
            p(f"| {os.path.basename(c)[:-len('__check.json')]} | {d['rotavg_gt_cost']:.15g} | {d['gt_gtsam_cost']:.15g} "
              f"| {d['rel_diff_gt_gtsam_vs_rotavg']:.1e} | {d['rotavg_solution_cost']:.15g} "
              f"| {d['rotavg_solution_gtsam_cost']:.15g} | {d['rel_diff_solution_gtsam_vs_rotavg']:.1e} |")
    p("")


if SCALE_ONLY:
    out = []
    scale_section(out.append)
    print("\n".join(out))
    sys.exit(0)


out = []
p = out.append

# ------------------------------------------------------------------ multiple
p("## Multiple rotation averaging (chordal L2, file weights = SE-Sync kappa)\n")
p("GTSAM times are the peer's own in-process solve times (no parsing, no graph construction; "
  "`chordal+LM` includes its chordal initialisation). rotavg's time is the wall time of the "
  "whole `certify_g2o` process (load + solve + certify + output); its solve / certify split "
  "is in parentheses. `cert` for Shonan is gtsam's own flag (lambda_min > -1e-4); `bound` is "
  "the peer harness's weak-duality suboptimality bound 3n max(0, -lambda_min) of the Shonan "
  "result. Our `gap` is upper bound minus the verified lower bound.\n")
p("| graph | n | m | Shonan time | Shonan cost | Shonan cert / bound | chordal+LM time | chordal+LM cost "
  "| rotavg total (solve / certify) | rotavg cost | rotavg certified (gap) | speed-up vs Shonan | cost vs best GTSAM |")
p("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for g in sorted(glob.glob(os.path.join(RES, "mra__*__gtsam.json"))):
    tag = tag_of(g, "__gtsam.json")
    peer, ours = load(g), load(os.path.join(RES, tag + "__rotavg.json"))
    name = tag[len("mra__"):]
    shonan_failed = None
    if not peer or "results" not in peer:
        # Shonan timed out: run.sh then reran GTSAM's chordal and chordal+LM alone
        shonan_failed = peer.get("error") if peer else "missing"
        peer = load(os.path.join(RES, tag + "__gtsamlm.json")) or {"results": {}}
    R = peer.get("results", {})
    sh, lm = R.get("shonan", {}), R.get("chordal_lm", {})
    meta = peer.get("problem_meta", {})
    n = meta.get("n") or (ours or {}).get("nodes")
    m = meta.get("m") or (ours or {}).get("edges")
    costs = [r.get("cost_file_weights") for r in R.values() if isinstance(r, dict) and r.get("cost_file_weights") is not None]
    best = min(costs) if costs else None
    row = [name, f(n), f(m)]
    if shonan_failed:
        row += ["timeout (> 600 s)" if "124" in str(shonan_failed) else f"failed ({shonan_failed})", "-", "-"]
    else:
        row += [secs(sh.get("time_s")), f(sh.get("cost_file_weights"), 6),
                f"{f(sh.get('certified'))} / {f(sh.get('our_cert_subopt_bound'), 2)}"]
    row += [secs(lm.get("time_s_incl_chordal_init", lm.get("time_s"))), f(lm.get("cost_file_weights"), 6)]
    if ours and "cost" in ours:
        row += [f"{secs(ours['process_wall_seconds'])} ({secs(ours['solve_seconds'])} / {secs(ours['certify_seconds'])})",
                f(ours["cost"], 6), f"{f(ours['certified'])} ({f(ours.get('gap'), 2)})"]
        st = sh.get("time_s")
        row.append(ratio(st / ours['process_wall_seconds']) if st else (">%.0fx" % (600 / ours['process_wall_seconds']) if shonan_failed else "-"))
        row.append(f"{(ours['cost'] - best) / best:+.1e}" if best else "-")
    else:
        row += [f"error: {(ours or {}).get('error', 'missing')}", "", "", "", ""]
    p("| " + " | ".join(row) + " |")
    tight = load(os.path.join(RES, tag + "__rotavgtight.json"))
    if tight and "cost" in tight:
        st = sh.get("time_s")
        p("| " + " | ".join([f"{name}, `--gradient-tolerance 1e-12`", "", "", "", "", "", "", "",
            f"{secs(tight['process_wall_seconds'])} ({secs(tight['solve_seconds'])} / {secs(tight['certify_seconds'])})",
            f(tight["cost"], 6), f"{f(tight['certified'])} ({f(tight.get('gap'), 2)})",
            ratio(st / tight['process_wall_seconds']) if st else "-",
            f"{(tight['cost'] - best) / best:+.1e}" if best else "-"]) + " |")
p("")

# ------------------------------------------------------------------ multiple, whole process
procs = sorted(glob.glob(os.path.join(RES, "mra__*__gtsamproc.json")))
if procs:
    p("### Whole process against whole process (stage `proc`, same run as rotavg's)\n")
    p("Shonan alone in its own process (`shonan.py --methods shonan --no-cert`), wall time measured "
      "by the driver exactly as for rotavg: interpreter start, imports, file parsing, graph "
      "construction and the Shonan staircase (with gtsam's own certification). rotavg: the whole "
      "`certify_g2o` process (load, solve, verified certificate, JSON). The in-process column "
      "compares Shonan's solve alone with rotavg's solve + certify.\n")
    p("| graph | Shonan process | Shonan solve (in-process) | Shonan cost | rotavg process | rotavg solve + certify | rotavg cost | speed-up, whole process | speed-up, in-process |")
    p("|---|---|---|---|---|---|---|---|---|")
    for g in procs:
        tag = tag_of(g, "__gtsamproc.json")
        pr, ours = load(g), load(os.path.join(RES, tag + "__rotavg.json"))
        name = tag[len("mra__"):]
        sh = (pr or {}).get("results", {}).get("shonan", {})
        pw = (pr or {}).get("process_wall_seconds")
        if not ours or "cost" not in ours or not pw or "time_s" not in sh:
            p(f"| {name} | {secs(pw)} | {(pr or {}).get('error', '-')} | | | | | | |")
            continue
        inproc = ours["solve_seconds"] + ours["certify_seconds"]
        p(f"| {name} | {secs(pw)} | {secs(sh['time_s'])} | {f(sh.get('cost_file_weights'), 6)} "
          f"| {secs(ours['process_wall_seconds'])} | {secs(inproc)} | {f(ours['cost'], 6)} "
          f"| {ratio(pw / ours['process_wall_seconds'])} | {ratio(sh['time_s'] / inproc)} |")
    p("")

# ------------------------------------------------------------------ SDP
for g in sorted(glob.glob(os.path.join(RES, "sdp__*__cvxpy.json"))):
    tag = tag_of(g, "__cvxpy.json")
    peer, ours = load(g), load(os.path.join(RES, tag + "__rotavg.json"))
    name = tag[len("sdp__"):]
    p(f"## SDP relaxation of multiple rotation averaging ({name})\n")
    p("cvxpy times: `time_s` (whole `prob.solve`, including cvxpy's canonicalisation) and the solver's "
      "own reported solve time. rotavg: `relax_multiple` (assembly + Clarabel + rounding) and "
      "Clarabel alone; plus the verification of the bound by a Cholesky factorisation. "
      "`lower bound` is rigorous for both (peer: its recomputed dual bound; ours: "
      "`certify_with_multipliers`).\n")
    p("| solver | form | time (total) | solver time | iterations | SDP value | rigorous lower bound | rounded cost | certified |")
    p("|---|---|---|---|---|---|---|---|---|")
    for s, r in ((peer or {}).get("results") or {}).items():
        p(f"| cvxpy + {s} | {r.get('form', '-')} | {secs(r.get('time_s'))} | {secs(r.get('solver_time_s'))} | {f(r.get('num_iters'))} "
          f"| {f(r.get('sdp_value'), 8)} | {f(r.get('dual_bound'), 8)} | {f(r.get('rounded_cost'), 8)} | "
          f"{'gap ' + f(r.get('gap_rounded_minus_bound'), 2) if r.get('gap_rounded_minus_bound') is not None else '-'} |")
    if ours and "sdp" in ours:
        s = ours["sdp"]
        p(f"| rotavg (Clarabel, Rust) | dual | {secs(s['relax_seconds'])} (+ bound {secs(s['seconds_with_certificate'] - s['relax_seconds'])}; process {secs(ours['process_wall_seconds'])}) "
          f"| {secs(s['solver_seconds'])} | {s['iterations']} | {f(s['dual_objective'], 8)} | {f(s['verified_lower_bound'], 8)} "
          f"| {f(s['rounded_cost'], 8)} | {f(s['certified'])} (gap {f(s['gap'], 2)}) |")
        p(f"| rotavg local solve + dual certificate | - | {secs(ours['solve_seconds'] + ours['certify_seconds'])} | - | {ours['iterations']} | - "
          f"| {f(ours['lower_bound'], 8)} | {f(ours['cost'], 8)} | {f(ours['certified'])} (gap {f(ours['gap'], 2)}) |")
    p("")

# ------------------------------------------------------------------ single
p("## Single rotation averaging\n")
p("Peer times are in-process (`time.perf_counter` around the call); ours are the library call "
  "(solve + certificate) measured inside the example; the process wall time of our example "
  "(all five methods, file parsing included) is in the last column. Costs: chordal L2 "
  "sum w ||R - R_k||_F^2, geodesic L2 sum w theta^2, geodesic L1 sum w theta (radians).\n")
p("| instance | cost | SciPy / numpy method | peer time | peer cost | rotavg time | rotavg cost | rotavg certified | rotavg process |")
p("|---|---|---|---|---|---|---|---|---|")
pairs = [("chordal_l2", "scipy_mean", ("chordal", "l2")),
         ("geodesic_l2", "karcher", ("geodesic", "l2")),
         ("geodesic_l1", "weiszfeld_l1", ("geodesic", "l1"))]
for g in sorted(glob.glob(os.path.join(RES, "single__*__scipy.json"))):
    tag = tag_of(g, "__scipy.json")
    peer, ours = load(g), load(os.path.join(RES, tag + "__rotavg.json"))
    name = tag[len("single__"):]
    for cost, pm, (metric, norm) in pairs:
        r = (peer or {}).get("results", {}).get(pm, {})
        o = next((x for x in (ours or {}).get("methods", []) if x["metric"] == metric and x["norm"] == norm), {})
        p(f"| {name} | {cost} | {pm} | {secs(r.get('time_s'))} | {f(r.get('costs', {}).get(cost), 10)} "
          f"| {secs(o.get('seconds'))} | {f(o.get('cost_' + cost), 10)} | {f(o.get('certified'))} "
          f"| {secs((ours or {}).get('process_wall_seconds'))} |")
p("")

# ------------------------------------------------------------------ hand-eye
p("## Hand-eye (conjugate) rotation averaging\n")
p("Inputs from `synth.py conj --mode poses` (N poses, all N(N-1)/2 pairs: exactly the pairs OpenCV "
  "forms internally) and the Tabb set via `tabb2conj.py`. Cost: chordal sum ||S R_k - L_k S||_F^2 "
  "on the pairs. OpenCV times: min of 5 in-process calls. rotavg: `rotavg conjugate FILE.json "
  "--json` — its in-process solver + SDP time, and the whole process wall time. `ref` is the "
  "peer harness's multi-start least-squares minimiser (best known). Error: angle to the planted S "
  "(Tabb: to Tabb's own AA/RPI estimate, a reference, not ground truth).\n")
methods = ["TSAI", "PARK", "HORAUD", "ANDREFF", "DANIILIDIS"]
p("| instance | pairs | " + " | ".join(f"{m} cost (err°)" for m in methods) +
  " | ref cost | rotavg cost (err°) | rotavg certified (gap) | OpenCV fastest | rotavg solve+SDP | rotavg process |")
p("|---|---|" + "---|" * (len(methods) + 6))


def read_gt_s(path):
    try:
        for line in open(path):
            t = line.split()
            if t and t[0] == "S":
                return np.array([float(x) for x in t[1:10]]).reshape(3, 3)
    except OSError:
        return None
    return None


def ang(a, b):
    c = (np.trace(a.T @ b) - 1) / 2
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


for g in sorted(glob.glob(os.path.join(RES, "conj__*__opencv.json"))):
    tag = tag_of(g, "__opencv.json")
    peer, ours = load(g), load(os.path.join(RES, tag + "__rotavg.json"))
    name = tag[len("conj__"):]
    R = (peer or {}).get("results", {})
    row = [name, f((peer or {}).get("m"))]
    for mth in methods:
        r = R.get(mth, {})
        row.append(f"{f(r.get('cost'), 6)} ({f(r.get('err_deg'), 3)})" if r.get("finite", True) and "cost" in r else "fail")
    row.append(f(R.get("ref_chordal", {}).get("cost"), 6))
    gt = read_gt_s(os.path.join(INST, name + ".gt.txt"))
    if ours and "estimate" in ours:
        s = np.array(ours["estimate"])
        err = ang(s, gt) if gt is not None else None
        c = ours.get("certificate") or {}
        row.append(f"{f(ours['chordal_cost'], 6)} ({f(err, 3)})")
        row.append(f"{f(c.get('verdict') == 'certified')} ({f(c.get('gap'), 1)})")
        times = [r.get("time_s") for r in (R.get(x, {}) for x in methods) if r.get("time_s")]
        row.append(secs(min(times)) if times else "-")
        inproc = (ours.get("solver") or {}).get("seconds", 0) + (ours.get("sdp") or {}).get("solve_seconds", 0)
        row.append(secs(inproc))
        row.append(secs(ours.get("process_wall_seconds")))
    else:
        row += [f"error: {(ours or {}).get('error', 'missing')}", "", "", "", ""]
    p("| " + " | ".join(row) + " |")
p("")
scale_section(p)
print("\n".join(out))
