//! Rigs at scale (issue 36 item 2): the simultaneous problem (two rigidly mounted sensors,
//! each with its own view graph over the same frames; `paper-notes/conjugate.md` `[H12]`,
//! `[H16]`, `[H17]`) on synthetic rigs of 100 to 10^4 frames: the joint solve (dense
//! Gauss-Newton up to 500 frames, the sparse alternation beyond), its accuracy against the
//! planted frames and `sensor_from_rig`, the certificate (the dual certificate at the estimate
//! `[H15]`, dense or in low-rank form `[H25]`, else the decoupled bound `[H16]`) and the times; and, on the row below each,
//! the frames averaged with the planted `sensor_from_rig` held (`[H18]`: one view graph,
//! certified by the multiple-averaging ladder).
//!
//! ```text
//! cargo run --release --example rig_scale -- [NOISE_RAD] [SEED] [FRAMES...]
//! ```
//!
//! Defaults: 0.02 rad of noise per tangent component on every edge of both graphs, 4 edges per
//! frame (the same pairs on both graphs), seed 1, 100, 1000 and 10^4 frames. Prints a Markdown
//! table.
use rotavg::Rotation;
use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::pipeline::Averaged;
use rotavg::pipeline::simultaneous::{
    SimultaneousSolution, SyntheticRig, average_simultaneous, average_with_sensor_held,
};
use rotavg::so3::angle_between;

fn main() -> rotavg::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let noise: f64 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(0.02);
    let seed: u64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(1);
    println!("noise {noise} rad per component, 4 edges per frame on each graph, seed {seed}\n");
    println!(
        "| frames | solver | passes | frames' mean error (deg) | S error (deg) | solve (s) | certify (s) | verdict | relative gap | bound |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    let mut sizes: Vec<usize> = args.iter().skip(3).filter_map(|s| s.parse().ok()).collect();
    if sizes.is_empty() {
        sizes = vec![100, 1000, 10_000];
    }
    for n in sizes {
        let graph = SyntheticGraph {
            num_rotations: n,
            num_edges: 4 * n,
            noise_sigma: noise,
            outlier_fraction: 0.0,
            seed,
        };
        let (p, truth, s) = SyntheticRig { graph }.generate();
        let joint = average_simultaneous(&p, &Default::default())?;
        row(n, "", &joint, &truth, &s)?;
        // the calibration known: S held at the planted one ([H18])
        let held = average_with_sensor_held(&p, &s, &Default::default())?;
        row(n, "S held: ", &held, &truth, &s)?;
    }
    Ok(())
}

/// One table row: `r` against the planted frames `truth` and `s`.
fn row(
    n: usize,
    label: &str,
    r: &Averaged<SimultaneousSolution>,
    truth: &[Rotation],
    s: &Rotation,
) -> rotavg::Result<()> {
    let known: Vec<_> = truth.iter().copied().map(Some).collect();
    let a = align_and_compare(&r.solution.rotations, &known)?;
    let c = r.certificate.as_ref();
    println!(
        "| {n} | {label}{} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {} | {} | {} |",
        r.solution.report.name,
        r.solution.report.iterations,
        a.mean_deg,
        angle_between(&r.solution.s, s).to_degrees(),
        r.details.solve_seconds,
        r.details.certify_seconds,
        c.map_or("none".into(), |c| c.verdict.to_string()),
        c.and_then(|c| c.relative_gap)
            .map_or("-".into(), |g| format!("{g:.1e}")),
        c.map_or("-".into(), |c| c
            .explanation
            .chars()
            .take(40)
            .collect::<String>()),
    );
    Ok(())
}
