//! Soft gravity priors on rigs whose sensors are estimated, certified jointly
//! (`paper-notes/gravity.md` `[G16]`): generated rigs (3 degrees of noise on the edges, every
//! sensor but the reference one estimated) with priors of 0.5 degrees on three images in four
//! and `W = 36`, run as `rotavg rig FILE --gravity P --gravity-weight 36` runs them
//! ([`average_rig_calibrated_with_gravity`]); one table row per rig: the whole run's and the
//! solves' seconds, the joint certificate and its seconds, the estimated sensors' mean error
//! (refined by the priors, then as returned), the frames' mean error, what was returned.
//!
//! `cargo run --release --example rig_gravity_joint [FRAMES SENSORS ...]` (default: 100 and
//! 1000 frames with 2, 4 and 6 sensors).

use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::gravity::GravityPriors;
use rotavg::pipeline::AverageSettings;
use rotavg::pipeline::rig::{RigLoss, average_rig_calibrated_with_gravity};
use rotavg::rig::{RigRobust, RigScene};

fn row(frames: usize, sensors: usize) -> rotavg::Result<String> {
    let (p, truth) = RigScene::sized(frames, sensors, 3f64.to_radians(), false, 3).generate();
    let dirs = truth.gravity(&p, 0.5f64.to_radians(), 4, 7);
    let g = GravityPriors::new(dirs)?.with_weight(36.0)?;
    let clock = std::time::Instant::now();
    let both = (RigLoss::Chordal, &RigRobust::default());
    let ((out, _, _), cal) =
        average_rig_calibrated_with_gravity(&p, g, both, &AverageSettings::default())?;
    let wall = clock.elapsed().as_secs_f64();
    let error = |s: &[rotavg::Rotation]| -> f64 {
        let e = cal
            .estimated
            .iter()
            .map(|&k| rotavg::so3::angle_between(&s[k], &truth.sensors[k]).to_degrees());
        e.sum::<f64>() / cal.estimated.len().max(1) as f64
    };
    let refined = (cal.refined_sensors_from_rig.as_deref()).unwrap_or(&cal.sensors_from_rig);
    let truth_some: Vec<_> = truth.frames.iter().copied().map(Some).collect();
    let frames_error = align_and_compare(&out.solution.frames, &truth_some)?.mean_deg;
    let joint = out.details.rig_joint.as_ref();
    let verdict = joint.map_or("not tried".into(), |j| {
        format!("{} ({:.1e})", j.verdict, j.relative_gap.unwrap_or(f64::NAN))
    });
    Ok(format!(
        "| {frames} | {sensors} | {wall:.2} | {:.2} | {verdict} | {:.2} | {:.4} -> {:.4} | {frames_error:.3} | {} |",
        out.details.solve_seconds,
        joint.map_or(0.0, |j| j.seconds),
        error(refined),
        error(&out.solution.sensors),
        match out.details.improved_by {
            Some(_) => "the polish",
            None => "the held rig's",
        }
    ))
}

fn main() -> rotavg::Result<()> {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let sizes: Vec<(usize, usize)> = match args.len() {
        0 | 1 => [100, 1000]
            .iter()
            .flat_map(|&f| [2, 4, 6].map(|s| (f, s)))
            .collect(),
        _ => args.chunks_exact(2).map(|c| (c[0], c[1])).collect(),
    };
    println!(
        "| frames | sensors | whole run s | solves s | joint certificate (relative gap) | joint s | \
         sensors' mean error deg, refined -> returned | frames' mean error deg | returned |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for (frames, sensors) in sizes {
        println!("{}", row(frames, sensors)?);
    }
    Ok(())
}
