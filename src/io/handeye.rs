//! Hand-eye data: Tabb's `robot_cali.txt` / `cali.txt`, the ETH ASL CSV pose streams, and the
//! conjugate JSON of SPEC section 5; and the relative motions `(L_i, R_i)` they define.
//!
//! Conventions (data README section 3 item 4, and `paper-notes/conjugate.md` `[H11]`):
//! * **Tabb**: `B_i` (robot_cali.txt) maps robot-base to hand coordinates, `A_i` (cali.txt)
//!   maps pattern to camera coordinates, and `A_i X = Z B_i` with `Z` hand -> camera. Then for
//!   stations `i < j`: `(A_j A_i^-1) Z = Z (B_j B_i^-1)`, so with `L = rot(A_j A_i^-1)` and
//!   `R = rot(B_j B_i^-1)` we have `R = Z^-1 L Z`: SPEC's `R_i ~ S^-1 L_i S` with `S = rot(Z)`.
//! * **ETH**: the hand file holds `H = T_B_H` (hand in base), the camera file `E = T_W_E`
//!   (camera in target); `(H_i^-1 H_j) X = X (E_i^-1 E_j)`, so `L = rot(H_i^-1 H_j)`,
//!   `R = rot(E_i^-1 E_j)`, `S = rot(X)` (camera -> hand rotation).
//!
//! Pairs whose `L` and `R` both rotate by less than `min_angle` carry no information about
//! `S` and are skipped (Tabb has station pairs that differ by a pure translation).

use crate::conjugate::{ConjugatePair, ConjugateProblem};
use crate::error::{Error, Result};
use crate::so3::{Rotation, angle, rotation_from_matrix, rotation_to_rows};
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A rigid pose: rotation and translation (units of the file).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Rotation part.
    pub rotation: Rotation,
    /// Translation part.
    pub translation: Vector3<f64>,
}

/// A time-stamped pose (ETH CSV).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StampedPose {
    /// Time in seconds.
    pub time: f64,
    /// The pose.
    pub pose: Pose,
}

/// How relative motions are formed from pose sequences.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MotionSettings {
    /// Skip pairs whose `L` and `R` both have angle below this (radians, default `1e-2`).
    pub min_angle: f64,
    /// Rotation validation tolerance (default [`crate::so3::DEFAULT_ROTATION_TOLERANCE`]).
    pub rotation_tolerance: f64,
    /// ETH: use matched samples `i` and `i + stride` (default 15, i.e. 0.5 s at 30 Hz).
    pub stride: usize,
    /// ETH: keep every `subsample`-th matched sample as a pair start (default 3).
    pub subsample: usize,
    /// ETH: a camera time stamp further than this (seconds) from the nearest hand samples on
    /// either side is not matched (default 0.05).
    pub max_gap: f64,
    /// ETH: constant time offset added to camera time stamps before matching (default 0).
    pub time_offset: f64,
}

impl Default for MotionSettings {
    fn default() -> Self {
        MotionSettings {
            min_angle: 1e-2,
            rotation_tolerance: crate::so3::DEFAULT_ROTATION_TOLERANCE,
            stride: 15,
            subsample: 3,
            max_gap: 0.05,
            time_offset: 0.0,
        }
    }
}

/// Counts from forming relative motions.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct MotionStats {
    /// Absolute poses used (matched, for ETH).
    pub poses: usize,
    /// Pairs kept.
    pub pairs: usize,
    /// Pairs skipped for a rotation angle below `min_angle`.
    pub skipped_small: usize,
}

/// Whitespace tokens with their 1-based line numbers.
fn tokens(text: &str) -> impl Iterator<Item = (&str, usize)> {
    text.lines()
        .enumerate()
        .flat_map(|(k, l)| l.split_whitespace().map(move |t| (t, k + 1)))
}

fn number(tok: &str, line: usize, file: &str) -> Result<f64> {
    let v: f64 = tok.parse().map_err(|_| {
        Error::parse(
            Some(file),
            Some(line),
            format!("expected a number, found `{tok}`"),
        )
    })?;
    if !v.is_finite() {
        return Err(Error::parse(
            Some(file),
            Some(line),
            format!("non-finite number `{tok}`"),
        ));
    }
    Ok(v)
}

