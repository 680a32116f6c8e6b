//! g2o / TORO pose graphs read as rotation-averaging problems, and a g2o writer.
//!
//! # Conventions (`paper-notes/formats.md`, `[F1]`..`[F4]`)
//!
//! A g2o vertex pose `T_i = (W_i, t_i)` maps body-i coordinates to world coordinates
//! (`W_i` is world-from-body), and an edge measures `T_i^{-1} T_j`, so its rotation is
//! `Z_ij = W_i^T W_j` `[F1]`. This crate's convention is `R_ij R_i = R_j` (contract section 1), so we
//! set **`R_i = W_i^T`** (world-to-body) and **`R_ij = Z_ij^T`**: then
//! `R_ij R_i = Z_ij^T W_i^T = (W_i Z_ij)^T = W_j^T = R_j`, and the chordal cost
//! `||R_j - R_ij R_i||_F = ||W_j - W_i Z_ij||_F` is SE-Sync's and GTSAM's rotation term.
//! The test `io_shared_data::mrob_sphere_gt_vertex_cost_is_tiny` checks this on a file whose
//! vertex lines are the ground truth, and that the opposite convention gives a large cost.
//!
//! Line types (tokens separated by any whitespace; empty lines and `#` comments skipped):
//!
//! * `VERTEX_SE3:QUAT id x y z qx qy qz qw` and `EDGE_SE3:QUAT i j x y z qx qy qz qw I(21)`:
//!   Hamilton quaternion, **scalar last**, normalised on read (it must be unit within
//!   [`ReadOptions::quaternion_tolerance`]). The 21 numbers are the upper triangle, row by row,
//!   of the 6x6 information matrix, translation block first. Weight (SE-Sync) `[F3]`:
//!   `kappa = 3 / (2 tr(Omega_rot^{-1}))` from the 3x3 rotation block, which must be finite and
//!   positive definite. An edge without the 21 numbers gets weight 1.
//! * `VERTEX3 id x y z roll pitch yaw`, `EDGE3 i j x y z roll pitch yaw [I(21)]` (TORO / GTSAM):
//!   `Z = Rz(yaw) Ry(pitch) Rx(roll)` `[F2]`. Without information (9 tokens): weight 1. With it:
//!   `kappa = 6 / tr(Omega_rot^{-1})` `[F3]`, because EDGE3 information is in rotation-angle
//!   units while g2o's is in quaternion-vector (half-angle) units (`Omega_g2o = 4 Omega_EDGE3`),
//!   so this is SE-Sync's rule applied to the equivalent g2o information. On sphere2500 the
//!   two files then give the same weights to 1 % (test `edge3_and_g2o_weights_agree`).
//! * `VERTEX_SE2 id x y theta`, `EDGE_SE2 i j dx dy dtheta I11 I12 I13 I22 I23 I33`: a rotation
//!   by `theta` about z `[F4]`; weight `kappa = I33` (SE-Sync's 2-D rule), `I33 > 0` required.
//! * Any other tag (`FIX`, `VERTEX_XY`, ...) is skipped and counted in a warning.
//! * With [`WeightSource::File`], a weight outside [`crate::io::MIN_WEIGHT`,
//!   `crate::io::MAX_WEIGHT`] is an error (the solvers' squared sums would overflow).
//!
//! Node ids may be sparse: they are sorted and mapped to `0..n` ([`LoadedGraph::node_ids`]).
//! Edges with `i > j` and multi-edges are kept as given.

use crate::error::{Error, Result};
use crate::io::detect::{GraphFormat, LoadedGraph, ReadOptions, WeightSource};
use crate::io::text::{MAX_RECORDS, TextLines};
use crate::io::{RawEdge, compact_edges};
use crate::multiple::MultipleProblem;
use crate::multiple::anisotropic::Information;
use crate::so3::Rotation;
use crate::warning::Warning;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Tokens of one line, with the file and line for error messages.
pub(crate) struct Tokens<'a> {
    pub(crate) file: &'a str,
    pub(crate) line: usize,
    pub(crate) toks: Vec<&'a str>,
    pos: usize,
}

impl<'a> Tokens<'a> {
    pub(crate) fn new(file: &'a str, line: usize, text: &'a str) -> Self {
        Tokens {
            file,
            line,
            toks: text.split_whitespace().collect(),
            pos: 0,
        }
    }

    pub(crate) fn err(&self, msg: impl Into<String>) -> Error {
        Error::parse(Some(self.file), Some(self.line), msg)
    }

    pub(crate) fn next_str(&mut self, what: &str) -> Result<&'a str> {
        let t = self
            .toks
            .get(self.pos)
            .copied()
            .ok_or_else(|| self.err(format!("missing {what}")))?;
        self.pos += 1;
        Ok(t)
    }

    pub(crate) fn next_f64(&mut self, what: &str) -> Result<f64> {
        let t = self.next_str(what)?;
        let v: f64 = t
            .parse()
            .map_err(|_| self.err(format!("{what}: `{t}` is not a number")))?;
        if !v.is_finite() {
            return Err(self.err(format!("{what}: `{t}` is not finite")));
        }
        Ok(v)
    }

    pub(crate) fn next_id(&mut self, what: &str) -> Result<u64> {
        let t = self.next_str(what)?;
        t.parse()
            .map_err(|_| self.err(format!("{what}: `{t}` is not a non-negative integer id")))
    }

    pub(crate) fn expect_count(&self, allowed: &[usize], layout: &str) -> Result<()> {
        if allowed.contains(&self.toks.len()) {
            Ok(())
        } else {
            Err(self.err(format!(
                "expected {} tokens ({layout}), found {}",
                allowed
                    .iter()
                    .map(|k| k.to_string())
                    .collect::<Vec<_>>()
                    .join(" or "),
                self.toks.len()
            )))
        }
    }
}

