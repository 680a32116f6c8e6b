//! Writing estimates to files, as `rotavg multiple --output FILE [--output-format F]` does:
//! [`OutputFormat`] `auto` picks g2o for a `.g2o` path, COLMAP `images.txt` for a path ending
//! in `images.txt`, otherwise JSON `{"node_ids": [...], "rotations": [R, ...]}` (readable by
//! [`crate::io::json::read_estimate`]).

use crate::error::{Error, Result};
use crate::multiple::MultipleProblem;
use crate::multiple::robust::EdgeResiduals;
use crate::so3::Rotation;
use serde::{Deserialize, Serialize};

/// The format of an estimate file.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OutputFormat {
    /// From the path ([`OutputFormat::for_path`]).
    #[default]
    Auto,
    /// `{"node_ids": [...], "rotations": [R, ...]}`.
    Json,
    /// g2o: the problem's edges and the estimate as vertex lines ([`crate::io::g2o::write_g2o`]).
    G2o,
    /// COLMAP `images.txt` ([`crate::io::colmap::write_images_text`]).
    Colmap,
}

impl OutputFormat {
    /// The format `auto` means for `path`: g2o for `*.g2o`, COLMAP for `*images.txt`, else
    /// JSON; any other value is returned unchanged.
    ///
    /// ```
    /// use rotavg::io::output::OutputFormat;
    /// assert_eq!(OutputFormat::Auto.for_path("sparse/images.txt"), OutputFormat::Colmap);
    /// assert_eq!(OutputFormat::Auto.for_path("est.g2o"), OutputFormat::G2o);
    /// assert_eq!(OutputFormat::Auto.for_path("est.txt"), OutputFormat::Json);
    /// assert_eq!(OutputFormat::Colmap.for_path("est.txt"), OutputFormat::Colmap);
    /// ```
    pub fn for_path(self, path: &str) -> OutputFormat {
        if self != OutputFormat::Auto {
            return self;
        }
        let lower = path.to_ascii_lowercase();
        if lower.ends_with(".g2o") {
            OutputFormat::G2o
        } else if lower.ends_with("images.txt") {
            OutputFormat::Colmap
        } else {
            OutputFormat::Json
        }
    }
}

/// What an estimate file holds: the problem, the estimate and the file's node ids and names.
#[derive(Debug, Clone, Copy)]
pub struct EstimateFile<'a> {
    /// The problem solved (its edges go into g2o files).
    pub problem: &'a MultipleProblem,
    /// The estimate, one rotation per node.
    pub rotations: &'a [Rotation],
    /// The file id of each node.
    pub node_ids: &'a [u64],
    /// The name of each node, or empty (COLMAP files then use the ids as names).
    pub node_names: &'a [String],
}

impl EstimateFile<'_> {
    /// The text of the file in `format` (resolved for `path` when `auto`).
    ///
    /// ```
    /// use rotavg::io::output::{EstimateFile, OutputFormat};
    /// use rotavg::multiple::{Edge, MultipleProblem};
    /// use rotavg::Rotation;
    /// let p = MultipleProblem::new(2, vec![Edge { i: 0, j: 1, rotation: Rotation::identity(), weight: 1.0 }])?;
    /// let rs = vec![Rotation::identity(); 2];
    /// let names = vec!["a.jpg".to_string(), "b.jpg".to_string()];
    /// let file = EstimateFile { problem: &p, rotations: &rs, node_ids: &[1, 2], node_names: &names };
    /// assert!(file.text("out/images.txt", OutputFormat::Auto)?.contains("\n2 1 0 0 0 0 0 0 1 b.jpg\n"));
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn text(&self, path: &str, format: OutputFormat) -> Result<String> {
        match format.for_path(path) {
            OutputFormat::Colmap => {
                crate::io::colmap::write_images_text(self.rotations, self.node_ids, self.node_names)
            }
            OutputFormat::G2o => Ok(crate::io::g2o::write_g2o(
                self.problem,
                Some(self.rotations),
            )),
            OutputFormat::Json | OutputFormat::Auto => {
                let mut s = serde_json::to_string(&EstimateWithIds {
                    node_ids: self.node_ids,
                    rotations: self.rotations,
                })
                .unwrap_or_default();
                s.push('\n');
                Ok(s)
            }
        }
    }

    /// Write [`Self::text`] to `path`; I/O errors name the path.
    pub fn write(&self, path: &str, format: OutputFormat) -> Result<()> {
        write_text(path, &self.text(path, format)?)
    }
}

#[derive(Serialize)]
struct EstimateWithIds<'a> {
    node_ids: &'a [u64],
    #[serde(with = "crate::so3::serde_rows::rotations")]
    rotations: &'a [Rotation],
}

/// The text of an estimate file for `path`: g2o ([`crate::io::g2o::write_g2o`]: the problem's
/// edges and the estimate as vertex lines) when `path` ends in `.g2o`, otherwise one JSON line
/// `{"node_ids": [...], "rotations": [R, ...]}` (`node_ids[k]` is the file id of node `k`).
/// (No names, no COLMAP: see [`EstimateFile`] for those.)
///
/// ```
/// use rotavg::io::output::estimate_file_text;
/// use rotavg::io::json::read_estimate;
/// use rotavg::io::detect::ReadOptions;
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::Rotation;
/// let p = MultipleProblem::new(2, vec![Edge { i: 0, j: 1, rotation: Rotation::identity(), weight: 1.0 }])?;
/// let rs = vec![Rotation::identity(); 2];
/// let json = estimate_file_text("est.json", &p, &rs, &[10, 20]);
/// assert!(json.starts_with(r#"{"node_ids":[10,20],"rotations":"#));
/// assert!(read_estimate(&json, "est.json", &ReadOptions::default()).is_ok());
/// assert!(estimate_file_text("est.g2o", &p, &rs, &[10, 20]).starts_with("VERTEX_SE3:QUAT 0 "));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn estimate_file_text(
    path: &str,
    problem: &MultipleProblem,
    rotations: &[Rotation],
    node_ids: &[u64],
) -> String {
    if path.to_ascii_lowercase().ends_with(".g2o") {
        crate::io::g2o::write_g2o(problem, Some(rotations))
    } else {
        let mut s = serde_json::to_string(&EstimateWithIds {
            node_ids,
            rotations,
        })
        .unwrap_or_default();
        s.push('\n');
        s
    }
}

