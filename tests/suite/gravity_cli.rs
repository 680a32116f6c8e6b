//! `--gravity` on the command line (`multiple`, `certify`): the committed example
//! (`examples/data/gravity/`), the file forms of the priors (`[F15]`), the convention warning,
//! and the errors, with their line numbers.

use crate::common::{assert_success, json_of, run, temp_file};
use std::path::Path;

fn example(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("examples/data/gravity")
        .join(name)
        .display()
        .to_string()
}

/// The priors of the example with every direction replaced by `f(g)` (text form).
fn priors_with(f: impl Fn([f64; 3]) -> [f64; 3]) -> String {
    let text = std::fs::read_to_string(example("gravity.txt")).unwrap();
    let mut out = String::new();
    for l in text.lines().filter(|l| !l.starts_with('#')) {
        let p: Vec<&str> = l.split_whitespace().collect();
        let g = [0, 1, 2].map(|k| p[k + 1].parse::<f64>().unwrap());
        let h = f(g);
        out += &format!("{} {} {} {}\n", p[0], h[0], h[1], h[2]);
    }
    out
}

/// The example: the priors make the estimate more accurate against the truth, the verdict
/// names the gravity problem, and the mixed problem is certified (`[G12]`).
#[test]
fn gravity_improves_the_example_and_names_its_problem() {
    let (graph, truth) = (example("graph.json"), example("truth.txt"));
    let args = ["multiple", &graph, "--ground-truth", &truth, "--json"];
    let without = run(&args);
    assert_success(&without);
    let gravity = example("gravity.txt");
    let with = run(&[&args[..], &["--gravity", &gravity]].concat());
    assert_success(&with);
    let (a, b) = (json_of(&without), json_of(&with));
    let mean = |v: &serde_json::Value| v["accuracy"]["mean_deg"].as_f64().unwrap();
    assert!(mean(&b) < 0.9 * mean(&a), "{} vs {}", mean(&b), mean(&a));
    assert_eq!(b["verdict"]["problem"]["kind"], "chordal_l2_gravity");
    let g = &b["pipeline"]["gravity"];
    assert_eq!(
        (g["kind"].as_str(), g["num_with_prior"].as_u64()),
        (Some("mixed"), Some(178))
    );
    // R_ij g_i vs g_j: 2 degrees of noise per axis on the edges, 0.5 on the priors
    assert!(g["check"]["median_deg"].as_f64().unwrap() < 5.0);
    assert!(
        b["warnings"].as_array().unwrap().is_empty(),
        "{}",
        b["warnings"]
    );
    // the mixed problem is certified by the tilted surrogate [G12], above the free optimum
    assert_eq!(b["certificate"]["verdict"], "certified");
    let lb = b["certificate"]["lower_bound"].as_f64().unwrap();
    assert!(lb > a["cost"].as_f64().unwrap() && lb <= b["cost"].as_f64().unwrap());
}

/// The warnings' codes of `multiple --gravity PRIORS` on the example.
fn warning_codes(priors: &str) -> (Vec<String>, serde_json::Value) {
    let graph = example("graph.json");
    let out = run(&["multiple", &graph, "--gravity", priors, "--json"]);
    assert_success(&out);
    let w = json_of(&out)["warnings"].clone();
    let codes = w
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["code"].as_str().unwrap().to_string())
        .collect();
    (codes, w)
}

/// Priors in phone landscape axes (x and y swapped, z negated) are named as such: the edges'
/// `R_ij g_i` and `g_j` disagree as given and agree in that convention. The example's cameras
/// are upright (turns about their y axis), so priors written with OpenGL axes (y up, z
/// backward) or as up vectors agree with the edges: they are said to point up the image.
#[test]
fn convention_mistakes_are_named() {
    let swapped = temp_file("swap.txt", &priors_with(|g| [g[1], g[0], -g[2]]));
    let (codes, w) = warning_codes(swapped.to_str().unwrap());
    assert_eq!(codes, ["gravity_convention"], "{w}");
    assert!(
        w[0]["message"]
            .as_str()
            .unwrap()
            .contains("x and y swapped"),
        "{w}"
    );
    for flip in [[1.0, -1.0, -1.0], [-1.0, -1.0, -1.0]] {
        let up = temp_file(
            "up.txt",
            &priors_with(|g| [0, 1, 2].map(|k| flip[k] * g[k])),
        );
        let (codes, w) = warning_codes(up.to_str().unwrap());
        assert_eq!(codes, ["gravity_points_up"], "{w}");
    }
}

