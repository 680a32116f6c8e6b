//! Hand-eye readers: conventions on noise-free synthetic files (cost 0 at the planted S), error
//! locations, and the real Tabb / ETH data (skipped when /work/shared/data is absent).

use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::Error;
use rotavg::conjugate::{ConjugateSettings, solve_conjugate};
use rotavg::io::handeye::{
    MotionSettings, eth_problem, read_conjugate_json, read_eth_csv, read_eth_dir, read_tabb_camera,
    read_tabb_dir, read_tabb_robot, tabb_problem, write_conjugate_json,
};
use rotavg::so3::{Rotation, angle_between, random_rotation, rotation_from_rows};
use std::path::{Path, PathBuf};

fn data_dir() -> Option<PathBuf> {
    let a = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    let b = PathBuf::from("/work/shared/data");
    [a, b].into_iter().find(|p| p.join("handeye").is_dir())
}

fn mat4_text(r: &Rotation, t: [f64; 3]) -> String {
    let m = r.matrix();
    let mut s = String::new();
    for i in 0..3 {
        s += &format!(
            "{:.15} {:.15} {:.15} {:.6}\n",
            m[(i, 0)],
            m[(i, 1)],
            m[(i, 2)],
            t[i]
        );
    }
    s + "0 0 0 1\n\n"
}

#[test]
fn tabb_convention_noise_free_cost_zero() {
    // A_i X = Z B_i exactly (data README 3.4); then (A_j A_i^-1) Z = Z (B_j B_i^-1) and the
    // problem's cost at S = rot(Z) is 0.
    let mut rng = StdRng::seed_from_u64(21);
    let (x, z) = (random_rotation(&mut rng), random_rotation(&mut rng));
    let n = 6;
    let bs: Vec<_> = (0..n).map(|_| random_rotation(&mut rng)).collect();
    let mut robot = format!("{n}\n");
    let mut cam = format!("{n}\n");
    for (k, b) in bs.iter().enumerate() {
        robot += &mat4_text(b, [1.0, 2.0, 3.0]);
        let a = z * b * x.inverse();
        let m = a.matrix();
        let rot: Vec<String> = (0..3)
            .flat_map(|i| (0..3).map(move |j| format!("{:.15}", m[(i, j)])))
            .collect();
        cam += &format!(
            "image{k}.png  1 0 1 0 1 1 0 0 1 {} 1 2 3 0 0 0 0 0 0 0 0\n",
            rot.join(" ")
        );
    }
    let r = read_tabb_robot(&robot, "robot_cali.txt", 1e-9).unwrap();
    let c = read_tabb_camera(&cam, "cali.txt", 1e-9).unwrap();
    let (p, stats) = tabb_problem(&r, &c, &MotionSettings::default()).unwrap();
    assert_eq!(stats.pairs + stats.skipped_small, n * (n - 1) / 2);
    assert!(
        p.chordal_cost(&z) < 1e-20,
        "cost at Z {}",
        p.chordal_cost(&z)
    );
    let sol = solve_conjugate(&p, &ConjugateSettings::default()).unwrap();
    assert!(angle_between(&sol.estimate, &z) < 1e-9);
}

#[test]
fn eth_convention_noise_free_cost_zero() {
    // E_j = W H_j X gives (H_i^-1 H_j) X = X (E_i^-1 E_j): cost 0 at S = X.
    let mut rng = StdRng::seed_from_u64(22);
    let (w, x) = (random_rotation(&mut rng), random_rotation(&mut rng));
    let mut hand = String::new();
    let mut cam = String::new();
    for k in 0..200 {
        let t = 100.0 + 0.02 * k as f64;
        let h = rotavg::so3::exp(&nalgebra::Vector3::new(
            0.7 * (t * 0.9).sin(),
            0.5 * (t * 1.3).cos(),
            0.3 * t,
        ));
        let e = w * h * x;
        let qh = nalgebra::UnitQuaternion::from_rotation_matrix(&h);
        let qe = nalgebra::UnitQuaternion::from_rotation_matrix(&e);
        hand += &format!(
            "{t}, 0, 0, 0, {:.17}, {:.17}, {:.17}, {:.17}\n",
            qh.i, qh.j, qh.k, qh.w
        );
        cam += &format!(
            "{t}, 1, 1, 1, {:.17}, {:.17}, {:.17}, {:.17}\n",
            qe.i, qe.j, qe.k, qe.w
        );
    }
    let h = read_eth_csv(&hand, "hand.csv", 1e-9).unwrap();
    let e = read_eth_csv(&cam, "cam.csv", 1e-9).unwrap();
    let (p, stats) = eth_problem(&h, &e, &MotionSettings::default()).unwrap();
    assert!(stats.pairs > 20);
    assert!(
        p.chordal_cost(&x) < 1e-20,
        "cost at X {}",
        p.chordal_cost(&x)
    );
}

