//! A seeded structure-from-motion scene with correspondences, written as a COLMAP database
//! (`paper-notes/formats.md` `[F16]`): buildings with textured facades, cameras around and along
//! them, noisy keypoints, matches with wrong ones among them, and two-view geometries estimated
//! from the matches, some of them wrong in the ways real matchers are wrong. With its ground
//! truth (a COLMAP text model) and a label per pair, it exercises `rotavg multiple database.db
//! --information full` end to end: the information of each edge comes from real (simulated)
//! correspondences. Cargo feature `colmap`.
//!
//! # What is modelled
//!
//! * **Scene.** A street of *sites* along the world `x` axis, 30 m apart (`z` up). Each site
//!   has a square building (12 m x 12 m, 10 m high, centred on the street's side at `y = 0`)
//!   whose four facades carry points ([`SfmScene::points_per_facade`] each), and a 2.5 m wall
//!   along the street (`y = -18`, as many points). The facades are *repeated structure*: the
//!   building is symmetric under `g`, the rotation by [`SfmScene::symmetry_deg`] (90 or 180)
//!   about the vertical axis through its centre, and `g` maps every facade point onto a facade
//!   point with the same texture. Occlusion is not modelled; back-facing facades are not seen.
//! * **Cameras.** [`SfmScene::cameras_per_site`] per site: 60 % on an orbit of radius 15 m
//!   around the building (height 1.6 m, looking at its centre with a few degrees of jitter), the
//!   rest walking along the street (`y = -28`) looking across it at the wall and the building.
//!   World-to-camera rotations `R_i`, OpenCV axes (`x` right, `y` down, `z` forward), one shared
//!   `PINHOLE` camera ([`SfmScene::focal_px`], [`SfmScene::width_px`] x [`SfmScene::height_px`],
//!   principal point at the image centre). A fraction [`SfmScene::near_pure`] of the images are
//!   *pans*: a copy of another camera moved by [`SfmScene::near_pure_baseline`] and turned by
//!   5 to 12 degrees about its vertical axis.
//! * **Rigs** ([`SfmScene::rig_sensors`] `K > 1`). The cameras above are the frames of a rig of
//!   `K` cameras, `cameras / K` of them; sensor `s` is turned by `s x` [`SfmScene::rig_yaw_deg`]
//!   about its `y` axis from sensor 0 and sits `0.1 s` m along the rig's `x` axis, so image
//!   `f K + s` has `R = S_s F_f` (COLMAP's `cam_from_world = sensor_from_rig * rig_from_world`).
//!   The database gets one camera per sensor and COLMAP's rig tables (`[F17]`), the
//!   `sensor_from_rig` poses stored when [`SfmScene::rig_known`], else `NULL`; the truth adds
//!   `rig.json` (frames, `sensors_from_rig`) for `rotavg rig`.
//! * **Keypoints.** Each visible point (in front, within the image and 60 m, facade facing the
//!   camera) is detected with probability [`SfmScene::detection_probability`], at its
//!   projection plus Gaussian noise of [`SfmScene::pixel_sigma`] pixels per coordinate; a
//!   fraction [`SfmScene::clutter`] of extra keypoints lie on nothing. Rows of 6 float32
//!   (`x, y, a11, a12, a21, a22`, SIFT's layout; the affine shape a random similarity).
//! * **View graph.** Image pairs sharing at least [`SfmScene::min_common`] detected points; each
//!   image keeps its [`SfmScene::max_pairs_per_image`] best (most shared points), and a pair is
//!   matched when either image keeps it (as a vocabulary-tree matcher's nearest neighbours).
//! * **Matches and "RANSAC".** A pair's matches are its true correspondences plus
//!   [`SfmScene::wrong_matches`] times as many random keypoint pairs. The inliers are the matches
//!   whose Sampson error is below [`SfmScene::inlier_threshold_px`] under the true pose; the
//!   stored pose is refined from them (Gauss-Newton on the Sampson error,
//!   [`refine_relative_pose`]) and the inliers are taken again under it: a few wrong matches
//!   survive, as in real data. `matches` holds every match, `two_view_geometries.data` the
//!   inliers, `qvec` / `tvec` the estimated `cam2_from_cam1` (config 2, `CALIBRATED`).
//! * **Wrong two-view geometries** ([`PairKind`]): *twisted* pairs (a fraction
//!   [`SfmScene::twisted`] of the correct pairs) store `Rot(t, pi) R` instead of `R`: the twisted
//!   pair of the essential matrix, `[t]x Rot(t, pi) R = -[t]x R`, so the same Sampson errors and a
//!   confident information about a rotation 180 degrees off about the baseline. *Repeated*
//!   pairs ([`SfmScene::repeated`] times the number of correct pairs, added) match image `a`'s
//!   observations of facade points `X` with image `b`'s observations of `g(X)`, pairs that see
//!   the building from sides `g` maps onto each other and that are not correct pairs; their
//!   geometry is estimated from those matches (they are exactly consistent with camera `b`
//!   moved by `g^-1`), so the stored rotation is off by the symmetry angle. *Near-pure* pairs (a
//!   pan and its camera) have a baseline of centimetres at depths of 10 to 30 m: they are stored
//!   as `PANORAMIC` (config 5) with `t = 0` and the rotation that best aligns the inliers'
//!   bearings (the inliers: transfer error below the threshold).
//!
//! Image `k` has id `k + 1` and name `img_{id:05}.jpg`. [`GeneratedScene::write`] writes
//! `database.db`, `truth/` (`cameras.txt`, `images.txt` with the true poses, an empty
//! `points3D.txt`; `--ground-truth truth` reads it) and `pairs.json` (each pair's images, kind,
//! config, match and inlier counts and the error of its stored rotation in degrees).
//!
//! Bounded: [`SfmScene::validate`] refuses settings outside the documented ranges (at most
//! 100 000 cameras, 10^7 scene points and 10^7 for `cameras x points_per_facade`: at that limit,
//! 10 000 cameras x 1000 points per facade, 44 million matches took 1.3 GB of memory, 15 s and a
//! 1.0 GB database) before anything is allocated. Generation time with the default
//! settings, a release build on the 2-core development machine shared with another build (load
//! about 4), `/usr/bin/time cargo run --release --example colmap_scene -- OUT --cameras N`
//! (the pair estimation dominates: one core, Gauss-Newton with the analytic Jacobian):
//!
//! | cameras | pairs | matches | generated | database written | peak memory |
//! |---|---|---|---|---|---|
//! | 100 | 831 | 150 967 | 0.08 s | 0.17 s | 11 MB |
//! | 1000 | 8505 | 1 737 628 | 0.67 s | 0.28 s | 56 MB |
//! | 10 000 | 85 066 | 17 584 216 | 6.81 s | 1.40 s (a 0.45 GB file) | 0.5 GB |
//!
//! ```
//! use rotavg::io::colmap::scene::{PairKind, SfmScene};
//! let scene = SfmScene { cameras: 24, twisted: 0.2, ..SfmScene::default() }.generate()?;
//! assert_eq!(scene.views.len(), 24);
//! let twisted: Vec<_> = scene.pairs.iter().filter(|p| p.kind == PairKind::Twisted).collect();
//! assert!(!twisted.is_empty());
//! // a twisted pair's rotation is about 180 degrees off; a correct one's is not
//! assert!(twisted.iter().all(|p| p.rotation_error_deg > 170.0));
//! assert!(scene.pairs.iter().any(|p| p.kind == PairKind::Inlier && p.rotation_error_deg < 1.0));
//! // written as a COLMAP database that `rotavg multiple` reads
//! let dir = std::env::temp_dir().join(format!("rotavg-doc-scene-{}", std::process::id()));
//! scene.write(&dir)?;
//! let options = rotavg::io::detect::ReadOptions { full_information: Some(true), ..Default::default() };
//! let graph = rotavg::io::colmap::read_colmap_database(&dir.join("database.db"), &options)?;
//! std::fs::remove_dir_all(&dir).unwrap();
//! assert!(graph.problem.is_anisotropic());
//! # Ok::<(), rotavg::Error>(())
//! ```

