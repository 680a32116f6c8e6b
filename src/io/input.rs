//! Loading what the `rotavg` command loads, as library functions: an input path or `-`
//! (standard input), the problem kind of a file, single / multiple / conjugate problems with
//! file or unit weights, ground truth matched by node id, estimate files, and a view graph
//! restricted to its largest component with the map back to the file.
//!
//! | function | reads |
//! |---|---|
//! | [`read_input`] | a path or `-`: name and text |
//! | [`detect_problem_kind`], [`read_problem`], [`load_problem`] | any problem file: kind from the content (`load_problem`: from a path, view graphs streamed) |
//! | [`read_single_problem`] | single JSON (weights per [`ReadOptions::weights`]) |
//! | [`load_view_graph`] | g2o, 1DSfM (streamed), JSON view graphs ([`crate::io::detect::read_graph_stream`]) |
//! | [`load_multiple_input`] | a view graph with ground truth, initial estimate, largest component |
//! | [`load_conjugate`], [`load_conjugate_with`] | conjugate JSON, Tabb and ETH directories, named hand / camera pose streams |
//! | [`read_ground_truth`], [`load_ground_truth`] | g2o vertices, Bundler, JSON estimate, rotation list, COLMAP `images.txt` / `images.bin` |
//! | [`load_initial_estimate`] | a JSON estimate or a COLMAP model, for the nodes of a graph |
//! | [`load_estimate`] | an estimate file ([`crate::io::json::read_estimate`]) |
//!
//! ```
//! use rotavg::io::input::{read_problem, Input, LoadedProblem, ProblemKind};
//! use rotavg::io::detect::{GraphFormat, ReadOptions, WeightSource};
//! // A single-averaging problem with weights, read with unit weights.
//! let input = Input::new("p.json", r#"{"rotations": [[[1,0,0],[0,1,0],[0,0,1]]], "weights": [4]}"#);
//! let options = ReadOptions { weights: WeightSource::Unit, ..Default::default() };
//! let problem = read_problem(&input, GraphFormat::Auto, &options)?;
//! assert_eq!(problem.kind(), ProblemKind::Single);
//! let LoadedProblem::Single(p) = problem else { unreachable!() };
//! assert_eq!(p.weights(), &[1.0]);
//! # Ok::<(), rotavg::Error>(())
//! ```

use crate::conjugate::{ConjugatePair, ConjugateProblem};
use crate::error::{Error, Result};
use crate::io::colmap::{
    is_images_binary, is_images_text, load_images, read_images_text, rotations_for_nodes,
};
use crate::io::detect::{
    ComponentSelection, GraphFormat, LoadedGraph, ReadOptions, WeightSource, detect_format,
    detect_stream_format, load_graph, read_graph, read_graph_stream,
};
use crate::io::handeye::{
    MotionSettings, MotionStats, TimeUnit, find_stream_files, read_conjugate_json,
    read_stream_pair, read_tabb_dir,
};
use crate::io::json::{Estimate, read_estimate, read_rotations_estimate};
use crate::io::names::ConjugateFormat;
use crate::io::sfm::{read_bundler, read_rotation_list, truth_for_nodes};
use crate::io::single_json::parse_single_json;
use crate::io::text::{MAX_INPUT_BYTES, TextStream};
use crate::single::SingleProblem;
use crate::so3::Rotation;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::path::Path;

/// The text of an input and the name that errors and reports use for it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Input {
    /// The path as given, or `-` for standard input.
    pub name: String,
    /// The whole text.
    pub text: String,
}

impl Input {
    /// An input from text already in memory.
    ///
    /// ```
    /// let input = rotavg::io::input::Input::new("inline.json", "{}");
    /// assert_eq!(input.name, "inline.json");
    /// ```
    pub fn new(name: impl Into<String>, text: impl Into<String>) -> Self {
        Input {
            name: name.into(),
            text: text.into(),
        }
    }
}

/// Read a whole input: the file at `path`, or standard input for `-`, with the size limit and
/// checks of [`super::text::read_text`]. I/O errors name the path.
///
/// ```
/// use rotavg::io::input::read_input;
/// let path = std::env::temp_dir().join(format!("rotavg-doc-input-{}.txt", std::process::id()));
/// std::fs::write(&path, "hello").unwrap();
/// let input = read_input(path.to_str().unwrap());
/// std::fs::remove_file(&path).unwrap();
/// assert_eq!(input?.text, "hello");
/// let err = read_input("no/such/file.json").unwrap_err();
/// assert!(err.to_string().contains("no/such/file.json"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_input(path: &str) -> Result<Input> {
    Ok(Input::new(path, super::text::read_text(path)?))
}

