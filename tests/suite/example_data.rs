//! The example data of `examples/data/` (every README example runs on them from a fresh clone):
//! all of it generated here, seeded, so the committed files are reproducible byte for byte. The
//! test regenerates them and compares; `ROTAVG_BLESS=1 cargo test --release --test suite
//! example_data::` writes them (after a deliberate change of the generator: review
//! `git diff examples/data`).
//!
//! - `slam.g2o`: a 3-D SLAM pose graph (`VERTEX_SE3:QUAT` and `EDGE_SE3:QUAT`): 400 poses on a
//!   winding trajectory, odometry with rotation information 1e4 (0.01 rad), 40 loop closures
//!   with information 1e2 (0.1 rad); the vertices are the noise-free poses.
//! - `sfm_outliers.txt`: a 1DSfM `EGs.txt` view graph of 150 cameras and 1200 pairs, 2 degrees of
//!   noise, 15 % of the pairs replaced by random rotations (outliers); `sfm_truth.txt` its
//!   ground truth as a rotation list (`id R11 .. R33`, world-to-camera).
//! - `single.json`: 50 rotations around one (0.05 rad), 10 % of them random (outliers).
//! - `handeye/hand.csv`, `handeye/camera.csv`: two time-stamped pose streams (ETH layout:
//!   `t, x, y, z, qx, qy, qz, qw`): a robot hand in its base and a camera observing a fixed target,
//!   related by the hand-eye transform `X` (camera to hand) in `handeye/truth.json`; 0.2 degrees of
//!   noise on the camera rotations.
//! - `anisotropic.json`: 60 cameras, 240 edges with anisotropic noise (standard deviations 0.5,
//!   0.5 and 5 degrees along random axes) and each edge's 3x3 information (the inverse
//!   covariance); `anisotropic_truth.txt` its ground truth as a rotation list.
//! - `strong_axis.json`: 60 cameras, 240 edges with one well-determined axis per edge (standard
//!   deviations 0.5, 5 and 5 degrees along random axes): every `M` is indefinite, the `O(3)`
//!   relaxation prefers reflections and the `conv(SO(3))` dual certificate `[A11]` certifies;
//!   `strong_axis_truth.txt` its ground truth.
//!
//! Conventions: `paper-notes/formats.md` and the readers in `src/io/`.

use nalgebra::{Translation3, UnitQuaternion, Vector3};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rotavg::Rotation;
use rotavg::so3::{exp, gaussian, perturb_gaussian, random_rotation};
use std::fmt::Write as _;
use std::path::Path;

type Pose = nalgebra::Isometry3<f64>;

fn quat(r: &Rotation) -> UnitQuaternion<f64> {
    UnitQuaternion::from_rotation_matrix(r)
}

fn gaussian_vector(rng: &mut StdRng, sigma: f64) -> Vector3<f64> {
    Vector3::new(gaussian(rng), gaussian(rng), gaussian(rng)) * sigma
}

/// One g2o `EDGE_SE3:QUAT` / `VERTEX_SE3:QUAT` pose: `x y z qx qy qz qw`.
fn pose_fields(p: &Pose) -> String {
    let (t, q) = (p.translation.vector, p.rotation);
    format!(
        "{:.9} {:.9} {:.9} {:.12} {:.12} {:.12} {:.12}",
        t.x, t.y, t.z, q.i, q.j, q.k, q.w
    )
}

/// The upper triangle of a 6x6 information `diag(t, t, t, r, r, r)` (g2o's order).
fn information(translation: f64, rotation: f64) -> String {
    let mut s = String::new();
    for row in 0..6 {
        for col in row..6 {
            let v = match (row == col, row < 3) {
                (true, true) => translation,
                (true, false) => rotation,
                _ => 0.0,
            };
            let _ = write!(s, " {v}");
        }
    }
    s
}