/// Full gravity from a JSON list: certified by the SO(2) certificate, and `certify --gravity`
/// certifies the written estimate; an estimate off its priors is refused.
#[test]
fn full_gravity_is_certified_and_certify_reads_priors() {
    let graph = example("graph.json");
    let truth = std::fs::read_to_string(example("truth.txt")).unwrap();
    // exact priors R_i e_3 from the truth (third column of each R_i)
    let list: Vec<String> = truth
        .lines()
        .filter(|l| !l.starts_with('#'))
        .map(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .skip(1)
                .map(|x| x.parse().unwrap())
                .collect();
            format!("[{}, {}, {}]", v[2], v[5], v[8])
        })
        .collect();
    let priors = temp_file(
        "full.json",
        &format!("{{\"gravity\": [{}]}}", list.join(", ")),
    );
    let priors = priors.to_str().unwrap();
    let est = crate::common::temp_dir().join("full_estimate.json");
    let est = est.to_str().unwrap();
    let out = run(&[
        "multiple",
        &graph,
        "--gravity",
        priors,
        "--output",
        est,
        "--json",
    ]);
    assert_success(&out);
    let v = json_of(&out);
    assert_eq!(v["verdict"]["verdict"], "certified", "{}", v["certificate"]);
    assert_eq!(v["pipeline"]["gravity"]["kind"], "full");
    let out = run(&[
        "certify",
        &graph,
        "--estimate",
        est,
        "--gravity",
        priors,
        "--json",
    ]);
    assert_success(&out);
    let c = json_of(&out);
    assert_eq!(c["verdict"]["verdict"], "certified");
    assert_eq!(c["verdict"]["problem"]["kind"], "chordal_l2_gravity");
    // the unconstrained estimate is not a point of the gravity problem
    let free = crate::common::temp_dir().join("free.json");
    let free = free.to_str().unwrap();
    assert_success(&run(&["multiple", &graph, "--output", free, "--quiet"]));
    let out = run(&["certify", &graph, "--estimate", free, "--gravity", priors]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("off its gravity priors"));
}

