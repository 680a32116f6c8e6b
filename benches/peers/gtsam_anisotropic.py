#!/usr/bin/env python3
"""GTSAM with full 3x3 noise models on an anisotropic rotavg JSON graph, and rotavg on the same
file, side by side (docs/benchmarks.md "Anisotropic measurements: GTSAM with full noise models").

    python3 gtsam_anisotropic.py GRAPH.json TRUTH.txt ROTAVG_BINARY > row.json
    python3 gtsam_anisotropic.py --table FOLDER_OF_ROWS > ANISO.md

GTSAM: one BetweenFactorRot3 per edge with noiseModel.Gaussian.Information(H_g), Levenberg-
Marquardt (GTSAM's defaults) from GTSAM's own chordal initialisation
(InitializePose3.computeOrientationsChordal on the same edges with zero translations).

Conventions (contract section 1): our edge (i, j, R_ij, H) measures R_j R_i^T = R_ij exp([e]x) with
information H for e. GTSAM's variables are world-from-body, X_i = R_i^T, and the factor's measured
value is Z = X_i^-1 X_j at zero noise, i.e. Z = R_ij^T. Its error is
g = Logmap(Z^-1 X_i^-1 X_j) = log(R_ij R_i R_j^T) = -R_ij e (because R_j R_i^T = R_ij exp([e]x)),
so the information of g is H_g = R_ij H R_ij^T and GTSAM's error 1/2 sum g^T H_g g is half the
anisotropic geodesic cost sum e^T H e that `rotavg multiple --loss geodesic` minimises. Both
costs are also evaluated here, with NumPy/SciPy, at both estimates.
"""
import json
import subprocess
import sys
import time

import gtsam
import numpy as np
from scipy.spatial.transform import Rotation as SR


def load(graph_path, truth_path):
    g = json.load(open(graph_path))
    n = g["num_rotations"]
    edges = [(e["i"], e["j"], np.array(e["rotation"]), np.array(e["information"])) for e in g["edges"]]
    truth = np.zeros((n, 3, 3))
    for line in open(truth_path):
        if line.strip() and not line.startswith("#"):
            v = line.split()
            truth[int(v[0])] = np.array([float(x) for x in v[1:10]]).reshape(3, 3)
    return n, edges, truth


def geodesic_cost(edges, r):
    """sum e^T H e, e = log(R_ij^T R_j R_i^T) (SciPy's logarithm)."""
    total = 0.0
    for i, j, rij, h in edges:
        e = SR.from_matrix(rij.T @ r[j] @ r[i].T).as_rotvec()
        total += e @ h @ e
    return total


def chordal_cost(edges, r):
    """sum 4 (tr M - <R_ij M, R_j R_i^T>), M = tr(H)/2 I - H."""
    total = 0.0
    for i, j, rij, h in edges:
        m = np.trace(h) / 2 * np.eye(3) - h
        total += 4 * (np.trace(m) - np.sum((rij @ m) * (r[j] @ r[i].T)))
    return total


def median_error_deg(r, truth):
    """Median angle after the chordal alignment R_i G ~ truth_i."""
    u, _, vt = np.linalg.svd(sum(r[k].T @ truth[k] for k in range(len(r))))
    g = u @ np.diag([1, 1, np.linalg.det(u @ vt)]) @ vt
    ang = [np.degrees(np.linalg.norm(SR.from_matrix((r[k] @ g).T @ truth[k]).as_rotvec())) for k in range(len(r))]
    return float(np.median(ang))


def cauchy_cost(edges, r, c_deg=5.0):
    """sum wbar c^2 ln(1 + theta_H^2 / c^2), theta_H = sqrt(e^T H e / wbar) (rotavg's Cauchy
    loss of the Mahalanobis angle, `--loss cauchy --loss-threshold c_deg`)."""
    c = np.radians(c_deg)
    total = 0.0
    for i, j, rij, h in edges:
        e = SR.from_matrix(rij.T @ r[j] @ r[i].T).as_rotvec()
        wbar = np.trace(h) / 3
        total += wbar * c * c * np.log1p((e @ h @ e / wbar) / (c * c))
    return total


def gtsam_solve(n, edges, cauchy_deg=None):
    t0 = time.perf_counter()
    pose_graph = gtsam.NonlinearFactorGraph()
    iso = gtsam.noiseModel.Isotropic.Sigma(6, 1.0)
    for i, j, rij, _ in edges:
        pose_graph.add(gtsam.BetweenFactorPose3(i, j, gtsam.Pose3(gtsam.Rot3(rij.T), np.zeros(3)), iso))
    pose_graph.add(gtsam.PriorFactorPose3(0, gtsam.Pose3(), iso))
    init_rot = gtsam.InitializePose3.computeOrientationsChordal(gtsam.InitializePose3.buildPose3graph(pose_graph))
    graph = gtsam.NonlinearFactorGraph()
    for i, j, rij, h in edges:
        hg = rij @ h @ rij.T
        model = gtsam.noiseModel.Gaussian.Information(hg)
        if cauchy_deg is not None:
            # GTSAM's Cauchy on the whitened norm sqrt(g^T H_g g) = sqrt(wbar) theta_H, with
            # k = sqrt(wbar) c: k^2/2 ln(1 + x^2/k^2) is half rotavg's wbar c^2 ln(1 + theta_H^2/c^2)
            k = np.sqrt(np.trace(h) / 3) * np.radians(cauchy_deg)
            model = gtsam.noiseModel.Robust.Create(gtsam.noiseModel.mEstimator.Cauchy.Create(k), model)
        graph.add(gtsam.BetweenFactorRot3(i, j, gtsam.Rot3(rij.T), model))
    initial = gtsam.Values()
    for k in range(n):
        initial.insert(k, init_rot.atRot3(k))
    params = gtsam.LevenbergMarquardtParams()
    opt = gtsam.LevenbergMarquardtOptimizer(graph, initial, params)
    result = opt.optimize()
    seconds = time.perf_counter() - t0
    r = np.array([result.atRot3(k).matrix().T for k in range(n)])
    return r, seconds, 2 * graph.error(result), opt.iterations()