/// `slam.g2o`: world-from-body poses `T_i`, edges `T_i^-1 T_j` with noise.
fn slam(rng: &mut StdRng) -> String {
    let n = 400;
    let mut poses: Vec<Pose> = vec![Pose::identity()];
    for i in 1..n {
        let turn = Vector3::new(
            0.02 * gaussian(rng),
            0.02 * gaussian(rng),
            0.15 * (i as f64 * 0.05).sin(),
        );
        let step = Pose::from_parts(Translation3::new(1.0, 0.0, 0.0), quat(&exp(&turn)));
        poses.push(poses[i - 1] * step);
    }
    let mut s =
        String::from("# rotavg example data (examples/example_data.rs): a 3-D SLAM pose graph\n");
    for (i, p) in poses.iter().enumerate() {
        let _ = writeln!(s, "VERTEX_SE3:QUAT {i} {}", pose_fields(p));
    }
    let edge = |s: &mut String, rng: &mut StdRng, i: usize, j: usize, info_t: f64, info_r: f64| {
        let rel = poses[i].inverse() * poses[j];
        let noise = Pose::from_parts(
            Translation3::from(gaussian_vector(rng, info_t.sqrt().recip())),
            quat(&exp(&gaussian_vector(rng, info_r.sqrt().recip()))),
        );
        let _ = writeln!(
            s,
            "EDGE_SE3:QUAT {i} {j} {}{}",
            pose_fields(&(rel * noise)),
            information(info_t, info_r)
        );
    };
    for i in 1..n {
        edge(&mut s, rng, i - 1, i, 1e4, 1e4);
    }
    for _ in 0..40 {
        let j = rng.random_range(20..n);
        let i = rng.random_range(0..j - 10);
        edge(&mut s, rng, i, j, 1e2, 1e2);
    }
    s
}

/// `sfm_outliers.txt` (1DSfM: `i j R t` with `R = C_i C_j^T`, `C` world-to-camera) and
/// `sfm_truth.txt` (`id R11 .. R33`, `C_id`).
fn sfm(rng: &mut StdRng) -> (String, String) {
    let n = 150;
    let cams: Vec<Rotation> = (0..n).map(|_| random_rotation(rng)).collect();
    let mut graph = String::new();
    let mut pairs = std::collections::BTreeSet::new();
    while pairs.len() < 1200 {
        let (i, j) = (rng.random_range(0..n), rng.random_range(0..n));
        if i < j {
            pairs.insert((i, j));
        }
    }
    for &(i, j) in &pairs {
        let exact = cams[i] * cams[j].inverse();
        let r = if rng.random::<f64>() < 0.15 {
            random_rotation(rng)
        } else {
            perturb_gaussian(&exact, 2f64.to_radians(), rng)
        };
        let m = r.matrix();
        let _ = write!(graph, "{i} {j}");
        for row in 0..3 {
            for col in 0..3 {
                let _ = write!(graph, " {:.12}", m[(row, col)]);
            }
        }
        let t = gaussian_vector(rng, 1.0).normalize();
        let _ = writeln!(graph, " {:.9} {:.9} {:.9}", t.x, t.y, t.z);
    }
    let mut truth =
        String::from("# ground truth of sfm_outliers.txt: id R11 .. R33 (world-to-camera)\n");
    for (i, c) in cams.iter().enumerate() {
        let _ = write!(truth, "{i}");
        for v in c.matrix().transpose().iter() {
            let _ = write!(truth, " {v:.15}");
        }
        truth.push('\n');
    }
    (graph, truth)
}

/// `single.json`: 50 rotations around a centre, 10 % random.
fn single(rng: &mut StdRng) -> String {
    let centre = random_rotation(rng);
    let rows: Vec<String> = (0..50)
        .map(|k| {
            let r = if k % 10 == 9 {
                random_rotation(rng)
            } else {
                perturb_gaussian(&centre, 0.05, rng)
            };
            serde_json::to_string(&rotavg::so3::rotation_to_rows(&r)).expect("rows serialise")
        })
        .collect();
    format!("{{\"rotations\": [\n  {}\n]}}\n", rows.join(",\n  "))
}

/// One ETH pose-stream line: `t, x, y, z, qx, qy, qz, qw`.
fn stream_line(t: f64, p: &Pose) -> String {
    let (v, q) = (p.translation.vector, p.rotation);
    format!(
        "{t:.4}, {:.9}, {:.9}, {:.9}, {:.12}, {:.12}, {:.12}, {:.12}\n",
        v.x, v.y, v.z, q.i, q.j, q.k, q.w
    )
}

