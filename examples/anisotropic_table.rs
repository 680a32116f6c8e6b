//! Anisotropic against isotropic chordal averaging on synthetic graphs with anisotropic noise
//! (`paper-notes/anisotropic.md`, docs/benchmarks.md "Anisotropic measurements").
//!
//! ```text
//! cargo run --release --example anisotropic_table -- [MAX_NODES]
//! ```
//!
//! Each row is one graph of `n` cameras and `4n` edges from
//! [`rotavg::multiple::synthetic::SyntheticAnisotropic`]: residual standard deviations 0.5, 0.5
//! and `0.5 x ratio` degrees (one weak axis) or 0.5, `0.5 x ratio` and `0.5 x ratio` degrees
//! (two weak axes: one well-determined axis, where the `O(3)` relaxation prefers reflections
//! and the `conv(SO(3))` dual certificate `[A11]` certifies) along a random frame per edge,
//! information the inverse covariance, seed 1. "anisotropic" is `average_multiple` on it (the command line's pipeline, certify
//! `auto`); "isotropic" the same graph with weights `tr(H) / 3` and no information. Errors are
//! after the optimal alignment to the planted truth. Rows up to `MAX_NODES` (default 10000).
//! Prints a Markdown table, then the certified fraction over 10 seeds of small graphs with two
//! weak axes.
//!
//! ```text
//! cargo run --release --example anisotropic_table -- --export DIR [MAX_NODES]
//! ```
//!
//! writes each row's graph instead, as `DIR/aniso_<n>_<ratio>_<outlier %>.json` (the contract's JSON
//! with an `information` per edge) and `..._truth.txt` (`id R11 .. R33`), for the GTSAM
//! comparison of `benches/peers/run.sh aniso` (docs/benchmarks.md).
use rotavg::multiple::MultipleProblem;
use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::synthetic::SyntheticAnisotropic;
use rotavg::pipeline::{AverageSettings, average_multiple};

