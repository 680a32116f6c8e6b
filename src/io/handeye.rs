//! Hand-eye data: Tabb's `robot_cali.txt` / `cali.txt`, the ETH ASL CSV pose streams, and the
//! conjugate JSON of contract section 5; and the relative motions `(L_i, R_i)` they define.
//!
//! Conventions (data README section 3 item 4, and `paper-notes/conjugate.md` `[H11]`):
//! * **Tabb**: `B_i` (robot_cali.txt) maps robot-base to hand coordinates, `A_i` (cali.txt)
//!   maps pattern to camera coordinates, and `A_i X = Z B_i` with `Z` hand -> camera. Then for
//!   stations `i < j`: `(A_j A_i^-1) Z = Z (B_j B_i^-1)`, so with `L = rot(A_j A_i^-1)` and
//!   `R = rot(B_j B_i^-1)` we have `R = Z^-1 L Z`: the contract's `R_i ~ S^-1 L_i S` with `S = rot(Z)`.
//! * **ETH**: the hand file holds `H = T_B_H` (hand in base), the camera file `E = T_W_E`
//!   (camera in target); `(H_i^-1 H_j) X = X (E_i^-1 E_j)`, so `L = rot(H_i^-1 H_j)`,
//!   `R = rot(E_i^-1 E_j)`, `S = rot(X)` (camera -> hand rotation).
//! * **Motion-capture streams** (Vicon, OptiTrack, ROS pose topics) are read the same way
//!   ([`read_pose_stream`]): the hand file is the tracked body's pose in the capture world
//!   (`H`, body -> world), the camera file the camera's pose in the target frame (`E`,
//!   camera -> target). Any pair of streams with these meanings works: `L` is always the
//!   hand (first file, `--hand`) motion, `R` the camera (`--camera`) motion, and `S` maps
//!   camera to hand coordinates. A camera stream that holds the *target in the camera* (the
//!   inverse, `E^-1`) gives `R = rot(E_i E_j^-1)` instead, which is not conjugate to `L` by a
//!   constant rotation: invert such poses before calling.
//!
//! File names: a directory is searched for a hand stream (name containing one of
//! [`HAND_NAMES`]) and a camera stream ([`CAMERA_NAMES`]); [`find_stream_files`] says what it
//! found when that fails, and either file can be named explicitly.
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

/// A time-stamped pose (ETH / motion-capture pose stream).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StampedPose {
    /// Time in seconds (nanosecond files are converted, see [`read_pose_stream`]).
    pub time: f64,
    /// The pose.
    pub pose: Pose,
}

/// Order of the four quaternion fields of a pose-stream line (after `t, x, y, z`). The
/// quaternion is Hamilton's in both orders; only where its scalar part `w` stands differs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum QuaternionOrder {
    /// `qx, qy, qz, qw`: scalar last (ETH ASL, ROS `geometry_msgs`; the default).
    #[default]
    Xyzw,
    /// `qw, qx, qy, qz`: scalar first (Eigen's constructor order, some Vicon exports).
    Wxyz,
}

/// Unit of the time column of a pose stream, as [`read_pose_stream`] detected it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeUnit {
    /// Seconds (any number that is not a nanosecond stamp).
    #[default]
    Seconds,
    /// Nanoseconds: the first stamp is an integer above `1e17` (ROS / Vicon `header.stamp`
    /// printed as one integer); every stamp of the file is divided by `1e9`.
    Nanoseconds,
}

/// How relative motions are formed from pose sequences (and how pose streams are read).
///
/// Pose streams (ETH, motion capture): the hand file holds `H_k` (hand in robot base, or the
/// tracked body in the motion-capture world), the camera file `E_k` (camera in the calibration
/// target's frame). Camera sample `k` (time `t_k`) is matched to the hand stream interpolated at
/// `t_k + time_offset`; of the matched samples `0, 1, 2, ...` the pairs start at
/// `i = 0, subsample, 2 subsample, ...` and end at `j = i + stride`, giving
/// `L = rot(H_i^-1 H_j)` (hand motion) and `R = rot(E_i^-1 E_j)` (camera motion), so that
/// `R = S^-1 L S` with `S = rot(X)` the camera-to-hand rotation (`[H11]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct MotionSettings {
    /// Skip pairs whose `L` and `R` both have angle below this (radians, default `1e-2`).
    pub min_angle: f64,
    /// Rotation validation tolerance (default [`crate::so3::DEFAULT_ROTATION_TOLERANCE`]).
    pub rotation_tolerance: f64,
    /// Streams: use matched samples `i` and `i + stride` (default 15, i.e. 0.5 s at 30 Hz).
    pub stride: usize,
    /// Streams: keep every `subsample`-th matched sample as a pair start (default 3).
    pub subsample: usize,
    /// Streams: a camera time stamp further than this (seconds) from the nearest hand samples on
    /// either side is not matched (default 0.05).
    pub max_gap: f64,
    /// Streams: constant time offset (seconds) added to camera time stamps before matching:
    /// camera time `t` is hand time `t + time_offset` (default 0).
    pub time_offset: f64,
    /// Streams: order of the quaternion fields (default `qx qy qz qw`).
    pub quaternion_order: QuaternionOrder,
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
            quaternion_order: QuaternionOrder::Xyzw,
        }
    }
}