/// Read a view graph from the file at `path` or, for `-`, from standard input
/// ([`read_graph_stream`]: g2o and 1DSfM line by line; `format` `auto` detects it).
///
/// ```
/// use rotavg::io::input::load_view_graph;
/// use rotavg::io::detect::{GraphFormat, ReadOptions};
/// let path = std::env::temp_dir().join(format!("rotavg-doc-graph-{}.txt", std::process::id()));
/// std::fs::write(&path, "0 1 1 0 0 0 1 0 0 0 1\n").unwrap();
/// let g = load_view_graph(path.to_str().unwrap(), GraphFormat::Auto, &ReadOptions::default());
/// std::fs::remove_file(&path).unwrap();
/// assert_eq!(g?.format, GraphFormat::OneDsfm);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn load_view_graph(
    path: &str,
    format: GraphFormat,
    options: &ReadOptions,
) -> Result<LoadedGraph> {
    if path == "-" {
        read_graph_stream(TextStream::open(path)?, format, options)
    } else {
        load_graph(Path::new(path), format, options)
    }
}

/// Read a problem of any kind from the file at `path` (`-`: standard input), as
/// [`read_problem`] but without holding the text of a view graph: the kind and format come
/// from the first block; g2o and 1DSfM files are streamed
/// ([`crate::io::detect::read_graph_stream`]), JSON is read whole (limit
/// [`crate::io::text::MAX_INPUT_BYTES`]).
///
/// ```
/// use rotavg::io::input::{load_problem, ProblemKind};
/// use rotavg::io::detect::{GraphFormat, ReadOptions};
/// let path = std::env::temp_dir().join(format!("rotavg-doc-problem-{}.txt", std::process::id()));
/// std::fs::write(&path, "EDGE3 0 1 0 0 0 0 0 0.1\n").unwrap();
/// let p = load_problem(path.to_str().unwrap(), GraphFormat::Auto, &ReadOptions::default());
/// std::fs::remove_file(&path).unwrap();
/// assert_eq!(p?.kind(), ProblemKind::Multiple);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn load_problem(
    path: &str,
    format: GraphFormat,
    options: &ReadOptions,
) -> Result<LoadedProblem> {
    let mut stream = TextStream::open(path)?;
    let graph_format = match format {
        GraphFormat::Auto => detect_stream_format(&mut stream)?,
        f => f,
    };
    if matches!(graph_format, GraphFormat::G2o | GraphFormat::OneDsfm) {
        return Ok(LoadedProblem::Multiple(read_graph_stream(
            stream,
            graph_format,
            options,
        )?));
    }
    let input = Input::new(path, stream.into_string(MAX_INPUT_BYTES)?);
    read_problem(&input, format, options)
}

/// The three problems.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProblemKind {
    /// Single rotation averaging.
    Single,
    /// Multiple rotation averaging (a view graph).
    Multiple,
    /// Conjugate (hand-eye) rotation averaging.
    Conjugate,
}

impl fmt::Display for ProblemKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            ProblemKind::Single => "single",
            ProblemKind::Multiple => "multiple",
            ProblemKind::Conjugate => "conjugate",
        })
    }
}

/// The problem kind of a file: g2o and 1DSfM files (by `format`, or detected when `format` is
/// `auto`) are view graphs; a JSON object with `"pairs"` is conjugate, one with
/// `"num_rotations"` or `"edges"` multiple, one with `"rotations"` single.
///
/// ```
/// use rotavg::io::input::{detect_problem_kind, ProblemKind};
/// use rotavg::io::detect::GraphFormat;
/// let kind = |text| detect_problem_kind("p.json", text, GraphFormat::Auto);
/// assert_eq!(kind(r#"{"pairs": []}"#)?, ProblemKind::Conjugate);
/// assert_eq!(kind(r#"{"num_rotations": 2, "edges": []}"#)?, ProblemKind::Multiple);
/// assert_eq!(kind(r#"{"rotations": []}"#)?, ProblemKind::Single);
/// assert!(kind(r#"{"other": 1}"#).is_err());
/// assert_eq!(detect_problem_kind("x.g2o", "EDGE3 0 1 0 0 0 0 0 0", GraphFormat::Auto)?, ProblemKind::Multiple);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn detect_problem_kind(file: &str, text: &str, format: GraphFormat) -> Result<ProblemKind> {
    let format = match format {
        GraphFormat::Auto => detect_format(file, text)?,
        f => f,
    };
    if format != GraphFormat::Json {
        return Ok(ProblemKind::Multiple);
    }
    let v: serde_json::Value = serde_json::from_str(text).map_err(|e| {
        let line = (e.line() > 0).then_some(e.line());
        Error::parse(Some(file), line, e.to_string())
    })?;
    let has = |k: &str| v.get(k).is_some();
    if has("pairs") {
        Ok(ProblemKind::Conjugate)
    } else if has("num_rotations") || has("edges") {
        Ok(ProblemKind::Multiple)
    } else if has("rotations") {
        Ok(ProblemKind::Single)
    } else {
        Err(Error::parse(
            Some(file),
            None,
            "cannot tell the problem type: expected \"edges\"/\"num_rotations\" (multiple), \
             \"rotations\" (single) or \"pairs\" (conjugate)",
        ))
    }
}

