//! Structure-from-motion formats: 1DSfM `EGs.txt` view graphs, and ground truth as a Bundler
//! v0.3 file (`gt_bundle.out`) or a plain list of rotations.
//!
//! # Conventions (`paper-notes/formats.md`, `[F5]`..`[F7]`)
//!
//! * `EGs.txt` `[F5]`: one line `i j R11 R12 R13 R21 R22 R23 R31 R32 R33 [tx ty tz]`, `R`
//!   row-major. With world-to-camera rotations `C_i`, noise-free data satisfy `R = C_i C_j^T`.
//!   This crate's `R_i` is the world-to-camera rotation `C_i` and `R_ij R_i = R_j`, so
//!   **`R_ij = R^T = C_j C_i^T`** (then `R_ij C_i = C_j`). Camera ids are sparse (line numbers
//!   of `list.txt`): they are sorted and mapped to `0..n`, the map kept in
//!   [`LoadedGraph::node_ids`]. Weights are 1 (the format has none).
//! * Bundler `gt_bundle.out` `[F6]`: header `# Bundle file v0.3`, then `num_cameras
//!   num_points`, then per camera 5 lines `f k1 k2` / three rows of `R` / `t`, with `R`
//!   world-to-camera (`x_cam = R X + t`): that is this crate's `R_i` unchanged. A camera with
//!   an all-zero `R` was not reconstructed (`None`). Camera block `k` is file id `k`.
//! * Plain rotation list `[F7]`: one row-major 3x3 rotation (9 numbers) per line, line `k` (of
//!   the non-blank, non-`#` lines) being file id `k`, or `id R11 .. R33` lines (10 tokens),
//!   already in this crate's convention (`R_i`, world-to-camera); a rotation of 9 zeros means
//!   "no ground truth for this node" (`None`).
//!
//! Use [`truth_for_nodes`] to reorder ground truth indexed by file id onto a graph's nodes.

use crate::error::{Error, Result};
use crate::io::RawEdge;
use crate::io::detect::{GraphFormat, LoadedGraph, ReadOptions};
use crate::io::g2o::{EdgeLines, Tokens};
use crate::io::text::{MAX_RECORDS, TextLines};
use crate::so3::{Rotation, rotation_from_matrix};
use nalgebra::Matrix3;

fn read_matrix(t: &mut Tokens<'_>) -> Result<Matrix3<f64>> {
    let mut m = Matrix3::zeros();
    for r in 0..3 {
        for c in 0..3 {
            m[(r, c)] = t.next_f64(&format!("R{}{}", r + 1, c + 1))?;
        }
    }
    Ok(m)
}

fn to_rotation(t: &Tokens<'_>, m: &Matrix3<f64>, tol: f64, item: &str) -> Result<Rotation> {
    rotation_from_matrix(m, tol, item).map_err(|e| e.in_file(t.file, Some(t.line)))
}

/// Read a 1DSfM `EGs.txt` file `[F5]`.
///
/// ```
/// use rotavg::io::{sfm::read_egs, detect::ReadOptions};
/// // cameras 3 and 7; R = C_3 C_7^T with C_3 = I and C_7 = Rz(90 deg)^T
/// let text = "3 7  0 -1 0  1 0 0  0 0 1  1 0 0\n";
/// let g = read_egs(text, "EGs.txt", &ReadOptions::default()).unwrap();
/// assert_eq!(g.node_ids, vec![3, 7]);
/// let c7 = rotavg::Rotation::from_matrix_unchecked(nalgebra::Matrix3::new(0., -1., 0., 1., 0., 0., 0., 0., 1.)).inverse();
/// assert!(g.problem.chordal_cost(&[rotavg::Rotation::identity(), c7]) < 1e-20);
/// ```
pub fn read_egs(text: &str, file: &str, options: &ReadOptions) -> Result<LoadedGraph> {
    read_egs_lines(&mut TextLines::from_text(file, text), options)
}

/// Read a 1DSfM `EGs.txt` file line by line ([`read_egs`] on a stream): the text is never held
/// whole, memory grows with the edges kept (at most [`crate::io::text::MAX_RECORDS`]). Errors
/// name [`TextLines::name`] and the line.
///
/// ```
/// use rotavg::io::{sfm::read_egs_lines, detect::ReadOptions, text::TextStream};
/// let text = "0 1 1 0 0 0 1 0 0 0 1\n1 2 1 0 0 0 1 0 0 0 1\n";
/// let mut lines = TextStream::from_reader("EGs.txt", text.as_bytes(), u64::MAX, None)?.into_lines();
/// let g = read_egs_lines(&mut lines, &ReadOptions::default())?;
/// assert_eq!((g.problem.num_rotations(), g.problem.num_edges()), (3, 2));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_egs_lines(lines: &mut TextLines<'_>, options: &ReadOptions) -> Result<LoadedGraph> {
    read_egs_limited(lines, options, MAX_RECORDS)
}

