//! The `--json` contract of the command line (contract section 5), pinned: every subcommand with
//! `--json` (single, multiple, conjugate, certify, info) runs on small inputs this test writes
//! itself, and its output must equal the stored object in `tests/cli_json_contract/` key for
//! key and value for value, timings excepted (every key containing `seconds` is removed).
//!
//! What "equal" means: the same keys at every level; the same strings, booleans, nulls and
//! integers; floats within `1e-9 + 1e-6 |x|` (so that a last-digit change of a solver does not
//! count as a contract change, while a changed cost or bound does); the free-text fields
//! `explanation` and `note` only need to stay strings.
//!
//! A deliberate change of the contract: run `ROTAVG_BLESS=1 cargo test --test suite
//! cli_json_contract::`, review `git diff tests/cli_json_contract/`, and say in the commit what
//! changed for scripts. `ROTAVG_CONTRACT_BIN=/path/to/rotavg` checks another binary (e.g. an
//! older build) against the stored objects.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

type Mat = [[f64; 3]; 3];

/// `exp(hat(v))` (Rodrigues).
fn exp(v: [f64; 3]) -> Mat {
    let t = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if t == 0.0 {
        return [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    }
    let k = [v[0] / t, v[1] / t, v[2] / t];
    let kx = [[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]];
    let kk = mul(&kx, &kx);
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let id = if i == j { 1.0 } else { 0.0 };
            r[i][j] = id + t.sin() * kx[i][j] + (1.0 - t.cos()) * kk[i][j];
        }
    }
    r
}

fn mul(a: &Mat, b: &Mat) -> Mat {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|l| a[i][l] * b[l][j]).sum();
        }
    }
    c
}

fn tr(a: &Mat) -> Mat {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = a[j][i];
        }
    }
    c
}

fn rows(r: &Mat) -> String {
    serde_json::to_string(r).expect("a matrix serialises")
}

/// `(x, y, z, w)` of a rotation matrix (trace > -1 for the matrices used here).
fn quaternion(m: &Mat) -> [f64; 4] {
    let w = (1.0 + m[0][0] + m[1][1] + m[2][2]).max(0.0).sqrt() / 2.0;
    [
        (m[2][1] - m[1][2]) / (4.0 * w),
        (m[0][2] - m[2][0]) / (4.0 * w),
        (m[1][0] - m[0][1]) / (4.0 * w),
        w,
    ]
}

/// A small deterministic perturbation (radians, about 0.01).
fn noise(k: usize) -> Mat {
    let k = k as f64;
    exp([
        0.01 * (3.0 * k).sin(),
        0.01 * (5.0 * k + 1.0).cos(),
        0.008 * (7.0 * k + 2.0).sin(),
    ])
}

/// The absolute rotations of the view graphs.
fn truth(i: usize) -> Mat {
    let i = i as f64;
    exp([0.3 * i, -0.2 + 0.15 * i, 0.4 - 0.1 * i * i])
}

/// Edges `(i, j)` with `R_ij = R_j R_i^T` times noise.
fn measured(edges: &[(usize, usize)], truth_of: impl Fn(usize) -> Mat) -> Vec<(usize, usize, Mat)> {
    edges
        .iter()
        .enumerate()
        .map(|(k, &(i, j))| (i, j, mul(&mul(&truth_of(j), &tr(&truth_of(i))), &noise(k))))
        .collect()
}

const GRAPH_EDGES: &[(usize, usize)] = &[
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 4),
    (4, 0),
    (0, 2),
    (3, 1),
    (2, 4),
];

/// The inputs, written once per process into a temporary directory.
struct Inputs {
    dir: PathBuf,
}

