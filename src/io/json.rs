//! JSON files of contract section 5: multiple-averaging problems and estimates.
//!
//! # Formats (`paper-notes/formats.md`, `[F8]`)
//!
//! * Problem: `{"num_rotations": n, "edges": [{"i": 0, "j": 1, "rotation": R, "weight": w}, ...]}`
//!   with `R` = `R_ij` (`R_ij R_i = R_j`, this crate's convention, no conversion), a row-major
//!   nested 3x3 array, indices 0-based, `weight` optional (default 1; within [`crate::io::MIN_WEIGHT`,
//!   `crate::io::MAX_WEIGHT`] when weights come from the file). Anisotropic measurements (contract
//!   section 1): `"information": H` (a symmetric positive semidefinite 3x3 array for the residual
//!   `e` of `R_j R_i^T = R_ij exp([e]x)`) instead of `"weight"`; when any edge has one, the problem
//!   is anisotropic and an edge without it counts as `H = w I` (exactly the isotropic term);
//!   `--weights unit` ignores every information and weight. Unknown fields in an
//!   edge are an error (a misspelt `"wieght"` must not silently become 1); unknown top-level
//!   fields are ignored.
//! * Estimate: `{"rotations": [R, ...]}`, or `{"estimate": [R, ...]}` as printed by `--json`
//!   (multiple), or `{"rotation": R}` / `{"estimate": R}` (single, conjugate). Rotations are
//!   this crate's `R_i`.
//!
//! Syntax errors carry serde_json's line number; a matrix that is not a rotation is reported
//! as `edge k` / `rotation k`.

use crate::error::{Error, Result};
use crate::io::detect::{LoadedGraph, ReadOptions, WeightSource};
use crate::multiple::anisotropic::Information;
use crate::multiple::{Edge, MultipleProblem};
use crate::so3::{Rotation, rotation_from_rows, rotation_to_rows};
use serde::{Deserialize, Serialize};

type Rows = [[f64; 3]; 3];

#[derive(Deserialize)]
#[serde(
    expecting = "a JSON object {\"num_rotations\": n, \"edges\": [{\"i\": 0, \"j\": 1, \"rotation\": R, \"weight\": w}, ...]}"
)]
struct ProblemFile {
    num_rotations: usize,
    edges: Vec<EdgeFile>,
}

#[derive(Deserialize, Serialize)]
#[serde(
    deny_unknown_fields,
    expecting = "an edge {\"i\": 0, \"j\": 1, \"rotation\": R, \"weight\": w} (weight optional; or \"information\": H, a 3x3 array, instead of the weight)"
)]
pub(crate) struct EdgeFile {
    i: usize,
    j: usize,
    rotation: Rows,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    weight: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    information: Option<Rows>,
}

fn syntax_error(file: &str, e: serde_json::Error) -> Error {
    let line = (e.line() > 0).then_some(e.line());
    Error::parse(Some(file), line, format!("invalid JSON: {e}"))
}

/// Read a multiple-averaging problem in the JSON format of contract section 5 `[F8]`.
///
/// ```
/// use rotavg::io::{json::read_problem_json, detect::ReadOptions};
/// let text = r#"{"num_rotations": 2, "edges": [{"i": 0, "j": 1, "rotation": [[1,0,0],[0,1,0],[0,0,1]]}]}"#;
/// let g = read_problem_json(text, "p.json", &ReadOptions::default()).unwrap();
/// assert_eq!(g.problem.edges()[0].weight, 1.0);
/// ```
pub fn read_problem_json(text: &str, file: &str, options: &ReadOptions) -> Result<LoadedGraph> {
    let pf: ProblemFile = serde_json::from_str(text).map_err(|e| syntax_error(file, e))?;
    let n = pf.num_rotations;
    let m = pf.edges.len();
    // No allocation sized from an unchecked count: more than 2m + 1 nodes means some node has
    // no edge at all (and the number could be absurd); reject before building anything of size n.
    if n > 2 * m + 1 {
        return Err(Error::parse(
            Some(file),
            None,
            format!(
                "num_rotations = {n}, but {m} edges touch at most {} nodes",
                2 * m
            ),
        ));
    }
    let (edges, information) = read_edges(&pf.edges, file, options)?;
    let reversed = edges.iter().filter(|e| e.i > e.j).count();
    let mut problem = MultipleProblem::new(n, edges).map_err(|e| e.in_file(file, None))?;
    if let Some(information) = information {
        problem = problem
            .with_information(information)
            .map_err(|e| e.in_file(file, None))?;
    }
    Ok(LoadedGraph {
        reversed,
        ..LoadedGraph::from_problem(problem)
    })
}

