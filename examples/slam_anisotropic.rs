//! Write issue 37's strongly anisotropic SLAM class as a JSON view graph with its truth
//! ([`rotavg::multiple::synthetic::SyntheticAnisotropicSlam::strongly_anisotropic`]: a trajectory with 5 %
//! loop closures, eigenvalue ratios about 1e4 to 1e6, every `M` indefinite):
//!
//!     cargo run --release --example slam_anisotropic -- N SEED OUT.json [TRUTH.txt]
//!     rotavg multiple OUT.json --ground-truth TRUTH.txt --max-seconds 60

use rotavg::multiple::synthetic::SyntheticAnisotropicSlam;
use std::fmt::Write as _;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (Some(n), Some(seed), Some(out)) = (
        args.first().and_then(|a| a.parse::<usize>().ok()),
        args.get(1).and_then(|a| a.parse::<u64>().ok()),
        args.get(2),
    ) else {
        eprintln!("usage: slam_anisotropic N SEED OUT.json [TRUTH.txt]");
        std::process::exit(2);
    };
    let (p, truth) = SyntheticAnisotropicSlam::strongly_anisotropic(n, seed).generate();
    let write = |path: &str, text: &str| {
        if let Err(e) = std::fs::write(path, text) {
            eprintln!("{path}: {e}");
            std::process::exit(1);
        }
    };
    write(out, &rotavg::io::json::write_problem_json(&p));
    if let Some(path) = args.get(3) {
        let mut list = String::from("# ground truth: id R11 .. R33 (R_i, with R_ij R_i = R_j)\n");
        for (i, r) in truth.iter().enumerate() {
            let _ = write!(list, "{i}");
            for v in r.matrix().transpose().iter() {
                let _ = write!(list, " {v:.15}");
            }
            list.push('\n');
        }
        write(path, &list);
    }
    let mut ratios: Vec<f64> = p
        .information()
        .map_or(Vec::new(), |h| h.iter().map(|x| x.anisotropy()).collect());
    ratios.sort_by(f64::total_cmp);
    println!(
        "{out}: {} poses, {} edges, eigenvalue ratio min {:.1e} median {:.1e} max {:.1e}",
        p.num_rotations(),
        p.num_edges(),
        ratios.first().copied().unwrap_or(1.0),
        ratios.get(ratios.len() / 2).copied().unwrap_or(1.0),
        ratios.last().copied().unwrap_or(1.0)
    );
}