use crate::error::{Error, Result};
use crate::io::colmap::{
    ColmapCamera, empty_points3d_text, image_pair_to_pair_id, write_cameras_text,
};
use crate::io::two_view_information::{Camera, refine_relative_pose, sampson_error};
use crate::so3::{Rotation, angle_between, exp, gaussian, random_unit_vector};
use nalgebra::{Vector2, Vector3};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::Path;

mod geometry;
mod output;
pub use geometry::{Frustum, View, relative_pose, wahba_rotation, wxyz};
pub use output::SCHEMA;

/// The settings of a generated scene (see the module docs for what each part models).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SfmScene {
    /// Number of images, 2 to 100 000 (pans included).
    pub cameras: usize,
    /// Seed of the random generator: the same settings give the same scene.
    pub seed: u64,
    /// Focal length of the shared camera, pixels (50 to 100 000).
    pub focal_px: f64,
    /// Image width, pixels (16 to 10 000).
    pub width_px: u32,
    /// Image height, pixels (16 to 10 000).
    pub height_px: u32,
    /// Standard deviation of the Gaussian noise of each keypoint coordinate, pixels (0 to 50).
    pub pixel_sigma: f64,
    /// Images per site (one building, its orbit and its stretch of street), 4 to 1000.
    pub cameras_per_site: usize,
    /// Points per facade of each building, and on each site's wall, 10 to 100 000 (and
    /// `cameras x points_per_facade` at most 10^7).
    pub points_per_facade: usize,
    /// Probability that a visible point is detected in an image, in `(0, 1]`.
    pub detection_probability: f64,
    /// Keypoints on nothing per image, a fraction of its detected points, 0 to 5.
    pub clutter: f64,
    /// Fewest shared detected points for a pair of images to be matched, 15 to 100 000.
    pub min_common: usize,
    /// Best pairs (most shared points) each image keeps, 1 to 200.
    pub max_pairs_per_image: usize,
    /// Wrong matches (random keypoint pairs) added to a pair, a fraction of its true matches,
    /// 0 to 5.
    pub wrong_matches: f64,
    /// The "RANSAC" inlier threshold on the Sampson error (transfer error for near-pure pairs),
    /// pixels (0 to 100, exclusive of 0).
    pub inlier_threshold_px: f64,
    /// Fraction of the correct pairs stored twisted (`Rot(t, pi) R`), 0 to 1.
    pub twisted: f64,
    /// Repeated-structure pairs added, a fraction of the number of correct pairs, 0 to 1.
    pub repeated: f64,
    /// Fraction of the images that are pans of another camera (near-pure rotation pairs), 0 to
    /// 0.5.
    pub near_pure: f64,
    /// Baseline of a pan and its camera, metres (0 to 1).
    pub near_pure_baseline: f64,
    /// The symmetry of the buildings (their repeated structure), degrees: 90 or 180.
    pub symmetry_deg: f64,
    /// Cameras of a rig, 1 to 8 (default 1: no rig). With `K > 1` the scene is `cameras / K`
    /// frames (at least 2), each taken by every camera of the rig (`K` images per frame, image
    /// `k` of frame `k / K` and sensor `k % K`): sensor `s` turned by `s x rig_yaw_deg` about
    /// the camera's `y` axis from sensor 0 (`sensor_from_rig = Rot(y, s x rig_yaw_deg)`, sensor
    /// 0 the reference) and `0.1 s` metres along the rig's `x` axis. The database gets COLMAP's
    /// rig tables (`rigs`, `rig_sensors`, `frames`, `frame_data`; `[F17]`) and one camera per
    /// sensor, the truth `truth/rig.json` (frames and `sensors_from_rig`).
    pub rig_sensors: usize,
    /// The yaw between successive sensors of a rig, degrees (0 to 90).
    pub rig_yaw_deg: f64,
    /// Whether the database stores the rig's `sensor_from_rig` poses (known) or `NULL` (to be
    /// calibrated, the default).
    pub rig_known: bool,
}