/// A problem of any kind, as read from a file.
#[derive(Debug, Clone, PartialEq)]
pub enum LoadedProblem {
    /// Single rotation averaging.
    Single(SingleProblem),
    /// Multiple rotation averaging, with what the file said beyond the measurements.
    Multiple(LoadedGraph),
    /// Conjugate rotation averaging.
    Conjugate(ConjugateProblem),
}

impl LoadedProblem {
    /// Which problem this is.
    pub fn kind(&self) -> ProblemKind {
        match self {
            LoadedProblem::Single(_) => ProblemKind::Single,
            LoadedProblem::Multiple(_) => ProblemKind::Multiple,
            LoadedProblem::Conjugate(_) => ProblemKind::Conjugate,
        }
    }
}

/// Read a problem of the kind [`detect_problem_kind`] finds; `format` applies to view graphs,
/// `options.weights` to every kind.
///
/// ```
/// use rotavg::io::input::{read_problem, Input, ProblemKind};
/// use rotavg::io::detect::{GraphFormat, ReadOptions};
/// let input = Input::new("-", "EDGE3 0 1 0 0 0 0 0 0.1\n");
/// let p = read_problem(&input, GraphFormat::Auto, &ReadOptions::default())?;
/// assert_eq!(p.kind(), ProblemKind::Multiple);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_problem(
    input: &Input,
    format: GraphFormat,
    options: &ReadOptions,
) -> Result<LoadedProblem> {
    let (name, text) = (input.name.as_str(), input.text.as_str());
    Ok(match detect_problem_kind(name, text, format)? {
        ProblemKind::Multiple => LoadedProblem::Multiple(read_graph(text, name, format, options)?),
        ProblemKind::Single => LoadedProblem::Single(read_single_problem(text, name, options)?),
        ProblemKind::Conjugate => {
            LoadedProblem::Conjugate(with_weights(read_conjugate_json(text, name)?, options)?)
        }
    })
}

/// Read a single-averaging problem (JSON, [`parse_single_json`]) with the weights of the file
/// or, when `options.weights` is [`WeightSource::Unit`], all weights 1.
///
/// ```
/// use rotavg::io::input::read_single_problem;
/// use rotavg::io::detect::{ReadOptions, WeightSource};
/// let text = r#"{"rotations": [[[1,0,0],[0,1,0],[0,0,1]]], "weights": [3]}"#;
/// assert_eq!(read_single_problem(text, "p.json", &ReadOptions::default())?.weights(), &[3.0]);
/// let unit = ReadOptions { weights: WeightSource::Unit, ..Default::default() };
/// assert_eq!(read_single_problem(text, "p.json", &unit)?.weights(), &[1.0]);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_single_problem(text: &str, file: &str, options: &ReadOptions) -> Result<SingleProblem> {
    let problem = parse_single_json(text, file)?;
    match options.weights {
        WeightSource::File => Ok(problem),
        WeightSource::Unit => SingleProblem::new(problem.rotations().to_vec(), None)?
            .with_objective(problem.objective()),
    }
}

/// The conjugate problem with the weights `options` asks for (all 1 for
/// [`WeightSource::Unit`]; the objective is kept).
fn with_weights(problem: ConjugateProblem, options: &ReadOptions) -> Result<ConjugateProblem> {
    match options.weights {
        WeightSource::File => Ok(problem),
        WeightSource::Unit => ConjugateProblem::new(
            problem
                .pairs()
                .iter()
                .map(|p| ConjugatePair::new(p.left, p.right))
                .collect(),
        )?
        .with_objective(problem.objective()),
    }
}

/// A conjugate problem read by [`load_conjugate`], with where it came from.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedConjugate {
    /// The problem (chordal L2 objective).
    pub problem: ConjugateProblem,
    /// The input as given (a file, `-`, or a dataset directory; the two stream files when only
    /// those were given).
    pub name: String,
    /// The format read (never `auto`).
    pub format: ConjugateFormat,
    /// Counts from forming relative motions (Tabb, ETH / pose streams).
    pub motion: Option<MotionStats>,
    /// The motion settings used (Tabb, ETH / pose streams).
    pub motion_settings: MotionSettings,
}