fn count(tok: Option<(&str, usize)>, file: &str) -> Result<usize> {
    let (t, line) = tok
        .ok_or_else(|| Error::parse(Some(file), Some(1), "empty file: expected the pose count"))?;
    t.parse::<usize>().map_err(|_| {
        Error::parse(
            Some(file),
            Some(line),
            format!("expected the pose count, found `{t}`"),
        )
    })
}

/// Read Tabb's `robot_cali.txt`: a count `N`, then `N` 4x4 row-major homogeneous matrices
/// `B_i` (robot base -> hand, translation in mm). Errors name the file and line.
pub fn read_tabb_robot(text: &str, file: &str, tol: f64) -> Result<Vec<Pose>> {
    let mut it = tokens(text);
    let n = count(it.next(), file)?;
    let mut out = Vec::with_capacity(n.min(10_000));
    for k in 0..n {
        let mut v = [0.0; 16];
        let mut first_line = 0;
        for (idx, slot) in v.iter_mut().enumerate() {
            let (t, line) = it.next().ok_or_else(|| {
                Error::parse(
                    Some(file),
                    Some(text.lines().count().max(1)),
                    format!("end of file inside pose {k} of {n}"),
                )
            })?;
            if idx == 0 {
                first_line = line;
            }
            *slot = number(t, line, file)?;
        }
        let m = Matrix3::new(v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10]);
        let rotation = rotation_from_matrix(&m, tol, &format!("pose {k}"))
            .map_err(|e| e.in_file(file, Some(first_line)))?;
        out.push(Pose {
            rotation,
            translation: Vector3::new(v[3], v[7], v[11]),
        });
    }
    if let Some((t, line)) = it.next() {
        return Err(Error::parse(
            Some(file),
            Some(line),
            format!("unexpected `{t}` after {n} poses"),
        ));
    }
    Ok(out)
}

/// Read Tabb's `cali.txt`: a count `N`, then one line per image: name, 9 intrinsics, 9 entries
/// of the row-major rotation, 3 of the translation (mm), then distortion. `[R | t] = A_i` maps
/// pattern (world) to camera coordinates.
pub fn read_tabb_camera(text: &str, file: &str, tol: f64) -> Result<Vec<Pose>> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (l0, first) = lines
        .next()
        .ok_or_else(|| Error::parse(Some(file), Some(1), "empty file: expected the image count"))?;
    let n: usize = first.trim().parse().map_err(|_| {
        Error::parse(
            Some(file),
            Some(l0 + 1),
            format!("expected the image count, found `{}`", first.trim()),
        )
    })?;
    let mut out = Vec::with_capacity(n.min(10_000));
    for (k, l) in lines {
        let line = k + 1;
        let toks: Vec<&str> = l.split_whitespace().collect();
        if toks.len() < 23 {
            return Err(Error::parse(
                Some(file),
                Some(line),
                format!(
                    "expected at least 23 fields (name, 9 intrinsics, 9 rotation, 3 translation), found {}",
                    toks.len()
                ),
            ));
        }
        let mut v = [0.0; 12];
        for (j, slot) in v.iter_mut().enumerate() {
            *slot = number(toks[10 + j], line, file)?;
        }
        let m = Matrix3::from_row_slice(&v[..9]);
        let rotation = rotation_from_matrix(&m, tol, &format!("image {}", out.len()))
            .map_err(|e| e.in_file(file, Some(line)))?;
        out.push(Pose {
            rotation,
            translation: Vector3::new(v[9], v[10], v[11]),
        });
    }
    if out.len() != n {
        return Err(Error::parse(
            Some(file),
            Some(text.lines().count().max(1)),
            format!("header says {n} images, found {}", out.len()),
        ));
    }
    Ok(out)
}

fn push_pair(
    pairs: &mut Vec<ConjugatePair>,
    stats: &mut MotionStats,
    l: Rotation,
    r: Rotation,
    min_angle: f64,
) {
    if angle(&l) < min_angle && angle(&r) < min_angle {
        stats.skipped_small += 1;
    } else {
        pairs.push(ConjugatePair::new(l, r));
        stats.pairs += 1;
    }
}

