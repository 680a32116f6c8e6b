//! Certify one graph of issue 37's realistic two-view class (no outliers) and print the
//! verification ladder: which proofs ran, what they predicted and how long they took.
//!
//! ```text
//! cargo run --release --example anisotropic_ladder -- [CAMERAS] [EDGES] [without-block | block-always]
//! ```
//!
//! Defaults: 1000 cameras, 4000 edges. `without-block` leaves the block comparison `[A15]` off
//! the ladder (the A/B of `paper-notes/anisotropic.md` `[A15]`); `block-always` puts it on at
//! any size (`DualSettings::block_comparison_above` 0).
use rotavg::certify::{CertifySettings, Proof, certify_multiple};
use rotavg::multiple::synthetic::SyntheticAnisotropic;
use rotavg::multiple::{MultipleSettings, solve_multiple};
use std::time::Instant;

fn main() -> rotavg::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let n: usize = args.first().and_then(|a| a.parse().ok()).unwrap_or(1000);
    let m: usize = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(4 * n);
    let (p, _) = SyntheticAnisotropic::two_view_like(n, m, 0.0).generate();
    let t = Instant::now();
    let s = solve_multiple(&p, &MultipleSettings::default())?;
    println!(
        "{n} cameras, {m} edges: solve {:.3} s",
        t.elapsed().as_secs_f64()
    );
    let mut settings = CertifySettings::default();
    if args.iter().any(|a| a == "without-block") {
        settings
            .dual
            .proofs
            .retain(|p| *p != Proof::BlockComparison);
    }
    if args.iter().any(|a| a == "block-always") {
        settings.dual.block_comparison_above = 0;
    }
    let t = Instant::now();
    let c = certify_multiple(&p, &s.rotations, &settings)?;
    println!(
        "certify {:.3} s: {}, relative gap {:.1e}",
        t.elapsed().as_secs_f64(),
        c.certificate.verdict,
        c.certificate.relative_gap.unwrap_or(f64::NAN)
    );
    for a in &c.details.ladder {
        let predicted = a
            .predicted
            .map_or("-".into(), |p| format!("{:.2} s", p.seconds));
        println!(
            "  {} at {:?}: {:.3} s (predicted {predicted}) {} {:?}",
            a.rung, a.point, a.seconds, a.note, a.outcome
        );
    }
    Ok(())
}