/// A JSON file's edges checked, and their information when any edge carries some (an edge
/// with a weight `w` then has `H = w I`). With unit weights ([`WeightSource::Unit`]) every
/// weight is 1 and no information is read (each edge's rotation, and that it gives a weight or
/// an information but not both, still checked). Errors name the file and the edge.
pub(crate) fn read_edges(
    entries: &[EdgeFile],
    file: &str,
    options: &ReadOptions,
) -> Result<(Vec<Edge>, Option<Vec<Information>>)> {
    let from_file = options.weights == WeightSource::File;
    let anisotropic = from_file && entries.iter().any(|e| e.information.is_some());
    let mut edges = Vec::with_capacity(entries.len());
    let mut information = Vec::with_capacity(if anisotropic { entries.len() } else { 0 });
    for (k, e) in entries.iter().enumerate() {
        let item = format!("edge {k} ({}, {})", e.i, e.j);
        let bad = |why: String| Error::parse(Some(file), None, format!("{item}: {why}"));
        let rotation = rotation_from_rows(&e.rotation, options.rotation_tolerance, &item)
            .map_err(|err| err.in_file(file, None))?;
        if e.weight.is_some() && e.information.is_some() {
            return Err(bad("give \"weight\" or \"information\", not both".into()));
        }
        let weight = e.weight.unwrap_or(1.0);
        if from_file && let Some(why) = crate::io::weight_out_of_range(weight) {
            return Err(bad(why));
        }
        if anisotropic {
            let rows = e.information.unwrap_or(isotropic_rows(weight));
            information.push(
                Information::try_from(rows).map_err(|why| bad(format!("information {why}")))?,
            );
        }
        edges.push(Edge {
            i: e.i,
            j: e.j,
            rotation,
            weight: if from_file { weight } else { 1.0 },
        });
    }
    Ok((edges, anisotropic.then_some(information)))
}

/// `w I` as rows.
fn isotropic_rows(w: f64) -> Rows {
    [[w, 0.0, 0.0], [0.0, w, 0.0], [0.0, 0.0, w]]
}

/// Write a problem as JSON (contract section 5), one edge per line (with its `information` when the
/// problem is anisotropic, its `weight` otherwise); numbers in Rust's shortest
/// round-trip form, so [`read_problem_json`] gives back the same problem.
///
/// ```
/// use rotavg::io::{json::{read_problem_json, write_problem_json}, detect::ReadOptions};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, _) = SyntheticGraph { num_rotations: 4, num_edges: 6, ..Default::default() }.generate();
/// let q = read_problem_json(&write_problem_json(&p), "-", &ReadOptions::default()).unwrap();
/// assert_eq!(q.problem.num_edges(), 6);
/// ```
pub fn write_problem_json(problem: &MultipleProblem) -> String {
    let mut s = format!(
        "{{\"num_rotations\": {}, \"edges\": [\n",
        problem.num_rotations()
    );
    let info = problem.information();
    let lines: Vec<String> = problem
        .edges()
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let information = info.map(|h| <[[f64; 3]; 3]>::from(h[k]));
            let ef = EdgeFile {
                i: e.i,
                j: e.j,
                rotation: rotation_to_rows(&e.rotation),
                weight: information.is_none().then_some(e.weight),
                information,
            };
            format!("  {}", serde_json::to_string(&ef).unwrap_or_default())
        })
        .collect();
    s.push_str(&lines.join(",\n"));
    s.push_str("\n]}\n");
    s
}

