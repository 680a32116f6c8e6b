//! The simultaneous problem (hand-eye rotation jointly with two view graphs) on synthetic rigs:
//! how often the trace-coupled relaxation `[H14]` certifies the joint estimate
//! (`paper-notes/conjugate.md`, docs/benchmarks.md "Simultaneous rigs").
//!
//! ```text
//! cargo run --release --example simultaneous_table -- [MAX_NODES] [SEEDS]
//! ```
//!
//! Each row is `SEEDS` rigs (default 5) of [`rotavg::pipeline::simultaneous::SyntheticRig`]:
//! `n` nodes and `2n` edges per graph (the same pairs), Gaussian noise `sigma` per tangent
//! component on every edge, a fraction of outliers on each graph. "decoupled" is the sum of the
//! two graphs' separately certified optima (the value of the earlier relaxation `[H12]`), as a
//! fraction of the joint cost. Mode `auto`: the dual certificate at the estimate `[H15]` first,
//! then the SDP `[H14]` where it fits the default budget (up to about 35 nodes). Rows up to
//! `MAX_NODES` (default 200).
//!
//! ```text
//! cargo run --release --example simultaneous_table -- --one N SIGMA [auto|dual|sdp]
//! ```
//!
//! runs one rig (seed 0, no outliers) in the given certify mode (default `auto`) and prints the prediction, the times and the process's
//! peak resident memory (`VmHWM`, Linux), to check the SDP's memory model.
use rotavg::certify::simultaneous::dual::predict_multipliers_at_estimate;
use rotavg::certify::{BoundMethod, CertifyMode};
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::pipeline::average_multiple;
use rotavg::pipeline::simultaneous::{
    AverageSimultaneousSettings, SyntheticRig, average_simultaneous,
};
use rotavg::relax::simultaneous::predict_relax_simultaneous;

fn peak_rss_gb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("VmHWM:"))?.to_string();
            line.split_whitespace().nth(1)?.parse::<f64>().ok()
        })
        .map_or(f64::NAN, |kb| kb * 1024.0 / 1e9)
}

fn rig(n: usize, sigma: f64, outliers: f64, seed: u64) -> SyntheticRig {
    SyntheticRig {
        graph: SyntheticGraph {
            num_rotations: n,
            num_edges: 2 * n,
            noise_sigma: sigma,
            outlier_fraction: outliers,
            seed,
        },
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        f64::NAN
    } else {
        v[v.len() / 2]
    }
}

fn main() -> rotavg::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--one") {
        let n: usize = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(20);
        let sigma: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0.1);
        let p = predict_relax_simultaneous(n);
        let q = predict_multipliers_at_estimate(n);
        let mode = match args.get(3).map(String::as_str) {
            Some("dual") => CertifyMode::Dual,
            Some("sdp") => CertifyMode::Sdp,
            _ => CertifyMode::Auto,
        };
        let (problem, _, _) = rig(n, sigma, 0.0, 0).generate();
        let mut settings = AverageSimultaneousSettings::default();
        settings.certify.mode = mode;
        let avg = average_simultaneous(&problem, &settings)?;
        let c = avg.certificate.expect("mode auto certifies");
        println!(
            "n {n} sigma {sigma}: {} rel. gap {:.2e}; solve {:.3} s, certify {:.2} s (predicted: dual {:.2} s, SDP {:.1} s); peak RSS {:.2} GB (predicted: dual {:.2} GB, SDP {:.2} GB)",
            c.verdict,
            c.relative_gap.unwrap_or(f64::NAN),
            avg.details.solve_seconds,
            avg.details.certify_seconds,
            q.seconds,
            p.seconds,
            peak_rss_gb(),
            q.bytes / 1e9,
            p.bytes / 1e9
        );
        if let Some(d) = &avg.details.certify {
            for a in &d.ladder {
                println!("  {} at {}: {}", a.rung, a.point, a.outcome);
            }
        }
        return Ok(());
    }
    let max_nodes: usize = args.first().and_then(|s| s.parse().ok()).unwrap_or(200);
    let seeds: u64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(5);
    println!(
        "| n | edges per graph | sigma (rad) | outliers | certified (by dual / by SDP) | median rel. gap (gap reported) | decoupled bound / joint cost | median solve (s) | median certify (s) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for n in [5, 10, 20, 30, 60, 100, 200]
        .into_iter()
        .filter(|&n| n <= max_nodes)
    {
        for (sigma, outliers) in [(0.05, 0.0), (0.1, 0.0), (0.3, 0.0), (0.05, 0.1)] {
            let (mut by_dual, mut by_sdp) = (0, 0);
            let (mut certified, mut gaps, mut ratios, mut solve, mut certify) =
                (0, vec![], vec![], vec![], vec![]);
            for seed in 0..seeds {
                let (problem, _, _) = rig(n, sigma, outliers, seed).generate();
                let avg = average_simultaneous(&problem, &Default::default())?;
                let c = avg.certificate.expect("mode auto certifies");
                if c.is_certified() {
                    certified += 1;
                    if c.method == BoundMethod::Dual {
                        by_dual += 1;
                    } else {
                        by_sdp += 1;
                    }
                } else if let Some(g) = c.relative_gap {
                    gaps.push(g);
                }
                let (right, left) = problem.graphs()?;
                let mut separate = 0.0;
                for g in [right, left] {
                    separate += average_multiple(&g, &Default::default())?.solution.cost;
                }
                ratios.push(separate / avg.solution.cost);
                solve.push(avg.details.solve_seconds);
                certify.push(avg.details.certify_seconds);
            }
            println!(
                "| {n} | {} | {sigma} | {:.0} % | {certified}/{seeds} ({by_dual} / {by_sdp}) | {} | {:.2} | {:.4} | {:.3} |",
                2 * n,
                100.0 * outliers,
                if gaps.is_empty() {
                    "-".to_string()
                } else {
                    format!("{:.1e}", median(gaps))
                },
                median(ratios),
                median(solve),
                median(certify),
            );
        }
    }
    Ok(())
}