/// The bare file name of a path (the path when it has none).
fn file_name(path: &str) -> String {
    Path::new(path)
        .file_name()
        .map_or_else(|| path.to_string(), |n| n.to_string_lossy().into_owned())
}

/// One line saying what was read, e.g. `Tabb: 88 stations, 3785 pairs (43 skipped: rotation
/// < 0.57 deg)` or `pairs.json: conjugate JSON`; pose streams add a line per stream and the
/// pairing settings.
impl fmt::Display for LoadedConjugate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let m = &self.motion_settings;
        match (self.format, &self.motion) {
            (ConjugateFormat::Tabb, Some(s)) => write!(
                f,
                "Tabb: {} stations, {} pairs ({} skipped: rotation < {:.2} deg)",
                s.poses,
                s.pairs,
                s.skipped_small,
                m.min_angle.to_degrees()
            ),
            (ConjugateFormat::Eth, Some(s)) => {
                write!(
                    f,
                    "ETH: {} time-matched samples ({} camera samples unmatched), {} pairs ({} skipped: rotation < {:.2} deg); stride {}, subsample {}, max gap {} s, time offset {} s",
                    s.poses,
                    s.unmatched,
                    s.pairs,
                    s.skipped_small,
                    m.min_angle.to_degrees(),
                    m.stride,
                    m.subsample,
                    m.max_gap,
                    m.time_offset
                )?;
                for (role, stream) in [("hand (L)", &s.hand), ("camera (R)", &s.camera)] {
                    if let Some(st) = stream {
                        write!(
                            f,
                            "\n{role}: {}: {} samples, {} repeated time stamps dropped{}{}",
                            file_name(&st.file),
                            st.samples,
                            st.repeated_stamps,
                            if st.header_lines > 0 {
                                format!(", {} header lines", st.header_lines)
                            } else {
                                String::new()
                            },
                            if st.time_unit == TimeUnit::Nanoseconds {
                                ", time in ns"
                            } else {
                                ""
                            }
                        )?;
                    }
                }
                Ok(())
            }
            _ => write!(f, "{}: conjugate JSON", self.name),
        }
    }
}

/// Where the hand-eye pose data are and how they are paired ([`load_conjugate_with`]).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct HandEyeOptions {
    /// The hand pose stream (`L_i` are its relative motions); found in the directory by name
    /// when `None` ([`crate::io::handeye::find_stream_files`]). A relative path is taken as
    /// given, or inside the directory when it does not exist as given.
    pub hand: Option<String>,
    /// The camera pose stream (`R_i` are its relative motions); found by name when `None`.
    pub camera: Option<String>,
    /// How motions are formed (Tabb uses `min_angle` only); `rotation_tolerance` is replaced by
    /// the read options'.
    pub motion: MotionSettings,
}

/// Read a conjugate problem: with `format` `auto`, a directory holding `robot_cali.txt` is a
/// Tabb dataset, another directory an ETH dataset, anything else (`-` included) conjugate JSON.
/// `options.weights` and `options.rotation_tolerance` apply. The same as
/// [`load_conjugate_with`] with default [`HandEyeOptions`].
///
/// ```
/// use rotavg::io::input::load_conjugate;
/// use rotavg::io::names::ConjugateFormat;
/// use rotavg::io::detect::ReadOptions;
/// let path = std::env::temp_dir().join(format!("rotavg-doc-conj-{}.json", std::process::id()));
/// let i = "[[1,0,0],[0,1,0],[0,0,1]]";
/// let rz = "[[0,-1,0],[1,0,0],[0,0,1]]";
/// std::fs::write(&path, format!(r#"{{"pairs": [{{"left": {rz}, "right": {rz}, "weight": 2}}, {{"left": {i}, "right": {i}}}]}}"#)).unwrap();
/// let c = load_conjugate(path.to_str().unwrap(), ConjugateFormat::Auto, &ReadOptions::default());
/// std::fs::remove_file(&path).unwrap();
/// let c = c?;
/// assert_eq!((c.format, c.problem.num_pairs()), (ConjugateFormat::Json, 2));
/// assert!(c.to_string().ends_with(": conjugate JSON"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn load_conjugate(
    path: &str,
    format: ConjugateFormat,
    options: &ReadOptions,
) -> Result<LoadedConjugate> {
    load_conjugate_with(Some(path), format, options, &HandEyeOptions::default())
}