/// The edges a line-by-line graph reader (g2o, 1DSfM `EGs.txt`) keeps, in file order, with what
/// its graph needs beyond them: the file's name and the line of the first edge (the problem's
/// errors name them), and the number of edges given with `i > j`.
pub(crate) struct EdgeLines {
    file: String,
    raw: Vec<RawEdge>,
    first_line: Option<usize>,
    reversed: usize,
}

impl EdgeLines {
    /// Read every content line of `lines` with `read_line`, which gets the line's tokens
    /// (errors name the file and the line) and the edges kept so far. A file without edges is
    /// the error `no_edges`, at its last line.
    pub(crate) fn read(
        lines: &mut TextLines<'_>,
        no_edges: &str,
        mut read_line: impl FnMut(&mut Tokens<'_>, &mut EdgeLines) -> Result<()>,
    ) -> Result<Self> {
        // the tokens borrow the name while `lines` moves on, so they get their own copy
        let file = lines.name().to_owned();
        let mut edges = EdgeLines {
            file: file.clone(),
            raw: Vec::new(),
            first_line: None,
            reversed: 0,
        };
        while let Some((ln, trimmed)) = lines.next_content()? {
            read_line(&mut Tokens::new(&file, ln, trimmed), &mut edges)?;
        }
        if edges.raw.is_empty() {
            let last = lines.lines_read().max(1);
            return Err(Error::parse(Some(&file), Some(last), no_edges));
        }
        Ok(edges)
    }

    /// The number of edges kept.
    pub(crate) fn len(&self) -> usize {
        self.raw.len()
    }

    /// Keep `edge`, read on line `line`.
    pub(crate) fn push(&mut self, line: usize, edge: RawEdge) {
        self.first_line.get_or_insert(line);
        self.reversed += usize::from(edge.i > edge.j);
        self.raw.push(edge);
    }

    /// The graph of the edges, its nodes the file ids of `vertex_ids` and of the edges'
    /// endpoints ([`compact_edges`]). It has no initial estimate, node names or warnings and is
    /// not planar: the reader sets what its format has.
    pub(crate) fn into_graph(
        self,
        vertex_ids: impl Iterator<Item = u64>,
        format: GraphFormat,
    ) -> Result<LoadedGraph> {
        let (ids, edges) = compact_edges(self.raw, vertex_ids);
        let problem = MultipleProblem::new(ids.len(), edges)
            .map_err(|e| e.in_file(&self.file, self.first_line))?;
        let duplicates = crate::multiple::stats::duplicate_edge_count(&problem);
        Ok(LoadedGraph {
            problem,
            node_ids: ids,
            node_names: Vec::new(),
            initial: None,
            duplicates,
            reversed: self.reversed,
            warnings: Vec::new(),
            format,
            planar: false,
            read: ReadOptions::default(),
        })
    }
}

/// Rotation of a g2o quaternion given scalar last, normalised; rejected if not unit within
/// `tol` (a zero quaternion is always rejected).
fn quaternion_rotation(t: &mut Tokens<'_>, tol: f64) -> Result<Rotation> {
    let x = t.next_f64("qx")?;
    let y = t.next_f64("qy")?;
    let z = t.next_f64("qz")?;
    let w = t.next_f64("qw")?;
    let q = Quaternion::new(w, x, y, z);
    let norm = q.norm();
    if !(norm > 1e-12 && (norm - 1.0).abs() <= tol) {
        return Err(t.err(format!(
            "quaternion (qx qy qz qw) = ({x} {y} {z} {w}) has norm {norm:.3e}, not 1 within {tol:.1e}"
        )));
    }
    Ok(UnitQuaternion::from_quaternion(q).to_rotation_matrix())
}

/// `Rz(yaw) Ry(pitch) Rx(roll)` `[F2]`.
///
/// ```
/// use rotavg::io::g2o::rotation_from_ypr;
/// use nalgebra::Vector3;
/// // Yaw alone turns x towards y; roll alone turns y towards z.
/// assert!((rotation_from_ypr(std::f64::consts::FRAC_PI_2, 0.0, 0.0) * Vector3::x() - Vector3::y()).norm() < 1e-15);
/// assert!((rotation_from_ypr(0.0, 0.0, std::f64::consts::FRAC_PI_2) * Vector3::y() - Vector3::z()).norm() < 1e-15);
/// ```
pub fn rotation_from_ypr(yaw: f64, pitch: f64, roll: f64) -> Rotation {
    Rotation::from_axis_angle(&Vector3::z_axis(), yaw)
        * Rotation::from_axis_angle(&Vector3::y_axis(), pitch)
        * Rotation::from_axis_angle(&Vector3::x_axis(), roll)
}

/// Read the 21 upper-triangular entries of a 6x6 information matrix and return the rotation
/// block (rows/columns 3..6), validated finite and positive definite, and `tr(block^{-1})`.
/// The rotation block `Omega_rot` (rows/columns 4..6) of the 21 information entries, checked
/// positive definite, and `tr(Omega_rot^-1)` `[F3]`.
fn rotation_information(t: &mut Tokens<'_>) -> Result<(Matrix3<f64>, f64)> {
    let mut info = nalgebra::Matrix6::<f64>::zeros();
    for r in 0..6 {
        for c in r..6 {
            let v = t.next_f64(&format!("information entry ({}, {})", r + 1, c + 1))?;
            info[(r, c)] = v;
            info[(c, r)] = v;
        }
    }
    let block: Matrix3<f64> = info.fixed_view::<3, 3>(3, 3).into_owned();
    let chol = block.cholesky().ok_or_else(|| {
        t.err(format!(
            "the rotation block of the information matrix is not positive definite: {:?}",
            (0..3)
                .map(|r| [block[(r, 0)], block[(r, 1)], block[(r, 2)]])
                .collect::<Vec<_>>()
        ))
    })?;
    let tr = chol.inverse().trace();
    if !(tr.is_finite() && tr > 0.0) {
        return Err(t.err(format!(
            "the rotation block of the information matrix is numerically singular (tr(Omega^-1) = {tr:e})"
        )));
    }
    Ok((block, tr))
}

/// The anisotropic information `H = R_ij^T (scale Omega_rot) R_ij` of an edge `[A7]`
/// (`scale` 1/2 for g2o's half-angle quaternion error, 2 for TORO's angle units), symmetrised
/// exactly (a product of the file's numbers, not the file's numbers themselves). An isotropic
/// block `w I` gives `scale w I` exactly: every rotation leaves it unchanged, and the product
/// would only add rounding (anisotropy `1 + 4e-16` on mrob's sphere), which turned the scalar
/// weights the file states into anisotropic information (contract section 1: `H = w I` is the
/// isotropic cost).
fn edge_information(r_ij: &Rotation, omega: &Matrix3<f64>, scale: f64) -> Matrix3<f64> {
    let scaled = omega * scale;
    if crate::multiple::anisotropic::exactly_isotropic(&scaled).is_some() {
        return scaled;
    }
    let h = r_ij.matrix().transpose() * scaled * r_ij.matrix();
    (h + h.transpose()) * 0.5
}

/// The pose type of a g2o vertex line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VertexKind {
    /// `VERTEX_SE3:QUAT id x y z qx qy qz qw`.
    Se3Quat,
    /// `VERTEX3 id x y z roll pitch yaw` (TORO).
    Vertex3,
    /// `VERTEX_SE2 id x y theta`.
    Se2,
}