impl Default for SfmScene {
    fn default() -> Self {
        SfmScene {
            cameras: 100,
            seed: 0,
            focal_px: 700.0,
            width_px: 640,
            height_px: 480,
            pixel_sigma: 1.0,
            cameras_per_site: 40,
            points_per_facade: 400,
            detection_probability: 0.7,
            clutter: 0.2,
            min_common: 30,
            max_pairs_per_image: 12,
            wrong_matches: 0.3,
            inlier_threshold_px: 4.0,
            twisted: 0.03,
            repeated: 0.05,
            near_pure: 0.05,
            near_pure_baseline: 0.03,
            symmetry_deg: 90.0,
            rig_sensors: 1,
            rig_yaw_deg: 30.0,
            rig_known: false,
        }
    }
}

/// What a pair's stored geometry is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PairKind {
    /// A correct pair: its pose estimated from its own (noisy) correspondences.
    Inlier,
    /// A correct pair stored with the twisted rotation `Rot(t, pi) R` (same essential matrix up
    /// to sign).
    Twisted,
    /// Matches between a facade and its symmetric copy: off by the symmetry angle.
    Repeated,
    /// A pan and its camera (centimetres of baseline): stored as `PANORAMIC`, `t = 0`.
    NearPure,
}

impl PairKind {
    /// The four kinds, in the order of [`SceneSummary::pairs`].
    pub const ALL: [PairKind; 4] = [
        PairKind::Inlier,
        PairKind::Twisted,
        PairKind::Repeated,
        PairKind::NearPure,
    ];

    /// The name used in `pairs.json`.
    pub fn name(self) -> &'static str {
        match self {
            PairKind::Inlier => "inlier",
            PairKind::Twisted => "twisted",
            PairKind::Repeated => "repeated",
            PairKind::NearPure => "near_pure",
        }
    }
}

/// One matched pair of a generated scene, as stored (`a < b` are image indices, ids `a + 1`,
/// `b + 1`).
#[derive(Debug, Clone, PartialEq)]
pub struct ScenePair {
    /// The first image (index; COLMAP's `image_id1 = a + 1`).
    pub a: usize,
    /// The second image (index, `b > a`).
    pub b: usize,
    /// What the stored geometry is.
    pub kind: PairKind,
    /// COLMAP's `config`: 2 (`CALIBRATED`) or 5 (`PANORAMIC`).
    pub config: i64,
    /// Every match: keypoint indices `[in a, in b]`.
    pub matches: Vec<[u32; 2]>,
    /// The inlier matches (the two-view geometry's `data`).
    pub inliers: Vec<[u32; 2]>,
    /// Inliers that are not the pair's planted correspondences (wrong matches that survived).
    pub wrong_inliers: usize,
    /// The stored rotation of `cam2_from_cam1` (`R_ab`, with `R_ab R_a ~ R_b`).
    pub rotation: Rotation,
    /// The stored translation (unit; zero for `PANORAMIC`).
    pub translation: Vector3<f64>,
    /// Angle between the stored rotation and the true `R_b R_a^T`, degrees.
    pub rotation_error_deg: f64,
}

/// A generated scene: the cameras, keypoints and matched pairs ([`SfmScene::generate`]).
#[derive(Debug, Clone, PartialEq)]
pub struct GeneratedScene {
    /// The settings it was generated with.
    pub settings: SfmScene,
    /// The true cameras (world-to-camera rotation, centre), image `k` having id `k + 1`.
    pub views: Vec<View>,
    /// For each image, the image it is a pan of (near-pure pairs).
    pub pan_of: Vec<Option<usize>>,
    /// Each image's keypoints, pixels (float32, as stored).
    pub keypoints: Vec<Vec<[f32; 2]>>,
    /// The matched pairs, sorted by `(a, b)`.
    pub pairs: Vec<ScenePair>,
    /// The rig's `sensor_from_rig` rotations (sensor 0 the identity), when
    /// [`SfmScene::rig_sensors`] is more than 1.
    pub sensors_from_rig: Option<Vec<Rotation>>,
}

/// Counts of a generated scene (the example's one-line summary).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct SceneSummary {
    /// Images.
    pub images: usize,
    /// Pairs by kind, in the order of [`PairKind::ALL`].
    pub pairs: [usize; 4],
    /// Keypoints, all images.
    pub keypoints: usize,
    /// Matches, all pairs.
    pub matches: usize,
    /// Inlier matches, all pairs.
    pub inliers: usize,
    /// Inliers that are wrong matches, all pairs.
    pub wrong_inliers: usize,
}

impl std::fmt::Display for SceneSummary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [inlier, twisted, repeated, near] = self.pairs;
        write!(
            f,
            "{} images, {} pairs ({inlier} inlier, {twisted} twisted, {repeated} repeated, {near} near_pure), \
             {} keypoints, {} matches, {} inlier matches ({} of them wrong)",
            self.images,
            self.pairs.iter().sum::<usize>(),
            self.keypoints,
            self.matches,
            self.inliers,
            self.wrong_inliers
        )
    }
}

/// Fewest inliers a pair keeps (COLMAP's `min_num_inliers` default).
const MIN_INLIERS: usize = 15;

/// Building half size, metres.
const HALF: f64 = 6.0;
/// Building height, metres.
const HEIGHT: f64 = 10.0;
/// Distance between sites along `x`, metres.
const SPACING: f64 = 30.0;
/// Depth of the facades' relief (windows, balconies), metres either side of the plane.
const RELIEF: f64 = 0.5;
/// Orbit radius, metres.
const ORBIT: f64 = 15.0;
/// The wall's plane `y`, metres.
const WALL_Y: f64 = -18.0;
/// The street's `y`, metres.
const STREET_Y: f64 = -28.0;
/// The largest `cameras x points_per_facade` (keypoints and matches grow with it).
const MAX_WORK: usize = 10_000_000;
/// The most points of a scene.
const MAX_POINTS: usize = 10_000_000;

