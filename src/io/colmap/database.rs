//! The COLMAP database reader (SQLite, cargo feature `colmap`): the view graph of
//! `two_view_geometries` (`[F12]`), with `--information full` each pair's rotation information
//! from its inlier correspondences (`[F13]`), the cameras, and the images' pose priors.

use super::*;
use crate::io::RawEdge;
use crate::io::detect::{GraphFormat, WeightSource};
use crate::multiple::MultipleProblem;
use crate::multiple::anisotropic::Information;
use crate::warning::Warning;
use rusqlite::{Connection, OpenFlags};

/// A little-endian f64 of 8 bytes.
fn f64_le(chunk: &[u8]) -> f64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(chunk);
    f64::from_le_bytes(b)
}

/// The first `N` little-endian f64 of `bytes` (zeros past its end).
fn f64s<const N: usize>(bytes: &[u8]) -> [f64; N] {
    let mut out = [0.0; N];
    for (k, chunk) in bytes.chunks_exact(8).take(N).enumerate() {
        out[k] = f64_le(chunk);
    }
    out
}

/// The longest image name accepted, characters.
const MAX_NAME_CHARS: i64 = 4096;

/// A COLMAP database opened read only, and the file name its errors carry.
struct Db {
    conn: Connection,
    file: String,
}

impl Db {
    /// Open `path` read only; an SQLite error names the file.
    fn open(path: &Path) -> Result<Db> {
        let file = path.display().to_string();
        match Connection::open_with_flags(
            path,
            OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
        ) {
            Ok(conn) => Ok(Db { conn, file }),
            Err(e) => Err(Error::parse(Some(&file), None, format!("SQLite: {e}"))),
        }
    }

    /// An error about the database (it has no lines).
    fn err(&self, msg: String) -> Error {
        Error::parse(Some(&self.file), None, msg)
    }

    /// An SQLite error, as [`Self::err`].
    fn sql(&self, e: rusqlite::Error) -> Error {
        self.err(format!("SQLite: {e}"))
    }

    /// The column names of `table` (none when there is no such table).
    fn columns(&self, table: &str) -> Result<Vec<String>> {
        self.conn
            .prepare(&format!("PRAGMA table_info({table})"))
            .and_then(|mut s| s.query_map([], |r| r.get(1))?.collect())
            .map_err(|e| self.sql(e))
    }
}

pub(super) fn read(path: &Path, options: &ReadOptions) -> Result<LoadedGraph> {
    if !path.is_file() {
        return Err(Error::Io {
            path: path.display().to_string(),
            message: "no such file (a COLMAP database)".into(),
        });
    }
    let db = Db::open(path)?;
    let has_tvec = check_tables(&db)?;
    let names = image_names(&db)?;
    let mut rows = geometries(&db, &names, has_tvec, options)?;
    let (information, mut warnings) = match options.weights {
        WeightSource::File => information(&db, &mut rows, options.full_information)?,
        WeightSource::Unit => (None, Vec::new()),
    };
    warnings.extend(rows.warnings());
    if rows.raw.is_empty() {
        return Err(db.err(format!(
            "no relative rotations in the COLMAP database: {} two-view geometries, {} skipped by config, \
             {} without a stored relative pose (COLMAP stores relative poses with \
             --TwoViewGeometry.compute_relative_pose 1; accepted configs: {})",
            rows.total,
            rows.skipped_by_config(),
            rows.no_pose,
            accepted_list()
        )));
    }
    view_graph(&db.file, rows.raw, &names, information, warnings)
}

