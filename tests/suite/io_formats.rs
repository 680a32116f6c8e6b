//! Readers and writers on hand-made and planted noise-free files: each format's convention
//! gives cost 0 for the planted rotations (`paper-notes/formats.md` [F1]-[F8]); every malformed
//! input gets a typed error with file and line; random garbage never panics.

use nalgebra::{Matrix3, UnitQuaternion};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rotavg::Error;
use rotavg::Rotation;
use rotavg::io::detect::{GraphFormat, ReadOptions, WeightSource, detect_format, read_graph};
use rotavg::io::g2o::{read_g2o, write_g2o};
use rotavg::io::json::{
    Estimate, read_estimate, read_problem_json, read_rotations_estimate, write_estimate_json,
    write_problem_json,
};
use rotavg::io::sfm::{read_bundler, read_egs, read_rotation_list, truth_for_nodes};
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::so3::{angle_between, random_rotation};
use std::fmt::Write as _;

fn opts() -> ReadOptions {
    ReadOptions::default()
}

/// Scalar-last quaternion text of a rotation.
fn q_text(r: &Rotation) -> String {
    let q = UnitQuaternion::from_rotation_matrix(r);
    format!("{} {} {} {}", q.i, q.j, q.k, q.w)
}

fn rx(a: f64) -> Matrix3<f64> {
    Matrix3::new(1.0, 0.0, 0.0, 0.0, a.cos(), -a.sin(), 0.0, a.sin(), a.cos())
}
fn ry(a: f64) -> Matrix3<f64> {
    Matrix3::new(a.cos(), 0.0, a.sin(), 0.0, 1.0, 0.0, -a.sin(), 0.0, a.cos())
}
fn rz(a: f64) -> Matrix3<f64> {
    Matrix3::new(a.cos(), -a.sin(), 0.0, a.sin(), a.cos(), 0.0, 0.0, 0.0, 1.0)
}

/// Edges of a small graph with sparse ids, one reversed edge and one multi-edge.
const PAIRS: [(usize, usize); 7] = [(0, 1), (1, 2), (2, 3), (3, 0), (2, 0), (1, 3), (1, 0)];
const IDS: [u64; 4] = [5, 17, 18, 400];

/// [F1] g2o 3-D: W_i world-from-body, Z_ij = W_i^T W_j; our R_i = W_i^T gives cost 0, and the
/// cost of an arbitrary estimate equals SE-Sync's sum kappa ||W_j - W_i Z_ij||^2 with
/// kappa = 3 / (2 tr(Omega_rot^-1)) [F3].
#[test]
fn g2o_se3_convention_is_noise_free_and_matches_sesync_cost() {
    let mut rng = StdRng::seed_from_u64(1);
    let w: Vec<Rotation> = (0..4).map(|_| random_rotation(&mut rng)).collect();
    let mut text = String::from("# comment line\n\n");
    for (k, wk) in w.iter().enumerate() {
        writeln!(text, "VERTEX_SE3:QUAT {}  1 2 3  {}   ", IDS[k], q_text(wk)).unwrap();
    }
    writeln!(text, "FIX 5").unwrap();
    // rotation information diag(400, 400, 99) -> kappa = 3 / (2 (1/400 + 1/400 + 1/99))
    let kappa = 3.0 / (2.0 * (1.0 / 400.0 + 1.0 / 400.0 + 1.0 / 99.0));
    for &(i, j) in &PAIRS {
        let z = w[i].inverse() * w[j];
        writeln!(
            text,
            "EDGE_SE3:QUAT {} {} 0.1 0.2 0.3 {} 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 400 0 0 400 0 99",
            IDS[i],
            IDS[j],
            q_text(&z)
        )
        .unwrap();
    }
    let g = read_g2o(&text, "planted.g2o", &opts()).unwrap();
    assert_eq!(g.node_ids, IDS.to_vec());
    assert_eq!(g.problem.num_edges(), 7);
    assert_eq!(g.duplicates, 1); // (1,0) repeats {0,1} (see duplicate_count_of_pairs)
    assert_eq!(g.reversed, 3); // (3,0), (2,0), (1,0)
    assert!(
        g.warnings.iter().any(|s| s.message.contains("FIX")),
        "{:?}",
        g.warnings
    );
    let truth: Vec<Rotation> = w.iter().map(|x| x.inverse()).collect();
    let init = g.initial.clone().unwrap();
    for (a, b) in init.iter().zip(&truth) {
        assert!(angle_between(a, b) < 1e-12);
    }
    assert!(g.problem.chordal_cost(&truth) < 1e-20);
    for e in g.problem.edges() {
        assert!((e.weight - kappa).abs() < 1e-12 * kappa);
    }
    // the opposite convention (R_i = W_i) is not a solution
    assert!(g.problem.chordal_cost(&w) > 1.0);
    // arbitrary estimate X_i (world-from-body W'_i = X_i^T): SE-Sync's cost, edge by edge
    let est: Vec<Rotation> = (0..4).map(|_| random_rotation(&mut rng)).collect();
    let sesync: f64 = PAIRS
        .iter()
        .map(|&(i, j)| {
            let z = w[i].inverse() * w[j];
            let (wi, wj) = (est[i].inverse(), est[j].inverse());
            kappa * (wj.matrix() - wi.matrix() * z.matrix()).norm_squared()
        })
        .sum();
    let ours = g.problem.chordal_cost(&est);
    assert!((ours - sesync).abs() < 1e-9 * sesync, "{ours} vs {sesync}");
}