impl SfmScene {
    /// Check every setting against its documented range: an [`Error::InvalidSettings`] names
    /// the first that is not.
    ///
    /// ```
    /// use rotavg::io::colmap::scene::SfmScene;
    /// assert!(SfmScene::default().validate().is_ok());
    /// let e = SfmScene { cameras: 1, ..SfmScene::default() }.validate().unwrap_err();
    /// assert!(e.to_string().contains("cameras"));
    /// ```
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: String| {
            Err(Error::InvalidSettings {
                name: name.into(),
                reason,
            })
        };
        let counts = [
            ("cameras", self.cameras, 2, 100_000),
            ("cameras_per_site", self.cameras_per_site, 4, 1000),
            ("points_per_facade", self.points_per_facade, 10, 100_000),
            ("min_common", self.min_common, MIN_INLIERS, 100_000),
            ("max_pairs_per_image", self.max_pairs_per_image, 1, 200),
            ("width_px", self.width_px as usize, 16, 10_000),
            ("height_px", self.height_px as usize, 16, 10_000),
        ];
        for (name, v, lo, hi) in counts {
            if !(lo..=hi).contains(&v) {
                return bad(name, format!("{v} is not in {lo} ..= {hi}"));
            }
        }
        let reals = [
            ("focal_px", self.focal_px, 50.0, 1e5),
            ("pixel_sigma", self.pixel_sigma, 0.0, 50.0),
            (
                "detection_probability",
                self.detection_probability,
                1e-9,
                1.0,
            ),
            ("clutter", self.clutter, 0.0, 5.0),
            ("wrong_matches", self.wrong_matches, 0.0, 5.0),
            ("inlier_threshold_px", self.inlier_threshold_px, 1e-9, 100.0),
            ("twisted", self.twisted, 0.0, 1.0),
            ("repeated", self.repeated, 0.0, 1.0),
            ("near_pure", self.near_pure, 0.0, 0.5),
            ("near_pure_baseline", self.near_pure_baseline, 0.0, 1.0),
            ("rig_yaw_deg", self.rig_yaw_deg, 0.0, 90.0),
        ];
        for (name, v, lo, hi) in reals {
            if !(v >= lo && v <= hi) {
                return bad(name, format!("{v} is not in [{lo}, {hi}]"));
            }
        }
        if !(1..=8).contains(&self.rig_sensors) || self.cameras / self.rig_sensors < 2 {
            return bad(
                "rig_sensors",
                format!(
                    "{} sensors: 1 to 8, and at least 2 frames of them in the {} cameras",
                    self.rig_sensors, self.cameras
                ),
            );
        }
        if self.symmetry_deg != 90.0 && self.symmetry_deg != 180.0 {
            return bad(
                "symmetry_deg",
                format!("{} is not 90 or 180", self.symmetry_deg),
            );
        }
        let work = self.cameras.saturating_mul(self.points_per_facade);
        if work > MAX_WORK {
            return bad(
                "points_per_facade",
                format!(
                    "{} cameras x {} points per facade = {work}, more than {MAX_WORK} \
                     (the keypoints and matches grow with it: 1.3 GB of memory at the limit)",
                    self.cameras, self.points_per_facade
                ),
            );
        }
        let points = self.sites().saturating_mul(5 * self.points_per_facade);
        if points > MAX_POINTS {
            return bad(
                "points_per_facade",
                format!(
                    "{} sites of 5 x {} points: {points} points, more than {MAX_POINTS}",
                    self.sites(),
                    self.points_per_facade
                ),
            );
        }
        Ok(())
    }

    /// Images that are pans of another.
    fn pans(&self) -> usize {
        ((self.near_pure * self.cameras as f64).round() as usize).min(self.cameras / 2)
    }

    /// Number of sites.
    fn sites(&self) -> usize {
        (self.cameras - self.pans()).div_ceil(self.cameras_per_site.max(1))
    }

    /// The shared camera.
    fn camera(&self) -> Camera {
        let (cx, cy) = (self.width_px as f64 / 2.0, self.height_px as f64 / 2.0);
        Camera::pinhole(self.focal_px, self.focal_px, cx, cy)
    }

    /// The scene of these settings (validated first).
    pub fn generate(&self) -> Result<GeneratedScene> {
        self.validate()?;
        let mut rng = StdRng::seed_from_u64(self.seed);
        // a rig's frames are placed as the cameras of a scene without rig (the same scene
        // when there is none)
        let frames = SfmScene {
            cameras: self.cameras / self.rig_sensors,
            ..self.clone()
        };
        let world = World::new(&frames, &mut rng);
        let (views, pan_of, site_of) = match self.rig_sensors {
            1 => frames.cameras_of(&mut rng),
            _ => self.rig_images(frames.cameras_of(&mut rng)),
        };
        let images: Vec<Image> = views
            .iter()
            .zip(&site_of)
            .map(|(v, &s)| world.observe(self, v, s, &mut rng))
            .collect();
        let tracks = Tracks::new(&images, world.points.len());
        let pairs = self.pairs_of(&world, &views, &pan_of, &images, &tracks, &mut rng);
        Ok(GeneratedScene {
            settings: self.clone(),
            views,
            pan_of,
            keypoints: images.into_iter().map(|i| i.pixels).collect(),
            pairs,
            sensors_from_rig: (self.rig_sensors > 1).then(|| self.sensors_from_rig()),
        })
    }

    /// The rig's `sensor_from_rig` rotations: `Rot(y, s x rig_yaw_deg)`.
    fn sensors_from_rig(&self) -> Vec<Rotation> {
        (0..self.rig_sensors)
            .map(|s| {
                exp(&Vector3::new(
                    0.0,
                    (s as f64 * self.rig_yaw_deg).to_radians(),
                    0.0,
                ))
            })
            .collect()
    }

    /// Each sensor's centre in the rig's frame, metres: `0.1 s` along `x`.
    pub(crate) fn rig_offset(s: usize) -> Vector3<f64> {
        Vector3::new(0.1 * s as f64, 0.0, 0.0)
    }

    /// The images of the rig's `frames` (views, pan sources, sites): frame `f`'s sensor `s` is
    /// image `f K + s`, rotation `S_s R_f`, centre `c_f + R_f^T o_s`; a pan frame's images are
    /// pans of its source frame's.
    fn rig_images(
        &self,
        frames: (Vec<View>, Vec<Option<usize>>, Vec<usize>),
    ) -> (Vec<View>, Vec<Option<usize>>, Vec<usize>) {
        let sensors = self.sensors_from_rig();
        let k = sensors.len();
        let (mut views, mut pan_of, mut site_of) = (Vec::new(), Vec::new(), Vec::new());
        for (f, frame) in frames.0.iter().enumerate() {
            for (s, sensor) in sensors.iter().enumerate() {
                views.push(View {
                    r: sensor * frame.r,
                    c: frame.c + frame.r.transpose() * Self::rig_offset(s),
                });
                pan_of.push(frames.1[f].map(|src| src * k + s));
                site_of.push(frames.2[f]);
            }
        }
        (views, pan_of, site_of)
    }

    /// The cameras: each site's orbit and street cameras, then the pans; with each image's pan
    /// source and site.
    fn cameras_of(&self, rng: &mut StdRng) -> (Vec<View>, Vec<Option<usize>>, Vec<usize>) {
        let pans = self.pans();
        let base = self.cameras - pans;
        let mut views = Vec::with_capacity(self.cameras);
        let mut site_of = Vec::with_capacity(self.cameras);
        for s in 0..self.sites() {
            let first = s * self.cameras_per_site;
            let count = self.cameras_per_site.min(base - first);
            let orbit = ((0.6 * count as f64).round() as usize).max(1);
            let sx = s as f64 * SPACING;
            let jitter = |rng: &mut StdRng, sigma: f64| sigma * gaussian(rng);
            for k in 0..count {
                let (c, target) = if k < orbit {
                    let step = std::f64::consts::TAU / orbit as f64;
                    let phi = -std::f64::consts::FRAC_PI_2 + step * (k as f64 + jitter(rng, 0.15));
                    let r = ORBIT + jitter(rng, 0.7);
                    let c = Vector3::new(sx + r * phi.cos(), r * phi.sin(), 1.6 + jitter(rng, 0.2));
                    let t = Vector3::new(sx + jitter(rng, 1.0), jitter(rng, 1.0), 3.0);
                    (c, t)
                } else {
                    let j = (k - orbit) as f64 + 0.5;
                    let x = sx - SPACING / 2.0 + SPACING * j / (count - orbit) as f64;
                    let c = Vector3::new(x + jitter(rng, 0.5), STREET_Y + jitter(rng, 1.0), 1.6);
                    (c, Vector3::new(x + jitter(rng, 4.0), 0.0, 3.0))
                };
                let roll = exp(&Vector3::new(0.0, 0.0, jitter(rng, 2f64.to_radians())));
                views.push(View {
                    r: roll * geometry::look_at(&c, &target),
                    c,
                });
                site_of.push(s);
            }
        }
        let mut pan_of = vec![None; base];
        for k in 0..pans {
            let src = k * base / pans;
            let sign = if rng.random::<bool>() { 1.0 } else { -1.0 };
            let turn = sign * rng.random_range(5.0f64..12.0).to_radians();
            let v = &views[src];
            let c = v.c + random_unit_vector(rng) * self.near_pure_baseline;
            let r = exp(&Vector3::new(0.0, turn, 0.0)) * v.r;
            views.push(View { r, c });
            site_of.push(site_of[src]);
            pan_of.push(Some(src));
        }
        (views, pan_of, site_of)
    }
}

