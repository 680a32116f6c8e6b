//! The COLMAP database reader (SQLite, cargo feature `colmap`): the view graph of
//! `two_view_geometries` (`[F12]`), with `--information full` each pair's rotation information
//! from its inlier correspondences (`[F13]`), the cameras, and the images' pose priors.

use super::*;
use crate::io::detect::GraphFormat;
use crate::multiple::MultipleProblem;
use rusqlite::{Connection, OpenFlags};

fn f64s<const N: usize>(bytes: &[u8]) -> [f64; N] {
    let mut out = [0.0; N];
    for (k, chunk) in bytes.chunks_exact(8).take(N).enumerate() {
        let mut b = [0u8; 8];
        b.copy_from_slice(chunk);
        out[k] = f64::from_le_bytes(b);
    }
    out
}

/// The longest image name accepted, characters.
const MAX_NAME_CHARS: i64 = 4096;

pub(super) fn read(path: &Path, options: &ReadOptions) -> Result<LoadedGraph> {
    let file = path.display().to_string();
    let err = |msg: String| Error::parse(Some(&file), None, msg);
    let sql = |e: rusqlite::Error| err(format!("SQLite: {e}"));
    if !path.is_file() {
        return Err(Error::Io {
            path: file.clone(),
            message: "no such file (a COLMAP database)".into(),
        });
    }
    let conn = Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(sql)?;
    // the tables and columns this reader needs
    let tables: Vec<String> = conn
        .prepare("SELECT name FROM sqlite_master WHERE type = 'table' ORDER BY name")
        .and_then(|mut s| s.query_map([], |r| r.get(0))?.collect())
        .map_err(|e| err(format!("not an SQLite database COLMAP wrote ({e})")))?;
    for needed in ["images", "two_view_geometries"] {
        if !tables.iter().any(|t| t == needed) {
            return Err(err(format!(
                "not a COLMAP database: no table `{needed}` (tables: {})",
                if tables.is_empty() {
                    "none".to_string()
                } else {
                    tables.join(", ")
                }
            )));
        }
    }
    let columns = |table: &str| -> Result<Vec<String>> {
        conn.prepare(&format!("PRAGMA table_info({table})"))
            .and_then(|mut s| s.query_map([], |r| r.get(1))?.collect())
            .map_err(sql)
    };
    let image_columns = columns("images")?;
    for c in ["image_id", "name", "camera_id"] {
        if !image_columns.iter().any(|x| x == c) {
            return Err(err(format!(
                "not a COLMAP database: the table `images` has no column `{c}`"
            )));
        }
    }
    let geometry_columns = columns("two_view_geometries")?;
    for c in ["pair_id", "config"] {
        if !geometry_columns.iter().any(|x| x == c) {
            return Err(err(format!(
                "not a COLMAP database: the table `two_view_geometries` has no column `{c}`"
            )));
        }
    }
    if !geometry_columns.iter().any(|x| x == "qvec") {
        return Err(err(
            "the table `two_view_geometries` has no column `qvec`: a database of an older COLMAP, \
             which stores no relative rotations (rotations are not derived from E here); \
             run COLMAP's matcher again with a current COLMAP and --TwoViewGeometry.compute_relative_pose 1"
                .into(),
        ));
    }
    let has_tvec = geometry_columns.iter().any(|x| x == "tvec");

    // images: id -> name
    let mut names: BTreeMap<u64, String> = BTreeMap::new();
    {
        let mut stmt = conn
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
    }

    // two-view geometries
    let tvec_sql = if has_tvec {
        "typeof(tvec), CASE WHEN length(tvec) = 24 THEN tvec END"
    } else {
        "'null', NULL"
    };
    let mut stmt = conn
        .prepare(&format!(
            "SELECT pair_id, config, typeof(qvec), length(qvec), \
             CASE WHEN length(qvec) = 32 THEN qvec END, {tvec_sql} \
             FROM two_view_geometries ORDER BY pair_id"
        ))
        .map_err(sql)?;
    let mut rows = stmt.query([]).map_err(sql)?;
    let mut raw: Vec<crate::io::RawEdge> = Vec::new();
    // (pair_id, tvec) of each edge in `raw`, for --information full
    let mut poses: Vec<(i64, Option<[f64; 3]>)> = Vec::new();
    let mut warnings = Vec::new();
    let mut total = 0usize;
    let mut by_config: BTreeMap<i64, usize> = BTreeMap::new();
    let mut no_pose = 0usize;
    while let Some(row) = rows.next().map_err(sql)? {
        total += 1;
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
            *by_config.entry(config).or_default() += 1;
            continue;
        }
        if id1 == id2 {
            return Err(err(format!("{at}: a pair of an image with itself")));
        }
        let kind: String = row.get(2).map_err(sql)?;
        let len: Option<i64> = row.get(3).map_err(sql)?;
        let qvec: Option<Vec<u8>> = row.get(4).map_err(sql)?;
        let q = match (kind.as_str(), qvec) {
            ("null", _) => {
                no_pose += 1;
                continue;
            }
            ("blob", Some(bytes)) => f64s::<4>(&bytes),
            ("blob", None) if len == Some(0) => {
                no_pose += 1;
                continue;
            }
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
            no_pose += 1;
            continue;
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
        raw.push(crate::io::RawEdge {
            i: id1,
            j: id2,
            rotation,
            weight: 1.0,
        });
        poses.push((pair_id, t));
    }
    let mut information = None;
    if options.full_information && options.weights == crate::io::detect::WeightSource::File {
        let (kept, info, skipped) = two_view::informations(&conn, path, raw, &poses, &file)?;
        if kept.is_empty() && skipped.0 > 0 {
            return Err(err(format!(
                "--information full: none of the {} two-view geometries with a relative pose gives an information (first: {})",
                skipped.0, skipped.1
            )));
        }
        raw = kept;
        if skipped.0 > 0 {
            warnings.push(format!(
                "--information full: skipped {} two-view geometries whose inlier correspondences give no information (first: {})",
                skipped.0, skipped.1
            ));
        }
        information = Some(info);
    }
    let skipped_config: usize = by_config.values().sum();
    if skipped_config > 0 {
        let list: Vec<String> = by_config
            .iter()
            .map(|(c, k)| format!("{k} {} ({c})", config_name(*c)))
            .collect();
        warnings.push(format!(
            "skipped {skipped_config} of {total} two-view geometries by config: {} (only {} carry a relative rotation)",
            list.join(", "),
            accepted_list()
        ));
    }
    if no_pose > 0 {
        warnings.push(format!(
            "skipped {no_pose} of {total} two-view geometries without a stored relative pose (qvec NULL or zero, or COLMAP's default identity with zero tvec)"
        ));
    }
    if raw.is_empty() {
        return Err(err(format!(
            "no relative rotations in the COLMAP database: {total} two-view geometries, {skipped_config} skipped by config, \
             {no_pose} without a stored relative pose (COLMAP stores relative poses with \
             --TwoViewGeometry.compute_relative_pose 1; accepted configs: {})",
            accepted_list()
        )));
    }
    let (ids, edges) = crate::io::compact_edges(raw, std::iter::empty());
    let node_names = ids
        .iter()
        .map(|id| names.get(id).cloned().unwrap_or_default())
        .collect();
    let mut problem = MultipleProblem::new(ids.len(), edges).map_err(|e| e.in_file(&file, None))?;
    if let Some(info) = information {
        problem = problem
            .with_information(info)
            .map_err(|e| e.in_file(&file, None))?;
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
    })
}

