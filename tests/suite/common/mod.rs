//! Helpers shared by the integration tests: running the `rotavg` binary, temporary input
//! files, the shared benchmark data, and small comparisons of estimates.
//!
//! `tests/suite/main.rs` declares `mod common;`; each test module that needs them has
//! `use crate::common;`. Not every module uses every helper.
#![allow(dead_code)]

use rotavg::Rotation;
use rotavg::multiple::{Edge, MultipleProblem, fix_gauge};
use rotavg::so3::angle_between;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// The built `rotavg` binary.
pub fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_rotavg"))
}

/// Runs `rotavg ARGS` to completion.
pub fn run(args: &[&str]) -> Output {
    bin().args(args).output().expect("run rotavg")
}

/// Runs `rotavg ARGS` with `stdin` written to its standard input.
pub fn run_with_stdin(args: &[&str], stdin: &str) -> Output {
    let mut child = bin()
        .args(args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn rotavg");
    child
        .stdin
        .take()
        .expect("piped stdin")
        .write_all(stdin.as_bytes())
        .expect("write stdin");
    child.wait_with_output().expect("wait for rotavg")
}

/// Runs `command` to completion (its standard output and error read while it runs) and returns
/// its output with its peak resident set size in KiB, as the kernel counted it (`wait4`'s
/// `ru_maxrss`): the memory the process touched, not the address space it reserved.
#[cfg(target_os = "linux")]
#[expect(
    clippy::zombie_processes,
    reason = "the child is reaped by wait4, not Child::wait"
)]
pub fn run_with_peak_memory(mut command: Command) -> (Output, u64) {
    use std::io::Read;
    use std::os::unix::process::ExitStatusExt;
    let mut child = (command.stdout(Stdio::piped()).stderr(Stdio::piped()))
        .spawn()
        .expect("spawn the command");
    let drain = |mut pipe: Box<dyn Read + Send>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            pipe.read_to_end(&mut bytes)
                .expect("read the command's output");
            bytes
        })
    };
    let stdout = drain(Box::new(child.stdout.take().expect("piped stdout")));
    let stderr = drain(Box::new(child.stderr.take().expect("piped stderr")));
    let pid = libc::pid_t::try_from(child.id()).expect("a process id");
    let mut status: libc::c_int = 0;
    // SAFETY: `rusage` is plain data (all-zero is a valid value); `wait4` writes `status` and
    // `usage` and reaps the child, whose `Child` is not waited on afterwards.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    let reaped = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert_eq!(reaped, pid, "wait4 on the command");
    let output = Output {
        status: std::process::ExitStatus::from_raw(status),
        stdout: stdout.join().expect("stdout reader"),
        stderr: stderr.join().expect("stderr reader"),
    };
    (output, u64::try_from(usage.ru_maxrss).unwrap_or(0))
}

/// Exit status 0, else fail showing the process's stderr.
pub fn assert_success(out: &Output) {
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The process's standard output parsed as JSON (fails showing stdout and stderr otherwise).
pub fn json_of(out: &Output) -> serde_json::Value {
    let s = String::from_utf8_lossy(&out.stdout);
    serde_json::from_str(&s).unwrap_or_else(|e| {
        panic!(
            "not JSON ({e}): {s} / {}",
            String::from_utf8_lossy(&out.stderr)
        )
    })
}

/// A temporary directory of the calling test file (`rotavg-<file stem>-<pid>`, e.g.
/// `rotavg-cli_multiple-1234`) and process: the test files share one binary and process, and
/// use the same file names in their directories.
#[track_caller]
pub fn temp_dir() -> PathBuf {
    let caller = Path::new(std::panic::Location::caller().file());
    let stem = caller
        .file_stem()
        .and_then(|s| s.to_str())
        .expect("a test file name");
    let d = scratch_root().join(format!("rotavg-{stem}-{}", std::process::id()));
    std::fs::create_dir_all(&d).expect("create temporary directory");
    d
}

/// Where the tests write their files: cargo's scratch folder for integration tests
/// (`target/tmp`, removed by `cargo clean`), not the system's temporary folder, which the runs
/// filled with a folder per test file and process until 2026-12-02.
pub fn scratch_root() -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
}