fn main() -> rotavg::Result<()> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let export = match args.first().map(String::as_str) {
        Some("--export") if args.len() >= 2 => {
            let dir = std::path::PathBuf::from(args.remove(1));
            args.remove(0);
            std::fs::create_dir_all(&dir).map_err(|e| rotavg::Error::Io {
                path: dir.display().to_string(),
                message: e.to_string(),
            })?;
            Some(dir)
        }
        _ => None,
    };
    let max_nodes: usize = args.first().and_then(|s| s.parse().ok()).unwrap_or(10_000);
    if export.is_none() {
        println!(
            "| n | edges | weak axes | std ratio | outliers | median error aniso / iso (deg) | aniso verdict | bound from | rel. gap | Newton its | solve (s) | certify (s) | iso solve + certify (s) |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    }
    let rows = [
        (30, 1, 3.0, 0.0),
        (30, 1, 20.0, 0.0),
        (200, 1, 3.0, 0.0),
        (200, 1, 10.0, 0.0),
        (200, 1, 20.0, 0.0),
        (200, 1, 10.0, 0.1),
        (1000, 1, 10.0, 0.0),
        (10_000, 1, 10.0, 0.0),
        (30, 2, 10.0, 0.0),
        (30, 2, 20.0, 0.0),
        (100, 2, 20.0, 0.0),
        (200, 2, 10.0, 0.0),
        (200, 2, 15.0, 0.0),
        (200, 2, 20.0, 0.0),
        (1000, 2, 10.0, 0.0),
        (1000, 2, 15.0, 0.0),
        (10_000, 2, 10.0, 0.0),
    ];
    for (n, weak_axes, ratio, outliers) in rows {
        if n > max_nodes {
            continue;
        }
        let (p, truth) = SyntheticAnisotropic {
            num_rotations: n,
            num_edges: 4 * n,
            sigma: 0.5f64.to_radians(),
            ratio,
            random_axes: true,
            outlier_fraction: outliers,
            seed: 1,
            weak_axes,
            ratio_spread: 0.0,
        }
        .generate();
        if let Some(dir) = &export {
            // the GTSAM comparison's files keep their names for one weak axis
            let weak = if weak_axes == 2 { "w2_" } else { "" };
            let stem = dir.join(format!("aniso_{weak}{n}_{ratio}_{:.0}", 100.0 * outliers));
            let mut list = String::new();
            for (i, r) in truth.iter().enumerate() {
                list += &format!("{i}");
                for row in 0..3 {
                    for col in 0..3 {
                        list += &format!(" {:.17e}", r.matrix()[(row, col)]);
                    }
                }
                list.push('\n');
            }
            let write = |path: std::path::PathBuf, text: &str| {
                std::fs::write(&path, text).map_err(|e| rotavg::Error::Io {
                    path: path.display().to_string(),
                    message: e.to_string(),
                })
            };
            write(
                stem.with_extension("json"),
                &rotavg::io::json::write_problem_json(&p),
            )?;
            write(
                dir.join(format!(
                    "{}_truth.txt",
                    stem.file_name().unwrap_or_default().to_string_lossy()
                )),
                &list,
            )?;
            continue;
        }
        let truth: Vec<_> = truth.into_iter().map(Some).collect();
        let iso = MultipleProblem::new(p.num_rotations(), p.edges().to_vec())?;
        let a = average_multiple(&p, &AverageSettings::default())?;
        let i = average_multiple(&iso, &AverageSettings::default())?;
        let ea = align_and_compare(&a.solution.rotations, &truth)?;
        let ei = align_and_compare(&i.solution.rotations, &truth)?;
        let c = a.certificate.as_ref();
        println!(
            "| {n} | {} | {weak_axes} | {ratio} | {:.0} % | {:.3} / {:.3} | {} | {} | {} | {} | {:.3} | {:.3} | {:.3} |",
            p.num_edges(),
            100.0 * outliers,
            ea.median_deg,
            ei.median_deg,
            c.map_or("none".into(), |c| c.verdict.to_string()),
            c.and_then(|c| c.bound_from)
                .map_or("-".into(), |b| serde_json::to_string(&b)
                    .unwrap_or_default()
                    .replace('"', "")),
            c.and_then(|c| c.relative_gap)
                .map_or("-".into(), |g| format!("{g:.1e}")),
            a.solution.report.iterations,
            a.details.solve_seconds,
            a.details.certify_seconds,
            i.details.total_seconds,
        );
    }
    if export.is_none() {
        certified_fraction(max_nodes)?;
    }
    Ok(())
}

/// The certified fraction over seeds 1-10 of graphs with two weak axes (`4n` edges), and how
/// many bounds stayed below the planted truth's cost (every one must).
fn certified_fraction(max_nodes: usize) -> rotavg::Result<()> {
    println!();
    println!(
        "| n | weak axes | std ratio | certified | bound below the truth's cost | certify (s, mean) |"
    );
    println!("|---|---|---|---|---|---|");
    for (n, ratio) in [
        (10, 20.0),
        (30, 10.0),
        (30, 20.0),
        (100, 10.0),
        (100, 20.0),
        (300, 15.0),
    ] {
        if n > max_nodes {
            continue;
        }
        let (mut certified, mut below, mut seconds) = (0, 0, 0.0);
        for seed in 1..=10 {
            let (p, truth) = SyntheticAnisotropic {
                num_rotations: n,
                num_edges: 4 * n,
                ratio,
                weak_axes: 2,
                seed,
                ..Default::default()
            }
            .generate();
            let a = average_multiple(&p, &AverageSettings::default())?;
            let c = a.certificate.as_ref();
            certified += usize::from(c.is_some_and(|c| c.is_certified()));
            below += usize::from(
                c.and_then(|c| c.lower_bound)
                    .is_some_and(|lb| lb <= p.chordal_cost(&truth)),
            );
            seconds += a.details.certify_seconds;
        }
        println!(
            "| {n} | 2 | {ratio} | {certified} / 10 | {below} / 10 | {:.3} |",
            seconds / 10.0
        );
    }
    Ok(())
}