/// A scene point: position and the outward normal of its surface.
struct Point {
    x: Vector3<f64>,
    normal: Vector3<f64>,
}

/// The points of every site: per site, four facades then the wall, `points_per_facade` each.
struct World {
    points: Vec<Point>,
    per_facade: usize,
    /// Facade `f`'s image under `g` is facade `(f + step) % 4`, point for point.
    step: usize,
    /// `g`'s rotation matrix (about `z`).
    g: Rotation,
}

/// An image's detections: the point of each keypoint (`u32::MAX` for clutter) and its pixels.
struct Image {
    points: Vec<u32>,
    pixels: Vec<[f32; 2]>,
}

impl World {
    fn new(s: &SfmScene, rng: &mut StdRng) -> World {
        let n = s.points_per_facade;
        let step = if s.symmetry_deg == 90.0 { 1 } else { 2 };
        let quarter = |f: usize| {
            exp(&Vector3::new(
                0.0,
                0.0,
                std::f64::consts::FRAC_PI_2 * f as f64,
            ))
        };
        let mut points = Vec::with_capacity(s.sites() * 5 * n);
        for site in 0..s.sites() {
            let centre = Vector3::new(site as f64 * SPACING, 0.0, 0.0);
            // the textures in the front facade's frame (y = -HALF, facing -y)
            let textures: Vec<Vec<Vector3<f64>>> = (0..step)
                .map(|_| {
                    (0..n)
                        .map(|_| {
                            let x = rng.random_range(-HALF..HALF);
                            let relief = rng.random_range(-RELIEF..RELIEF);
                            Vector3::new(x, relief - HALF, rng.random_range(0.3..HEIGHT))
                        })
                        .collect()
                })
                .collect();
            for f in 0..4 {
                let q = quarter(f);
                for p in &textures[f % step] {
                    points.push(Point {
                        x: centre + q * p,
                        normal: q * -Vector3::y(),
                    });
                }
            }
            for _ in 0..n {
                let x = centre.x + rng.random_range(-SPACING / 2.0..SPACING / 2.0);
                points.push(Point {
                    x: Vector3::new(x, WALL_Y, rng.random_range(0.1..2.5)),
                    normal: -Vector3::y(),
                });
            }
        }
        World {
            points,
            per_facade: n,
            step,
            g: quarter(step),
        }
    }

    /// The point `g(p)` of a facade point `p` (`None` for wall points).
    fn symmetric(&self, p: u32) -> Option<u32> {
        let n = self.per_facade;
        let (site, rest) = (p as usize / (5 * n), p as usize % (5 * n));
        let (f, k) = (rest / n, rest % n);
        (f < 4).then(|| (site * 5 * n + ((f + self.step) % 4) * n + k) as u32)
    }

    /// The centre of the building of point `p`'s site.
    fn centre_of(&self, p: u32) -> Vector3<f64> {
        Vector3::new(
            (p as usize / (5 * self.per_facade)) as f64 * SPACING,
            0.0,
            0.0,
        )
    }