/// The pairs' informations as `full` asks (`Some(true)`: read them, an error when none can
/// be; `Some(false)`: none; `None`: read them where the database gives them, else none with
/// the warning `database_without_information`), keeping in `rows` the pairs that have one;
/// the warnings of the pairs skipped.
fn information(
    db: &Db,
    rows: &mut Geometries,
    full: Option<bool>,
) -> Result<(Option<Vec<Information>>, Vec<Warning>)> {
    let read = match full {
        Some(false) => return Ok((None, Vec::new())),
        Some(true) => two_view::informations(db, &rows.raw, &rows.poses),
        None => match two_view::informations(db, &rows.raw, &rows.poses) {
            Ok(read) if read.kept.is_empty() && read.skipped.0 > 0 => {
                return Ok((None, vec![without_information(db, &read.skipped.1)]));
            }
            Err(Error::Parse { message, .. }) => {
                return Ok((None, vec![without_information(db, &message)]));
            }
            read => read,
        },
    };
    let two_view::Informations {
        kept,
        rotations,
        info,
        skipped,
        reestimated,
    } = read?;
    if kept.is_empty() && skipped.0 > 0 {
        return Err(db.err(format!(
            "--information full: none of the {} two-view geometries with a relative pose gives an information (first: {})",
            skipped.0, skipped.1
        )));
    }
    let mut kept = kept.into_iter().peekable();
    let mut k = 0;
    rows.raw.retain(|_| {
        k += 1;
        kept.next_if_eq(&(k - 1)).is_some()
    });
    for (edge, rotation) in rows.raw.iter_mut().zip(rotations) {
        edge.rotation = rotation;
    }
    let mut warnings = Vec::new();
    if reestimated.0 > 0 {
        let message = format!(
            "{} of {} pairs measured by their pose re-estimated without {} inlier correspondences beyond {} robust standard deviations of their Sampson errors (wrong matches; paper-notes/formats.md [F13]), not by the database's stored rotation; `--information kappa` reads the stored rotations",
            reestimated.0,
            info.len(),
            reestimated.1,
            crate::io::two_view_information::TRIM_SIGMAS
        );
        warnings.push(Warning::new("pairs_reestimated", message).with_count(reestimated.0));
    }
    if skipped.0 > 0 {
        let message = format!(
            "skipped {} two-view geometries whose inlier correspondences give no information (first: {})",
            skipped.0, skipped.1
        );
        warnings.push(Warning::new("skipped_without_information", message).with_count(skipped.0));
    }
    Ok((Some(info), warnings))
}

/// The warning of `--information auto` on a database that gives no information (`reason`).
fn without_information(db: &Db, reason: &str) -> Warning {
    let message = format!(
        "{}: no two-view information: {reason}; the pairs are weighed alike (weights 1). With \
         information the robust default was the more accurate on most generated scenes \
         (docs/benchmarks.md, \"The default against each robust loss a user can name\"); \
         `--information kappa` reads weights 1 without this warning",
        db.file
    );
    Warning::new("database_without_information", message)
}

/// The view graph of the edges kept, on the images they name (with their names), with
/// `information` when given.
fn view_graph(
    file: &str,
    raw: Vec<RawEdge>,
    names: &BTreeMap<u64, String>,
    information: Option<Vec<Information>>,
    warnings: Vec<Warning>,
) -> Result<LoadedGraph> {
    let anisotropic = information.is_some();
    let (ids, edges) = crate::io::compact_edges(raw, std::iter::empty());
    let node_names = ids
        .iter()
        .map(|id| names.get(id).cloned().unwrap_or_default())
        .collect();
    let mut problem = MultipleProblem::new(ids.len(), edges).map_err(|e| e.in_file(file, None))?;
    if let Some(info) = information {
        problem = problem
            .with_information(info)
            .map_err(|e| e.in_file(file, None))?;
    }
    let duplicates = crate::multiple::stats::duplicate_edge_count(&problem);
    Ok(LoadedGraph {
        problem,
        node_ids: ids,
        node_names,
        initial: None,
        duplicates,
        reversed: 0,
        warnings,
        format: GraphFormat::Colmap,
        planar: false,
        // the caller (io::detect::load_graph) sets the options; this records what was read
        read: ReadOptions {
            full_information: Some(anisotropic),
            ..Default::default()
        },
    })
}

/// Check that the tables and columns this reader needs exist; whether
/// `two_view_geometries` has a `tvec` column.
fn check_tables(db: &Db) -> Result<bool> {
    let tables: Vec<String> = db
        .conn
        .prepare("SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name")
        .and_then(|mut s| s.query_map([], |r| r.get(0))?.collect())
        .map_err(|e| db.err(format!("not an SQLite database COLMAP wrote ({e})")))?;
    for needed in ["images", "two_view_geometries"] {
        if !tables.iter().any(|t| t == needed) {
            return Err(db.err(format!(
                "not a COLMAP database: no table `{needed}` (tables: {})",
                if tables.is_empty() {
                    "none".to_string()
                } else {
                    tables.join(", ")
                }
            )));
        }
    }
    for (table, needed) in [
        ("images", &["image_id", "name", "camera_id"][..]),
        ("two_view_geometries", &["pair_id", "config"]),
    ] {
        let columns = db.columns(table)?;
        if let Some(c) = needed.iter().find(|c| !columns.iter().any(|x| x == *c)) {
            return Err(db.err(format!(
                "not a COLMAP database: the table `{table}` has no column `{c}`"
            )));
        }
    }
    let geometry_columns = db.columns("two_view_geometries")?;
    if !geometry_columns.iter().any(|x| x == "qvec") {
        return Err(db.err(
            "the table `two_view_geometries` has no column `qvec`: a database of an older COLMAP, \
             which stores no relative rotations (rotations are not derived from E here); \
             run COLMAP's matcher again with a current COLMAP and --TwoViewGeometry.compute_relative_pose 1"
                .into(),
        ));
    }
    Ok(geometry_columns.iter().any(|x| x == "tvec"))
}

