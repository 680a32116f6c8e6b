//! The rig's robust scale, fixed or from the data (`paper-notes/conjugate.md` `[H20]` "The
//! scale"): generated rigs with outliers solved by the default loss (`auto`, which turns to
//! Cauchy on them) with the Cauchy scale and inlier threshold both 5 degrees (the rule before
//! 2026-12-07) and with both from the data (`rig_data_scale`, the default since), certified as
//! `rotavg rig FILE` does; the error against the planted rig.
//!
//! ```text
//! cargo run --release --example rig_robust_scale -- [FRAMES [SENSORS [SEEDS]]]
//! ```
//!
//! Defaults 300 frames, 4 sensors (every one estimated), seeds 1-3. Rows: the outlier model
//! (`random`: random rotations; `3-15 deg`: the true rotation turned by 3-15 degrees about a
//! random axis, as repeated structure makes), the noise per axis (with `aniso`: along the
//! well-determined axes, the weak one `RigScene::anisotropy` 9 times it, information
//! matrices), the outlier fraction; per rule the frames' median error after the optimal
//! alignment, the sensors' mean error, the inlier edges, the verdict and the whole run's time.

use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::robust_scale::ScaleRule;
use rotavg::pipeline::rig::{RigLoss, average_rig_with_loss};
use rotavg::rig::{RigProblem, RigRobust, RigScene, RigTruth};
use rotavg::so3::angle_between;

/// One outlier model, noise and fraction.
struct Case {
    moderate: bool,
    sigma_deg: f64,
    anisotropy: f64,
    outliers: f64,
}

fn main() -> rotavg::Result<()> {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let arg = |k: usize, default: usize| args.get(k).copied().unwrap_or(default);
    let (frames, sensors, seeds) = (arg(0, 300), arg(1, 4), arg(2, 3));
    let mut cases = Vec::new();
    for sigma_deg in [0.1, 0.3, 1.0, 2.0, 4.0] {
        cases.push(Case {
            moderate: false,
            sigma_deg,
            anisotropy: 1.0,
            outliers: 0.15,
        });
    }
    for sigma_deg in [0.1, 0.3, 1.0, 2.0] {
        cases.push(Case {
            moderate: true,
            sigma_deg,
            anisotropy: 1.0,
            outliers: 0.15,
        });
    }
    for sigma_deg in [0.1, 0.3, 1.0] {
        cases.push(Case {
            moderate: true,
            sigma_deg,
            anisotropy: 9.0,
            outliers: 0.15,
        });
    }
    println!("{frames} frames, {sensors} sensors (all estimated), seeds 1-{seeds}");
    println!(
        "| outliers | noise | seed | 5 deg: frames / sensors deg, inliers, verdict, s | from the \
         data (scale / threshold deg): frames / sensors deg, inliers, verdict, s |"
    );
    println!("|---|---|---|---|---|");
    for case in &cases {
        for seed in 1..=seeds as u64 {
            let scene = RigScene {
                frames,
                sensors,
                noise_sigma: case.sigma_deg.to_radians(),
                outlier_fraction: case.outliers,
                outlier_angle_deg: case.moderate.then_some((3.0, 15.0)),
                anisotropy: case.anisotropy,
                seed,
                ..Default::default()
            };
            let (p, truth) = scene.generate();
            let model = match case.moderate {
                true => "3-15 deg",
                false => "random",
            };
            let aniso = if case.anisotropy > 1.0 { " aniso" } else { "" };
            let mut row = format!(
                "| {model} {:.0} % | {} deg{aniso} | {seed} |",
                100.0 * case.outliers,
                case.sigma_deg
            );
            for scale in [ScaleRule::Given, ScaleRule::FromData] {
                row += &cell(&p, &truth, scale)?;
            }
            println!("{row}");
        }
    }
    Ok(())
}

/// One rule's cell of a row: the default loss on `p` with the scale `scale`, against `truth`.
fn cell(p: &RigProblem, truth: &RigTruth, scale: ScaleRule) -> rotavg::Result<String> {
    let robust = RigRobust {
        scale,
        ..Default::default()
    };
    let start = std::time::Instant::now();
    let (out, _, details) = average_rig_with_loss(p, RigLoss::Auto, &robust, &Default::default())?;
    let seconds = start.elapsed().as_secs_f64();
    let s = &out.solution;
    let known: Vec<_> = truth.frames.iter().copied().map(Some).collect();
    let frames_err = align_and_compare(&s.frames, &known)?.median_deg;
    let sensors = s.sensors.len();
    let sensors_err = (1..sensors)
        .map(|k| angle_between(&s.sensors[k], &truth.sensors[k]).to_degrees())
        .sum::<f64>()
        / (sensors - 1).max(1) as f64;
    let verdict = (out.certificate).map_or("none".into(), |c| c.verdict.to_string());
    let (inliers, scale_words) = match &details {
        Some(d) => (
            format!("{}/{}", d.inlier_edges, d.total_edges),
            match &d.data_scale {
                Some(x) => format!(" ({} / {})", x.scale_deg, x.inlier_threshold_deg),
                None => String::new(),
            },
        ),
        None => ("all (least squares)".into(), String::new()),
    };
    Ok(format!(
        "{scale_words} {frames_err:.4} / {sensors_err:.4}, {inliers}, {verdict}, {seconds:.2} |"
    ))
}
