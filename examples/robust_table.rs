//! Robust multiple rotation averaging on a synthetic 1DSfM-like scene with planted outliers:
//! accuracy (after the robust alignment), inlier detection and the inlier graph's certificate.
//!
//! ```text
//! cargo run --release --example robust_table -- [N] [M] [NOISE_DEG] [OUTLIER_FRACTION] [SEED]
//! ```
//!
//! Defaults: 300 cameras, 20,000 edges, 2 degrees of noise (RMS angle: `NOISE_DEG / sqrt(3)`
//! per tangent component), 20 % of the edges replaced by uniformly random rotations, seed 1.
//! Each row is one run of `average_multiple` (the command line's pipeline) with the loss, the
//! threshold 5 degrees (Huber threshold, Cauchy scale, inlier threshold for all three), and
//! `--certify auto`: the robust estimate, then the chordal L2 refinement and certificate of
//! its inlier graph (the "inlier L2" row under each loss). "precision" and "recall" are those
//! of the detected outliers (edges that are not inliers) against the planted ones. Prints a
//! Markdown table.
use rotavg::Metric;
use rotavg::multiple::MultipleSettings;
use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::objective::{Loss, Objective};
use rotavg::pipeline::{AverageSettings, average_multiple};

fn main() -> rotavg::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let arg = |k: usize, default: f64| -> f64 {
        args.get(k).and_then(|s| s.parse().ok()).unwrap_or(default)
    };
    let n = arg(1, 300.0) as usize;
    let m = arg(2, 20_000.0) as usize;
    let noise_deg = arg(3, 2.0);
    let outliers = arg(4, 0.2);
    let seed = arg(5, 1.0) as u64;
    let spec = SyntheticGraph {
        num_rotations: n,
        num_edges: m,
        noise_sigma: (noise_deg / 3f64.sqrt()).to_radians(),
        outlier_fraction: outliers,
        seed,
    };
    let (problem, truth, planted) = spec.generate_labelled();
    let truth: Vec<_> = truth.into_iter().map(Some).collect();
    let num_planted = planted.iter().filter(|&&o| o).count();
    println!(
        "{n} cameras, {} edges, noise {noise_deg} deg RMS, {num_planted} planted outliers ({:.1} %), seed {seed}\n",
        problem.num_edges(),
        100.0 * num_planted as f64 / problem.num_edges() as f64
    );
    println!(
        "| method | time (s) | median error (deg) | mean error (deg) | outliers detected | precision | recall | inlier-graph certificate |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    let chordal = average_multiple(&problem, &AverageSettings::default())?;
    let a = align_and_compare(&chordal.solution.rotations, &truth)?;
    println!(
        "| chordal L2 (all edges) | {:.2} | {:.3} | {:.3} | — | — | — | {} |",
        chordal.details.total_seconds,
        a.robust.median_deg,
        a.robust.mean_deg,
        chordal
            .certificate
            .as_ref()
            .map_or("none".into(), |c| c.verdict.to_string())
    );
    for loss in [
        Loss::L1,
        Loss::Huber { threshold_deg: 5.0 },
        Loss::Cauchy { scale_deg: 5.0 },
    ] {
        let p = problem
            .clone()
            .with_objective(Objective::new(Metric::Geodesic, loss))?;
        let settings = AverageSettings {
            solve: MultipleSettings {
                inlier_threshold_deg: Some(5.0),
                ..Default::default()
            },
            ..Default::default()
        };
        let out = average_multiple(&p, &settings)?;
        let r = out
            .solution
            .residuals
            .as_ref()
            .expect("robust losses carry residuals");
        let detected = r.inlier.iter().filter(|&&i| !i).count();
        let hits = r
            .inlier
            .iter()
            .zip(&planted)
            .filter(|&(&i, &o)| !i && o)
            .count();
        let a = align_and_compare(&out.solution.rotations, &truth)?;
        println!(
            "| {} | {:.2} | {:.3} | {:.3} | {detected} | {:.4} | {:.4} | — |",
            loss.name(),
            out.details.solve_seconds,
            a.robust.median_deg,
            a.robust.mean_deg,
            hits as f64 / detected.max(1) as f64,
            hits as f64 / num_planted.max(1) as f64,
        );
        if let Some(g) = &out.details.inlier_graph {
            let a = align_and_compare(&g.estimate, &truth)?;
            let verdict = g.certificate.as_ref().map_or("none".into(), |c| {
                format!(
                    "{} ({} of {} edges, {} of {} nodes, relative gap {:.1e})",
                    c.verdict,
                    g.problem.num_edges,
                    g.problem.total_edges,
                    g.problem.num_nodes,
                    g.problem.total_nodes,
                    c.relative_gap.unwrap_or(f64::NAN)
                )
            });
            println!(
                "| {} + inlier L2 | +{:.2} | {:.3} | {:.3} | | | | {verdict} |",
                loss.name(),
                out.details.certify_seconds,
                a.robust.median_deg,
                a.robust.mean_deg,
            );
        }
    }
    Ok(())
}