/// The table `images`: image id -> name.
fn image_names(db: &Db) -> Result<BTreeMap<u64, String>> {
    let (err, sql) = (|m| db.err(m), |e| db.sql(e));
    let mut names = BTreeMap::new();
    let mut stmt = db
        .conn
        .prepare(&format!(
            "SELECT image_id, CASE WHEN length(name) <= {MAX_NAME_CHARS} THEN name END, typeof(name) FROM images"
        ))
        .map_err(sql)?;
    let mut rows = stmt.query([]).map_err(sql)?;
    while let Some(row) = rows.next().map_err(sql)? {
        let id: i64 = row
            .get(0)
            .map_err(|e| err(format!("table `images`: image_id: {e}")))?;
        let id = u64::try_from(id)
            .ok()
            .filter(|&v| v < MAX_NUM_IMAGES)
            .ok_or_else(|| {
                err(format!(
                    "table `images`: image_id {id} is outside COLMAP's range 0..{MAX_NUM_IMAGES}"
                ))
            })?;
        let name: Option<String> = row
            .get(1)
            .map_err(|e| err(format!("table `images`: image {id}: name: {e}")))?;
        let name = name.ok_or_else(|| {
            let kind: String = row.get(2).unwrap_or_default();
            err(format!(
                "table `images`: image {id}: the name is missing ({kind}) or longer than {MAX_NAME_CHARS} characters"
            ))
        })?;
        names.insert(id, name);
    }
    Ok(names)
}

/// The rows of `two_view_geometries` as read: the edges kept with each one's `(pair_id,
/// tvec)` (for `--information full`), and the rows skipped, by reason.
#[derive(Default)]
struct Geometries {
    raw: Vec<RawEdge>,
    poses: Vec<(i64, Option<[f64; 3]>)>,
    total: usize,
    by_config: BTreeMap<i64, usize>,
    no_pose: usize,
}

impl Geometries {
    /// The rows skipped for their `config`.
    fn skipped_by_config(&self) -> usize {
        self.by_config.values().sum()
    }

    /// The reader's remarks: rows skipped by config, rows without a relative pose.
    fn warnings(&self) -> Vec<Warning> {
        let (total, skipped_config) = (self.total, self.skipped_by_config());
        let mut warnings = Vec::new();
        if skipped_config > 0 {
            let list: Vec<String> = self
                .by_config
                .iter()
                .map(|(c, k)| format!("{k} {} ({c})", config_name(*c)))
                .collect();
            let message = format!(
                "skipped {skipped_config} of {total} two-view geometries by config: {} (only {} carry a relative rotation)",
                list.join(", "),
                accepted_list()
            );
            warnings.push(Warning::new("skipped_by_config", message).with_count(skipped_config));
        }
        if self.no_pose > 0 {
            let message = format!(
                "skipped {} of {total} two-view geometries without a stored relative pose (qvec NULL or zero, or COLMAP's default identity with zero tvec)",
                self.no_pose
            );
            warnings.push(Warning::new("skipped_without_pose", message).with_count(self.no_pose));
        }
        warnings
    }
}

/// What one row of `two_view_geometries` gives.
enum Row {
    /// An edge, its `pair_id` and `tvec`.
    Edge(RawEdge, i64, Option<[f64; 3]>),
    /// Skipped: its `config` carries no relative rotation.
    Config(i64),
    /// Skipped: no relative pose stored.
    NoPose,
}

/// Read the table `two_view_geometries` (`has_tvec`: whether it has the column `tvec`).
fn geometries(
    db: &Db,
    names: &BTreeMap<u64, String>,
    has_tvec: bool,
    options: &ReadOptions,
) -> Result<Geometries> {
    let sql = |e| db.sql(e);
    let tvec_sql = if has_tvec {
        "typeof(tvec), CASE WHEN length(tvec) = 24 THEN tvec END"
    } else {
        "'null', NULL"
    };
    let mut stmt = db
        .conn
        .prepare(&format!(
            "SELECT pair_id, config, typeof(qvec), length(qvec), \
             CASE WHEN length(qvec) = 32 THEN qvec END, {tvec_sql} \
             FROM two_view_geometries ORDER BY pair_id"
        ))
        .map_err(sql)?;
    let mut rows = stmt.query([]).map_err(sql)?;
    let mut g = Geometries::default();
    while let Some(row) = rows.next().map_err(sql)? {
        g.total += 1;
        match geometry_row(db, row, names, options)? {
            Row::Edge(edge, pair_id, t) => {
                g.raw.push(edge);
                g.poses.push((pair_id, t));
            }
            Row::Config(config) => *g.by_config.entry(config).or_default() += 1,
            Row::NoPose => g.no_pose += 1,
        }
    }
    Ok(g)
}

