//! The default text output of the main verbs keeps its lines to at most 100 characters, and
//! `--verbose` adds the proof's details: the rungs of the proof ladder that ran, the tolerance
//! rule and the labels of `paper-notes/` (issue 27, item 5). The files are those of
//! `examples/data/`, in every clone.

use std::process::Command;

const WIDTH: usize = 100;

/// `rotavg ARGS` in the repository root: its standard output (the run must succeed).
fn stdout(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_rotavg"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("rotavg runs");
    assert!(
        out.status.success(),
        "rotavg {args:?}: {}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("UTF-8 output")
}

/// The runs checked, each without and with `--verbose`.
fn runs(estimate: &str) -> Vec<Vec<String>> {
    let handeye = [
        "conjugate",
        "--hand",
        "examples/data/handeye/hand.csv",
        "--camera",
        "examples/data/handeye/camera.csv",
    ];
    let runs: Vec<Vec<&str>> = vec![
        vec!["single", "examples/data/single.json"],
        vec![
            "single",
            "examples/data/single.json",
            "--metric",
            "geodesic",
            "--p",
            "1",
        ],
        vec!["multiple", "examples/data/slam.g2o"],
        vec![
            "multiple",
            "examples/data/sfm_outliers.txt",
            "--ground-truth",
            "examples/data/sfm_truth.txt",
        ],
        vec![
            "multiple",
            "examples/data/sfm_outliers.txt",
            "--loss",
            "cauchy",
            "--ground-truth",
            "examples/data/sfm_truth.txt",
        ],
        handeye.to_vec(),
        vec!["certify", "examples/data/slam.g2o", "--estimate", estimate],
        vec!["demo", "--nodes", "200"],
    ];
    runs.into_iter()
        .map(|r| r.into_iter().map(String::from).collect())
        .collect()
}

#[test]
fn default_lines_are_short_and_verbose_shows_the_proof() {
    let dir = crate::common::scratch_root().join(format!("rotavg-width-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let estimate = dir.join("slam.json");
    let estimate = estimate.to_str().unwrap();
    stdout(&[
        "multiple",
        "examples/data/slam.g2o",
        "--output",
        estimate,
        "--quiet",
    ]);
    for args in runs(estimate) {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let short = stdout(&args);
        for line in short.lines() {
            assert!(
                line.chars().count() <= WIDTH,
                "rotavg {args:?}: a line of {} characters:\n{line}\n\n{short}",
                line.chars().count()
            );
        }
        assert!(
            !short.contains("[D1") && !short.contains("tolerance:"),
            "rotavg {args:?}: proof details without --verbose:\n{short}"
        );
        let mut verbose_args = args.clone();
        verbose_args.push("--verbose");
        let verbose = stdout(&verbose_args);
        assert!(
            verbose.contains("tolerance:"),
            "rotavg {args:?} --verbose: no tolerance rule:\n{verbose}"
        );
        assert!(
            verbose.len() > short.len(),
            "rotavg {args:?} --verbose adds nothing:\n{verbose}"
        );
    }
    // the ladder's rungs (one line per proof method that ran) and the labels of paper-notes/
    let verbose = stdout(&["multiple", "examples/data/slam.g2o", "--verbose"]);
    assert!(
        verbose.lines().any(|l| l.starts_with("  dual (")),
        "no rung of the proof ladder:\n{verbose}"
    );
    assert!(
        verbose.contains("[D"),
        "no label of paper-notes/:\n{verbose}"
    );
    let short = stdout(&["multiple", "examples/data/slam.g2o"]);
    assert!(!short.lines().any(|l| l.starts_with("  dual (")), "{short}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn json_is_the_same_with_and_without_verbose() {
    let strip_times = |text: String| -> serde_json::Value {
        let mut v: serde_json::Value = serde_json::from_str(&text).expect("JSON");
        fn zero(v: &mut serde_json::Value) {
            match v {
                serde_json::Value::Object(m) => {
                    for (k, x) in m.iter_mut() {
                        if k.contains("seconds") || k == "seed" {
                            *x = serde_json::Value::Null;
                        } else {
                            zero(x);
                        }
                    }
                }
                serde_json::Value::Array(a) => a.iter_mut().for_each(zero),
                _ => {}
            }
        }
        zero(&mut v);
        v
    };
    let args = ["single", "examples/data/single.json", "--json"];
    let plain = strip_times(stdout(&args));
    let verbose = strip_times(stdout(&[&args[..], &["--verbose"]].concat()));
    assert_eq!(plain, verbose);
}

#[test]
fn help_is_wrapped_for_every_verb() {
    for verb in ["demo", "single", "multiple", "conjugate", "certify", "info"] {
        for args in [vec!["help", verb], vec![verb, "--help"]] {
            let text = stdout(&args);
            assert!(text.contains("Usage:"), "{args:?}: {text}");
            let long: Vec<&str> = text.lines().filter(|l| l.chars().count() > WIDTH).collect();
            assert!(long.is_empty(), "{args:?}: {long:?}");
        }
    }
}