/// Write [`estimate_file_text`] to `path`; I/O errors name the path.
///
/// ```
/// use rotavg::io::output::write_estimate_file;
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::Rotation;
/// let p = MultipleProblem::new(2, vec![Edge { i: 0, j: 1, rotation: Rotation::identity(), weight: 1.0 }])?;
/// let err = write_estimate_file("no/such/dir/est.json", &p, &[Rotation::identity(); 2], &[0, 1]);
/// assert!(err.unwrap_err().to_string().contains("no/such/dir/est.json"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn write_estimate_file(
    path: &str,
    problem: &MultipleProblem,
    rotations: &[Rotation],
    node_ids: &[u64],
) -> Result<()> {
    write_text(
        path,
        &estimate_file_text(path, problem, rotations, node_ids),
    )
}

/// Write `text` to the file at `path`; I/O errors name the path.
///
/// ```
/// let err = rotavg::io::output::write_text("no/such/dir/x.txt", "x").unwrap_err();
/// assert!(matches!(err, rotavg::Error::Io { .. }));
/// ```
pub fn write_text(path: &str, text: &str) -> Result<()> {
    std::fs::write(path, text).map_err(|e| Error::Io {
        path: path.into(),
        message: e.to_string(),
    })
}

#[derive(Serialize)]
struct EdgeRow {
    i: u64,
    j: u64,
    residual_deg: f64,
    weight: f64,
    inlier: bool,
}

#[derive(Serialize)]
struct EdgesJson {
    inlier_threshold_deg: f64,
    edges: Vec<EdgeRow>,
}

/// The text of a per-edge residual file (`rotavg multiple --edges-output FILE`), one row per
/// edge in the input's edge order, nodes named by their file ids (`node_ids[k]` names node `k`):
/// JSON `{"inlier_threshold_deg": t, "edges": [{"i", "j", "residual_deg", "weight",
/// "inlier"}, ...]}` when `path` ends in `.json`, otherwise CSV with the header
/// `i,j,residual_deg,weight,inlier` (`inlier` 1 or 0). `residual_deg`: the residual angle at the
/// estimate; `weight`: the final IRLS weight relative to the edge's own weight, in `(0, 1]`;
/// `inlier`: `residual_deg <= inlier_threshold_deg` ([`EdgeResiduals`]).
///
/// ```
/// use rotavg::io::output::edges_file_text;
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::multiple::robust::edge_residuals;
/// use rotavg::objective::{Loss, Objective};
/// use rotavg::so3::exp;
/// use rotavg::{Metric, Rotation};
/// let turn = exp(&nalgebra::Vector3::new(0.0, 0.0, 10f64.to_radians()));
/// let p = MultipleProblem::new(2, vec![Edge { i: 0, j: 1, rotation: turn, weight: 1.0 }])?
///     .with_objective(Objective::new(Metric::Geodesic, Loss::Huber { threshold_deg: 5.0 }))?;
/// let r = edge_residuals(&p, &[Rotation::identity(); 2], 5.0);
/// let csv = edges_file_text("edges.csv", &p, &r, &[7, 9]);
/// assert_eq!(csv.lines().next(), Some("i,j,residual_deg,weight,inlier"));
/// let row: Vec<f64> = csv.lines().nth(1).unwrap().split(',').map(|x| x.parse().unwrap()).collect();
/// assert_eq!((row[0], row[1], row[4]), (7.0, 9.0, 0.0)); // file ids; an outlier
/// assert!((row[2] - 10.0).abs() < 1e-9 && (row[3] - 0.5).abs() < 1e-9); // Huber weight c / theta
/// let json = edges_file_text("edges.json", &p, &r, &[7, 9]);
/// assert!(json.contains(r#""i":7,"j":9"#) && json.contains(r#""inlier":false"#));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn edges_file_text(
    path: &str,
    problem: &MultipleProblem,
    residuals: &EdgeResiduals,
    node_ids: &[u64],
) -> String {
    let id = |k: usize| node_ids.get(k).copied().unwrap_or(k as u64);
    let rows = problem
        .edges()
        .iter()
        .zip(&residuals.residual_deg)
        .zip(&residuals.weight)
        .zip(&residuals.inlier)
        .map(|(((e, &residual_deg), &weight), &inlier)| EdgeRow {
            i: id(e.i),
            j: id(e.j),
            residual_deg,
            weight,
            inlier,
        });
    if path.to_ascii_lowercase().ends_with(".json") {
        let mut s = serde_json::to_string(&EdgesJson {
            inlier_threshold_deg: residuals.summary.inlier_threshold_deg,
            edges: rows.collect(),
        })
        .unwrap_or_default();
        s.push('\n');
        s
    } else {
        let mut s = String::from("i,j,residual_deg,weight,inlier\n");
        for r in rows {
            s.push_str(&format!(
                "{},{},{},{},{}\n",
                r.i,
                r.j,
                r.residual_deg,
                r.weight,
                u8::from(r.inlier)
            ));
        }
        s
    }
}
