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
