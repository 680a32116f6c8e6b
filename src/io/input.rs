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
use crate::warning::Warning;
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
/// from the first block; a COLMAP database (or a folder holding `database.db`) is a view
/// graph ([`crate::io::colmap::read_colmap_database`]); g2o and 1DSfM files are streamed
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
    // a COLMAP database (a file, or a folder holding database.db) is a view graph
    if path != "-"
        && (format == GraphFormat::Colmap
            || (format == GraphFormat::Auto
                && crate::io::colmap::find_database(Path::new(path)).is_some()))
    {
        return Ok(LoadedProblem::Multiple(load_graph(
            Path::new(path),
            format,
            options,
        )?));
    }
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

/// The problem `rotavg certify` reads, and the name it is reported under: hand-eye data
/// (pose streams named in `handeye`, or a folder that holds no COLMAP database) as
/// [`load_conjugate_with`] reads them, any other input with [`load_problem`]. A folder with
/// neither is an error that says what certify reads.
pub fn load_certify_problem(
    path: Option<&str>,
    format: GraphFormat,
    options: &ReadOptions,
    handeye: &HandEyeOptions,
) -> Result<(String, LoadedProblem)> {
    let streams = handeye.hand.is_some() || handeye.camera.is_some();
    let folder = path
        .map(Path::new)
        .is_some_and(|p| p.is_dir() && crate::io::colmap::find_database(p).is_none());
    match path {
        Some(p) if !(streams || folder) => Ok((p.to_string(), load_problem(p, format, options)?)),
        input => {
            let loaded = load_conjugate_with(input, ConjugateFormat::Auto, options, handeye)
                .map_err(|e| match (streams, e) {
                    (false, Error::Io { message, .. }) => Error::Io {
                        path: input.unwrap_or("-").to_string(),
                        message: format!(
                            "certify reads a folder holding a COLMAP database.db, or hand-eye \
                             data (Tabb's robot_cali.txt, or hand and camera pose streams); \
                             this folder has neither: {message}"
                        ),
                    },
                    (_, e) => e,
                })?;
            Ok((loaded.name, LoadedProblem::Conjugate(loaded.problem)))
        }
    }
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
    let format = conjugate_format(path, format, named, is_dir)?;
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
            let (p, s) = read_stream_dir(dir, handeye, &motion_settings)?;
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

/// The format of a conjugate input: `format`, or when `auto` from `path` (a Tabb directory
/// holds `robot_cali.txt`, other directories hold pose streams, files are JSON); pose streams
/// when hand or camera files are `named` (then `format` must be `auto` or `eth`).
fn conjugate_format(
    path: Option<&str>,
    format: ConjugateFormat,
    named: bool,
    is_dir: bool,
) -> Result<ConjugateFormat> {
    Ok(match format {
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
    })
}

/// The hand and camera pose streams of the directory `dir` (the files `handeye` names, as
/// given or inside `dir`, else found by name), paired into motions.
fn read_stream_dir(
    dir: &Path,
    handeye: &HandEyeOptions,
    settings: &MotionSettings,
) -> Result<(ConjugateProblem, MotionStats)> {
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
    read_stream_pair(&h, &c, settings)
}

/// The formats of a file of absolute rotations ([`load_rotations_for_nodes`]): estimates,
/// initial estimates and ground truth.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EstimateFormat {
    /// JSON `{"rotations": [...]}` / `{"estimate": [...]}` (node order), or rotavg's own
    /// `--output` `{"node_ids": [...], "rotations": [...]}` (matched by id).
    Json,
    /// g2o / TORO vertex lines (`VERTEX_SE3:QUAT`, `VERTEX3`, `VERTEX_SE2`), by vertex id.
    G2o,
    /// A COLMAP `images.txt` (alone or in a sparse model folder).
    ColmapText,
    /// A COLMAP `images.bin` (alone or in a sparse model folder).
    ColmapBinary,
    /// The pose priors of a COLMAP database's `images` table.
    ColmapDatabase,
    /// A Bundler `.out` file (camera `k` is id `k`).
    Bundler,
    /// A rotation list (`R11 .. R33` per line, or `id R11 .. R33`).
    RotationList,
    /// A NumPy array (`.npy`, or a `.npz` archive's array): shape `(n, 3, 3)` or `(n, 9)` in
    /// node order ([`crate::io::numpy`]).
    Numpy,
}

