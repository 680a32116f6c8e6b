//! The front door for view-graph files: the loaded-graph type shared by every reader, the
//! reader options, and format auto-detection (from the extension, then from the content).
//!
//! Formats and their conventions are documented where each is read ([`crate::io::g2o`],
//! [`crate::io::sfm`], [`crate::io::json`]) and in `paper-notes/formats.md` (`[F1]`..`[F8]`).

use crate::error::{Error, Result};
use crate::io::names::Choice;
use crate::io::text::{MAX_INPUT_BYTES, TextStream};
use crate::multiple::MultipleProblem;
use crate::so3::{DEFAULT_ROTATION_TOLERANCE, Rotation};
use crate::warning::Warning;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::Path;
use std::str::FromStr;

/// Where edge weights come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WeightSource {
    /// From the file where the format has them (g2o: SE-Sync's `kappa`, `[F3]`); 1 otherwise.
    #[default]
    File,
    /// All weights 1.
    Unit,
}

/// A view-graph file format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GraphFormat {
    /// Decide from the extension, then from the content ([`detect_format`]).
    #[default]
    Auto,
    /// g2o / TORO pose graph: `EDGE_SE3:QUAT`, `EDGE3`, `EDGE_SE2` (+ optional vertex lines).
    G2o,
    /// 1DSfM `EGs.txt`: `i j R11..R33 [tx ty tz]` per line.
    OneDsfm,
    /// The JSON problem format of contract section 5.
    Json,
    /// A COLMAP database (SQLite: tables `images` and `two_view_geometries`,
    /// [`crate::io::colmap::read_colmap_database`]); read from a path, never from text.
    Colmap,
}

impl fmt::Display for GraphFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(Choice::name(self))
    }
}

impl FromStr for GraphFormat {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.to_ascii_lowercase().as_str() {
            "auto" => Ok(GraphFormat::Auto),
            "g2o" | "toro" => Ok(GraphFormat::G2o),
            "1dsfm" | "egs" => Ok(GraphFormat::OneDsfm),
            "json" => Ok(GraphFormat::Json),
            "colmap" => Ok(GraphFormat::Colmap),
            _ => Err(Error::InvalidSettings {
                name: "format".into(),
                reason: format!("unknown format `{s}` (expected auto, g2o, 1dsfm, json or colmap)"),
            }),
        }
    }
}

/// Options of the view-graph readers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ReadOptions {
    /// Weights from the file or all 1.
    pub weights: WeightSource,
    /// Tolerance for matrices given as rotations (1DSfM, JSON): `||R^T R - I||_F` and
    /// `|det R - 1|` must not exceed it ([`crate::so3::rotation_from_matrix`]).
    pub rotation_tolerance: f64,
    /// Tolerance for quaternions (g2o): `| ||q|| - 1 |` must not exceed it; accepted quaternions
    /// are normalised. Files written with 6 decimals are accurate to about 1e-6.
    pub quaternion_tolerance: f64,
    /// Each format's full rotation information (`Some(true)`, `--information full`), its
    /// scalar weight (`Some(false)`, `--information kappa`) or the format's default (`None`,
    /// `--information auto`, the default):
    /// - g2o / TORO edges with an information matrix: `Some(true)` makes them anisotropic
    ///   measurements with their full 3x3 rotation information (`paper-notes/anisotropic.md`
    ///   `[A7]`); `Some(false)` and `None` give SE-Sync's scalar `kappa`.
    /// - COLMAP databases: `Some(true)` gives each pair the rotation information of its inlier
    ///   correspondences and the cameras (`paper-notes/formats.md` `[F13]`,
    ///   [`crate::io::two_view_information`]); `Some(false)` weights 1. `None` reads the
    ///   information where the database gives it, and otherwise weights 1 with the warning
    ///   `database_without_information` naming why (no keypoints, no relative translations,
    ///   a camera model without an undistortion, ...). `rotavg certify` and rigs read from a
    ///   database ([`crate::io::rig::read_colmap_rig`]) take `None` as `Some(false)`
    ///   ([`ReadOptions::scalar_by_default`]).
    /// - Other formats are unaffected (JSON view graphs and rigs: `information` is read unless
    ///   [`WeightSource::Unit`]; `kappa` and `full` change nothing).
    ///
    /// A graph's [`LoadedGraph::read`] records what was read: `Some(true)` or `Some(false)`.
    pub full_information: Option<bool>,
}

