//! The files of [`super::GeneratedScene`]: the COLMAP database and `pairs.json`.

use super::{GeneratedScene, PairKind, SfmScene, wxyz};
use crate::error::{Error, Result};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use serde::Serialize;
use std::path::Path;

/// COLMAP's schema of the tables written (`database.cc` of COLMAP 3.8 to 3.11): `images` with
/// pose priors, `two_view_geometries` with `qvec` / `tvec`.
pub const SCHEMA: &str = "
CREATE TABLE IF NOT EXISTS cameras (camera_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, model INTEGER NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL, params BLOB, prior_focal_length INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS images (image_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, name TEXT NOT NULL UNIQUE, camera_id INTEGER NOT NULL, prior_qw REAL, prior_qx REAL, prior_qy REAL, prior_qz REAL, prior_tx REAL, prior_ty REAL, prior_tz REAL, CONSTRAINT image_id_check CHECK(image_id >= 0 and image_id < 2147483647), FOREIGN KEY(camera_id) REFERENCES cameras(camera_id));
CREATE TABLE IF NOT EXISTS keypoints (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS descriptors (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS matches (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB);
CREATE TABLE IF NOT EXISTS two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, config INTEGER NOT NULL, F BLOB, E BLOB, H BLOB, qvec BLOB, tvec BLOB);
CREATE UNIQUE INDEX IF NOT EXISTS index_name ON images(name);
";

fn f64s(values: &[f64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

fn u32s(pairs: &[[u32; 2]]) -> Vec<u8> {
    pairs
        .iter()
        .flatten()
        .flat_map(|v| v.to_le_bytes())
        .collect()
}

/// An image's keypoint rows (`x, y, a11, a12, a21, a22` float32): the affine shape a similarity
/// of random scale (1.5 to 6 pixels) and orientation.
fn keypoint_blob(pixels: &[[f32; 2]], rng: &mut StdRng) -> Vec<u8> {
    let mut out = Vec::with_capacity(24 * pixels.len());
    for [x, y] in pixels {
        let scale = rng.random_range(1.5f32..6.0);
        let (s, c) = rng.random_range(0.0f32..std::f32::consts::TAU).sin_cos();
        for v in [*x, *y, scale * c, -scale * s, scale * s, scale * c] {
            out.extend_from_slice(&v.to_le_bytes());
        }
    }
    out
}

pub(super) fn write_database(scene: &GeneratedScene, path: &Path) -> Result<()> {
    let err = |e: String| Error::Io {
        path: path.display().to_string(),
        message: e,
    };
    if path.exists() {
        std::fs::remove_file(path).map_err(|e| err(e.to_string()))?;
    }
    let mut db = rusqlite::Connection::open(path).map_err(|e| err(format!("SQLite: {e}")))?;
    let sql = |e: rusqlite::Error| err(format!("SQLite: {e}"));
    db.execute_batch(SCHEMA).map_err(sql)?;
    let tx = db.transaction().map_err(sql)?;
    let s: &SfmScene = &scene.settings;
    let cam = s.camera();
    for sensor in 0..s.rig_sensors {
        tx.execute(
            "INSERT INTO cameras VALUES (?1, 1, ?2, ?3, ?4, 1)",
            rusqlite::params![
                sensor + 1,
                s.width_px,
                s.height_px,
                f64s(&[cam.focal.x, cam.focal.y, cam.principal.x, cam.principal.y])
            ],
        )
        .map_err(sql)?;
    }
    if let Some(sensors) = &scene.sensors_from_rig {
        write_rig(&tx, s, sensors, scene.keypoints.len()).map_err(sql)?;
    }
    {
        let mut image = tx
            .prepare("INSERT INTO images (image_id, name, camera_id) VALUES (?1, ?2, ?3)")
            .map_err(sql)?;
        let mut keypoints = tx
            .prepare("INSERT INTO keypoints VALUES (?1, ?2, 6, ?3)")
            .map_err(sql)?;
        let mut shapes = StdRng::seed_from_u64(s.seed ^ 0x5eed_4b50);
        for (k, pixels) in scene.keypoints.iter().enumerate() {
            let id = k as i64 + 1;
            image
                .execute(rusqlite::params![id, scene.name(k), k % s.rig_sensors + 1])
                .map_err(sql)?;
            let blob = keypoint_blob(pixels, &mut shapes);
            keypoints
                .execute(rusqlite::params![id, pixels.len(), blob])
                .map_err(sql)?;
        }
        let mut matches = tx
            .prepare("INSERT INTO matches VALUES (?1, ?2, 2, ?3)")
            .map_err(sql)?;
        let mut geometry = tx
            .prepare(
                "INSERT INTO two_view_geometries VALUES (?1, ?2, 2, ?3, ?4, NULL, NULL, NULL, ?5, ?6)",
            )
            .map_err(sql)?;
        for p in &scene.pairs {
            let id = scene.pair_id(p) as i64;
            matches
                .execute(rusqlite::params![id, p.matches.len(), u32s(&p.matches)])
                .map_err(sql)?;
            geometry
                .execute(rusqlite::params![
                    id,
                    p.inliers.len(),
                    u32s(&p.inliers),
                    p.config,
                    f64s(&wxyz(&p.rotation)),
                    f64s(p.translation.as_slice())
                ])
                .map_err(sql)?;
        }
    }
    tx.commit().map_err(sql)
}

/// COLMAP's rig tables (`[F17]`) for `images` images of a rig with `sensors` (camera `s + 1`
/// is sensor `s`; frame `f + 1` holds images `f K + 1 ..= f K + K`): known `sensor_from_rig`
/// poses (`Rigid3d`: `w x y z`, then `t = -S_s o_s`) or `NULL`.
fn write_rig(
    tx: &rusqlite::Transaction<'_>,
    s: &SfmScene,
    sensors: &[crate::so3::Rotation],
    images: usize,
) -> rusqlite::Result<()> {
    tx.execute_batch(RIG_SCHEMA)?;
    tx.execute("INSERT INTO rigs VALUES (1, 1, 0)", [])?;
    for (k, sensor) in sensors.iter().enumerate().skip(1) {
        let t = -(sensor * SfmScene::rig_offset(k));
        let pose = [wxyz(sensor).as_slice(), t.as_slice()].concat();
        let blob = s.rig_known.then(|| f64s(&pose));
        tx.execute(
            "INSERT INTO rig_sensors VALUES (1, ?1, 0, ?2)",
            rusqlite::params![k + 1, blob],
        )?;
    }
    let k = sensors.len();
    for f in 0..images / k {
        tx.execute("INSERT INTO frames VALUES (?1, 1)", [f + 1])?;
        for sensor in 0..k {
            tx.execute(
                "INSERT INTO frame_data VALUES (?1, ?2, ?3, 0)",
                [f + 1, f * k + sensor + 1, sensor + 1],
            )?;
        }
    }
    Ok(())
}

/// COLMAP's rig tables (as COLMAP 3.12 and later create them).
const RIG_SCHEMA: &str = "\
CREATE TABLE IF NOT EXISTS rigs (rig_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, ref_sensor_id INTEGER NOT NULL, ref_sensor_type INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS rig_sensors (rig_id INTEGER NOT NULL, sensor_id INTEGER NOT NULL, sensor_type INTEGER NOT NULL, sensor_from_rig BLOB, FOREIGN KEY(rig_id) REFERENCES rigs(rig_id) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS frames (frame_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, rig_id INTEGER NOT NULL, FOREIGN KEY(rig_id) REFERENCES rigs(rig_id) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS frame_data (frame_id INTEGER NOT NULL, data_id INTEGER NOT NULL, sensor_id INTEGER NOT NULL, sensor_type INTEGER NOT NULL, FOREIGN KEY(frame_id) REFERENCES frames(frame_id) ON DELETE CASCADE);
";

#[derive(Serialize)]
struct ImageLabel {
    image_id: usize,
    name: String,
    /// world-to-camera `(w, x, y, z)`
    qvec: [f64; 4],
    centre: [f64; 3],
    pan_of: Option<usize>,
}

#[derive(Serialize)]
struct PairLabel {
    image_id1: usize,
    image_id2: usize,
    name1: String,
    name2: String,
    kind: PairKind,
    config: i64,
    matches: usize,
    inliers: usize,
    wrong_inliers: usize,
    rotation_error_deg: f64,
}

#[derive(Serialize)]
struct Labels<'a> {
    generator: &'static str,
    settings: &'a SfmScene,
    summary: super::SceneSummary,
    images: Vec<ImageLabel>,
    pairs: Vec<PairLabel>,
}

pub(super) fn labels_json(scene: &GeneratedScene) -> String {
    let images = scene
        .views
        .iter()
        .enumerate()
        .map(|(k, v)| ImageLabel {
            image_id: k + 1,
            name: scene.name(k),
            qvec: wxyz(&v.r),
            centre: [v.c.x, v.c.y, v.c.z],
            pan_of: scene.pan_of[k].map(|s| s + 1),
        })
        .collect();
    let pairs = scene
        .pairs
        .iter()
        .map(|p| PairLabel {
            image_id1: p.a + 1,
            image_id2: p.b + 1,
            name1: scene.name(p.a),
            name2: scene.name(p.b),
            kind: p.kind,
            config: p.config,
            matches: p.matches.len(),
            inliers: p.inliers.len(),
            wrong_inliers: p.wrong_inliers,
            rotation_error_deg: p.rotation_error_deg,
        })
        .collect();
    let labels = Labels {
        generator: "rotavg::io::colmap::scene",
        settings: &scene.settings,
        summary: scene.summary(),
        images,
        pairs,
    };
    let mut s = serde_json::to_string_pretty(&labels).expect("labels serialise");
    s.push('\n');
    s
}