/// One vertex line of a g2o / TORO file.
#[derive(Debug, Clone, PartialEq)]
pub struct G2oVertex {
    /// The vertex id.
    pub id: u64,
    /// This crate's `R_i = W_i^T` (world-to-body) `[F1]`.
    pub rotation: Rotation,
    /// The vertex translation `x y z` (`z = 0` for `VERTEX_SE2`).
    pub translation: [f64; 3],
    /// The line's pose type.
    pub kind: VertexKind,
    /// The 1-based line number.
    pub line: usize,
}

/// Parse the tokens after the tag of a vertex line (`VERTEX_SE3:QUAT`, `VERTEX3`,
/// `VERTEX_SE2`); the one parser of vertex lines ([`read_g2o`], [`read_g2o_vertices`]).
fn parse_vertex(tag: &str, t: &mut Tokens<'_>, qtol: f64) -> Result<G2oVertex> {
    let line = t.line;
    let (kind, id, translation, rotation) = match tag {
        "VERTEX_SE3:QUAT" => {
            t.expect_count(&[9], "VERTEX_SE3:QUAT id x y z qx qy qz qw")?;
            let id = t.next_id("vertex id")?;
            let xyz = [t.next_f64("x")?, t.next_f64("y")?, t.next_f64("z")?];
            let wi = quaternion_rotation(t, qtol)?;
            (VertexKind::Se3Quat, id, xyz, wi.inverse()) // R_i = W_i^T [F1]
        }
        "VERTEX3" => {
            t.expect_count(&[8], "VERTEX3 id x y z roll pitch yaw")?;
            let id = t.next_id("vertex id")?;
            let xyz = [t.next_f64("x")?, t.next_f64("y")?, t.next_f64("z")?];
            let roll = t.next_f64("roll")?;
            let pitch = t.next_f64("pitch")?;
            let yaw = t.next_f64("yaw")?;
            let r = rotation_from_ypr(yaw, pitch, roll).inverse();
            (VertexKind::Vertex3, id, xyz, r)
        }
        "VERTEX_SE2" => {
            t.expect_count(&[5], "VERTEX_SE2 id x y theta")?;
            let id = t.next_id("vertex id")?;
            let xy = [t.next_f64("x")?, t.next_f64("y")?, 0.0];
            let th = t.next_f64("theta")?;
            let r = Rotation::from_axis_angle(&Vector3::z_axis(), -th);
            (VertexKind::Se2, id, xy, r)
        }
        other => return Err(t.err(format!("`{other}` is not a vertex tag"))),
    };
    Ok(G2oVertex {
        id,
        rotation,
        translation,
        kind,
        line,
    })
}

