//! Conjugate (hand-eye) rotation averaging on a seeded synthetic instance: find `S` with
//! `R_i ~ S^-1 L_i S`, certify it with the SDP, and compare with the planted `S`.
//!
//! ```text
//! cargo run --release --example conjugate [-- PAIRS SIGMA_DEG OUTLIER_FRACTION]
//! ```
//!
//! Defaults: 100 pairs, 2 degrees of noise per axis, 10 % outliers. The chordal L2 pipeline
//! ([`rotavg::pipeline::average_conjugate`]) runs the closed-form initialiser, the local
//! solver, and the SDP relaxation (Clarabel), whose multipliers give a verified lower bound.

use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::conjugate::synthetic::random_instance;
use rotavg::pipeline::{AverageSettings, average_conjugate};
use rotavg::so3::angle_between;
use std::time::Instant;

fn arg<T: std::str::FromStr>(k: usize, default: T) -> rotavg::Result<T> {
    match std::env::args().nth(k) {
        None => Ok(default),
        Some(s) => s.parse().map_err(|_| rotavg::Error::InvalidSettings {
            name: format!("argument {k}"),
            reason: format!(
                "cannot parse `{s}` (usage: conjugate [PAIRS SIGMA_DEG OUTLIER_FRACTION])"
            ),
        }),
    }
}

fn run() -> rotavg::Result<()> {
    let pairs: usize = arg(1, 100)?;
    let sigma_deg: f64 = arg(2, 2.0)?;
    let outliers: f64 = arg(3, 0.1)?;
    let mut rng = StdRng::seed_from_u64(42);
    let (problem, truth) = random_instance(pairs, sigma_deg.to_radians(), outliers, &mut rng);
    println!(
        "{} pairs, noise {sigma_deg} deg per axis, outlier fraction {outliers}",
        problem.num_pairs()
    );

    let t = Instant::now();
    let est = average_conjugate(&problem, &AverageSettings::default())?;
    let seconds = t.elapsed().as_secs_f64();

    let s = &est.solution;
    println!("solver       {}", s.report);
    println!("chordal cost {:.9e}", s.chordal_cost);
    println!(
        "error to planted S {:.4} deg",
        angle_between(&s.estimate, &truth).to_degrees()
    );
    if let Some(sdp) = est.details.certify.as_ref().and_then(|c| c.sdp.as_ref()) {
        println!(
            "sdp          {:?}, {} iterations, {:.2} ms, eigenvalue ratio {:.1e}",
            sdp.status,
            sdp.iterations,
            sdp.seconds * 1e3,
            sdp.eigenvalue_ratio
        );
    }
    match &est.certificate {
        Some(c) => println!("certificate  {c}"),
        None => println!("certificate  none"),
    }
    println!("total        {:.2} ms", seconds * 1e3);
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
