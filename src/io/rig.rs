//! Rigs of any number of sensors read from files (`paper-notes/formats.md` `[F17]`): the JSON
//! rig format and a COLMAP database's rig configuration, as a [`RigProblem`] with the files'
//! ids; and the estimate written back.
//!
//! The JSON rig format (`rotavg rig FILE`):
//!
//! ```text
//! {"num_frames": F,
//!  "sensors": [{"sensor_from_rig": S} | {}, ...],        // S known, or unknown
//!  "images": [{"frame": f, "sensor": s}, ...],
//!  "edges": [{"i": a, "j": b, "rotation": R, "weight": w}, ...]}   // between images
//! ```
//!
//! An edge may carry `"information": H` (a symmetric positive semidefinite 3x3 array for the
//! residual `e` of `X_b X_a^T = R exp([e]x)`, contract section 1) instead of its weight; when one
//! does, the rig is anisotropic and an edge with a weight `w` has `H = w I`
//! (`paper-notes/conjugate.md` `[H24]`). `--weights unit` ([`WeightSource::Unit`](crate::io::detect::WeightSource::Unit)) reads every
//! edge with weight 1 and no information, as the JSON view graph reader does; with
//! `--information full` too it is refused ([`ReadOptions::check`]).
//!
//! with `R X_a ~ X_b`, `X_a = S_{s_a} F_{f_a}` (world-to-camera; `S` is `sensor_from_rig`, as
//! COLMAP's). A sensor without a known `S` is estimated; a rig without any known sensor has its
//! first sensor held at the identity (COLMAP's reference sensor).

use crate::error::{Error, Result};
use crate::io::detect::ReadOptions;
use crate::io::json::EdgeFile;
use crate::rig::{Image, RigProblem, Sensor};
use crate::so3::{Rotation, rotation_from_rows, rotation_to_rows};
use crate::warning::Warning;
use serde::{Deserialize, Serialize};
use std::path::Path;

type Rows = [[f64; 3]; 3];

/// [`LoadedRig::format`] of two view graphs read as the rig of two sensors they describe
/// (`crate::report::rig_two_graphs`): its estimate is written as theirs
/// ([`crate::io::json::write_rig_json`]).
pub const TWO_GRAPHS_FORMAT: &str = "two view graphs";

/// A rig read from a file, with the file's ids.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoadedRig {
    /// The validated problem.
    pub problem: RigProblem,
    /// The file's id of each frame (COLMAP's `frame_id`; the index in a JSON file).
    pub frame_ids: Vec<u64>,
    /// The file's id of each sensor (COLMAP's `camera_id`; the index in a JSON file).
    pub sensor_ids: Vec<u64>,
    /// The file's id of each image (COLMAP's `image_id`; the index in a JSON file).
    pub image_ids: Vec<u64>,
    /// Each image's name (COLMAP's; none in a JSON file): keys of gravity priors.
    #[serde(default)]
    pub image_names: Vec<String>,
    /// `"json"`, `"colmap"` or [`TWO_GRAPHS_FORMAT`].
    pub format: String,
    /// Gravity priors given to a rig whose sensors are estimated: applied once they are
    /// (calibrated without the priors, refined by soft ones, then held; `[G14]`, `[G15]`,
    /// [`Self::with_gravity`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pending_gravity: Option<crate::multiple::gravity::GravityPriors>,
    /// The reader's remarks.
    pub warnings: Vec<Warning>,
}

impl LoadedRig {
    /// The rig with gravity priors on its images ([`RigProblem::with_gravity`], `[G14]`), the
    /// reader's `warnings` added to its own. With sensors to estimate, the priors wait in
    /// [`Self::pending_gravity`] (checked for their count now) until a calibration holds them.
    pub fn with_gravity(
        mut self,
        priors: crate::multiple::gravity::GravityPriors,
        warnings: Vec<Warning>,
    ) -> Result<Self> {
        if self.problem.all_held() {
            self.problem = self.problem.with_gravity(priors)?;
        } else {
            let images = self.problem.images().len();
            if priors.len() != images {
                return Err(Error::InvalidSettings {
                    name: "gravity".into(),
                    reason: format!(
                        "{} gravity entries for a rig of {images} images (one per image)",
                        priors.len()
                    ),
                });
            }
            self.pending_gravity = Some(priors);
        }
        self.warnings.extend(warnings);
        Ok(self)
    }
}