/// One row of the query of [`geometries`], checked.
fn geometry_row(
    db: &Db,
    row: &rusqlite::Row<'_>,
    names: &BTreeMap<u64, String>,
    options: &ReadOptions,
) -> Result<Row> {
    let (err, sql) = (|m| db.err(m), |e| db.sql(e));
    let pair_id: i64 = row
        .get(0)
        .map_err(|e| err(format!("table `two_view_geometries`: pair_id: {e}")))?;
    let (id1, id2) = pair_id_to_image_pair(pair_id).ok_or_else(|| {
        err(format!(
            "table `two_view_geometries`: pair_id {pair_id} is negative"
        ))
    })?;
    let at = format!("two_view_geometries row pair_id {pair_id} (images {id1}, {id2})");
    let config: i64 = row.get(1).map_err(|e| err(format!("{at}: config: {e}")))?;
    if !ACCEPTED_CONFIGS.iter().any(|&(c, _)| c == config) {
        return Ok(Row::Config(config));
    }
    if id1 == id2 {
        return Err(err(format!("{at}: a pair of an image with itself")));
    }
    let kind: String = row.get(2).map_err(sql)?;
    let len: Option<i64> = row.get(3).map_err(sql)?;
    let qvec: Option<Vec<u8>> = row.get(4).map_err(sql)?;
    let q = match (kind.as_str(), qvec) {
        ("null", _) => return Ok(Row::NoPose),
        ("blob", Some(bytes)) => f64s::<4>(&bytes),
        ("blob", None) if len == Some(0) => return Ok(Row::NoPose),
        (kind, _) => {
            return Err(err(format!(
                "{at}: qvec is a {kind} of {} bytes; expected a blob of 32 bytes (4 little-endian f64: w x y z)",
                len.unwrap_or(0)
            )));
        }
    };
    let tkind: String = row.get(5).map_err(sql)?;
    let tvec: Option<Vec<u8>> = row.get(6).map_err(sql)?;
    let t = tvec.as_deref().map(f64s::<3>);
    if tkind != "null" && t.is_none() {
        return Err(err(format!(
            "{at}: tvec is not a blob of 24 bytes (3 little-endian f64)"
        )));
    }
    // no relative pose stored: a zero quaternion, or COLMAP's default (identity, t = 0)
    let default_pose = q == [1.0, 0.0, 0.0, 0.0] && t == Some([0.0; 3]);
    if q == [0.0; 4] || default_pose {
        return Ok(Row::NoPose);
    }
    let rotation = quaternion_rotation(q, options.quaternion_tolerance, &format!("{at}: qvec"))
        .map_err(err)?;
    for id in [id1, id2] {
        if !names.contains_key(&id) {
            return Err(err(format!(
                "{at}: image_id {id} is not in the table `images`"
            )));
        }
    }
    let edge = RawEdge {
        i: id1,
        j: id2,
        rotation,
        weight: 1.0,
    };
    Ok(Row::Edge(edge, pair_id, t))
}

/// `--information full` (`[F13]`): each edge's information from the inlier
/// correspondences of its row and the two images' cameras.
pub(crate) mod rig;

mod two_view {
    use super::*;
    use crate::io::two_view_information::{
        Camera, rotation_information, scaled_by_residuals, trimmed_pose,
    };
    use nalgebra::{Vector2, Vector3};
    use rusqlite::Statement;

    /// The most keypoints or inlier matches read for one image or pair (COLMAP extracts
    /// at most 8192 SIFT features per image by default); a larger count is an error.
    const MAX_ROWS: i64 = 10_000_000;

    /// What [`informations`] read.
    pub(super) struct Informations {
        /// The indices of the edges kept (those with an information), increasing.
        pub kept: Vec<usize>,
        /// Each kept edge's rotation: the stored one, or its pose's re-estimated without its
        /// wrong matches ([`trimmed_pose`]).
        pub rotations: Vec<Rotation>,
        /// Each kept edge's information.
        pub info: Vec<Information>,
        /// The edges skipped, and the first reason.
        pub skipped: (usize, String),
        /// The kept edges re-estimated, and the correspondences they set aside.
        pub reestimated: (usize, usize),
    }