/// Tabb relative motions `[H11]`: for every station pair `i < j`, `L = A_j A_i^-1` and
/// `R = B_j B_i^-1` (rotation parts), so that `R = S^-1 L S` with `S = rot(Z)`.
///
/// Round trip through both readers on a planted hand-eye rotation `Z` (pattern pose `X = I`,
/// so `A_i = Z B_i` in rotation): every station pair gives an exact pair and the closed form
/// recovers `Z`.
///
/// ```
/// use rotavg::conjugate::{solve_conjugate, ConjugateSettings};
/// use rotavg::io::handeye::{read_tabb_camera, read_tabb_robot, tabb_problem, MotionSettings};
/// use rotavg::so3::{angle_between, exp, rotation_to_rows, DEFAULT_ROTATION_TOLERANCE as TOL};
/// use nalgebra::Vector3;
/// let z = exp(&Vector3::new(0.1, 0.2, 0.3));
/// let b: Vec<_> = [[0.5, 0.0, 0.0], [0.0, 0.7, 0.0], [0.0, 0.0, 0.9]]
///     .iter()
///     .map(|v| exp(&Vector3::from(*v)))
///     .collect();
/// // robot_cali.txt: a count, then 4x4 row-major matrices B_i.
/// let mut robot = String::from("3\n");
/// // cali.txt: a count, then name, 9 intrinsics, 9 rotation, 3 translation, distortion.
/// let mut camera = String::from("3\n");
/// for (k, bi) in b.iter().enumerate() {
///     for row in rotation_to_rows(bi) {
///         robot += &format!("{} {} {} 10\n", row[0], row[1], row[2]);
///     }
///     robot += "0 0 0 1\n\n";
///     let a: Vec<String> = rotation_to_rows(&(z * bi)).iter().flatten().map(|x| x.to_string()).collect();
///     camera += &format!("img{k}.png 800 0 320 0 800 240 0 0 1 {} 1 2 3 0 0 0 0 0\n", a.join(" "));
/// }
/// let robot = read_tabb_robot(&robot, "robot_cali.txt", TOL)?;
/// let camera = read_tabb_camera(&camera, "cali.txt", TOL)?;
/// let (problem, stats) = tabb_problem(&robot, &camera, &MotionSettings::default())?;
/// assert_eq!((stats.poses, stats.pairs, stats.skipped_small), (3, 3, 0));
/// let s = solve_conjugate(&problem, &ConjugateSettings::default())?;
/// assert!(angle_between(&s.estimate, &z) < 1e-9);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn tabb_problem(
    robot: &[Pose],
    camera: &[Pose],
    settings: &MotionSettings,
) -> Result<(ConjugateProblem, MotionStats)> {
    if robot.len() != camera.len() {
        return Err(Error::Degenerate {
            reason: format!(
                "{} robot poses but {} camera poses",
                robot.len(),
                camera.len()
            ),
        });
    }
    let mut pairs = Vec::new();
    let mut stats = MotionStats {
        poses: robot.len(),
        pairs: 0,
        skipped_small: 0,
    };
    for j in 0..robot.len() {
        for i in 0..j {
            let l = camera[j].rotation * camera[i].rotation.inverse();
            let r = robot[j].rotation * robot[i].rotation.inverse();
            push_pair(&mut pairs, &mut stats, l, r, settings.min_angle);
        }
    }
    Ok((ConjugateProblem::new(pairs)?, stats))
}

fn read_file(path: &Path) -> Result<String> {
    super::text::read_text(&path.display().to_string())
}

/// Read a Tabb dataset directory (`robot_cali.txt` and `cali.txt`) into a conjugate problem.
pub fn read_tabb_dir(
    dir: &Path,
    settings: &MotionSettings,
) -> Result<(ConjugateProblem, MotionStats)> {
    let rp = dir.join("robot_cali.txt");
    let cp = dir.join("cali.txt");
    let robot = read_tabb_robot(
        &read_file(&rp)?,
        &rp.display().to_string(),
        settings.rotation_tolerance,
    )?;
    let camera = read_tabb_camera(
        &read_file(&cp)?,
        &cp.display().to_string(),
        settings.rotation_tolerance,
    )?;
    tabb_problem(&robot, &camera, settings)
}