/// The duplicate count: PAIRS has {0,1} twice (as (0,1) and (1,0)), every other pair once.
#[test]
fn duplicate_count_of_pairs() {
    let e = |i, j| rotavg::multiple::Edge {
        i,
        j,
        rotation: Rotation::identity(),
        weight: 1.0,
    };
    let p =
        rotavg::multiple::MultipleProblem::new(4, PAIRS.iter().map(|&(i, j)| e(i, j)).collect())
            .unwrap();
    // {0,1},{1,2},{2,3},{0,3},{0,2},{1,3},{0,1}: 6 distinct pairs, 1 repeat
    assert_eq!(rotavg::multiple::stats::duplicate_edge_count(&p), 1);
}

/// [F2] TORO EDGE3 / VERTEX3: Z = Rz(yaw) Ry(pitch) Rx(roll); cost 0; weights: 9-token lines
/// get 1, 30-token lines kappa = 6 / tr(Omega_rot^-1) (angle-unit information).
#[test]
fn edge3_convention_and_weights() {
    let mut rng = StdRng::seed_from_u64(2);
    let ypr: Vec<[f64; 3]> = (0..4)
        .map(|_| {
            [
                rng.random_range(-3.0..3.0),
                rng.random_range(-1.5..1.5),
                rng.random_range(-3.0..3.0),
            ]
        })
        .collect();
    let wmat = |k: usize| rz(ypr[k][0]) * ry(ypr[k][1]) * rx(ypr[k][2]);
    let mut text = String::new();
    for (k, [yaw, pitch, roll]) in ypr.iter().enumerate() {
        writeln!(text, "VERTEX3 {k} 0 0 0 {roll} {pitch} {yaw}").unwrap();
    }
    for (n, &(i, j)) in PAIRS.iter().enumerate() {
        let z = Rotation::from_matrix_unchecked(wmat(i).transpose() * wmat(j));
        let (roll, pitch, yaw) = z.euler_angles(); // nalgebra: R = Rz(yaw) Ry(pitch) Rx(roll)
        let info = if n % 2 == 0 {
            " 10 0 0 0 0 0 10 0 0 0 0 10 0 0 0 100 0 0 100 0 25"
        } else {
            ""
        };
        writeln!(text, "EDGE3 {i} {j} 1 0 0 {roll} {pitch} {yaw}{info}").unwrap();
    }
    let g = read_g2o(&text, "t.txt", &opts()).unwrap();
    let truth: Vec<Rotation> = (0..4)
        .map(|k| Rotation::from_matrix_unchecked(wmat(k).transpose()))
        .collect();
    assert!(g.problem.chordal_cost(&truth) < 1e-20);
    assert!(g.problem.chordal_cost(g.initial.as_ref().unwrap()) < 1e-20);
    // 6 / (1/100 + 1/100 + 1/25) = 100
    for (n, e) in g.problem.edges().iter().enumerate() {
        let expect = if n % 2 == 0 { 100.0 } else { 1.0 };
        assert!((e.weight - expect).abs() < 1e-9, "edge {n}: {}", e.weight);
    }
    let u = read_g2o(
        &text,
        "t.txt",
        &ReadOptions {
            weights: WeightSource::Unit,
            ..opts()
        },
    )
    .unwrap();
    assert!(u.problem.edges().iter().all(|e| e.weight == 1.0));
}

