"""Hand-eye calibration from absolute poses (hand_eye, hand_eye_pairs) against an independent
numpy construction of OpenCV's setting, and hand-eye files (read_handeye) against the
`rotavg conjugate` command line."""

import json

import numpy as np
import pytest

import rotavg
from conftest import random_rotations, small_rotations, untimed

Rotation = pytest.importorskip("scipy.spatial.transform").Rotation


def transforms(rotations, translations):
    """(N, 4, 4) homogeneous transforms [R t; 0 1]."""
    t = np.zeros((len(rotations), 4, 4))
    t[:, :3, :3] = rotations
    t[:, :3, 3] = translations
    t[:, 3, 3] = 1.0
    return t


def eye_in_hand(rng, n, sigma=0.0):
    """OpenCV's eye-in-hand setting, built from its definitions alone: the gripper's poses in
    the robot base (gripper2base, base-from-gripper) G_k, a planted camera-to-gripper transform
    X (gripper-from-camera) and a target fixed in the base, base_from_target = T. The chain
    base <- gripper <- camera <- target gives T = G_k X C_k, so the camera's view of the target
    (target2cam, camera-from-target) is C_k = X^-1 G_k^-1 T. `sigma` (rad) perturbs C_k's
    rotation."""
    g = transforms(random_rotations(rng, n), rng.normal(scale=0.5, size=(n, 3)))
    x = transforms(random_rotations(rng, 1), rng.normal(scale=0.1, size=(1, 3)))[0]
    t = transforms(random_rotations(rng, 1), rng.normal(scale=1.0, size=(1, 3)))[0]
    c = np.linalg.inv(x) @ np.linalg.inv(g) @ t
    if sigma > 0:
        c[:, :3, :3] = small_rotations(rng, n, sigma) @ c[:, :3, :3]
    return g, c, x


def angle(a, b):
    """Rotation angle of a^T b, accurate near 0."""
    return float(2 * np.arcsin(min(np.linalg.norm(a - b) / np.sqrt(8), 1.0)))


def test_planted_rotation_is_recovered_and_certified(rng):
    g, c, x = eye_in_hand(rng, 12)
    res = rotavg.hand_eye(g, c)
    assert res.problem == "conjugate" and res.estimate.shape == (3, 3)
    assert np.abs(res.estimate - x[:3, :3]).max() < 1e-9
    assert res.certificate.certified
    assert res.num_measurements == 12 * 11 // 2  # every pair i < j, as OpenCV
    motion = res.to_dict()["motion"]
    assert (motion["poses"], motion["pairs"], motion["skipped_small"]) == (12, 66, 0)


def test_pairs_are_opencvs_relative_motions(rng):
    g, c, x = eye_in_hand(rng, 6)
    data = rotavg.hand_eye_pairs(g, c)
    assert data.format == "poses" and data.num_pairs == len(data) == 15
    # OpenCV (calibrateHandEye): for i < j, Hgij = Hg[j]^-1 Hg[i], Hcij = Hc[j] Hc[i]^-1
    ij = [(i, j) for i in range(6) for j in range(i + 1, 6)]
    left = np.array([(np.linalg.inv(g[j]) @ g[i])[:3, :3] for i, j in ij])
    right = np.array([(c[j] @ np.linalg.inv(c[i]))[:3, :3] for i, j in ij])
    assert np.allclose(data.left, left, atol=1e-12)
    assert np.allclose(data.right, right, atol=1e-12)
    # the convention: right ~ S^-1 left S with S = R_cam2gripper, i.e. A X = X B
    s = x[:3, :3]
    assert np.allclose(s.T @ data.left @ s, data.right, atol=1e-12)
    consecutive = rotavg.hand_eye_pairs(g, c, pairs="consecutive")
    assert consecutive.num_pairs == 5
    assert np.allclose(consecutive.left[2], (np.linalg.inv(g[3]) @ g[2])[:3, :3], atol=1e-12)
    assert consecutive.motion["settings"]["stride"] == 1
    with pytest.raises(ValueError):
        data.left[0, 0, 0] = 2.0  # read-only


def test_input_forms_give_the_same_rotation(rng):
    g, c, x = eye_in_hand(rng, 8)
    reference = rotavg.hand_eye(g, c).estimate
    variants = [
        (g[:, :3, :3], c[:, :3, :3], "target2cam"),  # rotations only
        (g, np.linalg.inv(c), "cam2target"),  # the camera's pose in the target frame
        (Rotation.from_matrix(g[:, :3, :3]), Rotation.from_matrix(c[:, :3, :3]), "target2cam"),
        (g.tolist(), c.tolist(), "target2cam"),
    ]
    for robot, camera, convention in variants:
        est = rotavg.hand_eye(robot, camera, camera=convention).estimate
        assert np.abs(est - reference).max() < 1e-9