impl EstimateFormat {
    /// A few words for messages, e.g. `g2o vertex lines`.
    pub fn describe(self) -> &'static str {
        match self {
            EstimateFormat::Json => "JSON estimate",
            EstimateFormat::G2o => "g2o vertex lines",
            EstimateFormat::ColmapText => "COLMAP images.txt",
            EstimateFormat::ColmapBinary => "COLMAP images.bin",
            EstimateFormat::ColmapDatabase => "COLMAP database pose priors",
            EstimateFormat::Bundler => "Bundler cameras",
            EstimateFormat::RotationList => "rotation list",
            EstimateFormat::Numpy => "NumPy array",
        }
    }
}

/// How the entries of a rotations file were matched to the nodes of a graph.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MatchedBy {
    /// Entry `k` is node `k` (a JSON list without `node_ids`).
    Order,
    /// By the node's file id (g2o vertex id, COLMAP `image_id`, Bundler camera index, ...).
    Id,
    /// By image name (a COLMAP model against a graph with names, e.g. from a COLMAP database).
    Name,
}

/// Absolute rotations read from a file and matched to the nodes of a graph
/// ([`load_rotations_for_nodes`]).
#[derive(Debug, Clone, PartialEq)]
pub struct NodeRotations {
    /// The file read (for a COLMAP model folder, its `images.bin` / `images.txt`).
    pub file: String,
    /// What the file is.
    pub format: EstimateFormat,
    /// How entries were matched to nodes.
    pub matched_by: MatchedBy,
    /// The rotation of each node (`None`: not in the file); with [`MatchedBy::Order`] the
    /// file's list as it is (its length may differ from the graph's number of nodes).
    pub rotations: Vec<Option<Rotation>>,
    /// The entries of the file that match no node (`id 12`, `name x.jpg`), in file order.
    pub unmatched: Vec<String>,
    /// COLMAP images whose translation is not finite (NaN: a model written after rotation
    /// averaging alone); their rotations are used, the translations never are.
    pub non_finite_translations: usize,
}

impl NodeRotations {
    /// Every node's rotation, or an error naming the file, how it was matched and the nodes
    /// it lacks (`what` starts the message, e.g. `estimate`).
    ///
    /// ```
    /// use rotavg::io::input::{read_rotations_for_nodes, Input};
    /// use rotavg::io::detect::{read_graph, GraphFormat, ReadOptions};
    /// let graph = read_graph("3 7 1 0 0 0 1 0 0 0 1\n", "EGs.txt", GraphFormat::Auto, &ReadOptions::default())?;
    /// let input = Input::new("est.g2o", "VERTEX_SE3:QUAT 7 0 0 0 0 0 0 1\n");
    /// let r = read_rotations_for_nodes(&input, &graph, &ReadOptions::default())?;
    /// let err = r.require_all(&graph, "estimate").unwrap_err().to_string();
    /// assert!(err.starts_with("est.g2o: estimate: 1 of 2 nodes have no rotation"), "{err}");
    /// assert!(err.contains("node 0 (id 3)"), "{err}");
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn require_all(self, graph: &LoadedGraph, what: &str) -> Result<Vec<Rotation>> {
        let n = graph.node_ids.len();
        if self.matched_by == MatchedBy::Order && self.rotations.len() != n {
            return Err(Error::parse(
                Some(&self.file),
                None,
                format!(
                    "{what}: the file has {} rotations, the problem has {n} nodes (a JSON \
                     list holds one rotation per node, in node order; rotavg's --output adds \
                     \"node_ids\" to match by id)",
                    self.rotations.len()
                ),
            ));
        }
        let missing: Vec<usize> = (0..n)
            .filter(|&k| self.rotations.get(k).copied().flatten().is_none())
            .collect();
        if missing.is_empty() {
            return Ok(self.rotations.into_iter().flatten().collect());
        }
        const SHOWN: usize = 5;
        let label = |k: usize| {
            let name = graph
                .node_names
                .get(k)
                .filter(|s| !s.is_empty())
                .map(|s| format!(", name {s}"))
                .unwrap_or_default();
            format!("node {k} (id {}{name})", graph.node_ids[k])
        };
        let mut list: Vec<String> = missing.iter().take(SHOWN).map(|&k| label(k)).collect();
        if missing.len() > SHOWN {
            list.push(format!("... ({} more)", missing.len() - SHOWN));
        }
        let by = match self.matched_by {
            MatchedBy::Name => "image name",
            MatchedBy::Id => "id",
            MatchedBy::Order => "order",
        };
        let hint = match self.unmatched.first() {
            Some(u) if missing.len() == n => format!(
                "; no entry of the file matches a node (the file has e.g. {u}: another numbering or \
                 naming?)"
            ),
            _ => String::new(),
        };
        Err(Error::parse(
            Some(&self.file),
            None,
            format!(
                "{what}: {} of {n} nodes have no rotation in the file ({}, matched by {by}): {}{hint}",
                missing.len(),
                self.format.describe(),
                list.join(", ")
            ),
        ))
    }