/// [F4] g2o 2-D: rotations about z, R_ij = Rz(-dtheta); kappa = I33; cost 0 on planted data.
#[test]
fn se2_convention() {
    let th = [0.3, -2.0, 2.9, 1.0];
    let mut text = String::new();
    for (k, t) in th.iter().enumerate() {
        writeln!(text, "VERTEX_SE2 {k} 0 0 {t}").unwrap();
    }
    for &(i, j) in &PAIRS {
        writeln!(text, "EDGE_SE2 {i} {j} 1 0 {} 1 0 0 1 0 7.5", th[j] - th[i]).unwrap();
    }
    let g = read_g2o(&text, "p.g2o", &opts()).unwrap();
    assert!(g.planar);
    let truth: Vec<Rotation> = th
        .iter()
        .map(|t| Rotation::from_matrix_unchecked(rz(*t).transpose()))
        .collect();
    assert!(g.problem.chordal_cost(&truth) < 1e-20);
    assert!(g.problem.edges().iter().all(|e| e.weight == 7.5));
}

/// [F5] 1DSfM: the file's R = C_i C_j^T (C world-to-camera), our R_ij = R^T; sparse ids.
#[test]
fn egs_convention_and_ground_truth_files() {
    let mut rng = StdRng::seed_from_u64(3);
    let c: Vec<Rotation> = (0..4).map(|_| random_rotation(&mut rng)).collect();
    let mut text = String::new();
    for &(i, j) in &PAIRS {
        let m = c[i].matrix() * c[j].matrix().transpose();
        let rows: Vec<String> = (0..3)
            .flat_map(|r| (0..3).map(move |cc| (r, cc)))
            .map(|(r, cc)| m[(r, cc)].to_string())
            .collect();
        writeln!(text, "{} {} {} 0.6 0 0.8", IDS[i], IDS[j], rows.join(" ")).unwrap();
    }
    assert_eq!(
        detect_format("EGs.txt", &text).unwrap(),
        GraphFormat::OneDsfm
    );
    let g = read_egs(&text, "EGs.txt", &opts()).unwrap();
    assert_eq!(g.node_ids, IDS.to_vec());
    assert!(g.problem.chordal_cost(&c) < 1e-20);
    let transposed: Vec<Rotation> = c.iter().map(|x| x.inverse()).collect();
    assert!(g.problem.chordal_cost(&transposed) > 1.0);

    // Bundler ground truth indexed by file id (401 cameras, only the 4 ids reconstructed)
    let mut b = String::from("# Bundle file v0.3\n401 2\n");
    for id in 0..401u64 {
        b.push_str("500 0 0\n");
        match IDS.iter().position(|&x| x == id) {
            Some(k) => {
                let m = c[k].matrix();
                for r in 0..3 {
                    writeln!(b, "{} {} {}", m[(r, 0)], m[(r, 1)], m[(r, 2)]).unwrap();
                }
            }
            None => b.push_str("0 0 0\n0 0 0\n0 0 0\n"),
        }
        b.push_str("0 0 0\n");
    }
    b.push_str("1 2 3\n255 0 0\n0\n1 2 3\n255 0 0\n0\n");
    let gt = read_bundler(&b, "gt_bundle.out", &opts()).unwrap();
    assert_eq!(gt.len(), 401);
    assert_eq!(gt.iter().filter(|x| x.is_some()).count(), 4);
    let per_node = truth_for_nodes(&gt, &g.node_ids);
    for (k, t) in per_node.iter().enumerate() {
        assert!(angle_between(t.as_ref().unwrap(), &c[k]) < 1e-12);
    }
    // plain list
    let mut l = String::new();
    for ck in &c {
        let m = ck.matrix();
        let v: Vec<String> = (0..3)
            .flat_map(|r| (0..3).map(move |cc| m[(r, cc)].to_string()))
            .collect();
        writeln!(l, "{}", v.join(" ")).unwrap();
    }
    l.push_str("0 0 0 0 0 0 0 0 0\n");
    let lst = read_rotation_list(&l, "gt.txt", &opts()).unwrap();
    assert_eq!(lst.len(), 5);
    assert!(lst[4].is_none());
    assert!(angle_between(lst[2].as_ref().unwrap(), &c[2]) < 1e-12);
}