/// `handeye/hand.csv` (`H = T_B_H`, hand in base), `handeye/camera.csv` (`E = T_W_E`, camera in
/// target) and `handeye/truth.json` (`X`, camera to hand): `H_j^-1 H_i ... ` as in
/// `src/io/handeye.rs`: `(H_i^-1 H_j) X = X (E_i^-1 E_j)` with the target fixed in the base,
/// `T_B_W`, so `E_i = T_B_W^-1 H_i X`.
fn handeye(rng: &mut StdRng) -> (String, String, String) {
    let x = Pose::from_parts(
        Translation3::new(0.03, -0.02, 0.08),
        quat(&random_rotation(rng)),
    );
    let target_in_base = Pose::from_parts(
        Translation3::new(0.8, 0.1, 0.0),
        quat(&random_rotation(rng)),
    );
    let (mut hand, mut camera) = (String::new(), String::new());
    for k in 0..200 {
        let t = 1.0 + 0.05 * k as f64;
        let h = Pose::from_parts(
            Translation3::from(gaussian_vector(rng, 0.2) + Vector3::new(0.5, 0.0, 0.6)),
            quat(&exp(&gaussian_vector(rng, 0.6))),
        );
        let e = target_in_base.inverse() * h * x;
        let noisy = Pose::from_parts(
            e.translation,
            quat(&exp(&gaussian_vector(rng, 0.2f64.to_radians()))) * e.rotation,
        );
        hand.push_str(&stream_line(t, &h));
        camera.push_str(&stream_line(t, &noisy));
    }
    let truth = format!(
        "{{\"rotation\": {}}}\n",
        serde_json::to_string(&rotavg::so3::rotation_to_rows(
            &x.rotation.to_rotation_matrix()
        ))
        .expect("rows serialise")
    );
    (hand, camera, truth)
}

/// `anisotropic.json` (the contract's JSON with an `information` per edge) and
/// `anisotropic_truth.txt` (`id R11 .. R33`): [`rotavg::multiple::synthetic::SyntheticAnisotropic`]
/// with 60 cameras, 240 edges, standard deviations 0.5, 0.5 and 5 degrees along random axes
/// (`weak_axes = 1`), or 0.5, 5 and 5 degrees (`weak_axes = 2`, `strong_axis.json`).
fn anisotropic(weak_axes: usize, name: &str) -> (String, String) {
    let (p, truth) = rotavg::multiple::synthetic::SyntheticAnisotropic {
        num_rotations: 60,
        num_edges: 240,
        sigma: 0.5f64.to_radians(),
        ratio: 10.0,
        random_axes: true,
        outlier_fraction: 0.0,
        seed: 2026,
        weak_axes,
        ratio_spread: 0.0,
    }
    .generate();
    problem_and_truth(&p, &truth, name)
}

/// A view graph as the contract's JSON and its truth as `id R11 .. R33` lines.
fn problem_and_truth(
    p: &rotavg::multiple::MultipleProblem,
    truth: &[Rotation],
    name: &str,
) -> (String, String) {
    let mut list = format!("# ground truth of {name}: id R11 .. R33 (R_i, with R_ij R_i = R_j)\n");
    for (i, r) in truth.iter().enumerate() {
        let _ = write!(list, "{i}");
        for row in 0..3 {
            for col in 0..3 {
                let _ = write!(list, " {:.15}", r.matrix()[(row, col)]);
            }
        }
        list.push('\n');
    }
    (rotavg::io::json::write_problem_json(p), list)
}

/// `slam_anisotropic.json`: issue 37's strongly anisotropic SLAM class
/// ([`rotavg::multiple::synthetic::SyntheticAnisotropicSlam::strongly_anisotropic`], 200 poses, seed 1:
/// eigenvalue ratios 1.4e3 to 1.7e7, median 1.3e5, every `M` indefinite) and its truth.
fn slam_anisotropic() -> (String, String) {
    let (p, truth) =
        rotavg::multiple::synthetic::SyntheticAnisotropicSlam::strongly_anisotropic(200, 1)
            .generate();
    problem_and_truth(&p, &truth, "slam_anisotropic.json")
}