fn read_egs_limited(
    lines: &mut TextLines<'_>,
    options: &ReadOptions,
    max_records: usize,
) -> Result<LoadedGraph> {
    let edges = EdgeLines::read(lines, "no edge lines in the EGs file", |t, edges| {
        t.expect_count(
            &[14, 11],
            "i j R11 R12 R13 R21 R22 R23 R31 R32 R33 [tx ty tz]",
        )?;
        let i = t.next_id("camera id i")?;
        let j = t.next_id("camera id j")?;
        let m = read_matrix(t)?;
        if t.toks.len() == 14 {
            for w in ["tx", "ty", "tz"] {
                t.next_f64(w)?;
            }
        }
        if i == j {
            return Err(t.err(format!("self loop: edge from camera {i} to itself")));
        }
        let item = format!("edge {} ({i}, {j})", edges.len());
        let r = to_rotation(t, &m, options.rotation_tolerance, &item)?;
        if edges.len() >= max_records {
            return Err(t.err(format!(
                "more than {max_records} edges, the limit of a view graph \
                 (rotavg::io::text::MAX_RECORDS)"
            )));
        }
        edges.push(
            t.line,
            RawEdge {
                i,
                j,
                rotation: r.inverse(), // R_ij = R^T [F5]
                weight: 1.0,
            },
        );
        Ok(())
    })?;
    edges.into_graph(std::iter::empty(), GraphFormat::OneDsfm)
}

fn is_zero(m: &Matrix3<f64>) -> bool {
    m.iter().all(|&x| x == 0.0)
}

/// Read a Bundler v0.3 file (e.g. 1DSfM's `gt_bundle.out`) as ground truth `[F6]`: entry `k`
/// is camera `k`'s world-to-camera rotation (this crate's `R_k`), `None` if not reconstructed.
/// Points after the cameras are ignored. No allocation is sized from the header.
///
/// ```
/// use rotavg::io::{sfm::read_bundler, detect::ReadOptions};
/// let text = "# Bundle file v0.3\n2 0\n500 0 0\n1 0 0\n0 1 0\n0 0 1\n0 0 0\n\
///             0 0 0\n0 0 0\n0 0 0\n0 0 0\n0 0 0\n";
/// let gt = read_bundler(text, "gt_bundle.out", &ReadOptions::default()).unwrap();
/// assert_eq!(gt.len(), 2);
/// assert!(gt[0].is_some() && gt[1].is_none());
/// ```
pub fn read_bundler(
    text: &str,
    file: &str,
    options: &ReadOptions,
) -> Result<Vec<Option<Rotation>>> {
    let mut lines = crate::io::content_lines(text);
    let (hl, header) = lines.next().ok_or_else(|| {
        Error::parse(
            Some(file),
            Some(1),
            "empty Bundler file (no `num_cameras num_points` line)",
        )
    })?;
    let mut t = Tokens::new(file, hl, header);
    t.expect_count(&[2], "num_cameras num_points")?;
    let num_cameras = t.next_id("num_cameras")?;
    t.next_id("num_points")?;
    let mut out = Vec::new();
    for cam in 0..num_cameras {
        let mut block: Vec<(usize, &str)> = Vec::with_capacity(5);
        for _ in 0..5 {
            match lines.next() {
                Some(l) => block.push(l),
                None => {
                    return Err(Error::parse(
                        Some(file),
                        Some(text.lines().count().max(1)),
                        format!(
                            "truncated: the header announces {num_cameras} cameras, the file ends inside camera {cam}"
                        ),
                    ));
                }
            }
        }
        let t = Tokens::new(file, block[0].0, block[0].1);
        t.expect_count(&[3], "f k1 k2")?;
        let mut m = Matrix3::zeros();
        for r in 0..3 {
            let mut t = Tokens::new(file, block[1 + r].0, block[1 + r].1);
            t.expect_count(&[3], "a row of R")?;
            for c in 0..3 {
                m[(r, c)] = t.next_f64("R entry")?;
            }
        }
        let mut tt = Tokens::new(file, block[4].0, block[4].1);
        tt.expect_count(&[3], "t")?;
        for w in ["tx", "ty", "tz"] {
            tt.next_f64(w)?;
        }
        if is_zero(&m) {
            out.push(None);
        } else {
            let t = Tokens::new(file, block[1].0, block[1].1);
            out.push(Some(to_rotation(
                &t,
                &m,
                options.rotation_tolerance,
                &format!("camera {cam}"),
            )?));
        }
    }
    Ok(out)
}