/// [`ReadOptions::full_information`] of a name, the command line's `--information`: `auto`
/// (`None`), `kappa` (`Some(false)`) or `full` (`Some(true)`).
///
/// ```
/// use rotavg::io::detect::information_choice;
/// assert_eq!(information_choice("full")?, Some(true));
/// assert_eq!(information_choice("auto")?, None);
/// assert!(information_choice("diagonal").is_err());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn information_choice(name: &str) -> Result<Option<bool>> {
    match name {
        "auto" => Ok(None),
        "kappa" => Ok(Some(false)),
        "full" => Ok(Some(true)),
        other => Err(Error::InvalidSettings {
            name: "information".into(),
            reason: format!("information must be \"auto\", \"kappa\" or \"full\", got {other:?}"),
        }),
    }
}

impl ReadOptions {
    /// These options with `--information auto` read as `kappa` (weights 1 on a COLMAP
    /// database): the rule of `rotavg certify` and of rigs. Certifying a given estimate for the
    /// least-squares problem over every pair of an SfM database is rarely tight with the
    /// pairs' information, whose wrong pairs are as confident as the right ones: on a
    /// generated 1000-image scene 64-76 s of certificate for a bound 99 % below the cost, where
    /// weights 1 took 0.12 s (`docs/benchmarks.md`, "A database's information by default").
    ///
    /// ```
    /// use rotavg::io::detect::ReadOptions;
    /// assert_eq!(ReadOptions::default().scalar_by_default().full_information, Some(false));
    /// let full = ReadOptions { full_information: Some(true), ..Default::default() };
    /// assert_eq!(full.scalar_by_default().full_information, Some(true));
    /// ```
    pub fn scalar_by_default(mut self) -> Self {
        self.full_information.get_or_insert(false);
        self
    }

    /// An error when the options contradict each other: every weight 1
    /// ([`WeightSource::Unit`]) reads no information, so asking for the full information too
    /// (`full_information: Some(true)`) is refused rather than silently dropped. Every graph
    /// reader checks it first.
    ///
    /// ```
    /// use rotavg::io::detect::{ReadOptions, WeightSource};
    /// let both = ReadOptions { weights: WeightSource::Unit, full_information: Some(true), ..Default::default() };
    /// assert!(both.check().is_err());
    /// assert!(ReadOptions { full_information: None, ..both }.check().is_ok());
    /// ```
    pub fn check(&self) -> Result<()> {
        if self.weights == WeightSource::Unit && self.full_information == Some(true) {
            return Err(Error::InvalidSettings {
                name: "information".into(),
                reason: "the full information cannot be read with unit weights (every weight 1 \
                         reads no information): ask for one or the other"
                    .into(),
            });
        }
        Ok(())
    }
}

impl Default for ReadOptions {
    fn default() -> Self {
        ReadOptions {
            weights: WeightSource::File,
            rotation_tolerance: DEFAULT_ROTATION_TOLERANCE,
            quaternion_tolerance: 1e-3,
            full_information: None,
        }
    }
}

/// A view graph read from a file, with what the file said beyond the measurements.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoadedGraph {
    /// The validated problem (nodes `0..n`, edges as read, in file order, multi-edges kept).
    pub problem: MultipleProblem,
    /// The file's id of each node: node `k` of [`Self::problem`] is `node_ids[k]` in the file.
    /// Ids are sorted increasingly, so contiguous 0-based ids map to themselves.
    pub node_ids: Vec<u64>,
    /// The file's name of each node where the format names nodes (COLMAP: image names), else
    /// empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub node_names: Vec<String>,
    /// Initial estimate from vertex lines (as this crate's `R_i`), when every node has one.
    pub initial: Option<Vec<Rotation>>,
    /// Number of edges whose unordered pair `{i, j}` already occurred earlier in the file.
    pub duplicates: usize,
    /// Number of edges given with `i > j` (kept as given; `R_ij` keeps its meaning).
    pub reversed: usize,
    /// Non-fatal remarks (skipped line types, missing vertices, ...), one per kind.
    pub warnings: Vec<crate::warning::Warning>,
    /// The format that was read.
    pub format: GraphFormat,
    /// `true` when every measurement is a planar rotation about z (g2o `EDGE_SE2`).
    pub planar: bool,
    /// The options it was read with (weights from the file or unit, `--information`,
    /// tolerances): the JSON reports record them (`input.read`).
    #[serde(default)]
    pub read: ReadOptions,
}