    /// Normalised image points.
    type Points = Vec<Vector2<f64>>;

    /// The keypoints of an image: the number of columns (2, 4 or 6 float32 per keypoint,
    /// the position first) and the blob.
    type Keypoints = (usize, Vec<u8>);

    /// The camera of each image, and the queries of keypoints and inlier matches.
    struct Sources<'a> {
        db: &'a Db,
        camera_of: BTreeMap<u32, Result<Camera>>,
        of_image: BTreeMap<u64, u32>,
        keypoints: Statement<'a>,
        matches: Statement<'a>,
    }

    impl<'a> Sources<'a> {
        fn new(db: &'a Db) -> Result<Self> {
            let (cams, of_image) = cameras(db)?;
            let mut camera_of = BTreeMap::new();
            for c in &cams {
                let cam = Camera::from_colmap(&c.model, &c.params)
                    .map_err(|m| db.err(format!("table `cameras`: camera {}: {m}", c.camera_id)));
                camera_of.insert(c.camera_id, cam);
            }
            let keypoints = db
                .conn
                .prepare(&format!(
                    "SELECT rows, cols, CASE WHEN rows <= {MAX_ROWS} AND cols IN (2, 4, 6) \
                     AND length(data) = 4 * rows * cols THEN data END FROM keypoints WHERE image_id = ?1"
                ))
                .map_err(|e| db.err(format!("the pairs' information needs the table `keypoints` ({e})")))?;
            let matches = db
                .conn
                .prepare(&format!(
                    "SELECT rows, cols, CASE WHEN rows <= {MAX_ROWS} AND cols = 2 \
                     AND length(data) = 8 * rows THEN data END FROM two_view_geometries WHERE pair_id = ?1"
                ))
                .map_err(|e| db.sql(e))?;
            Ok(Sources {
                db,
                camera_of,
                of_image,
                keypoints,
                matches,
            })
        }

        /// The camera of `image`.
        fn camera(&self, image: u64) -> Result<Camera> {
            let err = |m| self.db.err(m);
            let id = self
                .of_image
                .get(&image)
                .ok_or_else(|| err(format!("table `images`: image {image} has no camera")))?;
            match self.camera_of.get(id) {
                Some(Ok(c)) => Ok(*c),
                Some(Err(e)) => Err(e.clone()),
                None => Err(err(format!("table `cameras`: no camera {id}"))),
            }
        }

        /// The keypoints of `image`.
        fn keypoints(&mut self, image: u64) -> Result<Keypoints> {
            let (err, sql) = (|m| self.db.err(m), |e| self.db.sql(e));
            let mut rows = self.keypoints.query([image as i64]).map_err(sql)?;
            let row = rows
                .next()
                .map_err(sql)?
                .ok_or_else(|| err(format!("table `keypoints`: no keypoints of image {image}")))?;
            let (n, cols): (i64, i64) = (row.get(0).map_err(sql)?, row.get(1).map_err(sql)?);
            let data: Option<Vec<u8>> = row.get(2).map_err(sql)?;
            let data = data.ok_or_else(|| {
                err(format!(
                    "table `keypoints`: image {image}: {n} x {cols} keypoints, but the blob is not {n} x {cols} float32 (cols 2, 4 or 6, at most {MAX_ROWS} rows)"
                ))
            })?;
            Ok((cols as usize, data))
        }

        /// The inlier matches of `pair_id` (`at` names its row): `None` when it has none.
        fn matches(&mut self, pair_id: i64, at: &str) -> Result<Option<Vec<u8>>> {
            let (err, sql) = (|m| self.db.err(m), |e| self.db.sql(e));
            let mut rows = self.matches.query([pair_id]).map_err(sql)?;
            let row = rows
                .next()
                .map_err(sql)?
                .ok_or_else(|| err(format!("{at}: gone")))?;
            let n: i64 = row.get(0).map_err(sql)?;
            let data: Option<Vec<u8>> = row.get(2).map_err(sql)?;
            match data {
                Some(matches) => Ok(Some(matches)),
                None if n == 0 => Ok(None),
                None => Err(err(format!(
                    "{at}: the inlier matches (data) are not {n} x 2 uint32"
                ))),
            }
        }
    }

    pub(super) fn informations(
        db: &Db,
        raw: &[RawEdge],
        poses: &[(i64, Option<[f64; 3]>)],
    ) -> Result<Informations> {
        let mut sources = Sources::new(db)?;
        let (mut kept, mut info, mut pairs) = (Vec::new(), Vec::new(), Vec::new());
        let mut skipped = (0usize, String::new());
        let mut skip = |reason: String| {
            skipped.0 += 1;
            if skipped.1.is_empty() {
                skipped.1 = reason;
            }
        };
        let mut first: Option<(u64, Keypoints)> = None;
        for (k, (edge, &(pair_id, tvec))) in raw.iter().zip(poses).enumerate() {
            let at = format!(
                "two_view_geometries row pair_id {pair_id} (images {}, {})",
                edge.i, edge.j
            );
            let t = tvec.ok_or_else(|| {
                db.err(format!(
                    "{at}: no tvec: the pair's information needs the relative translation"
                ))
            })?;
            let cameras = (sources.camera(edge.i)?, sources.camera(edge.j)?);
            let Some(matches) = sources.matches(pair_id, &at)? else {
                skip(format!("{at}: no inlier matches"));
                continue;
            };
            if first.as_ref().map(|f| f.0) != Some(edge.i) {
                first = Some((edge.i, sources.keypoints(edge.i)?));
            }
            let kp1 = &first.as_ref().expect("set above").1;
            let kp2 = sources.keypoints(edge.j)?;
            let (x1, x2) = correspondences(db, &at, &matches, (kp1, &kp2), cameras)?;
            let (c1, c2) = cameras;
            // the pose without its wrong matches, where it has some (`[F13]`)
            let n = x1.len();
            let trimmed = trimmed_pose(&edge.rotation, &t.into(), &x1, &x2, &c1, &c2);
            let reestimated = trimmed.is_some();
            let (r, t, x1, x2) = match trimmed {
                Some(p) => {
                    let pick = |x: &[Vector2<f64>]| p.kept.iter().map(|&k| x[k]).collect();
                    (p.rotation, p.translation, pick(&x1), pick(&x2))
                }
                None => (edge.rotation, Vector3::from(t), x1, x2),
            };
            let set_aside = reestimated.then_some(n - x1.len());
            match rotation_information(&r, &t, &x1, &x2, &c1, &c2) {
                Ok(p) => pairs.push((k, at, p, r, set_aside)),
                Err(reason) => skip(format!("{at}: {reason}")),
            }
        }
        let scaled = scaled_by_residuals(&pairs.iter().map(|p| p.2).collect::<Vec<_>>());
        let (mut rotations, mut reestimated) = (Vec::new(), (0, 0));
        for ((k, at, _, r, set_aside), h) in pairs.into_iter().zip(scaled) {
            match Information::new(h) {
                Ok(h) => {
                    kept.push(k);
                    info.push(h);
                    rotations.push(r);
                    if let Some(set_aside) = set_aside {
                        reestimated = (reestimated.0 + 1, reestimated.1 + set_aside);
                    }
                }
                Err(e) => skip(format!("{at}: {e}")),
            }
        }
        Ok(Informations {
            kept,
            rotations,
            info,
            skipped,
            reestimated,
        })
    }

    /// The normalised points of the inlier matches `matches` (pairs of uint32 keypoint
    /// indices) of the images with keypoints `kp` and cameras `cameras`: those both cameras
    /// can normalise.
    fn correspondences(
        db: &Db,
        at: &str,
        matches: &[u8],
        kp: (&Keypoints, &Keypoints),
        cameras: (Camera, Camera),
    ) -> Result<(Points, Points)> {
        let f32_at = |b: &[u8], k: usize| {
            f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]])
        };
        let u32_at = |b: &[u8], k: usize| {
            u32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]])
        };
        let point = |(cols, kp): &Keypoints, a: usize| {
            Vector2::new(f32_at(kp, a * cols) as f64, f32_at(kp, a * cols + 1) as f64)
        };
        let (n1, n2) = (kp.0.1.len() / (4 * kp.0.0), kp.1.1.len() / (4 * kp.1.0));
        let m = matches.len() / 8;
        let (mut x1, mut x2) = (Vec::with_capacity(m), Vec::with_capacity(m));
        for k in 0..m {
            let (a, b) = (
                u32_at(matches, 2 * k) as usize,
                u32_at(matches, 2 * k + 1) as usize,
            );
            if a >= n1 || b >= n2 {
                return Err(db.err(format!(
                    "{at}: inlier match {k} names keypoint ({a}, {b}); the images have {n1} and {n2}"
                )));
            }
            let (p1, p2) = (point(kp.0, a), point(kp.1, b));
            if let (Some(u), Some(v)) = (cameras.0.normalise(&p1), cameras.1.normalise(&p2)) {
                x1.push(u);
                x2.push(v);
            }
        }
        Ok((x1, x2))
    }
}

