//! COLMAP, the structure-from-motion pipeline most users run first: relative rotations from a
//! COLMAP database ([`read_colmap_database`], cargo feature `colmap`, on by default), absolute
//! rotations from a sparse model's `images.txt` / `images.bin` ([`read_images_text`],
//! [`read_images_binary`], [`load_images`]) as ground truth or initial estimate, and absolute
//! rotations written back as `images.txt` ([`write_images_text`]).
//!
//! # Conventions (`paper-notes/formats.md`, `[F12]`)
//!
//! * **Absolute poses.** An image's pose in `images.txt` (`IMAGE_ID QW QX QY QZ TX TY TZ
//!   CAMERA_ID NAME`) and `images.bin` is COLMAP's `cam_from_world`: `x_cam = R_k X + t_k`,
//!   with `R_k` the rotation of the Hamilton unit quaternion `(qw, qx, qy, qz)`. That is
//!   world-to-camera, this crate's `R_k` unchanged (as Bundler's `R`, `[F6]`).
//! * **Relative rotations.** A row of the database table `two_view_geometries` with key
//!   `pair_id` holds the geometry of the images `(image_id1, image_id2)` decoded by COLMAP's
//!   formula `pair_id = 2147483647 * image_id1 + image_id2` ([`pair_id_to_image_pair`];
//!   COLMAP stores every pair with `image_id1 < image_id2`, inverting the geometry when it
//!   swaps them). Its blob `qvec` (4 little-endian `f64`: `w, x, y, z`) is the rotation of
//!   `cam2_from_cam1`: `x_2 = R_rel x_1 + t_rel` for a point `x_1` in camera 1's frame. With
//!   noise-free poses, `x_1 = R_1 X + t_1` and `x_2 = R_2 X + t_2 = R_2 R_1^T (x_1 - t_1) + t_2`,
//!   so **`R_rel = R_2 R_1^T`** (COLMAP's own synthetic data set writes exactly
//!   `cam2_from_cam1 = image2.CamFromWorld() * Inverse(image1.CamFromWorld())`). This crate's
//!   edge `(i, j)` = `(image_id1, image_id2)` needs `R_ij R_i = R_j`, i.e. `R_ij = R_j R_i^T`:
//!   **`R_ij = R_rel`**, the stored rotation itself (no transpose, unlike 1DSfM `[F5]`).
//! * **Which rows carry a rotation.** The column `config` is COLMAP's
//!   `TwoViewGeometry::ConfigurationType`. Accepted ([`ACCEPTED_CONFIGS`]): the
//!   configurations for which COLMAP's `EstimateTwoViewGeometryPose` recovers a relative pose:
//!   `CALIBRATED` (2) and `UNCALIBRATED` (3) (from the essential matrix; for `UNCALIBRATED`
//!   with COLMAP's current intrinsics, so less reliable), `PLANAR` (4), `PANORAMIC` (5),
//!   `PLANAR_OR_PANORAMIC` (6) (from the homography), and `CALIBRATED_RIG` (9). Skipped and
//!   counted: `UNDEFINED` (0) and `DEGENERATE` (1) (no geometry), `WATERMARK` (7: a 2-D image
//!   translation, not camera motion), `MULTIPLE` (8: inliers of several models, no single
//!   pose) and unknown values. (COLMAP's own synthetic data set, written by pycolmap 4.2.1
//!   without focal-length priors, stores its exact relative poses as `UNCALIBRATED`.)
//! * **Rows without a stored pose.** COLMAP computes relative poses only when asked
//!   (`--TwoViewGeometry.compute_relative_pose 1`; off by default). Otherwise it stores the
//!   identity quaternion with a zero translation (versions that always write a pose) or a zero
//!   quaternion (versions whose pose is optional), and a pair without inliers has NULL blobs.
//!   Such rows are skipped and counted: a relative pose from an essential matrix always has a
//!   unit translation, so "identity with exactly zero translation" is never a real estimate.
//!   No rotation is derived from `E`: choosing among its two rotations needs the matches and
//!   the cameras (the cheirality test), which this reader does not redo. A database with no
//!   usable row is an error that says so. A database without the column `qvec` (older COLMAP)
//!   is an error too.
//! * **Information**: each edge gets the information of its rotation from the row's inlier
//!   matches (`data`), the two images' `keypoints` and `cameras` (`paper-notes/formats.md`
//!   `[F13]`, [`crate::io::two_view_information`]); pairs that give none are skipped with a
//!   warning. By default ([`ReadOptions::full_information`] `None`, `--information auto`) a
//!   database that cannot give it (no keypoints, no `tvec`, an unsupported camera, no pair
//!   with an information) is read with weights 1 instead, with the warning
//!   `database_without_information` naming the reason; `Some(true)` (`--information full`)
//!   makes that an error, `Some(false)` (`--information kappa`) reads weights 1 (COLMAP
//!   stores no weights; the inlier count is not a variance).
//! * **Nodes** are the image ids that occur in a used row, sorted
//!   ([`LoadedGraph::node_ids`]), with the image names of the table `images`
//!   ([`LoadedGraph::node_names`]). A used row naming an image the table `images` does not
//!   have is an error.
//!
//! Reading a database does not load it into memory: SQLite reads the pages it needs, and only
//! `images (image_id, name, camera_id)` and `two_view_geometries (pair_id, config, qvec, tvec)`
//! are selected (blobs of the wrong size are refused before they are fetched).
//! `images.bin` is read through [`crate::io::text::read_bytes`] (the size limit of every
//! input) and every count in it is checked against the bytes that remain before anything is
//! allocated.
//!
//! ```
//! use rotavg::io::colmap::{image_pair_to_pair_id, pair_id_to_image_pair, read_images_text, write_images_text};
//! use rotavg::io::detect::ReadOptions;
//! use rotavg::so3::exp;
//! use rotavg::nalgebra::Vector3;
//! assert_eq!(image_pair_to_pair_id(2, 1), 2147483647 + 2);
//! assert_eq!(pair_id_to_image_pair(2147483647 + 2), Some((1, 2)));
//! // Absolute rotations written as images.txt and read back.
//! let rotations = [exp(&Vector3::new(0.1, 0.2, 0.3)), exp(&Vector3::new(-0.4, 0.0, 0.2))];
//! let text = write_images_text(&rotations, &[3, 8], &["a.jpg".into(), "b.jpg".into()])?;
//! let images = read_images_text(&text, "images.txt", &ReadOptions::default())?;
//! assert_eq!((images[1].image_id, images[1].name.as_str()), (8, "b.jpg"));
//! assert!((images[1].rotation.matrix() - rotations[1].matrix()).norm() < 1e-15);
//! # Ok::<(), rotavg::Error>(())
//! ```

