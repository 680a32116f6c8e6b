//! `rotavg info INPUT [--format auto|g2o|1dsfm|json] [--weights file|unit] [--json]`: describe
//! a view-graph file (sizes, duplicates, components, degrees, weights, residuals of the file's
//! initial guess, spectral gap).

use crate::Outcome;
use crate::common::read_input;
use clap::{Args as ClapArgs, ValueEnum};
use rotavg::io::detect::{GraphFormat, ReadOptions, WeightSource, read_graph};
use rotavg::multiple::stats::{StatsSettings, graph_stats};

/// Input format choices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FormatArg {
    /// From the extension, then the content.
    Auto,
    /// g2o / TORO pose graph.
    G2o,
    /// 1DSfM EGs.txt.
    #[value(name = "1dsfm")]
    OneDsfm,
    /// JSON problem (SPEC section 5).
    Json,
}

impl From<FormatArg> for GraphFormat {
    fn from(f: FormatArg) -> Self {
        match f {
            FormatArg::Auto => GraphFormat::Auto,
            FormatArg::G2o => GraphFormat::G2o,
            FormatArg::OneDsfm => GraphFormat::OneDsfm,
            FormatArg::Json => GraphFormat::Json,
        }
    }
}

/// Weight choices.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum WeightArg {
    /// From the file (g2o: SE-Sync's kappa).
    File,
    /// All 1.
    Unit,
}

/// Arguments of `rotavg info`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Input file, or `-` for standard input.
    pub input: String,
    /// Input format.
    #[arg(long, value_enum, default_value_t = FormatArg::Auto)]
    pub format: FormatArg,
    /// Weights from the file (`file`, default) or all 1 (`unit`).
    #[arg(long, value_enum, default_value_t = WeightArg::File)]
    pub weights: WeightArg,
    /// Print one JSON object instead of the readable summary.
    #[arg(long)]
    pub json: bool,
}

/// Run the subcommand.
pub fn run(args: &Args) -> rotavg::Result<Outcome> {
    let (name, text) = read_input(&args.input)?;
    let options = ReadOptions {
        weights: match args.weights {
            WeightArg::File => WeightSource::File,
            WeightArg::Unit => WeightSource::Unit,
        },
        ..Default::default()
    };
    let start = std::time::Instant::now();
    let g = read_graph(&text, &name, args.format.into(), &options)?;
    let load_seconds = start.elapsed().as_secs_f64();
    let stats = graph_stats(&g.problem, g.initial.as_deref(), &StatsSettings::default());
    if args.json {
        let ids_contiguous = g.node_ids.iter().enumerate().all(|(k, &id)| id == k as u64);
        let value = serde_json::json!({
            "file": name,
            "format": g.format,
            "planar": g.planar,
            "num_rotations": stats.num_nodes,
            "num_measurements": stats.num_edges,
            "reversed_edges": g.reversed,
            "node_ids_contiguous": ids_contiguous,
            "has_initial": g.initial.is_some(),
            "warnings": g.warnings,
            "load_seconds": load_seconds,
            "stats": stats,
        });
        println!("{value}");
    } else {
        println!(
            "file:           {name} ({} format{})",
            g.format,
            if g.planar { ", planar (2-D)" } else { "" }
        );
        if let (Some(a), Some(b)) = (g.node_ids.first(), g.node_ids.last()) {
            let contiguous = *b + 1 == g.node_ids.len() as u64 && *a == 0;
            if !contiguous {
                println!(
                    "node ids:       sparse ({a}..={b}), mapped to 0..{}",
                    g.node_ids.len()
                );
            }
        }
        println!("{stats}");
        println!("reversed edges: {} (given with i > j; kept)", g.reversed);
        println!(
            "vertex lines:   {}",
            if g.initial.is_some() {
                "an initial guess for every node"
            } else {
                "none used"
            }
        );
        for w in &g.warnings {
            println!("warning:        {w}");
        }
        println!("load time:      {:.3} s", load_seconds);
    }
    Ok(Outcome { verdict: None })
}