#[derive(Deserialize)]
#[serde(
    deny_unknown_fields,
    expecting = "a JSON rig {\"num_frames\": F, \"sensors\": [...], \"images\": [{\"frame\": f, \"sensor\": s}, ...], \"edges\": [...]}"
)]
struct RigFile {
    num_frames: usize,
    sensors: Vec<SensorFile>,
    images: Vec<Image>,
    edges: Vec<EdgeFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SensorFile {
    #[serde(default)]
    sensor_from_rig: Option<Rows>,
}

/// Read the JSON rig format (module docs) from `text` (of `file`). Errors name the file (and
/// the line of a syntax error): a rotation off SO(3) beyond `options.rotation_tolerance`, a
/// weight out of range, more frames than images, any error of [`RigProblem::new`].
///
/// ```
/// use rotavg::io::{detect::ReadOptions, rig::read_rig_json};
/// let text = r#"{"num_frames": 2, "sensors": [{}, {}],
///   "images": [{"frame": 0, "sensor": 0}, {"frame": 1, "sensor": 0}, {"frame": 1, "sensor": 1}],
///   "edges": [{"i": 0, "j": 1, "rotation": [[1,0,0],[0,1,0],[0,0,1]]},
///             {"i": 1, "j": 2, "rotation": [[0,-1,0],[1,0,0],[0,0,1]]}]}"#;
/// let rig = read_rig_json(text, "rig.json", &ReadOptions::default())?;
/// assert_eq!(rig.problem.images().len(), 3);
/// assert!(rig.problem.held()[1].is_none()); // sensor 1 is estimated
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_rig_json(text: &str, file: &str, options: &ReadOptions) -> Result<LoadedRig> {
    options.check()?;
    let rf: RigFile = serde_json::from_str(text).map_err(|e| {
        let line = (e.line() > 0).then_some(e.line());
        Error::parse(Some(file), line, format!("invalid JSON: {e}"))
    })?;
    let in_file = |e: Error| e.in_file(file, None);
    if rf.num_frames > rf.images.len() {
        return Err(Error::parse(
            Some(file),
            None,
            format!(
                "num_frames = {}, but only {} images",
                rf.num_frames,
                rf.images.len()
            ),
        ));
    }
    let sensors = rf
        .sensors
        .iter()
        .enumerate()
        .map(|(k, s)| {
            let known = s.sensor_from_rig.as_ref().map(|rows| {
                rotation_from_rows(rows, options.rotation_tolerance, &format!("sensor {k}"))
            });
            Ok(Sensor {
                sensor_from_rig: known.transpose()?,
            })
        })
        .collect::<Result<Vec<_>>>()
        .map_err(in_file)?;
    let (edges, information) = crate::io::json::read_edges(&rf.edges, file, options)?;
    let (frames, sensors_n, images_n) = (rf.num_frames, rf.sensors.len(), rf.images.len());
    let mut problem = RigProblem::new(frames, sensors, rf.images, edges).map_err(in_file)?;
    if let Some(info) = information {
        problem = problem.with_information(info).map_err(in_file)?;
    }
    Ok(LoadedRig {
        problem,
        frame_ids: (0..frames as u64).collect(),
        sensor_ids: (0..sensors_n as u64).collect(),
        image_ids: (0..images_n as u64).collect(),
        image_names: Vec::new(),
        format: "json".into(),
        warnings: Vec::new(),
        pending_gravity: None,
    })
}

/// Read a rig from `path`: a COLMAP database (or a folder holding `database.db`) with a rig
/// configuration, else the JSON rig format.
pub fn load_rig(path: &Path, options: &ReadOptions) -> Result<LoadedRig> {
    // the options' contradiction first: a missing file would hide it
    options.check()?;
    if let Some(db) = crate::io::colmap::find_database(path) {
        return read_colmap_rig(&db, options);
    }
    let file = path.display().to_string();
    let text = crate::io::text::read_text(&file)?;
    read_rig_json(&text, &file, options)
}

/// The rig of a COLMAP database (`[F17]`): the view graph of its two-view geometries over the
/// images (as `rotavg multiple` reads it), each image placed at its frame and camera by the
/// tables `frames` and `frame_data`, the cameras' `sensor_from_rig` from `rigs` (reference
/// sensors: the identity) and `rig_sensors` (known, or `NULL`: estimated); with
/// `--information full` each pair's information from its correspondences (`[F13]`, `[H24]`).
/// Errors: no rig tables, an image of the view graph in no frame, any error of the view graph's
/// reader.
pub fn read_colmap_rig(path: &Path, options: &ReadOptions) -> Result<LoadedRig> {
    #[cfg(feature = "colmap")]
    {
        let file = path.display().to_string();
        // `--information auto` is weights 1 for rigs: with the within-frame information pooled
        // (`[F18]`) the frames and most sensors are more accurate, but the certificate is
        // slower, a 6000-image rig `gap_reported` after 5 minutes where weights 1 certify in 2 s
        // (`docs/benchmarks.md`, "A rig's within-frame information, pooled")
        let graph = crate::io::colmap::read_colmap_database(path, &options.scalar_by_default())?;
        let layout =
            crate::io::colmap::database::rig::rig_layout(path, options.quaternion_tolerance)?;
        rig_of_layout(&graph, &layout.images, &layout.sensors).map_err(|e| e.in_file(&file, None))
    }
    #[cfg(not(feature = "colmap"))]
    {
        let _ = options;
        Err(crate::io::colmap::without_colmap_feature(path))
    }
}

/// The rig of `graph`'s images placed by `images` (image id -> frame id, camera id), the
/// cameras' `sensor_from_rig` in `known` (a camera in no rig: its own reference, the identity).
#[cfg(feature = "colmap")]
fn rig_of_layout(
    graph: &crate::io::detect::LoadedGraph,
    images: &std::collections::BTreeMap<u64, (u64, u64)>,
    known: &std::collections::BTreeMap<u64, Option<Rotation>>,
) -> Result<LoadedRig> {
    let mut frame_ids: Vec<u64> = Vec::new();
    let mut sensor_ids: Vec<u64> = Vec::new();
    let mut placed = Vec::with_capacity(graph.node_ids.len());
    for &id in &graph.node_ids {
        let &(frame, camera) = images.get(&id).ok_or_else(|| Error::InvalidSettings {
            name: "rig".into(),
            reason: format!("image {id} has two-view geometries but is in no frame (frame_data)"),
        })?;
        placed.push((frame, camera));
        frame_ids.push(frame);
        sensor_ids.push(camera);
    }
    frame_ids.sort_unstable();
    frame_ids.dedup();
    sensor_ids.sort_unstable();
    sensor_ids.dedup();
    let index = |ids: &[u64], v: u64| ids.binary_search(&v).unwrap_or_default();
    let rig_images = placed
        .iter()
        .map(|&(f, c)| Image {
            frame: index(&frame_ids, f),
            sensor: index(&sensor_ids, c),
        })
        .collect();
    let sensors = sensor_ids
        .iter()
        .map(|c| Sensor {
            sensor_from_rig: known.get(c).copied().unwrap_or(Some(Rotation::identity())),
        })
        .collect();
    let mut problem = RigProblem::new(
        frame_ids.len(),
        sensors,
        rig_images,
        graph.problem.edges().to_vec(),
    )?;
    // `--information full`: each pair's rotation information from its correspondences
    // (`[F13]`), one per sensor pair within the frames (`[F18]`)
    let mut warnings = graph.warnings.clone();
    if let Some(info) = graph.problem.information() {
        let pooled = super::within_frame::pooled_within_frames(
            problem.images(),
            graph.problem.edges(),
            info,
        )?;
        if pooled.pairs > 0 {
            let message = format!(
                "{} within-frame pairs of {} sensor pairs measured with their sensor pair's \
                 pooled information (the log-Euclidean median; paper-notes/formats.md [F18]), \
                 not each pair's own",
                pooled.pairs, pooled.sensor_pairs
            );
            let warning = Warning::new("within_frame_information_pooled", message);
            warnings.push(warning.with_count(pooled.pairs));
        }
        problem = problem.with_information(pooled.information)?;
    }
    Ok(LoadedRig {
        problem,
        frame_ids,
        sensor_ids,
        image_ids: graph.node_ids.clone(),
        image_names: graph.node_names.clone(),
        format: "colmap".into(),
        warnings,
        pending_gravity: None,
    })
}

/// A planted rig as JSON, `{"frames": [F...], "sensors_from_rig": [S...]}` and a newline (the
/// `truth.json` of generated rigs, as `rotavg rig`'s benchmarks and examples read it).
pub fn write_rig_truth_json(frames: &[Rotation], sensors: &[Rotation]) -> String {
    let rows = |rs: &[Rotation]| rs.iter().map(rotation_to_rows).collect::<Vec<_>>();
    let truth = serde_json::json!({"frames": rows(frames), "sensors_from_rig": rows(sensors)});
    format!("{truth}\n")
}

/// The estimate as JSON: `{"frames": [F...], "frame_ids": [...], "sensors_from_rig": [S...],
/// "sensor_ids": [...]}` (rotations as row-major 3x3 arrays).
pub fn write_rig_estimate_json(
    frames: &[Rotation],
    sensors: &[Rotation],
    rig: &LoadedRig,
) -> String {
    let rows = |rs: &[Rotation]| rs.iter().map(rotation_to_rows).collect::<Vec<_>>();
    let value = serde_json::json!({
        "frames": rows(frames),
        "frame_ids": rig.frame_ids,
        "sensors_from_rig": rows(sensors),
        "sensor_ids": rig.sensor_ids,
    });
    format!("{value:#}\n")
}

/// `problem` in the JSON rig format (module docs), as [`read_rig_json`] reads it back.
///
/// ```
/// use rotavg::io::{detect::ReadOptions, rig::{read_rig_json, write_rig_json}};
/// use rotavg::rig::RigScene;
/// let (p, _) = RigScene { frames: 5, sensors: 2, ..Default::default() }.generate();
/// let back = read_rig_json(&write_rig_json(&p), "rig.json", &ReadOptions::default())?;
/// assert_eq!(back.problem, p);
/// // with information matrices (`[H24]`)
/// let (p, _) = RigScene { frames: 5, sensors: 2, anisotropy: 9.0, ..Default::default() }.generate();
/// let back = read_rig_json(&write_rig_json(&p), "rig.json", &ReadOptions::default())?;
/// assert_eq!(back.problem.information(), p.information());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn write_rig_json(problem: &RigProblem) -> String {
    let sensors: Vec<serde_json::Value> = problem
        .sensors()
        .iter()
        .map(|s| match &s.sensor_from_rig {
            Some(r) => serde_json::json!({ "sensor_from_rig": rotation_to_rows(r) }),
            None => serde_json::json!({}),
        })
        .collect();
    let info = problem.information();
    let edges: Vec<serde_json::Value> = (problem.edges().iter().enumerate())
        .map(|(k, e)| {
            let mut v =
                serde_json::json!({"i": e.i, "j": e.j, "rotation": rotation_to_rows(&e.rotation)});
            match info {
                Some(h) => v["information"] = serde_json::json!(<[[f64; 3]; 3]>::from(h[k])),
                None => v["weight"] = serde_json::json!(e.weight),
            }
            v
        })
        .collect();
    let value = serde_json::json!({
        "num_frames": problem.num_frames(),
        "sensors": sensors,
        "images": problem.images(),
        "edges": edges,
    });
    format!("{value}\n")
}