/// `--information full` (`[F13]`): each edge's information from the inlier
/// correspondences of its row and the two images' cameras.
mod two_view {
    use super::*;
    use crate::io::two_view_information::{Camera, rotation_information};
    use crate::multiple::anisotropic::Information;
    use nalgebra::{Vector2, Vector3};

    /// The most keypoints or inlier matches read for one image or pair (COLMAP extracts
    /// at most 8192 SIFT features per image by default); a larger count is an error.
    const MAX_ROWS: i64 = 10_000_000;

    /// Edges kept (those with an information), their informations, and the number of
    /// edges skipped with the first reason.
    pub(super) type Informations = (Vec<crate::io::RawEdge>, Vec<Information>, (usize, String));

    pub(super) fn informations(
        conn: &Connection,
        path: &Path,
        raw: Vec<crate::io::RawEdge>,
        poses: &[(i64, Option<[f64; 3]>)],
        file: &str,
    ) -> Result<Informations> {
        let err = |msg: String| Error::parse(Some(file), None, msg);
        let sql = |e: rusqlite::Error| err(format!("SQLite: {e}"));
        let (cams, of_image) = cameras(path)?;
        let mut camera_of = BTreeMap::new();
        for c in &cams {
            let cam = Camera::from_colmap(&c.model, &c.params)
                .map_err(|m| err(format!("table `cameras`: camera {}: {m}", c.camera_id)));
            camera_of.insert(c.camera_id, cam);
        }
        let camera = |image: u64| -> Result<Camera> {
            let id = of_image
                .get(&image)
                .ok_or_else(|| err(format!("table `images`: image {image} has no camera")))?;
            match camera_of.get(id) {
                Some(Ok(c)) => Ok(*c),
                Some(Err(e)) => Err(e.clone()),
                None => Err(err(format!("table `cameras`: no camera {id}"))),
            }
        };
        let mut keypoints_stmt = conn
            .prepare(&format!(
                "SELECT rows, cols, CASE WHEN rows <= {MAX_ROWS} AND cols IN (2, 4, 6) \
                 AND length(data) = 4 * rows * cols THEN data END FROM keypoints WHERE image_id = ?1"
            ))
            .map_err(|e| err(format!("--information full needs the table `keypoints` ({e})")))?;
        let mut keypoints = |image: u64| -> Result<(usize, Vec<u8>)> {
            let mut rows = keypoints_stmt.query([image as i64]).map_err(sql)?;
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
        };
        let mut matches_stmt = conn
            .prepare(&format!(
                "SELECT rows, cols, CASE WHEN rows <= {MAX_ROWS} AND cols = 2 \
                 AND length(data) = 8 * rows THEN data END FROM two_view_geometries WHERE pair_id = ?1"
            ))
            .map_err(sql)?;
        let f32_at = |b: &[u8], k: usize| {
            f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]])
        };
        let u32_at = |b: &[u8], k: usize| {
            u32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]])
        };
        let mut kept = Vec::new();
        let mut info = Vec::new();
        let mut skipped = (0usize, String::new());
        let mut first: Option<(u64, (usize, Vec<u8>))> = None;
        for (edge, &(pair_id, tvec)) in raw.into_iter().zip(poses) {
            let at = format!(
                "two_view_geometries row pair_id {pair_id} (images {}, {})",
                edge.i, edge.j
            );
            let t = tvec.ok_or_else(|| {
                err(format!(
                    "{at}: no tvec: --information full needs the relative translation"
                ))
            })?;
            let (c1, c2) = (camera(edge.i)?, camera(edge.j)?);
            let mut rows = matches_stmt.query([pair_id]).map_err(sql)?;
            let row = rows
                .next()
                .map_err(sql)?
                .ok_or_else(|| err(format!("{at}: gone")))?;
            let n: i64 = row.get(0).map_err(sql)?;
            let data: Option<Vec<u8>> = row.get(2).map_err(sql)?;
            let Some(matches) = data else {
                if n == 0 {
                    skipped.0 += 1;
                    if skipped.1.is_empty() {
                        skipped.1 = format!("{at}: no inlier matches");
                    }
                    continue;
                }
                return Err(err(format!(
                    "{at}: the inlier matches (data) are not {n} x 2 uint32"
                )));
            };
            drop(rows);
            if first.as_ref().map(|f| f.0) != Some(edge.i) {
                first = Some((edge.i, keypoints(edge.i)?));
            }
            let (cols1, kp1) = &first.as_ref().expect("set above").1;
            let (cols2, kp2) = keypoints(edge.j)?;
            let m = matches.len() / 8;
            let (mut x1, mut x2) = (Vec::with_capacity(m), Vec::with_capacity(m));
            for k in 0..m {
                let (a, b) = (
                    u32_at(&matches, 2 * k) as usize,
                    u32_at(&matches, 2 * k + 1) as usize,
                );
                let (n1, n2) = (kp1.len() / (4 * cols1), kp2.len() / (4 * cols2));
                if a >= n1 || b >= n2 {
                    return Err(err(format!(
                        "{at}: inlier match {k} names keypoint ({a}, {b}); the images have {n1} and {n2}"
                    )));
                }
                let p1 = Vector2::new(
                    f32_at(kp1, a * cols1) as f64,
                    f32_at(kp1, a * cols1 + 1) as f64,
                );
                let p2 = Vector2::new(
                    f32_at(&kp2, b * cols2) as f64,
                    f32_at(&kp2, b * cols2 + 1) as f64,
                );
                if let (Some(u), Some(v)) = (c1.normalise(&p1), c2.normalise(&p2)) {
                    x1.push(u);
                    x2.push(v);
                }
            }
            let h = rotation_information(&edge.rotation, &Vector3::from(t), &x1, &x2, &c1, &c2)
                .and_then(|h| Information::new(h).map_err(|e| e.to_string()));
            match h {
                Ok(h) => {
                    kept.push(edge);
                    info.push(h);
                }
                Err(reason) => {
                    skipped.0 += 1;
                    if skipped.1.is_empty() {
                        skipped.1 = format!("{at}: {reason}");
                    }
                }
            }
        }
        Ok((kept, info, skipped))
    }
}

