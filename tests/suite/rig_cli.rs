//! `rotavg rig RIGHT LEFT` (issue 36 item 1): the committed two-sensor rig
//! (`examples/data/rig/`) calibrated and certified, checked against its planted truth; the
//! written estimate; the errors of graphs that do not pair.

use crate::common::{assert_success, json_of, run, temp_dir, temp_file};
use rotavg::Rotation;
use rotavg::so3::{angle_between, rotation_from_rows};
use std::path::Path;

fn example(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/data/rig")
        .join(name)
        .display()
        .to_string()
}

fn rotation(v: &serde_json::Value) -> Rotation {
    let rows: [[f64; 3]; 3] = serde_json::from_value(v.clone()).unwrap();
    rotation_from_rows(&rows, 1e-9, "test").unwrap()
}

/// The example rig: `sensor_from_rig` within 0.2 degrees of the planted one, the frames within
/// 2 degrees (after the gauge `R_0`), certified; the JSON names the problem `rig`, and
/// `--output` writes the frames, their ids and `S`.
#[test]
fn the_example_rig_is_calibrated_and_certified() {
    let out_path = temp_dir().join("rig.json");
    let out = run(&[
        "rig",
        &example("right.json"),
        &example("left.json"),
        "--json",
        "--output",
        out_path.to_str().unwrap(),
    ]);
    assert_success(&out);
    let v = json_of(&out);
    assert_eq!(v["problem"], "rig");
    assert_eq!(v["num_measurements"], 960);
    assert_eq!(
        v["certificate"]["verdict"], "certified",
        "{}",
        v["certificate"]
    );
    // the verdict names the problem as multiple's does: both graphs' 480 + 480 edges
    assert_eq!(v["verdict"]["verdict"], "certified");
    assert_eq!(v["verdict"]["estimate"], "returned");
    assert_eq!(v["verdict"]["problem"]["kind"], "chordal_l2_rig");
    assert_eq!(v["verdict"]["problem"]["num_edges"], 960);
    assert_eq!(v["verdict"]["problem"]["num_nodes"], 120);
    let text = run(&["rig", &example("right.json"), &example("left.json")]);
    let printed = String::from_utf8_lossy(&text.stdout)
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    assert!(
        printed
            .contains("verdict: certified for the rig's joint chordal L2 problem on all 960 edges"),
        "{printed}"
    );
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(example("truth.json")).unwrap()).unwrap();
    let s = rotation(&v["sensor_from_rig"]);
    let s_true = rotation(&truth["sensor_from_rig"]);
    assert!(angle_between(&s, &s_true).to_degrees() < 0.2);
    let frames: Vec<Rotation> = v["estimate"]
        .as_array()
        .unwrap()
        .iter()
        .map(rotation)
        .collect();
    let planted: Vec<Rotation> = truth["rotations"]
        .as_array()
        .unwrap()
        .iter()
        .map(rotation)
        .collect();
    // both in the gauge R_0 = I
    let worst = frames
        .iter()
        .zip(&planted)
        .map(|(a, b)| angle_between(a, b).to_degrees())
        .fold(0.0, f64::max);
    assert!(worst < 2.0, "{worst} degrees");
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out_path).unwrap()).unwrap();
    assert_eq!(written["rotations"].as_array().unwrap().len(), 120);
    assert_eq!(written["node_ids"][119], 119);
    assert!(angle_between(&rotation(&written["sensor_from_rig"]), &s) < 1e-12);
}

/// Graphs over different frames, and anisotropic information, are errors that say so.
#[test]
fn graphs_that_do_not_pair_are_errors() {
    let text = std::fs::read_to_string(example("left.json")).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["num_rotations"] = serde_json::json!(121);
    let edges = v["edges"].as_array_mut().unwrap();
    let mut extra = edges[0].clone();
    extra["j"] = serde_json::json!(120);
    edges.push(extra);
    let more = temp_file("left_more.json", &v.to_string());
    let out = run(&["rig", &example("right.json"), more.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("same frames") && err.contains("1 only in the second"),
        "{err}"
    );
}

/// `rotavg certify RIGHT --left LEFT --estimate FILE`: the written rig estimate is certified
/// unchanged (the same cost), the planted truth (not a minimum under noise) is not, and its bound
/// stays below the rig's own cost; an estimate without `sensor_from_rig` is an error.
#[test]
fn certify_reads_a_rig_estimate() {
    let est = temp_dir().join("rig_for_certify.json");
    let est = est.to_str().unwrap();
    let (right, left) = (example("right.json"), example("left.json"));
    let solved = run(&["rig", &right, &left, "--output", est, "--json"]);
    assert_success(&solved);
    let cost = json_of(&solved)["cost"].as_f64().unwrap();
    let run_certify = |estimate: &str| {
        let args = [
            "certify",
            &right,
            "--left",
            &left,
            "--estimate",
            estimate,
            "--json",
        ];
        run(&args)
    };
    let certify = |estimate: &str| {
        let out = run_certify(estimate);
        assert_success(&out);
        json_of(&out)
    };
    let v = certify(est);
    assert_eq!(v["certificate"]["verdict"], "certified");
    assert!((v["cost"].as_f64().unwrap() - cost).abs() <= 1e-12 * cost);
    let v = certify(&example("truth.json"));
    assert_eq!(v["certificate"]["verdict"], "gap_reported");
    assert!(v["certificate"]["lower_bound"].as_f64().unwrap() <= cost * (1.0 + 1e-9));
    let plain = temp_file(
        "no_s.json",
        &std::fs::read_to_string(est)
            .unwrap()
            .replace("sensor_from_rig", "other"),
    );
    let out = run_certify(plain.to_str().unwrap());
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("sensor_from_rig"));
}