    /// The noisy detections of the points of sites `site - 1 ..= site + 1` in `view`, then the
    /// clutter.
    fn observe(&self, s: &SfmScene, view: &View, site: usize, rng: &mut StdRng) -> Image {
        let frustum = Frustum {
            focal: s.focal_px,
            half_width: s.width_px as f64 / 2.0 - 1.0,
            half_height: s.height_px as f64 / 2.0 - 1.0,
            near: 1.0,
            far: 60.0,
        };
        let (cx, cy) = (s.width_px as f64 / 2.0, s.height_px as f64 / 2.0);
        let per_site = 5 * self.per_facade;
        let range =
            site.saturating_sub(1) * per_site..((site + 2) * per_site).min(self.points.len());
        let mut image = Image {
            points: Vec::new(),
            pixels: Vec::new(),
        };
        for id in range {
            let p = &self.points[id];
            if (view.c - p.x).dot(&p.normal) <= 0.0 {
                continue;
            }
            if let Some(u) = view.project(&p.x, &frustum)
                && rng.random::<f64>() < s.detection_probability
            {
                let noise = |rng: &mut StdRng| s.pixel_sigma * gaussian(rng);
                let px = [
                    u.x * s.focal_px + cx + noise(rng),
                    u.y * s.focal_px + cy + noise(rng),
                ];
                image.points.push(id as u32);
                image.pixels.push([px[0] as f32, px[1] as f32]);
            }
        }
        let clutter = (s.clutter * image.points.len() as f64).round() as usize;
        for _ in 0..clutter {
            let x = rng.random_range(0.0..s.width_px as f64);
            let y = rng.random_range(0.0..s.height_px as f64);
            image.points.push(u32::MAX);
            image.pixels.push([x as f32, y as f32]);
        }
        image
    }
}

/// The images detecting each point (compressed rows).
struct Tracks {
    offsets: Vec<usize>,
    images: Vec<u32>,
}

impl Tracks {
    fn new(images: &[Image], points: usize) -> Tracks {
        let mut offsets = vec![0usize; points + 1];
        for im in images {
            for &p in im.points.iter().filter(|&&p| p != u32::MAX) {
                offsets[p as usize + 1] += 1;
            }
        }
        for k in 0..points {
            offsets[k + 1] += offsets[k];
        }
        let mut next = offsets.clone();
        let mut ids = vec![0u32; offsets[points]];
        for (i, im) in images.iter().enumerate() {
            for &p in im.points.iter().filter(|&&p| p != u32::MAX) {
                ids[next[p as usize]] = i as u32;
                next[p as usize] += 1;
            }
        }
        Tracks {
            offsets,
            images: ids,
        }
    }

    fn of(&self, p: u32) -> &[u32] {
        &self.images[self.offsets[p as usize]..self.offsets[p as usize + 1]]
    }
}

/// The keypoint of point `p` in `image` (its detections are sorted by point, clutter last).
fn keypoint_of(image: &Image, p: u32) -> Option<u32> {
    image.points.binary_search(&p).ok().map(|k| k as u32)
}

/// The parts of a scene the pairs are made from.
#[derive(Clone, Copy)]
struct Built<'a> {
    world: &'a World,
    views: &'a [View],
    images: &'a [Image],
    tracks: &'a Tracks,
}

/// A pair before measurement: images `a < b`, planted correspondences (keypoint indices), the
/// pose they are consistent with (`cam2_from_cam1`), and what it is.
struct Planted {
    a: usize,
    b: usize,
    correspondences: Vec<[u32; 2]>,
    start: (Rotation, Vector3<f64>),
    kind: PairKind,
}

impl SfmScene {
    /// Every image's partners sharing at least `min_common` points counted through `partner`
    /// (`p -> the point whose track counts`): `(a, b, count)` for `b` among `a`'s
    /// `max_pairs_per_image` best.
    fn best_partners(
        &self,
        images: &[Image],
        tracks: &Tracks,
        partner: impl Fn(u32) -> Option<u32>,
    ) -> Vec<(usize, usize, usize)> {
        let mut count = vec![0usize; images.len()];
        let mut touched = Vec::new();
        let mut out = Vec::new();
        for (a, im) in images.iter().enumerate() {
            for q in im
                .points
                .iter()
                .filter_map(|&p| (p != u32::MAX).then(|| partner(p)).flatten())
            {
                for &b in tracks.of(q) {
                    let b = b as usize;
                    if b != a {
                        if count[b] == 0 {
                            touched.push(b);
                        }
                        count[b] += 1;
                    }
                }
            }
            let mut best: Vec<(usize, usize)> = touched
                .iter()
                .filter(|&&b| count[b] >= self.min_common)
                .map(|&b| (count[b], b))
                .collect();
            best.sort_by(|x, y| y.0.cmp(&x.0).then(x.1.cmp(&y.1)));
            best.truncate(self.max_pairs_per_image);
            out.extend(best.into_iter().map(|(c, b)| (a, b, c)));
            for &b in &touched {
                count[b] = 0;
            }
            touched.clear();
        }
        out
    }

    /// The measured pairs: correct pairs (some twisted, pans near-pure), then repeated-structure
    /// pairs, sorted by images.
    fn pairs_of(
        &self,
        world: &World,
        views: &[View],
        pan_of: &[Option<usize>],
        images: &[Image],
        tracks: &Tracks,
        rng: &mut StdRng,
    ) -> Vec<ScenePair> {
        let mut correct: BTreeSet<(usize, usize)> = self
            .best_partners(images, tracks, Some)
            .into_iter()
            .map(|(a, b, _)| (a.min(b), a.max(b)))
            .collect();
        for (k, src) in pan_of.iter().enumerate() {
            if let Some(s) = src {
                correct.insert((*s.min(&k), *s.max(&k)));
            }
        }
        let mut planted: Vec<Planted> = Vec::with_capacity(correct.len());
        for &(a, b) in &correct {
            let near = pan_of[b] == Some(a) || pan_of[a] == Some(b);
            let kind = if near {
                PairKind::NearPure
            } else if rng.random::<f64>() < self.twisted {
                PairKind::Twisted
            } else {
                PairKind::Inlier
            };
            let correspondences = common_keypoints(&images[a], &images[b]);
            let start = relative_pose(&views[a], &views[b]);
            planted.push(Planted {
                a,
                b,
                correspondences,
                start,
                kind,
            });
        }
        let wanted = (self.repeated * correct.len() as f64).round() as usize;
        let built = Built {
            world,
            views,
            images,
            tracks,
        };
        planted.extend(self.repeated_pairs(&built, &correct, wanted, rng));
        planted.sort_by_key(|p| (p.a, p.b));
        let camera = self.camera();
        planted
            .into_iter()
            .filter_map(|p| self.measure(&camera, views, images, p, rng))
            .collect()
    }

