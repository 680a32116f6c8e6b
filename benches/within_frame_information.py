"""Why a rig's within-frame pairs carry one pooled information (`paper-notes/formats.md`
`[F18]`): on a generated rig scene (`cargo run --release --example colmap_scene -- DIR --cameras
N --rig-sensors K --seed S`), each pair's own information from its correspondences (`[F13]`,
read by the view graph's reader, where nothing is pooled) against the pairs' yaw errors.

    python benches/within_frame_information.py DIR K

For every sensor pair, the within-frame pairs within 2 degrees of the truth (images `K f + s +
1`, frame `f`, sensor `s`, as the generator numbers them; errors `e = log(R^T R_b R_a^T)` in the
first sensor's camera, degrees): their plain mean, their information-weighted mean
`(sum H)^-1 sum H e` (what a least-squares sensor follows), and the mean yaw error in each
quarter of the pairs sorted by their yaw information `H_yy`. Needs the Python package (`pip
install ./python`), numpy and scipy.
"""

import sys

import numpy as np
import rotavg
from scipy.spatial.transform import Rotation


def true_rotations(folder):
    truth = {}
    for line in open(f"{folder}/truth/images.txt"):
        fields = line.split()
        if line.startswith("#") or len(fields) < 10:
            continue
        w, x, y, z = (float(v) for v in fields[1:5])
        truth[int(fields[0])] = Rotation.from_quat([x, y, z, w]).as_matrix()
    return truth


def main():
    folder, k = sys.argv[1], int(sys.argv[2])
    g = rotavg.read_graph(f"{folder}/database.db", information="full")
    ids = [int(v) for v in g.node_ids]
    rel, info = np.asarray(g.rel), np.asarray(g.information)
    truth = true_rotations(folder)
    groups = {}
    for e, (i, j) in enumerate(zip(np.asarray(g.i), np.asarray(g.j))):
        a, b = ids[i], ids[j]
        (fa, sa), (fb, sb) = divmod(a - 1, k), divmod(b - 1, k)
        if fa != fb:
            continue
        err = Rotation.from_matrix(rel[e].T @ truth[b] @ truth[a].T).as_rotvec()
        if np.degrees(np.linalg.norm(err)) < 2.0:
            groups.setdefault((sa, sb), []).append((err, info[e]))
    for (s, t), pairs in sorted(groups.items()):
        errs = np.array([p[0] for p in pairs])
        hs = np.array([p[1] for p in pairs])
        weighted = np.linalg.solve(hs.sum(0), np.einsum("kij,kj->i", hs, errs))
        order = np.argsort(hs[:, 1, 1])
        quarters = [np.degrees(errs[q, 1].mean()) for q in np.array_split(order, 4)]
        print(
            f"sensors {s}-{t}: {len(pairs)} pairs; plain mean {np.round(np.degrees(errs.mean(0)), 4)}"
            f", information-weighted {np.round(np.degrees(weighted), 4)} deg; mean yaw error by"
            f" quarter of H_yy (lowest first) {np.round(quarters, 2)}"
        )


if __name__ == "__main__":
    main()
