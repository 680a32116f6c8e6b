//! Gravity priors on rigs with every sensor known (`paper-notes/gravity.md` `[G14]`): generated
//! rigs of 2 and 6 sensors, 100 to 10^4 frames, 3 degrees of noise on the edges, priors on
//! three images in four with 0.5 or 2 degrees of tilt noise; the frames' mean error against the
//! planted rig without priors, with them held, and soft (`W = (3 / sigma_g)^2`), with the time
//! of `rotavg::pipeline::average_rig` and its verdict.
//!
//! `cargo run --release --example rig_gravity [frames ...]`; `-- write DIR FRAMES SENSORS
//! SEED` writes one rig of the table (priors of 0.5 degrees) as `DIR/rig.json`,
//! `DIR/gravity.txt` and `DIR/truth.json`, for `rotavg rig` and `benches/colmap_rig.py`. The
//! committed example `examples/data/rig_gravity/` is made by `tests/suite/example_data.rs`.

use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::gravity::GravityPriors;
use rotavg::pipeline::average_rig;
use rotavg::rig::{RigProblem, RigScene, RigTruth};

fn scene(frames: usize, sensors: usize, noise: f64, seed: u64) -> (RigProblem, RigTruth) {
    RigScene::sized(frames, sensors, noise, true, seed).generate()
}

/// `write DIR FRAMES SENSORS SEED`.
fn write(args: &[String]) -> rotavg::Result<()> {
    let bad = || rotavg::Error::InvalidSettings {
        name: "write".into(),
        reason: "usage: write DIR FRAMES SENSORS SEED".into(),
    };
    let [dir, frames, sensors, seed] = args else {
        return Err(bad());
    };
    let number = |s: &String| s.parse::<usize>().map_err(|_| bad());
    let (frames, sensors, seed) = (number(frames)?, number(sensors)?, number(seed)? as u64);
    let (p, truth) = scene(frames, sensors, 3f64.to_radians(), seed);
    let priors = truth.gravity(&p, 0.5f64.to_radians(), 4, 7);
    let truth = rotavg::io::rig::write_rig_truth_json(&truth.frames, &truth.sensors);
    std::fs::create_dir_all(dir).map_err(|e| rotavg::Error::Io {
        path: dir.clone(),
        message: e.to_string(),
    })?;
    let out =
        |name: &str, text: &str| rotavg::io::output::write_text(&format!("{dir}/{name}"), text);
    out("rig.json", &rotavg::io::rig::write_rig_json(&p))?;
    out(
        "gravity.txt",
        &rotavg::io::gravity::write_gravity_text(&priors),
    )?;
    out("truth.json", &truth)
}

fn main() -> rotavg::Result<()> {
    let all: Vec<String> = std::env::args().skip(1).collect();
    if all.first().is_some_and(|a| a == "write") {
        return write(&all[1..]);
    }
    let sizes: Vec<usize> = all.iter().filter_map(|a| a.parse().ok()).collect();
    let sizes = if sizes.is_empty() {
        vec![100, 1000, 10_000]
    } else {
        sizes
    };
    println!("| frames | sensors | priors (deg) | priors | mean error (deg) | seconds | verdict |");
    println!("|---|---|---|---|---|---|---|");
    for &frames in &sizes {
        for sensors in [2, 6] {
            let (p, truth) = scene(
                frames,
                sensors,
                3f64.to_radians(),
                frames as u64 + sensors as u64,
            );
            let truth_some: Vec<_> = truth.frames.iter().copied().map(Some).collect();
            for sigma_g in [0.5f64, 2.0] {
                let dirs = truth.gravity(&p, sigma_g.to_radians(), 4, 7);
                let weight = (3.0 / sigma_g).powi(2);
                let runs = [
                    ("none", None),
                    ("held", Some(GravityPriors::new(dirs.clone())?)),
                    (
                        "soft",
                        Some(GravityPriors::new(dirs.clone())?.with_weight(weight)?),
                    ),
                ];
                for (name, g) in runs {
                    if name == "none" && sigma_g > 1.0 {
                        continue;
                    }
                    let q = match g {
                        Some(g) => p.clone().with_gravity(g)?,
                        None => p.clone(),
                    };
                    let clock = std::time::Instant::now();
                    let out = average_rig(&q, &Default::default())?;
                    let seconds = clock.elapsed().as_secs_f64();
                    let acc = align_and_compare(&out.solution.frames, &truth_some)?;
                    let verdict = out.certificate.map_or("none".to_string(), |c| {
                        format!(
                            "{:?}, relative gap {:.1e}",
                            c.verdict,
                            c.relative_gap.unwrap_or(f64::NAN)
                        )
                    });
                    println!(
                        "| {frames} | {sensors} | {sigma_g} | {name} | {:.3} | {seconds:.2} | {verdict} |",
                        acc.mean_deg
                    );
                }
            }
        }
    }
    Ok(())
}
