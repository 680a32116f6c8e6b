//! Measure the whole pipeline (solve, then certify) on synthetic graphs, one size per run so
//! that `/usr/bin/time -v` reports its peak RSS:
//!
//! ```text
//! cargo run --release --example pipeline_scale -- [random|chain|planar-chain|grid|torus] N [M] [SIGMA] [ABSOLUTE_TOLERANCE_PER_MIN_WEIGHT] [MAX_MEMORY_GIB]
//! ```
//!
//! `random`: `SyntheticGraph` with `M` edges (default `3 N`), noise `SIGMA` (default 0.05 rad).
//! `chain`, `planar-chain`: `SyntheticChain` (odometry with 2 % loop closures; `M` ignored),
//! noise `SIGMA` (default 1e-4 rad). `grid`, `torus`: `SyntheticGrid`, a sqrt(N) x sqrt(N)
//! sweep with half of the other lattice edges as loop closures (`M` ignored), noise `SIGMA`
//! (default 1e-3 rad). Prints one line: sizes, solve and certify seconds, Newton
//! iterations, verdict, relative gap, and the certificate methods tried; then the linear
//! algebra of the solve (solver, symbolic analyses, numeric factorisations, CG iterations),
//! and the explanation when not certified (always with `ROTAVG_EXPLAIN=1`).
//! `ROTAVG_CERTIFY=none` runs the solve alone (to measure its own peak RSS).
//!
//! `--outliers F` (anywhere on the line, `random` only): that fraction of the edges carries a
//! random rotation instead of a measurement.
//!
//! `--write-g2o PATH` (anywhere on the line): do not solve; write the generated problem to
//! `PATH` (edges only, `rotavg::io::g2o::write_g2o`: `Q_ij = R_ij^T`, information `2 w I_3` so
//! that SE-Sync's weight reads back as `w = 1`) and the ground truth next to it as
//! `PATH` with `.g2o` replaced by `_gt.g2o` (vertex lines `W_i = R_i^T`, plus the same edges),
//! the names the peer harness looks for. Both files are read back with `read_g2o` and the
//! chordal cost of the ground truth is compared with the in-memory problem's (printed; the
//! program fails when they differ by more than 1e-9 relative). `benches/peers/run.sh scale`
//! feeds these files to `rotavg multiple` and to GTSAM.
use rotavg::certify::{Budget, CertifyMode, CertifySettings, ToleranceRule};
use rotavg::io::detect::ReadOptions;
use rotavg::io::g2o::{read_g2o, write_g2o};
use rotavg::multiple::MultipleProblem;
use rotavg::multiple::synthetic::{SyntheticChain, SyntheticGraph, SyntheticGrid};
use rotavg::pipeline::{AverageMultipleSettings, average_multiple};
use rotavg::so3::Rotation;

