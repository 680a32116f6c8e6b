//! The JSON carries every warning the text prints (issue 38, `rotavg::warning`): for every
//! reader warning path and every warning of a run, the `--json` object's `warnings` entry (code,
//! message, count) says what the text run printed, on stdout or stderr; verbs without warnings
//! have an empty array.

use crate::common;
use common::{assert_success, json_of, run, temp_dir, temp_file};
use std::process::Output;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/data");

/// Whitespace runs collapsed (the text output breaks long lines).
fn flat(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// The JSON run's warnings, each checked against the text run's stdout and stderr; their codes.
fn warnings_of(text: &Output, json: &Output) -> Vec<(String, Option<u64>)> {
    assert_success(text);
    assert_success(json);
    let printed = flat(&format!(
        "{}\n{}",
        String::from_utf8_lossy(&text.stdout),
        String::from_utf8_lossy(&text.stderr)
    ));
    let j = json_of(json);
    let list = j["warnings"].as_array().expect("a warnings array");
    list.iter()
        .map(|w| {
            let message = w["message"].as_str().expect("a message");
            assert!(
                printed.contains(&flat(message)),
                "not in the text: {message}\n{printed}"
            );
            let code = w["code"].as_str().expect("a code").to_owned();
            (code, w["count"].as_u64())
        })
        .collect()
}

/// Runs `rotavg ARGS` as text and with `--json`.
fn both(args: &[&str]) -> Vec<(String, Option<u64>)> {
    let mut with_json = args.to_vec();
    with_json.push("--json");
    warnings_of(&run(args), &run(&with_json))
}

#[test]
fn g2o_reader_warnings_are_in_the_json() {
    // three 3-D edges of a triangle (one without information), an unknown tag twice, a 2-D
    // vertex line, vertices for two of the three nodes
    let q = "0 0 0 1";
    let info = "1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1";
    let text = format!(
        "VERTEX_SE3:QUAT 0 0 0 0 {q}\nVERTEX_SE2 1 0 0 0\nFIX 0\nFIX 1\n\
         EDGE_SE3:QUAT 0 1 1 0 0 {q} {info}\nEDGE_SE3:QUAT 1 2 1 0 0 {q} {info}\n\
         EDGE_SE3:QUAT 2 0 1 0 0 {q}\n"
    );
    let path = temp_file("warnings.g2o", &text);
    let codes = both(&["multiple", path.to_str().unwrap()]);
    assert!(
        codes.contains(&("skipped_lines".into(), Some(2))),
        "{codes:?}"
    );
    assert!(
        codes.iter().any(|(c, _)| c == "mixed_dimensions"),
        "{codes:?}"
    );
    assert!(
        codes.contains(&("no_initial_estimate".into(), Some(1))),
        "{codes:?}"
    );
    assert!(
        codes.contains(&("without_information".into(), Some(1))),
        "{codes:?}"
    );
    assert_eq!(codes.len(), 4, "{codes:?}");
    // `info --json`: the messages as strings (its contract) and the same warnings coded
    let info = run(&["info", path.to_str().unwrap(), "--json"]);
    assert_success(&info);
    let j = json_of(&info);
    let details = j["warning_details"].as_array().expect("warning_details");
    let strings = j["warnings"].as_array().expect("warnings");
    assert_eq!(details.len(), strings.len());
    for (d, s) in details.iter().zip(strings) {
        assert_eq!(d["message"], *s);
    }
    let info_codes: Vec<&str> = details
        .iter()
        .map(|d| d["code"].as_str().unwrap())
        .collect();
    for (code, _) in &codes {
        assert!(
            info_codes.contains(&code.as_str()),
            "{code} not in {info_codes:?}"
        );
    }
}

#[test]
fn run_warnings_are_in_the_json() {
    // least squares on a view graph with outliers: the diagnosis, with the suspected count
    let sfm = format!("{DATA}/sfm_outliers.txt");
    let codes = both(&["multiple", &sfm, "--loss", "chordal"]);
    assert_eq!(codes, [("outliers_suspected".into(), Some(185))]);
    // the default acts on it instead: no warning
    assert_eq!(both(&["multiple", &sfm]), []);
    // robust outputs asked for where `auto` keeps least squares
    let slam = format!("{DATA}/slam.g2o");
    let edges = temp_dir().join("warnings_edges.csv");
    let codes = both(&["multiple", &slam, "--edges-output", edges.to_str().unwrap()]);
    assert_eq!(codes, [("output_not_written".into(), Some(1))]);
}

#[test]
fn certify_warnings_are_in_the_json_and_other_verbs_have_none() {
    let slam = format!("{DATA}/slam.g2o");
    let estimate = temp_dir().join("warnings_estimate.json");
    assert_success(&run(&[
        "multiple",
        &slam,
        "--output",
        estimate.to_str().unwrap(),
        "--quiet",
    ]));
    // one more entry than the graph has nodes: matched by id, the extra one reported
    let mut e: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&estimate).unwrap()).unwrap();
    let first = e["rotations"][0].clone();
    e["rotations"].as_array_mut().unwrap().push(first);
    e["node_ids"].as_array_mut().unwrap().push(99_999.into());
    let extra = temp_file("warnings_extra.json", &e.to_string());
    let codes = both(&["certify", &slam, "--estimate", extra.to_str().unwrap()]);
    assert_eq!(codes.len(), 1, "{codes:?}");
    assert_eq!(codes[0].0, "estimate_unmatched");
    for args in [
        vec!["single".to_string(), format!("{DATA}/single.json")],
        vec![
            "conjugate".to_string(),
            "--hand".into(),
            format!("{DATA}/handeye/hand.csv"),
            "--camera".into(),
            format!("{DATA}/handeye/camera.csv"),
        ],
        vec!["multiple".to_string(), slam.clone()],
    ] {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        assert_eq!(both(&args), [], "{args:?}");
    }
}

