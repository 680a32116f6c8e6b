//! Write a synthetic gravity scene for side-by-side runs with other tools
//! (`benches/colmap_gravity.py`): a JSON view graph, gravity priors (`KEY gx gy gz`, the
//! world's down direction `e_3` in each camera's frame) and the truth (`id R11 .. R33`).
//!
//! ```text
//! cargo run --release --example gravity_scene -- FOLDER [N] [EDGES_PER_CAMERA] [NOISE_DEG] [GRAVITY_NOISE_DEG] [OUTLIER_FRACTION] [SEED]
//! ```
//!
//! Defaults: 1000 cameras, 4 edges per camera, 3 degrees RMS relative noise, priors good to
//! 0.5 degrees, no outliers, seed 1 (the generators of `gravity_table`).
use rotavg::multiple::synthetic::{SyntheticGraph, SyntheticGravity};
use std::fmt::Write as _;

fn main() -> rotavg::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let folder = std::path::PathBuf::from(args.get(1).map_or("gravity_scene", String::as_str));
    let arg = |k: usize, default: f64| -> f64 {
        args.get(k).and_then(|s| s.parse().ok()).unwrap_or(default)
    };
    let n = arg(2, 1000.0) as usize;
    let (per_camera, noise_deg, gravity_deg) = (arg(3, 4.0), arg(4, 3.0), arg(5, 0.5));
    let (outliers, seed) = (arg(6, 0.0), arg(7, 1.0) as u64);
    let (graph, truth) = SyntheticGraph {
        num_rotations: n,
        num_edges: (per_camera * n as f64) as usize,
        noise_sigma: (noise_deg / 3f64.sqrt()).to_radians(),
        outlier_fraction: outliers,
        seed,
    }
    .generate();
    let priors = SyntheticGravity {
        noise_deg: gravity_deg,
        missing_fraction: 0.0,
        seed,
    }
    .priors(&truth)?;
    let mut gravity =
        String::from("# KEY gx gy gz: the world's down direction e_3 in each camera's frame\n");
    let mut rows = String::from("# id R11 .. R33 (R_i, with R_ij R_i = R_j)\n");
    for (i, r) in truth.iter().enumerate() {
        if let Some(g) = priors.direction(i) {
            let _ = writeln!(gravity, "{i} {:.15} {:.15} {:.15}", g.x, g.y, g.z);
        }
        let _ = write!(rows, "{i}");
        for row in 0..3 {
            for col in 0..3 {
                let _ = write!(rows, " {:.15}", r.matrix()[(row, col)]);
            }
        }
        rows.push('\n');
    }
    let io = |e: std::io::Error| rotavg::Error::Io {
        path: folder.display().to_string(),
        message: e.to_string(),
    };
    std::fs::create_dir_all(&folder).map_err(io)?;
    std::fs::write(
        folder.join("graph.json"),
        rotavg::io::json::write_problem_json(&graph),
    )
    .map_err(io)?;
    std::fs::write(folder.join("gravity.txt"), gravity).map_err(io)?;
    std::fs::write(folder.join("truth.txt"), rows).map_err(io)?;
    println!(
        "wrote {}: {n} cameras, {} edges",
        folder.display(),
        graph.num_edges()
    );
    Ok(())
}
