#!/usr/bin/env python3
"""Random expander view graphs and perturbed estimates for benches/ab.sh (standard library only).

    python3 benches/gen_graph.py expander N DEGREE SIGMA SEED OUT.json
        A multiple-averaging problem in the JSON format of contract section 5:
        {"num_rotations": n, "edges": [{"i", "j", "rotation": R_ij, "weight": 1}]}.
        Ground truth R_i uniform on SO(3); the edges are a random Hamiltonian cycle (so the
        graph is connected) plus distinct uniformly random pairs up to an average degree DEGREE
        (a random graph of average degree >= 6 is an expander with high probability); each
        measurement is R_ij = R_j R_i^T exp([e]x) with e ~ N(0, SIGMA^2 I_3) (radians), so
        R_ij R_i = R_j without noise.

    python3 benches/gen_graph.py chain N CLOSURES SIGMA SEED OUT.json [planar]
        A SLAM-like pose graph (as rotavg's `SyntheticChain`): headings on a random walk
        (R_{i+1} = exp([t]x) R_i, t ~ N(0, 0.1^2 I_3), or a turn about z with `planar`),
        odometry edges (i, i + 1) and round(CLOSURES * N) loop closures joining a random node
        j >= 10 to a random earlier node i < j - 5; measurement noise as for `expander`.

    python3 benches/gen_graph.py grid N CLOSURES SIGMA SEED OUT.json
        A SLAM-like lattice (as rotavg's `SyntheticGrid`): a robot sweeps a sqrt(N) x sqrt(N)
        grid row by row (odometry edges along the path, headings on a random walk as for
        `chain`), and every other lattice edge to the next row is a loop closure kept with
        probability CLOSURES; measurement noise as for `expander`.

    python3 benches/gen_graph.py perturb IN.json DEGREES SEED OUT.json
        Reads an estimate file ({"rotations": [...]} as `rotavg multiple --output` writes it,
        or {"estimate": [...]} as `--json` prints it) and writes {"rotations": [...]} with each
        R_i replaced by exp(DEGREES * pi/180 [a_i]x) R_i, a_i a uniformly random unit axis per
        node.

Rotations are written with 17 significant digits (orthonormal to rounding). Seeded: the same
arguments give the same file.
"""
import json
import math
import random
import sys


def quat_to_matrix(w, x, y, z):
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]


def random_rotation(rng):
    q = [rng.gauss(0.0, 1.0) for _ in range(4)]
    s = math.sqrt(sum(v * v for v in q))
    return quat_to_matrix(*(v / s for v in q))


def exp_so3(v):
    """Rotation exp([v]x) through the unit quaternion (orthonormal to rounding)."""
    theta = math.sqrt(sum(c * c for c in v))
    if theta == 0.0:
        return quat_to_matrix(1.0, 0.0, 0.0, 0.0)
    s = math.sin(theta / 2) / theta
    return quat_to_matrix(math.cos(theta / 2), v[0] * s, v[1] * s, v[2] * s)


def mul(a, b):
    return [[sum(a[r][k] * b[k][c] for k in range(3)) for c in range(3)] for r in range(3)]


def transpose(a):
    return [[a[c][r] for c in range(3)] for r in range(3)]


def random_axis(rng):
    while True:
        v = [rng.gauss(0.0, 1.0) for _ in range(3)]
        s = math.sqrt(sum(c * c for c in v))
        if s > 1e-6:
            return [c / s for c in v]