/// The cameras of the database at `path`, and the camera of each image.
pub(super) fn read_cameras(path: &Path) -> Result<(Vec<ColmapCamera>, BTreeMap<u64, u32>)> {
    cameras(&Db::open(path)?)
}

/// The table `cameras`, and the camera of each image (table `images`).
fn cameras(db: &Db) -> Result<(Vec<ColmapCamera>, BTreeMap<u64, u32>)> {
    let (err, sql) = (|m| db.err(m), |e| db.sql(e));
    let mut cameras = Vec::new();
    {
        let mut stmt = db
            .conn
            .prepare(
                "SELECT camera_id, model, width, height, typeof(params), \
                 CASE WHEN length(params) <= 1024 THEN params END FROM cameras ORDER BY camera_id",
            )
            .map_err(|e| err(format!("no table `cameras` with COLMAP's columns ({e})")))?;
        let mut rows = stmt.query([]).map_err(sql)?;
        while let Some(row) = rows.next().map_err(sql)? {
            cameras.push(camera_row(db, row)?);
        }
    }
    let mut of_image = BTreeMap::new();
    let mut stmt = db
        .conn
        .prepare("SELECT image_id, camera_id FROM images")
        .map_err(sql)?;
    let mut rows = stmt.query([]).map_err(sql)?;
    while let Some(row) = rows.next().map_err(sql)? {
        let (image, camera): (i64, i64) = (row.get(0).map_err(sql)?, row.get(1).map_err(sql)?);
        let (Ok(image), Ok(camera)) = (u64::try_from(image), u32::try_from(camera)) else {
            return Err(err(format!(
                "table `images`: image {image}: camera_id {camera} is not a 32-bit id"
            )));
        };
        if !cameras.iter().any(|c: &ColmapCamera| c.camera_id == camera) {
            return Err(err(format!(
                "table `images`: image {image} names camera {camera}, which the table `cameras` does not have"
            )));
        }
        of_image.insert(image, camera);
    }
    Ok((cameras, of_image))
}