/// The vertex lines of a g2o / TORO file (`VERTEX_SE3:QUAT`, `VERTEX3`, `VERTEX_SE2`), in file
/// order, as an estimate: `R_i = W_i^T` `[F1]`. Edge lines and other tags are skipped (a file
/// with vertices only, as some tools write an estimate, is fine); a file without vertex lines,
/// a vertex defined twice or a quaternion that is not a unit one within
/// [`ReadOptions::quaternion_tolerance`] is an error naming the file and line. At most
/// [`MAX_RECORDS`] vertices.
///
/// ```
/// use rotavg::io::{g2o::read_g2o_vertices, detect::ReadOptions};
/// let text = "VERTEX_SE3:QUAT 7 1 2 3 0 0 0.70710678118 0.70710678118\nEDGE3 0 1 0 0 0 0 0 0.1\n";
/// let v = read_g2o_vertices(text, "est.g2o", &ReadOptions::default())?;
/// assert_eq!((v[0].id, v[0].translation, v[0].line), (7, [1.0, 2.0, 3.0], 1));
/// let err = read_g2o_vertices("VERTEX_SE3:QUAT 7 0 0 0 0 0 0 2\n", "est.g2o", &ReadOptions::default());
/// assert!(err.unwrap_err().to_string().starts_with("est.g2o:1: quaternion"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_g2o_vertices(text: &str, file: &str, options: &ReadOptions) -> Result<Vec<G2oVertex>> {
    read_g2o_vertices_lines(&mut TextLines::from_text(file, text), options)
}

/// [`read_g2o_vertices`] line by line (a file or standard input never held whole).
pub fn read_g2o_vertices_lines(
    lines: &mut TextLines<'_>,
    options: &ReadOptions,
) -> Result<Vec<G2oVertex>> {
    let file = lines.name().to_owned();
    let file = file.as_str();
    let mut out: Vec<G2oVertex> = Vec::new();
    let mut seen: BTreeMap<u64, usize> = BTreeMap::new();
    while let Some((ln, line)) = lines.next_content()? {
        let mut t = Tokens::new(file, ln, line);
        let tag = t.next_str("tag")?;
        if !matches!(tag, "VERTEX_SE3:QUAT" | "VERTEX3" | "VERTEX_SE2") {
            continue;
        }
        if out.len() >= MAX_RECORDS {
            return Err(t.err(format!(
                "more than {MAX_RECORDS} vertices (rotavg::io::text::MAX_RECORDS)"
            )));
        }
        let v = parse_vertex(tag, &mut t, options.quaternion_tolerance)?;
        if let Some(first) = seen.insert(v.id, ln) {
            return Err(t.err(format!(
                "vertex {} defined twice (first at line {first})",
                v.id
            )));
        }
        out.push(v);
    }
    if out.is_empty() {
        return Err(Error::parse(
            Some(file),
            Some(lines.lines_read().max(1)),
            "no vertex lines (VERTEX_SE3:QUAT, VERTEX3 or VERTEX_SE2): a g2o estimate holds one \
             vertex per node",
        ));
    }
    Ok(out)
}

/// Read a g2o / TORO file (see the module documentation for the conventions).
///
/// ```
/// use rotavg::io::{g2o::read_g2o, detect::ReadOptions};
/// // Two poses, the second rotated by 90 deg about z (W_1), one edge measuring Z_01 = W_1.
/// let text = "VERTEX_SE3:QUAT 0 0 0 0 0 0 0 1\n\
///             VERTEX_SE3:QUAT 1 1 0 0 0 0 0.70710678118 0.70710678118\n\
///             EDGE_SE3:QUAT 0 1 1 0 0 0 0 0.70710678118 0.70710678118 \
///             1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 2 0 0 2 0 2\n";
/// let g = read_g2o(text, "t.g2o", &ReadOptions::default()).unwrap();
/// let init = g.initial.unwrap();
/// assert!(g.problem.chordal_cost(&init) < 1e-12);
/// assert!((g.problem.edges()[0].weight - 1.0).abs() < 1e-12); // kappa = 3 / (2 * 3/2)
/// ```
pub fn read_g2o(text: &str, file: &str, options: &ReadOptions) -> Result<LoadedGraph> {
    read_g2o_lines(&mut TextLines::from_text(file, text), options)
}

/// Read a g2o / TORO file line by line ([`read_g2o`] on a stream): the text is never held
/// whole, memory grows with the edges and vertices kept (at most
/// [`crate::io::text::MAX_RECORDS`]). Errors name [`TextLines::name`] and the line.
///
/// ```
/// use rotavg::io::{g2o::read_g2o_lines, detect::ReadOptions, text::TextStream};
/// let text = "EDGE3 0 1 0 0 0 0 0 0.1\nEDGE3 1 2 0 0 0 0 0 0.2\n";
/// let mut lines = TextStream::from_reader("t.g2o", text.as_bytes(), u64::MAX, None)?.into_lines();
/// let g = read_g2o_lines(&mut lines, &ReadOptions::default())?;
/// assert_eq!((g.problem.num_rotations(), g.problem.num_edges()), (3, 2));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_g2o_lines(lines: &mut TextLines<'_>, options: &ReadOptions) -> Result<LoadedGraph> {
    read_g2o_limited(lines, options, MAX_RECORDS)
}

/// The most distinct unknown tags counted by name in the warnings (the others are counted
/// together), and the characters of a tag kept.
const MAX_SKIPPED_TAGS: usize = 32;
const MAX_TAG_CHARS: usize = 64;

/// An edge line as parsed: `R_ij`, SE-Sync's weight (`[F3]`, `[F4]`; 1 without an
/// information matrix) and the rotation information `H` (`[A7]`).
struct ParsedEdge {
    i: u64,
    j: u64,
    rotation: Rotation,
    weight: f64,
    information: Matrix3<f64>,
    /// Whether the line gave an information matrix (else `weight` 1, `information` I).
    informed: bool,
}