impl MotionSettings {
    /// Check the ranges: `stride`, `subsample` >= 1; `max_gap` > 0 and `min_angle` >= 0;
    /// every number finite.
    ///
    /// ```
    /// use rotavg::io::handeye::MotionSettings;
    /// assert!(MotionSettings::default().validate().is_ok());
    /// let bad = MotionSettings { max_gap: -1.0, ..Default::default() };
    /// assert!(bad.validate().unwrap_err().to_string().contains("max_gap"));
    /// ```
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: &str| {
            Err(Error::InvalidSettings {
                name: name.into(),
                reason: reason.into(),
            })
        };
        if self.stride == 0 {
            return bad("stride", "must be >= 1");
        }
        if self.subsample == 0 {
            return bad("subsample", "must be >= 1");
        }
        if !(self.max_gap.is_finite() && self.max_gap > 0.0) {
            return bad("max_gap", "must be a positive number of seconds");
        }
        if !self.time_offset.is_finite() {
            return bad("time_offset", "must be a finite number of seconds");
        }
        if !(self.min_angle.is_finite() && self.min_angle >= 0.0) {
            return bad("min_angle", "must be a finite angle >= 0");
        }
        Ok(())
    }
}

/// What reading one pose stream found ([`read_pose_stream`]).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StreamStats {
    /// The file.
    pub file: String,
    /// Data lines read.
    pub samples: usize,
    /// Samples kept (`samples - repeated_stamps`).
    pub kept: usize,
    /// Samples dropped because their time stamp equals the previous one (the first sample of a
    /// repeated stamp is kept).
    pub repeated_stamps: usize,
    /// Leading lines skipped as a header (first field not a number).
    pub header_lines: usize,
    /// Unit of the time column.
    pub time_unit: TimeUnit,
}

/// A pose stream with what reading it found.
#[derive(Debug, Clone, PartialEq)]
pub struct PoseStream {
    /// The samples, time stamps strictly increasing.
    pub poses: Vec<StampedPose>,
    /// The counts.
    pub stats: StreamStats,
}

/// Counts from forming relative motions.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct MotionStats {
    /// Absolute poses used (Tabb: stations; streams: time-matched camera samples).
    pub poses: usize,
    /// Pairs kept.
    pub pairs: usize,
    /// Pairs skipped for a rotation angle below `min_angle`.
    pub skipped_small: usize,
    /// Streams: camera samples not matched (no hand sample within `max_gap` on either side of
    /// the shifted time, or outside the hand stream); 0 for Tabb.
    pub unmatched: usize,
    /// Streams: the hand stream read (`None` for Tabb, or streams given in memory).
    pub hand: Option<StreamStats>,
    /// Streams: the camera stream read.
    pub camera: Option<StreamStats>,
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
        ..Default::default()
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

/// The fields of a pose-stream line: comma-separated when the line holds a comma, else
/// whitespace-separated.
fn stream_fields(line: &str) -> Vec<&str> {
    if line.contains(',') {
        line.split(',').map(str::trim).collect()
    } else {
        line.split_whitespace().collect()
    }
}

/// A nanosecond stamp: an integer (digits only) above `1e17` (nanoseconds since 1973).
fn nanoseconds(tok: &str) -> Option<i64> {
    if !tok.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    tok.parse::<i64>()
        .ok()
        .filter(|&ns| ns > 100_000_000_000_000_000)
}

/// An integer stamp between `1e12` and `1e17`: milliseconds or microseconds since the epoch
/// (no plausible count of seconds), which this reader does not guess.
fn ambiguous_integer_stamp(tok: &str) -> bool {
    tok.bytes().all(|b| b.is_ascii_digit())
        && tok
            .parse::<u64>()
            .is_ok_and(|v| v > 1_000_000_000_000 && v <= 100_000_000_000_000_000)
}