    /// What to say about the file besides its rotations: entries that match no node
    /// (`estimate_unmatched`, [`Self::unmatched_warning`]) and translations that are not
    /// finite (`translations_not_finite`, counted).
    pub fn warnings(&self) -> Vec<Warning> {
        let mut warnings: Vec<Warning> = self
            .unmatched_warning()
            .map(|w| Warning::new("estimate_unmatched", w).with_count(self.unmatched.len()))
            .into_iter()
            .collect();
        if self.non_finite_translations > 0 {
            let message = format!(
                "{}: {} images have translations that are not finite (NaN): not used, a \
                 rotation certificate needs none",
                self.file, self.non_finite_translations
            );
            warnings.push(
                Warning::new("translations_not_finite", message)
                    .with_count(self.non_finite_translations),
            );
        }
        warnings
    }

    /// A remark when some entries of the file match no node (they are not used), e.g.
    /// `est.g2o: 2 vertex / image entries match no node of the problem and are not used: id 40, id 41`.
    pub fn unmatched_warning(&self) -> Option<String> {
        if self.unmatched.is_empty() {
            return None;
        }
        const SHOWN: usize = 5;
        let mut list: Vec<&str> = self
            .unmatched
            .iter()
            .take(SHOWN)
            .map(String::as_str)
            .collect();
        let more = format!("... ({} more)", self.unmatched.len().saturating_sub(SHOWN));
        if self.unmatched.len() > SHOWN {
            list.push(&more);
        }
        Some(format!(
            "{}: {} entries ({}) match no node of the problem and are not used: {}",
            self.file,
            self.unmatched.len(),
            self.format.describe(),
            list.join(", ")
        ))
    }
}

/// The entries of a rotations file before they are matched to nodes.
enum Entries {
    /// A list in node order.
    InOrder(Vec<Rotation>),
    /// `(id, rotation)` pairs.
    ById(Vec<(u64, Rotation)>),
    /// Entry `id` is the rotation of file id `id` (`None`: unknown).
    Indexed(Vec<Option<Rotation>>),
    /// COLMAP images: by name when the graph has names, else by id.
    Images(Vec<crate::io::colmap::ColmapImage>),
}