/// One row of the table `cameras`, checked.
fn camera_row(db: &Db, row: &rusqlite::Row<'_>) -> Result<ColmapCamera> {
    let (err, sql) = (|m| db.err(m), |e| db.sql(e));
    let id: i64 = row.get(0).map_err(sql)?;
    let camera_id = u32::try_from(id)
        .map_err(|_| err(format!("table `cameras`: camera_id {id} is not 32-bit")))?;
    let model: i64 = row.get(1).map_err(sql)?;
    let (width, height): (i64, i64) = (row.get(2).map_err(sql)?, row.get(3).map_err(sql)?);
    let blob: Option<Vec<u8>> = row.get(5).map_err(sql)?;
    let Some(&(_, name, count)) = CAMERA_MODELS.iter().find(|m| m.0 == model) else {
        return Err(err(format!(
            "table `cameras`: camera {id}: model {model} is not one of COLMAP's camera models"
        )));
    };
    let blob = blob.unwrap_or_default();
    if blob.len() != 8 * count {
        return Err(err(format!(
            "table `cameras`: camera {id} ({name}): params has {} bytes, expected {} ({count} f64)",
            blob.len(),
            8 * count
        )));
    }
    Ok(ColmapCamera {
        camera_id,
        model: name.to_string(),
        width: u64::try_from(width).unwrap_or(0),
        height: u64::try_from(height).unwrap_or(0),
        params: blob.chunks_exact(8).map(f64_le).collect(),
    })
}