impl Inputs {
    /// Write the inputs into a directory of their own (`tag` names the test using it).
    fn write(tag: &str) -> Inputs {
        let dir = crate::common::scratch_root()
            .join(format!("rotavg-cli-contract-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("temporary directory");
        let put = |name: &str, text: String| {
            std::fs::write(dir.join(name), text).expect("write an input");
        };

        // single: six samples around one rotation, with weights
        let center = exp([0.3, -0.2, 0.5]);
        let samples: Vec<String> = (0..6).map(|k| rows(&mul(&center, &noise(k)))).collect();
        put(
            "single.json",
            format!(
                "{{\"rotations\": [{}], \"weights\": [1, 2, 1, 3, 1, 2]}}\n",
                samples.join(", ")
            ),
        );
        put(
            "single_estimate.json",
            format!("{{\"rotation\": {}}}\n", rows(&center)),
        );

        // multiple: five nodes, eight noisy edges, weights 1..3
        let edges: Vec<String> = measured(GRAPH_EDGES, truth)
            .iter()
            .enumerate()
            .map(|(k, (i, j, r))| {
                format!(
                    "{{\"i\": {i}, \"j\": {j}, \"rotation\": {}, \"weight\": {}}}",
                    rows(r),
                    1 + k % 3
                )
            })
            .collect();
        put(
            "graph.json",
            format!(
                "{{\"num_rotations\": 5, \"edges\": [\n{}\n]}}\n",
                edges.join(",\n")
            ),
        );
        let truth_rows: Vec<String> = (0..5).map(|i| rows(&truth(i))).collect();
        put(
            "graph_truth.json",
            format!("{{\"rotations\": [{}]}}\n", truth_rows.join(", ")),
        );

        // g2o with sparse ids and two components ({10, 11, 13, 17, 20} and {30, 31}), and a g2o
        // ground truth (vertex W_i = R_i^T, edge Z_ij = R_ij^T)
        let ids = [10usize, 11, 13, 17, 20, 30, 31];
        let pairs: Vec<(usize, usize)> = GRAPH_EDGES.iter().copied().chain([(5, 6)]).collect();
        let info = "1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 4 0 0 4 0 4";
        let edge_lines: Vec<String> = measured(&pairs, truth)
            .iter()
            .map(|(i, j, r)| {
                let q = quaternion(&tr(r));
                format!(
                    "EDGE_SE3:QUAT {} {} 0 0 0 {} {} {} {} {info}",
                    ids[*i], ids[*j], q[0], q[1], q[2], q[3]
                )
            })
            .collect();
        put("sparse.g2o", edge_lines.join("\n") + "\n");
        let vertex_lines: Vec<String> = (0..ids.len())
            .map(|i| {
                let q = quaternion(&tr(&truth(i)));
                format!(
                    "VERTEX_SE3:QUAT {} 0 0 0 {} {} {} {}",
                    ids[i], q[0], q[1], q[2], q[3]
                )
            })
            .collect();
        put(
            "sparse_truth.g2o",
            vertex_lines.join("\n") + "\n" + &edge_lines.join("\n") + "\n",
        );

        // conjugate: twelve pairs R_k ~ S^T L_k S with noise on L_k, weights 1 and 2
        let s = exp([0.4, 0.1, -0.7]);
        let pairs: Vec<String> = (0..12)
            .map(|k| {
                let kf = k as f64;
                let r = exp([
                    (1.3 * kf).sin(),
                    (0.7 * kf + 0.5).cos(),
                    0.3 * (2.1 * kf).sin(),
                ]);
                let l = mul(&mul(&mul(&s, &r), &tr(&s)), &noise(k + 20));
                format!(
                    "{{\"left\": {}, \"right\": {}, \"weight\": {}}}",
                    rows(&l),
                    rows(&r),
                    1 + k % 2
                )
            })
            .collect();
        put(
            "conjugate.json",
            format!("{{\"pairs\": [\n{}\n]}}\n", pairs.join(",\n")),
        );
        put(
            "conjugate_estimate.json",
            format!("{{\"rotation\": {}}}\n", rows(&s)),
        );
        Inputs { dir }
    }

    fn path(&self, name: &str) -> String {
        self.dir.join(name).display().to_string()
    }
}

fn binary() -> PathBuf {
    std::env::var_os("ROTAVG_CONTRACT_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_rotavg")))
}