pub(super) fn cameras(path: &Path) -> Result<(Vec<ColmapCamera>, BTreeMap<u64, u32>)> {
    let file = path.display().to_string();
    let err = |msg: String| Error::parse(Some(&file), None, msg);
    let sql = |e: rusqlite::Error| err(format!("SQLite: {e}"));
    let conn = Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(sql)?;
    let mut cameras = Vec::new();
    {
        let mut stmt = conn
            .prepare(
                "SELECT camera_id, model, width, height, typeof(params), \
                 CASE WHEN length(params) <= 1024 THEN params END FROM cameras ORDER BY camera_id",
            )
            .map_err(|e| err(format!("no table `cameras` with COLMAP's columns ({e})")))?;
        let mut rows = stmt.query([]).map_err(sql)?;
        while let Some(row) = rows.next().map_err(sql)? {
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
            let params = blob
                .chunks_exact(8)
                .map(|c| {
                    let mut b = [0u8; 8];
                    b.copy_from_slice(c);
                    f64::from_le_bytes(b)
                })
                .collect();
            cameras.push(ColmapCamera {
                camera_id,
                model: name.to_string(),
                width: u64::try_from(width).unwrap_or(0),
                height: u64::try_from(height).unwrap_or(0),
                params,
            });
        }
    }
    let mut of_image = BTreeMap::new();
    let mut stmt = conn
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
        if !cameras.iter().any(|c| c.camera_id == camera) {
            return Err(err(format!(
                "table `images`: image {image} names camera {camera}, which the table `cameras` does not have"
            )));
        }
        of_image.insert(image, camera);
    }
    Ok((cameras, of_image))
}