/// Read a plain rotation list `[F7]`: one row-major rotation per line, either 9 numbers
/// (line `k` is file id `k`) or `id R11 .. R33` (10 tokens: the file id first, the layout many
/// rotation-averaging tools write, world-to-camera = this crate's `R_i`); 9 zeros mean
/// "unknown" (`None`), and so does an id no line names. All lines use the same layout; ids are
/// unique and at most `16 x lines + 1024` (so a stray large id cannot allocate without bound).
///
/// ```
/// use rotavg::io::{sfm::read_rotation_list, detect::ReadOptions};
/// let gt = read_rotation_list("1 0 0 0 1 0 0 0 1\n0 0 0 0 0 0 0 0 0\n", "gt.txt", &ReadOptions::default()).unwrap();
/// assert_eq!(gt.len(), 2);
/// // with ids: file ids 3 and 1 known, 0 and 2 not
/// let gt = read_rotation_list("3 1 0 0 0 1 0 0 0 1\n1 1 0 0 0 1 0 0 0 1\n", "gt.txt", &ReadOptions::default()).unwrap();
/// assert_eq!(gt.iter().map(Option::is_some).collect::<Vec<_>>(), [false, true, false, true]);
/// ```
pub fn read_rotation_list(
    text: &str,
    file: &str,
    options: &ReadOptions,
) -> Result<Vec<Option<Rotation>>> {
    let lines: Vec<(usize, &str)> = crate::io::content_lines(text).collect();
    let Some(&(first_line, first)) = lines.first() else {
        return Err(Error::parse(Some(file), None, "no rotations in the file"));
    };
    let with_ids = first.split_whitespace().count() == 10;
    let max_id = 16 * lines.len() as u64 + 1024;
    let mut out: Vec<Option<Rotation>> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for &(ln, trimmed) in &lines {
        let mut t = Tokens::new(file, ln, trimmed);
        let id = if with_ids {
            t.expect_count(
                &[10],
                &format!("id R11 R12 R13 R21 R22 R23 R31 R32 R33, as on line {first_line}"),
            )?;
            let id = t.next_id("id")?;
            if id > max_id {
                return Err(t.err(format!(
                    "id {id} is larger than {max_id} (16 x the number of lines + 1024)"
                )));
            }
            if !seen.insert(id) {
                return Err(t.err(format!("id {id} appears twice")));
            }
            id as usize
        } else {
            t.expect_count(
                &[9],
                "R11 R12 R13 R21 R22 R23 R31 R32 R33, as on the first line",
            )?;
            out.len()
        };
        let m = read_matrix(&mut t)?;
        let rotation = if is_zero(&m) {
            None
        } else {
            Some(to_rotation(
                &t,
                &m,
                options.rotation_tolerance,
                &format!("rotation {id}"),
            )?)
        };
        if out.len() <= id {
            out.resize(id + 1, None);
        }
        out[id] = rotation;
    }
    Ok(out)
}

/// Ground truth indexed by file id, reordered onto a graph's nodes: entry `k` is the truth of
/// node `k` (file id `node_ids[k]`), `None` when the file has none for it.
///
/// ```
/// use rotavg::io::sfm::truth_for_nodes;
/// use rotavg::Rotation;
/// // Truth known for file ids 0 and 2; the graph's nodes are file ids 2 and 1.
/// let truth = vec![Some(Rotation::identity()), None, Some(Rotation::identity())];
/// let per_node = truth_for_nodes(&truth, &[2, 1]);
/// assert!(per_node[0].is_some() && per_node[1].is_none());
/// ```
pub fn truth_for_nodes(
    truth_by_id: &[Option<Rotation>],
    node_ids: &[u64],
) -> Vec<Option<Rotation>> {
    node_ids
        .iter()
        .map(|&id| {
            usize::try_from(id)
                .ok()
                .and_then(|k| truth_by_id.get(k).copied().flatten())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::text::check_record_limit;

    #[test]
    fn record_limit() {
        let text = "0 1 1 0 0 0 1 0 0 0 1\n# c\n1 2 1 0 0 0 1 0 0 0 1\n";
        check_record_limit(text, 2, "t:3: more than 1 edges", |lines, max| {
            read_egs_limited(lines, &ReadOptions::default(), max)
        });
    }
}
