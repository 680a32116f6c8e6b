//! `rotavg conjugate` end to end: JSON output fields (contract section 5), exit codes, errors.

use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::conjugate::synthetic::random_instance;
use rotavg::io::handeye::write_conjugate_json;
use rotavg::so3::{angle_between, rotation_from_rows};

use crate::common;
use common::{bin, temp_file as tmp};

#[test]
fn json_output_and_exit_codes() {
    let mut rng = StdRng::seed_from_u64(51);
    let (p, s) = random_instance(12, 0.0, 0.0, &mut rng);
    let f = tmp("exact.json", &write_conjugate_json(&p));
    let out = bin()
        .args([
            "conjugate",
            f.to_str().unwrap(),
            "--json",
            "--require-certified",
        ])
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["problem"], "conjugate");
    assert_eq!(v["num_measurements"], 12);
    let rows: [[f64; 3]; 3] = serde_json::from_value(v["estimate"].clone()).unwrap();
    let est = rotation_from_rows(&rows, 1e-9, "estimate").unwrap();
    assert!(angle_between(&est, &s) < 1e-8);
    assert_eq!(v["certificate"]["verdict"], "certified");
    assert_eq!(v["certificate"]["method"], "sdp");
    for k in [
        "upper_bound",
        "lower_bound",
        "gap",
        "relative_gap",
        "min_eigenvalue",
        "seconds",
    ] {
        assert!(v["certificate"][k].is_number(), "{k}");
    }
    assert!(v["solver"]["name"].is_string() && v["solver"]["iterations"].is_number());

    // --certify none: certificate null; --require-certified then exits 3
    let out = bin()
        .args([
            "conjugate",
            f.to_str().unwrap(),
            "--json",
            "--certify",
            "none",
            "--require-certified",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(3));

    // bad input: exit 1 naming file and line
    let bad = tmp(
        "bad.json",
        "{\"pairs\": [\n  {\"left\": [[1,0,0],[0,1,0]], \"right\": 3}\n]}",
    );
    let out = bin()
        .args(["conjugate", bad.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad.json:2"), "{err}");

    // degenerate data: exit 1 with an explanation
    let axis = nalgebra::Vector3::new(0.0, 0.0, 1.0);
    let rs: Vec<_> = [0.3, 0.9]
        .iter()
        .map(|a| rotavg::so3::exp(&(axis * *a)))
        .collect();
    let ls: Vec<_> = rs.iter().map(|r| s * r * s.inverse()).collect();
    let d = rotavg::conjugate::ConjugateProblem::from_rotations(&ls, &rs).unwrap();
    let f = tmp("degenerate.json", &write_conjugate_json(&d));
    let out = bin()
        .args(["conjugate", f.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("parallel"));
}