/// `rotavg rig RIGHT LEFT --sensor-from-rig FILE` (`[H18]`): with the planted `S` held, only
/// the frames are estimated; they are the chordal minimiser of the frames' view graph built
/// here by hand (right edges and `S^T L_ij S`, solved by `multiple`), the verdict names that
/// problem, and the joint cost is at least the jointly calibrated rig's (which also minimises
/// over `S`). Held at the joint estimate's own `S`, the cost is the joint one. A file whose
/// `sensor_from_rig` is not a rotation is an error naming it.
#[test]
fn a_held_sensor_from_rig_averages_the_frames_on_one_graph() {
    let (right, left) = (example("right.json"), example("left.json"));
    let truth = example("truth.json");
    let held = run(&["rig", &right, &left, "--sensor-from-rig", &truth, "--json"]);
    assert_success(&held);
    let v = json_of(&held);
    assert_eq!(v["sensor_from_rig_held"], true);
    assert_eq!(v["num_rotations"], 120);
    assert_eq!(v["verdict"]["verdict"], "certified", "{}", v["certificate"]);
    assert_eq!(
        v["verdict"]["problem"]["kind"],
        "chordal_l2_rig_sensor_held"
    );
    let truth_v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&truth).unwrap()).unwrap();
    let s_true = rotation(&truth_v["sensor_from_rig"]);
    assert!(angle_between(&rotation(&v["sensor_from_rig"]), &s_true) < 1e-12);
    // the frames' graph by hand, as a `multiple` input
    let graph = |path: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
    };
    let (mut frames, l) = (graph(&right), graph(&left));
    for e in l["edges"].as_array().unwrap() {
        let mut turned = e.clone();
        let r = rotation(&e["rotation"]);
        let m = (s_true.inverse() * r * s_true).into_inner();
        turned["rotation"] = serde_json::json!(
            (0..3)
                .map(|a| (0..3).map(|b| m[(a, b)]).collect::<Vec<_>>())
                .collect::<Vec<_>>()
        );
        frames["edges"].as_array_mut().unwrap().push(turned);
    }
    let frames_file = temp_file("rig_frames.json", &frames.to_string());
    let m = run(&["multiple", frames_file.to_str().unwrap(), "--json"]);
    assert_success(&m);
    let m = json_of(&m);
    let cost = v["cost"].as_f64().unwrap();
    assert!((m["cost"].as_f64().unwrap() - cost).abs() <= 1e-9 * cost);
    let worst = v["estimate"]
        .as_array()
        .unwrap()
        .iter()
        .zip(m["estimate"].as_array().unwrap())
        .map(|(a, b)| angle_between(&rotation(a), &rotation(b)))
        .fold(0.0, f64::max);
    assert!(worst < 1e-7, "{worst} rad from multiple's estimate");
    // the joint calibration minimises over S too; held at its S, the same cost
    let joint_out = temp_dir().join("rig_joint.json");
    let joint_out = joint_out.to_str().unwrap();
    let joint = json_of(&run(&[
        "rig", &right, &left, "--json", "--output", joint_out,
    ]));
    let joint_cost = joint["cost"].as_f64().unwrap();
    assert!(joint_cost <= cost * (1.0 + 1e-9), "{joint_cost} vs {cost}");
    let again = json_of(&run(&[
        "rig",
        &right,
        &left,
        "--sensor-from-rig",
        joint_out,
        "--json",
    ]));
    assert!((again["cost"].as_f64().unwrap() - joint_cost).abs() <= 1e-7 * joint_cost);
    let bad = temp_file(
        "bad_s.json",
        r#"{"sensor_from_rig": [[1, 0, 0], [0, 1, 0], [0, 0, 2]]}"#,
    );
    let out = run(&[
        "rig",
        &right,
        &left,
        "--sensor-from-rig",
        bad.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad_s.json") && err.contains("not a rotation"),
        "{err}"
    );
}

/// `rotavg rig FILE` on the committed 3-sensor rig (`examples/data/rig_sensors`, sensors 0 and
/// 2 known, sensor 1 estimated): the estimated `sensor_from_rig` within 0.3 degrees of the
/// planted one, the known ones unchanged, the frames' median error under 1 degree; the verdict
/// names the rig's images problem; `--output` writes frames and sensors with their ids.
#[test]
fn a_rig_file_of_three_sensors_is_calibrated() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/rig_sensors");
    let out_path = temp_dir().join("rig_sensors_estimate.json");
    let out = run(&[
        "rig",
        dir.join("rig.json").to_str().unwrap(),
        "--json",
        "--output",
        out_path.to_str().unwrap(),
    ]);
    assert_success(&out);
    let v = json_of(&out);
    assert_eq!(v["problem"], "rig");
    assert_eq!(v["num_images"], 120);
    assert_eq!(v["num_rotations"], 41); // 40 frames and one estimated sensor
    assert_eq!(v["sensors_held"], serde_json::json!([true, false, true]));
    assert_eq!(v["verdict"]["problem"]["kind"], "chordal_l2_rig_images");
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    for s in 0..3 {
        let (est, planted) = (
            rotation(&v["sensors_from_rig"][s]),
            rotation(&truth["sensors_from_rig"][s]),
        );
        assert!(
            angle_between(&est, &planted).to_degrees() < 0.3,
            "sensor {s}"
        );
    }
    let mut errs: Vec<f64> = (0..40)
        .map(|f| {
            angle_between(&rotation(&v["estimate"][f]), &rotation(&truth["frames"][f])).to_degrees()
        })
        .collect();
    errs.sort_by(f64::total_cmp);
    assert!(errs[20] < 1.0, "median frame error {}", errs[20]);
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out_path).unwrap()).unwrap();
    assert_eq!(written["frames"], v["estimate"]);
    assert_eq!(written["sensors_from_rig"], v["sensors_from_rig"]);
    assert_eq!(written["sensor_ids"], serde_json::json!([0, 1, 2]));
}

