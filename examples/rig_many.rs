//! Rigs of several sensors at scale (`paper-notes/conjugate.md` `[H19]`): generated rigs of
//! 2-6 sensors and 100 to 10^4 frames, solved and certified by `rotavg::pipeline::average_rig`,
//! with every sensor estimated and with every sensor known; the error against the planted rig.
//!
//! `cargo run --release --example rig_many [frames ...] [anisotropic] [known | estimated]
//! [sensors=2,4,6] [span=W] [memory=GiB] [verbose]` (`span`: each sensor's extra pairs within
//! `W` frames, `RigScene::extra_edge_span`; default any two frames) (`memory`: the certificate's memory budget, default
//! 4; `verbose`: the certificate's ladder and the progress lines on stderr) (`anisotropic`: the
//! edges carry information matrices, `RigScene::anisotropy` 9, `[H24]`, and a last column gives
//! the sensors' error of the same data with scalar weights `tr(H)/3`, solve only; `known`: only
//! the rows with every sensor known); `-- write DIR FRAMES SENSORS OUTLIERS
//! SEED` writes one rig (`RigScene`, 0.01 rad of noise, that fraction of random-rotation
//! outliers) as `DIR/rig.json` and its truth `DIR/truth.json`, for `rotavg rig` and
//! `benches/colmap_rig.py`.

use rotavg::pipeline::average_rig;
use rotavg::rig::RigScene;
use rotavg::so3::angle_between;

/// `write DIR FRAMES SENSORS OUTLIERS SEED`: one rig and its truth.
fn write(args: &[String]) -> rotavg::Result<()> {
    let bad = || rotavg::Error::InvalidSettings {
        name: "write".into(),
        reason: "usage: write DIR FRAMES SENSORS OUTLIERS SEED".into(),
    };
    let [dir, frames, sensors, outliers, seed] = args else {
        return Err(bad());
    };
    let scene = RigScene {
        frames: frames.parse().map_err(|_| bad())?,
        sensors: sensors.parse().map_err(|_| bad())?,
        outlier_fraction: outliers.parse().map_err(|_| bad())?,
        seed: seed.parse().map_err(|_| bad())?,
        noise_sigma: 0.01,
        ..Default::default()
    };
    let (p, truth) = scene.generate();
    let truth = rotavg::io::rig::write_rig_truth_json(&truth.frames, &truth.sensors);
    std::fs::create_dir_all(dir).map_err(|e| rotavg::Error::Io {
        path: dir.clone(),
        message: e.to_string(),
    })?;
    rotavg::io::output::write_text(
        &format!("{dir}/rig.json"),
        &rotavg::io::rig::write_rig_json(&p),
    )?;
    rotavg::io::output::write_text(&format!("{dir}/truth.json"), &truth)
}

fn main() -> rotavg::Result<()> {
    let all: Vec<String> = std::env::args().skip(1).collect();
    if all.first().is_some_and(|a| a == "write") {
        return write(&all[1..]);
    }
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let sizes = if args.is_empty() {
        vec![100, 1000, 10_000]
    } else {
        args
    };
    let known_only = all.iter().any(|a| a == "known");
    let estimated_only = all.iter().any(|a| a == "estimated");
    let verbose = all.iter().any(|a| a == "verbose");
    if verbose {
        // the progress lines the command line writes, on stderr
        let lines = std::sync::Arc::new(rotavg::progress::ProgressLines::new());
        rotavg::progress::set_observer(Some(lines.clone()));
        lines.spawn(rotavg::progress::ProgressLines::delay_from_env());
    }
    let span: usize = all
        .iter()
        .find_map(|a| a.strip_prefix("span=").and_then(|m| m.parse().ok()))
        .unwrap_or(0);
    let memory_gib: Option<u64> = all
        .iter()
        .find_map(|a| a.strip_prefix("memory=").and_then(|m| m.parse().ok()));
    let sensor_counts: Vec<usize> = match all.iter().find_map(|a| a.strip_prefix("sensors=")) {
        Some(k) => k.split(',').filter_map(|k| k.parse().ok()).collect(),
        None => vec![2, 4, 6],
    };
    let anisotropy = if all.iter().any(|a| a == "anisotropic") {
        9.0
    } else {
        1.0
    };
    println!(
        "| frames | sensors | images | edges | sensors known | solve s | passes | certify s | verdict | relative gap | frames' median error deg | sensors' max error deg |{}",
        if anisotropy > 1.0 {
            " scalar weights: sensors' max error deg |"
        } else {
            ""
        }
    );
    println!(
        "|---|---|---|---|---|---|---|---|---|---|---|---|{}",
        if anisotropy > 1.0 { "---|" } else { "" }
    );
    for &frames in &sizes {
        for &sensors in &sensor_counts {
            for known in [false, true] {
                if (known_only && !known) || (estimated_only && known) {
                    continue;
                }
                let scene = RigScene {
                    frames,
                    sensors,
                    noise_sigma: 0.01,
                    known,
                    seed: 7,
                    anisotropy,
                    extra_edge_span: span,
                    ..Default::default()
                };
                let (p, truth) = scene.generate();
                let max_error = |x: &[rotavg::Rotation]| {
                    (x.iter().zip(&truth.sensors))
                        .map(|(a, b)| angle_between(a, b).to_degrees())
                        .fold(0.0, f64::max)
                };
                let mut settings = rotavg::pipeline::rig::AverageRigSettings::default();
                if let Some(gib) = memory_gib {
                    settings.certify.budget.max_memory_bytes = gib << 30;
                }
                let out = average_rig(&p, &settings)?;
                let c = out.certificate.as_ref().expect("certified");
                if verbose {
                    for a in out.details.certify.iter().flat_map(|d| &d.ladder) {
                        eprintln!("  {} {:.3} s {} {:?}", a.rung, a.seconds, a.note, a.outcome);
                    }
                    eprintln!("  {}", c.explanation);
                }
                let s = &out.solution;
                let mut errs: Vec<f64> = s
                    .frames
                    .iter()
                    .zip(&truth.frames)
                    .map(|(a, b)| angle_between(a, b).to_degrees())
                    .collect();
                errs.sort_by(f64::total_cmp);
                let sens = max_error(&s.sensors);
                let scalar = if anisotropy > 1.0 && !known {
                    let r = rotavg::rig::solve_rig(&p.scalar(), &Default::default())?;
                    format!(" {:.4} |", max_error(&r.sensors))
                } else if anisotropy > 1.0 {
                    " |".to_string()
                } else {
                    String::new()
                };
                println!(
                    "| {frames} | {sensors} | {} | {} | {known} | {:.3} | {} | {:.3} | {} | {:.1e} | {:.3} | {:.4} |{scalar}",
                    p.images().len(),
                    p.edges().len(),
                    out.details.solve_seconds,
                    s.report.iterations,
                    out.details.certify_seconds,
                    c.verdict,
                    c.relative_gap.unwrap_or(f64::NAN),
                    errs[errs.len() / 2],
                    sens
                );
            }
        }
    }
    Ok(())
}
