//! Writes a two-sensor rig as two view graphs (`rotavg rig RIGHT LEFT`): a
//! [`rotavg::pipeline::simultaneous::SyntheticRig`] of `FRAMES` frames, 4 pairs per frame on
//! both graphs, `NOISE` rad of noise (default 0.01) and a fraction `OUTLIERS` of random-rotation
//! outliers on each, with its planted frames and `S` (`truth.json`: `{"frames": [...], "s":
//! ...}`, rows); `gravity_priors` writes priors on its frames.
//!
//! ```text
//! cargo run --release --example rig_pair -- FRAMES OUTLIERS SEED DIR [NOISE]
//! rotavg rig DIR/right.json DIR/left.json --json
//! ```
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::pipeline::simultaneous::SyntheticRig;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: rig_pair FRAMES OUTLIERS SEED DIR [NOISE]";
    let (frames, outliers, seed, dir, noise) = match args.as_slice() {
        [f, o, s, d] => (f, o, s, d, 0.01),
        [f, o, s, d, noise] => (f, o, s, d, noise.parse()?),
        _ => return Err(usage.into()),
    };
    let n: usize = frames.parse()?;
    let graph = SyntheticGraph {
        num_rotations: n,
        num_edges: 4 * n,
        noise_sigma: noise,
        outlier_fraction: outliers.parse()?,
        seed: seed.parse()?,
    };
    let (p, frames, s) = SyntheticRig { graph }.generate();
    let (right, left) = p.graphs()?;
    std::fs::create_dir_all(dir)?;
    std::fs::write(format!("{dir}/right.json"), serde_json::to_string(&right)?)?;
    std::fs::write(format!("{dir}/left.json"), serde_json::to_string(&left)?)?;
    let rows = |r: &rotavg::Rotation| -> Vec<[f64; 3]> {
        let m = r.matrix();
        (0..3).map(|i| [m[(i, 0)], m[(i, 1)], m[(i, 2)]]).collect()
    };
    let truth = serde_json::json!({
        "frames": frames.iter().map(rows).collect::<Vec<_>>(),
        "s": rows(&s),
    });
    std::fs::write(format!("{dir}/truth.json"), truth.to_string())?;
    Ok(())
}
