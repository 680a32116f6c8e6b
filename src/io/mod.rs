//! Readers and writers for the file formats: JSON (contract section 5), g2o (3-D and 2-D), TORO
//! `EDGE3`, 1DSfM `EGs.txt`, Bundler ground truth, COLMAP databases and sparse models,
//! hand-eye pose files. Each reader documents,
//! where it reads, how the format maps onto this crate's conventions.
//!
//! | module | reads | writes |
//! |---|---|---|
//! | [`colmap`] | COLMAP databases ([`colmap::read_colmap_database`], SQLite), `images.txt` / `images.bin` ([`colmap::load_images`]) | `images.txt` ([`colmap::write_images_text`]) |
//! | [`detect`] | any view graph: [`detect::load_graph`] (path, streamed), [`detect::read_graph`] (text), [`detect::read_graph_stream`], format auto-detection | — |
//! | [`g2o`] | g2o 3-D / 2-D and TORO `EDGE3` ([`g2o::read_g2o`], line by line: [`g2o::read_g2o_lines`]) | [`g2o::write_g2o`] |
//! | [`sfm`] | 1DSfM `EGs.txt` ([`sfm::read_egs`], line by line: [`sfm::read_egs_lines`]), Bundler ground truth, rotation lists | — |
//! | [`json`] | multiple problems ([`json::read_problem_json`]) and estimates ([`json::read_estimate`]) | [`json::write_problem_json`], [`json::write_estimate_json`] |
//! | [`single_json`] | single problems ([`single_json::parse_single_json`]) and estimates | [`single_json::to_single_json`] |
//! | [`handeye`] | Tabb and ETH hand-eye data, conjugate JSON ([`handeye::read_conjugate_json`]) | [`handeye::write_conjugate_json`] |
//! | [`input`] | what the command line reads: `-` for stdin, problem-kind detection, unit weights, ground truth, estimates, the largest component ([`input::load_multiple_input`]) | — |
//! | [`output`] | — | estimate files ([`output::write_estimate_file`]: g2o or JSON with node ids) |
//! | [`text`] | any text input with bounded memory ([`text::TextStream`]: size limit, binary data refused from the first block, UTF-8 errors with the line; read whole, [`text::read_text`], or line by line, [`text::TextLines`]) | — |
//! | [`names`] | the names of metrics, losses, certify modes, formats ([`names::Choice`], `FromStr`) | — |
//!
//! **Memory.** The view-graph formats that can be large, g2o / TORO and 1DSfM `EGs.txt`, are
//! streamed from a path or standard input ([`detect::load_graph`],
//! [`input::load_view_graph`], [`input::load_problem`]: what `rotavg multiple`, `certify` and
//! `info` read): one line of text at a time, so memory is what is kept, a fixed size per edge
//! and vertex, at most [`text::MAX_RECORDS`] of them. JSON inputs (problems, estimates), ground
//! truth, COLMAP `images.txt` and hand-eye streams are read whole (serde_json and the
//! line readers take the text), below [`text::MAX_INPUT_BYTES`].
//!
//! Readers take the text and a file name (used in error messages, with the line number), so
//! tests and examples can read from inline strings:
//!
//! ```
//! use rotavg::io::detect::{read_graph, GraphFormat, ReadOptions};
//! // 1DSfM: `i j R11 .. R33` per line, holding R_i R_j^T; read as R_ij = its transpose.
//! let text = "0 1 1 0 0 0 1 0 0 0 1\n1 2 1 0 0 0 1 0 0 0 1\n";
//! let g = read_graph(text, "EGs.txt", GraphFormat::Auto, &ReadOptions::default())?;
//! assert_eq!(g.format, GraphFormat::OneDsfm);
//! assert_eq!((g.problem.num_rotations(), g.problem.num_edges()), (3, 2));
//! let err = read_graph("0 1 2 3\n", "bad.txt", GraphFormat::OneDsfm, &ReadOptions::default());
//! assert!(err.unwrap_err().to_string().starts_with("bad.txt:1:"));
//! # Ok::<(), rotavg::Error>(())
//! ```

pub mod colmap;
pub mod detect;
pub mod g2o;
pub mod gravity;
pub mod handeye;
pub mod input;
pub mod json;
pub mod names;
pub mod nearest;
pub mod numpy;
pub mod output;
pub mod rig;
pub mod sfm;
pub mod single_json;
pub mod text;
pub mod two_view_information;
pub mod values;
pub mod within_frame;

pub(crate) use crate::validate::weight_out_of_range;
/// The weight window of every reader and constructor (see [`crate::validate::MAX_WEIGHT`]).
pub use crate::validate::{MAX_WEIGHT, MIN_WEIGHT};

/// An edge as a reader keeps it, with the file's node ids: the size and alignment of
/// [`crate::multiple::Edge`], so [`compact_edges`] turns the one into the other in place.
pub(crate) struct RawEdge {
    pub(crate) i: u64,
    pub(crate) j: u64,
    pub(crate) rotation: crate::so3::Rotation,
    pub(crate) weight: f64,
}

/// Node ids compacted, for edges read with file ids: the sorted distinct ids of `extra_ids`
/// (e.g. vertex lines) and of the edges' endpoints (node `k` is `ids[k]`), and the edges
/// between their indices, in file order (1DSfM, g2o, COLMAP). The edge list is converted in place (the two types
/// have one size), so the peak memory is the edges plus 16 bytes per edge for the ids.
pub(crate) fn compact_edges(
    raw: Vec<RawEdge>,
    extra_ids: impl Iterator<Item = u64>,
) -> (Vec<u64>, Vec<crate::multiple::Edge>) {
    let mut ids: Vec<u64> = extra_ids.collect();
    ids.extend(raw.iter().flat_map(|e| [e.i, e.j]));
    ids.sort_unstable();
    ids.dedup();
    ids.shrink_to_fit();
    let index = |id: u64| ids.binary_search(&id).unwrap_or(0);
    let edges = raw
        .into_iter()
        .map(|e| crate::multiple::Edge {
            i: index(e.i),
            j: index(e.j),
            rotation: e.rotation,
            weight: e.weight,
        })
        .collect();
    (ids, edges)
}

/// The content lines of a text file: `(1-based line number, trimmed line)` for every line that
/// is neither blank nor a `#` comment. Shared by the line-oriented readers.
pub(crate) fn content_lines(text: &str) -> impl Iterator<Item = (usize, &str)> {
    text.lines()
        .enumerate()
        .map(|(k, l)| (k + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'))
}

/// The line to blame for "nothing found" errors: the last line of the file (1 when empty).
pub(crate) fn last_line(text: &str) -> usize {
    text.lines().count().max(1)
}
