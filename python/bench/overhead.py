"""Python call overhead of rotavg.average_multiple on a synthetic view graph.

    python python/bench/overhead.py [--nodes 10000] [--edges-per-node 3] [--repeats 5]

Overhead = wall time of the Python call minus the library pipeline's own time (the report's
pipeline.total_seconds: local solve + certificate). It covers copying the arrays in, the
library's validation of every rotation and index (as its file readers do), building the
report and the (n, 3, 3) output array. Prints the median over the repeats.
"""

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from conftest import synthetic_graph  # noqa: E402

import rotavg  # noqa: E402


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--nodes", type=int, default=10_000)
    p.add_argument("--edges-per-node", type=int, default=3)
    p.add_argument("--noise", type=float, default=0.02)
    p.add_argument("--repeats", type=int, default=5)
    a = p.parse_args()
    rng = np.random.default_rng(1)
    n = a.nodes
    _, i, j, rel = synthetic_graph(rng, n, a.edges_per_node * n, a.noise)
    rows = []
    for _ in range(a.repeats):
        t = time.perf_counter()
        res = rotavg.average_multiple(n, i, j, rel)
        wall = time.perf_counter() - t
        rust = res.to_dict()["pipeline"]["total_seconds"]
        rows.append((wall, rust, wall - rust))
    wall, rust, over = (statistics.median(c) for c in zip(*rows))
    print(f"{n} nodes, {len(i)} edges, verdict {res.certificate.verdict}")
    print(f"python call {wall:.4f} s, rust pipeline {rust:.4f} s, overhead {over * 1e3:.1f} ms "
          f"= {100 * over / rust:.2f} % (median of {a.repeats})")


if __name__ == "__main__":
    main()