use crate::error::{Error, Result};
use crate::io::detect::{LoadedGraph, ReadOptions};
use crate::so3::Rotation;
use nalgebra::{Quaternion, UnitQuaternion};
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The first 16 bytes of every SQLite 3 database file.
pub const SQLITE_MAGIC: &[u8; 16] = b"SQLite format 3\0";

/// COLMAP's `kMaxNumImages`: the multiplier of `image_id1` in a `pair_id`.
pub const MAX_NUM_IMAGES: u64 = 2_147_483_647;

/// The `config` values of `two_view_geometries` whose rows carry a relative rotation (see the
/// module docs), with COLMAP's names.
pub const ACCEPTED_CONFIGS: [(i64, &str); 6] = [
    (2, "CALIBRATED"),
    (3, "UNCALIBRATED"),
    (4, "PLANAR"),
    (5, "PANORAMIC"),
    (6, "PLANAR_OR_PANORAMIC"),
    (9, "CALIBRATED_RIG"),
];

/// COLMAP's name of a `config` value (`UNKNOWN` for other values).
///
/// ```
/// assert_eq!(rotavg::io::colmap::config_name(1), "DEGENERATE");
/// ```
pub fn config_name(config: i64) -> &'static str {
    match config {
        0 => "UNDEFINED",
        1 => "DEGENERATE",
        2 => "CALIBRATED",
        3 => "UNCALIBRATED",
        4 => "PLANAR",
        5 => "PANORAMIC",
        6 => "PLANAR_OR_PANORAMIC",
        7 => "WATERMARK",
        8 => "MULTIPLE",
        9 => "CALIBRATED_RIG",
        _ => "UNKNOWN",
    }
}

/// COLMAP's `pair_id` of two images (the smaller id first, as COLMAP stores pairs).
///
/// ```
/// use rotavg::io::colmap::image_pair_to_pair_id;
/// assert_eq!(image_pair_to_pair_id(1, 2), image_pair_to_pair_id(2, 1));
/// ```
pub fn image_pair_to_pair_id(image_id1: u32, image_id2: u32) -> u64 {
    let (a, b) = if image_id1 > image_id2 {
        (image_id2, image_id1)
    } else {
        (image_id1, image_id2)
    };
    MAX_NUM_IMAGES * u64::from(a) + u64::from(b)
}

/// The images `(image_id1, image_id2)` of a `pair_id` (COLMAP's `PairIdToImagePair`); `None`
/// for a negative `pair_id`.
///
/// ```
/// use rotavg::io::colmap::pair_id_to_image_pair;
/// assert_eq!(pair_id_to_image_pair(3 * 2147483647 + 7), Some((3, 7)));
/// assert_eq!(pair_id_to_image_pair(-1), None);
/// ```
pub fn pair_id_to_image_pair(pair_id: i64) -> Option<(u64, u64)> {
    let p = u64::try_from(pair_id).ok()?;
    let id2 = p % MAX_NUM_IMAGES;
    Some(((p - id2) / MAX_NUM_IMAGES, id2))
}

/// `true` when the file at `path` starts with [`SQLITE_MAGIC`] (reads 16 bytes).
pub fn is_sqlite_file(path: &Path) -> bool {
    use std::io::Read;
    let mut head = [0u8; 16];
    std::fs::File::open(path)
        .and_then(|mut f| f.read_exact(&mut head))
        .is_ok()
        && &head == SQLITE_MAGIC
}

/// The COLMAP database that `path` names: the file itself when it is an SQLite file, or
/// `path/database.db` (COLMAP's default name) when `path` is a directory holding one.
///
/// ```
/// use rotavg::io::colmap::find_database;
/// assert_eq!(find_database(std::path::Path::new("no/such/dir")), None);
/// ```
pub fn find_database(path: &Path) -> Option<PathBuf> {
    if path.is_dir() {
        let db = path.join("database.db");
        return is_sqlite_file(&db).then_some(db);
    }
    is_sqlite_file(path).then(|| path.to_path_buf())
}

/// The rotation of a COLMAP quaternion `(w, x, y, z)` (Hamilton), normalised; an error
/// (`what` names the item) when it is not finite or its norm is not 1 within `tol`.
fn quaternion_rotation(q: [f64; 4], tol: f64, what: &str) -> std::result::Result<Rotation, String> {
    if q.iter().any(|v| !v.is_finite()) {
        return Err(format!(
            "{what}: quaternion (w x y z) = {q:?} is not finite"
        ));
    }
    let quat = Quaternion::new(q[0], q[1], q[2], q[3]);
    let norm = quat.norm();
    if !(norm > 1e-12 && (norm - 1.0).abs() <= tol) {
        return Err(format!(
            "{what}: quaternion (w x y z) = ({} {} {} {}) has norm {norm:.3e}, not 1 within {tol:.1e}: not a rotation",
            q[0], q[1], q[2], q[3]
        ));
    }
    Ok(UnitQuaternion::from_quaternion(quat).to_rotation_matrix())
}