/// JSON problem, estimate and g2o writers round-trip.
#[test]
fn writers_round_trip() {
    let (p, gt) = SyntheticGraph {
        num_rotations: 30,
        num_edges: 80,
        noise_sigma: 0.1,
        seed: 9,
        ..Default::default()
    }
    .generate();
    let j = read_problem_json(&write_problem_json(&p), "p.json", &opts()).unwrap();
    assert_eq!(j.problem.num_edges(), p.num_edges());
    for (a, b) in j.problem.edges().iter().zip(p.edges()) {
        assert_eq!((a.i, a.j, a.weight), (b.i, b.j, b.weight));
        assert!(angle_between(&a.rotation, &b.rotation) < 1e-14);
    }
    let g = read_g2o(&write_g2o(&p, Some(&gt)), "p.g2o", &opts()).unwrap();
    assert!((g.problem.chordal_cost(&gt) - p.chordal_cost(&gt)).abs() < 1e-9 * p.chordal_cost(&gt));
    for (a, b) in g.problem.edges().iter().zip(p.edges()) {
        assert!((a.weight - b.weight).abs() < 1e-12 * b.weight);
        assert!(angle_between(&a.rotation, &b.rotation) < 1e-12);
    }
    for (a, b) in g.initial.unwrap().iter().zip(&gt) {
        assert!(angle_between(a, b) < 1e-12);
    }
    let est = read_rotations_estimate(&write_estimate_json(&gt), "e.json", &opts()).unwrap();
    assert!(
        est.iter()
            .zip(&gt)
            .all(|(a, b)| angle_between(a, b) < 1e-14)
    );
    // --json output style and single-rotation files
    let printed = format!(
        "{{\"problem\": \"multiple\", \"cost\": 1.0, \"estimate\": {}}}",
        serde_json::to_string(
            &gt.iter()
                .map(rotavg::so3::rotation_to_rows)
                .collect::<Vec<_>>()
        )
        .unwrap()
    );
    assert!(
        matches!(read_estimate(&printed, "o.json", &opts()).unwrap(), Estimate::Multiple(v) if v.len() == 30)
    );
    let single = r#"{"estimate": [[0,-1,0],[1,0,0],[0,0,1]], "problem": "single"}"#;
    assert!(matches!(
        read_estimate(single, "s.json", &opts()).unwrap(),
        Estimate::Single(_)
    ));
    assert!(read_rotations_estimate(single, "s.json", &opts()).is_err());
}

#[test]
fn detection() {
    assert_eq!(detect_format("a.json", "").unwrap(), GraphFormat::Json);
    assert_eq!(detect_format("a.g2o", "").unwrap(), GraphFormat::G2o);
    assert_eq!(
        detect_format("a.txt", "\n# c\nEDGE3 0 1").unwrap(),
        GraphFormat::G2o
    );
    assert!(detect_format("a.txt", "1 2 3\n").is_err());
    assert!(detect_format("a.txt", "  \n").is_err());
    let text = "EDGE_SE2 0 1 0 0 0.1 1 0 0 1 0 1\n";
    assert!(read_graph(text, "-", GraphFormat::Auto, &opts()).is_ok());
    assert!(read_graph(text, "-", GraphFormat::Json, &opts()).is_err());
}

/// (file, line) of a parse error; panics (test failure) on any other error kind.
fn location(e: &Error) -> (Option<String>, Option<usize>) {
    match e {
        Error::Parse { location, .. } => (location.file.clone(), location.line),
        other => panic!("expected a parse error, got {other:?}"),
    }
}

const GOOD_EDGE: &str = "EDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1";