fn main() {
    let mut args: Vec<String> = std::env::args().collect();
    // `--outliers F`: that fraction of a random graph's edges replaced by random rotations
    let outliers: f64 = args
        .iter()
        .position(|a| a == "--outliers")
        .map(|k| {
            let f = args
                .get(k + 1)
                .and_then(|v| v.parse().ok())
                .expect("--outliers needs F");
            args.drain(k..k + 2);
            f
        })
        .unwrap_or(0.0);
    let write_g2o: Option<String> = args.iter().position(|a| a == "--write-g2o").map(|k| {
        let path = args.get(k + 1).cloned().expect("--write-g2o needs a PATH");
        args.drain(k..k + 2);
        path
    });
    let (kind, rest) = match args.get(1).map(String::as_str) {
        Some(k @ ("random" | "chain" | "planar-chain" | "grid" | "torus")) => {
            (k.to_string(), &args[2..])
        }
        _ => ("random".to_string(), &args[1..]),
    };
    let n: usize = rest.first().and_then(|s| s.parse().ok()).unwrap_or(10_000);
    let m: usize = rest.get(1).and_then(|s| s.parse().ok()).unwrap_or(3 * n);
    let default_sigma = match kind.as_str() {
        "random" => 0.05,
        "grid" | "torus" => 1e-3,
        _ => 1e-4,
    };
    let sigma: f64 = rest
        .get(2)
        .and_then(|s| s.parse().ok())
        .unwrap_or(default_sigma);
    let per_weight: f64 = rest.get(3).and_then(|s| s.parse().ok()).unwrap_or(1e-9);
    // the certificate's memory budget (default 4 GiB, as on the command line)
    let max_memory_gib: Option<u64> = rest.get(4).and_then(|s| s.parse().ok());
    let (p, truth) = match kind.as_str() {
        "random" => SyntheticGraph {
            num_rotations: n,
            num_edges: m,
            noise_sigma: sigma,
            outlier_fraction: outliers,
            ..Default::default()
        }
        .generate(),
        "grid" | "torus" => {
            let side = (n as f64).sqrt().round() as usize;
            SyntheticGrid {
                width: side,
                height: side,
                torus: kind == "torus",
                noise_sigma: sigma,
                seed: 3,
                ..Default::default()
            }
            .generate()
        }
        planar => SyntheticChain {
            num_rotations: n,
            loop_closure_fraction: 0.02,
            noise_sigma: sigma,
            planar: planar == "planar-chain",
            seed: 3,
            ..Default::default()
        }
        .generate(),
    };
    if let Some(path) = write_g2o {
        write_and_check(&kind, &p, &truth, &path);
        return;
    }
    // ROTAVG_CERTIFY=none: the solve alone (its peak RSS)
    let mode = match std::env::var("ROTAVG_CERTIFY").as_deref() {
        Ok("none") => CertifyMode::None,
        _ => CertifyMode::Auto,
    };
    let settings = AverageMultipleSettings {
        certify: CertifySettings {
            mode,
            tolerance: ToleranceRule {
                absolute_per_min_weight: per_weight,
                ..Default::default()
            },
            budget: Budget {
                max_memory_bytes: max_memory_gib
                    .map_or(Budget::default().max_memory_bytes, |g| g << 30),
                ..Default::default()
            },
            ..Default::default()
        },
        ..Default::default()
    };
    match average_multiple(&p, &settings) {
        Ok(e) => {
            let c = e.certificate.as_ref();
            println!(
                "{kind} n {n} m {} sigma {sigma}: solve {:.3} s ({} iterations), certify {:.3} s, verdict {}, relative gap {}, methods {:?}",
                p.num_edges(),
                e.solution.report.seconds,
                e.solution.report.iterations,
                e.details.certify_seconds,
                c.map_or("none".into(), |c| c.verdict.to_string()),
                c.and_then(|c| c.relative_gap)
                    .map_or("-".into(), |g| format!("{g:.1e}")),
                e.details
                    .certify
                    .iter()
                    .flat_map(|c| c.methods())
                    .map(|r| r.method.to_string())
                    .collect::<Vec<_>>()
            );
            if let Some(la) = &e.solution.linear_algebra {
                println!(
                    "  linear algebra: {}, {} symbolic analyses, {} numeric factorisations, {} CG iterations",
                    la.solver, la.symbolic_analyses, la.numeric_factorizations, la.cg_iterations
                );
            }
            if let Some(r) = c.and_then(|c| c.randomized) {
                println!(
                    "  randomized [D16]: {}, relative gap {:.1e}, failure probability {:.0e}",
                    if r.within_tolerance {
                        "within tolerance"
                    } else {
                        "gap above tolerance"
                    },
                    r.relative_gap,
                    r.failure_probability
                );
            }
            if let Some(c) =
                c.filter(|c| !c.is_certified() || std::env::var_os("ROTAVG_EXPLAIN").is_some())
            {
                println!("  why: {}", c.explanation);
            }
        }
        Err(e) => println!("error: {e}"),
    }
}

/// Write the problem (and, beside it, the ground truth) as g2o, read both back and check that
/// the ground truth's chordal cost is the same on the problem as read.
fn write_and_check(kind: &str, p: &MultipleProblem, truth: &[Rotation], path: &str) {
    let gt_path = match path.strip_suffix(".g2o") {
        Some(stem) => format!("{stem}_gt.g2o"),
        None => format!("{path}_gt.g2o"),
    };
    std::fs::write(path, write_g2o(p, None)).expect("write the problem");
    std::fs::write(&gt_path, write_g2o(p, Some(truth))).expect("write the ground truth");
    let opts = ReadOptions::default(); // file weights: kappa = 3 / (2 tr((2 w I)^-1)) = w
    let read = |f: &str| {
        let text = std::fs::read_to_string(f).expect("read back");
        read_g2o(&text, f, &opts).expect("parse back")
    };
    let (back, back_gt) = (read(path), read(&gt_path));
    let gt_back = back_gt.initial.expect("ground-truth vertices");
    assert_eq!(back.problem.num_rotations(), p.num_rotations());
    assert_eq!(back.problem.num_edges(), p.num_edges());
    // kappa = 3 / (2 tr((2 I)^-1)) = 1 up to the rounding of the Cholesky inverse
    let dw = back
        .problem
        .edges()
        .iter()
        .map(|e| (e.weight - 1.0).abs())
        .fold(0.0, f64::max);
    assert!(dw <= 1e-12, "file weights differ from 1 by {dw:e}");
    let (c0, c1) = (p.chordal_cost(truth), back.problem.chordal_cost(&gt_back));
    let rel = (c1 - c0).abs() / c0.abs().max(f64::MIN_POSITIVE);
    println!(
        "{kind} n {} m {}: wrote {path} and {gt_path}; ground-truth chordal cost {c0:.17e} in memory, {c1:.17e} read back (relative difference {rel:.1e}); file weights 1 within {dw:.1e}",
        p.num_rotations(),
        p.num_edges()
    );
    assert!(
        rel <= 1e-9,
        "the written problem differs from the generated one"
    );
}