/// A planted COLMAP rig (`[F17]`): 12 frames, camera 1 the reference, cameras 2 and 3.
struct ColmapRig {
    frames: Vec<Rotation>,
    sensors: [Rotation; 3],
}

impl ColmapRig {
    fn new() -> Self {
        use rotavg::so3::random_rotation;
        let mut rng = <rotavg::rand::rngs::StdRng as rotavg::rand::SeedableRng>::seed_from_u64(5);
        let frames: Vec<Rotation> = (0..12).map(|_| random_rotation(&mut rng)).collect();
        let sensors = [
            Rotation::identity(),
            random_rotation(&mut rng),
            random_rotation(&mut rng),
        ];
        ColmapRig { frames, sensors }
    }

    fn image(f: usize, c: usize) -> u32 {
        (1 + 3 * f + c) as u32
    }

    fn x(&self, f: usize, c: usize) -> Rotation {
        self.sensors[c] * self.frames[f]
    }

    /// The database at `path` with COLMAP 4's schema: noise-free geometries within each camera
    /// and across cameras; with `with_rigs` the rig tables (camera 2 known by its `Rigid3d`
    /// blob, camera 3 known when `third_known`, else `NULL`; frames with ids from 10; with
    /// `orphan`, image 12 in no frame).
    fn write(&self, path: &std::path::Path, with_rigs: bool, orphan: bool, third_known: bool) {
        use rotavg::io::colmap::image_pair_to_pair_id;
        let image = Self::image;
        let _ = std::fs::remove_file(path);
        let db = rusqlite::Connection::open(path).unwrap();
        db.execute_batch(rotavg::io::colmap::scene::SCHEMA).unwrap();
        for c in 1..=3 {
            db.execute(
                "INSERT INTO cameras VALUES (?1, 0, 640, 480, ?2, 0)",
                rusqlite::params![c, blob(&[500.0, 320.0, 240.0])],
            )
            .unwrap();
        }
        for f in 0..12 {
            for c in 0..3 {
                db.execute(
                    "INSERT INTO images (image_id, name, camera_id) VALUES (?1, ?2, ?3)",
                    rusqlite::params![image(f, c), format!("f{f}c{c}.jpg"), c + 1],
                )
                .unwrap();
            }
        }
        let mut pairs = Vec::new();
        for f in 0..12 {
            for c in 0..3 {
                pairs.push(((f, c), ((f + 1) % 12, c)));
                pairs.push(((f, c), ((f + 5) % 12, c)));
            }
            pairs.push(((f, 0), (f, 1 + f % 2)));
        }
        for ((fa, ca), (fb, cb)) in pairs {
            let (a, b) = if image(fa, ca) < image(fb, cb) {
                ((fa, ca), (fb, cb))
            } else {
                ((fb, cb), (fa, ca))
            };
            let rel = self.x(b.0, b.1) * self.x(a.0, a.1).inverse();
            db.execute(
                "INSERT OR REPLACE INTO two_view_geometries VALUES (?1, 0, 2, NULL, 2, NULL, NULL, NULL, ?2, ?3)",
                rusqlite::params![image_pair_to_pair_id(image(a.0, a.1), image(b.0, b.1)) as i64, blob(&wxyz(&rel)), blob(&[0.0, 0.0, 1.0])],
            ).unwrap();
        }
        if !with_rigs {
            return;
        }
        db.execute_batch(
            "CREATE TABLE rigs (rig_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, ref_sensor_id INTEGER NOT NULL, ref_sensor_type INTEGER NOT NULL);
             CREATE TABLE rig_sensors (rig_id INTEGER NOT NULL, sensor_id INTEGER NOT NULL, sensor_type INTEGER NOT NULL, sensor_from_rig BLOB);
             CREATE TABLE frames (frame_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, rig_id INTEGER NOT NULL);
             CREATE TABLE frame_data (frame_id INTEGER NOT NULL, data_id INTEGER NOT NULL, sensor_id INTEGER NOT NULL, sensor_type INTEGER NOT NULL);
             INSERT INTO rigs VALUES (1, 1, 0);",
        ).unwrap();
        let rigid = |r: &Rotation| {
            let mut v = wxyz(r).to_vec();
            v.extend([0.1, 0.0, 0.0]);
            blob(&v)
        };
        db.execute(
            "INSERT INTO rig_sensors VALUES (1, 2, 0, ?1)",
            [rigid(&self.sensors[1])],
        )
        .unwrap();
        let third = third_known.then(|| rigid(&self.sensors[2]));
        db.execute("INSERT INTO rig_sensors VALUES (1, 3, 0, ?1)", [third])
            .unwrap();
        for f in 0..12 {
            db.execute("INSERT INTO frames VALUES (?1, 1)", [10 + f])
                .unwrap();
            for c in 0..3 {
                if orphan && f == 3 && c == 2 {
                    continue;
                }
                db.execute(
                    "INSERT INTO frame_data VALUES (?1, ?2, ?3, 0)",
                    rusqlite::params![10 + f, image(f, c), c + 1],
                )
                .unwrap();
            }
        }
    }
}