fn match_entries(
    entries: Entries,
    file: &str,
    format: EstimateFormat,
    graph: &LoadedGraph,
) -> NodeRotations {
    use std::collections::{BTreeMap, BTreeSet};
    let node_ids: BTreeSet<u64> = graph.node_ids.iter().copied().collect();
    let non_finite_translations = match &entries {
        Entries::Images(images) => images
            .iter()
            .filter(|im| !im.translation.iter().all(|t| t.is_finite()))
            .count(),
        _ => 0,
    };
    let (matched_by, rotations, unmatched) = match entries {
        Entries::InOrder(rs) => (MatchedBy::Order, rs.into_iter().map(Some).collect(), vec![]),
        Entries::ById(list) => {
            let unmatched = list
                .iter()
                .filter(|(id, _)| !node_ids.contains(id))
                .map(|(id, _)| format!("id {id}"))
                .collect();
            let by_id: BTreeMap<u64, Rotation> = list.into_iter().collect();
            let rs = graph
                .node_ids
                .iter()
                .map(|id| by_id.get(id).copied())
                .collect();
            (MatchedBy::Id, rs, unmatched)
        }
        Entries::Indexed(by_id) => {
            let unmatched = by_id
                .iter()
                .enumerate()
                .filter(|(id, r)| r.is_some() && !node_ids.contains(&(*id as u64)))
                .map(|(id, _)| format!("id {id}"))
                .collect();
            (
                MatchedBy::Id,
                truth_for_nodes(&by_id, &graph.node_ids),
                unmatched,
            )
        }
        Entries::Images(images) => {
            let rs = rotations_for_nodes(&images, graph);
            let by_name =
                graph.node_names.len() == graph.node_ids.len() && !graph.node_names.is_empty();
            let unmatched = if by_name {
                let names: BTreeSet<&str> = graph.node_names.iter().map(String::as_str).collect();
                images
                    .iter()
                    .filter(|im| !names.contains(im.name.as_str()))
                    .map(|im| format!("name {}", im.name))
                    .collect()
            } else {
                images
                    .iter()
                    .filter(|im| !node_ids.contains(&u64::from(im.image_id)))
                    .map(|im| format!("image_id {}", im.image_id))
                    .collect()
            };
            let by = if by_name {
                MatchedBy::Name
            } else {
                MatchedBy::Id
            };
            (by, rs, unmatched)
        }
    };
    NodeRotations {
        file: file.to_string(),
        format,
        matched_by,
        rotations,
        unmatched,
        non_finite_translations,
    }
}

#[derive(Deserialize)]
struct JsonNodeIds {
    node_ids: Option<Vec<u64>>,
}