/// The error of a database read in a build without the cargo feature `colmap`.
#[cfg(not(feature = "colmap"))]
pub(crate) fn without_colmap_feature(path: &Path) -> Error {
    Error::parse(
        Some(&path.display().to_string()),
        None,
        "a COLMAP database (SQLite), but rotavg was built without the cargo feature `colmap`",
    )
}

/// Read a COLMAP database (SQLite) as a view graph `[F12]`: the relative rotations of the
/// rows of `two_view_geometries` whose `config` is accepted and that store a pose, on the
/// images they name. The reader's remarks (rows skipped, by reason) are in
/// [`LoadedGraph::warnings`]. Needs the cargo feature `colmap` (on by default); without it,
/// an error says so.
///
/// ```
/// # #[cfg(feature = "colmap")] {
/// use rotavg::io::colmap::{image_pair_to_pair_id, read_colmap_database};
/// use rotavg::io::detect::ReadOptions;
/// // A database with COLMAP's tables (the columns this reader uses) and one calibrated pair.
/// let path = std::env::temp_dir().join(format!("rotavg-doc-colmap-{}.db", std::process::id()));
/// # let _ = std::fs::remove_file(&path);
/// let db = rusqlite::Connection::open(&path).unwrap();
/// db.execute_batch(
///     "CREATE TABLE images (image_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, name TEXT NOT NULL UNIQUE, camera_id INTEGER NOT NULL);
///      CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, config INTEGER NOT NULL, F BLOB, E BLOB, H BLOB, qvec BLOB, tvec BLOB);
///      INSERT INTO images VALUES (1, 'a.jpg', 1), (2, 'b.jpg', 1);",
/// ).unwrap();
/// // cam2_from_cam1: 90 degrees about z, i.e. (w, x, y, z) = (cos 45, 0, 0, sin 45).
/// let h = std::f64::consts::FRAC_1_SQRT_2;
/// let qvec: Vec<u8> = [h, 0.0, 0.0, h].iter().flat_map(|v| v.to_le_bytes()).collect();
/// let tvec: Vec<u8> = [1.0f64, 0.0, 0.0].iter().flat_map(|v| v.to_le_bytes()).collect();
/// db.execute(
///     "INSERT INTO two_view_geometries VALUES (?1, 0, 2, NULL, 2, NULL, NULL, NULL, ?2, ?3)",
///     rusqlite::params![image_pair_to_pair_id(1, 2) as i64, qvec, tvec],
/// ).unwrap();
/// drop(db);
/// let g = read_colmap_database(&path, &ReadOptions::default());
/// std::fs::remove_file(&path).unwrap();
/// let g = g?;
/// assert_eq!((g.node_ids.clone(), g.node_names.clone()), (vec![1, 2], vec!["a.jpg".to_string(), "b.jpg".into()]));
/// // R_01 = cam2_from_cam1: it maps the x axis of camera 1's frame to y.
/// let r = g.problem.edges()[0].rotation;
/// assert!((r * rotavg::nalgebra::Vector3::x() - rotavg::nalgebra::Vector3::y()).norm() < 1e-15);
/// # }
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_colmap_database(path: &Path, options: &ReadOptions) -> Result<LoadedGraph> {
    options.check()?;
    #[cfg(feature = "colmap")]
    {
        database::read(path, options)
    }
    #[cfg(not(feature = "colmap"))]
    {
        let _ = options;
        Err(without_colmap_feature(path))
    }
}

#[cfg(feature = "colmap")]
pub(crate) mod database;
#[cfg(feature = "colmap")]
pub mod scene;

/// One image of a COLMAP sparse model (`images.txt` / `images.bin`).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ColmapImage {
    /// COLMAP's `image_id`.
    pub image_id: u32,
    /// The image's name (file path relative to COLMAP's image folder).
    pub name: String,
    /// COLMAP's `camera_id`.
    pub camera_id: u32,
    /// World-to-camera rotation (COLMAP's `cam_from_world`): this crate's `R_k`.
    #[serde(with = "crate::so3::serde_rows::rotation")]
    pub rotation: Rotation,
    /// COLMAP's `cam_from_world` translation, as written: NaN where the writer had none
    /// (pycolmap's rotation averaging writes NaN translations; no rotation uses them).
    pub translation: [f64; 3],
}

/// The images of an `images.txt` or `images.bin` as they are read: each checked as it comes
/// (its quaternion), the whole list at the end (not empty, no repeated id or name).
struct ImageList {
    images: Vec<ColmapImage>,
    /// [`ReadOptions::quaternion_tolerance`].
    tol: f64,
}

impl ImageList {
    /// An empty list with room for `capacity` images.
    fn with_capacity(capacity: usize, options: &ReadOptions) -> Self {
        ImageList {
            images: Vec::with_capacity(capacity),
            tol: options.quaternion_tolerance,
        }
    }

    /// Add the image of a record, whose `v` is `qw qx qy qz tx ty tz`, the quaternion checked
    /// against the tolerance; `Err` names `what`.
    fn push(
        &mut self,
        image_id: u32,
        camera_id: u32,
        name: String,
        v: &[f64; 7],
        what: &str,
    ) -> std::result::Result<(), String> {
        self.images.push(ColmapImage {
            image_id,
            name,
            camera_id,
            rotation: quaternion_rotation([v[0], v[1], v[2], v[3]], self.tol, what)?,
            translation: [v[4], v[5], v[6]],
        });
        Ok(())
    }