/// A 3-D edge (the tag read): `EDGE_SE3:QUAT i j x y z qx qy qz qw [+ 21 information
/// entries]` when `quaternion`, else TORO's `EDGE3 i j x y z roll pitch yaw [+ 21 ...]`.
fn parse_edge_3d(t: &mut Tokens<'_>, quaternion: bool, qtol: f64) -> Result<ParsedEdge> {
    let full = if quaternion {
        t.expect_count(
            &[31, 10],
            "EDGE_SE3:QUAT i j x y z qx qy qz qw + 21 information entries",
        )?;
        31
    } else {
        t.expect_count(
            &[9, 30],
            "EDGE3 i j x y z roll pitch yaw [+ 21 information entries]",
        )?;
        30
    };
    let i = t.next_id("edge id i")?;
    let j = t.next_id("edge id j")?;
    for w in ["x", "y", "z"] {
        t.next_f64(w)?;
    }
    let rotation = if quaternion {
        quaternion_rotation(t, qtol)?.inverse() // R_ij = Z_ij^T [F1]
    } else {
        let roll = t.next_f64("roll")?;
        let pitch = t.next_f64("pitch")?;
        let yaw = t.next_f64("yaw")?;
        rotation_from_ypr(yaw, pitch, roll).inverse()
    };
    let (weight, information) = if t.toks.len() != full {
        (1.0, Matrix3::identity())
    } else if quaternion {
        let (omega, tr) = rotation_information(t)?;
        // [F3] kappa; [A7] H = R_ij^T (Omega / 2) R_ij (kappa I when isotropic)
        (3.0 / (2.0 * tr), edge_information(&rotation, &omega, 0.5))
    } else {
        let (omega, tr) = rotation_information(t)?;
        // [F3], angle units: kappa = 6 / tr; [A7] H = R_ij^T (2 Omega) R_ij
        (6.0 / tr, edge_information(&rotation, &omega, 2.0))
    };
    Ok(ParsedEdge {
        i,
        j,
        rotation,
        weight,
        information,
        informed: t.toks.len() == full,
    })
}

/// `EDGE_SE2 i j dx dy dtheta [I11 I12 I13 I22 I23 I33]` (the tag read).
fn parse_edge_se2(t: &mut Tokens<'_>) -> Result<ParsedEdge> {
    t.expect_count(
        &[12, 6],
        "EDGE_SE2 i j dx dy dtheta I11 I12 I13 I22 I23 I33",
    )?;
    let i = t.next_id("edge id i")?;
    let j = t.next_id("edge id j")?;
    t.next_f64("dx")?;
    t.next_f64("dy")?;
    let th = t.next_f64("dtheta")?;
    let informed = t.toks.len() == 12;
    let weight = if informed {
        let mut info = [0.0; 6];
        for (n, v) in info.iter_mut().enumerate() {
            *v = t.next_f64(&format!("information entry {}", n + 1))?;
        }
        if info[5] <= 0.0 {
            return Err(t.err(format!(
                "the rotation information I33 = {} must be > 0",
                info[5]
            )));
        }
        info[5] // [F4] SE-Sync's 2-D kappa; [A7] H = I33 I
    } else {
        1.0
    };
    Ok(ParsedEdge {
        i,
        j,
        // Z = Rz(dtheta), R_ij = Z^T = Rz(-dtheta) [F1], [F4]
        rotation: Rotation::from_axis_angle(&Vector3::z_axis(), -th),
        weight,
        information: Matrix3::identity() * weight,
        informed,
    })
}

/// What a g2o file holds besides its edges, gathered line by line.
#[derive(Default)]
struct G2oContents {
    /// Each vertex's rotation and line.
    vertices: BTreeMap<u64, (Rotation, usize)>,
    /// Lines with an unknown tag: count and first line, by tag (at most
    /// [`MAX_SKIPPED_TAGS`]), and of the other tags together.
    skipped: BTreeMap<String, (usize, usize)>,
    skipped_other: (usize, usize),
    /// Edge lines without an information matrix under `--weights file`: count and first line.
    uninformed: (usize, usize),
    seen_3d: bool,
    seen_2d: bool,
    /// [A7]: each kept edge's full rotation information, in edge order (used with
    /// `options.full_information`).
    infos: Vec<Information>,
}

impl G2oContents {
    /// Count a line with the unknown tag `tag` at line `ln`.
    fn skip(&mut self, tag: &str, ln: usize) {
        let tag = match tag.char_indices().nth(MAX_TAG_CHARS) {
            Some((k, _)) => &tag[..k],
            None => tag,
        };
        let e = if let Some(e) = self.skipped.get_mut(tag) {
            e
        } else if self.skipped.len() < MAX_SKIPPED_TAGS {
            self.skipped.entry(tag.to_owned()).or_insert((0, ln))
        } else {
            if self.skipped_other.0 == 0 {
                self.skipped_other.1 = ln;
            }
            &mut self.skipped_other
        };
        e.0 += 1;
    }

    /// Keep the vertex `id` with rotation `r` (an error if it was defined before).
    fn vertex(&mut self, t: &Tokens<'_>, id: u64, r: Rotation) -> Result<()> {
        if let Some((_, first)) = self.vertices.get(&id) {
            return Err(t.err(format!("vertex {id} defined twice (first at line {first})")));
        }
        self.vertices.insert(id, (r, t.line));
        Ok(())
    }

