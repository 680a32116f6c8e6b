//! The rig's robust scale from the data (`paper-notes/conjugate.md` `[H20]` "The scale"):
//! against the closed-form median of Gaussian residual angles, under scaled weights, and by the
//! accuracy against planted rigs it buys over the fixed 5 degrees.

use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::robust_scale::{MAX_DATA_SCALE_DEG, ScaleRule};
use rotavg::rig::{
    RigProblem, RigRobust, RigScene, RigSettings, RigTruth, rig_data_scale, solve_rig_robust,
};

/// The median of `sigma chi(3)` (the residual angle of Gaussian noise of `sigma` per axis) over
/// `sigma`: the root of the chi distribution's CDF at 1/2, `1.5382`.
const CHI3_MEDIAN: f64 = 1.5382;

fn scene(sigma_deg: f64, outliers: f64, moderate: bool, seed: u64) -> (RigProblem, RigTruth) {
    RigScene {
        frames: 150,
        sensors: 3,
        noise_sigma: sigma_deg.to_radians(),
        outlier_fraction: outliers,
        outlier_angle_deg: moderate.then_some((3.0, 15.0)),
        seed,
        ..Default::default()
    }
    .generate()
}

/// With 10 % random-rotation outliers the median residual the scale is read from is an
/// inlier's: within 0.85-1.3 times the closed form `1.538 sigma` from 0.1 to 2 degrees of
/// noise, the scale 1.5 times it and the inlier threshold 3 times it (to three digits); at 8
/// degrees both are the 10 degree bound and say so.
#[test]
fn the_scale_follows_the_noise() {
    for (k, sigma_deg) in [0.1, 0.5, 1.0, 2.0].into_iter().enumerate() {
        let (p, _) = scene(sigma_deg, 0.1, false, 11 + k as u64);
        let s = rig_data_scale(&p, &RigSettings::default()).unwrap();
        let ratio = s.median_deg / (CHI3_MEDIAN * sigma_deg);
        assert!((0.85..1.3).contains(&ratio), "{sigma_deg}: {s:?}");
        let near = |a: f64, b: f64| (a - b).abs() <= 0.006 * b;
        assert!(near(s.scale_deg, 1.5 * s.median_deg), "{s:?}");
        assert!(near(s.inlier_threshold_deg, 3.0 * s.median_deg), "{s:?}");
        assert!(!s.clamped && s.mahalanobis_median_deg.is_none());
    }
    let (p, _) = scene(8.0, 0.1, false, 17);
    let s = rig_data_scale(&p, &RigSettings::default()).unwrap();
    assert_eq!(
        (s.scale_deg, s.inlier_threshold_deg),
        (MAX_DATA_SCALE_DEG, MAX_DATA_SCALE_DEG)
    );
    assert!(s.clamped, "{s:?}");
}

/// Every weight times `1e-4` or `1e4`: the same scale, threshold and inlier edges.
#[test]
fn scaled_weights_keep_the_scale_and_the_inliers() {
    let (p, _) = scene(0.5, 0.15, true, 21);
    let scaled = |c: f64| {
        let edges = (p.edges().iter())
            .map(|e| rotavg::multiple::Edge {
                weight: c * e.weight,
                ..e.clone()
            })
            .collect();
        p.with_edges(edges).unwrap()
    };
    let run = |q: &RigProblem| solve_rig_robust(q, &RigRobust::default(), &Default::default());
    let base = run(&p).unwrap();
    let s = base.scale.clone().expect("the scale from the data");
    for c in [1e-4, 1e4] {
        let other = run(&scaled(c)).unwrap();
        let t = other.scale.unwrap();
        assert_eq!(
            (t.scale_deg, t.inlier_threshold_deg),
            (s.scale_deg, s.inlier_threshold_deg)
        );
        assert_eq!(other.inliers, base.inliers, "{c}");
    }
}

/// The frames' median error after the optimal alignment and the sensors' mean error, degrees.
fn errors(frames: &[rotavg::Rotation], sensors: &[rotavg::Rotation], t: &RigTruth) -> (f64, f64) {
    let known: Vec<_> = t.frames.iter().copied().map(Some).collect();
    let f = align_and_compare(frames, &known).unwrap().median_deg;
    let s = (1..sensors.len())
        .map(|k| rotavg::so3::angle_between(&sensors[k], &t.sensors[k]).to_degrees())
        .sum::<f64>()
        / (sensors.len() - 1) as f64;
    (f, s)
}

/// The scale from the data against the fixed 5 degrees, by the error against the planted rig:
/// 0.1 degrees of noise and 15 % wrong pairs 3-15 degrees off (repeated structure), where 5
/// degrees keeps most of them (frames and sensors measured 3x closer with the scale,
/// 2026-12-07); and 4 degrees of noise with random outliers, where 5 degrees drops half the
/// inliers (frames 1.3-1.4x closer; the sensors' error, from fewer pairs, is not always
/// smaller there).
#[test]
fn the_scale_from_the_data_is_more_accurate_than_five_degrees() {
    for (sigma_deg, moderate, factor, sensors) in [(0.1, true, 0.5, 0.5), (4.0, false, 0.85, 1.5)] {
        let (p, truth) = scene(sigma_deg, 0.15, moderate, 31);
        let run = |scale: ScaleRule| {
            let robust = RigRobust {
                scale,
                ..Default::default()
            };
            let r = solve_rig_robust(&p, &robust, &Default::default()).unwrap();
            let s = &r.inlier_solution;
            errors(&s.frames, &s.sensors, &truth)
        };
        let (data, fixed) = (run(ScaleRule::FromData), run(ScaleRule::Given));
        assert!(
            data.0 < factor * fixed.0 && data.1 < sensors * fixed.1,
            "{sigma_deg} deg: from the data {data:?}, 5 deg {fixed:?}"
        );
    }
}
