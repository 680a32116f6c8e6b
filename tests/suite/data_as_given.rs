//! The numbers are those of the data as given (contract section 3, issue 24): a matrix accepted within
//! the validation tolerance (1e-5) but not exactly orthogonal is kept, and every reported cost
//! and proven lower bound is that of the file's matrices, never of their projections onto SO(3).
//! Costs and minima are recomputed here from their definitions with nalgebra, independently of
//! the crate.

use nalgebra::Matrix3;
use rand::SeedableRng;
use rand::rngs::StdRng;
use serde_json::Value;

use crate::common;
use common::{assert_success, json_of, run, temp_file};

/// 1 - 2.8e-6: `||(cR)^T (cR) - I||_F = 2.8e-6 (2 - 2.8e-6) sqrt(3) ~ 9.7e-6`, inside the
/// validation tolerance 1e-5.
const SCALE: f64 = 1.0 - 2.8e-6;

fn rows(m: &Matrix3<f64>) -> String {
    let r: Vec<Vec<f64>> = (0..3)
        .map(|i| (0..3).map(|j| m[(i, j)]).collect())
        .collect();
    serde_json::to_string(&r).unwrap()
}

fn matrix(v: &Value) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| v[i][j].as_f64().expect("a number"))
}

fn f(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number in {v}"))
}

/// Single chordal L2 of 20 samples scaled by `1 - 2.8e-6`: the reported cost is
/// `sum ||R_i - R||_F^2` of the file's matrices, and the proven lower bound is at most the exact
/// minimum of that cost, `sum ||R_i||_F^2 + 3n - 2 (s1 + s2 + sign(det M) s3)` (SVD of
/// `M = sum R_i`), which is also where the cost of the answer lies.
#[test]
fn single_chordal_l2_is_the_files_cost() {
    let mut rng = StdRng::seed_from_u64(3);
    let centre = rotavg::so3::random_rotation(&mut rng);
    let samples: Vec<Matrix3<f64>> = (0..20)
        .map(|_| rotavg::so3::perturb_gaussian(&centre, 0.2, &mut rng).matrix() * SCALE)
        .collect();
    let text = format!(
        "{{\"rotations\": [{}]}}",
        samples.iter().map(rows).collect::<Vec<_>>().join(", ")
    );
    let path = temp_file("scaled_single.json", &text);
    let out = run(&["single", path.to_str().unwrap(), "--json"]);
    assert_success(&out);
    let v = json_of(&out);
    let r = matrix(&v["estimate"]);
    let cost: f64 = samples.iter().map(|a| (a - r).norm_squared()).sum();
    let m: Matrix3<f64> = samples.iter().sum();
    let mut s: Vec<f64> = m.singular_values().iter().copied().collect();
    s.sort_by(|a, b| b.total_cmp(a));
    let sign = m.determinant().signum();
    let norms: f64 = samples.iter().map(|a| a.norm_squared()).sum();
    let minimum = norms + 60.0 - 2.0 * (s[0] + s[1] + sign * s[2]);
    assert!(
        (f(&v, "cost") - cost).abs() <= 1e-12 * cost,
        "{} vs {cost}",
        v["cost"]
    );
    assert!(
        (cost - minimum).abs() <= 1e-12 * cost,
        "{cost} vs minimum {minimum}"
    );
    let c = &v["certificate"];
    assert_eq!(c["verdict"], "certified", "{c}");
    let lb = f(c, "lower_bound");
    assert!(
        lb <= minimum + 1e-14 * minimum,
        "bound {lb} above the minimum {minimum}"
    );
    // the projected problem's minimum is higher by about 2.8e-6 relative: a bound of it would
    // have been 'proven' above the file's minimum
    let projected_norms = 60.0;
    assert!(projected_norms - norms > 2e-6 * minimum);
}

/// An 8-node view graph whose measurements are scaled by `1 - 2.8e-6`: the reported cost is
/// `sum ||R_j - R_ij R_i||_F^2` of the file's matrices at the reported estimate, and the proven
/// lower bound is at most that cost (the minimum is at most the cost of any point).
#[test]
fn multiple_chordal_l2_is_the_files_cost() {
    let mut rng = StdRng::seed_from_u64(8);
    let truth: Vec<Matrix3<f64>> = (0..8)
        .map(|_| *rotavg::so3::random_rotation(&mut rng).matrix())
        .collect();
    let mut edges = Vec::new();
    let mut measured = Vec::new();
    for (i, j) in [
        (0, 1),
        (1, 2),
        (2, 3),
        (3, 4),
        (4, 5),
        (5, 6),
        (6, 7),
        (7, 0),
        (0, 4),
        (2, 6),
        (1, 5),
    ] {
        let exact = rotavg::Rotation::from_matrix_unchecked(truth[j] * truth[i].transpose());
        let noisy = rotavg::so3::perturb_gaussian(&exact, 0.05, &mut rng).matrix() * SCALE;
        edges.push(format!(
            "{{\"i\": {i}, \"j\": {j}, \"rotation\": {}}}",
            rows(&noisy)
        ));
        measured.push((i, j, noisy));
    }
    let text = format!(
        "{{\"num_rotations\": 8, \"edges\": [{}]}}",
        edges.join(", ")
    );
    let path = temp_file("scaled_multiple.json", &text);
    let out = run(&["multiple", path.to_str().unwrap(), "--json"]);
    assert_success(&out);
    let v = json_of(&out);
    let est: Vec<Matrix3<f64>> = v["estimate"]
        .as_array()
        .unwrap()
        .iter()
        .map(matrix)
        .collect();
    let cost: f64 = measured
        .iter()
        .map(|(i, j, r)| (est[*j] - r * est[*i]).norm_squared())
        .sum();
    assert!(
        (f(&v, "cost") - cost).abs() <= 1e-12 * cost,
        "{} vs {cost}",
        v["cost"]
    );
    let c = &v["certificate"];
    assert_eq!(c["verdict"], "certified", "{c}");
    assert!(f(c, "lower_bound") <= cost, "{c}");
    assert!(cost - f(c, "lower_bound") <= 1e-6 * cost, "{c}");

    // `certify` of an estimate whose rotations are scaled too: its cost is of those matrices
    let scaled: Vec<Matrix3<f64>> = est.iter().map(|r| r * SCALE).collect();
    let estimate = format!(
        "{{\"rotations\": [{}]}}",
        scaled.iter().map(rows).collect::<Vec<_>>().join(", ")
    );
    let est_path = temp_file("scaled_estimate.json", &estimate);
    let out = run(&[
        "certify",
        path.to_str().unwrap(),
        "--estimate",
        est_path.to_str().unwrap(),
        "--json",
    ]);
    assert_success(&out);
    let w = json_of(&out);
    let given: f64 = measured
        .iter()
        .map(|(i, j, r)| (scaled[*j] - r * scaled[*i]).norm_squared())
        .sum();
    assert!(
        (f(&w, "cost") - given).abs() <= 1e-12 * given,
        "{} vs {given}",
        w["cost"]
    );
    let lb = f(&w["certificate"], "lower_bound");
    assert!(
        lb <= cost + 1e-15,
        "bound {lb} above the cost {cost} of a point"
    );
}