    /// The images of `file`; an error `none` (at `line`) when there are none, or naming a
    /// repeated image id or name.
    fn finish(self, file: &str, line: Option<usize>, none: &str) -> Result<Vec<ColmapImage>> {
        if self.images.is_empty() {
            return Err(Error::parse(Some(file), line, none));
        }
        reject_repeated_images(&self.images, file)?;
        Ok(self.images)
    }
}

/// A sparse model names each image once: a repeated `image_id` or name would make the match to
/// the graph's nodes depend on the order of the file.
fn reject_repeated_images(images: &[ColmapImage], file: &str) -> Result<()> {
    let mut ids = std::collections::BTreeSet::new();
    let mut names = std::collections::BTreeSet::new();
    for im in images {
        if !ids.insert(im.image_id) {
            return Err(Error::parse(
                Some(file),
                None,
                format!("image_id {} appears more than once", im.image_id),
            ));
        }
        if !names.insert(im.name.as_str()) {
            return Err(Error::parse(
                Some(file),
                None,
                format!("image name `{}` appears more than once", im.name),
            ));
        }
    }
    Ok(())
}

/// What a COLMAP project or model folder holds for absolute rotations ([`find_model_images`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ModelFile {
    /// A sparse model's `images.bin` or `images.txt`.
    Images(PathBuf),
    /// A database (`database.db`) and no model.
    Database(PathBuf),
}

/// The file of absolute rotations in the folder `dir`: a sparse model's `images.bin` (COLMAP's
/// and GLOMAP's default), else its `images.txt`, else a `database.db`. A folder holding model
/// folders (`sparse/` with `0/`, `1/`) or nothing usable is an error that says what to give.
///
/// ```
/// use rotavg::io::colmap::{find_model_images, ModelFile};
/// let dir = std::env::temp_dir().join(format!("rotavg-doc-find-model-{}", std::process::id()));
/// std::fs::create_dir_all(dir.join("0")).unwrap();
/// std::fs::write(dir.join("0/images.txt"), "").unwrap();
/// let err = find_model_images(&dir).unwrap_err().to_string();
/// let found = find_model_images(&dir.join("0"));
/// std::fs::remove_dir_all(&dir).unwrap();
/// assert!(err.contains("holds the sparse models 0"), "{err}");
/// assert!(matches!(found?, ModelFile::Images(p) if p.ends_with("images.txt")));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn find_model_images(dir: &Path) -> Result<ModelFile> {
    for name in ["images.bin", "images.txt"] {
        let f = dir.join(name);
        if f.is_file() {
            return Ok(ModelFile::Images(f));
        }
    }
    if let Some(db) = find_database(dir) {
        return Ok(ModelFile::Database(db));
    }
    let mut models: Vec<String> = std::fs::read_dir(dir)
        .map_err(|e| Error::Io {
            path: dir.display().to_string(),
            message: e.to_string(),
        })?
        .filter_map(|e| e.ok())
        .filter(|e| {
            let p = e.path();
            p.join("images.bin").is_file() || p.join("images.txt").is_file()
        })
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    models.sort();
    let message = if models.is_empty() {
        "a folder without images.bin, images.txt or database.db: give a COLMAP sparse model \
         folder (e.g. sparse/0) or one of its images files"
            .to_string()
    } else {
        format!(
            "the folder holds the sparse models {}: give one of them (e.g. {})",
            models.join(", "),
            dir.join(&models[0]).display()
        )
    };
    Err(Error::parse(
        Some(&dir.display().to_string()),
        None,
        message,
    ))
}

/// An error for the other files of a sparse model (`cameras.*`, `points3D.*`, `frames.*`,
/// `rigs.*`), which hold no image rotations: "give images.bin / images.txt or the folder".
pub fn refuse_other_model_file(file: &str) -> Result<()> {
    let base = Path::new(file)
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    for stem in ["cameras", "points3d", "frames", "rigs"] {
        if base == format!("{stem}.bin") || base == format!("{stem}.txt") {
            return Err(Error::parse(
                Some(file),
                None,
                "this file of a COLMAP sparse model holds no image poses: give the model's \
                 images.bin / images.txt, or the model folder",
            ));
        }
    }
    Ok(())
}

/// Absolute rotations stored in a COLMAP database: the pose priors `prior_qw .. prior_qz` of
/// the table `images` (COLMAP before 3.9), for the images that have one (with `image_id`,
/// `name`, `camera_id`; translations from `prior_tx ..` when present). A database stores no
/// estimated poses, only two-view geometries: without pose priors this is an error saying to
/// give the sparse model the mapper wrote (`sparse/0`). Needs the cargo feature `colmap`.
pub fn read_database_poses(path: &Path, options: &ReadOptions) -> Result<Vec<ColmapImage>> {
    #[cfg(feature = "colmap")]
    {
        database::poses(path, options)
    }
    #[cfg(not(feature = "colmap"))]
    {
        let _ = options;
        Err(without_colmap_feature(path))
    }
}

/// `true` when `file` / `text` look like a COLMAP `images.txt`: the file name ends in
/// `images.txt`, or the text starts with COLMAP's header `# Image list with two lines of data
/// per image`.
///
/// ```
/// use rotavg::io::colmap::is_images_text;
/// assert!(is_images_text("sparse/0/images.txt", ""));
/// assert!(is_images_text("-", "# Image list with two lines of data per image:\n"));
/// assert!(!is_images_text("EGs.txt", "0 1 1 0 0 0 1 0 0 0 1"));
/// ```
pub fn is_images_text(file: &str, text: &str) -> bool {
    file.to_ascii_lowercase().ends_with("images.txt")
        || text
            .trim_start()
            .starts_with("# Image list with two lines of data per image")
}

