//! Write gravity priors for the rotations of a truth file (`rotavg rig RIGHT LEFT --gravity`,
//! `rotavg multiple --gravity`): `KEY gx gy gz` lines, `KEY` the rotation's index, `g` the
//! world's down direction `e_3` in its frame turned by a normal angle of `NOISE_DEG` degrees
//! (standard deviation) about a random axis, a fraction `MISSING` of them (never the first)
//! left out ([`rotavg::multiple::synthetic::SyntheticGravity`]). The truth is JSON with
//! `"rotations"` or `"frames"` (as `examples/data/rig/truth.json` and `rig_pair` write it).
//!
//! ```text
//! cargo run --release --example gravity_priors -- TRUTH.json NOISE_DEG MISSING SEED > gravity.txt
//! ```
use rotavg::multiple::synthetic::SyntheticGravity;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [truth, noise, missing, seed] = args.as_slice() else {
        return Err("usage: gravity_priors TRUTH.json NOISE_DEG MISSING SEED".into());
    };
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(truth)?)?;
    let rows = v.get("rotations").or_else(|| v.get("frames"));
    let rows: Vec<[[f64; 3]; 3]> = serde_json::from_value(rows.ok_or("no rotations")?.clone())?;
    let rotations = (rows.iter())
        .map(|r| rotavg::so3::rotation_from_rows(r, 1e-9, truth))
        .collect::<rotavg::Result<Vec<_>>>()?;
    let priors = SyntheticGravity {
        noise_deg: noise.parse()?,
        missing_fraction: missing.parse()?,
        seed: seed.parse()?,
    }
    .priors(&rotations)?;
    let directions: Vec<Option<[f64; 3]>> = (0..priors.len())
        .map(|i| priors.direction(i).map(Into::into))
        .collect();
    print!("{}", rotavg::io::gravity::write_gravity_text(&directions));
    Ok(())
}
