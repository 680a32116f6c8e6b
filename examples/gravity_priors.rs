//! Write gravity priors for the rotations of a truth file (`rotavg rig RIGHT LEFT --gravity`,
//! `rotavg multiple --gravity`): `KEY gx gy gz` lines, `KEY` the rotation's index, `g` the
//! world's down direction `e_3` in its frame turned by a normal angle of `NOISE_DEG` degrees
//! (standard deviation) about a random axis, a fraction `MISSING` of them (never the first)
//! left out ([`rotavg::multiple::synthetic::SyntheticGravity`]). The truth is JSON with
//! `"rotations"` or `"frames"` (as `examples/data/rig/truth.json` and `rig_pair` write it); with
//! a view graph `GRAPH` (any file or COLMAP database `rotavg multiple` reads), any ground truth
//! `--ground-truth` reads for it (a COLMAP `images.txt` or model folder, as `colmap_scene`
//! writes), and `KEY` is the graph's file id (image id) of each node; the generated scenes have
//! `z` up, so there the directions are of the world's down `-e_3`, to be read with
//! `--world-down 0,0,-1`.
//!
//! ```text
//! cargo run --release --example gravity_priors -- TRUTH.json NOISE_DEG MISSING SEED > gravity.txt
//! cargo run --release --example gravity_priors -- DIR/truth NOISE_DEG MISSING SEED DIR/database.db > gravity.txt
//! ```
use rotavg::Rotation;
use rotavg::multiple::synthetic::SyntheticGravity;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (truth, noise, missing, seed, graph) = match args.as_slice() {
        [t, n, m, s] => (t, n, m, s, None),
        [t, n, m, s, g] => (t, n, m, s, Some(g)),
        _ => return Err("usage: gravity_priors TRUTH NOISE_DEG MISSING SEED [GRAPH]".into()),
    };
    let (rotations, keys) = match graph {
        None => (truth_json(truth)?, None),
        Some(graph) => {
            let (rotations, keys) = truth_of_graph(truth, graph)?;
            (rotations, Some(keys))
        }
    };
    let priors = SyntheticGravity {
        noise_deg: noise.parse()?,
        missing_fraction: missing.parse()?,
        seed: seed.parse()?,
    }
    .priors(&rotations)?;
    let directions: Vec<Option<[f64; 3]>> = (0..priors.len())
        .map(|i| priors.direction(i).map(Into::into))
        .collect();
    let text = rotavg::io::gravity::write_gravity_text(&directions);
    let Some(keys) = keys else {
        print!("{text}");
        return Ok(());
    };
    // the lines are keyed by index: put each node's file id instead; the generated scenes
    // (`colmap_scene`) have `z` up, so their down is `-z`: the directions negated, read with
    // `--world-down 0,0,-1` (the priors' check warns about up vectors otherwise)
    println!("# world down (0, 0, -1) (z up): rotavg ... --gravity FILE --world-down 0,0,-1");
    for line in text.lines() {
        let mut words = line.split_whitespace();
        match words.next().map(str::parse::<usize>) {
            Some(Ok(k)) => {
                let g: Vec<String> = (words.enumerate())
                    .map(|(a, w)| (a < 3).then(|| negated(w)).flatten().unwrap_or(w.into()))
                    .collect();
                println!("{} {}", keys[k], g.join(" "));
            }
            _ => println!("{line}"),
        }
    }
    Ok(())
}

/// The rotations of a JSON truth file (`"rotations"` or `"frames"`).
fn truth_json(truth: &str) -> Result<Vec<Rotation>, Box<dyn std::error::Error>> {
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(truth)?)?;
    let rows = v.get("rotations").or_else(|| v.get("frames"));
    let rows: Vec<[[f64; 3]; 3]> = serde_json::from_value(rows.ok_or("no rotations")?.clone())?;
    let rotations = (rows.iter())
        .map(|r| rotavg::so3::rotation_from_rows(r, 1e-9, truth))
        .collect::<rotavg::Result<Vec<_>>>()?;
    Ok(rotations)
}

/// The truth of every node of the view graph `graph` (read as `rotavg multiple GRAPH
/// --ground-truth TRUTH` reads it), with the nodes' file ids.
fn truth_of_graph(
    truth: &str,
    graph: &str,
) -> Result<(Vec<Rotation>, Vec<u64>), Box<dyn std::error::Error>> {
    use rotavg::io::detect::{GraphFormat, ReadOptions, load_graph};
    let options = ReadOptions::default();
    let g = load_graph(std::path::Path::new(graph), GraphFormat::Auto, &options)?;
    let r = rotavg::io::input::load_rotations_for_nodes(truth, &g, &options)?;
    let rotations = (r.rotations.iter())
        .map(|r| r.ok_or("a node without ground truth"))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((rotations, g.node_ids.clone()))
}

/// A number of the text written, negated (`None`: not a number).
fn negated(word: &str) -> Option<String> {
    word.parse::<f64>().ok().map(|x| (-x).to_string())
}