/// Every malformed g2o line: a typed parse error naming the file and the line.
#[test]
fn malformed_g2o_inputs() {
    let cases: Vec<(String, usize, &str)> = vec![
        (
            format!("{GOOD_EDGE}\nEDGE_SE3:QUAT 0 1 0 0 0 0 0 0 1 5\n"),
            2,
            "tokens",
        ),
        (
            format!(
                "{GOOD_EDGE}\nEDGE_SE3:QUAT 0 x 0 0 0 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n"
            ),
            2,
            "not a non-negative integer",
        ),
        (
            format!(
                "{GOOD_EDGE}\nEDGE_SE3:QUAT 0 -1 0 0 0 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n"
            ),
            2,
            "integer",
        ),
        (
            format!(
                "\n{GOOD_EDGE}\nEDGE_SE3:QUAT 0 2 0 0 0 0 0 0 abc 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n"
            ),
            3,
            "not a number",
        ),
        (
            format!(
                "{GOOD_EDGE}\nEDGE_SE3:QUAT 0 2 0 0 0 0 0 0 NaN 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n"
            ),
            2,
            "not finite",
        ),
        (
            format!(
                "{GOOD_EDGE}\nEDGE_SE3:QUAT 0 2 0 0 inf 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n"
            ),
            2,
            "not finite",
        ),
        (
            format!(
                "{GOOD_EDGE}\nEDGE_SE3:QUAT 0 2 0 0 0 0 0 0 0 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n"
            ),
            2,
            "quaternion",
        ),
        (
            format!(
                "{GOOD_EDGE}\nEDGE_SE3:QUAT 0 2 0 0 0 0 0 0 2 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n"
            ),
            2,
            "quaternion",
        ),
        // rotation block diag(1, -1, 1): not positive definite
        (
            format!(
                "{GOOD_EDGE}\nEDGE_SE3:QUAT 0 2 0 0 0 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 -1 0 1\n"
            ),
            2,
            "positive definite",
        ),
        // rotation block all zero
        (
            format!(
                "{GOOD_EDGE}\nEDGE_SE3:QUAT 0 2 0 0 0 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 0 0 0 0 0 0\n"
            ),
            2,
            "positive definite",
        ),
        (
            format!(
                "{GOOD_EDGE}\nEDGE_SE3:QUAT 3 3 0 0 0 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n"
            ),
            2,
            "self loop",
        ),
        (
            format!(
                "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\nVERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n{GOOD_EDGE}\n"
            ),
            2,
            "twice",
        ),
        ("VERTEX_SE3:QUAT 0 0 0 0 0 0 0\n".to_string(), 1, "tokens"),
        ("EDGE3 0 1 0 0 0 0 0\n".to_string(), 1, "tokens"),
        (
            "EDGE3 0 1 0 0 0 0 0 0 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 0\n".to_string(),
            1,
            "positive definite",
        ),
        ("EDGE_SE2 0 1 0 0 0 1 0 0 1 0 0\n".to_string(), 1, "I33"),
        ("EDGE_SE2 0 1 0 0\n".to_string(), 1, "tokens"),
        ("VERTEX_SE2 0 0 0 0\nFIX 0\n".to_string(), 2, "no edge"),
    ];
    for (text, line, needle) in &cases {
        let err = read_g2o(text, "bad.g2o", &opts()).expect_err(text);
        let (file, l) = location(&err);
        assert_eq!(file.as_deref(), Some("bad.g2o"), "{err}");
        assert_eq!(l, Some(*line), "{text}: {err}");
        assert!(err.to_string().contains(needle), "{err} lacks `{needle}`");
        assert!(
            err.to_string().starts_with(&format!("bad.g2o:{line}: ")),
            "{err}"
        );
    }
    // empty file
    let err = read_g2o("", "empty.g2o", &opts()).unwrap_err();
    assert_eq!(location(&err).0.as_deref(), Some("empty.g2o"));
}

