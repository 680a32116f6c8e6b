//! `rotavg info` run as a process: readable and JSON output, exit codes, error messages with
//! file and line.

use crate::common;
use common::{bin, run_with_stdin, shared_data, temp_file as tmp};

/// A 4-cycle of planar edges plus a duplicate that contradicts by 30 deg: n = 4, m = 5.
/// Unit weights: the scalar Laplacian of C_4 plus a double edge (0,1)... lambda_2 checked below
/// only through the JSON (present and positive).
const CYCLE: &str = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 0 0 0\nVERTEX_SE2 2 0 0 0\nVERTEX_SE2 3 0 0 0\n\
EDGE_SE2 0 1 0 0 0 1 0 0 1 0 1\nEDGE_SE2 1 2 0 0 0 1 0 0 1 0 1\nEDGE_SE2 2 3 0 0 0 1 0 0 1 0 1\n\
EDGE_SE2 3 0 0 0 0 1 0 0 1 0 1\nEDGE_SE2 1 0 0 0 0.5235987755982988 1 0 0 1 0 1\n";

#[test]
fn info_readable_and_json() {
    let p = tmp("cycle.g2o", CYCLE);
    let out = bin().arg("info").arg(&p).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout} {}",
        String::from_utf8_lossy(&out.stderr)
    );
    for needle in [
        "nodes:          4",
        "edges:          5 (4 distinct pairs, 1 duplicate edges)",
        "1 contradictory",
        "spectral gap",
        "components:     1",
    ] {
        assert!(stdout.contains(needle), "missing `{needle}` in\n{stdout}");
    }
    let out = bin().args(["info", "--json"]).arg(&p).output().unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["num_rotations"], 4);
    assert_eq!(v["num_measurements"], 5);
    assert_eq!(v["stats"]["contradictory_pairs"], 1);
    assert_eq!(v["reversed_edges"], 2);
    // the vertex lines (all identity) fit the 4 consistent edges exactly, the 30 deg one not
    let max = v["stats"]["initial_residuals"]["angle_deg"]["max"]
        .as_f64()
        .unwrap();
    assert!((max - 30.0).abs() < 1e-9, "{max}");
    // C_4 with edge (0,1) doubled: L = [[3,-2,0,-1],[-2,3,-1,0],[0,-1,2,-1],[-1,0,-1,2]];
    // lambda_2 = 2 (eigenvector (1,1,-1,-1)), d_max = 3 -> 2/3.
    let gap = v["stats"]["spectral_gap"]["normalized"].as_f64().unwrap();
    assert!((gap - 2.0 / 3.0).abs() < 1e-12, "{gap}");
}

#[test]
fn info_reads_stdin_and_forced_format() {
    let out = run_with_stdin(&["info", "--format", "g2o", "-"], CYCLE);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("nodes:          4"));
}

#[test]
fn info_errors_name_file_and_line() {
    let p = tmp(
        "bad.g2o",
        "EDGE_SE2 0 1 0 0 0 1 0 0 1 0 1\nEDGE_SE2 0 1 0 0 zz 1 0 0 1 0 1\n",
    );
    let out = bin().arg("info").arg(&p).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains(&format!("{}:2:", p.display())), "{stderr}");
    let out = bin().args(["info", "/nonexistent/x.g2o"]).output().unwrap();
    assert_eq!(out.status.code(), Some(1));
    let out = bin()
        .args(["info", "--format", "nope", "x"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn info_on_shared_data_if_present() {
    let dir = shared_data();
    let Some(dir) = dir else {
        println!("skipping: shared data not found");
        return;
    };
    for rel in [
        "1dsfm/Madrid_Metropolis/EGs.txt",
        "g2o/3d/sesync/sphere2500.g2o",
    ] {
        let out = bin().arg("info").arg(dir.join(rel)).output().unwrap();
        let s = String::from_utf8_lossy(&out.stdout);
        println!("{s}");
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        assert!(s.contains("components:     1 (connected)"));
    }
}