/// `true` when `file` names a COLMAP binary model file (`.bin`).
pub fn is_images_binary(file: &str) -> bool {
    file.to_ascii_lowercase().ends_with(".bin")
}

/// Read a COLMAP `images.txt` `[F12]`: after `#` comments and blank lines, each image is one
/// line `IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME` followed by one line of 2-D points
/// (`X Y POINT3D_ID` triples; possibly empty; not read). The quaternion must be a unit one
/// within `options.quaternion_tolerance` (then normalised); errors name the file and line.
///
/// ```
/// use rotavg::io::colmap::read_images_text;
/// use rotavg::io::detect::ReadOptions;
/// let text = "# Image list with two lines of data per image:\n1 1 0 0 0 0 0 0 1 a.jpg\n\n2 0 0 0 1 0 0 0 1 b.jpg\n10 20 -1\n";
/// let images = read_images_text(text, "images.txt", &ReadOptions::default())?;
/// assert_eq!(images.len(), 2);
/// assert!((images[1].rotation.angle() - std::f64::consts::PI).abs() < 1e-15);
/// let err = read_images_text("1 0 0 0 0 0 0 0 1 a.jpg\n\n", "images.txt", &ReadOptions::default());
/// assert!(err.unwrap_err().to_string().starts_with("images.txt:1: "));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_images_text(text: &str, file: &str, options: &ReadOptions) -> Result<Vec<ColmapImage>> {
    let mut images = ImageList::with_capacity(0, options);
    let mut lines = text.lines().enumerate().map(|(k, l)| (k + 1, l.trim()));
    while let Some((ln, line)) = lines.next() {
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let perr = |msg: String| Error::parse(Some(file), Some(ln), msg);
        let toks: Vec<&str> = line.split_whitespace().collect();
        if toks.len() < 10 {
            return Err(perr(format!(
                "expected IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME (10 tokens), found {}",
                toks.len()
            )));
        }
        let id = |k: usize, what: &str| -> Result<u32> {
            toks[k].parse::<u32>().map_err(|_| {
                perr(format!(
                    "{what}: `{}` is not an id (an integer in 0..2^32)",
                    toks[k]
                ))
            })
        };
        let image_id = id(0, "IMAGE_ID")?;
        let mut v = [0.0; 7];
        for (k, what) in ["QW", "QX", "QY", "QZ", "TX", "TY", "TZ"]
            .iter()
            .enumerate()
        {
            // translations (k >= 4) are kept as written, NaN included (no rotation uses them)
            v[k] = toks[k + 1]
                .parse::<f64>()
                .ok()
                .filter(|x| k >= 4 || x.is_finite())
                .ok_or_else(|| perr(format!("{what}: `{}` is not a finite number", toks[k + 1])))?;
        }
        let camera_id = id(8, "CAMERA_ID")?;
        // the name is the rest of the line (COLMAP writes names without spaces)
        let name = toks[9..].join(" ");
        images
            .push(image_id, camera_id, name, &v, &format!("image {image_id}"))
            .map_err(perr)?;
        // the points line that follows every image line: empty or `X Y POINT3D_ID` triples
        // (a second image line here would otherwise be skipped without a word)
        if let Some((pln, points)) = lines.next() {
            let toks: Vec<&str> = points.split_whitespace().collect();
            if !toks.len().is_multiple_of(3) || toks.iter().any(|t| t.parse::<f64>().is_err()) {
                return Err(Error::parse(
                    Some(file),
                    Some(pln),
                    format!(
                        "expected the 2-D points line of image {image_id} (empty, or X Y POINT3D_ID triples): every image line is followed by one"
                    ),
                ));
            }
        }
    }
    let last = Some(crate::io::last_line(text));
    images.finish(file, last, "no image lines in the COLMAP images.txt")
}