impl LoadedGraph {
    /// A problem built in memory, as the JSON reader would return it: node ids `0..n`, no
    /// names, no initial estimate, its duplicate edges counted, and the warning
    /// `information_symmetrized` when information matrices were given asymmetric by rounding.
    ///
    /// ```
    /// use rotavg::io::detect::LoadedGraph;
    /// use rotavg::multiple::synthetic::SyntheticGraph;
    /// let (p, _) = SyntheticGraph { num_rotations: 5, num_edges: 8, ..Default::default() }.generate();
    /// let g = LoadedGraph::from_problem(p);
    /// assert_eq!(g.node_ids, vec![0, 1, 2, 3, 4]);
    /// ```
    pub fn from_problem(problem: MultipleProblem) -> Self {
        LoadedGraph {
            node_ids: (0..problem.num_rotations() as u64).collect(),
            node_names: Vec::new(),
            initial: None,
            duplicates: crate::multiple::stats::duplicate_edge_count(&problem),
            reversed: 0,
            warnings: information_symmetrized(&problem).into_iter().collect(),
            format: GraphFormat::Json,
            planar: false,
            read: ReadOptions {
                full_information: Some(false),
                ..Default::default()
            },
            problem,
        }
    }

    /// This graph, recorded as read with `options`; `--information auto` (`None`) recorded as
    /// what the reader chose (`Some(true)` when it read the information, else `Some(false)`).
    pub fn read_with(mut self, options: &ReadOptions) -> Self {
        let chosen = self.read.full_information;
        self.read = *options;
        self.read.full_information = options.full_information.or(chosen).or(Some(false));
        self
    }

    /// The node index of a file id, if the id occurs.
    pub fn node_of_id(&self, id: u64) -> Option<usize> {
        self.node_ids.binary_search(&id).ok()
    }

    /// The graph restricted to its largest connected component (problem, node ids and initial
    /// estimate; nodes renumbered in increasing order, as
    /// [`MultipleProblem::largest_component`]), and which nodes were kept. A connected graph
    /// is returned unchanged.
    ///
    /// ```
    /// use rotavg::io::detect::{read_graph, GraphFormat, ReadOptions};
    /// // Two components: {0, 1, 2} (a triangle) and {5, 7} (one edge).
    /// let text = "EDGE3 0 1 0 0 0 0 0 0\nEDGE3 1 2 0 0 0 0 0 0\nEDGE3 2 0 0 0 0 0 0 0\nEDGE3 5 7 0 0 0 0 0 0\n";
    /// let g = read_graph(text, "two.g2o", GraphFormat::Auto, &ReadOptions::default())?;
    /// assert!(g.problem.require_connected().is_err());
    /// let (big, selection) = g.largest_component();
    /// assert_eq!(big.node_ids, vec![0, 1, 2]);
    /// assert_eq!(selection.kept, vec![0, 1, 2]);
    /// assert_eq!((selection.num_read, selection.other_component_sizes.clone()), (5, vec![2]));
    /// // Per-node data of the file's graph (e.g. ground truth) follow the selection.
    /// assert_eq!(selection.select(&["a", "b", "c", "d", "e"]), Some(vec!["a", "b", "c"]));
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn largest_component(self) -> (LoadedGraph, ComponentSelection) {
        let num_read = self.problem.num_rotations();
        let comps = self.problem.components();
        if comps.len() <= 1 {
            return (self, ComponentSelection::whole(num_read));
        }
        let (problem, kept) = self.problem.largest_component();
        let node_ids = kept.iter().map(|&k| self.node_ids[k]).collect();
        let node_names = if self.node_names.len() == num_read {
            kept.iter().map(|&k| self.node_names[k].clone()).collect()
        } else {
            Vec::new()
        };
        let initial = self
            .initial
            .as_ref()
            .map(|v| kept.iter().map(|&k| v[k]).collect());
        let selection = ComponentSelection {
            kept,
            num_read,
            other_component_sizes: comps.iter().skip(1).map(Vec::len).collect(),
        };
        (
            LoadedGraph {
                problem,
                node_ids,
                node_names,
                initial,
                ..self
            },
            selection,
        )
    }
}

