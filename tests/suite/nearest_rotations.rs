//! `rotavg certify --nearest-rotations` (`rotavg::io::nearest`, `[D19]`): an estimate that is a
//! rotation set only approximately (orthogonal to 1e-6) or its mirror image (every det -1, as
//! a Burer-Monteiro rounding may return it) is certified at its nearest rotations, said in a
//! warning; without the option it is an error naming the option; reflections mixed with
//! rotations and matrices far from O(3) are refused. The cost the report states is checked
//! against the test's own cost of the test's own polar factors (SVD), and the verdict against
//! the planted optimum's.

use nalgebra::Matrix3;
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::multiple::{MultipleProblem, MultipleSettings, solve_multiple};

use crate::common;
use common::{assert_success, json_of, run, temp_file};

/// The polar factor of `m` with det +1, from nalgebra's SVD (independent of `so3`).
fn polar(m: &Matrix3<f64>) -> Matrix3<f64> {
    let svd = m.svd(true, true);
    let (u, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
    let mut d = Matrix3::identity();
    d[(2, 2)] = (u * vt).determinant().signum();
    u * d * vt
}

/// sum w ||R_j - R_ij R_i||_F^2, written here.
fn cost(p: &MultipleProblem, rs: &[Matrix3<f64>]) -> f64 {
    p.edges()
        .iter()
        .map(|e| e.weight * (rs[e.j] - e.rotation.matrix() * rs[e.i]).norm_squared())
        .sum()
}

/// A matrix as JSON rows.
fn rows(m: &Matrix3<f64>) -> String {
    let r: Vec<String> = (0..3)
        .map(|i| format!("[{:.17e},{:.17e},{:.17e}]", m[(i, 0)], m[(i, 1)], m[(i, 2)]))
        .collect();
    format!("[{}]", r.join(","))
}

fn json_of_matrices(ms: &[Matrix3<f64>]) -> String {
    let all: Vec<String> = ms.iter().map(rows).collect();
    format!(r#"{{"rotations":[{}]}}"#, all.join(","))
}

/// A noisy graph as a g2o-free JSON problem, its certified optimum, and a seeded perturbation
/// of size `eps` (not orthogonal) of each optimum matrix.
fn setup(name: &str) -> (MultipleProblem, String, Vec<Matrix3<f64>>) {
    let (p, _) = SyntheticGraph {
        num_rotations: 30,
        num_edges: 120,
        noise_sigma: 0.05,
        outlier_fraction: 0.0,
        seed: 11,
    }
    .generate();
    let sol = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let edges: Vec<String> = p
        .edges()
        .iter()
        .map(|e| {
            let r = rows(e.rotation.matrix());
            format!(
                r#"{{"i":{},"j":{},"rotation":{r},"weight":{}}}"#,
                e.i, e.j, e.weight
            )
        })
        .collect();
    let problem = temp_file(
        &format!("{name}.json"),
        &format!(r#"{{"num_rotations":30,"edges":[{}]}}"#, edges.join(",")),
    );
    let optimum = sol.rotations.iter().map(|r| *r.matrix()).collect();
    (p, problem.to_str().unwrap().to_string(), optimum)
}

/// The report's one `estimate_projected` warning.
fn projected_warning(j: &serde_json::Value) -> &serde_json::Value {
    let all = j["warnings"].as_array().unwrap();
    let mut it = all.iter().filter(|w| w["code"] == "estimate_projected");
    let w = it.next().expect("an estimate_projected warning");
    assert!(it.next().is_none());
    w
}

/// `m` times `(I + eps E)` for a fixed, non-orthogonal `E` varying with `k`.
fn skewed(m: &Matrix3<f64>, k: usize, eps: f64) -> Matrix3<f64> {
    let e = Matrix3::from_fn(|i, j| ((3 * i + j + 7 * k) % 5) as f64 - 2.0);
    m * (Matrix3::identity() + e * eps)
}

#[test]
fn a_mirrored_estimate_orthogonal_to_1e_6_is_certified_at_its_nearest_rotations() {
    let (p, problem, optimum) = setup("nearest_mirror");
    let given: Vec<Matrix3<f64>> = optimum
        .iter()
        .enumerate()
        .map(|(k, m)| -skewed(m, k, 1e-6))
        .collect();
    assert!(given.iter().all(|m| m.determinant() < 0.0));
    let est = temp_file("nearest_mirror_est.json", &json_of_matrices(&given));
    let est = est.to_str().unwrap();
    // without the option: an error naming it, no verdict
    let out = run(&["certify", &problem, "--estimate", est]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("det = -1.0") && err.contains("--nearest-rotations"),
        "{err}"
    );
    // with it: the negated polar factors are certified, and the report says so
    let out = run(&[
        "certify",
        &problem,
        "--estimate",
        est,
        "--nearest-rotations",
        "--json",
    ]);
    assert_success(&out);
    let j = json_of(&out);
    let projected: Vec<Matrix3<f64>> = given.iter().map(|m| polar(&-m)).collect();
    let want = cost(&p, &projected);
    let stated = j["cost"].as_f64().unwrap();
    assert!((stated - want).abs() <= 1e-12 * want, "{stated} vs {want}");
    // the optimum's own cost, independently: the projection moved each rotation by at most
    // about 4e-6 rad, which changes the cost at a critical point by second order only (the
    // Hessian's scale is the degree, about 8: 30 x 8 x (4e-6)^2 ~ 4e-9, against a cost ~ 1)
    let at_optimum = cost(&p, &optimum);
    assert!(
        (want - at_optimum).abs() <= 1e-7 * want,
        "{want} vs {at_optimum}"
    );
    assert_eq!(j["certificate"]["verdict"], "certified");
    let w = projected_warning(&j);
    assert_eq!(w["count"], 30);
    let message = w["message"].as_str().unwrap();
    assert!(message.contains("negated"), "{message}");
    // the text prints the same warning
    let text = run(&[
        "certify",
        &problem,
        "--estimate",
        est,
        "--nearest-rotations",
    ]);
    let flat = |s: &str| s.split_whitespace().collect::<Vec<_>>().join(" ");
    assert!(flat(&String::from_utf8_lossy(&text.stdout)).contains(&flat(message)));
}

#[test]
fn a_rotation_estimate_beyond_the_tolerance_is_projected_without_negation() {
    let (p, problem, optimum) = setup("nearest_plain");
    let given: Vec<Matrix3<f64>> = optimum
        .iter()
        .enumerate()
        .map(|(k, m)| skewed(m, k, 1e-4))
        .collect();
    let est = temp_file("nearest_plain_est.json", &json_of_matrices(&given));
    let est = est.to_str().unwrap();
    assert_eq!(
        run(&["certify", &problem, "--estimate", est]).status.code(),
        Some(1)
    );
    let out = run(&[
        "certify",
        &problem,
        "--estimate",
        est,
        "--nearest-rotations",
        "--json",
    ]);
    assert_success(&out);
    let j = json_of(&out);
    let projected: Vec<Matrix3<f64>> = given.iter().map(polar).collect();
    let want = cost(&p, &projected);
    assert!((j["cost"].as_f64().unwrap() - want).abs() <= 1e-12 * want);
    let message = projected_warning(&j)["message"].as_str().unwrap();
    assert!(!message.contains("negated"), "{message}");
}

#[test]
fn mixed_reflections_and_matrices_far_from_o3_are_refused() {
    let (_, problem, optimum) = setup("nearest_bad");
    let mut mixed = optimum.clone();
    mixed[3] = -mixed[3];
    let mut far = optimum.clone();
    far[5] *= 1.5;
    for (name, given, says) in [
        ("mixed", mixed, "1 of its 30 matrices are reflections"),
        ("far", far, "rotation 5 is no estimate of a rotation"),
    ] {
        let est = temp_file(&format!("nearest_{name}.json"), &json_of_matrices(&given));
        let out = run(&[
            "certify",
            &problem,
            "--estimate",
            est.to_str().unwrap(),
            "--nearest-rotations",
        ]);
        assert_eq!(out.status.code(), Some(1), "{name}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(says), "{name}: {err}");
    }
}