    /// The edge `e` checked and weighted as `options` say (its information kept with
    /// `options.full_information`).
    fn edge(&mut self, t: &Tokens<'_>, e: ParsedEdge, options: &ReadOptions) -> Result<RawEdge> {
        let ParsedEdge { i, j, weight, .. } = e;
        if i == j {
            return Err(t.err(format!("self loop: edge from node {i} to itself")));
        }
        if !(weight.is_finite() && weight > 0.0) {
            return Err(t.err(format!("edge weight {weight:e} is not finite and > 0")));
        }
        if options.weights == WeightSource::File
            && let Some(why) = crate::io::weight_out_of_range(weight)
        {
            return Err(t.err(format!("edge {why}")));
        }
        let weight = match options.weights {
            WeightSource::File => weight,
            WeightSource::Unit => 1.0,
        };
        if !e.informed && options.weights == WeightSource::File {
            if self.uninformed.0 == 0 {
                self.uninformed.1 = t.line;
            }
            self.uninformed.0 += 1;
        }
        if options.full_information == Some(true) && options.weights == WeightSource::File {
            // checked here, so that an error names this line
            let h = Information::new(e.information).map_err(|e| t.err(format!("edge {e}")))?;
            self.infos.push(h);
        }
        Ok(RawEdge {
            i,
            j,
            rotation: e.rotation,
            weight,
        })
    }

    /// The reader's remarks: lines skipped by tag, 2-D and 3-D lines mixed.
    fn warnings(&self) -> Vec<Warning> {
        let mut warnings = Vec::new();
        for (tag, (count, first)) in &self.skipped {
            let message =
                format!("skipped {count} line(s) with unknown tag `{tag}` (first at line {first})");
            warnings.push(Warning::new("skipped_lines", message).with_count(*count));
        }
        if self.skipped_other.0 > 0 {
            let message = format!(
                "skipped {} line(s) with {MAX_SKIPPED_TAGS}+ other unknown tags (first at line {})",
                self.skipped_other.0, self.skipped_other.1
            );
            warnings.push(Warning::new("skipped_lines", message).with_count(self.skipped_other.0));
        }
        if self.uninformed.0 > 0 {
            let message = format!(
                "{} edge line(s) carry no information matrix (first at line {}): weight 1 \
                 (identity information)",
                self.uninformed.0, self.uninformed.1
            );
            warnings
                .push(Warning::new("without_information", message).with_count(self.uninformed.0));
        }
        if self.seen_2d && self.seen_3d {
            warnings.push(Warning::new(
                "mixed_dimensions",
                "the file mixes 2-D and 3-D lines",
            ));
        }
        warnings
    }
}

fn read_g2o_limited(
    lines: &mut TextLines<'_>,
    options: &ReadOptions,
    max_records: usize,
) -> Result<LoadedGraph> {
    let qtol = options.quaternion_tolerance;
    let mut c = G2oContents::default();
    let no_edges = "no edge lines (EDGE_SE3:QUAT, EDGE3 or EDGE_SE2) in the file";
    let name = lines.name().to_owned();
    let edges = EdgeLines::read(lines, no_edges, |t, edges| {
        let tag = t.next_str("tag")?;
        let (vertex, edge) = match tag {
            "VERTEX_SE3:QUAT" | "VERTEX3" | "VERTEX_SE2" => {
                let v = parse_vertex(tag, t, qtol)?;
                c.seen_3d |= v.kind != VertexKind::Se2;
                c.seen_2d |= v.kind == VertexKind::Se2;
                (Some((v.id, v.rotation)), None)
            }
            "EDGE_SE3:QUAT" | "EDGE3" => {
                c.seen_3d = true;
                (None, Some(parse_edge_3d(t, tag == "EDGE_SE3:QUAT", qtol)?))
            }
            "EDGE_SE2" => {
                c.seen_2d = true;
                (None, Some(parse_edge_se2(t)?))
            }
            other => {
                c.skip(other, t.line);
                return Ok(());
            }
        };
        if edges.len() + c.vertices.len() >= max_records {
            return Err(t.err(format!(
                "more than {max_records} edges and vertices, the limit of a view graph \
                 (rotavg::io::text::MAX_RECORDS)"
            )));
        }
        if let Some((id, r)) = vertex {
            c.vertex(t, id, r)?;
        }
        if let Some(e) = edge {
            let raw = c.edge(t, e, options)?;
            edges.push(t.line, raw);
        }
        Ok(())
    })?;
    let mut warnings = c.warnings();
    let mut graph = edges.into_graph(c.vertices.keys().copied(), GraphFormat::G2o)?;
    if !c.infos.is_empty() {
        graph.problem = graph
            .problem
            .with_information(c.infos)
            .map_err(|e| e.in_file(&name, None))?;
    }
    let initial = if c.vertices.is_empty() {
        None
    } else if c.vertices.len() == graph.node_ids.len() {
        Some(c.vertices.values().map(|(r, _)| *r).collect())
    } else {
        let missing = graph.node_ids.len() - c.vertices.len();
        let message = format!(
            "{missing} of {} nodes have no vertex line: no initial estimate",
            graph.node_ids.len()
        );
        warnings.push(Warning::new("no_initial_estimate", message).with_count(missing));
        None
    };
    Ok(LoadedGraph {
        initial,
        warnings,
        planar: c.seen_2d && !c.seen_3d,
        ..graph
    })
}