/// Read a COLMAP `images.bin` `[F12]` (little-endian): `u64` number of images, then per image
/// `u32 image_id`, 4 `f64` `qw qx qy qz`, 3 `f64` `tx ty tz`, `u32 camera_id`, the name
/// terminated by a NUL byte, `u64` number of 2-D points and 24 bytes per point (`f64 x, f64 y,
/// u64 point3D_id`; skipped). Every count is checked against the bytes that remain before
/// anything is allocated; errors name the file and the byte offset.
///
/// ```
/// use rotavg::io::colmap::read_images_binary;
/// use rotavg::io::detect::ReadOptions;
/// // One image, id 5, identity rotation, camera 1, name "a.jpg", no points.
/// let mut b = 1u64.to_le_bytes().to_vec();
/// b.extend(5u32.to_le_bytes());
/// for v in [1.0f64, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0] { b.extend(v.to_le_bytes()); }
/// b.extend(1u32.to_le_bytes());
/// b.extend(b"a.jpg\0");
/// b.extend(0u64.to_le_bytes());
/// let images = read_images_binary(&b, "images.bin", &ReadOptions::default())?;
/// assert_eq!((images[0].image_id, images[0].name.as_str()), (5, "a.jpg"));
/// // A header claiming 10^12 images in a file of 8 bytes is refused without allocating.
/// let err = read_images_binary(&1_000_000_000_000u64.to_le_bytes(), "images.bin", &ReadOptions::default());
/// assert!(err.unwrap_err().to_string().contains("claims 1000000000000 images"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_images_binary(
    bytes: &[u8],
    file: &str,
    options: &ReadOptions,
) -> Result<Vec<ColmapImage>> {
    /// The fewest bytes one image takes: id, 7 doubles, camera, an empty name's NUL, count.
    const MIN_IMAGE_BYTES: u64 = 4 + 7 * 8 + 4 + 1 + 8;
    let mut r = Bytes {
        bytes,
        pos: 0,
        file,
    };
    let n = r.u64("the number of images")?;
    let remaining = r.remaining() as u64;
    if n > remaining / MIN_IMAGE_BYTES {
        return Err(r.err(format!(
            "the header claims {n} images, but the {remaining} bytes that follow hold at most {} (an image takes at least {MIN_IMAGE_BYTES} bytes): truncated or not an images.bin",
            remaining / MIN_IMAGE_BYTES
        )));
    }
    // n is now bounded by the file size
    let mut images = ImageList::with_capacity(n as usize, options);
    for k in 0..n {
        let start = r.pos;
        let image_id = r.u32(&format!("image {k}: image_id"))?;
        let mut v = [0.0; 7];
        let names = ["qw", "qx", "qy", "qz", "tx", "ty", "tz"];
        for (c, (slot, what)) in v.iter_mut().zip(names).enumerate() {
            let what = format!("image {k} (id {image_id}): {what}");
            // translations (c >= 4) are kept as written, NaN included (no rotation uses them)
            *slot = if c >= 4 {
                f64::from_le_bytes(r.take::<8>(&what)?)
            } else {
                r.f64(&what)?
            };
        }
        let camera_id = r.u32(&format!("image {k} (id {image_id}): camera_id"))?;
        let name = r.name(&format!("image {k} (id {image_id}): name"))?;
        let points = r.u64(&format!("image {k} (id {image_id}): number of 2-D points"))?;
        let left = r.remaining() as u64;
        if points > left / 24 {
            return Err(r.err(format!(
                "image {k} (id {image_id}): {points} 2-D points need {} bytes, only {left} remain: truncated",
                u128::from(points) * 24
            )));
        }
        r.pos += (points * 24) as usize;
        let what = format!("image {k} (id {image_id})");
        images
            .push(image_id, camera_id, name, &v, &what)
            .map_err(|m| Error::parse(Some(file), None, format!("byte {start}: {m}")))?;
    }
    if r.remaining() > 0 {
        return Err(r.err(format!(
            "{} bytes after the last of the {n} images: not an images.bin",
            r.remaining()
        )));
    }
    images.finish(file, None, "no images in the COLMAP images.bin")
}

/// A cursor over the bytes of a binary file, with errors naming the file and byte offset.
struct Bytes<'a> {
    bytes: &'a [u8],
    pos: usize,
    file: &'a str,
}

impl Bytes<'_> {
    fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    fn err(&self, msg: String) -> Error {
        Error::parse(Some(self.file), None, format!("byte {}: {msg}", self.pos))
    }

    fn take<const N: usize>(&mut self, what: &str) -> Result<[u8; N]> {
        let Some(slice) = self.bytes.get(self.pos..self.pos + N) else {
            return Err(self.err(format!(
                "{what}: needs {N} bytes, only {} remain: truncated",
                self.remaining()
            )));
        };
        let mut out = [0u8; N];
        out.copy_from_slice(slice);
        self.pos += N;
        Ok(out)
    }

    fn u64(&mut self, what: &str) -> Result<u64> {
        self.take::<8>(what).map(u64::from_le_bytes)
    }

    fn u32(&mut self, what: &str) -> Result<u32> {
        self.take::<4>(what).map(u32::from_le_bytes)
    }

    fn f64(&mut self, what: &str) -> Result<f64> {
        let v = f64::from_le_bytes(self.take::<8>(what)?);
        if !v.is_finite() {
            return Err(self.err(format!("{what}: {v} is not finite")));
        }
        Ok(v)
    }

    fn name(&mut self, what: &str) -> Result<String> {
        let rest = &self.bytes[self.pos..];
        let Some(end) = rest.iter().position(|&b| b == 0) else {
            return Err(self.err(format!("{what}: no terminating NUL byte: truncated")));
        };
        let name = std::str::from_utf8(&rest[..end])
            .map_err(|_| self.err(format!("{what}: not UTF-8")))?
            .to_string();
        self.pos += end + 1;
        Ok(name)
    }
}

/// Read a COLMAP `images.txt` or `images.bin` from `path` (binary when the name ends in
/// `.bin`), through the size limit of [`crate::io::text`].
///
/// ```
/// use rotavg::io::colmap::load_images;
/// use rotavg::io::detect::ReadOptions;
/// let err = load_images("no/such/images.bin", &ReadOptions::default()).unwrap_err();
/// assert!(err.to_string().contains("no/such/images.bin"));
/// ```
pub fn load_images(path: &str, options: &ReadOptions) -> Result<Vec<ColmapImage>> {
    if is_images_binary(path) {
        read_images_binary(&crate::io::text::read_bytes(path)?, path, options)
    } else {
        read_images_text(&crate::io::text::read_text(path)?, path, options)
    }
}

