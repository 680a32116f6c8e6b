//! Anisotropic against isotropic chordal averaging on synthetic graphs with anisotropic noise
//! (`paper-notes/anisotropic.md`, docs/benchmarks.md "Anisotropic measurements").
//!
//! ```text
//! cargo run --release --example anisotropic_table -- [MAX_NODES]
//! ```
//!
//! Each row is one graph of `n` cameras and `4n` edges from
//! [`rotavg::multiple::synthetic::SyntheticAnisotropic`]: residual standard deviations 0.5, 0.5
//! and `0.5 x ratio` degrees along a random frame per edge, information the inverse covariance,
//! seed 1. "anisotropic" is `average_multiple` on it (the command line's pipeline, certify
//! `auto`); "isotropic" the same graph with weights `tr(H) / 3` and no information. Errors are
//! after the optimal alignment to the planted truth. Rows up to `MAX_NODES` (default 10000).
//! Prints a Markdown table.
//!
//! ```text
//! cargo run --release --example anisotropic_table -- --export DIR [MAX_NODES]
//! ```
//!
//! writes each row's graph instead, as `DIR/aniso_<n>_<ratio>_<outlier %>.json` (SPEC's JSON
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
            "| n | edges | std ratio | outliers | median error aniso / iso (deg) | aniso verdict | rel. gap | Newton its | solve (s) | certify (s) | iso solve + certify (s) |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|");
    }
    let rows = [
        (30, 3.0, 0.0),
        (30, 20.0, 0.0),
        (200, 3.0, 0.0),
        (200, 10.0, 0.0),
        (200, 20.0, 0.0),
        (200, 10.0, 0.1),
        (1000, 10.0, 0.0),
        (10_000, 10.0, 0.0),
    ];
    for (n, ratio, outliers) in rows {
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
        }
        .generate();
        if let Some(dir) = &export {
            let stem = dir.join(format!("aniso_{n}_{ratio}_{:.0}", 100.0 * outliers));
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
            "| {n} | {} | {ratio} | {:.0} % | {:.3} / {:.3} | {} | {} | {} | {:.3} | {:.3} | {:.3} |",
            p.num_edges(),
            100.0 * outliers,
            ea.median_deg,
            ei.median_deg,
            c.map_or("none".into(), |c| c.verdict.to_string()),
            c.and_then(|c| c.relative_gap)
                .map_or("-".into(), |g| format!("{g:.1e}")),
            a.solution.report.iterations,
            a.details.solve_seconds,
            a.details.certify_seconds,
            i.details.total_seconds,
        );
    }
    Ok(())
}
