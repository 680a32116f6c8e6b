//! The report of `rotavg info`: a description of a view-graph file.

use crate::error::Result;
use crate::io::detect::{GraphFormat, ReadOptions, read_graph};
use crate::io::input::Input;
use crate::multiple::stats::{GraphStats, StatsSettings, graph_stats};
use serde::Serialize;
use std::fmt;
use std::time::Instant;

/// What a view-graph file holds: sizes, duplicates, components, degrees, weights, residuals
/// of the file's initial guess, spectral gap ([`GraphStats`]).
///
/// JSON (`--json`, the fields in this order): `file`, `format`, `planar`, `num_rotations`,
/// `num_measurements`, `reversed_edges`, `node_ids_contiguous`, `has_initial`, `warnings` (the
/// messages, as strings: the contract of `info` since its first version), `warning_details`
/// (the same warnings as every other verb writes them: `{code, message, count}`),
/// `load_seconds`, `stats`.
///
/// ```
/// use rotavg::io::input::Input;
/// use rotavg::io::detect::{GraphFormat, ReadOptions};
/// use rotavg::report::InfoReport;
/// let input = Input::new("EGs.txt", "0 1 1 0 0 0 1 0 0 0 1\n1 2 1 0 0 0 1 0 0 0 1\n");
/// let info = InfoReport::read(&input, GraphFormat::Auto, &ReadOptions::default())?;
/// assert_eq!((info.num_rotations, info.num_measurements), (3, 2));
/// assert!(info.to_string().contains("nodes:          3"));
/// let json = serde_json::to_value(&info).unwrap();
/// assert_eq!(json["format"], "one_dsfm"); // serde's name
/// assert_eq!(json["warning_details"], serde_json::json!([]));
/// # Ok::<(), rotavg::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct InfoReport {
    /// The input as given.
    pub file: String,
    /// The format read.
    pub format: GraphFormat,
    /// Every measurement is a planar rotation about z (g2o `EDGE_SE2`).
    pub planar: bool,
    /// Nodes.
    pub num_rotations: usize,
    /// Edges (multi-edges counted).
    pub num_measurements: usize,
    /// Edges given with `i > j` (kept as given).
    pub reversed_edges: usize,
    /// The file's node ids are `0..n`.
    pub node_ids_contiguous: bool,
    /// The file has an initial guess (vertex lines) for every node.
    pub has_initial: bool,
    /// The reader's remarks (their messages).
    pub warnings: Vec<String>,
    /// The same remarks with their codes and counts ([`crate::warning`]).
    pub warning_details: Vec<crate::warning::Warning>,
    /// Time to read the file, seconds.
    pub load_seconds: f64,
    /// The graph's statistics.
    pub stats: GraphStats,
    /// The smallest and largest file ids.
    #[serde(skip)]
    pub id_range: Option<(u64, u64)>,
}

impl InfoReport {
    /// Read the view graph of `input` and describe it (default [`StatsSettings`]).
    pub fn read(input: &Input, format: GraphFormat, options: &ReadOptions) -> Result<Self> {
        let start = Instant::now();
        let g = read_graph(&input.text, &input.name, format, options)?;
        Ok(Self::describe(
            &input.name,
            g,
            start.elapsed().as_secs_f64(),
        ))
    }

    /// Read the view graph at `path` (`-`: standard input; a COLMAP database or the folder
    /// holding one too, [`crate::io::input::load_view_graph`]) and describe it; `load_seconds`
    /// includes reading the file.
    pub fn load(path: &str, format: GraphFormat, options: &ReadOptions) -> Result<Self> {
        let start = Instant::now();
        let g = crate::io::input::load_view_graph(path, format, options)?;
        Ok(Self::describe(path, g, start.elapsed().as_secs_f64()))
    }

    fn describe(file: &str, g: crate::io::detect::LoadedGraph, load_seconds: f64) -> Self {
        let stats = graph_stats(&g.problem, g.initial.as_deref(), &StatsSettings::default());
        InfoReport {
            file: file.to_string(),
            format: g.format,
            planar: g.planar,
            num_rotations: stats.num_nodes,
            num_measurements: stats.num_edges,
            reversed_edges: g.reversed,
            node_ids_contiguous: g.node_ids.iter().enumerate().all(|(k, &id)| id == k as u64),
            has_initial: g.initial.is_some(),
            warnings: g.warnings.iter().map(|w| w.message.clone()).collect(),
            warning_details: g.warnings.clone(),
            load_seconds,
            stats,
            id_range: g.node_ids.first().copied().zip(g.node_ids.last().copied()),
        }
    }
}

impl fmt::Display for InfoReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "file:           {} ({} format{})",
            self.file,
            self.format,
            if self.planar { ", planar (2-D)" } else { "" }
        )?;
        if let Some((a, b)) = self.id_range
            && !self.node_ids_contiguous
        {
            writeln!(
                f,
                "node ids:       sparse ({a}..={b}), mapped to 0..{}",
                self.num_rotations
            )?;
        }
        writeln!(f, "{}", self.stats)?;
        writeln!(
            f,
            "reversed edges: {} (given with i > j; kept)",
            self.reversed_edges
        )?;
        writeln!(
            f,
            "vertex lines:   {}",
            if self.has_initial {
                "an initial guess for every node"
            } else {
                "none used"
            }
        )?;
        for w in &self.warnings {
            writeln!(f, "warning:        {w}")?;
        }
        write!(f, "load time:      {:.3} s", self.load_seconds)
    }
}