/// The rotation of each node of `graph` from a COLMAP model (`None` where the model has no
/// image for the node): matched by image name when the graph has names
/// ([`LoadedGraph::node_names`], e.g. read from a COLMAP database), otherwise by image id
/// (the graph's file ids).
///
/// ```
/// use rotavg::io::colmap::{read_images_text, rotations_for_nodes};
/// use rotavg::io::detect::{read_graph, GraphFormat, ReadOptions};
/// let graph = read_graph("3 7 1 0 0 0 1 0 0 0 1\n", "EGs.txt", GraphFormat::Auto, &ReadOptions::default())?;
/// let model = read_images_text("7 1 0 0 0 0 0 0 1 x.jpg\n\n", "images.txt", &ReadOptions::default())?;
/// let truth = rotations_for_nodes(&model, &graph);
/// assert!(truth[0].is_none() && truth[1].is_some());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn rotations_for_nodes(images: &[ColmapImage], graph: &LoadedGraph) -> Vec<Option<Rotation>> {
    if graph.node_names.len() == graph.node_ids.len() && !graph.node_names.is_empty() {
        let by_name: BTreeMap<&str, Rotation> = images
            .iter()
            .map(|im| (im.name.as_str(), im.rotation))
            .collect();
        graph
            .node_names
            .iter()
            .map(|n| by_name.get(n.as_str()).copied())
            .collect()
    } else {
        let by_id: BTreeMap<u64, Rotation> = images
            .iter()
            .map(|im| (u64::from(im.image_id), im.rotation))
            .collect();
        graph
            .node_ids
            .iter()
            .map(|id| by_id.get(id).copied())
            .collect()
    }
}

/// The text of a COLMAP `images.txt` holding absolute rotations `[F12]`: node `k` is image
/// `node_ids[k]` (which must fit COLMAP's 32-bit `image_id`) named `node_names[k]` (the id
/// when `node_names` is empty), with `qvec` the world-to-camera rotation `rotations[k]`
/// (`qw >= 0`), `tvec` 0 (translations are not estimated: a comment says so), `CAMERA_ID` 1
/// and an empty points line. [`read_images_text`] reads it back.
///
/// ```
/// use rotavg::io::colmap::write_images_text;
/// let text = write_images_text(&[rotavg::Rotation::identity()], &[4], &[])?;
/// assert!(text.contains("\n4 1 0 0 0 0 0 0 1 4\n\n"));
/// assert!(write_images_text(&[rotavg::Rotation::identity()], &[1 << 40], &[]).is_err());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn write_images_text(
    rotations: &[Rotation],
    node_ids: &[u64],
    node_names: &[String],
) -> Result<String> {
    write_images_text_with_cameras(rotations, node_ids, node_names, &[])
}

/// [`write_images_text`] with each image's `CAMERA_ID` (`camera_ids[k]` for node `k`; all 1
/// when `camera_ids` is empty).
///
/// ```
/// use rotavg::io::colmap::{read_images_text, write_images_text_with_cameras};
/// use rotavg::io::detect::ReadOptions;
/// let text = write_images_text_with_cameras(&[rotavg::Rotation::identity()], &[4], &[], &[7])?;
/// let images = read_images_text(&text, "images.txt", &ReadOptions::default())?;
/// assert_eq!((images[0].image_id, images[0].camera_id), (4, 7));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn write_images_text_with_cameras(
    rotations: &[Rotation],
    node_ids: &[u64],
    node_names: &[String],
    camera_ids: &[u32],
) -> Result<String> {
    let bad = |reason: String| Error::InvalidSettings {
        name: "output".into(),
        reason,
    };
    if node_ids.len() != rotations.len()
        || (!node_names.is_empty() && node_names.len() != rotations.len())
        || (!camera_ids.is_empty() && camera_ids.len() != rotations.len())
    {
        return Err(bad(format!(
            "{} rotations, {} node ids and {} names: one of each per node",
            rotations.len(),
            node_ids.len(),
            node_names.len()
        )));
    }
    let mut s = String::new();
    s.push_str("# Image list with two lines of data per image:\n");
    s.push_str("#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n");
    s.push_str("#   POINTS2D[] as (X, Y, POINT3D_ID)\n");
    let _ = writeln!(
        s,
        "# Number of images: {}, mean observations per image: 0",
        rotations.len()
    );
    s.push_str(if camera_ids.is_empty() {
        "# Written by rotavg: rotations only (QW QX QY QZ = world-to-camera, COLMAP's cam_from_world); \
         translations are not estimated (TX TY TZ = 0), CAMERA_ID is 1, no 2-D points.\n"
    } else {
        "# Written by rotavg: rotations only (QW QX QY QZ = world-to-camera, COLMAP's cam_from_world); \
         translations are not estimated (TX TY TZ = 0), cameras of the input, no 2-D points.\n"
    });
    for (k, r) in rotations.iter().enumerate() {
        let id = u32::try_from(node_ids[k]).map_err(|_| {
            bad(format!(
                "node {k} has id {}, larger than COLMAP's 32-bit image_id",
                node_ids[k]
            ))
        })?;
        let name = match node_names.get(k) {
            Some(n) if !n.is_empty() => n.clone(),
            _ => id.to_string(),
        };
        if name.contains(['\n', '\r']) {
            return Err(bad(format!(
                "node {k}: the name {name:?} holds a line break"
            )));
        }
        let q = UnitQuaternion::from_rotation_matrix(r);
        let q = if q.w < 0.0 {
            -q.into_inner()
        } else {
            q.into_inner()
        };
        let _ = writeln!(
            s,
            "{id} {} {} {} {} 0 0 0 {} {name}\n",
            q.w + 0.0,
            q.i + 0.0,
            q.j + 0.0,
            q.k + 0.0,
            camera_ids.get(k).copied().unwrap_or(1)
        );
    }
    Ok(s)
}

/// A camera of a COLMAP model (a line of `cameras.txt`).
#[derive(Debug, Clone, PartialEq)]
pub struct ColmapCamera {
    /// COLMAP's `camera_id`.
    pub camera_id: u32,
    /// The model's name (`PINHOLE`, `SIMPLE_RADIAL`, ...).
    pub model: String,
    /// Image width, pixels.
    pub width: u64,
    /// Image height, pixels.
    pub height: u64,
    /// The model's parameters.
    pub params: Vec<f64>,
}

