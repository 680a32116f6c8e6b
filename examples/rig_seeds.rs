//! Small rigs captured along a path, seed by seed (`paper-notes/conjugate.md` `[H21]`, "The
//! search"): each of seeds `1..=SEEDS` of `RigScene { frames, sensors, noise_sigma: 0.01,
//! anisotropy: 9, extra_edge_span: SPAN }` (every sensor estimated) solved and certified by
//! `certify_rig`; one line per seed, the ladder of those not certified.
//!
//! ```text
//! cargo run --release --example rig_seeds -- FRAMES SENSORS SPAN SEEDS [scalar] [verbose]
//! ```
//!
//! `scalar`: the same data with scalar weights `tr(H) / 3`; `verbose`: every seed's ladder.
use rotavg::rig::{RigScene, RigSettings, solve_rig};

fn main() -> rotavg::Result<()> {
    let all: Vec<String> = std::env::args().skip(1).collect();
    let numbers: Vec<usize> = all.iter().filter_map(|x| x.parse().ok()).collect();
    let number = |k: usize, default: usize| numbers.get(k).copied().unwrap_or(default);
    let (frames, sensors, span, seeds) = (number(0, 30), number(1, 4), number(2, 10), number(3, 4));
    let scalar = all.iter().any(|x| x == "scalar");
    let verbose = all.iter().any(|x| x == "verbose");
    let mut certified = 0;
    for seed in 1..=seeds as u64 {
        let scene = RigScene {
            frames,
            sensors,
            noise_sigma: 0.01,
            seed,
            anisotropy: 9.0,
            extra_edge_span: span,
            ..Default::default()
        };
        let (p, _) = scene.generate();
        let p = if scalar { p.scalar() } else { p };
        let s = solve_rig(&p, &RigSettings::default())?;
        let clock = std::time::Instant::now();
        let c = rotavg::certify::certify_rig(&p, &s.frames, &s.sensors, &Default::default())?;
        let cert = &c.certificate;
        println!(
            "seed {seed}: cost {:.6} {} relative gap {:.1e} certify {:.2} s",
            s.cost,
            cert.verdict,
            cert.relative_gap.unwrap_or(f64::NAN),
            clock.elapsed().as_secs_f64()
        );
        certified += usize::from(cert.is_certified());
        if !cert.is_certified() || verbose {
            for a in &c.details.ladder {
                println!("  {} {:.3} s {} {:?}", a.rung, a.seconds, a.note, a.outcome);
            }
        }
    }
    println!("{certified} of {seeds} certified");
    Ok(())
}