/// [`load_conjugate`] with the hand-eye options: named hand / camera pose streams (then
/// `path`, a directory, may be `None` when both are named, and `format` must be `auto` or
/// `eth`) and the pairing settings.
///
/// ```
/// use rotavg::io::input::{load_conjugate_with, HandEyeOptions};
/// use rotavg::io::handeye::MotionSettings;
/// use rotavg::io::names::ConjugateFormat;
/// use rotavg::io::detect::ReadOptions;
/// use rotavg::so3::exp;
/// use nalgebra::{UnitQuaternion, Vector3};
/// // Hand poses H_k and camera poses E_k = H_k X (rotations), the camera stream 5 ms late and
/// // with one repeated time stamp.
/// let x = exp(&Vector3::new(0.1, 0.4, -0.2));
/// let (mut hand, mut camera) = (String::new(), String::new());
/// for k in 0..60 {
///     let t = 0.02 * k as f64;
///     let h = exp(&Vector3::new((2.0 * t).sin(), t, 0.5 * (3.0 * t).cos()));
///     let (qh, qe) = (UnitQuaternion::from_rotation_matrix(&h), UnitQuaternion::from_rotation_matrix(&(h * x)));
///     hand += &format!("{t:.3},0,0,0,{},{},{},{}\n", qh.i, qh.j, qh.k, qh.w);
///     let line = format!("{:.3} 0 0 0 {} {} {} {}\n", t + 0.005, qe.i, qe.j, qe.k, qe.w);
///     camera += &line;
///     if k == 30 { camera += &line; }
/// }
/// let dir = std::env::temp_dir().join(format!("rotavg-doc-streams-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// std::fs::write(dir.join("arm.csv"), hand).unwrap();
/// std::fs::write(dir.join("cam.txt"), camera).unwrap();
/// let he = HandEyeOptions {
///     hand: Some("arm.csv".into()),   // inside the directory
///     camera: Some("cam.txt".into()),
///     motion: MotionSettings { stride: 5, subsample: 2, time_offset: -0.005, ..Default::default() },
/// };
/// let c = load_conjugate_with(dir.to_str(), ConjugateFormat::Auto, &ReadOptions::default(), &he);
/// std::fs::remove_dir_all(&dir).unwrap();
/// let c = c?;
/// let stats = c.motion.as_ref().unwrap();
/// assert_eq!(stats.camera.as_ref().unwrap().repeated_stamps, 1);
/// assert!(c.problem.chordal_cost(&x) < 1e-12 && stats.pairs > 20);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn load_conjugate_with(
    path: Option<&str>,
    format: ConjugateFormat,
    options: &ReadOptions,
    handeye: &HandEyeOptions,
) -> Result<LoadedConjugate> {
    let named = handeye.hand.is_some() || handeye.camera.is_some();
    let is_dir = path.is_some_and(|p| p != "-" && Path::new(p).is_dir());
    let format = match format {
        ConjugateFormat::Auto | ConjugateFormat::Eth if named => ConjugateFormat::Eth,
        f if named => {
            return Err(Error::InvalidSettings {
                name: "hand/camera".into(),
                reason: format!(
                    "named hand and camera files are pose streams (format eth), not format {f}"
                ),
            });
        }
        ConjugateFormat::Auto
            if is_dir && path.is_some_and(|p| Path::new(p).join("robot_cali.txt").is_file()) =>
        {
            ConjugateFormat::Tabb
        }
        ConjugateFormat::Auto if is_dir => ConjugateFormat::Eth,
        ConjugateFormat::Auto => ConjugateFormat::Json,
        f => f,
    };
    let motion_settings = MotionSettings {
        rotation_tolerance: options.rotation_tolerance,
        ..handeye.motion
    };
    motion_settings.validate()?;
    let Some(path) = path.or(if named { None } else { Some("-") }) else {
        // Only named streams: both must be given.
        let (Some(h), Some(c)) = (&handeye.hand, &handeye.camera) else {
            return Err(Error::InvalidSettings {
                name: "hand/camera".into(),
                reason: "without a directory both the hand and the camera file must be named"
                    .into(),
            });
        };
        let (p, s) = read_stream_pair(Path::new(h), Path::new(c), &motion_settings)?;
        return Ok(LoadedConjugate {
            problem: with_weights(p, options)?,
            name: format!("{h} + {c}"),
            format,
            motion: Some(s),
            motion_settings,
        });
    };
    let dir = Path::new(path);
    let (problem, motion) = match format {
        ConjugateFormat::Tabb => {
            let (p, s) = read_tabb_dir(dir, &motion_settings)?;
            (p, Some(s))
        }
        ConjugateFormat::Eth => {
            if !is_dir {
                return Err(Error::Io {
                    path: path.to_string(),
                    message: "not a directory (pose streams: a directory, or name both files with --hand and --camera)".into(),
                });
            }
            let in_dir = |f: &Option<String>| {
                f.as_ref().map(|f| {
                    let p = Path::new(f);
                    if p.exists() {
                        p.to_path_buf()
                    } else {
                        dir.join(p)
                    }
                })
            };
            let (hand, camera) = (in_dir(&handeye.hand), in_dir(&handeye.camera));
            let (h, c) = find_stream_files(dir, hand.as_deref(), camera.as_deref())?;
            let (p, s) = read_stream_pair(&h, &c, &motion_settings)?;
            (p, Some(s))
        }
        ConjugateFormat::Json | ConjugateFormat::Auto => {
            let input = read_input(path)?;
            (read_conjugate_json(&input.text, &input.name)?, None)
        }
    };
    Ok(LoadedConjugate {
        problem: with_weights(problem, options)?,
        name: path.to_string(),
        format,
        motion,
        motion_settings,
    })
}