/// COLMAP's camera models: `(model id, name, number of parameters)` (`colmap/sensor/models.h`).
pub const CAMERA_MODELS: [(i64, &str, usize); 12] = [
    (0, "SIMPLE_PINHOLE", 3),
    (1, "PINHOLE", 4),
    (2, "SIMPLE_RADIAL", 4),
    (3, "RADIAL", 5),
    (4, "OPENCV", 8),
    (5, "OPENCV_FISHEYE", 8),
    (6, "FULL_OPENCV", 12),
    (7, "FOV", 5),
    (8, "SIMPLE_RADIAL_FISHEYE", 4),
    (9, "RADIAL_FISHEYE", 5),
    (10, "THIN_PRISM_FISHEYE", 12),
    (11, "RAD_TAN_THIN_PRISM_FISHEYE", 16),
];

/// The placeholder camera of a model written for an input without cameras (1DSfM, g2o, JSON):
/// camera 1, `SIMPLE_PINHOLE`, 1 x 1 pixels, `f = 1`, principal point `(0.5, 0.5)`. It makes
/// the folder a loadable sparse model; it is not a calibration.
pub fn placeholder_camera() -> ColmapCamera {
    ColmapCamera {
        camera_id: 1,
        model: "SIMPLE_PINHOLE".into(),
        width: 1,
        height: 1,
        params: vec![1.0, 0.5, 0.5],
    }
}

/// The cameras of a COLMAP database and the camera of each image: `(cameras, image_id ->
/// camera_id)`. A model id COLMAP does not define, or a parameter blob of the wrong size, is an
/// error. Needs the cargo feature `colmap`.
pub fn read_database_cameras(path: &Path) -> Result<(Vec<ColmapCamera>, BTreeMap<u64, u32>)> {
    #[cfg(feature = "colmap")]
    {
        database::read_cameras(path)
    }
    #[cfg(not(feature = "colmap"))]
    {
        Err(Error::parse(
            Some(&path.display().to_string()),
            None,
            "a COLMAP database (SQLite), but rotavg was built without the cargo feature `colmap`",
        ))
    }
}

/// The text of a COLMAP `cameras.txt`.
///
/// ```
/// use rotavg::io::colmap::{placeholder_camera, write_cameras_text};
/// assert!(write_cameras_text(&[placeholder_camera()]).ends_with("\n1 SIMPLE_PINHOLE 1 1 1 0.5 0.5\n"));
/// ```
pub fn write_cameras_text(cameras: &[ColmapCamera]) -> String {
    let mut s = String::from(
        "# Camera list with one line of data per camera:\n#   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n",
    );
    let _ = writeln!(s, "# Number of cameras: {}", cameras.len());
    for c in cameras {
        let params: Vec<String> = c.params.iter().map(|p| p.to_string()).collect();
        let _ = writeln!(
            s,
            "{} {} {} {} {}",
            c.camera_id,
            c.model,
            c.width,
            c.height,
            params.join(" ")
        );
    }
    s
}

/// The text of an empty COLMAP `points3D.txt` (a model of poses only).
pub fn empty_points3d_text() -> &'static str {
    "# 3D point list with one line of data per point:\n\
     #   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n\
     # Number of points: 0, mean track length: 0\n"
}

/// Write a COLMAP sparse model of absolute rotations into the folder `dir` (which must exist):
/// `images.txt` ([`write_images_text_with_cameras`]; the file name `images` when given, e.g. a
/// path ending in `images.txt`), `cameras.txt` (`cameras`, or [`placeholder_camera`] when
/// `None`) and an empty `points3D.txt`. I/O errors name the file.
///
/// ```
/// use rotavg::io::colmap::{load_images, write_sparse_model};
/// use rotavg::io::detect::ReadOptions;
/// let dir = std::env::temp_dir().join(format!("rotavg-doc-model-out-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// write_sparse_model(&dir, &dir.join("images.txt"), &[rotavg::Rotation::identity()], &[3], &["a.jpg".into()], None)?;
/// let images = load_images(dir.join("images.txt").to_str().unwrap(), &ReadOptions::default());
/// let cameras = std::fs::read_to_string(dir.join("cameras.txt")).unwrap();
/// assert!(dir.join("points3D.txt").is_file());
/// std::fs::remove_dir_all(&dir).unwrap();
/// assert_eq!(images?[0].name, "a.jpg");
/// assert!(cameras.contains("1 SIMPLE_PINHOLE"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn write_sparse_model(
    dir: &Path,
    images: &Path,
    rotations: &[Rotation],
    node_ids: &[u64],
    node_names: &[String],
    cameras: Option<(&[ColmapCamera], &[u32])>,
) -> Result<()> {
    let (cams, camera_ids): (Vec<ColmapCamera>, &[u32]) = match cameras {
        Some((c, ids)) => (c.to_vec(), ids),
        None => (vec![placeholder_camera()], &[]),
    };
    let write = |path: &Path, text: &str| {
        std::fs::write(path, text).map_err(|e| Error::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        })
    };
    let images_text = write_images_text_with_cameras(rotations, node_ids, node_names, camera_ids)?;
    let mut cameras_text = write_cameras_text(&cams);
    if cameras.is_none() {
        cameras_text.insert_str(
            0,
            "# Written by rotavg: a placeholder camera (the input has no camera models), not a calibration.\n",
        );
    }
    write(images, &images_text)?;
    write(&dir.join("cameras.txt"), &cameras_text)?;
    write(&dir.join("points3D.txt"), empty_points3d_text())
}