pub(super) fn poses(path: &Path, options: &ReadOptions) -> Result<Vec<ColmapImage>> {
    let file = path.display().to_string();
    let err = |msg: String| Error::parse(Some(&file), None, msg);
    let sql = |e: rusqlite::Error| err(format!("SQLite: {e}"));
    let conn = Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(sql)?;
    let columns: Vec<String> = conn
        .prepare("PRAGMA table_info(images)")
        .and_then(|mut s| s.query_map([], |r| r.get(1))?.collect())
        .map_err(sql)?;
    let has = |c: &str| columns.iter().any(|x| x == c);
    let refuse = || {
        err(
            "a COLMAP database holds no estimated camera poses (only two-view geometries, \
             and no pose priors here): give the sparse model the mapper wrote (e.g. sparse/0, \
             or its images.bin)"
                .into(),
        )
    };
    if !["image_id", "name", "camera_id"].iter().all(|c| has(c)) {
        return Err(err(
            "not a COLMAP database: no table `images` with image_id, name, camera_id".into(),
        ));
    }
    if !["prior_qw", "prior_qx", "prior_qy", "prior_qz"]
        .iter()
        .all(|c| has(c))
    {
        return Err(refuse());
    }
    let t = if ["prior_tx", "prior_ty", "prior_tz"].iter().all(|c| has(c)) {
        "prior_tx, prior_ty, prior_tz"
    } else {
        "0.0, 0.0, 0.0"
    };
    let mut stmt = conn
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
        let get_f = |k: usize| -> Result<f64> {
            let v: Option<f64> = row.get(k).map_err(sql)?;
            Ok(v.unwrap_or(0.0))
        };
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
            *slot = get_f(3 + k)?;
        }
        if v[..4] == [0.0; 4] || v.iter().any(|x| !x.is_finite()) {
            continue; // no prior stored
        }
        images
            .push(
                image_id,
                camera_id,
                name,
                &v,
                &format!("table `images`: image {id}: prior"),
            )
            .map_err(err)?;
    }
    if images.images.is_empty() {
        return Err(refuse());
    }
    images.finish(&file, None, "no pose priors")
}

fn accepted_list() -> String {
    ACCEPTED_CONFIGS
        .iter()
        .map(|(c, n)| format!("{n} ({c})"))
        .collect::<Vec<_>>()
        .join(", ")
}