/// A rig estimate as [`write_rig_estimate_json`] writes it, for `rig`: `"frames"` (one per frame)
/// and `"sensors_from_rig"` (one per sensor), in the rig's order; `"frame_ids"` and
/// `"sensor_ids"`, when present, must be the rig's. Each matrix must be a rotation within
/// `options.rotation_tolerance` and is then taken at its nearest rotation (the certificate is
/// about rotations); with `nearest`, as `certify --nearest-rotations`, any matrix near O(3)
/// ([`crate::io::nearest::project_estimate`], all of them negated first when every one is a
/// reflection), and what was done is returned. Errors name the file.
pub fn read_rig_estimate(
    text: &str,
    file: &str,
    rig: &LoadedRig,
    options: &ReadOptions,
    nearest: bool,
) -> Result<RigEstimate> {
    #[derive(Deserialize)]
    struct EstimateFile {
        frames: Vec<Rows>,
        sensors_from_rig: Vec<Rows>,
        #[serde(default)]
        frame_ids: Option<Vec<u64>>,
        #[serde(default)]
        sensor_ids: Option<Vec<u64>>,
    }
    let bad = |msg: String| Error::parse(Some(file), None, msg);
    let e: EstimateFile = serde_json::from_str(text).map_err(|e| {
        let line = (e.line() > 0).then_some(e.line());
        Error::parse(Some(file), line, format!("invalid rig estimate: {e}"))
    })?;
    let p = &rig.problem;
    if e.frames.len() != p.num_frames() || e.sensors_from_rig.len() != p.sensors().len() {
        return Err(bad(format!(
            "{} frames and {} sensors for a rig of {} frames and {} sensors",
            e.frames.len(),
            e.sensors_from_rig.len(),
            p.num_frames(),
            p.sensors().len()
        )));
    }
    for (name, given, ours) in [
        ("frame_ids", &e.frame_ids, &rig.frame_ids),
        ("sensor_ids", &e.sensor_ids, &rig.sensor_ids),
    ] {
        if given.as_ref().is_some_and(|g| g != ours) {
            return Err(bad(format!("{name} differ from the rig's")));
        }
    }
    let tolerance = if nearest {
        f64::INFINITY
    } else {
        options.rotation_tolerance
    };
    let mut all = e
        .frames
        .iter()
        .chain(&e.sensors_from_rig)
        .enumerate()
        .map(|(k, rows)| {
            let item = match k.checked_sub(e.frames.len()) {
                None => format!("frame {k}"),
                Some(s) => format!("sensor {s}"),
            };
            rotation_from_rows(rows, tolerance, &item).map_err(|err| err.in_file(file, None))
        })
        .collect::<Result<Vec<_>>>()?;
    let projection = if nearest {
        Some(crate::io::nearest::project_estimate(&mut all, file)?)
    } else {
        all.iter_mut()
            .for_each(|r| *r = crate::so3::nearest_rotation(r));
        None
    };
    let sensors = all.split_off(e.frames.len());
    Ok(RigEstimate {
        frames: all,
        sensors,
        projection,
    })
}

/// A rig estimate read by [`read_rig_estimate`].
#[derive(Debug, Clone, PartialEq)]
pub struct RigEstimate {
    /// The frames, in the rig's order.
    pub frames: Vec<Rotation>,
    /// Every sensor's `sensor_from_rig`.
    pub sensors: Vec<Rotation>,
    /// What `--nearest-rotations` did, when it was asked for.
    pub projection: Option<crate::io::nearest::Projection>,
}