#[test]
fn malformed_egs_bundler_list_json() {
    let rot = "1 0 0 0 1 0 0 0 1";
    let cases: Vec<(String, usize, &str)> = vec![
        (format!("0 1 {rot} 1 0 0\n0 2 {rot} 1 0\n"), 2, "tokens"),
        (
            format!("0 1 {rot} 1 0 0\n0 2 1 0 0 0 1 0 0 0 2 1 0 0\n"),
            2,
            "not a rotation",
        ),
        (
            format!("0 1 {rot} 1 0 0\n0 2 1 0 0 0 1 0 0 0 -1 1 0 0\n"),
            2,
            "not a rotation",
        ),
        (
            format!("0 1 {rot} 1 0 0\n2 2 {rot} 1 0 0\n"),
            2,
            "self loop",
        ),
        (
            format!("0 1 {rot} 1 0 0\n0 1 1 0 0 0 nan 0 0 0 1 1 0 0\n"),
            2,
            "finite",
        ),
        (format!("0 1 {rot} 1 0 0\nx 1 {rot} 1 0 0\n"), 2, "integer"),
    ];
    for (text, line, needle) in &cases {
        let err = read_egs(text, "EGs.txt", &opts()).expect_err(text);
        let (file, l) = location(&err);
        assert_eq!(
            (file.as_deref(), l),
            (Some("EGs.txt"), Some(*line)),
            "{err}"
        );
        assert!(err.to_string().contains(needle), "{err} lacks `{needle}`");
    }
    assert!(read_egs("\n\n", "EGs.txt", &opts()).is_err());
    // Bundler: truncated; bad rotation; header lies about a huge count (no allocation from it)
    let hdr = "# Bundle file v0.3\n";
    let err = read_bundler(
        &format!("{hdr}18446744073709551615 0\n500 0 0\n1 0 0\n0 1 0\n0 0 1\n0 0 0\n"),
        "b.out",
        &opts(),
    )
    .unwrap_err();
    assert!(err.to_string().contains("truncated"), "{err}");
    let err = read_bundler(
        &format!("{hdr}1 0\n500 0 0\n1 0 0\n0 1 0\n0 0 2\n0 0 0\n"),
        "b.out",
        &opts(),
    )
    .unwrap_err();
    assert_eq!(location(&err).1, Some(4), "{err}");
    assert!(read_bundler("", "b.out", &opts()).is_err());
    assert!(read_rotation_list("1 0 0 0 1 0 0 0\n", "l.txt", &opts()).is_err());
    // JSON: syntax error with line; non-rotation named by edge; index out of range; self loop;
    // absurd num_rotations; unknown edge field
    let err = read_problem_json("{\"num_rotations\": 2,\n \"edges\": [\n {\"i\": 0, \"j\": 1, \"rotation\": [[1,0,0],[0,1,0]]}]}", "p.json", &opts()).unwrap_err();
    assert_eq!(location(&err), (Some("p.json".into()), Some(3)), "{err}");
    let id = "[[1,0,0],[0,1,0],[0,0,1]]";
    let json = |edges: &str, n: usize| format!("{{\"num_rotations\": {n}, \"edges\": [{edges}]}}");
    let bad = [
        (
            json(
                &format!(
                    "{{\"i\":0,\"j\":1,\"rotation\":{id}}}, {{\"i\":1,\"j\":2,\"rotation\":[[1,0,0],[0,1,0],[0,0,3]]}}"
                ),
                3,
            ),
            "edge 1",
        ),
        (
            json(
                &format!(
                    "{{\"i\":0,\"j\":1,\"rotation\":{id}}}, {{\"i\":1,\"j\":3,\"rotation\":{id}}}"
                ),
                3,
            ),
            "node 3",
        ),
        (
            json(
                &format!(
                    "{{\"i\":0,\"j\":1,\"rotation\":{id}}}, {{\"i\":1,\"j\":1,\"rotation\":{id}}}"
                ),
                3,
            ),
            "self loop",
        ),
        (
            json(
                &format!("{{\"i\":0,\"j\":1,\"rotation\":{id},\"weight\":-1}}"),
                2,
            ),
            "weight",
        ),
        (
            json(
                &format!("{{\"i\":0,\"j\":1,\"rotation\":{id},\"wieght\":2}}"),
                2,
            ),
            "wieght",
        ),
        (
            json(
                &format!("{{\"i\":0,\"j\":1,\"rotation\":{id}}}"),
                1_000_000_000_000,
            ),
            "num_rotations",
        ),
        (json("", 0), "empty"),
    ];
    for (text, needle) in &bad {
        let err = read_problem_json(text, "p.json", &opts()).expect_err(text);
        assert_eq!(location(&err).0.as_deref(), Some("p.json"), "{err}");
        assert!(err.to_string().contains(needle), "{err} lacks `{needle}`");
    }
    assert!(read_estimate("{}", "e.json", &opts()).is_err());
    assert!(read_estimate("{\"rotations\": []}", "e.json", &opts()).is_err());
    assert!(
        read_estimate(
            "{\"rotations\": [[[1,0,0],[0,1,0],[0,0,-1]]]}",
            "e.json",
            &opts()
        )
        .is_err()
    );
}

