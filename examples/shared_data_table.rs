//! The README's table "Multiple averaging on every graph of the shared data": every view graph
//! of the shared benchmark data, with unit and with file weights, solved and certified by the
//! default pipeline ([`rotavg::pipeline::average_multiple`]).
//!
//! ```text
//! cargo run --release --example shared_data_table [-- DATA_DIR]
//! ```
//!
//! `DATA_DIR` defaults to `../shared/data` beside the repository, else `/work/shared/data`; the
//! program prints a notice and exits 0 when neither exists. Prints one Markdown table row per
//! file and weighting: sizes, cost, verdict, gap, relative gap, the tolerance part that decided,
//! and the solve and certify seconds.

use rotavg::certify::TolerancePart;
use rotavg::io::detect::{GraphFormat, ReadOptions, WeightSource, load_graph};
use rotavg::pipeline::{AverageSettings, average_multiple};
use std::path::{Path, PathBuf};

fn graph_files(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.join("g2o"), dir.join("1dsfm")];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "g2o" || x == "txt")
                && (p.starts_with(dir.join("g2o")) || p.ends_with("EGs.txt"))
            {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

fn main() -> rotavg::Result<()> {
    let dir = std::env::args_os().nth(1).map(PathBuf::from).or_else(|| {
        [
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"),
            PathBuf::from("/work/shared/data"),
        ]
        .into_iter()
        .find(|p| p.is_dir())
    });
    let Some(dir) = dir else {
        println!("shared data not found: nothing to do");
        return Ok(());
    };
    println!(
        "| file | weights | n | m | cost | verdict | gap | relative gap | decided by | solve s | certify s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for path in graph_files(&dir) {
        let name = path
            .strip_prefix(&dir)
            .unwrap_or(&path)
            .display()
            .to_string();
        for (label, weights) in [("unit", WeightSource::Unit), ("file", WeightSource::File)] {
            let options = ReadOptions {
                weights,
                ..Default::default()
            };
            let graph = match load_graph(&path, GraphFormat::Auto, &options) {
                Ok(g) => g,
                Err(e) => {
                    println!("| {name} | {label} | not read: {e} |");
                    continue;
                }
            };
            let p = &graph.problem;
            let est = average_multiple(p, &AverageSettings::default())?;
            let (verdict, gap, rel, part, secs) = match &est.certificate {
                Some(c) => (
                    c.verdict.to_string(),
                    c.gap.map_or("-".into(), |g| format!("{g:.1e}")),
                    c.relative_gap.map_or("-".into(), |g| format!("{g:.1e}")),
                    match c.tolerance_part {
                        TolerancePart::Relative => "relative",
                        TolerancePart::Absolute => "absolute",
                    },
                    format!("{:.3}", c.seconds),
                ),
                None => ("none".into(), "-".into(), "-".into(), "-", "-".into()),
            };
            println!(
                "| {name} | {label} | {} | {} | {:.6e} | {verdict} | {gap} | {rel} | {part} | {:.3} | {secs} |",
                p.num_rotations(),
                p.num_edges(),
                est.solution.cost,
                est.solution.report.seconds,
            );
        }
    }
    Ok(())
}