def expander(n, degree, sigma, seed):
    if n < 3:
        raise SystemExit("expander: n must be at least 3")
    rng = random.Random(seed)
    truth = [random_rotation(rng) for _ in range(n)]
    order = list(range(n))
    rng.shuffle(order)
    pairs = set()
    for k in range(n):
        a, b = order[k], order[(k + 1) % n]
        pairs.add((min(a, b), max(a, b)))
    target = min(int(round(degree * n / 2)), n * (n - 1) // 2)
    while len(pairs) < target:
        a, b = rng.randrange(n), rng.randrange(n)
        if a != b:
            pairs.add((min(a, b), max(a, b)))
    edges = []
    for i, j in sorted(pairs):
        if rng.random() < 0.5:
            i, j = j, i
        noise = exp_so3([rng.gauss(0.0, sigma) for _ in range(3)])
        rij = mul(mul(truth[j], transpose(truth[i])), noise)
        edges.append({"i": i, "j": j, "rotation": rij, "weight": 1})
    return {"num_rotations": n, "edges": edges}


def chain(n, closures, sigma, seed, planar):
    if n < 17:
        raise SystemExit("chain: n must be at least 17")
    rng = random.Random(seed)

    def step(s):
        return [0.0, 0.0, rng.gauss(0.0, s)] if planar else [rng.gauss(0.0, s) for _ in range(3)]

    truth = [quat_to_matrix(1.0, 0.0, 0.0, 0.0)]
    for _ in range(1, n):
        truth.append(mul(exp_so3(step(0.1)), truth[-1]))
    pairs = [(i - 1, i) for i in range(1, n)]
    for _ in range(int(round(closures * n))):
        j = rng.randrange(10, n)
        pairs.append((rng.randrange(0, j - 5), j))
    edges = []
    for i, j in pairs:
        rij = mul(mul(truth[j], transpose(truth[i])), exp_so3(step(sigma)))
        edges.append({"i": i, "j": j, "rotation": rij, "weight": 1})
    return {"num_rotations": n, "edges": edges}


def grid(n, closures, sigma, seed):
    w = max(2, int(round(math.sqrt(n))))
    h = w
    rng = random.Random(seed)
    truth = [quat_to_matrix(1.0, 0.0, 0.0, 0.0)]
    for _ in range(1, w * h):
        truth.append(mul(exp_so3([rng.gauss(0.0, 0.1) for _ in range(3)]), truth[-1]))

    def node(r, c):
        return r * w + (c if r % 2 == 0 else w - 1 - c)

    pairs = [(k - 1, k) for k in range(1, w * h)]
    for r in range(h - 1):
        for c in range(w):
            a, b = node(r, c), node(r + 1, c)
            if abs(a - b) != 1 and rng.random() < closures:
                pairs.append((min(a, b), max(a, b)))
    edges = []
    for i, j in pairs:
        noise = exp_so3([rng.gauss(0.0, sigma) for _ in range(3)])
        edges.append({"i": i, "j": j, "rotation": mul(mul(truth[j], transpose(truth[i])), noise),
                      "weight": 1})
    return {"num_rotations": w * h, "edges": edges}


def perturb(path, degrees, seed):
    with open(path) as f:
        doc = json.load(f)
    rotations = doc.get("rotations", doc.get("estimate"))
    if rotations is None:
        raise SystemExit(f"{path}: no \"rotations\" or \"estimate\" array")
    rng = random.Random(seed)
    angle = math.radians(degrees)
    out = []
    for r in rotations:
        a = random_axis(rng)
        out.append(mul(exp_so3([angle * c for c in a]), r))
    return {"rotations": out}


def write(doc, path):
    with open(path, "w") as f:
        json.dump(doc, f, separators=(",", ":"))
        f.write("\n")


def main(argv):
    usage = __doc__.split("\n\n")[1]
    if len(argv) == 7 and argv[1] == "expander":
        n, degree, sigma, seed = int(argv[2]), float(argv[3]), float(argv[4]), int(argv[5])
        write(expander(n, degree, sigma, seed), argv[6])
    elif len(argv) in (7, 8) and argv[1] == "chain" and argv[7:] in ([], ["planar"]):
        n, closures, sigma, seed = int(argv[2]), float(argv[3]), float(argv[4]), int(argv[5])
        write(chain(n, closures, sigma, seed, len(argv) == 8), argv[6])
    elif len(argv) == 7 and argv[1] == "grid":
        n, closures, sigma, seed = int(argv[2]), float(argv[3]), float(argv[4]), int(argv[5])
        write(grid(n, closures, sigma, seed), argv[6])
    elif len(argv) == 6 and argv[1] == "perturb":
        write(perturb(argv[2], float(argv[3]), int(argv[4])), argv[5])
    else:
        sys.stderr.write("usage:\n" + usage + "\n")
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