/// Absolute rotations for the nodes of `graph` from the text of a file
/// ([`load_rotations_for_nodes`] reads paths, folders, databases and binary files too):
/// * COLMAP `images.txt` (a name ending in `images.txt`, or COLMAP's header line): by image
///   name when the graph has names (a COLMAP database), else by image id
///   ([`crate::io::colmap::rotations_for_nodes`]);
/// * JSON (`.json`, or text starting with `{`): `{"rotations": [...]}` or `{"estimate": [...]}`
///   in node order, or with `"node_ids"` (rotavg's `--output`) by id;
/// * g2o / TORO (`.g2o`, or a first token that is a tag): the vertex lines, by vertex id
///   ([`crate::io::g2o::read_g2o_vertices`]; edge lines are skipped);
/// * Bundler (`.out`, or a `# Bundle` header): camera `k` is file id `k`;
/// * otherwise a rotation list: 9 numbers per line (line `k` = file id `k`), or `id R11 .. R33`
///   lines ([`crate::io::sfm::read_rotation_list`]; an all-zero rotation means "unknown").
///
/// Every rotation is checked as it is read (errors name the file and line).
///
/// ```
/// use rotavg::io::input::{read_rotations_for_nodes, Input, MatchedBy};
/// use rotavg::io::detect::{read_graph, GraphFormat, ReadOptions};
/// let graph = read_graph("3 7 1 0 0 0 1 0 0 0 1\n", "EGs.txt", GraphFormat::Auto, &ReadOptions::default())?;
/// let input = Input::new("est.g2o", "VERTEX_SE2 7 0 0 0.5\nVERTEX_SE2 3 0 0 0\nVERTEX_SE2 9 0 0 0\n");
/// let r = read_rotations_for_nodes(&input, &graph, &ReadOptions::default())?;
/// assert_eq!(r.matched_by, MatchedBy::Id);
/// assert!((r.rotations[1].unwrap().angle() - 0.5).abs() < 1e-15); // node 1 is id 7
/// assert_eq!(r.unmatched, vec!["id 9".to_string()]);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_rotations_for_nodes(
    input: &Input,
    graph: &LoadedGraph,
    options: &ReadOptions,
) -> Result<NodeRotations> {
    let (text, file) = (input.text.as_str(), input.name.as_str());
    let lower = file.to_ascii_lowercase();
    let trimmed = text.trim_start();
    let (entries, format) = if is_images_text(file, text) {
        (
            Entries::Images(read_images_text(text, file, options)?),
            EstimateFormat::ColmapText,
        )
    } else if lower.ends_with(".json") || trimmed.starts_with('{') {
        let rs = read_rotations_estimate(text, file, options)?;
        let ids = serde_json::from_str::<JsonNodeIds>(text)
            .ok()
            .and_then(|j| j.node_ids);
        let entries = match ids {
            Some(ids) if ids.len() != rs.len() => {
                return Err(Error::parse(
                    Some(file),
                    None,
                    format!(
                        "\"node_ids\" has {} entries, \"rotations\" {}: one id per rotation",
                        ids.len(),
                        rs.len()
                    ),
                ));
            }
            Some(ids) => {
                let mut seen = std::collections::BTreeSet::new();
                if let Some(id) = ids.iter().find(|&&id| !seen.insert(id)) {
                    return Err(Error::parse(
                        Some(file),
                        None,
                        format!("\"node_ids\": id {id} appears more than once"),
                    ));
                }
                Entries::ById(ids.into_iter().zip(rs).collect())
            }
            None => Entries::InOrder(rs),
        };
        (entries, EstimateFormat::Json)
    } else {
        let first_token = crate::io::content_lines(text)
            .next()
            .and_then(|(_, l)| l.split_whitespace().next())
            .unwrap_or("");
        if lower.ends_with(".g2o") || first_token.starts_with(|c: char| c.is_ascii_alphabetic()) {
            let vertices = crate::io::g2o::read_g2o_vertices(text, file, options)?;
            (
                Entries::ById(vertices.into_iter().map(|v| (v.id, v.rotation)).collect()),
                EstimateFormat::G2o,
            )
        } else if lower.ends_with(".out") || trimmed.starts_with("# Bundle") {
            (
                Entries::Indexed(read_bundler(text, file, options)?),
                EstimateFormat::Bundler,
            )
        } else {
            (
                Entries::Indexed(read_rotation_list(text, file, options)?),
                EstimateFormat::RotationList,
            )
        }
    };
    Ok(match_entries(entries, file, format, graph))
}