/// A disconnected graph loads (info reports it) but `require_connected` gives the typed error
/// with component sizes.
#[test]
fn disconnected_graph_is_reported() {
    let text = "EDGE_SE2 0 1 0 0 0\nEDGE_SE2 2 3 0 0 0\nEDGE_SE2 3 4 0 0 0\n";
    let g = read_g2o(text, "d.g2o", &opts()).unwrap();
    match g.problem.require_connected() {
        Err(Error::Disconnected { component_sizes }) => assert_eq!(component_sizes, vec![3, 2]),
        other => panic!("{other:?}"),
    }
}

/// Random mutations and truncations of valid files never panic (any Result is fine).
#[test]
fn fuzz_readers_never_panic() {
    let mut rng = StdRng::seed_from_u64(77);
    let (p, gt) = SyntheticGraph {
        num_rotations: 6,
        num_edges: 10,
        ..Default::default()
    }
    .generate();
    let g2o = write_g2o(&p, Some(&gt));
    let json = write_problem_json(&p);
    let egs = "0 1 1 0 0 0 1 0 0 0 1 1 0 0\n3 1 0 -1 0 1 0 0 0 0 1 1 0 0\n".to_string();
    let toro = "VERTEX3 0 0 0 0 0.1 0.2 0.3\nEDGE3 0 1 1 0 0 0.1 0.2 0.3\nEDGE3 1 2 1 0 0 0.1 0.2 0.3 10 0 0 0 0 0 10 0 0 0 0 10 0 0 0 100 0 0 100 0 25\nEDGE_SE2 2 3 0 0 1 1 0 0 1 0 1\n".to_string();
    let bundle =
        "# Bundle file v0.3\n1 1\n500 0 0\n1 0 0\n0 1 0\n0 0 1\n0 0 0\n1 2 3\n".to_string();
    let est = write_estimate_json(&gt);
    let pieces = [
        "",
        " ",
        "\n",
        "0",
        "-1",
        "nan",
        "1e308",
        "-0",
        "{",
        "}",
        "[",
        "]",
        ",",
        "\"",
        "EDGE3",
        "FIX",
        "99999999999999999999",
        "1.5",
        "x",
    ];
    for base in [&g2o, &json, &egs, &toro, &bundle, &est] {
        for _ in 0..600 {
            let mut s: Vec<char> = base.chars().collect();
            match rng.random_range(0..4) {
                0 => s.truncate(rng.random_range(0..=s.len())),
                1 => {
                    let k = rng.random_range(0..s.len());
                    s.remove(k);
                }
                2 => {
                    let k = rng.random_range(0..=s.len());
                    let piece = pieces[rng.random_range(0..pieces.len())];
                    for (n, c) in piece.chars().enumerate() {
                        s.insert(k + n, c);
                    }
                }
                _ => {
                    let k = rng.random_range(0..s.len());
                    s[k] = char::from(rng.random_range(32u8..127));
                }
            }
            let text: String = s.into_iter().collect();
            for fmt in [
                GraphFormat::Auto,
                GraphFormat::G2o,
                GraphFormat::OneDsfm,
                GraphFormat::Json,
            ] {
                let _ = read_graph(&text, "fuzz", fmt, &opts());
            }
            let _ = read_bundler(&text, "fuzz", &opts());
            let _ = read_rotation_list(&text, "fuzz", &opts());
            let _ = read_estimate(&text, "fuzz", &opts());
            if let Ok(g) = read_graph(&text, "fuzz", GraphFormat::Auto, &opts()) {
                let _ = rotavg::multiple::stats::graph_stats(
                    &g.problem,
                    g.initial.as_deref(),
                    &Default::default(),
                );
            }
        }
    }
}