#[test]
fn parse_errors_name_file_and_line() {
    let bad = "2\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n\n1 0 0 0\n0 1 x 0\n";
    match read_tabb_robot(bad, "robot_cali.txt", 1e-6) {
        Err(Error::Parse { location, .. }) => {
            assert_eq!(location.file.as_deref(), Some("robot_cali.txt"));
            assert_eq!(location.line, Some(8));
        }
        other => panic!("{other:?}"),
    }
    let notrot = "1\n1 0 0 0\n0 2 0 0\n0 0 1 0\n0 0 0 1\n";
    assert!(matches!(
        read_tabb_robot(notrot, "r.txt", 1e-6),
        Err(Error::Parse { .. })
    ));
    let csv = "1.0, 0, 0, 0, 0, 0, 0, 1\n0.5, 0, 0, 0, 0, 0, 0, 1\n";
    match read_eth_csv(csv, "a.csv", 1e-6) {
        Err(Error::Parse { location, .. }) => assert_eq!(location.line, Some(2)),
        other => panic!("{other:?}"),
    }
    let json = "{\"pairs\": [\n {\"left\": [[1,0,0],[0,1,0],[0,0,1]], \"right\": [[1,0,0],[0,1,0],[0,0,2]]}\n]}";
    match read_conjugate_json(json, "p.json") {
        Err(Error::Parse { location, .. }) => assert_eq!(location.line, Some(2)),
        other => panic!("{other:?}"),
    }
}

#[test]
fn conjugate_json_round_trip() {
    let mut rng = StdRng::seed_from_u64(23);
    let (p, _) = rotavg::conjugate::synthetic::random_instance(5, 0.1, 0.0, &mut rng);
    let text = write_conjugate_json(&p);
    let q = read_conjugate_json(&text, "x.json").unwrap();
    assert_eq!(q.num_pairs(), 5);
    for (a, b) in p.pairs().iter().zip(q.pairs()) {
        assert!(
            angle_between(&a.left, &b.left) < 1e-12 && angle_between(&a.right, &b.right) < 1e-12
        );
    }
    // weight optional
    let q = read_conjugate_json(
        r#"{"pairs":[{"left":[[1,0,0],[0,1,0],[0,0,1]],"right":[[1,0,0],[0,1,0],[0,0,1]]}]}"#,
        "y",
    )
    .unwrap();
    assert_eq!(q.pairs()[0].weight, 1.0);
}

#[test]
fn real_tabb_residuals() {
    let Some(dir) = data_dir() else {
        println!("skipping: shared data not found");
        return;
    };
    let dir = dir.join("handeye/tabb_rwhe_dataset1");
    let set = MotionSettings {
        min_angle: 0.0,
        ..Default::default()
    };
    let (all, stats) = read_tabb_dir(&dir, &set).unwrap();
    // 88 stations -> 88*87/2 = 3828 pairs (data README 3.4).
    assert_eq!(stats.poses, 88);
    assert_eq!(all.num_pairs(), 3828);
    // Tabb's reference Z (reference_rwhe_AA_RPI_transformations.txt): the README reports a
    // median residual of 0.43 deg over all 3828 pairs.
    let z = rotation_from_rows(
        &[
            [0.997365, -0.0725279, 0.00171889],
            [0.072544, 0.997283, -0.0128158],
            [-0.000784715, 0.0129068, 0.999916],
        ],
        1e-5,
        "Z",
    )
    .unwrap();
    let med = |v: Vec<f64>| {
        let mut v = v;
        v.sort_by(f64::total_cmp);
        v[v.len() / 2].to_degrees()
    };
    let ref_median = med(all.residual_angles(&z));
    println!("Tabb: median residual at reference Z {ref_median:.3} deg");
    assert!((ref_median - 0.43).abs() < 0.03);
    let (p, stats) = read_tabb_dir(&dir, &MotionSettings::default()).unwrap();
    println!(
        "Tabb: {} pairs kept, {} skipped (angle < 0.57 deg)",
        stats.pairs, stats.skipped_small
    );
    let sol = solve_conjugate(&p, &ConjugateSettings::default()).unwrap();
    let our_median = med(all.residual_angles(&sol.estimate));
    println!(
        "Tabb: chordal estimate cost {:.6}, {} from reference Z {:.3} deg, median residual {our_median:.3} deg (cost at reference {:.6})",
        sol.cost,
        sol.report,
        angle_between(&sol.estimate, &z).to_degrees(),
        p.chordal_cost(&z)
    );
    assert!(sol.cost <= p.chordal_cost(&z));
    assert!(our_median < 0.6);
    assert!(angle_between(&sol.estimate, &z).to_degrees() < 1.0);
}

#[test]
fn real_eth_residuals() {
    let Some(dir) = data_dir() else {
        println!("skipping: shared data not found");
        return;
    };
    let (p, stats) = read_eth_dir(
        &dir.join("handeye/ethz_robot_arm_real"),
        &MotionSettings::default(),
    )
    .unwrap();
    let sol = solve_conjugate(&p, &ConjugateSettings::default()).unwrap();
    let mut r = p.residual_angles(&sol.estimate);
    r.sort_by(f64::total_cmp);
    let med = r[r.len() / 2].to_degrees();
    println!(
        "ETH: {} matched samples, {} pairs ({} skipped), median residual {med:.3} deg, cost {:.6}",
        stats.poses, stats.pairs, stats.skipped_small, sol.cost
    );
    // data README 3.4: median 0.6 deg with nearest-timestamp matching; interpolation does no worse.
    assert!(med < 1.0);
}

/// Regression: a truncated Tabb robot file used to give an error without a line number.
#[test]
fn truncated_tabb_file_error_names_the_last_line() {
    let text = "2\n1 0 0 0\n0 1 0 0\n0 0 1 0\n0 0 0 1\n\n1 0 0 0\n";
    let err = read_tabb_robot(text, "robot_cali.txt", 1e-6).unwrap_err();
    let msg = err.to_string();
    assert!(msg.starts_with("robot_cali.txt:7: "), "{msg}");
}