/// Ground truth for the nodes of `graph` (entry `k` for node `k`, `None` where unknown) from
/// `text`, matched by file id:
/// * a JSON estimate (`.json`, or text starting with `{`): one rotation per node, in node order;
/// * g2o (`.g2o`, or a first token that is a tag): the vertex rotations;
/// * Bundler (`.out`, or a `# Bundle` header): camera `k` is file id `k`;
/// * COLMAP `images.txt` (a name ending in `images.txt`, or COLMAP's header line): matched by
///   image name when the graph has names (a COLMAP database), else by image id
///   ([`crate::io::colmap::rotations_for_nodes`]); [`load_ground_truth`] also reads
///   `images.bin`;
/// * otherwise a rotation list: 9 numbers per line (line `k` = file id `k`), or `id R11 .. R33`
///   lines (world-to-camera, as many rotation-averaging tools write them)
///   ([`crate::io::sfm::read_rotation_list`]). An all-zero rotation means "no ground truth for
///   this camera".
///
/// ```
/// use rotavg::io::input::read_ground_truth;
/// use rotavg::io::detect::{read_graph, GraphFormat, ReadOptions};
/// let graph = read_graph("0 1 1 0 0 0 1 0 0 0 1\n", "EGs.txt", GraphFormat::Auto, &ReadOptions::default())?;
/// // A rotation list: file id 0 is known, id 1 is not (9 zeros).
/// let truth = read_ground_truth("1 0 0 0 1 0 0 0 1\n0 0 0 0 0 0 0 0 0\n", "gt.txt", &graph, &ReadOptions::default())?;
/// assert!(truth[0].is_some() && truth[1].is_none());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_ground_truth(
    text: &str,
    file: &str,
    graph: &LoadedGraph,
    options: &ReadOptions,
) -> Result<Vec<Option<Rotation>>> {
    let lower = file.to_ascii_lowercase();
    let trimmed = text.trim_start();
    if is_images_text(file, text) {
        return Ok(rotations_for_nodes(
            &read_images_text(text, file, options)?,
            graph,
        ));
    }
    if lower.ends_with(".json") || trimmed.starts_with('{') {
        let rs = read_rotations_estimate(text, file, options)?;
        if rs.len() != graph.node_ids.len() {
            return Err(Error::parse(
                Some(file),
                None,
                format!(
                    "ground truth has {} rotations, the graph has {} nodes",
                    rs.len(),
                    graph.node_ids.len()
                ),
            ));
        }
        return Ok(rs.into_iter().map(Some).collect());
    }
    let first_token = crate::io::content_lines(text)
        .next()
        .and_then(|(_, l)| l.split_whitespace().next())
        .unwrap_or("");
    if lower.ends_with(".g2o") || first_token.starts_with(|c: char| c.is_ascii_alphabetic()) {
        let gt = read_graph(text, file, GraphFormat::G2o, options)?;
        let init = gt.initial.as_ref();
        return Ok(graph
            .node_ids
            .iter()
            .map(|&id| {
                let k = gt.node_of_id(id)?;
                init.and_then(|v| v.get(k).copied())
            })
            .collect());
    }
    let by_id = if lower.ends_with(".out") || trimmed.starts_with("# Bundle") {
        read_bundler(text, file, options)?
    } else {
        read_rotation_list(text, file, options)?
    };
    Ok(truth_for_nodes(&by_id, &graph.node_ids))
}

