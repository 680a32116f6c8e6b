//! Gravity priors on synthetic scenes (`paper-notes/gravity.md`): accuracy against the truth,
//! time and verdict of the chordal L2 solve without and with the priors, over sizes, gravity
//! noise and the fraction of images without a prior.
//!
//! ```text
//! cargo run --release --example gravity_table -- [EDGES_PER_CAMERA] [NOISE_DEG] [SEED]
//! ```
//!
//! Defaults: 4 edges per camera on a random connected graph (sparse: where gravity helps),
//! 3 degrees of relative-rotation noise (RMS angle; `NOISE_DEG / sqrt(3)` per tangent
//! component), seed 1. Rows: 100, 1000 and 10,000 cameras; gravity noise 0.1, 0.5 and 2
//! degrees with every image's prior, then 0.5 degrees with 30 % of the images without one;
//! the priors held as constraints and as soft terms weighted by their noise
//! (`W = sigma_e^2 / sigma_g^2`, `[G10]`).
//! Each run is `average_multiple` / `average_with_gravity` (the command line's pipelines,
//! default budget). Errors after the optimal global alignment. Prints a Markdown table.
use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::gravity::GravityProblem;
use rotavg::multiple::synthetic::{SyntheticGraph, SyntheticGravity};
use rotavg::pipeline::{AverageSettings, average_multiple, average_with_gravity};

fn verdict(c: &Option<rotavg::Certificate>) -> String {
    c.as_ref().map_or("none".into(), |c| match c.relative_gap {
        Some(g) if !c.is_certified() => format!("{} ({g:.1e})", c.verdict),
        _ => c.verdict.to_string(),
    })
}

fn main() -> rotavg::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: usize, default: f64| -> f64 {
        args.get(k).and_then(|s| s.parse().ok()).unwrap_or(default)
    };
    let (per_camera, noise_deg, seed) = (arg(1, 4.0), arg(2, 3.0), arg(3, 1.0) as u64);
    println!("{per_camera} edges per camera, {noise_deg} deg RMS relative noise, seed {seed}\n");
    println!(
        "| cameras | priors | gravity noise (deg) | mean error without (deg) | held (deg) | soft (deg) | time without (s) | held (s) | soft (s) | verdict without | held | soft |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for n in [100, 1000, 10_000] {
        let (graph, truth) = SyntheticGraph {
            num_rotations: n,
            num_edges: (per_camera * n as f64) as usize,
            noise_sigma: (noise_deg / 3f64.sqrt()).to_radians(),
            outlier_fraction: 0.0,
            seed,
        }
        .generate();
        let known: Vec<_> = truth.iter().copied().map(Some).collect();
        let free = average_multiple(&graph, &AverageSettings::default())?;
        let without = align_and_compare(&free.solution.rotations, &known)?;
        for (g_noise, missing) in [(0.1, 0.0), (0.5, 0.0), (2.0, 0.0), (0.5, 0.3)] {
            let priors = SyntheticGravity {
                noise_deg: g_noise,
                missing_fraction: missing,
                seed,
            }
            .priors(&truth)?;
            let label = format!("{} of {n}", priors.num_known());
            // the soft priors' weight by their noise: edges of weight 1 with sigma_e per axis,
            // priors turned by g_noise about one axis orthogonal to g (g_noise / sqrt(2) per
            // tilt axis): W = sigma_e^2 / sigma_g^2
            let weight = 2.0 * (noise_deg / 3f64.sqrt() / g_noise).powi(2);
            let p = GravityProblem::new(graph.clone(), priors.clone())?;
            let with = average_with_gravity(&p, &AverageSettings::default())?;
            let a = align_and_compare(&with.solution.rotations, &known)?;
            let soft_p = GravityProblem::new(graph.clone(), priors.with_weight(weight)?)?;
            let soft = average_with_gravity(&soft_p, &AverageSettings::default())?;
            let b = align_and_compare(&soft.solution.rotations, &known)?;
            println!(
                "| {n} | {label} | {g_noise} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {} | {} | {} |",
                without.mean_deg,
                a.mean_deg,
                b.mean_deg,
                free.details.total_seconds,
                with.details.total_seconds,
                soft.details.total_seconds,
                verdict(&free.certificate),
                verdict(&with.certificate),
                verdict(&soft.certificate)
            );
        }
    }
    outliers(noise_deg, seed)
}

/// The second table: 1000 cameras, 8 edges per camera, 15 % of the edges random rotations,
/// priors good to 0.5 degrees; least squares and the rule `auto` (Cauchy on these data), each
/// without the priors, with them held and with them soft; the verdict is the run's (the inlier graph's under `auto`).
fn outliers(noise_deg: f64, seed: u64) -> rotavg::Result<()> {
    use rotavg::io::names::MultipleLoss;
    use rotavg::multiple::MultipleSettings;
    let n = 1000;
    let (graph, truth) = SyntheticGraph {
        num_rotations: n,
        num_edges: 8 * n,
        noise_sigma: (noise_deg / 3f64.sqrt()).to_radians(),
        outlier_fraction: 0.15,
        seed,
    }
    .generate();
    let priors = SyntheticGravity {
        noise_deg: 0.5,
        missing_fraction: 0.0,
        seed,
    }
    .priors(&truth)?;
    let p = GravityProblem::new(graph.clone(), priors.clone())?;
    // soft priors weighted by their noise (as in the first table): W = 2 (sigma_e / 0.5 deg)^2
    let weight = 2.0 * (noise_deg / 3f64.sqrt() / 0.5).powi(2);
    let soft = GravityProblem::new(graph.clone(), priors.with_weight(weight)?)?;
    let known: Vec<_> = truth.iter().copied().map(Some).collect();
    println!(
        "\n{n} cameras, {} edges, 15 % outliers, priors 0.5 deg\n",
        8 * n
    );
    println!("| loss | priors | median error (deg) | mean error (deg) | time (s) | verdict |");
    println!("|---|---|---|---|---|---|");
    for loss in [MultipleLoss::Chordal, MultipleLoss::Auto] {
        let settings = AverageSettings {
            solve: MultipleSettings {
                robust_on_outliers: loss.robust_on_outliers(5.0),
                ..Default::default()
            },
            ..Default::default()
        };
        for with in ["none", "held", "soft"] {
            let r = match with {
                "held" => average_with_gravity(&p, &settings)?,
                "soft" => average_with_gravity(&soft, &settings)?,
                _ => average_multiple(&graph, &settings)?,
            };
            let a = align_and_compare(&r.solution.rotations, &known)?;
            let c = r.certificate.clone().or_else(|| {
                r.details
                    .inlier_graph
                    .as_ref()
                    .and_then(|g| g.certificate.clone())
            });
            println!(
                "| {loss} | {with} | {:.3} | {:.3} | {:.3} | {} |",
                a.robust.median_deg,
                a.robust.mean_deg,
                r.details.total_seconds,
                verdict(&c)
            );
        }
    }
    Ok(())
}