/// Writes `text` to the file `name` of [`temp_dir`] (the calling file's) and returns its path.
#[track_caller]
pub fn temp_file(name: &str, text: &str) -> PathBuf {
    let p = temp_dir().join(name);
    std::fs::write(&p, text).expect("write temporary file");
    p
}

/// The shared benchmark data (`../shared/data` beside the repository, or `/work/shared/data`),
/// if present. Tests that need it print a skip notice when it is absent.
pub fn shared_data() -> Option<PathBuf> {
    let a = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data");
    let b = PathBuf::from("/work/shared/data");
    [a, b].into_iter().find(|p| p.is_dir())
}

/// A file of the shared data, if present.
pub fn shared(rel: &str) -> Option<PathBuf> {
    shared_data().map(|d| d.join(rel)).filter(|p| p.exists())
}

/// The rotation about z by `t` radians as a row-major nested JSON array.
pub fn rz_json(t: f64) -> String {
    let (s, c) = t.sin_cos();
    format!("[[{c}, {}, 0], [{s}, {c}, 0], [0, 0, 1]]", -s)
}

/// The angles between corresponding rotations after fixing the gauge of both (`R_0 = I`).
pub fn gauge_errors(a: &[Rotation], b: &[Rotation]) -> Vec<f64> {
    let (mut a, mut b) = (a.to_vec(), b.to_vec());
    fix_gauge(&mut a);
    fix_gauge(&mut b);
    a.iter().zip(&b).map(|(x, y)| angle_between(x, y)).collect()
}

/// Largest angle between corresponding rotations after fixing the gauge of both (`R_0 = I`).
pub fn max_gauge_error(a: &[Rotation], b: &[Rotation]) -> f64 {
    gauge_errors(a, b).into_iter().fold(0.0, f64::max)
}

/// Mean angle between corresponding rotations after fixing the gauge of both (`R_0 = I`).
pub fn mean_gauge_error(a: &[Rotation], b: &[Rotation]) -> f64 {
    let e = gauge_errors(a, b);
    e.iter().sum::<f64>() / e.len().max(1) as f64
}

/// The same graph with every edge weight multiplied by `c`.
pub fn scale_weights(p: &MultipleProblem, c: f64) -> MultipleProblem {
    let edges = p
        .edges()
        .iter()
        .map(|e| Edge {
            weight: e.weight * c,
            ..e.clone()
        })
        .collect();
    MultipleProblem::new(p.num_rotations(), edges).expect("scaled weights stay valid")
}

/// An anisotropic view graph from `(i, j, R_ij, H)` per edge (weights 1; every `H` must be a
/// valid information).
pub fn anisotropic_graph(
    n: usize,
    edges: &[(usize, usize, Rotation, nalgebra::Matrix3<f64>)],
) -> MultipleProblem {
    let info = edges
        .iter()
        .map(|(_, _, _, h)| rotavg::multiple::anisotropic::Information::new(*h).unwrap())
        .collect();
    let edges = edges
        .iter()
        .map(|(i, j, r, _)| Edge {
            i: *i,
            j: *j,
            rotation: *r,
            weight: 1.0,
        })
        .collect();
    MultipleProblem::new(n, edges)
        .unwrap()
        .with_information(info)
        .unwrap()
}