/// [`read_ground_truth`] from the file at `path` (or standard input for `-`).
///
/// ```
/// use rotavg::io::input::load_ground_truth;
/// use rotavg::io::detect::{read_graph, GraphFormat, ReadOptions};
/// let graph = read_graph("0 1 1 0 0 0 1 0 0 0 1\n", "EGs.txt", GraphFormat::Auto, &ReadOptions::default())?;
/// let path = std::env::temp_dir().join(format!("rotavg-doc-truth-{}.json", std::process::id()));
/// std::fs::write(&path, r#"{"rotations": [[[1,0,0],[0,1,0],[0,0,1]], [[1,0,0],[0,1,0],[0,0,1]]]}"#).unwrap();
/// let truth = load_ground_truth(path.to_str().unwrap(), &graph, &ReadOptions::default());
/// std::fs::remove_file(&path).unwrap();
/// assert!(truth?.iter().all(Option::is_some));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn load_ground_truth(
    path: &str,
    graph: &LoadedGraph,
    options: &ReadOptions,
) -> Result<Vec<Option<Rotation>>> {
    if is_images_binary(path) {
        return Ok(rotations_for_nodes(&load_images(path, options)?, graph));
    }
    let input = read_input(path)?;
    read_ground_truth(&input.text, &input.name, graph, options)
}

/// An initial estimate for the nodes of `graph` (the graph as read), from the file at `path`:
/// a COLMAP sparse model (`images.txt`, `images.bin`: matched as in [`read_ground_truth`]; every
/// node must have an image) or a JSON estimate ([`load_estimate`], one rotation per node in node
/// order, or per kept node).
///
/// ```
/// use rotavg::io::input::load_initial_estimate;
/// use rotavg::io::detect::{read_graph, GraphFormat, ReadOptions};
/// let graph = read_graph("3 7 1 0 0 0 1 0 0 0 1\n", "EGs.txt", GraphFormat::Auto, &ReadOptions::default())?;
/// let path = std::env::temp_dir().join(format!("rotavg-doc-init-{}-images.txt", std::process::id()));
/// std::fs::write(&path, "7 1 0 0 0 0 0 0 1 x.jpg\n\n").unwrap();
/// let init = load_initial_estimate(path.to_str().unwrap(), &graph, &ReadOptions::default());
/// std::fs::remove_file(&path).unwrap();
/// // image 3 is not in the model: an error naming the node
/// assert!(init.unwrap_err().to_string().contains("node 0 (id 3"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn load_initial_estimate(
    path: &str,
    graph: &LoadedGraph,
    options: &ReadOptions,
) -> Result<Vec<Rotation>> {
    let per_node = if is_images_binary(path) {
        Some(rotations_for_nodes(&load_images(path, options)?, graph))
    } else {
        let input = read_input(path)?;
        if is_images_text(&input.name, &input.text) {
            Some(rotations_for_nodes(
                &read_images_text(&input.text, &input.name, options)?,
                graph,
            ))
        } else {
            return LoadedEstimate {
                estimate: read_estimate(&input.text, &input.name, options)?,
                name: input.name,
            }
            .into_rotations();
        }
    };
    let per_node = per_node.unwrap_or_default();
    per_node
        .iter()
        .enumerate()
        .map(|(k, r)| {
            r.ok_or_else(|| {
                let name = graph
                    .node_names
                    .get(k)
                    .map(|n| format!(", name {n}"))
                    .unwrap_or_default();
                Error::parse(
                    Some(path),
                    None,
                    format!(
                        "initial estimate: node {k} (id {}{name}) has no image in the COLMAP model",
                        graph.node_ids[k]
                    ),
                )
            })
        })
        .collect()
}

/// An estimate file and its name (for errors about its size or kind).
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedEstimate {
    /// The path as given.
    pub name: String,
    /// The rotations read.
    pub estimate: Estimate,
}

impl LoadedEstimate {
    /// The rotations of a multiple-averaging estimate (error naming the file for one rotation).
    pub fn into_rotations(self) -> Result<Vec<Rotation>> {
        self.estimate.into_rotations(&self.name)
    }

    /// The rotation of a single or conjugate estimate (error naming the file for a list).
    pub fn into_rotation(self) -> Result<Rotation> {
        self.estimate.into_rotation(&self.name)
    }
}

/// Read an estimate file (`{"rotations": [...]}`, `{"estimate": ...}` as printed by `--json`,
/// or `{"rotation": R}`; [`read_estimate`]) at `path`, or standard input for `-`.
///
/// ```
/// use rotavg::io::input::load_estimate;
/// use rotavg::io::detect::ReadOptions;
/// let path = std::env::temp_dir().join(format!("rotavg-doc-est-{}.json", std::process::id()));
/// std::fs::write(&path, r#"{"rotation": [[1,0,0],[0,1,0],[0,0,1]]}"#).unwrap();
/// let e = load_estimate(path.to_str().unwrap(), &ReadOptions::default());
/// std::fs::remove_file(&path).unwrap();
/// assert_eq!(e?.into_rotation()?, rotavg::Rotation::identity());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn load_estimate(path: &str, options: &ReadOptions) -> Result<LoadedEstimate> {
    let input = read_input(path)?;
    Ok(LoadedEstimate {
        estimate: read_estimate(&input.text, &input.name, options)?,
        name: input.name,
    })
}

