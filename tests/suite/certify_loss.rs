//! `rotavg certify --loss l1|huber|cauchy` (`rotavg::pipeline::certify_estimate_inliers`): an
//! estimate computed elsewhere judged on the chordal L2 problem of its own inlier graph,
//! unchanged. Checked against planted truth (noise-free inliers: the truth is optimal on them),
//! against the same certification of the inlier problem written out by the test itself, under
//! weight scaling, and on bad requests.

use rotavg::certify::{CertifiedProblemKind, CertifySettings};
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::multiple::{Edge, MultipleProblem};
use rotavg::pipeline::certify_estimate_inliers;
use rotavg::so3::angle_between;
use rotavg::{Rotation, Verdict};

use crate::common;
use common::{json_of, run, scale_weights, temp_file};

fn rotation_json(r: &Rotation) -> String {
    let m = r.matrix();
    let rows: Vec<String> = (0..3)
        .map(|i| format!("[{:.17e},{:.17e},{:.17e}]", m[(i, 0)], m[(i, 1)], m[(i, 2)]))
        .collect();
    format!("[{}]", rows.join(","))
}

/// The problem as a JSON problem file (contract section 5), written here from its edges.
fn problem_json(n: usize, edges: &[Edge]) -> String {
    let edges: Vec<String> = edges
        .iter()
        .map(|e| {
            format!(
                r#"{{"i":{},"j":{},"rotation":{},"weight":{:.17e}}}"#,
                e.i,
                e.j,
                rotation_json(&e.rotation),
                e.weight
            )
        })
        .collect();
    format!(r#"{{"num_rotations":{n},"edges":[{}]}}"#, edges.join(","))
}

fn estimate_json(rs: &[Rotation]) -> String {
    let rs: Vec<String> = rs.iter().map(rotation_json).collect();
    format!(r#"{{"rotations":[{}]}}"#, rs.join(","))
}

/// The residual angle of every edge at `rs` (degrees), computed here: angle(R_ij R_i, R_j).
fn residuals_deg(p: &MultipleProblem, rs: &[Rotation]) -> Vec<f64> {
    p.edges()
        .iter()
        .map(|e| angle_between(&(e.rotation * rs[e.i]), &rs[e.j]).to_degrees())
        .collect()
}

fn files(name: &str, p: &MultipleProblem, rs: &[Rotation]) -> (String, String) {
    let problem = temp_file(
        &format!("{name}.json"),
        &problem_json(p.num_rotations(), p.edges()),
    );
    let estimate = temp_file(&format!("{name}_estimate.json"), &estimate_json(rs));
    (
        problem.to_str().unwrap().to_string(),
        estimate.to_str().unwrap().to_string(),
    )
}

#[test]
fn the_truth_of_noise_free_inliers_is_certified_on_its_inlier_graph_only() {
    let (p, truth, planted) = SyntheticGraph {
        num_rotations: 30,
        num_edges: 150,
        noise_sigma: 0.0,
        outlier_fraction: 0.2,
        seed: 7,
    }
    .generate_labelled();
    // the expected inlier set, from the geometry: the planted inliers (residual 0) and any
    // random outlier that happens to fall within 5 degrees
    let expected = residuals_deg(&p, &truth)
        .iter()
        .filter(|&&d| d <= 5.0)
        .count();
    assert!(expected >= planted.iter().filter(|&&b| b).count());
    assert!(expected < p.num_edges(), "outliers were planted");
    let (problem, estimate) = files("certify_loss_truth", &p, &truth);
    let args = ["certify", &problem, "--estimate", &estimate, "--json"];

    let robust = run(&[&args[..], &["--loss", "cauchy", "--require-certified"]].concat());
    assert_eq!(robust.status.code(), Some(0), "{robust:?}");
    let j = json_of(&robust);
    assert_eq!(j["loss"], "cauchy");
    assert_eq!(j["verdict"]["verdict"], "certified");
    assert_eq!(j["verdict"]["estimate"], "given");
    assert_eq!(j["verdict"]["problem"]["kind"], "chordal_l2_inliers");
    assert_eq!(j["verdict"]["problem"]["num_edges"], expected);
    assert_eq!(j["inlier_graph"]["residuals"]["num_inliers"], expected);
    assert!(j["inlier_graph"]["chordal_cost"].as_f64().unwrap() < 1e-20);
    // the all-edges certificate is still reported, and it is not a certificate
    assert_ne!(j["certificate"]["verdict"], "certified");
    // the estimate is returned unchanged
    let given = &j["estimate"][3][1][2];
    assert_eq!(given.as_f64().unwrap(), truth[3].matrix()[(1, 2)]);

    let whole = run(&[&args[..], &["--require-certified"]].concat());
    assert_eq!(whole.status.code(), Some(3), "{whole:?}");
    let j = json_of(&whole);
    assert_eq!(j["verdict"]["problem"]["kind"], "chordal_l2");
    assert!(j.get("inlier_graph").is_none() && j.get("loss").is_none());
}

#[test]
fn the_inlier_certificate_is_that_of_the_inlier_problem_written_out() {
    let (p, truth, _) = SyntheticGraph {
        num_rotations: 40,
        num_edges: 240,
        noise_sigma: (1.0f64).to_radians(),
        outlier_fraction: 0.2,
        seed: 3,
    }
    .generate_labelled();
    let residual = residuals_deg(&p, &truth);
    let inliers: Vec<Edge> = p
        .edges()
        .iter()
        .zip(&residual)
        .filter(|(_, d)| **d <= 5.0)
        .map(|(e, _)| e.clone())
        .collect();
    let sub = MultipleProblem::new(p.num_rotations(), inliers).expect("inliers");
    assert_eq!(sub.components().len(), 1, "the inliers connect every node");
    let (problem, estimate) = files("certify_loss_noisy", &p, &truth);
    let (sub_problem, _) = files("certify_loss_noisy_inliers", &sub, &truth);

    let robust = json_of(&run(&[
        "certify",
        &problem,
        "--estimate",
        &estimate,
        "--loss",
        "huber",
        "--json",
    ]));
    let direct = json_of(&run(&[
        "certify",
        &sub_problem,
        "--estimate",
        &estimate,
        "--json",
    ]));
    let g = &robust["inlier_graph"];
    assert_eq!(g["problem"]["num_edges"], sub.num_edges());
    assert_eq!(
        g["certificate"]["verdict"],
        direct["certificate"]["verdict"]
    );
    for key in ["upper_bound", "lower_bound"] {
        let (a, b) = (
            g["certificate"][key].as_f64().unwrap(),
            direct["certificate"][key].as_f64().unwrap(),
        );
        assert!(
            (a - b).abs() <= 1e-9 * b.abs().max(1.0),
            "{key}: {a} vs {b}"
        );
    }
    // the truth of noisy data is not optimal: an honest gap, never a certificate
    assert_eq!(robust["verdict"]["verdict"], "gap_reported");
}

#[test]
fn scaling_all_weights_changes_neither_the_inlier_set_nor_the_verdict() {
    let (p, truth) = SyntheticGraph {
        num_rotations: 25,
        num_edges: 120,
        noise_sigma: 0.0,
        outlier_fraction: 0.25,
        seed: 11,
    }
    .generate();
    let judge = |p: &MultipleProblem| {
        certify_estimate_inliers(p, &truth, 5.0, &CertifySettings::default())
            .expect("certifies")
            .expect("some inliers")
    };
    let base = judge(&p);
    assert_eq!(base.certificate.verdict, Verdict::Certified);
    assert_eq!(base.problem.kind, CertifiedProblemKind::ChordalL2Inliers);
    for c in [1e-6, 1e6] {
        let g = judge(&scale_weights(&p, c));
        assert_eq!(g.certificate.verdict, base.certificate.verdict, "scale {c}");
        assert_eq!(g.problem, base.problem, "scale {c}");
        assert_eq!(g.nodes, base.nodes);
    }
}

#[test]
fn without_an_inlier_edge_only_the_whole_problem_is_judged() {
    let (p, truth) = SyntheticGraph {
        num_rotations: 10,
        num_edges: 30,
        noise_sigma: 0.05,
        ..Default::default()
    }
    .generate();
    let (problem, estimate) = files("certify_loss_none", &p, &truth);
    let args = ["certify", &problem, "--estimate", &estimate, "--loss", "l1"];
    let out = run(&[&args[..], &["--inlier-threshold", "1e-9", "--json"]].concat());
    let j = json_of(&out);
    assert!(j.get("inlier_graph").is_none());
    assert_eq!(j["verdict"]["problem"]["kind"], "chordal_l2");
    let text = run(&[&args[..], &["--inlier-threshold", "1e-9"]].concat());
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.contains("no edge is an inlier"), "{text}");
}

#[test]
fn requests_it_cannot_answer_are_refused_by_name() {
    let (p, truth) = SyntheticGraph {
        num_rotations: 6,
        num_edges: 12,
        ..Default::default()
    }
    .generate();
    let (problem, estimate) = files("certify_loss_refused", &p, &truth);
    let single = temp_file(
        "certify_loss_single.json",
        &format!(
            r#"{{"rotations": [{}, {}]}}"#,
            common::rz_json(0.1),
            common::rz_json(0.2)
        ),
    );
    let single_estimate = temp_file(
        "certify_loss_single_estimate.json",
        &format!(
            r#"{{"rotation": {}}}"#,
            rotation_json(&Rotation::identity())
        ),
    );
    let (single, single_estimate) = (single.to_str().unwrap(), single_estimate.to_str().unwrap());
    let graph = ["certify", problem.as_str(), "--estimate", estimate.as_str()];
    let cases: [(Vec<&str>, &str); 3] = [
        ([&graph[..], &["--loss", "auto"]].concat(), "not with auto"),
        (
            [&graph[..], &["--loss", "cauchy", "--inlier-threshold", "0"]].concat(),
            "inlier_threshold",
        ),
        (
            vec![
                "certify",
                single,
                "--estimate",
                single_estimate,
                "--loss",
                "huber",
            ],
            "view graphs",
        ),
    ];
    for (args, words) in cases {
        let out = run(&args);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {out:?}");
        assert!(out.stdout.is_empty(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(words), "{args:?}: {err}");
    }
}