/// Read a pose stream (ETH ASL CSV, motion-capture exports such as Vicon's): one sample per
/// line, `t, x, y, z` and the quaternion in `settings.quaternion_order` (default
/// `qx, qy, qz, qw`, Hamilton, scalar last). Variants accepted:
/// * fields separated by commas, or by white space when a line has no comma;
/// * leading header lines (first field not a number) are skipped and counted; `#` comments
///   and blank lines are ignored anywhere;
/// * time in seconds, or in integer nanoseconds when the first stamp is an integer above
///   `1e17` (then every stamp must be one; they are converted to seconds, resolution about
///   `2.5e-7` s at today's epoch times);
/// * repeated time stamps: a sample whose stamp equals the previous one is dropped (the first
///   sample of the stamp is kept: interpolation needs strictly increasing stamps, and a motion
///   capture driver that repeats a stamp re-sends or mis-stamps a frame, which averaging would
///   not repair) and counted in [`StreamStats::repeated_stamps`]; a stamp *before* the
///   previous one is an error with its line.
///
/// A quaternion whose norm differs from 1 by more than `settings.rotation_tolerance`, or is
/// below `1e-12`, is rejected. Errors name the file and line.
///
/// ```
/// use rotavg::io::handeye::{read_pose_stream, MotionSettings, QuaternionOrder, TimeUnit};
/// // A Vicon-style export: a header, whitespace separators, nanosecond stamps, scalar first,
/// // and one repeated stamp.
/// let text = "time x y z qw qx qy qz\n\
///             1700000000000000000 0 0 0 1 0 0 0\n\
///             1700000000010000000 0 0 0 1 0 0 0\n\
///             1700000000010000000 9 9 9 1 0 0 0\n\
///             1700000000020000000 0 0 0 0 1 0 0\n";
/// let settings = MotionSettings { quaternion_order: QuaternionOrder::Wxyz, ..Default::default() };
/// let stream = read_pose_stream(text, "tool_vicon.txt", &settings)?;
/// let s = &stream.stats;
/// assert_eq!((s.samples, s.kept, s.repeated_stamps, s.header_lines), (4, 3, 1, 1));
/// assert_eq!(s.time_unit, TimeUnit::Nanoseconds);
/// assert!((stream.poses[1].time - stream.poses[0].time - 0.01).abs() < 1e-6);
/// assert_eq!(stream.poses[1].pose.translation.x, 0.0); // the first sample of a stamp is kept
/// // A stamp before the previous one is an error naming the line.
/// let bad = "0.0 0 0 0 0 0 0 1\n0.2 0 0 0 0 0 0 1\n0.1 0 0 0 0 0 0 1\n";
/// let err = read_pose_stream(bad, "hand.csv", &MotionSettings::default()).unwrap_err();
/// assert!(err.to_string().starts_with("hand.csv:3: "), "{err}");
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_pose_stream(text: &str, file: &str, settings: &MotionSettings) -> Result<PoseStream> {
    let mut poses: Vec<StampedPose> = Vec::new();
    let mut stats = StreamStats {
        file: file.to_string(),
        ..Default::default()
    };
    let mut unit = None;
    let mut first_header: Option<(usize, &str)> = None;
    let mut prev_line = 0;
    for (line, l) in crate::io::content_lines(text) {
        let f = stream_fields(l);
        if unit.is_none() && f[0].parse::<f64>().is_err() {
            stats.header_lines += 1;
            first_header.get_or_insert((line, l));
            continue;
        }
        let err = |msg: String| Error::parse(Some(file), Some(line), msg);
        if f.len() != 8 {
            return Err(err(format!(
                "expected 8 fields (t, x, y, z and the quaternion, separated by commas or spaces), found {}",
                f.len()
            )));
        }
        let unit = match unit {
            Some(u) => u,
            None => *unit.insert(time_unit(f[0]).map_err(err)?),
        };
        let (time, pose) = stream_sample(&f, unit, line, file, settings)?;
        stats.samples += 1;
        if let Some(prev) = poses.last() {
            if time == prev.time {
                stats.repeated_stamps += 1;
                continue;
            }
            if time < prev.time {
                return Err(err(format!(
                    "time stamp {} is before the previous one {} (line {prev_line}); repeated stamps are dropped, decreasing ones are an error",
                    f[0], prev.time
                )));
            }
        }
        prev_line = line;
        poses.push(StampedPose { time, pose });
    }
    if poses.is_empty() {
        let why = match first_header {
            Some((line, l)) => format!(
                "no poses: {} line(s) do not start with a number (skipped as a header), the first at line {line}: `{}`",
                stats.header_lines,
                l.chars().take(60).collect::<String>()
            ),
            None => "no poses".to_string(),
        };
        return Err(Error::parse(Some(file), None, why));
    }
    stats.kept = poses.len();
    stats.time_unit = unit.unwrap_or_default();
    Ok(PoseStream { poses, stats })
}