    /// `wanted` pairs `(a, b)` that are not correct pairs, matching `a`'s facade points `X` with
    /// `b`'s `g(X)` (at least `min_common` of them), chosen at random.
    fn repeated_pairs(
        &self,
        built: &Built<'_>,
        correct: &BTreeSet<(usize, usize)>,
        wanted: usize,
        rng: &mut StdRng,
    ) -> Vec<Planted> {
        let Built {
            world,
            views,
            images,
            tracks,
        } = *built;
        if wanted == 0 {
            return Vec::new();
        }
        let mut seen = BTreeSet::new();
        let mut candidates: Vec<(usize, usize)> = self
            .best_partners(images, tracks, |p| world.symmetric(p))
            .into_iter()
            .filter(|&(a, b, _)| {
                let key = (a.min(b), a.max(b));
                !correct.contains(&key) && seen.insert(key)
            })
            .map(|(a, b, _)| (a, b))
            .collect();
        // a partial Fisher-Yates shuffle picks `wanted` of them
        let take = wanted.min(candidates.len());
        for k in 0..take {
            let j = rng.random_range(k..candidates.len());
            candidates.swap(k, j);
        }
        candidates.truncate(take);
        candidates
            .into_iter()
            .map(|(a, b)| {
                // a sees X, b sees g(X): b's camera moved by g^-1 sees X where b sees g(X)
                let mut pairs: Vec<[u32; 2]> = Vec::new();
                let mut o = Vector3::zeros();
                for (i, &p) in images[a].points.iter().enumerate() {
                    if let Some(gp) = world.symmetric(p).filter(|_| p != u32::MAX)
                        && let Some(j) = keypoint_of(&images[b], gp)
                    {
                        pairs.push([i as u32, j]);
                        o = world.centre_of(p);
                    }
                }
                let vb = &views[b];
                let moved = View {
                    r: vb.r * world.g,
                    c: o + world.g.inverse() * (vb.c - o),
                };
                let (lo, hi) = (a.min(b), a.max(b));
                let start = if a < b {
                    relative_pose(&views[a], &moved)
                } else {
                    relative_pose(&moved, &views[a])
                };
                let correspondences = if a < b {
                    pairs
                } else {
                    let mut flipped: Vec<[u32; 2]> = pairs.iter().map(|m| [m[1], m[0]]).collect();
                    flipped.sort_unstable();
                    flipped
                };
                Planted {
                    a: lo,
                    b: hi,
                    correspondences,
                    start,
                    kind: PairKind::Repeated,
                }
            })
            .collect()
    }

    /// Add wrong matches to a planted pair, take the inliers, estimate its geometry: `None`
    /// when fewer than 15 inliers remain or the pose is not determined.
    fn measure(
        &self,
        camera: &Camera,
        views: &[View],
        images: &[Image],
        p: Planted,
        rng: &mut StdRng,
    ) -> Option<ScenePair> {
        let (ia, ib) = (&images[p.a], &images[p.b]);
        let planted: BTreeSet<[u32; 2]> = p.correspondences.iter().copied().collect();
        let mut matches = p.correspondences.clone();
        let wrong = (self.wrong_matches * matches.len() as f64).round() as usize;
        for _ in 0..wrong {
            let m = [
                rng.random_range(0..ia.points.len()) as u32,
                rng.random_range(0..ib.points.len()) as u32,
            ];
            let (pa, pb) = (ia.points[m[0] as usize], ib.points[m[1] as usize]);
            if pa == u32::MAX || pa != pb {
                matches.push(m);
            }
        }
        matches.sort_unstable();
        matches.dedup();
        let norm = |im: &Image, k: u32| {
            let [x, y] = im.pixels[k as usize];
            camera
                .normalise(&Vector2::new(x as f64, y as f64))
                .expect("a pinhole camera")
        };
        let x: Vec<(Vector2<f64>, Vector2<f64>)> = matches
            .iter()
            .map(|m| (norm(ia, m[0]), norm(ib, m[1])))
            .collect();
        let (rotation, translation, inside) = self.estimate(camera, &x, p.start, p.kind)?;
        let inliers: Vec<[u32; 2]> = matches
            .iter()
            .zip(&inside)
            .filter_map(|(m, &i)| i.then_some(*m))
            .collect();
        if inliers.len() < MIN_INLIERS {
            return None;
        }
        let truth = views[p.b].r * views[p.a].r.inverse();
        Some(ScenePair {
            a: p.a,
            b: p.b,
            kind: p.kind,
            config: if p.kind == PairKind::NearPure { 5 } else { 2 },
            wrong_inliers: inliers.iter().filter(|m| !planted.contains(*m)).count(),
            matches,
            inliers,
            rotation,
            translation,
            rotation_error_deg: angle_between(&rotation, &truth).to_degrees(),
        })
    }

    /// The "RANSAC": inliers under the start pose, the pose refined from them, the inliers under
    /// it; twisted pairs get `Rot(t, pi) R`, near-pure ones the best rotation and `t = 0`.
    fn estimate(
        &self,
        camera: &Camera,
        x: &[(Vector2<f64>, Vector2<f64>)],
        (r0, t0): (Rotation, Vector3<f64>),
        kind: PairKind,
    ) -> Option<(Rotation, Vector3<f64>, Vec<bool>)> {
        let thr = self.inlier_threshold_px;
        let pick = |keep: &[bool]| -> (Vec<Vector2<f64>>, Vec<Vector2<f64>>) {
            x.iter()
                .zip(keep)
                .filter(|(_, k)| **k)
                .map(|(p, _)| *p)
                .unzip()
        };
        if kind == PairKind::NearPure {
            let inside = |r: &Rotation| -> Vec<bool> {
                x.iter()
                    .map(|(p, q)| {
                        let u = r * p.push(1.0);
                        u.z > 0.0 && (u.xy() / u.z - q).norm() * camera.focal.x < thr
                    })
                    .collect()
            };
            let (x1, x2) = pick(&inside(&r0));
            let r = wahba_rotation(&x1, &x2)?;
            let keep = inside(&r);
            return Some((r, Vector3::zeros(), keep));
        }
        let inside = |r: &Rotation, t: &Vector3<f64>| -> Vec<bool> {
            x.iter()
                .map(|(p, q)| sampson_error(r, t, p, q, camera, camera).abs() < thr)
                .collect()
        };
        let (x1, x2) = pick(&inside(&r0, &t0));
        let (r, t) = refine_relative_pose(&r0, &t0, &x1, &x2, camera, camera, 30).ok()?;
        let keep = inside(&r, &t);
        let r = if kind == PairKind::Twisted {
            geometry::half_turn(&t) * r
        } else {
            r
        };
        Some((r, t, keep))
    }
}