/// `gravity/`: 200 upright cameras (OpenCV axes: x right, y down the image, z forward; tilted
/// by 5 degrees at most), 1000 random pairs with 2 degrees of noise per axis as a JSON view
/// graph, gravity priors (the world's down direction `e_3` seen by each camera, 0.5 degrees of
/// noise, 10 % of the images without one) as `KEY gx gy gz` lines, the same for every image
/// (`gravity_all.txt`), and the truth.
fn gravity() -> (String, String, String, String) {
    let mut rng = StdRng::seed_from_u64(2027);
    let n = 200;
    let cams: Vec<Rotation> = (0..n)
        .map(|_| {
            // camera-to-world: x horizontal, y down (world e_3), z = x cross y
            let yaw = rng.random_range(0.0..std::f64::consts::TAU);
            let x = Vector3::new(yaw.cos(), yaw.sin(), 0.0);
            let (y, z) = (Vector3::z(), x.cross(&Vector3::z()));
            let upright =
                Rotation::from_matrix_unchecked(nalgebra::Matrix3::from_columns(&[x, y, z]));
            let tilt = gaussian_vector(&mut rng, 2f64.to_radians());
            let tilt = exp(&(tilt * (5f64.to_radians() / tilt.norm()).min(1.0)));
            (upright * tilt).inverse() // world-to-camera R_i
        })
        .collect();
    let mut pairs = std::collections::BTreeSet::new();
    while pairs.len() < 1000 {
        let (i, j) = (rng.random_range(0..n), rng.random_range(0..n));
        if i < j {
            pairs.insert((i, j));
        }
    }
    let edges = pairs
        .iter()
        .map(|&(i, j)| rotavg::multiple::Edge {
            i,
            j,
            rotation: perturb_gaussian(&(cams[j] * cams[i].inverse()), 2f64.to_radians(), &mut rng),
            weight: 1.0,
        })
        .collect();
    let p = rotavg::multiple::MultipleProblem::new(n, edges).expect("a valid graph");
    let mut priors = String::from(
        "# gravity priors of graph.json: image gx gy gz (the world's down direction in the camera frame)\n",
    );
    let mut all = priors.clone();
    let mut truth =
        String::from("# ground truth of graph.json: id R11 .. R33 (R_i, with R_ij R_i = R_j)\n");
    for (i, r) in cams.iter().enumerate() {
        let g = exp(&(gaussian_vector(&mut rng, 0.5f64.to_radians()))) * (r * Vector3::z());
        let line = format!("{i} {:.12} {:.12} {:.12}\n", g.x, g.y, g.z);
        if rng.random::<f64>() >= 0.1 {
            priors.push_str(&line);
        }
        all.push_str(&line);
        let _ = write!(truth, "{i}");
        for row in 0..3 {
            for col in 0..3 {
                let _ = write!(truth, " {:.15}", r.matrix()[(row, col)]);
            }
        }
        truth.push('\n');
    }
    (rotavg::io::json::write_problem_json(&p), priors, all, truth)
}

/// `rig/`: a two-sensor rig of 120 frames (`SyntheticRig`: 480 pairs measured by both sensors,
/// 0.02 rad of noise per axis): the reference sensor's view graph (`right.json`), the other
/// sensor's (`left.json`, `L_ij ~ S R_ij S^T`) and the truth (`truth.json`: the frames and
/// `sensor_from_rig`).
fn rig() -> (String, String, String) {
    use rotavg::multiple::MultipleProblem;
    let graph = rotavg::multiple::synthetic::SyntheticGraph {
        num_rotations: 120,
        num_edges: 480,
        noise_sigma: 0.02,
        outlier_fraction: 0.0,
        seed: 2028,
    };
    let (p, frames, s) = rotavg::pipeline::simultaneous::SyntheticRig { graph }.generate();
    let write = |edges: &[rotavg::multiple::Edge]| {
        let g = MultipleProblem::new(p.num_nodes, edges.to_vec()).expect("a valid graph");
        rotavg::io::json::write_problem_json(&g)
    };
    let rows =
        |r: &Rotation| serde_json::to_string(&rotavg::so3::rotation_to_rows(r)).expect("rows");
    let truth = format!(
        "{{\"rotations\": [\n  {}\n], \"sensor_from_rig\": {}}}\n",
        frames.iter().map(rows).collect::<Vec<_>>().join(",\n  "),
        rows(&s)
    );
    (write(&p.right), write(&p.left), truth)
}

/// `rig_sensors/`: a rig of 40 frames and 3 sensors (`RigScene`, seed 2026: every sensor
/// photographs every frame, 0.01 rad of noise, 30 % of frames with an edge between two
/// sensors), sensor 0 the reference (the identity) and sensor 2 known, sensor 1 estimated, in
/// the JSON rig format (`rig.json`), and the truth (`truth.json`: frames and sensors).
fn rig_sensors() -> (String, String) {
    use rotavg::rig::{RigProblem, RigScene, Sensor};
    let scene = RigScene {
        frames: 40,
        sensors: 3,
        noise_sigma: 0.01,
        seed: 2026,
        ..Default::default()
    };
    let (p, truth) = scene.generate();
    let mut sensors = p.sensors().to_vec();
    sensors[0] = Sensor {
        sensor_from_rig: Some(Rotation::identity()),
    };
    sensors[2] = Sensor {
        sensor_from_rig: Some(truth.sensors[2]),
    };
    let p = RigProblem::new(
        p.num_frames(),
        sensors,
        p.images().to_vec(),
        p.edges().to_vec(),
    )
    .expect("a valid rig");
    let truth = rotavg::io::rig::write_rig_truth_json(&truth.frames, &truth.sensors);
    (rotavg::io::rig::write_rig_json(&p), truth)
}