/// The time unit of a stream from its first stamp `first`; an error for an integer stamp
/// that is neither seconds nor nanoseconds.
fn time_unit(first: &str) -> std::result::Result<TimeUnit, String> {
    if ambiguous_integer_stamp(first) {
        return Err(format!(
            "time stamp `{first}`: an integer between 1e12 and 1e17 is neither seconds nor nanoseconds since the epoch (milliseconds or microseconds?); convert the stamps to seconds"
        ));
    }
    Ok(if nanoseconds(first).is_some() {
        TimeUnit::Nanoseconds
    } else {
        TimeUnit::Seconds
    })
}

/// The time (seconds) and pose of the 8 fields `f` of a stream's line `line`: time stamp in
/// `unit`, translation, quaternion in `settings.quaternion_order` (its norm 1 within
/// `settings.rotation_tolerance`).
fn stream_sample(
    f: &[&str],
    unit: TimeUnit,
    line: usize,
    file: &str,
    settings: &MotionSettings,
) -> Result<(f64, Pose)> {
    let err = |msg: String| Error::parse(Some(file), Some(line), msg);
    let time = match unit {
        TimeUnit::Seconds => number(f[0], line, file)?,
        TimeUnit::Nanoseconds => {
            let ns = nanoseconds(f[0]).ok_or_else(|| {
                err(format!(
                    "expected an integer nanosecond time stamp (as the first one), found `{}`",
                    f[0]
                ))
            })?;
            (ns / 1_000_000_000) as f64 + (ns % 1_000_000_000) as f64 * 1e-9
        }
    };
    let mut v = [0.0; 7];
    for (slot, t) in v.iter_mut().zip(&f[1..]) {
        *slot = number(t, line, file)?;
    }
    let q = match settings.quaternion_order {
        QuaternionOrder::Xyzw => Quaternion::new(v[6], v[3], v[4], v[5]),
        QuaternionOrder::Wxyz => Quaternion::new(v[3], v[4], v[5], v[6]),
    };
    // A (near-)zero quaternion has no direction, whatever the tolerance: normalising it
    // would give NaN (found by fuzzing, tests/fuzz_regressions.rs).
    let (norm, tol) = (q.norm(), settings.rotation_tolerance);
    if !(norm > 1e-12 && (norm - 1.0).abs() <= tol) {
        return Err(err(format!(
            "quaternion norm {norm} is not 1 (tolerance {tol:.1e})"
        )));
    }
    let pose = Pose {
        rotation: UnitQuaternion::from_quaternion(q).to_rotation_matrix(),
        translation: Vector3::new(v[0], v[1], v[2]),
    };
    Ok((time, pose))
}

/// Read an ETH ASL CSV (`t, x, y, z, qx, qy, qz, qw`, seconds): the samples of
/// [`read_pose_stream`] with default settings and rotation tolerance `tol`. Repeated time
/// stamps are dropped (the first sample is kept); decreasing ones are an error.
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
/// // Time stamps must not decrease.
/// assert!(read_eth_csv("1,0,0,0,0,0,0,1\n0,0,0,0,0,0,0,1\n", "bad.csv", TOL).is_err());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn read_eth_csv(text: &str, file: &str, tol: f64) -> Result<Vec<StampedPose>> {
    let settings = MotionSettings {
        rotation_tolerance: tol,
        ..Default::default()
    };
    Ok(read_pose_stream(text, file, &settings)?.poses)
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