def test_eye_to_hand_with_inverse_robot_poses(rng):
    # The camera is fixed in the base (base-from-camera Xb), the target rides on the gripper
    # (gripper-from-target Y): C_k = Xb^-1 G_k Y. As OpenCV documents, passing base2gripper
    # poses G_k^-1 gives the camera-to-base rotation.
    g, _, _ = eye_in_hand(rng, 10)
    xb = transforms(random_rotations(rng, 1), [[1.0, 0.5, 2.0]])[0]
    y = transforms(random_rotations(rng, 1), [[0.0, 0.0, 0.1]])[0]
    c = np.linalg.inv(xb) @ g @ y
    res = rotavg.hand_eye(np.linalg.inv(g), c)
    assert np.abs(res.estimate - xb[:3, :3]).max() < 1e-9 and res.certificate.certified


def test_noisy_poses_and_certifying_opencvs_answer(rng):
    g, c, x = eye_in_hand(rng, 15, sigma=0.01)
    data = rotavg.hand_eye_pairs(g, c)
    res = rotavg.average_conjugate(data)
    assert res.certificate.certified and angle(res.estimate, x[:3, :3]) < 0.02
    same = rotavg.hand_eye(g, c)
    assert np.array_equal(same.estimate, res.estimate)
    # another solver's estimate (here: the planted one) is certified or bounded, never changed
    theirs = rotavg.certify_conjugate(data, estimate=x[:3, :3])
    assert theirs.solver is None and np.array_equal(theirs.estimate, x[:3, :3])
    assert theirs.certificate.lower_bound <= res.chordal_cost * (1 + 1e-9)
    assert theirs.cost >= res.chordal_cost * (1 - 1e-9)
    ours = rotavg.certify_conjugate(data, estimate=res.estimate)
    assert ours.certificate.certified
    # the arrays give the same problem
    arrays = rotavg.average_conjugate(data.left, data.right, data.weights)
    assert arrays.chordal_cost == pytest.approx(res.chordal_cost, rel=1e-12)


def test_min_angle_skips_small_motions(rng):
    g, c, x = eye_in_hand(rng, 5)
    # station 1 repeats station 0's rotations (a pure translation)
    g[1, :3, :3], c[1, :3, :3] = g[0, :3, :3], c[0, :3, :3]
    data = rotavg.hand_eye_pairs(g, c)
    assert (data.num_pairs, data.motion["skipped_small"]) == (9, 1)
    assert rotavg.hand_eye_pairs(g, c, min_angle=0).num_pairs == 10


def test_bad_poses_say_what_is_wrong(rng):
    g, c, _ = eye_in_hand(rng, 4)
    bad = g.copy()
    bad[2, 3, 0] = 0.5
    with pytest.raises(rotavg.Error, match=r"robot_poses\[2\] is not a homogeneous transform"):
        rotavg.hand_eye(bad, c)
    with pytest.raises(rotavg.Error, match="one pose per station: got 4 and 3"):
        rotavg.hand_eye(g, c[:3])
    with pytest.raises(rotavg.Error, match=r"shape \(N, 4, 4\).*got \(4, 3, 4\)"):
        rotavg.hand_eye(g[:, :3, :], c)
    with pytest.raises(rotavg.Error, match="target2cam"):
        rotavg.hand_eye(g, c, camera="world")
    with pytest.raises(rotavg.Error, match="consecutive"):
        rotavg.hand_eye_pairs(g, c, pairs="some")
    scaled = c.copy()
    scaled[1, :3, :3] *= 1.1
    with pytest.raises(rotavg.Error, match=r"camera_poses\[1\] is not a rotation"):
        rotavg.hand_eye(g, scaled)
    # rotations about one axis do not determine S
    z = Rotation.from_rotvec(np.outer([0.3, 0.8, 1.5, 2.0], [0, 0, 1])).as_matrix()
    with pytest.raises(rotavg.DegenerateError, match="degenerate"):
        rotavg.hand_eye(z, z)
    with pytest.raises(rotavg.DegenerateError, match="no pair"):
        rotavg.hand_eye(np.stack([np.eye(3)] * 3), np.stack([np.eye(3)] * 3))