/// An estimate read from a file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Estimate {
    /// One rotation per node (multiple averaging).
    Multiple(#[serde(with = "crate::so3::serde_rows::rotations")] Vec<Rotation>),
    /// One rotation (single, conjugate).
    Single(#[serde(with = "crate::so3::serde_rows::rotation")] Rotation),
}

impl Estimate {
    /// The rotations of a multiple-averaging estimate; a parse error naming `file` for a
    /// single rotation.
    ///
    /// ```
    /// use rotavg::io::json::Estimate;
    /// use rotavg::Rotation;
    /// assert_eq!(Estimate::Multiple(vec![Rotation::identity(); 2]).into_rotations("e.json")?.len(), 2);
    /// assert!(Estimate::Single(Rotation::identity()).into_rotations("e.json").is_err());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn into_rotations(self, file: &str) -> Result<Vec<Rotation>> {
        match self {
            Estimate::Multiple(rs) => Ok(rs),
            Estimate::Single(_) => Err(Error::parse(
                Some(file),
                None,
                "expected a list of rotations (\"rotations\": [R, ...]), found a single rotation",
            )),
        }
    }

    /// The rotation of a single or conjugate estimate; a parse error naming `file` for a list.
    ///
    /// ```
    /// use rotavg::io::json::Estimate;
    /// use rotavg::Rotation;
    /// assert_eq!(Estimate::Single(Rotation::identity()).into_rotation("e.json")?, Rotation::identity());
    /// assert!(Estimate::Multiple(vec![]).into_rotation("e.json").is_err());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn into_rotation(self, file: &str) -> Result<Rotation> {
        match self {
            Estimate::Single(r) => Ok(r),
            Estimate::Multiple(_) => Err(Error::parse(
                Some(file),
                None,
                "expected one rotation ({\"rotation\": R}) for this problem, found a list",
            )),
        }
    }
}

#[derive(Deserialize)]
#[serde(
    expecting = "a JSON object {\"rotations\": [R, ...]} (or {\"estimate\": ...} as `--json` prints it, or {\"rotation\": R})"
)]
struct EstimateFile {
    rotations: Option<Vec<Rows>>,
    rotation: Option<Rows>,
    estimate: Option<serde_json::Value>,
}

/// Read an estimate file `[F8]`: `{"rotations": [R, ...]}`, `{"estimate": [R, ...]}`,
/// `{"rotation": R}` or `{"estimate": R}`. Extra fields (the rest of a `--json` output) are
/// ignored. Every matrix must be a rotation within `options.rotation_tolerance`.
///
/// ```
/// use rotavg::io::{json::{read_estimate, Estimate}, detect::ReadOptions};
/// let e = read_estimate(r#"{"rotation": [[1,0,0],[0,1,0],[0,0,1]]}"#, "e.json", &ReadOptions::default()).unwrap();
/// assert!(matches!(e, Estimate::Single(_)));
/// ```
pub fn read_estimate(text: &str, file: &str, options: &ReadOptions) -> Result<Estimate> {
    let ef: EstimateFile = serde_json::from_str(text).map_err(|e| syntax_error(file, e))?;
    let tol = options.rotation_tolerance;
    let many = |rows: &[Rows]| -> Result<Vec<Rotation>> {
        if rows.is_empty() {
            return Err(Error::parse(
                Some(file),
                None,
                "the estimate has no rotations",
            ));
        }
        rows.iter()
            .enumerate()
            .map(|(k, r)| {
                rotation_from_rows(r, tol, &format!("rotation {k}"))
                    .map_err(|e| e.in_file(file, None))
            })
            .collect()
    };
    let one = |r: &Rows| rotation_from_rows(r, tol, "rotation").map_err(|e| e.in_file(file, None));
    match (&ef.rotations, &ef.rotation, &ef.estimate) {
        (Some(rs), None, None) => Ok(Estimate::Multiple(many(rs)?)),
        (None, Some(r), None) => Ok(Estimate::Single(one(r)?)),
        (None, None, Some(v)) => {
            if let Ok(rs) = serde_json::from_value::<Vec<Rows>>(v.clone()) {
                Ok(Estimate::Multiple(many(&rs)?))
            } else if let Ok(r) = serde_json::from_value::<Rows>(v.clone()) {
                Ok(Estimate::Single(one(&r)?))
            } else {
                Err(Error::parse(
                    Some(file),
                    None,
                    "\"estimate\" is neither a 3x3 rotation nor a list of them",
                ))
            }
        }
        (None, None, None) => Err(Error::parse(
            Some(file),
            None,
            "no \"rotations\", \"estimate\" or \"rotation\" field",
        )),
        _ => Err(Error::parse(
            Some(file),
            None,
            "more than one of \"rotations\", \"estimate\", \"rotation\": ambiguous estimate",
        )),
    }
}