/// ETH (pose-stream) relative motions `[H11]`: every camera sample (time `+ time_offset`) is
/// matched to the hand stream interpolated at that time ([`interpolate`]; samples without a
/// hand sample within `max_gap` on both sides are counted in [`MotionStats::unmatched`]); for
/// matched samples `i` (every `subsample`-th) and `j = i + stride`, `L = rot(H_i^-1 H_j)`,
/// `R = rot(E_i^-1 E_j)`, so `R = S^-1 L S` with `S` the camera-to-hand rotation. `stride`
/// counts matched samples, not camera samples.
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
    settings.validate()?;
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
        unmatched: camera.len() - matched.len(),
        ..Default::default()
    };
    // starts 0, subsample, 2 subsample, ... while the pair's end is a matched sample (no
    // overflow for any stride / subsample the command line accepts)
    let last_start = matched.len().saturating_sub(settings.stride);
    for i in (0..last_start).step_by(settings.subsample.max(1)) {
        let (hi, ei) = matched[i];
        let (hj, ej) = matched[i + settings.stride];
        push_pair(
            &mut pairs,
            &mut stats,
            hi.inverse() * hj,
            ei.inverse() * ej,
            settings.min_angle,
        );
    }
    if pairs.is_empty() {
        return Err(Error::Degenerate {
            reason: format!(
                "no relative motions: {} time-matched samples (hand stream {} samples, camera stream {} samples; max gap {} s, time offset {} s, stride {})",
                matched.len(),
                hand.len(),
                camera.len(),
                settings.max_gap,
                settings.time_offset,
                settings.stride
            ),
        });
    }
    Ok((ConjugateProblem::new(pairs)?, stats))
}

/// Words that mark the hand stream in a file name (lower case): `base_link` (ETH), `hand`,
/// `vicon` (a motion-capture stream tracks the hand).
pub const HAND_NAMES: [&str; 3] = ["base_link", "hand", "vicon"];

/// Words that mark the camera stream in a file name (lower case): `target` (ETH), `camera`.
pub const CAMERA_NAMES: [&str; 2] = ["target", "camera"];

fn name_list(words: &[&str]) -> String {
    let w: Vec<String> = words.iter().map(|w| format!("`{w}`")).collect();
    w.join(", ")
}

fn path_list(paths: &[std::path::PathBuf]) -> String {
    if paths.is_empty() {
        return "none".into();
    }
    let names: Vec<String> = paths
        .iter()
        .map(|p| {
            p.file_name()
                .map_or_else(|| p.display().to_string(), |n| n.to_string_lossy().into())
        })
        .collect();
    names.join(", ")
}

/// The hand and camera stream files of a directory. A file given (`hand`, `camera`) is used as
/// is; the other one is the only `.csv` or `.txt` file (case-insensitive) whose name contains
/// one of [`HAND_NAMES`] (resp. [`CAMERA_NAMES`]) and none of the other list's words, the
/// given file excluded. No candidate or several are an error listing what was found and how
/// to name the files explicitly.
///
/// ```
/// use rotavg::io::handeye::find_stream_files;
/// let dir = std::env::temp_dir().join(format!("rotavg-doc-streams-{}", std::process::id()));
/// std::fs::create_dir_all(&dir).unwrap();
/// for name in ["run1_vicon_tool.csv", "run1_camera.csv", "notes.md"] {
///     std::fs::write(dir.join(name), "").unwrap();
/// }
/// let (hand, camera) = find_stream_files(&dir, None, None)?;
/// assert!(hand.ends_with("run1_vicon_tool.csv") && camera.ends_with("run1_camera.csv"));
/// // A second hand candidate makes detection ambiguous; the error says what to do.
/// std::fs::write(dir.join("run2_vicon_tool.csv"), "").unwrap();
/// let err = find_stream_files(&dir, None, None).unwrap_err().to_string();
/// assert!(err.contains("run2_vicon_tool.csv") && err.contains("--hand FILE"), "{err}");
/// // Naming the hand file resolves it.
/// let (hand, _) = find_stream_files(&dir, Some(&dir.join("run2_vicon_tool.csv")), None)?;
/// assert!(hand.ends_with("run2_vicon_tool.csv"));
/// std::fs::remove_dir_all(&dir).unwrap();
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn find_stream_files(
    dir: &Path,
    hand: Option<&Path>,
    camera: Option<&Path>,
) -> Result<(std::path::PathBuf, std::path::PathBuf)> {
    if let (Some(h), Some(c)) = (hand, camera) {
        return Ok((h.to_path_buf(), c.to_path_buf()));
    }
    let entries = std::fs::read_dir(dir).map_err(|e| Error::Io {
        path: dir.display().to_string(),
        message: e.to_string(),
    })?;
    let mut files: Vec<std::path::PathBuf> = entries
        .flatten()
        .map(|e| e.path())
        .filter(|p| {
            let name = p
                .file_name()
                .map(|n| n.to_string_lossy().to_lowercase())
                .unwrap_or_default();
            (name.ends_with(".csv") || name.ends_with(".txt")) && p.is_file()
        })
        .collect();
    files.sort();
    let given = |p: &Path| [hand, camera].iter().flatten().any(|g| same_file(g, p));
    let has = |p: &Path, words: &[&str]| {
        let name = p
            .file_name()
            .map(|n| n.to_string_lossy().to_lowercase())
            .unwrap_or_default();
        words.iter().any(|w| name.contains(w))
    };
    let pick = |mine: &[&str], other: &[&str]| -> Vec<std::path::PathBuf> {
        files
            .iter()
            .filter(|p| !given(p) && has(p, mine) && !has(p, other))
            .cloned()
            .collect()
    };
    let hands = pick(&HAND_NAMES, &CAMERA_NAMES);
    let cameras = pick(&CAMERA_NAMES, &HAND_NAMES);
    let h = match hand {
        Some(h) => Some(h.to_path_buf()),
        None if hands.len() == 1 => Some(hands[0].clone()),
        None => None,
    };
    let c = match camera {
        Some(c) => Some(c.to_path_buf()),
        None if cameras.len() == 1 => Some(cameras[0].clone()),
        None => None,
    };
    match (h, c) {
        (Some(h), Some(c)) => Ok((h, c)),
        _ => Err(Error::Io {
            path: dir.display().to_string(),
            message: format!(
                "cannot tell the hand and camera pose streams apart: hand candidates (.csv/.txt name containing {}): {}; camera candidates (name containing {}): {}. Name the files with --hand FILE and --camera FILE",
                name_list(&HAND_NAMES),
                if hand.is_some() {
                    "given".into()
                } else {
                    path_list(&hands)
                },
                name_list(&CAMERA_NAMES),
                if camera.is_some() {
                    "given".into()
                } else {
                    path_list(&cameras)
                },
            ),
        }),
    }
}