/// Write a problem (and optionally an estimate `R_i`, as vertex lines) in g2o 3-D format with
/// zero translations. Inverse of [`read_g2o`] `[F1]`, `[F3]`: vertex `W_i = R_i^T`, edge
/// `Z_ij = R_ij^T`, and the information matrix `diag(1, 1, 1, 2w, 2w, 2w)`, for which SE-Sync's
/// rule gives back `kappa = 3 / (2 * 3 / (2w)) = w`. Node ids are `0..n`. Numbers use Rust's
/// shortest round-trip formatting.
///
/// ```
/// use rotavg::io::{g2o::{read_g2o, write_g2o}, detect::ReadOptions};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, gt) = SyntheticGraph { num_rotations: 5, num_edges: 8, ..Default::default() }.generate();
/// let text = write_g2o(&p, Some(&gt));
/// let g = read_g2o(&text, "round-trip", &ReadOptions::default()).unwrap();
/// assert!((g.problem.chordal_cost(&gt) - p.chordal_cost(&gt)).abs() < 1e-9);
/// ```
pub fn write_g2o(problem: &MultipleProblem, estimate: Option<&[Rotation]>) -> String {
    let mut s = String::new();
    let quat = |r: &Rotation| {
        let q = UnitQuaternion::from_rotation_matrix(r);
        let q = q.quaternion();
        format!("{} {} {} {}", q.i, q.j, q.k, q.w)
    };
    if let Some(est) = estimate {
        for (k, r) in est.iter().enumerate() {
            let _ = writeln!(s, "VERTEX_SE3:QUAT {k} 0 0 0 {}", quat(&r.inverse()));
        }
    }
    for e in problem.edges() {
        let a = 2.0 * e.weight;
        let _ = writeln!(
            s,
            "EDGE_SE3:QUAT {} {} 0 0 0 {} 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 {a} 0 0 {a} 0 {a}",
            e.i,
            e.j,
            quat(&e.rotation.inverse())
        );
    }
    s
}

/// The g2o vertex line of `kind` for vertex `id` with the translation tokens `xyz` (as read,
/// or numbers) and this crate's rotation `r` (`W = R^T` `[F1]`; `VERTEX3`: roll pitch yaw of
/// `W = Rz(yaw) Ry(pitch) Rx(roll)`; `VERTEX_SE2`: the heading of `W`, about z).
fn vertex_line(kind: VertexKind, id: u64, xyz: &[&str], r: &Rotation) -> String {
    let w = r.inverse();
    match kind {
        VertexKind::Se3Quat => {
            let q = UnitQuaternion::from_rotation_matrix(&w);
            let q = q.quaternion();
            format!(
                "VERTEX_SE3:QUAT {id} {} {} {} {} {}",
                xyz.join(" "),
                q.i + 0.0,
                q.j + 0.0,
                q.k + 0.0,
                q.w + 0.0
            )
        }
        VertexKind::Vertex3 => {
            let (roll, pitch, yaw) = w.euler_angles();
            format!("VERTEX3 {id} {} {roll} {pitch} {yaw}", xyz.join(" "))
        }
        VertexKind::Se2 => {
            let m = w.matrix();
            let theta = m[(1, 0)].atan2(m[(0, 0)]);
            format!("VERTEX_SE2 {id} {} {theta}", xyz.join(" "))
        }
    }
}

/// Write an estimate in the layout of the g2o / TORO file it was computed from (read again
/// line by line from `input`): every line as read (edges, comments, other tags, and the
/// translations of the vertices) except that each vertex line of a node in `estimate` (by
/// vertex id; this crate's `R_i`) gets the estimate's rotation, in the vertex's own type
/// (`VERTEX_SE3:QUAT`, `VERTEX3`, `VERTEX_SE2`). Nodes of `estimate` without a vertex line get
/// one (translation 0) at the top, in the file's vertex type (so vertices precede the edges,
/// as g2o needs). Reading the result with [`read_g2o`] gives the same edges and the estimate as
/// [`crate::io::detect::LoadedGraph::initial`].
///
/// ```
/// use rotavg::io::{g2o::{read_g2o, write_g2o_like}, detect::ReadOptions, text::TextLines};
/// use rotavg::so3::exp;
/// use std::collections::BTreeMap;
/// let input = "VERTEX_SE3:QUAT 4 1.5 2 3 0 0 0 1\nEDGE3 4 9 1 0 0 0 0 0.1\n";
/// let r = exp(&nalgebra::Vector3::new(0.0, 0.0, 0.3));
/// let estimate = BTreeMap::from([(4, rotavg::Rotation::identity()), (9, r)]);
/// let out = write_g2o_like(&mut TextLines::from_text("in.g2o", input), &estimate)?;
/// assert!(out.contains("VERTEX_SE3:QUAT 4 1.5 2 3 0 0 0 1\n") && out.ends_with("EDGE3 4 9 1 0 0 0 0 0.1\n"));
/// let g = read_g2o(&out, "out.g2o", &ReadOptions::default())?;
/// assert!((g.initial.unwrap()[1].angle() - 0.3).abs() < 1e-12);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn write_g2o_like(
    input: &mut TextLines<'_>,
    estimate: &BTreeMap<u64, Rotation>,
) -> Result<String> {
    let mut body = String::new();
    let mut written: std::collections::BTreeSet<u64> = std::collections::BTreeSet::new();
    let (mut kinds_3d, mut kinds_2d, mut vertex3) = (0usize, 0usize, 0usize);
    let file = input.name().to_owned();
    while let Some((ln, line)) = input.next_line()? {
        let trimmed = line.trim();
        let toks: Vec<&str> = trimmed.split_whitespace().collect();
        let kind = match toks.first().copied() {
            Some("VERTEX_SE3:QUAT") => Some(VertexKind::Se3Quat),
            Some("VERTEX3") => Some(VertexKind::Vertex3),
            Some("VERTEX_SE2") => Some(VertexKind::Se2),
            _ => None,
        };
        match kind {
            Some(VertexKind::Se2) => kinds_2d += 1,
            Some(VertexKind::Vertex3) => vertex3 += 1,
            Some(VertexKind::Se3Quat) => kinds_3d += 1,
            None => {}
        }
        let id = toks.get(1).and_then(|t| t.parse::<u64>().ok());
        let (Some(kind), Some(id)) = (kind, id) else {
            body.push_str(line);
            body.push('\n');
            continue;
        };
        let Some(r) = estimate.get(&id) else {
            body.push_str(line);
            body.push('\n');
            continue;
        };
        let n_xyz = if kind == VertexKind::Se2 { 2 } else { 3 };
        let Some(xyz) = toks.get(2..2 + n_xyz) else {
            return Err(Error::parse(
                Some(&file),
                Some(ln),
                "a vertex line without its translation (the file changed since it was read?)",
            ));
        };
        body.push_str(&vertex_line(kind, id, xyz, r));
        body.push('\n');
        written.insert(id);
    }
    let kind = if kinds_2d > kinds_3d + vertex3 {
        VertexKind::Se2
    } else if vertex3 > kinds_3d {
        VertexKind::Vertex3
    } else {
        VertexKind::Se3Quat
    };
    let mut head = String::new();
    for (id, r) in estimate.iter().filter(|(id, _)| !written.contains(id)) {
        let zeros: &[&str] = if kind == VertexKind::Se2 {
            &["0", "0"]
        } else {
            &["0", "0", "0"]
        };
        head.push_str(&vertex_line(kind, *id, zeros, r));
        head.push('\n');
    }
    head.push_str(&body);
    Ok(head)
}