/// Read an estimate for multiple averaging (a list of rotations); a single rotation is an error.
///
/// ```
/// use rotavg::io::{detect::ReadOptions, json::{read_rotations_estimate, write_estimate_json}};
/// use rotavg::so3::{angle_between, exp};
/// let rs = vec![rotavg::Rotation::identity(), exp(&nalgebra::Vector3::new(0.1, 0.2, 0.3))];
/// let text = write_estimate_json(&rs);
/// let back = read_rotations_estimate(&text, "estimate.json", &ReadOptions::default())?;
/// assert!(angle_between(&back[1], &rs[1]) < 1e-15);
/// let one = r#"{"rotation": [[1,0,0],[0,1,0],[0,0,1]]}"#;
/// assert!(read_rotations_estimate(one, "single.json", &ReadOptions::default()).is_err());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_rotations_estimate(
    text: &str,
    file: &str,
    options: &ReadOptions,
) -> Result<Vec<Rotation>> {
    read_estimate(text, file, options)?.into_rotations(file)
}

/// Write a single or conjugate estimate `{"rotation": R}` (what [`read_estimate`],
/// `rotavg certify --estimate` and `--init` read), shortest round-trip numbers.
///
/// ```
/// use rotavg::io::{json::{write_rotation_json, read_estimate, Estimate}, detect::ReadOptions};
/// let r = rotavg::so3::exp(&nalgebra::Vector3::new(0.1, -0.2, 0.3));
/// let back = read_estimate(&write_rotation_json(&r), "-", &ReadOptions::default())?;
/// assert_eq!(back, Estimate::Single(r));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn write_rotation_json(rotation: &Rotation) -> String {
    let rows = serde_json::to_string(&rotation_to_rows(rotation)).unwrap_or_default();
    format!("{{\"rotation\": {rows}}}\n")
}

/// Write an estimate `{"rotations": [R, ...]}`, one rotation per line, shortest round-trip
/// numbers.
///
/// ```
/// use rotavg::io::{json::{write_estimate_json, read_rotations_estimate}, detect::ReadOptions};
/// let rs = vec![rotavg::Rotation::identity(); 3];
/// let back = read_rotations_estimate(&write_estimate_json(&rs), "-", &ReadOptions::default()).unwrap();
/// assert_eq!(back, rs);
/// ```
pub fn write_estimate_json(rotations: &[Rotation]) -> String {
    let lines: Vec<String> = rotations
        .iter()
        .map(|r| {
            format!(
                "  {}",
                serde_json::to_string(&rotation_to_rows(r)).unwrap_or_default()
            )
        })
        .collect();
    format!("{{\"rotations\": [\n{}\n]}}\n", lines.join(",\n"))
}

/// Write a rig's estimate `{"rotations": [R, ...], "node_ids": [...], "sensor_from_rig": S}`
/// (`rotavg rig --output`): the frames one per line, then the frames' file ids and `S`.
///
/// ```
/// use rotavg::io::json::write_rig_json;
/// let text = write_rig_json(&[rotavg::Rotation::identity(); 2], &[4, 7], &rotavg::Rotation::identity());
/// let v: serde_json::Value = serde_json::from_str(&text).unwrap();
/// assert_eq!(v["node_ids"], serde_json::json!([4, 7]));
/// assert_eq!(v["sensor_from_rig"][2][2], 1.0);
/// ```
pub fn write_rig_json(rotations: &[Rotation], node_ids: &[u64], s: &Rotation) -> String {
    let frames = write_estimate_json(rotations);
    let head = frames.trim_end().trim_end_matches('}');
    format!(
        "{head}, \"node_ids\": {}, \"sensor_from_rig\": {}}}\n",
        serde_json::to_string(node_ids).unwrap_or_default(),
        serde_json::to_string(&rotation_to_rows(s)).unwrap_or_default()
    )
}

/// The `"sensor_from_rig"` rotation of a rig estimate file (`rotavg rig --output`), a rotation
/// within `options.rotation_tolerance`. Errors: no such field, not a rotation, not JSON.
pub fn read_sensor_from_rig(path: &str, options: &ReadOptions) -> Result<Rotation> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
        path: path.into(),
        message: e.to_string(),
    })?;
    #[derive(Deserialize)]
    struct Rig {
        sensor_from_rig: Option<[[f64; 3]; 3]>,
    }
    let rig: Rig = serde_json::from_str(&text).map_err(|e| syntax_error(path, e))?;
    let rows = rig.sensor_from_rig.ok_or_else(|| {
        Error::parse(
            Some(path),
            None,
            "a rig estimate needs \"sensor_from_rig\": S (as `rotavg rig --output` writes it)",
        )
    })?;
    crate::so3::rotation_from_rows(
        &rows,
        options.rotation_tolerance,
        &format!("{path}: sensor_from_rig"),
    )
}