/// The best of `starts` local solves (chordal) from random rotations: a brute-force stand-in
/// for the global minimum of a tiny graph.
pub fn best_of_random_starts(
    p: &MultipleProblem,
    starts: usize,
    rng: &mut impl rand::Rng,
) -> Vec<Rotation> {
    let mut best: Option<(f64, Vec<Rotation>)> = None;
    for _ in 0..starts {
        let mut init: Vec<Rotation> = (0..p.num_rotations())
            .map(|_| rotavg::so3::random_rotation(rng))
            .collect();
        fix_gauge(&mut init);
        let local = rotavg::multiple::MultipleSettings {
            init: rotavg::multiple::Initialisation::Given(init),
            ..Default::default()
        };
        if let Ok(sol) = rotavg::multiple::solve_multiple(p, &local)
            && best.as_ref().is_none_or(|b| sol.chordal_cost < b.0)
        {
            best = Some((sol.chordal_cost, sol.rotations));
        }
    }
    best.expect("a local solve").1
}

/// Every row of the tables of a COLMAP database, as text (blobs as bytes): two databases with
/// the same rows compare equal whatever SQLite version wrote them.
#[cfg(feature = "colmap")]
pub fn database_rows(path: &Path) -> Vec<String> {
    let db = rusqlite::Connection::open(path).expect("open the database");
    let mut out = Vec::new();
    for table in [
        "cameras",
        "images",
        "keypoints",
        "descriptors",
        "matches",
        "two_view_geometries",
    ] {
        let mut stmt = db
            .prepare(&format!("SELECT * FROM {table} ORDER BY 1"))
            .expect("a COLMAP table");
        let n = stmt.column_count();
        let mut rows = stmt.query([]).expect("query");
        while let Some(row) = rows.next().expect("a row") {
            let cells: Vec<String> = (0..n)
                .map(|k| {
                    format!(
                        "{:?}",
                        row.get::<_, rusqlite::types::Value>(k).expect("a cell")
                    )
                })
                .collect();
            out.push(format!("{table}: {}", cells.join(" | ")));
        }
    }
    out
}

/// Assert that every rotation is in SO(3) to 1e-12 (`||R^T R - I||_F` and `|det R - 1|`),
/// computed here from the matrices, not by the crate.
pub fn assert_in_so3(rotations: &[Rotation], what: &str) {
    for (k, r) in rotations.iter().enumerate() {
        let m = r.matrix();
        let defect = (m.transpose() * m - nalgebra::Matrix3::identity()).norm();
        let det = m.determinant();
        assert!(
            defect <= 1e-12 && (det - 1.0).abs() <= 1e-12,
            "{what}: rotation {k} off SO(3): defect {defect:e}, det {det}"
        );
    }
}

/// The outlier scene of the gravity tests: 150 cameras, 1200 edges with 2 degrees of noise and
/// 15 % random-rotation outliers, priors good to 0.3 degrees for every image (seed 11), with the
/// truth.
pub fn gravity_outlier_scene() -> (
    MultipleProblem,
    Vec<Rotation>,
    rotavg::multiple::gravity::GravityPriors,
) {
    use rotavg::multiple::synthetic::{SyntheticGraph, SyntheticGravity};
    let (graph, truth) = SyntheticGraph {
        num_rotations: 150,
        num_edges: 1200,
        noise_sigma: (2f64 / 3f64.sqrt()).to_radians(),
        outlier_fraction: 0.15,
        seed: 11,
    }
    .generate();
    let priors = SyntheticGravity {
        noise_deg: 0.3,
        missing_fraction: 0.0,
        seed: 11,
    }
    .priors(&truth)
    .expect("generated priors are valid");
    (graph, truth, priors)
}

/// The pipeline's settings under the loss rule `auto` (the command line's default, 5 degrees).
pub fn auto_loss_settings() -> rotavg::pipeline::AverageSettings<rotavg::multiple::MultipleSettings>
{
    rotavg::pipeline::AverageSettings {
        solve: rotavg::multiple::MultipleSettings {
            robust_on_outliers: rotavg::io::names::MultipleLoss::Auto.robust_on_outliers(5.0),
            ..Default::default()
        },
        ..Default::default()
    }
}