/// Keyed JSON, unmatched keys counted; bad lines named; the geodesic L2 loss refused.
#[test]
fn file_forms_and_errors() {
    let graph = example("graph.json");
    let keyed = temp_file(
        "keyed.json",
        r#"{"gravity": {"0": [0, 1, 0], "7": [0, 0.99, 0.1], "9999": [0, 1, 0]}, "world_down": [0, 0, 1]}"#,
    );
    let out = run(&[
        "multiple",
        &graph,
        "--gravity",
        keyed.to_str().unwrap(),
        "--json",
    ]);
    assert_success(&out);
    let v = json_of(&out);
    assert_eq!(v["pipeline"]["gravity"]["num_with_prior"], 2);
    let w = v["warnings"].as_array().unwrap();
    assert!(
        w.iter()
            .any(|w| w["code"] == "gravity_unmatched" && w["count"] == 1),
        "{w:?}"
    );
    for (text, words) in [
        (
            "0 0 1 0\n1 0 1\n",
            "bad.txt:2: expected `KEY gx gy gz [relative weight]`",
        ),
        ("0 0 1 0 2\n1 0 1 0 -2\n", "bad.txt:2: relative weight -2"),
        ("0 0 1 0 1 5\n", "found 5 numbers"),
        ("0 0 1 0\n1 0 nan 1\n", "not a finite number"),
        ("0 0 0 0\n", "zero vector"),
        ("# nothing here\n", "no gravity prior matches"),
    ] {
        let bad = temp_file("bad.txt", text);
        let out = run(&["multiple", &graph, "--gravity", bad.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(1), "{text}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(words), "{text}: {err}");
    }
    let gravity = example("gravity.txt");
    let out = run(&[
        "multiple",
        &graph,
        "--gravity",
        &gravity,
        "--loss",
        "geodesic",
    ]);
    assert_ne!(out.status.code(), Some(0));
    assert!(String::from_utf8_lossy(&out.stderr).contains("not `--loss geodesic`"));
}

/// `multiple --gravity PRIORS` on the example, held and soft of weight 16 (the estimate
/// written to `out`), and `certify` of that estimate: the two runs' JSON, after checking that
/// `certify` certifies it at the same cost.
fn held_and_soft(priors: &str, out: &str) -> (serde_json::Value, serde_json::Value) {
    let (graph, truth) = (example("graph.json"), example("truth.txt"));
    let out = temp_file(out, "").display().to_string();
    let args = [
        "multiple",
        &graph,
        "--ground-truth",
        &truth,
        "--json",
        "--gravity",
        priors,
    ];
    let held = json_of(&run(&args));
    let soft = run(&[&args[..], &["--gravity-weight", "16", "--output", &out]].concat());
    assert_success(&soft);
    let soft = json_of(&soft);
    let certify = run(&[
        "certify",
        &graph,
        "--estimate",
        &out,
        "--gravity",
        priors,
        "--gravity-weight",
        "16",
        "--json",
    ]);
    assert_success(&certify);
    let c = json_of(&certify);
    assert_eq!(c["certificate"]["verdict"], "certified");
    let (a, b) = (c["cost"].as_f64().unwrap(), soft["cost"].as_f64().unwrap());
    assert!((a - b).abs() <= 1e-9 * b, "{a} vs {b}");
    (held, soft)
}

/// `--gravity-weight`: soft priors on the mixed example are certified and named, more accurate
/// than held ones, `certify` states the same cost and verdict for the estimate written, and a
/// weight that is not positive, or one without priors, is an error.
#[test]
fn soft_priors_from_the_command_line() {
    let (graph, gravity) = (example("graph.json"), example("gravity.txt"));
    let (held, soft) = held_and_soft(&gravity, "soft_estimate.json");
    assert_eq!(
        soft["verdict"]["problem"]["kind"],
        "chordal_l2_gravity_soft"
    );
    assert_eq!(soft["certificate"]["verdict"], "certified");
    let mean = |v: &serde_json::Value| v["accuracy"]["mean_deg"].as_f64().unwrap();
    assert!(
        mean(&soft) < mean(&held),
        "{} vs {}",
        mean(&soft),
        mean(&held)
    );
    for bad in [
        &["--gravity-weight", "-1", "--gravity", &gravity][..],
        &["--gravity-weight", "2"],
    ] {
        let r = run(&[&["multiple", &graph][..], bad].concat());
        assert!(!r.status.success());
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(err.contains("weight") || err.contains("gravity"), "{err}");
    }
}

/// A fourth number per prior, its relative weight (`GravityPriors::with_scales`): soft priors
/// use it (`pipeline.gravity.scaled`), `certify` states the same cost, the JSON list form reads
/// it too, and held priors warn that it is not used.
#[test]
fn per_image_weights_from_the_command_line() {
    let text = std::fs::read_to_string(example("gravity.txt")).unwrap();
    let mut weighted = String::new();
    let mut scaled = 0;
    for (k, l) in text.lines().filter(|l| !l.starts_with('#')).enumerate() {
        let w = if k % 3 == 0 { 0.25 } else { 1.0 };
        scaled += usize::from(w != 1.0);
        weighted += &format!("{l} {w}\n");
    }
    let priors = temp_file("weighted.txt", &weighted).display().to_string();
    let (held, soft) = held_and_soft(&priors, "weighted_estimate.json");
    assert_eq!(soft["pipeline"]["gravity"]["scaled"], scaled);
    assert_eq!(soft["certificate"]["verdict"], "certified");
    // one weight for all costs differently
    let (_, plain) = held_and_soft(&example("gravity.txt"), "plain_estimate.json");
    let (a, b) = (
        plain["cost"].as_f64().unwrap(),
        soft["cost"].as_f64().unwrap(),
    );
    assert!((a - b).abs() > 1e-6 * b, "{a} vs {b}");
    let w = held["warnings"].as_array().unwrap();
    assert!(
        w.iter()
            .any(|w| w["code"] == "gravity_scales_unused" && w["count"] == scaled),
        "{w:?}"
    );
    let list = temp_file(
        "list.json",
        r#"{"gravity": [[0, 1, 0, 3], null, [0, 1, 0]]}"#,
    );
    let tiny = temp_file(
        "tiny.json",
        r#"{"num_rotations": 3, "edges": [{"i": 0, "j": 1, "rotation": [[1,0,0],[0,1,0],[0,0,1]], "weight": 1}, {"i": 1, "j": 2, "rotation": [[1,0,0],[0,1,0],[0,0,1]], "weight": 1}]}"#,
    );
    let r = run(&[
        "multiple",
        tiny.to_str().unwrap(),
        "--gravity",
        list.to_str().unwrap(),
        "--gravity-weight",
        "2",
        "--json",
    ]);
    assert_success(&r);
    assert_eq!(json_of(&r)["pipeline"]["gravity"]["scaled"], 1);
}
