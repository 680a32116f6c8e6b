//! The SDP relaxation's predicted cost against a measured solve (issue 25, `paper-notes/sdp.md`
//! `[P6]`): one random view graph per run, so that the peak memory is the solve's own.
//!
//! ```text
//! cargo run --release --example sdp_predict -- N M [OUTLIER_FRACTION] [--predict-only]
//! ```
//!
//! Prints the prediction (`relax::predict_relax_multiple`: cliques, largest clique, bytes,
//! seconds) and, unless `--predict-only`, the measured solve time and the process's peak
//! resident memory (`VmHWM` of `/proc/self/status`, Linux).
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::relax::{SdpSettings, predict_relax_multiple, relax_multiple};

fn peak_rss_bytes() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024.0)
}

fn main() -> Result<(), rotavg::Error> {
    let args: Vec<String> = std::env::args().collect();
    let predict_only = args.iter().any(|a| a == "--predict-only");
    let num: Vec<f64> = args[1..].iter().filter_map(|a| a.parse().ok()).collect();
    let n = num.first().copied().unwrap_or(60.0) as usize;
    let m = num.get(1).copied().unwrap_or(4.0 * n as f64) as usize;
    let outliers = num.get(2).copied().unwrap_or(0.0);
    let (problem, _) = SyntheticGraph {
        num_rotations: n,
        num_edges: m,
        noise_sigma: 0.05,
        outlier_fraction: outliers,
        seed: 1,
    }
    .generate();
    let p = predict_relax_multiple(&problem)?;
    println!(
        "n {n} m {m} outliers {outliers}: predicted {} cliques, largest {} nodes, {:.2} GB, {:.1} s",
        p.cliques,
        p.largest_clique,
        p.bytes / 1e9,
        p.seconds
    );
    if !predict_only {
        let before = peak_rss_bytes().unwrap_or(0.0);
        let sol = relax_multiple(&problem, &SdpSettings::default())?;
        let after = peak_rss_bytes().unwrap_or(0.0);
        println!(
            "measured: {:?}, {} iterations, {:.2} s, peak RSS {:.2} GB (before the solve {:.2} GB)",
            sol.status,
            sol.iterations,
            sol.seconds,
            after / 1e9,
            before / 1e9
        );
    }
    Ok(())
}