/// Absolute rotations for the nodes of `graph` from `path`, in any format rotavg reads or
/// writes: a COLMAP sparse model folder (its `images.bin`, else `images.txt`), `images.bin`,
/// a COLMAP database (the pose priors of its `images` table when every image has one;
/// otherwise an error: a database holds no estimated poses), or a text file
/// ([`read_rotations_for_nodes`]: COLMAP `images.txt`, JSON, g2o vertices, Bundler, rotation
/// list). `-` reads standard input (text formats). The one loader of `--estimate` (`rotavg
/// certify`), `--init` and `--ground-truth`.
///
/// ```
/// use rotavg::io::input::{load_rotations_for_nodes, EstimateFormat, MatchedBy};
/// use rotavg::io::detect::{read_graph, GraphFormat, ReadOptions};
/// let graph = read_graph("3 7 1 0 0 0 1 0 0 0 1\n", "EGs.txt", GraphFormat::Auto, &ReadOptions::default())?;
/// // A sparse model folder holding images.txt (COLMAP's cam_from_world, by image id).
/// let dir = std::env::temp_dir().join(format!("rotavg-doc-model-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// std::fs::write(dir.join("images.txt"), "3 1 0 0 0 0 0 0 1 a.jpg\n\n7 0 0 0 1 0 0 0 1 b.jpg\n\n").unwrap();
/// let r = load_rotations_for_nodes(dir.to_str().unwrap(), &graph, &ReadOptions::default());
/// std::fs::remove_dir_all(&dir).unwrap();
/// let r = r?;
/// assert_eq!((r.format, r.matched_by), (EstimateFormat::ColmapText, MatchedBy::Id));
/// assert!((r.rotations[1].unwrap().angle() - std::f64::consts::PI).abs() < 1e-12);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn load_rotations_for_nodes(
    path: &str,
    graph: &LoadedGraph,
    options: &ReadOptions,
) -> Result<NodeRotations> {
    use crate::io::colmap::{find_model_images, is_sqlite_file, read_database_poses};
    if path != "-" {
        let p = Path::new(path);
        let file = if p.is_dir() {
            match find_model_images(p)? {
                crate::io::colmap::ModelFile::Images(f) => f,
                crate::io::colmap::ModelFile::Database(db) => {
                    let images = read_database_poses(&db, options)?;
                    let name = db.display().to_string();
                    return Ok(match_entries(
                        Entries::Images(images),
                        &name,
                        EstimateFormat::ColmapDatabase,
                        graph,
                    ));
                }
            }
        } else if is_sqlite_file(p) {
            let images = read_database_poses(p, options)?;
            return Ok(match_entries(
                Entries::Images(images),
                path,
                EstimateFormat::ColmapDatabase,
                graph,
            ));
        } else {
            p.to_path_buf()
        };
        let name = file.display().to_string();
        crate::io::colmap::refuse_other_model_file(&name)?;
        if let Some(rotations) = load_numpy(&name, options)? {
            return Ok(match_entries(
                Entries::InOrder(rotations),
                &name,
                EstimateFormat::Numpy,
                graph,
            ));
        }
        if is_images_binary(&name) {
            let images = load_images(&name, options)?;
            return Ok(match_entries(
                Entries::Images(images),
                &name,
                EstimateFormat::ColmapBinary,
                graph,
            ));
        }
        return read_rotations_for_nodes(&read_input(&name)?, graph, options);
    }
    read_rotations_for_nodes(&read_input(path)?, graph, options)
}

/// The rotations of the NumPy file at `path` ([`crate::io::numpy`]) when it is one: a `.npy`
/// file (by its magic bytes), or a zip archive named `*.npz`; `None` for any other file (and
/// for `-`). A name ending in `.npy` / `.npz` whose content is not NumPy's is an error.
fn load_numpy(path: &str, options: &ReadOptions) -> Result<Option<Vec<Rotation>>> {
    use crate::io::numpy::{is_npy, is_zip, read_numpy_rotations};
    let lower = path.to_ascii_lowercase();
    let named = lower.ends_with(".npy") || lower.ends_with(".npz");
    if path == "-" || !(named || Path::new(path).is_file()) {
        return Ok(None);
    }
    let io = |e: std::io::Error| Error::Io {
        path: path.to_string(),
        message: e.to_string(),
    };
    let mut head = Vec::with_capacity(8);
    {
        use std::io::Read;
        let file = std::fs::File::open(path).map_err(io)?;
        file.take(8).read_to_end(&mut head).map_err(io)?;
    }
    if !(is_npy(&head) || (is_zip(&head) && lower.ends_with(".npz"))) {
        return if named {
            Err(Error::parse(
                Some(path),
                None,
                "named as a NumPy file, but it is not one (np.save writes .npy, np.savez .npz)",
            ))
        } else {
            Ok(None)
        };
    }
    let bytes = std::fs::read(path).map_err(io)?;
    read_numpy_rotations(&bytes, path, options).map(Some)
}