/// `rig_gravity/`: a rig of 30 frames and 3 known sensors (`RigScene`, seed 2, 0.05 rad of
/// noise) in the JSON rig format (`rig.json`), gravity priors of 0.5 degrees on three images in
/// four (`gravity.txt`: `IMAGE gx gy gz`, the image's index) and the truth (`truth.json`).
fn rig_gravity() -> (String, String, String) {
    use rotavg::rig::RigScene;
    let scene = RigScene::sized(30, 3, 0.05, true, 2);
    let (p, truth) = scene.generate();
    let priors = truth.gravity(&p, 0.5f64.to_radians(), 4, 2);
    let truth = rotavg::io::rig::write_rig_truth_json(&truth.frames, &truth.sensors);
    (
        rotavg::io::rig::write_rig_json(&p),
        rotavg::io::gravity::write_gravity_text(&priors),
        truth,
    )
}

/// `rig_information/`: a rig of 40 frames and 3 sensors with information matrices
/// (`RigScene::anisotropy` 9, seed 24: each edge's noise 0.01 rad along two axes of a random
/// frame and about 9 times that along the third, its information the inverse covariance; `[H24]`),
/// sensor 0 the reference, sensors 1 and 2 estimated, in the JSON rig format with each edge's
/// `"information"`, and the truth.
fn rig_information() -> (String, String) {
    use rotavg::rig::RigScene;
    let scene = RigScene {
        anisotropy: 9.0,
        ..RigScene::sized(40, 3, 0.01, false, 24)
    };
    let (p, truth) = scene.generate();
    let truth = rotavg::io::rig::write_rig_truth_json(&truth.frames, &truth.sensors);
    (rotavg::io::rig::write_rig_json(&p), truth)
}

/// Every file of the example data, `(relative path, contents)`, from one seed.
fn files() -> Vec<(&'static str, String)> {
    let mut rng = StdRng::seed_from_u64(2026);
    let (graph, truth) = sfm(&mut rng);
    let (hand, camera, x) = handeye(&mut rng);
    let (gravity_graph, gravity_priors, gravity_all, gravity_truth) = gravity();
    let (rig_right, rig_left, rig_truth) = rig();
    let (rig_sensors, rig_sensors_truth) = rig_sensors();
    let (rig_gravity, rig_gravity_priors, rig_gravity_truth) = rig_gravity();
    let (rig_information, rig_information_truth) = rig_information();
    vec![
        ("rig_information/rig.json", rig_information),
        ("rig_information/truth.json", rig_information_truth),
        ("rig_gravity/rig.json", rig_gravity),
        ("rig_gravity/gravity.txt", rig_gravity_priors),
        ("rig_gravity/truth.json", rig_gravity_truth),
        ("rig_sensors/rig.json", rig_sensors),
        ("rig_sensors/truth.json", rig_sensors_truth),
        ("rig/right.json", rig_right),
        ("rig/left.json", rig_left),
        ("rig/truth.json", rig_truth),
        ("gravity/graph.json", gravity_graph),
        ("gravity/gravity.txt", gravity_priors),
        ("gravity/gravity_all.txt", gravity_all),
        ("gravity/truth.txt", gravity_truth),
        ("slam.g2o", slam(&mut rng)),
        ("sfm_outliers.txt", graph),
        ("sfm_truth.txt", truth),
        ("single.json", single(&mut rng)),
        ("handeye/hand.csv", hand),
        ("handeye/camera.csv", camera),
        ("handeye/truth.json", x),
        ("anisotropic.json", anisotropic(1, "anisotropic.json").0),
        (
            "anisotropic_truth.txt",
            anisotropic(1, "anisotropic.json").1,
        ),
        ("strong_axis.json", anisotropic(2, "strong_axis.json").0),
        (
            "strong_axis_truth.txt",
            anisotropic(2, "strong_axis.json").1,
        ),
        ("slam_anisotropic.json", slam_anisotropic().0),
        ("slam_anisotropic_truth.txt", slam_anisotropic().1),
    ]
}