pub(super) fn poses(path: &Path, options: &ReadOptions) -> Result<Vec<ColmapImage>> {
    let db = Db::open(path)?;
    let sql = |e| db.sql(e);
    let refuse = || {
        db.err(
            "a COLMAP database holds no estimated camera poses (only two-view geometries, \
             and no pose priors here): give the sparse model the mapper wrote (e.g. sparse/0, \
             or its images.bin)"
                .into(),
        )
    };
    let columns = db.columns("images")?;
    let has = |c: &&str| columns.iter().any(|x| x == c);
    if !["image_id", "name", "camera_id"].iter().all(has) {
        return Err(db.err(
            "not a COLMAP database: no table `images` with image_id, name, camera_id".into(),
        ));
    }
    if !["prior_qw", "prior_qx", "prior_qy", "prior_qz"]
        .iter()
        .all(has)
    {
        return Err(refuse());
    }
    let t = if ["prior_tx", "prior_ty", "prior_tz"].iter().all(has) {
        "prior_tx, prior_ty, prior_tz"
    } else {
        "0.0, 0.0, 0.0"
    };
    let mut stmt = db
        .conn
        .prepare(&format!(
            "SELECT image_id, CASE WHEN length(name) <= {MAX_NAME_CHARS} THEN name END, camera_id, \
             prior_qw, prior_qx, prior_qy, prior_qz, {t} FROM images \
             WHERE prior_qw IS NOT NULL AND prior_qx IS NOT NULL AND prior_qy IS NOT NULL \
             AND prior_qz IS NOT NULL ORDER BY image_id"
        ))
        .map_err(sql)?;
    let mut rows = stmt.query([]).map_err(sql)?;
    let mut images = ImageList::with_capacity(0, options);
    while let Some(row) = rows.next().map_err(sql)? {
        prior_row(&db, row, &mut images)?;
    }
    if images.images.is_empty() {
        return Err(refuse());
    }
    images.finish(&db.file, None, "no pose priors")
}

/// One row of the pose priors of the table `images`: pushed to `images` when it holds a prior.
fn prior_row(db: &Db, row: &rusqlite::Row<'_>, images: &mut ImageList) -> Result<()> {
    let (err, sql) = (|m| db.err(m), |e| db.sql(e));
    let id: i64 = row.get(0).map_err(sql)?;
    let image_id = u32::try_from(id)
        .map_err(|_| err(format!("table `images`: image_id {id} is not a 32-bit id")))?;
    let name: Option<String> = row.get(1).map_err(sql)?;
    let name = name.ok_or_else(|| {
        err(format!(
            "table `images`: image {id}: no name, or a name too long"
        ))
    })?;
    let cam: i64 = row.get(2).map_err(sql)?;
    let camera_id = u32::try_from(cam).map_err(|_| {
        err(format!(
            "table `images`: image {id}: camera_id {cam} is not a 32-bit id"
        ))
    })?;
    let mut v = [0.0; 7];
    for (k, slot) in v.iter_mut().enumerate() {
        let x: Option<f64> = row.get(3 + k).map_err(sql)?;
        *slot = x.unwrap_or(0.0);
    }
    if v[..4] == [0.0; 4] || v.iter().any(|x| !x.is_finite()) {
        return Ok(()); // no prior stored
    }
    images
        .push(
            image_id,
            camera_id,
            name,
            &v,
            &format!("table `images`: image {id}: prior"),
        )
        .map_err(err)
}

fn accepted_list() -> String {
    ACCEPTED_CONFIGS
        .iter()
        .map(|(c, n)| format!("{n} ({c})"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// COLMAP 4's gravity priors: `(image id, g)` for every camera row of `pose_priors` whose
/// `gravity` is three finite numbers, not all zero (`[F15]`). Errors: no `pose_priors` table with
/// a `gravity` column (older databases store positions only).
pub(crate) fn gravity_priors(path: &Path) -> Result<Vec<(u64, [f64; 3])>> {
    let db = Db::open(path)?;
    let columns = db.columns("pose_priors")?;
    let has = |c: &str| columns.iter().any(|x| x == c);
    if !has("gravity") {
        return Err(db.err(
            "no gravity priors: the database has no `pose_priors.gravity` column (COLMAP 4 \
             stores them there); give a JSON or text file instead"
                .into(),
        ));
    }
    // COLMAP 4: priors attach to sensor data (`corr_data_id`, a camera's is its image id);
    // sensor type 0 is a camera
    let sql = if has("corr_data_id") {
        "SELECT corr_data_id, gravity FROM pose_priors WHERE corr_sensor_type = 0"
    } else {
        "SELECT image_id, gravity FROM pose_priors"
    };
    let mut stmt = db.conn.prepare(sql).map_err(|e| db.sql(e))?;
    let mut rows = stmt.query([]).map_err(|e| db.sql(e))?;
    let mut out = Vec::new();
    while let Some(row) = rows.next().map_err(|e| db.sql(e))? {
        let id: i64 = row.get(0).map_err(|e| db.sql(e))?;
        let blob: Option<Vec<u8>> = row.get(1).unwrap_or(None);
        let Some(blob) = blob.filter(|b| b.len() == 24) else {
            continue;
        };
        let g = f64s::<3>(&blob);
        if let Ok(id) = u64::try_from(id)
            && g.iter().all(|x| x.is_finite())
            && g.iter().any(|x| *x != 0.0)
        {
            out.push((id, g));
        }
    }
    Ok(out)
}