def write_tabb(directory, rng, n):
    """A Tabb dataset (robot_cali.txt: B_i, robot base -> hand; cali.txt: A_i, pattern ->
    camera) with A_i = Z B_i W for a planted hand -> camera Z and base-from-pattern W."""
    b = transforms(random_rotations(rng, n), rng.normal(scale=300, size=(n, 3)))
    z = transforms(random_rotations(rng, 1), [[10.0, 20.0, 30.0]])[0]
    w = transforms(random_rotations(rng, 1), [[500.0, 0.0, 0.0]])[0]
    a = z @ b @ w
    robot = f"{n}\n" + "".join(
        "\n".join(" ".join(repr(float(v)) for v in row) for row in m) + "\n\n" for m in b
    )
    camera = f"{n}\n" + "".join(
        f"img{k}.png 800 0 320 0 800 240 0 0 1 "
        + " ".join(repr(float(v)) for v in m[:3, :3].ravel())
        + " "
        + " ".join(repr(float(v)) for v in m[:3, 3])
        + " 0 0 0 0 0\n"
        for k, m in enumerate(a)
    )
    directory.mkdir(exist_ok=True)
    (directory / "robot_cali.txt").write_text(robot)
    (directory / "cali.txt").write_text(camera)
    return z[:3, :3]


def test_tabb_directory_as_the_command_line(rng, cli, tmp_path):
    z = write_tabb(tmp_path / "tabb", rng, 7)
    data = rotavg.read_handeye(tmp_path / "tabb")
    assert data.format == "tabb" and data.num_pairs == 21 and data.motion["poses"] == 7
    res = rotavg.average_conjugate(data)
    assert np.abs(res.estimate - z).max() < 1e-9 and res.certificate.certified
    assert untimed(res.to_dict()) == untimed(cli("conjugate", tmp_path / "tabb"))
    assert str(res).startswith("Tabb: 7 stations, 21 pairs")


def write_streams(directory, rng, n, stride):
    """Pose streams at 30 Hz: hand poses H_k (hand in base) turning smoothly, camera poses
    E_k = W H_k X (camera in the target frame) for a planted camera -> hand X."""
    t = np.arange(n) / 30.0
    h = Rotation.from_rotvec(np.stack([np.sin(2 * t), 0.7 * t, 0.5 * np.cos(3 * t)], -1))
    x = Rotation.from_matrix(random_rotations(rng, 1)[0])
    w = Rotation.from_matrix(random_rotations(rng, 1)[0])
    e = w * h * x

    def lines(times, rotations, sep):
        q = rotations.as_quat()  # x, y, z, w: scalar last
        return "".join(
            sep.join([repr(float(tk)), "0", "0", "0"] + [repr(float(v)) for v in qk]) + "\n"
            for tk, qk in zip(times, q)
        )

    directory.mkdir(exist_ok=True)
    (directory / "arm_hand.csv").write_text("# t,x,y,z,qx,qy,qz,qw\n" + lines(t, h, ","))
    (directory / "target_camera.txt").write_text(lines(t, e, " "))
    return x.as_matrix()


def test_pose_streams_as_the_command_line(rng, cli, tmp_path):
    x = write_streams(tmp_path / "streams", rng, 90, 5)
    data = rotavg.read_handeye(tmp_path / "streams", stride=5, subsample=2)
    assert data.format == "eth" and data.motion["settings"]["stride"] == 5
    res = rotavg.average_conjugate(data)
    assert angle(res.estimate, x) < 1e-7 and res.certificate.certified
    theirs = cli("conjugate", tmp_path / "streams", "--stride", 5, "--subsample", 2)
    assert untimed(res.to_dict()) == untimed(theirs)
    # both files named, no directory
    named = rotavg.read_handeye(
        hand=tmp_path / "streams" / "arm_hand.csv",
        camera=tmp_path / "streams" / "target_camera.txt",
        stride=5,
        subsample=2,
    )
    assert np.array_equal(named.left, data.left) and np.array_equal(named.right, data.right)


def test_conjugate_json_and_unit_weights(rng, tmp_path):
    s = random_rotations(rng, 1)[0]
    right = random_rotations(rng, 6)
    left = s @ right @ s.T
    path = tmp_path / "pairs.json"
    path.write_text(json.dumps({"pairs": [
        {"left": l.tolist(), "right": r.tolist(), "weight": 2.0} for l, r in zip(left, right)
    ]}))
    data = rotavg.read_handeye(path)
    assert data.format == "json" and data.motion is None and np.all(data.weights == 2.0)
    assert np.all(rotavg.read_handeye(path, weights="unit").weights == 1.0)
    res = rotavg.average_conjugate(data)
    assert np.abs(res.estimate - s).max() < 1e-9


SHARED_HANDEYE = [
    ("handeye/tabb_rwhe_dataset1", []),
    ("handeye/ethz_robot_arm_real", []),
]


@pytest.mark.parametrize("name,flags", SHARED_HANDEYE)
def test_shared_handeye_data_as_the_command_line(name, flags, data_dir, cli):
    path = data_dir / name
    if not path.is_dir():
        pytest.skip(f"{path} absent")
    data = rotavg.read_handeye(path)
    res = rotavg.average_conjugate(data)
    assert untimed(res.to_dict()) == untimed(cli("conjugate", path, *flags))