/// Run `rotavg ARGS` (file names resolved in the input directory), expect exit status 0 and
/// one JSON object on stdout; return it without its timings.
fn run(inputs: &Inputs, args: &[&str]) -> Value {
    let args: Vec<String> = args
        .iter()
        .map(|a| {
            if !a.starts_with('-') && inputs.dir.join(a).is_file() {
                inputs.path(a)
            } else {
                a.to_string()
            }
        })
        .collect();
    let out = Command::new(binary())
        .args(&args)
        .output()
        .expect("run rotavg");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(
        out.status.code(),
        Some(0),
        "rotavg {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_str(&stdout)
        .unwrap_or_else(|e| panic!("rotavg {args:?} printed no JSON object ({e}): {stdout}"));
    assert!(v.is_object(), "rotavg {args:?}: not an object");
    // The input directory differs between runs: file names are compared without it.
    without_timings(&v, &inputs.dir)
}

/// `v` without the keys that contain `seconds`, and with the input directory removed from
/// strings.
fn without_timings(v: &Value, dir: &Path) -> Value {
    match v {
        Value::Object(m) => Value::Object(
            m.iter()
                .filter(|(k, _)| !k.contains("seconds"))
                .map(|(k, x)| (k.clone(), without_timings(x, dir)))
                .collect(),
        ),
        Value::Array(a) => Value::Array(a.iter().map(|x| without_timings(x, dir)).collect()),
        Value::String(s) => {
            let prefix = format!("{}/", dir.display());
            Value::String(s.replace(&prefix, ""))
        }
        other => other.clone(),
    }
}

/// Differences between the stored object and the output, as `path: what` lines.
fn differences(expected: &Value, actual: &Value, path: &str, out: &mut Vec<String>) {
    match (expected, actual) {
        (Value::Object(e), Value::Object(a)) => {
            for k in e.keys().filter(|k| !a.contains_key(*k)) {
                out.push(format!("{path}/{k}: missing"));
            }
            for k in a.keys().filter(|k| !e.contains_key(*k)) {
                out.push(format!("{path}/{k}: new key"));
            }
            for (k, x) in e {
                if let Some(y) = a.get(k) {
                    if (k == "explanation" || k == "note") && x.is_string() && y.is_string() {
                        continue;
                    }
                    differences(x, y, &format!("{path}/{k}"), out);
                }
            }
        }
        (Value::Array(e), Value::Array(a)) if e.len() == a.len() => {
            for (k, (x, y)) in e.iter().zip(a).enumerate() {
                differences(x, y, &format!("{path}/{k}"), out);
            }
        }
        (Value::Number(x), Value::Number(y)) if x.is_f64() || y.is_f64() => {
            let (x, y) = (
                x.as_f64().unwrap_or(f64::NAN),
                y.as_f64().unwrap_or(f64::NAN),
            );
            if (x - y).abs() > 1e-9 + 1e-6 * x.abs().max(y.abs()) {
                out.push(format!("{path}: {x} -> {y}"));
            }
        }
        (e, a) if e == a => {}
        (e, a) => {
            let short = |v: &Value| {
                let s = v.to_string();
                if s.len() > 80 {
                    format!("{}...", &s[..80])
                } else {
                    s
                }
            };
            out.push(format!("{path}: {} -> {}", short(e), short(a)));
        }
    }
}

/// Compare with (or, under `ROTAVG_BLESS=1`, store) `tests/cli_json_contract/NAME.json`.
fn check(name: &str, actual: &Value) -> Vec<String> {
    let file = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/cli_json_contract")
        .join(format!("{name}.json"));
    if std::env::var_os("ROTAVG_BLESS").is_some() {
        std::fs::create_dir_all(file.parent().expect("a parent directory")).expect("mkdir");
        let text = serde_json::to_string_pretty(actual).expect("serialise") + "\n";
        std::fs::write(&file, text).expect("write the stored object");
        return Vec::new();
    }
    let text = std::fs::read_to_string(&file)
        .unwrap_or_else(|e| panic!("{}: {e} (ROTAVG_BLESS=1 writes it)", file.display()));
    let expected: Value = serde_json::from_str(&text).expect("stored object is JSON");
    let mut out = Vec::new();
    differences(&expected, actual, "", &mut out);
    out.into_iter().map(|d| format!("{name}: {d}")).collect()
}

/// The contract section 5 keys every problem object has.
fn assert_spec_keys(name: &str, v: &Value) {
    for key in [
        "problem",
        "num_rotations",
        "num_measurements",
        "cost",
        "estimate",
        "solver",
        "certificate",
    ] {
        assert!(v.get(key).is_some(), "{name}: no `{key}`");
    }
    if let Some(c) = v.get("certificate").filter(|c| !c.is_null()) {
        for key in [
            "verdict",
            "upper_bound",
            "lower_bound",
            "gap",
            "relative_gap",
            "min_eigenvalue",
            "method",
        ] {
            assert!(c.get(key).is_some(), "{name}: no `certificate.{key}`");
        }
    }
}

#[test]
fn json_output_of_every_subcommand_is_pinned() {
    let inputs = Inputs::write("pinned");
    let cases: &[(&str, &[&str])] = &[
        ("single", &["single", "single.json", "--json"]),
        (
            "single_geodesic_l1_unit",
            &[
                "single",
                "single.json",
                "--metric",
                "geodesic",
                "--p",
                "1",
                "--weights",
                "unit",
                "--json",
            ],
        ),
        ("multiple", &["multiple", "graph.json", "--json"]),
        (
            "multiple_truth_init",
            &[
                "multiple",
                "graph.json",
                "--ground-truth",
                "graph_truth.json",
                "--init",
                "graph_truth.json",
                "--json",
            ],
        ),
        (
            "multiple_huber_uncertified",
            &[
                "multiple",
                "graph.json",
                "--loss",
                "huber",
                "--loss-threshold",
                "0.5",
                "--certify",
                "none",
                "--json",
            ],
        ),
        (
            "multiple_huber_inlier_graph",
            &[
                "multiple",
                "graph.json",
                "--loss",
                "huber",
                "--loss-threshold",
                "0.5",
                "--inlier-threshold",
                "0.7",
                "--ground-truth",
                "graph_truth.json",
                "--json",
            ],
        ),
        (
            "multiple_largest_component_g2o",
            &[
                "multiple",
                "sparse.g2o",
                "--largest-component",
                "--ground-truth",
                "sparse_truth.g2o",
                "--weights",
                "unit",
                "--json",
            ],
        ),
        ("conjugate", &["conjugate", "conjugate.json", "--json"]),
        (
            "conjugate_geodesic_huber",
            &[
                "conjugate",
                "conjugate.json",
                "--metric",
                "geodesic",
                "--loss",
                "huber",
                "--loss-threshold",
                "0.5",
                "--json",
            ],
        ),
        (
            "certify_multiple",
            &[
                "certify",
                "graph.json",
                "--estimate",
                "graph_truth.json",
                "--json",
            ],
        ),
        (
            "certify_single",
            &[
                "certify",
                "single.json",
                "--estimate",
                "single_estimate.json",
                "--json",
            ],
        ),
        (
            "certify_conjugate",
            &[
                "certify",
                "conjugate.json",
                "--estimate",
                "conjugate_estimate.json",
                "--json",
            ],
        ),
        ("info", &["info", "sparse.g2o", "--json"]),
    ];
    let mut failures = Vec::new();
    for (name, args) in cases {
        let v = run(&inputs, args);
        if *name != "info" {
            assert_spec_keys(name, &v);
        }
        failures.extend(check(name, &v));
    }
    let _ = std::fs::remove_dir_all(&inputs.dir);
    assert!(
        failures.is_empty(),
        "the --json contract changed (ROTAVG_BLESS=1 stores the new objects after review):\n{}",
        failures.join("\n")
    );
}

/// Run `rotavg ARGS` with `stdin` as standard input; (exit status, stdout, stderr).
fn run_raw(inputs: &Inputs, args: &[&str], stdin: Option<&str>) -> (Option<i32>, String, String) {
    use std::io::Write;
    let args: Vec<String> = args
        .iter()
        .map(|a| {
            if !a.starts_with('-') && inputs.dir.join(a).is_file() {
                inputs.path(a)
            } else {
                a.to_string()
            }
        })
        .collect();
    let mut child = Command::new(binary())
        .args(&args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run rotavg");
    if let Some(mut pipe) = child.stdin.take() {
        pipe.write_all(stdin.unwrap_or("").as_bytes())
            .expect("write stdin");
    }
    let out = child.wait_with_output().expect("rotavg ends");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// Exit status 0 whatever the verdict, 1 for bad input (the message names the file and line),
/// 2 for usage errors, 3 with `--require-certified` when not certified; `-` reads standard
/// input; nothing on stderr for a successful run whose stderr is not a terminal.
#[test]
fn exit_codes_streams_and_stdin() {
    let inputs = Inputs::write("exit");
    let certify_truth = ["certify", "graph.json", "--estimate", "graph_truth.json"];

    // gap reported: 0, or 3 with --require-certified (message unless --quiet)
    let (code, stdout, stderr) = run_raw(&inputs, &certify_truth, None);
    assert_eq!(code, Some(0), "{stderr}");
    assert!(stdout.contains("certificate: gap_reported"), "{stdout}");
    assert!(stderr.is_empty(), "{stderr}");
    let (code, _, stderr) = run_raw(
        &inputs,
        &[&certify_truth[..], &["--require-certified"]].concat(),
        None,
    );
    assert_eq!(code, Some(3));
    assert!(
        stderr.contains("--require-certified: verdict is gap_reported"),
        "{stderr}"
    );
    let quiet = [&certify_truth[..], &["--require-certified", "--quiet"]].concat();
    let (code, stdout, stderr) = run_raw(&inputs, &quiet, None);
    assert_eq!((code, stdout.as_str(), stderr.as_str()), (Some(3), "", ""));
    let (code, _, _) = run_raw(
        &inputs,
        &["multiple", "graph.json", "--require-certified", "--quiet"],
        None,
    );
    assert_eq!(code, Some(0));

    // bad input: 1, naming the file (and the line)
    std::fs::write(
        inputs.dir.join("bad.g2o"),
        "EDGE3 0 1 0 0 0 0 0 0\nEDGE3 1 x 0 0 0 0 0 0\n",
    )
    .expect("write");
    let (code, _, stderr) = run_raw(&inputs, &["multiple", "bad.g2o"], None);
    assert_eq!(code, Some(1));
    assert!(
        stderr.starts_with("rotavg: error: ") && stderr.contains("bad.g2o:2"),
        "{stderr}"
    );
    let (code, _, stderr) = run_raw(&inputs, &["single", "no-such-file.json"], None);
    assert_eq!(code, Some(1));
    assert!(stderr.contains("no-such-file.json"), "{stderr}");
    let (code, _, stderr) = run_raw(
        &inputs,
        &["certify", "single.json", "--estimate", "graph_truth.json"],
        None,
    );
    assert_eq!(code, Some(1));
    assert!(stderr.contains("graph_truth.json"), "{stderr}");

    // usage: 2
    for args in [
        &["multiple", "graph.json", "--loss", "bogus"][..],
        &["multiple"],
        &["conjugate", "conjugate.json", "--certify", "dual"],
        &["single", "single.json", "--p", "3"],
    ] {
        let (code, _, stderr) = run_raw(&inputs, args, None);
        assert_eq!(code, Some(2), "{args:?}: {stderr}");
    }

    // `-` is standard input: the same object as from the file
    for (sub, file) in [
        ("single", "single.json"),
        ("multiple", "graph.json"),
        ("conjugate", "conjugate.json"),
    ] {
        let text = std::fs::read_to_string(inputs.dir.join(file)).expect("read");
        let (code, stdout, stderr) = run_raw(&inputs, &[sub, "-", "--json"], Some(&text));
        assert_eq!(code, Some(0), "{sub} -: {stderr}");
        let mut from_stdin: Value = serde_json::from_str(&stdout).expect("JSON");
        let mut from_file = run(&inputs, &[sub, file, "--json"]);
        // the same object but for the input's path, which says where it came from
        if let Some(path) = from_stdin.pointer_mut("/input/path") {
            assert_eq!(path, "-");
            *path = Value::from(file);
        }
        from_stdin = without_timings(&from_stdin, &inputs.dir);
        if let Some(path) = from_file.pointer_mut("/input/path") {
            assert_eq!(path, file);
        }
        assert_eq!(from_stdin, from_file, "{sub}");
    }
    let _ = std::fs::remove_dir_all(&inputs.dir);
}