/// Which nodes of a graph as read were kept ([`LoadedGraph::largest_component`]).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ComponentSelection {
    /// Index, in the graph as read, of each kept node (increasing).
    pub kept: Vec<usize>,
    /// Number of nodes of the graph as read.
    pub num_read: usize,
    /// Sizes of the components not kept, largest first (empty when all nodes were kept).
    pub other_component_sizes: Vec<usize>,
}

impl ComponentSelection {
    /// Every node of a graph of `num_read` nodes.
    ///
    /// ```
    /// use rotavg::io::detect::ComponentSelection;
    /// let all = ComponentSelection::whole(3);
    /// assert!(all.is_whole());
    /// assert_eq!(all.select(&[1, 2, 3]), Some(vec![1, 2, 3]));
    /// ```
    pub fn whole(num_read: usize) -> Self {
        ComponentSelection {
            kept: (0..num_read).collect(),
            num_read,
            other_component_sizes: Vec::new(),
        }
    }

    /// `true` when every node was kept.
    pub fn is_whole(&self) -> bool {
        self.kept.len() == self.num_read
    }

    /// The entries of the kept nodes, from one entry per node of the graph as read; `None`
    /// when `per_node` does not have [`Self::num_read`] entries (or a kept index is out of
    /// range).
    pub fn select<T: Clone>(&self, per_node: &[T]) -> Option<Vec<T>> {
        if per_node.len() != self.num_read {
            return None;
        }
        self.kept
            .iter()
            .map(|&k| per_node.get(k).cloned())
            .collect()
    }

    /// An estimate for the kept nodes from `rotations`, which has one rotation per kept node
    /// (used as given) or one per node of the graph as read (restricted); otherwise a parse
    /// error naming `file`.
    ///
    /// ```
    /// use rotavg::io::detect::ComponentSelection;
    /// use rotavg::Rotation;
    /// let sel = ComponentSelection { kept: vec![1, 2], num_read: 3, other_component_sizes: vec![1] };
    /// assert_eq!(sel.estimate_for_kept(vec![Rotation::identity(); 3], "init.json")?.len(), 2);
    /// assert_eq!(sel.estimate_for_kept(vec![Rotation::identity(); 2], "init.json")?.len(), 2);
    /// let err = sel.estimate_for_kept(vec![Rotation::identity(); 5], "init.json").unwrap_err();
    /// assert!(err.to_string().contains("init.json"));
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn estimate_for_kept(&self, rotations: Vec<Rotation>, file: &str) -> Result<Vec<Rotation>> {
        if rotations.len() == self.kept.len() {
            return Ok(rotations);
        }
        self.select(&rotations).ok_or_else(|| {
            Error::parse(
                Some(file),
                None,
                format!(
                    "initial estimate has {} rotations, the graph has {} nodes",
                    rotations.len(),
                    self.kept.len()
                ),
            )
        })
    }
}

/// The warning for information matrices given asymmetric by rounding (`information_symmetrized`,
/// their symmetric part used: [`crate::multiple::anisotropic::SYMMETRY_TOLERANCE`]), or `None`
/// when every one was exactly symmetric (or the problem has none).
///
/// ```
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::multiple::anisotropic::Information;
/// use rotavg::Rotation;
/// let e = |i, j| Edge { i, j, rotation: Rotation::identity(), weight: 1.0 };
/// let mut h = nalgebra::Matrix3::identity();
/// h[(0, 1)] = 1e-15; // numpy's J.T @ W @ J can be this far from symmetric
/// let info = vec![Information::new(h)?, Information::isotropic(1.0)?];
/// let p = MultipleProblem::new(2, vec![e(0, 1), e(1, 0)])?.with_information(info)?;
/// let w = rotavg::io::detect::information_symmetrized(&p).unwrap();
/// assert_eq!((w.code.as_str(), w.count), ("information_symmetrized", Some(1)));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn information_symmetrized(problem: &MultipleProblem) -> Option<Warning> {
    let asymmetric: Vec<f64> = problem
        .information()?
        .iter()
        .map(|h| h.asymmetry())
        .filter(|&a| a > 0.0)
        .collect();
    let largest = asymmetric.iter().copied().fold(0.0, f64::max);
    (!asymmetric.is_empty()).then(|| {
        Warning::new(
            "information_symmetrized",
            format!(
                "{} information matrices are asymmetric by rounding (largest |H - H^T| {:.1e} \
                 of the largest entry): their symmetric parts are used",
                asymmetric.len(),
                largest
            ),
        )
        .with_count(asymmetric.len())
    })
}