/// What to read with a view graph ([`load_multiple_input`]).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MultipleInputOptions {
    /// The graph's format (`auto`: detect).
    pub format: GraphFormat,
    /// Weights and tolerances of every reader.
    pub read: ReadOptions,
    /// Keep the largest connected component of a disconnected graph (otherwise a disconnected
    /// graph is [`Error::Disconnected`]).
    pub largest_component: bool,
    /// A ground-truth file ([`read_ground_truth`]).
    pub ground_truth: Option<String>,
    /// An initial estimate ([`load_initial_estimate`]): a JSON estimate (one rotation per node
    /// of the graph as read or per kept node) or a COLMAP `images.txt` / `images.bin`.
    pub init: Option<String>,
}

/// A view graph as `rotavg multiple` solves it: connected (or restricted to its largest
/// component), with ground truth and initial estimate for its nodes.
#[derive(Debug, Clone, PartialEq)]
pub struct MultipleInput {
    /// The input as given (`-` for standard input).
    pub name: String,
    /// The graph solved (restricted when asked).
    pub graph: LoadedGraph,
    /// Which nodes of the file's graph were kept, and the sizes of the others.
    pub selection: ComponentSelection,
    /// Ground truth of each node of [`Self::graph`], when a file was given.
    pub truth: Option<Vec<Option<Rotation>>>,
    /// Initial estimate of each node of [`Self::graph`], when a file was given.
    pub init: Option<Vec<Rotation>>,
}

/// Read a view graph (`-`: standard input), its ground truth and initial estimate, and keep
/// its largest component when asked.
///
/// ```
/// use rotavg::io::input::{load_multiple_input, MultipleInputOptions};
/// let dir = std::env::temp_dir().join(format!("rotavg-doc-multiple-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// // Nodes 0-1-2 connected, node 3-4 apart (1DSfM lines: i j R_i R_j^T).
/// let graph = dir.join("EGs.txt");
/// std::fs::write(&graph, "0 1 1 0 0 0 1 0 0 0 1\n1 2 1 0 0 0 1 0 0 0 1\n3 4 1 0 0 0 1 0 0 0 1\n").unwrap();
/// let truth = dir.join("truth.txt");
/// std::fs::write(&truth, "1 0 0 0 1 0 0 0 1\n".repeat(5)).unwrap();
/// let options = MultipleInputOptions {
///     largest_component: true,
///     ground_truth: Some(truth.to_str().unwrap().into()),
///     ..Default::default()
/// };
/// let input = load_multiple_input(graph.to_str().unwrap(), &options);
/// std::fs::remove_dir_all(&dir).unwrap();
/// let input = input?;
/// assert_eq!(input.graph.node_ids, vec![0, 1, 2]);
/// assert_eq!(input.selection.other_component_sizes, vec![2]);
/// assert_eq!(input.truth.map(|t| t.len()), Some(3));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn load_multiple_input(path: &str, options: &MultipleInputOptions) -> Result<MultipleInput> {
    let graph = load_view_graph(path, options.format, &options.read)?;
    let truth = match &options.ground_truth {
        Some(p) => Some((p, load_ground_truth(p, &graph, &options.read)?)),
        None => None,
    };
    let init = match &options.init {
        Some(p) => Some((p, load_initial_estimate(p, &graph, &options.read)?)),
        None => None,
    };
    let (graph, selection) = if options.largest_component {
        graph.largest_component()
    } else {
        graph.problem.require_connected()?;
        let n = graph.problem.num_rotations();
        (graph, ComponentSelection::whole(n))
    };
    let truth = match truth {
        Some((file, t)) => Some(selection.select(&t).ok_or_else(|| {
            Error::parse(
                Some(file),
                None,
                format!(
                    "ground truth has {} entries, the graph has {} nodes",
                    t.len(),
                    selection.num_read
                ),
            )
        })?),
        None => None,
    };
    let init = match init {
        Some((name, rotations)) => Some(selection.estimate_for_kept(rotations, name)?),
        None => None,
    };
    Ok(MultipleInput {
        name: path.to_string(),
        graph,
        selection,
        truth,
        init,
    })
}
