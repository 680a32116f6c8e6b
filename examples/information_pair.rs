//! Writes two view graphs with information matrices over the same frames, the rig of two
//! sensors they describe (`rotavg rig RIGHT LEFT`, `paper-notes/conjugate.md` `[H22]`
//! "Information", `[H27]`): `FRAMES` random frames and a random `S`, each graph a ring plus
//! random pairs (3 edges per frame), every edge with its own information `H = Q diag(1/sd^2)
//! Q^T` (random axes `Q`, per-axis standard deviations `sd = SIGMA exp(SPREAD z)`, `z` normal)
//! and noise drawn from it; the left graph measures `S R_ij S^T`. Writes `DIR/right.json`,
//! `DIR/left.json` and `DIR/truth.json` (`{"frames": [...], "s": ...}`, rows).
//!
//! ```text
//! cargo run --release --example information_pair -- FRAMES SIGMA SPREAD SEED DIR
//! rotavg rig DIR/right.json DIR/left.json
//! ```
use nalgebra::{Matrix3, Vector3};
use rand::{Rng, SeedableRng};
use rotavg::Rotation;
use rotavg::so3::{exp, gaussian, random_rotation, rotation_to_rows};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [frames, sigma, spread, seed, dir] = args.as_slice() else {
        return Err("usage: information_pair FRAMES SIGMA SPREAD SEED DIR".into());
    };
    let (n, sigma, spread): (usize, f64, f64) = (frames.parse()?, sigma.parse()?, spread.parse()?);
    if n < 3 {
        return Err("at least 3 frames".into());
    }
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed.parse()?);
    let truth: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
    let s = random_rotation(&mut rng);
    let lefts: Vec<Rotation> = truth.iter().map(|f| s * f).collect();
    std::fs::create_dir_all(dir)?;
    for (name, x) in [("right", &truth), ("left", &lefts)] {
        let mut pairs: Vec<(usize, usize)> = (0..n).map(|i| (i, (i + 1) % n)).collect();
        while pairs.len() < 3 * n {
            let (i, j) = (rng.random_range(0..n), rng.random_range(0..n));
            if i != j && !pairs.contains(&(i, j)) && !pairs.contains(&(j, i)) {
                pairs.push((i, j));
            }
        }
        let edges: Vec<serde_json::Value> = (pairs.iter())
            .map(|&(i, j)| {
                let sd = Vector3::from_fn(|_, _| sigma * (spread * gaussian(&mut rng)).exp());
                let q = random_rotation(&mut rng);
                let h = q.matrix() * Matrix3::from_diagonal(&sd.map(|d| 1.0 / (d * d)))
                    * q.matrix().transpose();
                let e = q * Vector3::from_fn(|k, _| sd[k] * gaussian(&mut rng));
                let r = x[j] * x[i].inverse() * exp(&-e);
                let h = 0.5 * (h + h.transpose());
                let rows: Vec<Vec<f64>> = (0..3).map(|a| (0..3).map(|b| h[(a, b)]).collect()).collect();
                serde_json::json!({"i": i, "j": j, "rotation": rotation_to_rows(&r), "information": rows})
            })
            .collect();
        let graph = serde_json::json!({"num_rotations": n, "edges": edges});
        std::fs::write(format!("{dir}/{name}.json"), graph.to_string())?;
    }
    let truth = serde_json::json!({
        "frames": truth.iter().map(rotation_to_rows).collect::<Vec<_>>(),
        "s": rotation_to_rows(&s),
    });
    std::fs::write(format!("{dir}/truth.json"), truth.to_string())?;
    Ok(())
}