fn blob(v: &[f64]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn wxyz(r: &Rotation) -> [f64; 4] {
    let q = rotavg::so3::to_quaternion(r);
    [q.w, q.i, q.j, q.k]
}

/// COLMAP's rig configuration (`[F17]`, [`ColmapRig`]). The planted rig is recovered and
/// certified; the frames and sensors carry COLMAP's ids. A database without rig tables, and an
/// image in no frame, are errors that say so.
#[test]
fn a_colmap_rig_configuration_is_read_and_certified() {
    let rig = ColmapRig::new();
    let (frames, sensors) = (&rig.frames, &rig.sensors);
    let path = temp_dir().join("rig_colmap.db");
    let write = |with_rigs: bool, orphan: bool| rig.write(&path, with_rigs, orphan, false);
    write(true, false);
    let out = run(&["rig", path.to_str().unwrap(), "--json"]);
    assert_success(&out);
    let v = json_of(&out);
    assert_eq!(v["format"], "colmap");
    assert_eq!(v["sensor_ids"], serde_json::json!([1, 2, 3]));
    assert_eq!(v["frame_ids"][0], 10);
    assert_eq!(v["sensors_held"], serde_json::json!([true, true, false]));
    assert_eq!(v["verdict"]["verdict"], "certified");
    assert!(v["cost"].as_f64().unwrap() < 1e-18);
    for c in 0..3 {
        assert!(
            angle_between(&rotation(&v["sensors_from_rig"][c]), &sensors[c]) < 1e-9,
            "sensor {c}"
        );
    }
    // frames in the gauge F_0 = I
    let g = frames[0].inverse();
    for f in 0..12 {
        assert!(
            angle_between(&rotation(&v["estimate"][f]), &(frames[f] * g)) < 1e-9,
            "frame {f}"
        );
    }
    // `--information full` reads each pair's information from its correspondences (`[H24]`):
    // this database has none
    let out = run(&["rig", path.to_str().unwrap(), "--information", "full"]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !out.status.success() && err.contains("no inlier matches"),
        "{err}"
    );
    write(true, true);
    let out = run(&["rig", path.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !out.status.success() && err.contains("image 12") && err.contains("no frame"),
        "{err}"
    );
    write(false, false);
    let out = run(&["rig", path.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        !out.status.success() && err.contains("no rig configuration"),
        "{err}"
    );
}

/// `rotavg certify FILE --rig --estimate EST` on the committed 3-sensor rig: `rotavg rig`'s own
/// estimate gets the same cost and bound (to 1e-12), its matrices changed only by rounding; the estimate with every frame turned by
/// 0.05 rad gets a higher cost and a bound still below `rotavg rig`'s cost (the optimum is at
/// most that); an estimate 1e-4 off SO(3) needs `--nearest-rotations` (then a warning says
/// so); ids or counts that do not match are errors naming the file.
#[test]
fn certify_reads_a_rig_file_estimate() {
    let rig = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/rig_sensors/rig.json");
    let rig = rig.to_str().unwrap();
    let est = temp_dir().join("rig_sensors_for_certify.json");
    let solved = json_of(&run(&[
        "rig",
        rig,
        "--json",
        "--output",
        est.to_str().unwrap(),
    ]));
    let certify = |file: &Path, extra: &[&str]| {
        let mut args = vec![
            "certify",
            rig,
            "--rig",
            "--estimate",
            file.to_str().unwrap(),
            "--json",
        ];
        args.extend(extra);
        run(&args)
    };
    let v = json_of(&certify(&est, &[]));
    let close = |a: &serde_json::Value, b: &serde_json::Value| {
        (a.as_f64().unwrap() - b.as_f64().unwrap()).abs() <= 1e-12 * b.as_f64().unwrap()
    };
    assert!(close(&v["cost"], &solved["cost"]));
    // the same verdict; the bound within the tolerance of the solve's (the coupled bound is of
    // a point polished from the estimate as written, a change of rounding away [H21])
    assert_eq!(
        v["certificate"]["verdict"],
        solved["certificate"]["verdict"]
    );
    let (lb, solved_lb) = (
        v["certificate"]["lower_bound"].as_f64().unwrap(),
        solved["certificate"]["lower_bound"].as_f64().unwrap(),
    );
    assert!(lb <= v["cost"].as_f64().unwrap() && (lb - solved_lb).abs() <= 1e-6 * solved_lb);
    // the estimate as given, at its nearest rotations (a change of rounding only)
    for f in 0..40 {
        let (a, b) = (
            rotation(&v["estimate"][f]),
            rotation(&solved["estimate"][f]),
        );
        assert!((a.matrix() - b.matrix()).norm() < 1e-15);
    }
    let mut text: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&est).unwrap()).unwrap();
    let turn = rotavg::so3::exp(&nalgebra::Vector3::new(0.05, 0.0, 0.0));
    let frames: Vec<Rotation> = (0..40).map(|f| rotation(&text["frames"][f])).collect();
    text["frames"] = serde_json::json!(
        frames
            .iter()
            .map(|f| rotavg::so3::rotation_to_rows(&(turn * f)))
            .collect::<Vec<_>>()
    );
    let off = temp_file("rig_sensors_off.json", &text.to_string());
    let w = json_of(&certify(&off, &[]));
    let cost = solved["cost"].as_f64().unwrap();
    assert!(w["cost"].as_f64().unwrap() > cost);
    assert!(w["certificate"]["lower_bound"].as_f64().unwrap() <= cost);
    assert_eq!(w["certificate"]["verdict"], "gap_reported");
    // 1e-4 off SO(3): refused without --nearest-rotations, certified at the nearest rotations with
    let mut scaled = text.clone();
    scaled["frames"] = serde_json::json!(
        frames
            .iter()
            .map(|f| {
                let m = f.matrix() * (1.0 + 1e-4);
                [
                    [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
                    [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
                    [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
                ]
            })
            .collect::<Vec<_>>()
    );
    let scaled = temp_file("rig_sensors_scaled.json", &scaled.to_string());
    assert!(!certify(&scaled, &[]).status.success());
    let x = json_of(&certify(&scaled, &["--nearest-rotations"]));
    assert_eq!(x["warnings"][0]["code"], "estimate_projected");
    assert!((x["cost"].as_f64().unwrap() - cost).abs() < 1e-9 * cost);
    for (key, value) in [
        ("sensor_ids", serde_json::json!([0, 1, 5])),
        ("frames", serde_json::json!([])),
    ] {
        let mut bad = text.clone();
        bad[key] = value;
        let bad = temp_file("rig_sensors_bad.json", &bad.to_string());
        let out = certify(&bad, &[]);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(
            !out.status.success() && err.contains("rig_sensors_bad.json"),
            "{key}: {err}"
        );
    }
}

/// A rig file with 15 % outliers (random rotations): the default `--loss auto` finds them in
/// the least-squares residuals (`outliers_suspected`), runs the Cauchy loss and certifies the
/// inlier edges' problem (named in the verdict); its frames and sensors are at least 5 times
/// closer to the planted rig than least squares' (`--loss chordal`, which keeps the warning);
/// every outlier the generator planted at more than 10 degrees is among the edges dropped.
#[test]
fn outliers_in_a_rig_file_turn_the_default_robust() {
    use rotavg::rig::{RigScene, residual_angles};
    let scene = RigScene {
        frames: 80,
        sensors: 3,
        noise_sigma: 0.01,
        outlier_fraction: 0.15,
        seed: 31,
        ..Default::default()
    };
    let (p, truth) = scene.generate();
    let file = temp_file("rig_outliers.json", &rotavg::io::rig::write_rig_json(&p));
    let file = file.to_str().unwrap();
    let auto = json_of(&run(&["rig", file, "--json"]));
    let ls = json_of(&run(&["rig", file, "--json", "--loss", "chordal"]));
    assert_eq!(auto["warnings"][0]["code"], "outliers_suspected");
    assert_eq!(ls["warnings"][0]["code"], "outliers_suspected");
    assert_eq!(
        auto["verdict"]["problem"]["kind"],
        "chordal_l2_rig_images_inliers"
    );
    assert!(auto["robust"]["robust"].as_bool().unwrap());
    let error = |v: &serde_json::Value| {
        let frames: f64 = (0..80)
            .map(|f| angle_between(&rotation(&v["estimate"][f]), &truth.frames[f]))
            .sum::<f64>()
            / 80.0;
        let sensors = (0..3)
            .map(|s| angle_between(&rotation(&v["sensors_from_rig"][s]), &truth.sensors[s]))
            .fold(0.0, f64::max);
        (frames, sensors)
    };
    let (a, b) = (error(&auto), error(&ls));
    assert!(
        a.0 * 5.0 < b.0 && a.1 * 5.0 < b.1,
        "robust {a:?}, least squares {b:?}"
    );
    // the planted outliers (residual above 10 degrees at the truth) are all dropped
    let at_truth = residual_angles(&p, &truth.frames, &truth.sensors);
    let planted = at_truth.iter().filter(|t| t.to_degrees() > 10.0).count();
    let kept = auto["robust"]["inlier_edges"].as_u64().unwrap() as usize;
    assert!(
        kept + planted <= p.edges().len(),
        "{kept} kept, {planted} planted outliers"
    );
    assert!(
        kept + planted + p.edges().len() / 50 >= p.edges().len(),
        "too many dropped: {kept}"
    );
    // the scale and inlier threshold from the data (`[H20]` "The scale"): 0.01 rad of noise,
    // median residual angle 1.538 x 0.573 = 0.88 deg; given, or with `--loss cauchy`, as given
    let scale = &auto["robust"]["data_scale"];
    assert_eq!(scale["rule"], "from_data");
    let median = scale["median_deg"].as_f64().unwrap();
    assert!((0.75..1.15).contains(&median), "{scale}");
    assert_eq!(auto["robust"]["scale_deg"], scale["scale_deg"]);
    assert_eq!(
        auto["robust"]["inlier_threshold_deg"],
        scale["inlier_threshold_deg"]
    );
    let text = String::from_utf8_lossy(&run(&["rig", file]).stdout).to_string();
    assert!(
        text.contains("from the data: 1.5 x the median residual"),
        "{text}"
    );
    for flags in [["--loss-threshold", "4"], ["--loss", "cauchy"]] {
        let given = json_of(&run(&["rig", file, "--json", flags[0], flags[1]]));
        let expected = if flags[1] == "4" { 4.0 } else { 5.0 };
        assert!(given["robust"]["data_scale"].is_null(), "{flags:?}");
        assert_eq!(given["robust"]["scale_deg"].as_f64(), Some(expected));
        assert_eq!(
            given["robust"]["inlier_threshold_deg"].as_f64(),
            Some(expected)
        );
    }
}

/// Two view graphs with 15 % random-rotation outliers on each: `--loss auto` (the default)
/// turns robust (warning `outliers_suspected`), returns and certifies the inlier problem
/// (`[H20]`, `[H22]`), its frames and `sensor_from_rig` at least 5 times closer to the planted
/// rig than least squares'; `--loss chordal` keeps least squares; with `--sensor-from-rig`
/// `cauchy` is an error.
#[test]
fn outliers_in_two_view_graphs_turn_the_default_robust() {
    use rotavg::multiple::MultipleProblem;
    use rotavg::multiple::synthetic::SyntheticGraph;
    use rotavg::pipeline::simultaneous::SyntheticRig;
    let graph = SyntheticGraph {
        num_rotations: 60,
        num_edges: 300,
        noise_sigma: 0.01,
        outlier_fraction: 0.15,
        seed: 41,
    };
    let (p, truth, s) = SyntheticRig { graph }.generate();
    let write = |name: &str, edges: &[rotavg::multiple::Edge]| {
        let g = MultipleProblem::new(p.num_nodes, edges.to_vec()).unwrap();
        temp_file(name, &rotavg::io::json::write_problem_json(&g))
    };
    let (right, left) = (
        write("rig_r_out.json", &p.right),
        write("rig_l_out.json", &p.left),
    );
    let (right, left) = (right.to_str().unwrap(), left.to_str().unwrap());
    let auto = json_of(&run(&["rig", right, left, "--json"]));
    let ls = json_of(&run(&["rig", right, left, "--json", "--loss", "chordal"]));
    let codes = |v: &serde_json::Value| -> Vec<String> {
        let w = v["warnings"].as_array().unwrap();
        w.iter()
            .map(|w| w["code"].as_str().unwrap().to_string())
            .collect()
    };
    assert!(codes(&auto).contains(&"outliers_suspected".to_string()));
    assert!(codes(&ls).contains(&"outliers_suspected".to_string()));
    assert_eq!(
        auto["verdict"]["problem"]["kind"],
        "chordal_l2_rig_images_inliers"
    );
    assert_eq!(auto["certificate"]["verdict"], "certified");
    assert!(auto["robust"]["robust"].as_bool().unwrap());
    // two graphs without edges between them: the scale from the data all the same
    assert_eq!(auto["robust"]["data_scale"]["rule"], "from_data");
    assert!(ls["robust"].is_null());
    let error = |v: &serde_json::Value| {
        let frames: f64 = (0..60)
            .map(|f| angle_between(&rotation(&v["estimate"][f]), &truth[f]))
            .sum::<f64>()
            / 60.0;
        (frames, angle_between(&rotation(&v["sensor_from_rig"]), &s))
    };
    let (a, b) = (error(&auto), error(&ls));
    assert!(
        a.0 * 5.0 < b.0 && a.1 * 5.0 < b.1,
        "robust {a:?}, least squares {b:?}"
    );
    let held = temp_file(
        "rig_held_out.json",
        &format!(
            "{{\"sensor_from_rig\": {}}}",
            serde_json::to_string(&rotavg::so3::rotation_to_rows(&s)).unwrap()
        ),
    );
    let out = run(&[
        "rig",
        right,
        left,
        "--loss",
        "cauchy",
        "--sensor-from-rig",
        held.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
}

/// COLMAP 4's gravity priors on a rig (`pose_priors`, keyed by image id, world down `+y`;
/// `[F15]`, `[G14]`), every sensor known: planted `g_a = X_a (0, 1, 0)` on all images but
/// one, read from the database itself. Noise-free: cost 0, certified for the rig with its priors
/// held, every image's prior satisfied to 1e-9.
#[test]
fn colmap_gravity_priors_on_a_colmap_rig() {
    let rig = ColmapRig::new();
    let path = temp_dir().join("rig_colmap_gravity.db");
    rig.write(&path, true, false, true);
    let db = rusqlite::Connection::open(&path).unwrap();
    db.execute_batch(
        "CREATE TABLE pose_priors (pose_prior_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, \
         corr_data_id INTEGER NOT NULL, corr_sensor_id INTEGER NOT NULL, corr_sensor_type \
         INTEGER NOT NULL, position BLOB, position_covariance BLOB, gravity BLOB, \
         coordinate_system INTEGER NOT NULL);",
    )
    .unwrap();
    let down = nalgebra::Vector3::new(0.0, 1.0, 0.0);
    for f in 0..12 {
        for c in 0..3 {
            if (f, c) == (4, 1) {
                continue;
            }
            let g = rig.x(f, c) * down;
            db.execute(
                "INSERT INTO pose_priors (corr_data_id, corr_sensor_id, corr_sensor_type, \
                 gravity, coordinate_system) VALUES (?1, ?2, 0, ?3, -1)",
                rusqlite::params![ColmapRig::image(f, c), c + 1, blob(&[g.x, g.y, g.z])],
            )
            .unwrap();
        }
    }
    drop(db);
    let p = path.to_str().unwrap();
    let out = run(&["rig", p, "--gravity", p, "--json"]);
    assert_success(&out);
    let v = json_of(&out);
    assert_eq!(v["verdict"]["verdict"], "certified");
    assert_eq!(v["verdict"]["problem"]["kind"], "chordal_l2_rig_gravity");
    assert_eq!(v["gravity"]["images"]["num_with_prior"], 35);
    assert_eq!(
        v["gravity"]["images"]["world_down"],
        serde_json::json!([0.0, 1.0, 0.0])
    );
    assert!(v["cost"].as_f64().unwrap() < 1e-18);
    for f in 0..12 {
        for c in 0..3 {
            let x = rotation(&v["sensors_from_rig"][c]) * rotation(&v["estimate"][f]);
            assert!(
                (x * down - rig.x(f, c) * down).norm() < 1e-9,
                "image ({f}, {c})"
            );
        }
    }
}

/// `rotavg rig FILE` on the committed rig with information matrices (`[H24]`): certified (by the
/// within-frame couplings), the estimated sensors within 0.3 degrees of the planted ones; the
/// text and the JSON both say the edges carry information.
#[test]
fn a_rig_file_with_information_is_certified_and_says_so() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/data/rig_information");
    let rig = dir.join("rig.json");
    let out = run(&["rig", rig.to_str().unwrap(), "--json"]);
    assert_success(&out);
    let v = json_of(&out);
    assert_eq!(v["verdict"]["verdict"], "certified", "{v}");
    assert_eq!(v["information"]["edges"], 363);
    let truth: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    for s in 0..3 {
        let (a, b) = (
            rotation(&v["sensors_from_rig"][s]),
            rotation(&truth["sensors_from_rig"][s]),
        );
        assert!(angle_between(&a, &b).to_degrees() < 0.3, "sensor {s}");
    }
    let out = run(&["rig", rig.to_str().unwrap()]);
    let text = String::from_utf8_lossy(&out.stdout).to_string();
    assert!(text.contains("information: 3x3 on 363 edges"), "{text}");
}

/// Two view graphs over the same frames with information matrices, written as JSON problems
/// (`name_right.json`, `name_left.json`): frames `F`, the left sensor's `S`, each graph a ring
/// with chords (`3n` edges), each edge's noise drawn from its own information `H = Q diag(1 /
/// sd^2) Q^T` (`sd` log-normal of spread `spread` about `sigma` per axis), the residual of
/// contract section 1 (`X_j X_i^T = R_ij exp([e]x)`). Returns the files and the truth.
fn information_pair(
    name: &str,
    (n, sigma, spread): (usize, f64, f64),
    seed: u64,
) -> (
    std::path::PathBuf,
    std::path::PathBuf,
    Vec<Rotation>,
    Rotation,
) {
    use rand::{Rng, SeedableRng};
    use rotavg::so3::{exp, random_rotation, rotation_to_rows};
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let frames: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
    let s = random_rotation(&mut rng);
    let mut normal = move || -> f64 {
        // Box-Muller
        let (u, v): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
        (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
    };
    let mut graph = |x: &[Rotation], seed: u64| {
        let mut pick = rand::rngs::StdRng::seed_from_u64(seed);
        let mut pairs: Vec<(usize, usize)> = (0..n).map(|i| (i, (i + 1) % n)).collect();
        while pairs.len() < 3 * n {
            let (i, j) = (pick.random_range(0..n), pick.random_range(0..n));
            if i != j && !pairs.contains(&(i, j)) && !pairs.contains(&(j, i)) {
                pairs.push((i, j));
            }
        }
        let edges: Vec<serde_json::Value> = pairs
            .iter()
            .map(|&(i, j)| {
                let sd = nalgebra::Vector3::from_fn(|_, _| sigma * (spread * normal()).exp());
                let q = random_rotation(&mut pick);
                let h = q.matrix()
                    * nalgebra::Matrix3::from_diagonal(&sd.map(|d| 1.0 / (d * d)))
                    * q.matrix().transpose();
                let e = q * nalgebra::Vector3::from_fn(|k, _| sd[k] * normal());
                let r = x[j] * x[i].inverse() * exp(&-e);
                let rows = |m: &nalgebra::Matrix3<f64>| {
                    (0..3)
                        .map(|a| (0..3).map(|b| m[(a, b)]).collect())
                        .collect::<Vec<Vec<f64>>>()
                };
                serde_json::json!({"i": i, "j": j, "rotation": rotation_to_rows(&r),
                    "information": rows(&(0.5 * (h + h.transpose())))})
            })
            .collect();
        serde_json::json!({"num_rotations": n, "edges": edges}).to_string()
    };
    let right = temp_file(&format!("{name}_right.json"), &graph(&frames, seed + 1));
    let lefts: Vec<Rotation> = frames.iter().map(|f| s * f).collect();
    let left = temp_file(&format!("{name}_left.json"), &graph(&lefts, seed + 2));
    (right, left, frames, s)
}

/// Two view graphs whose edges carry information (`[H22]` "Information"): `rotavg rig RIGHT
/// LEFT` solves them as the rig of two sensors they describe, `S` near the planted one; with
/// mild anisotropy (every `M = tr(H)/2 I - H` near positive semidefinite) the simultaneous
/// dual certificate proves the estimate (its cost the test's own sum over both files' edges),
/// written in the two graphs' format, certified again unchanged by `rotavg certify --left`
/// and, `S` held at it, the frames alone; with strong anisotropy (most `M` indefinite, where
/// the `O(3)` relaxation alone left a 16 % gap) certified by the `conv(SO(3))` surrogate
/// `[H27]`, its bound below the planted truth's cost (the test's own sum over the edges, from
/// the files).
#[test]
fn two_view_graphs_with_information_are_a_rig_of_two_sensors() {
    let dir = temp_dir();
    let est = dir.join("information_pair_estimate.json");
    let (right, left, _, s) = information_pair("info_pair_mild", (30, 0.01, 0.1), 7);
    let (r, l) = (right.to_str().unwrap(), left.to_str().unwrap());
    let out = run(&["rig", r, l, "--json", "--output", est.to_str().unwrap()]);
    assert_success(&out);
    let v = json_of(&out);
    assert_eq!(v["verdict"]["verdict"], "certified", "{v}");
    assert_eq!(v["information"]["edges"], 180);
    let got = rotation(&v["sensors_from_rig"][1]);
    assert!(
        angle_between(&got, &s).to_degrees() < 0.5,
        "{}",
        angle_between(&got, &s)
    );
    let written: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&est).unwrap()).unwrap();
    assert_eq!(written["node_ids"].as_array().map(Vec::len), Some(30));
    assert!(angle_between(&rotation(&written["sensor_from_rig"]), &got) < 1e-12);
    // the reported cost is the two files' cost at the written estimate
    let frames: Vec<Rotation> = (written["rotations"].as_array().unwrap().iter())
        .map(rotation)
        .collect();
    let lefts: Vec<Rotation> = frames.iter().map(|f| got * f).collect();
    let cost = information_cost(&right, &frames) + information_cost(&left, &lefts);
    let reported = v["cost"].as_f64().unwrap();
    assert!(
        (cost - reported).abs() <= 1e-9 * cost,
        "{cost} against {reported}"
    );
    let out = run(&[
        "certify",
        r,
        "--left",
        l,
        "--estimate",
        est.to_str().unwrap(),
        "--json",
    ]);
    assert_success(&out);
    let c = json_of(&out);
    assert_eq!(c["verdict"]["verdict"], "certified", "{c}");
    let (a, b) = (c["cost"].as_f64().unwrap(), v["cost"].as_f64().unwrap());
    assert!((a - b).abs() <= 1e-9 * b, "{a} against {b}");
    // `S` held: both sensors known, least squares (the loss `auto` is `chordal` then)
    let out = run(&[
        "rig",
        r,
        l,
        "--sensor-from-rig",
        est.to_str().unwrap(),
        "--json",
    ]);
    assert_success(&out);
    let h = json_of(&out);
    assert_eq!(h["verdict"]["verdict"], "certified", "{h}");
    let kind = &h["verdict"]["problem"]["kind"];
    assert_eq!(kind, "chordal_l2_rig_images_sensors_held", "{h}");
    assert!(angle_between(&rotation(&h["sensors_from_rig"][1]), &got) < 1e-9);
    // strong anisotropy: the conv(SO(3)) surrogate certifies; the bound is below the truth's
    // cost
    let (right, left, frames, s) = information_pair("info_pair_strong", (12, 0.01, 0.8), 8);
    let (r, l) = (right.to_str().unwrap(), left.to_str().unwrap());
    let out = run(&["rig", r, l, "--json"]);
    assert_success(&out);
    let v = json_of(&out);
    assert_eq!(v["verdict"]["verdict"], "certified", "{v}");
    let note = v["certificate"]["explanation"].as_str().unwrap_or("");
    assert!(note.contains("[H27]"), "{note}");
    let bound = v["certificate"]["lower_bound"].as_f64().unwrap();
    let truth_cost = information_cost(&right, &frames)
        + information_cost(&left, &{ frames.iter().map(|f| s * f).collect::<Vec<_>>() });
    assert!(
        bound <= truth_cost,
        "{bound} above the truth's {truth_cost}"
    );
    assert!(bound <= v["cost"].as_f64().unwrap());
}

/// The anisotropic chordal cost of contract section 1 of a JSON problem file at `x`: `sum 4 (tr
/// M - <R M, X_j X_i^T>)`, `M = tr(H)/2 I - H`, written here from the file's numbers.
fn information_cost(path: &Path, x: &[Rotation]) -> f64 {
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let matrix =
        |m: &serde_json::Value| nalgebra::Matrix3::from_fn(|a, b| m[a][b].as_f64().unwrap());
    (v["edges"].as_array().unwrap().iter())
        .map(|e| {
            let (i, j) = (
                e["i"].as_u64().unwrap() as usize,
                e["j"].as_u64().unwrap() as usize,
            );
            let (r, h) = (matrix(&e["rotation"]), matrix(&e["information"]));
            let m = nalgebra::Matrix3::identity() * (h.trace() / 2.0) - h;
            let gram = x[j].matrix() * x[i].matrix().transpose();
            4.0 * (m.trace() - (r * m).dot(&gram))
        })
        .sum()
}
