//! Single rotation averaging under every metric and norm, each with its certificate.
//!
//! ```text
//! cargo run --release --example single                        # 100 synthetic samples
//! cargo run --release --example single -- --file X.txt [--json]
//! ```
//!
//! Without `--file`: 100 noisy samples (Gaussian, 5 degrees per axis) of a planted rotation
//! plus 10 outliers, seeded. With `--file`: a `ROTAVG_SINGLE 1` text file as written by the peer
//! harness (`M m`, then `ROT k w r00 .. r22` per sample, row-major; `#` comments), which is how
//! `benches/peers/run.sh` compares with SciPy on the same samples. `--json` prints one JSON
//! object (one entry per method) instead of text.

use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::objective::{Loss, Objective};
use rotavg::pipeline::{AverageSettings, average_single};
use rotavg::single::SingleProblem;
use rotavg::so3::{
    DEFAULT_ROTATION_TOLERANCE, Metric, Rotation, angle_between, exp, perturb_gaussian,
    random_rotation, rotation_from_matrix, rotation_to_rows,
};
use std::time::Instant;

/// Read a `ROTAVG_SINGLE 1` file: samples and weights.
fn read_single_txt(path: &str) -> rotavg::Result<SingleProblem> {
    let text = std::fs::read_to_string(path).map_err(|e| rotavg::Error::Io {
        path: path.into(),
        message: e.to_string(),
    })?;
    let (mut rots, mut weights) = (Vec::new(), Vec::new());
    for (k, line) in text.lines().enumerate() {
        let t: Vec<&str> = line.split_whitespace().collect();
        if t.first() != Some(&"ROT") {
            continue;
        }
        let err = |msg: &str| rotavg::Error::parse(Some(path), Some(k + 1), msg);
        if t.len() != 12 {
            return Err(err("expected `ROT k w r00 .. r22` (12 tokens)"));
        }
        let v: Vec<f64> = t[2..]
            .iter()
            .map(|s| s.parse::<f64>().map_err(|_| err("not a number")))
            .collect::<rotavg::Result<_>>()?;
        let m = nalgebra::Matrix3::from_row_slice(&v[1..]);
        let r = rotation_from_matrix(&m, DEFAULT_ROTATION_TOLERANCE, &format!("sample {}", t[1]))
            .map_err(|e| e.in_file(path, Some(k + 1)))?;
        rots.push(r);
        weights.push(v[0]);
    }
    SingleProblem::new(rots, Some(weights))
}

/// 100 inliers around a planted rotation, 10 outliers; returns the problem and the truth.
fn synthetic() -> rotavg::Result<(SingleProblem, Rotation)> {
    let mut rng = StdRng::seed_from_u64(7);
    let truth = exp(&nalgebra::Vector3::new(0.3, -1.1, 0.6));
    let mut samples: Vec<Rotation> = (0..100)
        .map(|_| perturb_gaussian(&truth, 5f64.to_radians(), &mut rng))
        .collect();
    samples.extend((0..10).map(|_| random_rotation(&mut rng)));
    Ok((SingleProblem::new(samples, None)?, truth))
}

fn run() -> rotavg::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let json = args.iter().any(|a| a == "--json");
    let file = args
        .iter()
        .position(|a| a == "--file")
        .and_then(|i| args.get(i + 1));
    let (problem, truth) = match file {
        Some(f) => (read_single_txt(f)?, None),
        None => {
            let (p, t) = synthetic()?;
            (p, Some(t))
        }
    };
    let methods = [
        (Metric::Chordal, Loss::L2),
        (Metric::Quaternion, Loss::L2),
        (Metric::Geodesic, Loss::L2),
        (Metric::Geodesic, Loss::L1),
        (Metric::Chordal, Loss::L1),
    ];
    let mut out = Vec::new();
    if !json {
        println!("{} samples", problem.len());
    }
    for (metric, norm) in methods {
        let t = Instant::now();
        let p = problem
            .clone()
            .with_objective(Objective::new(metric, norm))?;
        let est = average_single(&p, &AverageSettings::default())?;
        let seconds = t.elapsed().as_secs_f64();
        let sol = &est.solution;
        let c = est
            .certificate
            .as_ref()
            .expect("single averaging always certifies");
        if json {
            out.push(serde_json::json!({
                "metric": metric,
                "norm": norm.name(),
                "estimate": rotation_to_rows(&sol.estimate),
                "cost": sol.cost,
                "cost_chordal_l2": problem.cost_under(&sol.estimate, Objective::CHORDAL_L2),
                "cost_geodesic_l2": problem.cost_under(&sol.estimate, Objective::new(Metric::Geodesic, Loss::L2)),
                "cost_geodesic_l1": problem.cost_under(&sol.estimate, Objective::new(Metric::Geodesic, Loss::L1)),
                "certified": c.is_certified(),
                "lower_bound": c.lower_bound,
                "gap": c.gap,
                "iterations": sol.report.iterations,
                "seconds": seconds,
            }));
        } else {
            println!("\n{est}");
            if let Some(t) = &truth {
                println!(
                    "  error to truth {:.4} deg",
                    angle_between(&sol.estimate, t).to_degrees()
                );
            }
        }
    }
    if json {
        println!(
            "{}",
            serde_json::json!({"num_samples": problem.len(), "methods": out})
        );
    }
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