/// Read an ETH ASL CSV: lines `t, x, y, z, q_x, q_y, q_z, q_w` (Hamilton quaternion, scalar
/// last). A quaternion whose norm differs from 1 by more than `tol`, or is below `1e-12`, is
/// rejected; time stamps must increase strictly.
///
/// ```
/// use rotavg::io::handeye::{interpolate, read_eth_csv};
/// use rotavg::so3::{angle, DEFAULT_ROTATION_TOLERANCE as TOL};
/// // Identity at t = 0, a quarter turn about z at t = 1 (q = (0, 0, sin pi/4, cos pi/4)).
/// let h = std::f64::consts::FRAC_1_SQRT_2;
/// let text = format!("# t,x,y,z,qx,qy,qz,qw\n0.0,0,0,0,0,0,0,1\n1.0,2,0,0,0,0,{h},{h}\n");
/// let stream = read_eth_csv(&text, "hand.csv", TOL)?;
/// assert_eq!(stream.len(), 2);
/// // Halfway: SLERP gives an eighth of a turn, and the translation is averaged.
/// let mid = interpolate(&stream, 0.5, 1.0).unwrap();
/// assert!((angle(&mid.rotation) - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
/// assert!((mid.translation.x - 1.0).abs() < 1e-12);
/// assert!(interpolate(&stream, 1.5, 1.0).is_none()); // outside the stream
/// // Time stamps must increase.
/// assert!(read_eth_csv("1,0,0,0,0,0,0,1\n0,0,0,0,0,0,0,1\n", "bad.csv", TOL).is_err());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_eth_csv(text: &str, file: &str, tol: f64) -> Result<Vec<StampedPose>> {
    let mut out: Vec<StampedPose> = Vec::new();
    for (line, l) in crate::io::content_lines(text) {
        let f: Vec<&str> = l.split(',').map(str::trim).collect();
        if f.len() != 8 {
            return Err(Error::parse(
                Some(file),
                Some(line),
                format!(
                    "expected 8 comma-separated fields (t, x, y, z, qx, qy, qz, qw), found {}",
                    f.len()
                ),
            ));
        }
        let mut v = [0.0; 8];
        for (slot, t) in v.iter_mut().zip(&f) {
            *slot = number(t, line, file)?;
        }
        let q = Quaternion::new(v[7], v[4], v[5], v[6]);
        // A (near-)zero quaternion has no direction, whatever the tolerance: normalising it
        // would give NaN (found by fuzzing, tests/fuzz_regressions.rs).
        let norm = q.norm();
        if !(norm > 1e-12 && (norm - 1.0).abs() <= tol) {
            return Err(Error::parse(
                Some(file),
                Some(line),
                format!("quaternion norm {norm} is not 1 (tolerance {tol:.1e})"),
            ));
        }
        if let Some(prev) = out.last()
            && v[0] <= prev.time
        {
            return Err(Error::parse(
                Some(file),
                Some(line),
                format!(
                    "time stamp {} does not increase (previous {})",
                    v[0], prev.time
                ),
            ));
        }
        out.push(StampedPose {
            time: v[0],
            pose: Pose {
                rotation: UnitQuaternion::from_quaternion(q).to_rotation_matrix(),
                translation: Vector3::new(v[1], v[2], v[3]),
            },
        });
    }
    if out.is_empty() {
        return Err(Error::parse(Some(file), None, "no poses"));
    }
    Ok(out)
}

/// The pose of a stream at time `t`: SLERP of the rotation (geodesic interpolation on SO(3))
/// and linear interpolation of the translation between the bracketing samples; `None` outside
/// the stream or when a bracketing sample is further than `max_gap` away.
pub fn interpolate(stream: &[StampedPose], t: f64, max_gap: f64) -> Option<Pose> {
    let k = stream.partition_point(|p| p.time <= t);
    if k == 0 || k == stream.len() {
        return None;
    }
    let (a, b) = (&stream[k - 1], &stream[k]);
    if t - a.time > max_gap || b.time - t > max_gap {
        return None;
    }
    let u = (t - a.time) / (b.time - a.time);
    let qa = UnitQuaternion::from_rotation_matrix(&a.pose.rotation);
    let qb = UnitQuaternion::from_rotation_matrix(&b.pose.rotation);
    let q = qa.try_slerp(&qb, u, 1e-12).unwrap_or(qa);
    Some(Pose {
        rotation: q.to_rotation_matrix(),
        translation: a.pose.translation * (1.0 - u) + b.pose.translation * u,
    })
}