#[test]
fn input_checks_are_warned_in_text_and_json() {
    // a triangle measured twice on one pair, the second time turned by 90 degrees about z
    let i = "1 0 0 0 1 0 0 0 1";
    let turned = "0 -1 0 1 0 0 0 0 1";
    let egs = format!("3 7 {i}\n7 9 {i}\n3 9 {i}\n3 7 {turned}\n9 3 {i}\n");
    let path = temp_file("warnings_dup_EGs.txt", &egs);
    let codes = both(&["multiple", path.to_str().unwrap()]);
    assert_eq!(codes, [("duplicates_disagree".to_string(), Some(1))]);
    // a text graph named like a COLMAP database is read by its content, and said so
    let db = temp_file("warnings_text.db", &format!("3 7 {i}\n7 9 {i}\n3 9 {i}\n"));
    let codes = both(&["multiple", db.to_str().unwrap()]);
    assert_eq!(codes, [("name_not_format".to_string(), None)]);
    let printed = run(&["multiple", path.to_str().unwrap()]);
    let printed = flat(&String::from_utf8_lossy(&printed.stdout));
    assert!(printed.contains("pair (3, 7), 90.0 deg"), "{printed}");
    // information asymmetric by rounding
    let h = |x: &str| format!("[[2,{x},0],[0,1,0],[0,0,3]]");
    let r = "[[1,0,0],[0,1,0],[0,0,1]]";
    let json = format!(
        r#"{{"num_rotations": 3, "edges": [
        {{"i":0,"j":1,"rotation":{r},"information":{}}},
        {{"i":1,"j":2,"rotation":{r},"information":{}}},
        {{"i":2,"j":0,"rotation":{r},"information":{}}}]}}"#,
        h("1e-15"),
        h("0"),
        h("0")
    );
    let path = temp_file("warnings_asym.json", &json);
    let codes = both(&["multiple", path.to_str().unwrap()]);
    assert_eq!(codes, [("information_symmetrized".to_string(), Some(1))]);
    // an estimate in the other convention: the hand-eye truth transposed, and the optimum of a
    // view graph transposed
    let dir = temp_dir();
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(format!("{DATA}/handeye/truth.json")).unwrap(),
    )
    .unwrap();
    let rows: [[f64; 3]; 3] = serde_json::from_value(truth["rotation"].clone()).unwrap();
    let transposed: Vec<Vec<f64>> = (0..3)
        .map(|a| (0..3).map(|b| rows[b][a]).collect())
        .collect();
    let s_t = dir.join("warnings_s_transposed.json");
    std::fs::write(
        &s_t,
        serde_json::json!({ "rotation": transposed }).to_string(),
    )
    .unwrap();
    let handeye = format!("{DATA}/handeye");
    let codes = both(&["certify", &handeye, "--estimate", s_t.to_str().unwrap()]);
    assert_eq!(codes, [("convention_suspected".to_string(), None)]);
    let right = both(&[
        "certify",
        &handeye,
        "--estimate",
        &format!("{DATA}/handeye/truth.json"),
    ]);
    assert!(right.is_empty(), "{right:?}");
    let slam = format!("{DATA}/slam.g2o");
    let solved = json_of(&run(&["multiple", &slam, "--json"]));
    let estimate: Vec<[[f64; 3]; 3]> = serde_json::from_value(solved["estimate"].clone()).unwrap();
    let flipped: Vec<[[f64; 3]; 3]> = estimate
        .iter()
        .map(|m| [0, 1, 2].map(|a| [0, 1, 2].map(|b| m[b][a])))
        .collect();
    let est = dir.join("warnings_transposed.json");
    std::fs::write(
        &est,
        serde_json::json!({ "rotations": flipped }).to_string(),
    )
    .unwrap();
    let codes = both(&["certify", &slam, "--estimate", est.to_str().unwrap()]);
    assert_eq!(codes, [("convention_suspected".to_string(), None)]);
}