def rotavg(binary, graph_path, truth_path, extra):
    t0 = time.perf_counter()
    out = subprocess.run([binary, "multiple", graph_path, "--json", "--ground-truth", truth_path] + extra,
                         capture_output=True, text=True, check=True)
    wall = time.perf_counter() - t0
    d = json.loads(out.stdout)
    return np.array(d["estimate"]), d, wall


def table(folder):
    """A Markdown table of the rows in `folder` (smallest graphs first)."""
    import glob
    import os

    rows = [json.load(open(p)) for p in glob.glob(os.path.join(folder, "*.json"))]
    rows.sort(key=lambda r: (r["n"], r["graph"]))
    print("| graph | n | edges | median error (deg): GTSAM LM full noise / rotavg geodesic / rotavg chordal / isotropic "
          "| geodesic cost sum e^T H e: GTSAM / rotavg | rotavg chordal verdict | seconds: GTSAM (init + LM) / rotavg geodesic / rotavg chordal (process) |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        g, a, c, i = (r["gtsam_lm_full_noise"], r["rotavg_geodesic"], r["rotavg_chordal"], r["rotavg_isotropic_chordal"])
        print(f"| {os.path.basename(r['graph'])} | {r['n']} | {r['edges']} "
              f"| {g['median_error_deg']:.4f} / {a['median_error_deg']:.4f} / {c['median_error_deg']:.4f} / {i['median_error_deg']:.4f} "
              f"| {g['geodesic_cost']:.10g} / {a['geodesic_cost']:.10g} | {c['verdict']} "
              f"| {g['seconds']:.3f} / {a['process_wall_seconds']:.3f} / {c['process_wall_seconds']:.3f} |")
    robust = [r for r in rows if "rotavg_cauchy" in r]
    if robust:
        print()
        print("| graph | median error (deg): GTSAM LM full noise + Cauchy / rotavg Cauchy | Cauchy cost: GTSAM / rotavg "
              "| seconds: GTSAM / rotavg (process) |")
        print("|---|---|---|---|")
        for r in robust:
            g, a = r["gtsam_lm_full_noise_cauchy"], r["rotavg_cauchy"]
            print(f"| {os.path.basename(r['graph'])} | {g['median_error_deg']:.4f} / {a['median_error_deg']:.4f} "
                  f"| {g['cauchy_cost']:.10g} / {a['cauchy_cost']:.10g} | {g['seconds']:.3f} / {a['process_wall_seconds']:.3f} |")


def main():
    if sys.argv[1] == "--table":
        table(sys.argv[2])
        return
    graph_path, truth_path, binary = sys.argv[1:4]
    n, edges, truth = load(graph_path, truth_path)
    rg, g_seconds, g_cost, g_iters = gtsam_solve(n, edges)
    rows = {"graph": graph_path, "n": n, "edges": len(edges)}
    rows["gtsam_lm_full_noise"] = {
        "median_error_deg": median_error_deg(rg, truth),
        "geodesic_cost": geodesic_cost(edges, rg),
        "gtsam_2x_error": g_cost,
        "chordal_cost": chordal_cost(edges, rg),
        "iterations": g_iters,
        "seconds": g_seconds,
    }
    if "_0.json" not in graph_path:  # graphs with outliers: the Cauchy loss too
        rc, c_seconds, c_cost, c_iters = gtsam_solve(n, edges, cauchy_deg=5.0)
        rows["gtsam_lm_full_noise_cauchy"] = {
            "median_error_deg": median_error_deg(rc, truth),
            "cauchy_cost": cauchy_cost(edges, rc),
            "gtsam_2x_error": c_cost,
            "iterations": c_iters,
            "seconds": c_seconds,
        }
        r, d, wall = rotavg(binary, graph_path, truth_path, ["--loss", "cauchy"])
        rows["rotavg_cauchy"] = {
            "median_error_deg": median_error_deg(r, truth),
            "cauchy_cost": cauchy_cost(edges, r),
            "reported_cost": d["cost"],
            "seconds_solve": d["solver"]["seconds"],
            "process_wall_seconds": wall,
        }
    for name, extra in [("rotavg_geodesic", ["--loss", "geodesic"]),
                        ("rotavg_chordal", []),
                        ("rotavg_isotropic_chordal", ["--weights", "unit"])]:
        r, d, wall = rotavg(binary, graph_path, truth_path, extra)
        rows[name] = {
            "median_error_deg": median_error_deg(r, truth),
            "geodesic_cost": geodesic_cost(edges, r),
            "chordal_cost": chordal_cost(edges, r),
            "reported_cost": d["cost"],
            "verdict": (d.get("certificate") or {}).get("verdict"),
            "seconds_solve": d["solver"]["seconds"],
            "process_wall_seconds": wall,
        }
    json.dump(rows, sys.stdout, indent=1)


if __name__ == "__main__":
    main()