/// ETH relative motions `[H11]`: every camera sample (time `+ time_offset`) is matched to the
/// hand stream interpolated at that time; for matched samples `i` (every `subsample`-th) and
/// `j = i + stride`, `L = rot(H_i^-1 H_j)`, `R = rot(E_i^-1 E_j)`, so `R = S^-1 L S` with `S`
/// the camera-to-hand rotation.
///
/// ```
/// use rotavg::conjugate::{solve_conjugate, ConjugateSettings};
/// use rotavg::io::handeye::{eth_problem, MotionSettings, Pose, StampedPose};
/// use rotavg::so3::{angle_between, exp};
/// use nalgebra::Vector3;
/// // Hand poses H_k about changing axes at 10 Hz; camera poses E_k = X^-1 H_k X (rotation
/// // parts), time-stamped identically, so that every relative motion satisfies
/// // R = X^-1 L X exactly.
/// let x = exp(&Vector3::new(0.3, -0.2, 0.5));
/// let stamped = |k: usize, r| StampedPose { time: 0.1 * k as f64, pose: Pose { rotation: r, translation: Vector3::zeros() } };
/// let hand: Vec<_> = (0..12).map(|k| {
///     let t = k as f64;
///     stamped(k, exp(&Vector3::new(0.3 * t.sin(), 0.2 * t, 0.4 * t.cos())))
/// }).collect();
/// let camera: Vec<_> = hand.iter().enumerate().map(|(k, h)| stamped(k, x.inverse() * h.pose.rotation * x)).collect();
/// let settings = MotionSettings { stride: 2, subsample: 1, max_gap: 0.2, ..Default::default() };
/// let (problem, stats) = eth_problem(&hand, &camera, &settings)?;
/// assert!(stats.pairs >= 5);
/// let s = solve_conjugate(&problem, &ConjugateSettings::default())?;
/// assert!(angle_between(&s.estimate, &x) < 1e-9);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn eth_problem(
    hand: &[StampedPose],
    camera: &[StampedPose],
    settings: &MotionSettings,
) -> Result<(ConjugateProblem, MotionStats)> {
    if settings.stride == 0 || settings.subsample == 0 {
        return Err(Error::InvalidSettings {
            name: "stride/subsample".into(),
            reason: "must be >= 1".into(),
        });
    }
    let matched: Vec<(Rotation, Rotation)> = camera
        .iter()
        .filter_map(|e| {
            interpolate(hand, e.time + settings.time_offset, settings.max_gap)
                .map(|h| (h.rotation, e.pose.rotation))
        })
        .collect();
    let mut pairs = Vec::new();
    let mut stats = MotionStats {
        poses: matched.len(),
        pairs: 0,
        skipped_small: 0,
    };
    let mut i = 0;
    while i + settings.stride < matched.len() {
        let (hi, ei) = matched[i];
        let (hj, ej) = matched[i + settings.stride];
        push_pair(
            &mut pairs,
            &mut stats,
            hi.inverse() * hj,
            ei.inverse() * ej,
            settings.min_angle,
        );
        i += settings.subsample;
    }
    if pairs.is_empty() {
        return Err(Error::Degenerate {
            reason: format!(
                "no relative motions: {} time-matched samples (hand stream {} samples, camera stream {} samples)",
                matched.len(),
                hand.len(),
                camera.len()
            ),
        });
    }
    Ok((ConjugateProblem::new(pairs)?, stats))
}