/// The keypoint pairs of the points two images both detect.
fn common_keypoints(a: &Image, b: &Image) -> Vec<[u32; 2]> {
    let (mut i, mut j, mut out) = (0, 0, Vec::new());
    while i < a.points.len()
        && j < b.points.len()
        && a.points[i] != u32::MAX
        && b.points[j] != u32::MAX
    {
        match a.points[i].cmp(&b.points[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                out.push([i as u32, j as u32]);
                i += 1;
                j += 1;
            }
        }
    }
    out
}

impl GeneratedScene {
    /// The scene's counts.
    pub fn summary(&self) -> SceneSummary {
        let mut pairs = [0; 4];
        for p in &self.pairs {
            pairs[PairKind::ALL
                .iter()
                .position(|k| *k == p.kind)
                .expect("a kind")] += 1;
        }
        SceneSummary {
            images: self.views.len(),
            pairs,
            keypoints: self.keypoints.iter().map(Vec::len).sum(),
            matches: self.pairs.iter().map(|p| p.matches.len()).sum(),
            inliers: self.pairs.iter().map(|p| p.inliers.len()).sum(),
            wrong_inliers: self.pairs.iter().map(|p| p.wrong_inliers).sum(),
        }
    }

    /// Image `k`'s name.
    pub fn name(&self, k: usize) -> String {
        format!("img_{:05}.jpg", k + 1)
    }

    /// The true world-to-camera rotations `R_k` (image `k` has id `k + 1`).
    pub fn rotations(&self) -> Vec<Rotation> {
        self.views.iter().map(|v| v.r).collect()
    }

    /// Write `dir/database.db` ([`Self::write_database`]), `dir/truth/`
    /// ([`Self::write_truth`]) and `dir/pairs.json` ([`Self::labels_json`]), creating `dir`.
    pub fn write(&self, dir: &Path) -> Result<()> {
        let io = |path: &Path, e: std::io::Error| Error::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        };
        std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
        self.write_database(&dir.join("database.db"))?;
        self.write_truth(&dir.join("truth"))?;
        let labels = dir.join("pairs.json");
        std::fs::write(&labels, self.labels_json()).map_err(|e| io(&labels, e))
    }

    /// The truth as a COLMAP text model in the folder `dir` (created): `cameras.txt` (the shared
    /// `PINHOLE` camera), `images.txt` (every image's true `cam_from_world`: `R_k` and
    /// `t_k = -R_k c_k`) and an empty `points3D.txt`.
    pub fn write_truth(&self, dir: &Path) -> Result<()> {
        let io = |path: &Path, e: std::io::Error| Error::Io {
            path: path.display().to_string(),
            message: e.to_string(),
        };
        std::fs::create_dir_all(dir).map_err(|e| io(dir, e))?;
        let s = &self.settings;
        let cam = self.settings.camera();
        let camera = ColmapCamera {
            camera_id: 1,
            model: "PINHOLE".into(),
            width: s.width_px as u64,
            height: s.height_px as u64,
            params: vec![cam.focal.x, cam.focal.y, cam.principal.x, cam.principal.y],
        };
        let cameras: Vec<ColmapCamera> = (0..s.rig_sensors)
            .map(|k| ColmapCamera {
                camera_id: k as u32 + 1,
                ..camera.clone()
            })
            .collect();
        let mut images = String::from(
            "# Image list with two lines of data per image:\n\
             #   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n\
             #   POINTS2D[] as (X, Y, POINT3D_ID)\n\
             # Written by rotavg::io::colmap::scene: the true poses (cam_from_world), no 2-D points.\n",
        );
        for (k, v) in self.views.iter().enumerate() {
            let [w, x, y, z] = wxyz(&v.r);
            let t = -(v.r * v.c);
            let _ = writeln!(
                images,
                "{} {w} {x} {y} {z} {} {} {} {} {}\n",
                k + 1,
                t.x,
                t.y,
                t.z,
                k % s.rig_sensors + 1,
                self.name(k)
            );
        }
        let mut files = vec![
            ("cameras.txt", write_cameras_text(&cameras)),
            ("images.txt", images),
            ("points3D.txt", empty_points3d_text().to_string()),
        ];
        if let Some(sensors) = &self.sensors_from_rig {
            let frames: Vec<Rotation> = self
                .views
                .iter()
                .step_by(sensors.len())
                .map(|v| v.r)
                .collect();
            files.push((
                "rig.json",
                crate::io::rig::write_rig_truth_json(&frames, sensors),
            ));
        }
        for (name, text) in files {
            let path = dir.join(name);
            std::fs::write(&path, text).map_err(|e| io(&path, e))?;
        }
        Ok(())
    }

    /// `pairs.json`: the settings, each image's id, name, true `qvec` (`w x y z`,
    /// world-to-camera) and centre, and each pair's image ids and names, kind, `config`, match
    /// and inlier counts, wrong inliers and the error of its stored rotation (degrees).
    pub fn labels_json(&self) -> String {
        output::labels_json(self)
    }

    /// Write the COLMAP database `path` (an existing file is replaced): COLMAP's tables
    /// `cameras`, `images`, `keypoints`, `descriptors` (empty), `matches` and
    /// `two_view_geometries` (`F`, `E`, `H` NULL), one transaction.
    pub fn write_database(&self, path: &Path) -> Result<()> {
        output::write_database(self, path)
    }

    /// COLMAP's `pair_id` of a pair.
    pub fn pair_id(&self, p: &ScenePair) -> u64 {
        image_pair_to_pair_id(p.a as u32 + 1, p.b as u32 + 1)
    }
}
