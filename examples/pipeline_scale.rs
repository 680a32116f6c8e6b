//! Measure the pipeline on synthetic graphs:
//! `cargo run --release --example pipeline_scale -- N M SIGMA [ABSOLUTE_TOLERANCE_PER_MEDIAN_WEIGHT]`.
use rotavg::certify::{CertifySettings, ToleranceRule};
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::pipeline::{AverageMultipleSettings, average_multiple};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(10_000);
    let m: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(3 * n);
    let sigma: f64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0.05);
    let per_weight: f64 = args.get(4).and_then(|s| s.parse().ok()).unwrap_or(1e-9);
    let (p, _) = SyntheticGraph {
        num_rotations: n,
        num_edges: m,
        noise_sigma: sigma,
        ..Default::default()
    }
    .generate();
    let settings = AverageMultipleSettings {
        certify: CertifySettings {
            tolerance: ToleranceRule {
                absolute_per_median_weight: per_weight,
                ..Default::default()
            },
            ..Default::default()
        },
        ..Default::default()
    };
    match average_multiple(&p, &settings) {
        Ok(e) => println!(
            "n {n} m {m} sigma {sigma}: {e}\nmethods: {:?}",
            e.details
                .certify
                .iter()
                .flat_map(|c| &c.methods)
                .map(|r| (r.method, r.lower_bound, r.seconds))
                .collect::<Vec<_>>()
        ),
        Err(e) => println!("error: {e}"),
    }
}
