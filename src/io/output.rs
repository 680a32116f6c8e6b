//! Writing estimates to files, as `rotavg multiple --output FILE` does: g2o for a `.g2o` path,
//! otherwise JSON `{"node_ids": [...], "rotations": [R, ...]}` (readable by
//! [`crate::io::json::read_estimate`]).

use crate::error::{Error, Result};
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use serde::Serialize;

#[derive(Serialize)]
struct EstimateWithIds<'a> {
    node_ids: &'a [u64],
    #[serde(with = "crate::so3::serde_rows::rotations")]
    rotations: &'a [Rotation],
}

/// The text of an estimate file for `path`: g2o ([`crate::io::g2o::write_g2o`]: the problem's
/// edges and the estimate as vertex lines) when `path` ends in `.g2o`, otherwise one JSON line
/// `{"node_ids": [...], "rotations": [R, ...]}` (`node_ids[k]` is the file id of node `k`).
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