/// Guess the format of a file from its content, and only when the content does not say, from
/// its extension (`.json`, `.g2o`): a first non-blank character `{` means JSON; a first data
/// line starting with a letter (a tag such as `EDGE_SE3:QUAT`, `VERTEX3`) means g2o; a first
/// data line of 11 or 14 numbers means 1DSfM `EGs.txt` ([`detect_by_content`]). A g2o file
/// named `*.json` is read as g2o.
///
/// ```
/// use rotavg::io::detect::{detect_format, GraphFormat};
/// assert_eq!(detect_format("x.txt", "EDGE3 0 1 0 0 0 0 0 0").unwrap(), GraphFormat::G2o);
/// assert_eq!(detect_format("-", " {\"num_rotations\": 2}").unwrap(), GraphFormat::Json);
/// assert_eq!(detect_format("EGs.txt", "0 1 1 0 0 0 1 0 0 0 1 1 0 0").unwrap(), GraphFormat::OneDsfm);
/// assert_eq!(detect_format("misnamed.json", "EDGE3 0 1 0 0 0 0 0 0").unwrap(), GraphFormat::G2o);
/// ```
pub fn detect_format(file: &str, text: &str) -> Result<GraphFormat> {
    if let Some(format) = detect_by_content(text) {
        return Ok(format);
    }
    let lower = file.to_ascii_lowercase();
    if lower.ends_with(".json") {
        return Ok(GraphFormat::Json);
    }
    if lower.ends_with(".g2o") {
        return Ok(GraphFormat::G2o);
    }
    match crate::io::content_lines(text).next() {
        Some((ln, t)) => Err(Error::parse(
            Some(file),
            Some(ln),
            format!(
                "cannot detect the file format from this line ({} tokens); pass --format \
                 g2o|1dsfm|json",
                t.split_whitespace().count()
            ),
        )),
        None => Err(Error::parse(
            Some(file),
            None,
            "empty input: no data lines, cannot detect the format",
        )),
    }
}

/// The format a view graph's text shows, if it shows one: JSON (first non-blank character
/// `{`), g2o (a first data line starting with a letter), 1DSfM (a first data line of 11 or 14
/// numbers).
pub fn detect_by_content(text: &str) -> Option<GraphFormat> {
    if text.trim_start().starts_with('{') {
        return Some(GraphFormat::Json);
    }
    let (_, t) = crate::io::content_lines(text).next()?;
    let first = t.split_whitespace().next().unwrap_or("");
    if first.starts_with(|c: char| c.is_ascii_alphabetic()) {
        return Some(GraphFormat::G2o);
    }
    matches!(t.split_whitespace().count(), 11 | 14).then_some(GraphFormat::OneDsfm)
}

/// The error for a JSON reader of `verb` (`single`, `conjugate`) given a view graph: when
/// `text` is g2o or 1DSfM (not JSON), an error naming the format and the verb that reads it;
/// `None` otherwise (the reader's own error stands).
///
/// ```
/// use rotavg::io::detect::read_by_another_verb;
/// let e = read_by_another_verb("pose.g2o", "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n", "single").unwrap();
/// assert!(e.to_string().contains("rotavg multiple pose.g2o"), "{e}");
/// assert!(read_by_another_verb("p.json", "{\"rotations\": 3}", "single").is_none());
/// ```
pub fn read_by_another_verb(file: &str, text: &str, verb: &str) -> Option<Error> {
    let format = detect_by_content(text).filter(|f| *f != GraphFormat::Json)?;
    let what = match verb {
        "conjugate" => "pairs {\"pairs\": [{\"left\": L, \"right\": R}, ...]}",
        _ => "rotations {\"rotations\": [R, ...]}",
    };
    Some(Error::parse(
        Some(file),
        None,
        format!(
            "this is a {} view graph (multiple rotation averaging): `rotavg multiple {file}` \
             reads it; `rotavg {verb}` reads JSON {what}",
            crate::io::names::Choice::name(&format)
        ),
    ))
}