/// Ground truth for the nodes of `graph` (entry `k` for node `k`, `None` where unknown) from
/// `text` ([`read_rotations_for_nodes`]); a JSON list without `"node_ids"` must have one rotation
/// per node.
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
    truth_of(
        read_rotations_for_nodes(&Input::new(file, text), graph, options)?,
        graph,
    )
}

fn truth_of(r: NodeRotations, graph: &LoadedGraph) -> Result<Vec<Option<Rotation>>> {
    if r.matched_by == MatchedBy::Order && r.rotations.len() != graph.node_ids.len() {
        return Err(Error::parse(
            Some(&r.file),
            None,
            format!(
                "ground truth has {} rotations, the graph has {} nodes",
                r.rotations.len(),
                graph.node_ids.len()
            ),
        ));
    }
    Ok(r.rotations)
}

/// [`read_ground_truth`] from `path` (or standard input for `-`), in every format of
/// [`load_rotations_for_nodes`] (COLMAP model folders and `images.bin` too).
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
    truth_of(load_rotations_for_nodes(path, graph, options)?, graph)
}

/// An initial estimate for the nodes of `graph` (the graph as read), from `path`, in every
/// format of [`load_rotations_for_nodes`]: every node must have a rotation, except that a JSON
/// list without `"node_ids"` is returned as it is (one rotation per node in node order, or per
/// kept node: [`ComponentSelection::estimate_for_kept`]).
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
    initial_of(load_rotations_for_nodes(path, graph, options)?, graph)
}

/// The initial estimate of [`load_initial_estimate`] from the rotations read.
fn initial_of(r: NodeRotations, graph: &LoadedGraph) -> Result<Vec<Rotation>> {
    if r.matched_by == MatchedBy::Order {
        return Ok(r.rotations.into_iter().flatten().collect());
    }
    r.require_all(graph, "initial estimate")
}

/// An estimate of every node of `graph`, as `rotavg certify` reads `--estimate`: any format of
/// [`load_rotations_for_nodes`] (JSON, g2o vertices, COLMAP `images.txt` / `images.bin` / a
/// sparse model folder / database pose priors, Bundler `.out`, rotation lists), matched by id,
/// or by image name for a COLMAP model against a graph with names. A node without a rotation
/// is an error naming the file and the nodes; entries that match no node are not used and
/// reported by [`NodeRotations::unmatched_warning`] (kept in [`GraphEstimate::unmatched`]).
///
/// ```
/// use rotavg::io::input::{load_estimate_for, MatchedBy};
/// use rotavg::io::detect::{read_graph, GraphFormat, ReadOptions};
/// use rotavg::so3::{angle_between, exp};
/// use rotavg::nalgebra::Vector3;
/// // A triangle of g2o nodes 10, 20, 30 whose edges agree with the rotations R below.
/// let r = [exp(&Vector3::new(0.1, 0.0, 0.0)), exp(&Vector3::new(0.0, 0.2, 0.0)), exp(&Vector3::new(0.0, 0.0, 0.3))];
/// let quat = |m: &rotavg::Rotation| { let q = rotavg::nalgebra::UnitQuaternion::from_rotation_matrix(m); format!("{} {} {} {}", q.i, q.j, q.k, q.w) };
/// let mut problem = String::new();
/// for (a, b) in [(0, 1), (1, 2), (2, 0)] {
///     // g2o edges measure W_i^T W_j with W = R^T
///     problem += &format!("EDGE_SE3:QUAT {} {} 0 0 0 {}\n", 10 * (a + 1), 10 * (b + 1), quat(&(r[a] * r[b].inverse())));
/// }
/// let graph = read_graph(&problem, "p.g2o", GraphFormat::Auto, &ReadOptions::default())?;
/// // Another tool's answer: vertices in another order, with translations.
/// let mut est = String::new();
/// for k in [2, 0, 1] {
///     est += &format!("VERTEX_SE3:QUAT {} 1 2 3 {}\n", 10 * (k + 1), quat(&r[k].inverse()));
/// }
/// let path = std::env::temp_dir().join(format!("rotavg-doc-est-{}.g2o", std::process::id()));
/// std::fs::write(&path, est).unwrap();
/// let e = load_estimate_for(path.to_str().unwrap(), &graph, &ReadOptions::default());
/// std::fs::remove_file(&path).unwrap();
/// let e = e?;
/// assert_eq!(e.matched_by, MatchedBy::Id);
/// assert!((0..3).all(|k| angle_between(&e.rotations[k], &r[k]) < 1e-9));
/// assert!(graph.problem.chordal_cost(&e.rotations) < 1e-12);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn load_estimate_for(
    path: &str,
    graph: &LoadedGraph,
    options: &ReadOptions,
) -> Result<GraphEstimate> {
    let r = load_rotations_for_nodes(path, graph, options)?;
    let warning = r.unmatched_warning();
    let warnings = r.warnings();
    let (file, format, matched_by, unmatched) =
        (r.file.clone(), r.format, r.matched_by, r.unmatched.clone());
    let rotations = r.require_all(graph, "estimate")?;
    Ok(GraphEstimate {
        name: path.to_string(),
        file,
        format,
        matched_by,
        rotations,
        unmatched,
        warning,
        warnings,
    })
}