/// Whether two paths name the same file (canonical paths when both resolve).
fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    }
}

/// Read a hand and a camera pose stream ([`read_pose_stream`]) and form their relative
/// motions ([`eth_problem`]); the stream counts are in [`MotionStats::hand`] and
/// [`MotionStats::camera`].
pub fn read_stream_pair(
    hand: &Path,
    camera: &Path,
    settings: &MotionSettings,
) -> Result<(ConjugateProblem, MotionStats)> {
    settings.validate()?;
    let h = read_pose_stream(&read_file(hand)?, &hand.display().to_string(), settings)?;
    let c = read_pose_stream(&read_file(camera)?, &camera.display().to_string(), settings)?;
    let (problem, mut stats) = eth_problem(&h.poses, &c.poses, settings)?;
    stats.hand = Some(h.stats);
    stats.camera = Some(c.stats);
    Ok((problem, stats))
}

/// Read an ETH (or motion-capture) directory: the hand and camera streams found by
/// [`find_stream_files`], read and paired by [`read_stream_pair`].
pub fn read_eth_dir(
    dir: &Path,
    settings: &MotionSettings,
) -> Result<(ConjugateProblem, MotionStats)> {
    let (hand, camera) = find_stream_files(dir, None, None)?;
    read_stream_pair(&hand, &camera, settings)
}

#[derive(Serialize, Deserialize)]
#[serde(expecting = "a JSON object {\"pairs\": [{\"left\": L, \"right\": R, \"weight\": w}, ...]}")]
struct ConjugateJson {
    pairs: Vec<ConjugatePair>,
}

/// Read the conjugate JSON of contract section 5: `{"pairs": [{"left": L, "right": R, "weight": w}]}`
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
    let parsed: ConjugateJson = serde_json::from_str(text).map_err(|e| {
        crate::io::detect::read_by_another_verb(file, text, "conjugate")
            .unwrap_or_else(|| Error::parse(Some(file), Some(e.line()), e.to_string()))
    })?;
    for (k, p) in parsed.pairs.iter().enumerate() {
        if let Some(why) = crate::io::weight_out_of_range(p.weight) {
            return Err(Error::parse(Some(file), None, format!("pair {k}: {why}")));
        }
    }
    ConjugateProblem::new(parsed.pairs).map_err(|e| e.in_file(file, None))
}

/// Write a problem as conjugate JSON (contract section 5).
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