/// [`write_g2o`] with the file's node ids (`node_ids[k]` names node `k`) instead of `0..n`.
///
/// ```
/// use rotavg::io::{g2o::{read_g2o, write_g2o_with_ids}, detect::ReadOptions};
/// use rotavg::multiple::{Edge, MultipleProblem};
/// let p = MultipleProblem::new(2, vec![Edge { i: 0, j: 1, rotation: rotavg::Rotation::identity(), weight: 2.0 }])?;
/// let text = write_g2o_with_ids(&p, Some(&[rotavg::Rotation::identity(); 2]), &[10, 30]);
/// let g = read_g2o(&text, "t.g2o", &ReadOptions::default())?;
/// assert_eq!(g.node_ids, vec![10, 30]);
/// assert!((g.problem.edges()[0].weight - 2.0).abs() < 1e-12);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn write_g2o_with_ids(
    problem: &MultipleProblem,
    estimate: Option<&[Rotation]>,
    node_ids: &[u64],
) -> String {
    let id = |k: usize| node_ids.get(k).copied().unwrap_or(k as u64);
    let mut s = String::new();
    if let Some(est) = estimate {
        for (k, r) in est.iter().enumerate() {
            s.push_str(&vertex_line(
                VertexKind::Se3Quat,
                id(k),
                &["0", "0", "0"],
                r,
            ));
            s.push('\n');
        }
    }
    for e in problem.edges() {
        let a = 2.0 * e.weight;
        let q = UnitQuaternion::from_rotation_matrix(&e.rotation.inverse());
        let q = q.quaternion();
        let _ = writeln!(
            s,
            "EDGE_SE3:QUAT {} {} 0 0 0 {} {} {} {} 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 {a} 0 0 {a} 0 {a}",
            id(e.i),
            id(e.j),
            q.i,
            q.j,
            q.k,
            q.w
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::text::check_record_limit;

    #[test]
    fn record_limit_and_skipped_tags() {
        let text = "VERTEX3 0 0 0 0 0 0 0\nEDGE3 0 1 0 0 0 0 0 0\nEDGE3 1 2 0 0 0 0 0 0\n";
        let expected = "t:3: more than 2 edges and vertices";
        check_record_limit(text, 3, expected, |lines, max| {
            read_g2o_limited(lines, &ReadOptions::default(), max)
        });
        // many distinct unknown tags: a bounded number of warnings
        let mut text = String::new();
        for k in 0..100 {
            text.push_str(&format!("TAG{k} 1 2\n"));
        }
        text.push_str("EDGE3 0 1 0 0 0 0 0 0\n");
        let g = read_g2o(&text, "t", &ReadOptions::default()).unwrap();
        let skipped: Vec<&Warning> = g
            .warnings
            .iter()
            .filter(|w| w.code == "skipped_lines")
            .collect();
        assert_eq!(skipped.len(), MAX_SKIPPED_TAGS + 1);
        assert!(
            skipped[MAX_SKIPPED_TAGS]
                .message
                .starts_with("skipped 68 line(s) with 32+ other"),
            "{:?}",
            g.warnings
        );
        // the EDGE3 line carries no information: weight 1, said so
        let uninformed: Vec<&Warning> = g
            .warnings
            .iter()
            .filter(|w| w.code == "without_information")
            .collect();
        assert_eq!(uninformed.len(), 1);
        assert_eq!(uninformed[0].count, Some(1));
    }
}