/// Read a view graph from text. `file` names the source in error messages (`-` for stdin).
///
/// ```
/// use rotavg::io::detect::{read_graph, GraphFormat, ReadOptions};
/// let text = "EDGE_SE2 0 1 1 0 0.5 1 0 0 1 0 10\nEDGE_SE2 1 2 1 0 0.5 1 0 0 1 0 10\n";
/// let g = read_graph(text, "a.g2o", GraphFormat::Auto, &ReadOptions::default()).unwrap();
/// assert_eq!((g.problem.num_rotations(), g.problem.num_edges()), (3, 2));
/// assert!(g.planar);
/// ```
pub fn read_graph(
    text: &str,
    file: &str,
    format: GraphFormat,
    options: &ReadOptions,
) -> Result<LoadedGraph> {
    options.check()?;
    let format = match format {
        GraphFormat::Auto => detect_format(file, text)?,
        f => f,
    };
    let graph = match format {
        GraphFormat::Colmap => Err(Error::parse(
            Some(file),
            None,
            "a COLMAP database is an SQLite file: give its path (or the folder holding database.db), not text",
        )),
        GraphFormat::OneDsfm => crate::io::sfm::read_egs(text, file, options),
        GraphFormat::Json => crate::io::json::read_problem_json(text, file, options),
        // `Auto` was resolved above; detect_format never returns it.
        GraphFormat::G2o | GraphFormat::Auto => crate::io::g2o::read_g2o(text, file, options),
    };
    graph.map(|g| g.read_with(options))
}

/// Read a file from disk ([`read_graph`]); I/O errors name the path. A COLMAP database
/// (`format` `colmap`, or with `auto` a file starting with SQLite's header or a folder holding
/// `database.db`) is read by [`crate::io::colmap::read_colmap_database`].
///
/// ```
/// use rotavg::io::detect::{load_graph, GraphFormat, ReadOptions};
/// // A TORO triangle (EDGE3 i j x y z roll pitch yaw), written to a temporary file.
/// let path = std::env::temp_dir().join(format!("rotavg-doc-{}.g2o", std::process::id()));
/// std::fs::write(&path, "EDGE3 0 1 0 0 0 0 0 0.1\nEDGE3 1 2 0 0 0 0 0 0.2\nEDGE3 2 0 0 0 0 0 0 -0.3\n").unwrap();
/// let g = load_graph(&path, GraphFormat::Auto, &ReadOptions::default());
/// std::fs::remove_file(&path).unwrap();
/// let g = g?;
/// assert_eq!(g.format, GraphFormat::G2o);
/// assert_eq!((g.problem.num_rotations(), g.problem.num_edges()), (3, 3));
/// // A missing file is an I/O error naming the path.
/// let err = load_graph(std::path::Path::new("no/such/file.g2o"), GraphFormat::Auto, &ReadOptions::default());
/// assert!(matches!(err, Err(rotavg::Error::Io { .. })));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn load_graph(path: &Path, format: GraphFormat, options: &ReadOptions) -> Result<LoadedGraph> {
    // the options' contradiction first, though both readers below check it too: a missing
    // file would otherwise hide it (Python's error test asks for it with no file)
    options.check()?;
    let database = match format {
        GraphFormat::Colmap => {
            Some(crate::io::colmap::find_database(path).unwrap_or_else(|| path.to_path_buf()))
        }
        GraphFormat::Auto => crate::io::colmap::find_database(path),
        _ => None,
    };
    if let Some(db) = database {
        return crate::io::colmap::read_colmap_database(&db, options).map(|g| g.read_with(options));
    }
    let name = path.display().to_string();
    let mut graph = read_graph_stream(TextStream::open(&name)?, format, options)?;
    // the content decides the format, not the name: say so when the name says otherwise
    let named_database = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("db") || e.eq_ignore_ascii_case("sqlite"));
    if named_database {
        let message = format!(
            "{name}: named like a COLMAP database, but it is a text file: read as {}",
            graph.format.name()
        );
        graph
            .warnings
            .push(Warning::new("name_not_format", message));
    }
    Ok(graph)
}

/// The most bytes read ahead to find the first data line for format detection (4 MiB).
const MAX_DETECT_BYTES: usize = 1 << 22;

