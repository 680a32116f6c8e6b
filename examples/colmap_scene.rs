//! Write a seeded structure-from-motion scene as a COLMAP database with its ground truth
//! (`rotavg::io::colmap::scene`): `OUT_DIR/database.db`, `OUT_DIR/truth/` (a COLMAP text model
//! of the true poses) and `OUT_DIR/pairs.json` (each pair's kind and rotation error).
//!
//! ```text
//! cargo run --release --example colmap_scene -- OUT_DIR [--cameras N] [--seed S] [--twisted F]
//!     [--repeated F] [--near-pure F] [--wrong-matches F] [--pixel-sigma PX] [--focal PX]
//!     [--points-per-facade N] [--cameras-per-site N] [--max-pairs N] [--min-common N]
//!     [--symmetry DEG] [--rig-sensors K] [--rig-yaw DEG] [--rig-known] [--settings FILE.json]
//! rotavg multiple OUT_DIR/database.db --information full --ground-truth OUT_DIR/truth
//! ```
//!
//! `--settings` reads an `SfmScene` as JSON (missing fields take their defaults); the other
//! options then override it. Prints one line: images, pairs by kind, matches, and the times.
use rotavg::io::colmap::scene::SfmScene;
use std::time::Instant;

fn bad(reason: String) -> rotavg::Error {
    rotavg::Error::InvalidSettings {
        name: "arguments".into(),
        reason,
    }
}

/// The settings and output folder of the command line.
fn parse(args: &[String]) -> rotavg::Result<(SfmScene, String)> {
    let mut s = SfmScene::default();
    let mut out = None;
    let mut k = 0;
    while k < args.len() {
        let flag = args[k].as_str();
        if !flag.starts_with("--") {
            out = Some(flag.to_string());
            k += 1;
            continue;
        }
        if flag == "--rig-known" {
            s.rig_known = true;
            k += 1;
            continue;
        }
        let value = args
            .get(k + 1)
            .ok_or_else(|| bad(format!("{flag} needs a value")))?;
        let num = || -> rotavg::Result<f64> {
            value
                .parse()
                .map_err(|_| bad(format!("{flag} {value}: not a number")))
        };
        match flag {
            "--settings" => {
                let text =
                    std::fs::read_to_string(value).map_err(|e| bad(format!("{value}: {e}")))?;
                s = serde_json::from_str(&text).map_err(|e| bad(format!("{value}: {e}")))?;
            }
            "--cameras" => s.cameras = num()? as usize,
            "--seed" => s.seed = num()? as u64,
            "--twisted" => s.twisted = num()?,
            "--repeated" => s.repeated = num()?,
            "--near-pure" => s.near_pure = num()?,
            "--wrong-matches" => s.wrong_matches = num()?,
            "--pixel-sigma" => s.pixel_sigma = num()?,
            "--focal" => s.focal_px = num()?,
            "--points-per-facade" => s.points_per_facade = num()? as usize,
            "--cameras-per-site" => s.cameras_per_site = num()? as usize,
            "--max-pairs" => s.max_pairs_per_image = num()? as usize,
            "--min-common" => s.min_common = num()? as usize,
            "--symmetry" => s.symmetry_deg = num()?,
            "--rig-sensors" => s.rig_sensors = num()? as usize,
            "--rig-yaw" => s.rig_yaw_deg = num()?,

            other => return Err(bad(format!("unknown option {other}"))),
        }
        k += 2;
    }
    let out = out.ok_or_else(|| bad("usage: colmap_scene OUT_DIR [--cameras N] ...".into()))?;
    Ok((s, out))
}

fn main() {
    if let Err(e) = run() {
        eprintln!("colmap_scene: {e}");
        std::process::exit(2);
    }
}

fn run() -> rotavg::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (settings, out) = parse(&args)?;
    let start = Instant::now();
    let scene = settings.generate()?;
    let generated = start.elapsed().as_secs_f64();
    scene.write(std::path::Path::new(&out))?;
    let written = start.elapsed().as_secs_f64() - generated;
    println!(
        "{out}: {}; generated in {generated:.2} s, written in {written:.2} s",
        scene.summary()
    );
    Ok(())
}