#[test]
fn init_and_ground_truth_warnings_are_reported() {
    // the least-squares estimate of the committed SLAM file as a COLMAP images.txt (NaN
    // translations, as pycolmap's rotation averaging writes), with one image the graph lacks
    let slam = format!("{DATA}/slam.g2o");
    let solved = json_of(&run(&["multiple", &slam, "--loss", "chordal", "--json"]));
    let ids: Vec<u64> = serde_json::from_value(solved["node_ids"].clone()).unwrap();
    let estimate: Vec<[[f64; 3]; 3]> = serde_json::from_value(solved["estimate"].clone()).unwrap();
    let mut text = String::new();
    for (id, m) in ids.iter().zip(&estimate) {
        let r =
            rotavg::Rotation::from_matrix_unchecked(rotavg::nalgebra::Matrix3::from_fn(|a, b| {
                m[a][b]
            }));
        let q = rotavg::nalgebra::UnitQuaternion::from_rotation_matrix(&r);
        text += &format!(
            "{id} {} {} {} {} nan nan nan 1 img{id}.jpg\n\n",
            q.w, q.i, q.j, q.k
        );
    }
    text += "99999 1 0 0 0 0 0 0 1 extra.jpg\n\n";
    let model = temp_file("warnings_init_images.txt", &text);
    let model = model.to_str().unwrap();
    let codes = both(&["multiple", &slam, "--loss", "chordal", "--init", model]);
    assert_eq!(
        codes,
        [
            ("estimate_unmatched".to_string(), Some(1)),
            (
                "translations_not_finite".to_string(),
                Some(ids.len() as u64)
            )
        ]
    );
    // as ground truth, entries the graph lacks are expected (not said); NaN translations are
    let codes = both(&[
        "multiple",
        &slam,
        "--loss",
        "chordal",
        "--ground-truth",
        model,
    ]);
    assert_eq!(
        codes,
        [(
            "translations_not_finite".to_string(),
            Some(ids.len() as u64)
        )]
    );
}