/// The format of an opened input ([`detect_format`] on its first block, so nothing more is
/// read): the extension, then the first content line. When the first block holds no complete
/// content line (long comments), more blocks are read ahead (at most 4 MiB; they stay in the
/// stream); when still none, the start decides (`{`: JSON, a letter: g2o), else it is an error.
///
/// ```
/// use rotavg::io::detect::{detect_stream_format, GraphFormat};
/// use rotavg::io::text::TextStream;
/// let mut stream = TextStream::from_reader("-", "0 1 1 0 0 0 1 0 0 0 1\n".as_bytes(), u64::MAX, None)?;
/// assert_eq!(detect_stream_format(&mut stream)?, GraphFormat::OneDsfm);
/// // a comment longer than the first block, then a g2o line
/// let text = format!("# {}\nEDGE3 0 1 0 0 0 0 0 0\n", "x".repeat(100_000));
/// let mut stream = TextStream::from_reader("-", text.as_bytes(), u64::MAX, None)?;
/// assert_eq!(detect_stream_format(&mut stream)?, GraphFormat::G2o);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn detect_stream_format(stream: &mut TextStream<'_>) -> Result<GraphFormat> {
    let file = stream.name().to_owned();
    let file = file.as_str();
    loop {
        let whole = stream.head_is_whole();
        let head = stream.head()?;
        if whole {
            return detect_format(file, head);
        }
        // only the complete lines: a cut line would show too few tokens
        let complete = head.rfind('\n').map_or("", |k| &head[..=k]);
        if crate::io::content_lines(complete).next().is_some() {
            return detect_format(file, complete);
        }
        if let Ok(f) = detect_format(file, "") {
            return Ok(f); // no complete line yet: the extension decides
        }
        if head.trim_start().starts_with('{') {
            return Ok(GraphFormat::Json);
        }
        if head.len() >= MAX_DETECT_BYTES || !stream.extend_head()? {
            break;
        }
    }
    let head = stream.head()?;
    if stream.head_is_whole() {
        return detect_format(file, head);
    }
    if head
        .trim_start()
        .starts_with(|c: char| c.is_ascii_alphabetic())
    {
        return Ok(GraphFormat::G2o);
    }
    Err(Error::parse(
        Some(file),
        Some(1),
        format!(
            "cannot detect the file format: no complete data line in the first {} bytes; pass --format g2o|1dsfm|json",
            head.len()
        ),
    ))
}

/// Read a view graph from an opened input ([`TextStream`]): g2o / TORO and 1DSfM `EGs.txt`
/// line by line ([`crate::io::g2o::read_g2o_lines`], [`crate::io::sfm::read_egs_lines`]: the
/// text is never held whole), JSON whole (serde_json; limit
/// [`crate::io::text::MAX_INPUT_BYTES`]). `auto` detects the format from the first block
/// ([`detect_stream_format`]).
///
/// ```
/// use rotavg::io::detect::{read_graph_stream, GraphFormat, ReadOptions};
/// use rotavg::io::text::TextStream;
/// let text = "EDGE3 0 1 0 0 0 0 0 0.1\nEDGE3 1 2 0 0 0 0 0 0.2\n";
/// let stream = TextStream::from_reader("-", text.as_bytes(), u64::MAX, None)?;
/// let g = read_graph_stream(stream, GraphFormat::Auto, &ReadOptions::default())?;
/// assert_eq!((g.format, g.problem.num_edges()), (GraphFormat::G2o, 2));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_graph_stream(
    stream: TextStream<'_>,
    format: GraphFormat,
    options: &ReadOptions,
) -> Result<LoadedGraph> {
    options.check()?;
    let mut stream = stream;
    let format = match format {
        GraphFormat::Auto => detect_stream_format(&mut stream)?,
        f => f,
    };
    let graph = match format {
        GraphFormat::Json => {
            let name = stream.name().to_owned();
            let text = stream.into_string(MAX_INPUT_BYTES)?;
            crate::io::json::read_problem_json(&text, &name, options)
        }
        GraphFormat::OneDsfm => crate::io::sfm::read_egs_lines(&mut stream.into_lines(), options),
        GraphFormat::G2o | GraphFormat::Auto => {
            crate::io::g2o::read_g2o_lines(&mut stream.into_lines(), options)
        }
        GraphFormat::Colmap => read_graph("", stream.name(), format, options),
    };
    graph.map(|g| g.read_with(options))
}