/// Read an ETH directory: the hand CSV is the one whose name contains `base_link` or `hand`,
/// the camera CSV the one whose name contains `target` or `camera`.
pub fn read_eth_dir(
    dir: &Path,
    settings: &MotionSettings,
) -> Result<(ConjugateProblem, MotionStats)> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::Io {
        path: dir.display().to_string(),
        message: e.to_string(),
    })?;
    let (mut hand, mut cam) = (None, None);
    for e in entries.flatten() {
        let p = e.path();
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().to_lowercase())
            .unwrap_or_default();
        if !name.ends_with(".csv") {
            continue;
        }
        if name.contains("base_link") || name.contains("hand") {
            hand = Some(p);
        } else if name.contains("target") || name.contains("camera") {
            cam = Some(p);
        }
    }
    let (Some(hp), Some(cp)) = (hand, cam) else {
        return Err(Error::Io {
            path: dir.display().to_string(),
            message: "expected a hand CSV (name containing `base_link` or `hand`) and a camera CSV (name containing `target` or `camera`)".into(),
        });
    };
    let h = read_eth_csv(
        &read_file(&hp)?,
        &hp.display().to_string(),
        settings.rotation_tolerance,
    )?;
    let c = read_eth_csv(
        &read_file(&cp)?,
        &cp.display().to_string(),
        settings.rotation_tolerance,
    )?;
    eth_problem(&h, &c, settings)
}

#[derive(Serialize, Deserialize)]
struct ConjugateJson {
    pairs: Vec<ConjugatePair>,
}

/// Read the conjugate JSON of SPEC section 5: `{"pairs": [{"left": L, "right": R, "weight": w}]}`
/// (row-major rotations; weight optional, default 1, within
/// [`[MIN_WEIGHT, MAX_WEIGHT]`](crate::io::MAX_WEIGHT); `R_i ~ S^-1 L_i S`).
///
/// ```
/// use rotavg::io::handeye::{read_conjugate_json, write_conjugate_json};
/// let text = r#"{"pairs": [
///   {"left": [[0,-1,0],[1,0,0],[0,0,1]], "right": [[1,0,0],[0,0,-1],[0,1,0]], "weight": 2.0},
///   {"left": [[1,0,0],[0,1,0],[0,0,1]], "right": [[1,0,0],[0,1,0],[0,0,1]]}
/// ]}"#;
/// let p = read_conjugate_json(text, "pairs.json")?;
/// assert_eq!(p.num_pairs(), 2);
/// assert_eq!(p.total_weight(), 3.0); // the missing weight defaults to 1
/// // The writer produces the same format (re-read rotations agree to rounding).
/// let again = read_conjugate_json(&write_conjugate_json(&p), "again.json")?;
/// let s = rotavg::Rotation::identity();
/// assert!((again.chordal_cost(&s) - p.chordal_cost(&s)).abs() < 1e-12);
/// // A matrix that is not a rotation is rejected with the file name.
/// let bad = r#"{"pairs": [{"left": [[2,0,0],[0,1,0],[0,0,1]], "right": [[1,0,0],[0,1,0],[0,0,1]]}]}"#;
/// assert!(read_conjugate_json(bad, "bad.json").unwrap_err().to_string().starts_with("bad.json"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_conjugate_json(text: &str, file: &str) -> Result<ConjugateProblem> {
    let parsed: ConjugateJson = serde_json::from_str(text)
        .map_err(|e| Error::parse(Some(file), Some(e.line()), e.to_string()))?;
    for (k, p) in parsed.pairs.iter().enumerate() {
        if let Some(why) = crate::io::weight_out_of_range(p.weight) {
            return Err(Error::parse(Some(file), None, format!("pair {k}: {why}")));
        }
    }
    ConjugateProblem::new(parsed.pairs).map_err(|e| e.in_file(file, None))
}

/// Write a problem as conjugate JSON (SPEC section 5).
pub fn write_conjugate_json(problem: &ConjugateProblem) -> String {
    let pairs: Vec<serde_json::Value> = problem
        .pairs()
        .iter()
        .map(|p| {
            serde_json::json!({
                "left": rotation_to_rows(&p.left),
                "right": rotation_to_rows(&p.right),
                "weight": p.weight,
            })
        })
        .collect();
    serde_json::json!({ "pairs": pairs }).to_string()
}
