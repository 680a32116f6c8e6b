//! COLMAP's rig configuration (`[F17]`, COLMAP 3.12 and later): which frame and which sensor
//! took each image, and each sensor's `sensor_from_rig` rotation when it is known.
//!
//! * `rigs (rig_id, ref_sensor_id, ref_sensor_type)`: the reference sensor of a rig, whose
//!   `sensor_from_rig` is the identity.
//! * `rig_sensors (rig_id, sensor_id, sensor_type, sensor_from_rig)`: the other sensors; the
//!   blob is COLMAP's `Rigid3d`, 7 little-endian `f64`: the quaternion `w, x, y, z` of the
//!   rotation, then the translation; `NULL` when the pose is unknown (to be calibrated).
//! * `frames (frame_id, rig_id)` and `frame_data (frame_id, data_id, sensor_id, sensor_type)`:
//!   a camera's data id is its image id, its sensor id its camera id; sensor type 0 is a camera
//!   (other sensors, such as IMUs, are ignored).
//!
//! COLMAP's `cam_from_world = sensor_from_rig * rig_from_world`, so its `sensor_from_rig`
//! rotation is this crate's `S_s` and `rig_from_world` the frame `F_f` (contract section 5).

use super::super::quaternion_rotation;
use super::Db;
use crate::error::Result;
use crate::so3::Rotation;
use std::collections::BTreeMap;
use std::path::Path;

/// COLMAP's sensor type of a camera.
const CAMERA: i64 = 0;

/// The rig configuration of a database: image id -> (frame id, camera id), and each camera
/// sensor's `sensor_from_rig` (`None`: unknown).
#[derive(Debug, Default)]
pub(crate) struct RigLayout {
    pub images: BTreeMap<u64, (u64, u64)>,
    pub sensors: BTreeMap<u64, Option<Rotation>>,
}

/// Read the rig configuration of the database at `path`, rotations checked to `tol`. Errors: a
/// database without the four tables, ids out of range, a blob that is not 7 numbers, a
/// quaternion that is not a rotation.
pub(crate) fn rig_layout(path: &Path, tol: f64) -> Result<RigLayout> {
    let db = Db::open(path)?;
    for table in ["rigs", "rig_sensors", "frames", "frame_data"] {
        if db.columns(table)?.is_empty() {
            return Err(db.err(format!(
                "no rig configuration: the database has no table `{table}` (COLMAP 3.12 and \
                 later write rigs, rig_sensors, frames and frame_data); average its images with \
                 `rotavg multiple` instead"
            )));
        }
    }
    let mut layout = RigLayout::default();
    let id = |v: i64, what: &str| {
        u64::try_from(v).map_err(|_| db.err(format!("{what} {v} is negative")))
    };
    let refs = query(&db, "SELECT ref_sensor_id, ref_sensor_type FROM rigs")?;
    for (sensor, kind) in refs {
        if kind == CAMERA {
            layout.sensors.insert(
                id(sensor, "rigs: ref_sensor_id")?,
                Some(Rotation::identity()),
            );
        }
    }
    sensor_rows(&db, tol, &mut layout)?;
    let frames: BTreeMap<i64, i64> = query(&db, "SELECT frame_id, rig_id FROM frames")?
        .into_iter()
        .collect();
    let mut stmt = db
        .conn
        .prepare("SELECT frame_id, data_id, sensor_id FROM frame_data WHERE sensor_type = 0")
        .map_err(|e| db.sql(e))?;
    let mut rows = stmt.query([]).map_err(|e| db.sql(e))?;
    while let Some(row) = rows.next().map_err(|e| db.sql(e))? {
        let get = |k| row.get::<_, i64>(k).map_err(|e| db.sql(e));
        let (frame, image, camera) = (get(0)?, get(1)?, get(2)?);
        if !frames.contains_key(&frame) {
            return Err(db.err(format!(
                "frame_data: frame {frame} is not in the table `frames`"
            )));
        }
        let (frame, image, camera) = (
            id(frame, "frame_id")?,
            id(image, "data_id")?,
            id(camera, "sensor_id")?,
        );
        if layout.images.insert(image, (frame, camera)).is_some() {
            return Err(db.err(format!("frame_data: image {image} is in two frames")));
        }
    }
    Ok(layout)
}

/// The camera rows of `rig_sensors`: known (`sensor_from_rig` a 7-number blob) or unknown
/// (`NULL`).
fn sensor_rows(db: &Db, tol: f64, layout: &mut RigLayout) -> Result<()> {
    let mut stmt = db
        .conn
        .prepare("SELECT sensor_id, sensor_from_rig FROM rig_sensors WHERE sensor_type = 0")
        .map_err(|e| db.sql(e))?;
    let mut rows = stmt.query([]).map_err(|e| db.sql(e))?;
    while let Some(row) = rows.next().map_err(|e| db.sql(e))? {
        let sensor: i64 = row.get(0).map_err(|e| db.sql(e))?;
        let sensor = u64::try_from(sensor)
            .map_err(|_| db.err(format!("rig_sensors: sensor_id {sensor} is negative")))?;
        let blob: Option<Vec<u8>> = row.get(1).map_err(|e| {
            db.err(format!(
                "rig_sensors: sensor {sensor}: sensor_from_rig: {e}"
            ))
        })?;
        let rotation = match blob {
            None => None,
            Some(b) if b.len() == 56 => {
                let v = super::f64s::<7>(&b);
                let what = format!("rig_sensors: sensor {sensor}: sensor_from_rig");
                Some(
                    quaternion_rotation([v[0], v[1], v[2], v[3]], tol, &what)
                        .map_err(|m| db.err(m))?,
                )
            }
            Some(b) => {
                return Err(db.err(format!(
                    "rig_sensors: sensor {sensor}: sensor_from_rig has {} bytes, not 56 (7 numbers)",
                    b.len()
                )));
            }
        };
        layout.sensors.insert(sensor, rotation);
    }
    Ok(())
}

/// The integer pairs a query selects.
fn query(db: &Db, sql: &str) -> Result<Vec<(i64, i64)>> {
    let mut stmt = db.conn.prepare(sql).map_err(|e| db.sql(e))?;
    stmt.query_map([], |r| Ok((r.get(0)?, r.get(1)?)))
        .and_then(|rows| rows.collect())
        .map_err(|e| db.sql(e))
}