/// An estimate of every node of a graph ([`load_estimate_for`]).
#[derive(Debug, Clone, PartialEq)]
pub struct GraphEstimate {
    /// The path as given.
    pub name: String,
    /// The file read (a model folder's `images.bin` / `images.txt`, a folder's database).
    pub file: String,
    /// What the file is.
    pub format: EstimateFormat,
    /// How entries were matched to nodes.
    pub matched_by: MatchedBy,
    /// The rotation of each node.
    pub rotations: Vec<Rotation>,
    /// Entries of the file that match no node (not used).
    pub unmatched: Vec<String>,
    /// [`NodeRotations::unmatched_warning`].
    pub warning: Option<String>,
    /// [`NodeRotations::warnings`] (the unmatched entries among them).
    pub warnings: Vec<Warning>,
}

impl GraphEstimate {
    /// The estimate as [`crate::report::CertifyReport::certify`] takes it.
    pub fn into_loaded(self) -> LoadedEstimate {
        LoadedEstimate {
            name: self.name,
            estimate: Estimate::Multiple(self.rotations),
            warnings: self.warnings,
        }
    }
}

/// An estimate file and its name (for errors about its size or kind).
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedEstimate {
    /// The path as given.
    pub name: String,
    /// The rotations read.
    pub estimate: Estimate,
    /// What the reader said about the file ([`NodeRotations::warnings`]; none for single and
    /// conjugate estimates).
    pub warnings: Vec<Warning>,
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
    if let Some(rotations) = load_numpy(path, options)? {
        let estimate = match <[Rotation; 1]>::try_from(rotations) {
            Ok([one]) => Estimate::Single(one),
            Err(many) => Estimate::Multiple(many),
        };
        return Ok(LoadedEstimate {
            name: path.to_string(),
            estimate,
            warnings: Vec::new(),
        });
    }
    let input = read_input(path)?;
    Ok(LoadedEstimate {
        estimate: read_estimate(&input.text, &input.name, options)?,
        name: input.name,
        warnings: Vec::new(),
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
    let mut graph = load_view_graph(path, options.format, &options.read)?;
    let truth = match &options.ground_truth {
        Some(p) => {
            let r = load_rotations_for_nodes(p, &graph, &options.read)?;
            // a ground truth of more cameras than the graph's is common: only what is not
            // used of the entries that match (NaN translations) is said
            let said = r
                .warnings()
                .into_iter()
                .filter(|w| w.code != "estimate_unmatched");
            graph.warnings.extend(said);
            Some((p, truth_of(r, &graph)?))
        }
        None => None,
    };
    let init = match &options.init {
        Some(p) => {
            let r = load_rotations_for_nodes(p, &graph, &options.read)?;
            graph.warnings.extend(r.warnings());
            Some((p, initial_of(r, &graph)?))
        }
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