/// Inputs that cannot be text are refused before they are read whole: a file above the size
/// limit from its size alone (a sparse file: no disk used), binary data from its first block.
/// A streamed view graph (g2o) has the larger limit, so a sparse file of zeros above the
/// whole-file limit is refused by its first block; a JSON one still from its size.
#[test]
fn oversized_and_binary_inputs_are_refused_early() {
    use rotavg::io::detect::{GraphFormat, ReadOptions, load_graph};
    use rotavg::io::text::{MAX_INPUT_BYTES, read_text};
    let dir =
        crate::common::scratch_root().join(format!("rotavg-io-limits-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let big = dir.join("big.g2o");
    let f = std::fs::File::create(&big).unwrap();
    f.set_len(MAX_INPUT_BYTES + 1).unwrap();
    let err = read_text(big.to_str().unwrap()).unwrap_err();
    assert!(err.to_string().contains("input limit"), "{err}");
    let err = load_graph(&big, GraphFormat::Auto, &ReadOptions::default()).unwrap_err();
    assert!(err.to_string().contains("NUL byte at offset 0"), "{err}");
    let big_json = dir.join("big.json");
    std::fs::rename(&big, &big_json).unwrap();
    let err = load_graph(&big_json, GraphFormat::Auto, &ReadOptions::default()).unwrap_err();
    assert!(err.to_string().contains("NUL byte at offset 0"), "{err}");
    // text in the first block, then a sparse tail: refused from the size, before reading it
    std::fs::write(&big_json, [b' '; 70_000]).unwrap();
    let f = std::fs::OpenOptions::new()
        .write(true)
        .open(&big_json)
        .unwrap();
    f.set_len(MAX_INPUT_BYTES + 1).unwrap();
    drop(f);
    let err = load_graph(&big_json, GraphFormat::Auto, &ReadOptions::default()).unwrap_err();
    assert!(
        err.to_string().contains("more than the input limit"),
        "{err}"
    );
    let zeros = dir.join("zeros.g2o");
    std::fs::write(&zeros, vec![0u8; 200_000]).unwrap();
    let err = read_text(zeros.to_str().unwrap()).unwrap_err().to_string();
    assert!(err.contains("NUL byte at offset 0"), "{err}");
    let latin1 = dir.join("latin1.g2o");
    std::fs::write(&latin1, b"# ok\n# caf\xe9\n").unwrap();
    let err = read_text(latin1.to_str().unwrap()).unwrap_err().to_string();
    assert!(err.contains(":2: not UTF-8"), "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Ground truth as `id R11 .. R33` lines (world-to-camera, the layout many rotation-averaging
/// tools write): matched to nodes by id, zeros and missing ids unknown, bad layouts refused
/// with the line.
#[test]
fn ground_truth_with_ids() {
    use rotavg::io::detect::{GraphFormat, ReadOptions, read_graph};
    use rotavg::io::input::read_ground_truth;
    use rotavg::so3::{angle_between, exp};
    let o = ReadOptions::default();
    // 1DSfM edges between file ids 2, 5 and 7 (nodes 0, 1, 2 in sorted id order)
    let graph = read_graph(
        "2 5 1 0 0 0 1 0 0 0 1\n5 7 1 0 0 0 1 0 0 0 1\n",
        "EGs.txt",
        GraphFormat::Auto,
        &o,
    )
    .unwrap();
    assert_eq!(graph.node_ids, [2, 5, 7]);
    let r = exp(&nalgebra::Vector3::new(0.1, -0.2, 0.3));
    let m = r.matrix();
    let row = |id: u64| {
        format!(
            "{id} {} {} {} {} {} {} {} {} {}\n",
            m[(0, 0)],
            m[(0, 1)],
            m[(0, 2)],
            m[(1, 0)],
            m[(1, 1)],
            m[(1, 2)],
            m[(2, 0)],
            m[(2, 1)],
            m[(2, 2)]
        )
    };
    let text = format!("# id R\n{}{}0 0 0 0 0 0 0 0 0 0\n", row(7), row(2));
    let truth = read_ground_truth(&text, "gt.txt", &graph, &o).unwrap();
    assert!(angle_between(&truth[0].unwrap(), &r) < 1e-12);
    assert!(truth[1].is_none()); // id 5 not listed
    assert!(angle_between(&truth[2].unwrap(), &r) < 1e-12);
    // mixed layouts, repeated ids, absurd ids: errors naming the line
    for (bad, line, what) in [
        (
            format!("{}1 0 0 0 1 0 0 0 1\n", row(2)),
            2,
            "expected 10 tokens",
        ),
        (format!("{}{}", row(2), row(2)), 2, "appears twice"),
        (row(1 << 40), 1, "larger than"),
    ] {
        let err = read_ground_truth(&bad, "gt.txt", &graph, &o)
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with(&format!("gt.txt:{line}:")) && err.contains(what),
            "{err}"
        );
    }
}