/// The committed example data are what this generator writes; with `ROTAVG_BLESS=1` it writes
/// them. Then every file is read back by the command line's readers (a solve and a certificate
/// each), so the README's examples have data that work.
#[test]
fn example_data_is_reproducible_and_reads() {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data");
    let bless = std::env::var_os("ROTAVG_BLESS").is_some();
    for (name, text) in files() {
        let path = folder.join(name);
        if bless {
            std::fs::create_dir_all(path.parent().expect("a folder")).expect("create the folder");
            std::fs::write(&path, &text).expect("write the example data");
        }
        let stored = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{}: {e} (ROTAVG_BLESS=1 writes it)", path.display()));
        assert!(
            stored == text,
            "{} differs from its generator (ROTAVG_BLESS=1 rewrites it)",
            path.display()
        );
    }
    let options = rotavg::io::detect::ReadOptions::default();
    for name in [
        "slam.g2o",
        "sfm_outliers.txt",
        "anisotropic.json",
        "strong_axis.json",
    ] {
        let g = rotavg::io::input::load_problem(
            folder.join(name).to_str().expect("utf-8"),
            Default::default(),
            &options,
        )
        .expect("the example graph reads");
        let rotavg::io::input::LoadedProblem::Multiple(g) = g else {
            panic!("{name} is a multiple problem")
        };
        let out =
            rotavg::pipeline::average_multiple(&g.problem, &Default::default()).expect("solve");
        assert!(
            out.certificate.expect("a certificate").is_certified(),
            "{name}"
        );
    }
}

/// The settings of `colmap_scene/` (`rotavg::io::colmap::scene`): 36 images of one site, 200
/// points per facade, 8 pairs per image, 5 % twisted pairs, 5 % repeated-structure pairs, 10 %
/// pans (near-pure pairs); the example `colmap_scene` writes the same with `--cameras 36 --seed
/// 2029 --points-per-facade 200 --max-pairs 8 --twisted 0.05 --repeated 0.05 --near-pure 0.1`.
#[cfg(feature = "colmap")]
fn colmap_scene_settings() -> rotavg::io::colmap::scene::SfmScene {
    rotavg::io::colmap::scene::SfmScene {
        cameras: 36,
        seed: 2029,
        points_per_facade: 200,
        max_pairs_per_image: 8,
        twisted: 0.05,
        repeated: 0.05,
        near_pure: 0.1,
        ..Default::default()
    }
}

/// `colmap_scene/` (`database.db`, `truth/`, `pairs.json`) is what the generator writes (the
/// text files byte for byte, the database row for row: SQLite's file header holds its library
/// version); with `ROTAVG_BLESS=1` it writes them. The database reads with `--information full`,
/// one edge per pair.
#[cfg(feature = "colmap")]
#[test]
fn colmap_scene_is_reproducible_and_reads() {
    let folder = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/colmap_scene");
    let scene = colmap_scene_settings().generate().expect("valid settings");
    if std::env::var_os("ROTAVG_BLESS").is_some() {
        scene.write(&folder).expect("write the example data");
    }
    let fresh =
        crate::common::scratch_root().join(format!("rotavg-example-scene-{}", std::process::id()));
    scene.write(&fresh).expect("write the scene");
    for name in [
        "pairs.json",
        "truth/cameras.txt",
        "truth/images.txt",
        "truth/points3D.txt",
    ] {
        let stored = std::fs::read(folder.join(name))
            .unwrap_or_else(|e| panic!("{name}: {e} (ROTAVG_BLESS=1 writes it)"));
        assert!(
            stored == std::fs::read(fresh.join(name)).expect("written"),
            "colmap_scene/{name} differs from its generator (ROTAVG_BLESS=1 rewrites it)"
        );
    }
    assert!(
        crate::common::database_rows(&folder.join("database.db"))
            == crate::common::database_rows(&fresh.join("database.db")),
        "colmap_scene/database.db differs from its generator (ROTAVG_BLESS=1 rewrites it)"
    );
    std::fs::remove_dir_all(&fresh).expect("remove the scratch folder");
    let options = rotavg::io::detect::ReadOptions {
        full_information: Some(true),
        ..Default::default()
    };
    let graph =
        rotavg::io::colmap::read_colmap_database(&folder.join("database.db"), &options).unwrap();
    assert_eq!(
        graph.problem.information().unwrap().len(),
        scene.pairs.len()
    );
}
