//! Budgets never hurt (issue 24): raising `--max-memory` or `--max-seconds` never gives a weaker
//! verdict on the same input. Before the ladder, a 1000-node graph with 10^4 edges was
//! `certified` at 4 GiB and 256 MiB, `inconclusive` at 128, 64 and 16 MiB, and `certified` at
//! 8 MiB: a size threshold skipped the scalar comparison in between. Now every proof is a rung
//! refused only by its own predicted cost, so a larger budget only adds rungs.
//!
//! Verdicts are ranked `inconclusive < gap_reported < certified`; for every graph shape the rank
//! must not decrease along a sweep of memory budgets (time unlimited), nor along time budgets
//! whose refusals come from the predictions alone (a microsecond, ten minutes, none).

use rotavg::certify::{Budget, CertifySettings, Verdict, certify_multiple};
use rotavg::multiple::synthetic::{SyntheticChain, SyntheticGraph, SyntheticGrid};
use rotavg::multiple::{MultipleProblem, MultipleSettings, solve_multiple};
use rotavg::so3::Rotation;

fn rank(v: Verdict) -> u8 {
    match v {
        Verdict::Inconclusive => 0,
        Verdict::GapReported => 1,
        Verdict::Certified => 2,
    }
}

/// The shapes: a dense random graph (the issue's), a sparse noisy one, a chain with closures,
/// a grid sweep; each at its local solution.
fn shapes() -> Vec<(&'static str, MultipleProblem, Vec<Rotation>)> {
    let graphs = vec![
        (
            "random 1000 / 10^4, 0.1 rad",
            SyntheticGraph {
                num_rotations: 1000,
                num_edges: 10_000,
                noise_sigma: 0.1,
                seed: 24,
                ..Default::default()
            }
            .generate()
            .0,
        ),
        (
            "random 600 / 1800, 0.2 rad",
            SyntheticGraph {
                num_rotations: 600,
                num_edges: 1800,
                noise_sigma: 0.2,
                seed: 7,
                ..Default::default()
            }
            .generate()
            .0,
        ),
        (
            "chain 3000, 2 % closures",
            SyntheticChain {
                num_rotations: 3000,
                seed: 3,
                ..Default::default()
            }
            .generate()
            .0,
        ),
        (
            "grid 40 x 40",
            SyntheticGrid {
                width: 40,
                height: 40,
                seed: 5,
                ..Default::default()
            }
            .generate()
            .0,
        ),
    ];
    graphs
        .into_iter()
        .map(|(name, p)| {
            let sol = solve_multiple(&p, &MultipleSettings::default()).unwrap();
            (name, p, sol.rotations)
        })
        .collect()
}

fn verdict(p: &MultipleProblem, y: &[Rotation], budget: Budget) -> Verdict {
    let settings = CertifySettings {
        budget,
        ..Default::default()
    };
    certify_multiple(p, y, &settings)
        .unwrap()
        .certificate
        .verdict
}

#[test]
fn raising_a_budget_never_weakens_the_verdict() {
    let memory: [u64; 8] = [
        1 << 20,
        8 << 20,
        16 << 20,
        64 << 20,
        128 << 20,
        256 << 20,
        1 << 30,
        4 << 30,
    ];
    let seconds = [Some(1e-6), Some(600.0), None];
    for (name, p, y) in shapes() {
        let by_memory: Vec<Verdict> = memory
            .iter()
            .map(|&max_memory_bytes| {
                let budget = Budget {
                    max_memory_bytes,
                    max_seconds: None,
                };
                verdict(&p, &y, budget)
            })
            .collect();
        println!("{name}: memory sweep {by_memory:?}");
        for w in by_memory.windows(2) {
            assert!(
                rank(w[1]) >= rank(w[0]),
                "{name}: memory sweep {by_memory:?}"
            );
        }
        let by_time: Vec<Verdict> = seconds
            .iter()
            .map(|&max_seconds| {
                let budget = Budget {
                    max_seconds,
                    ..Default::default()
                };
                verdict(&p, &y, budget)
            })
            .collect();
        println!("{name}: time sweep {by_time:?}");
        for w in by_time.windows(2) {
            assert!(rank(w[1]) >= rank(w[0]), "{name}: time sweep {by_time:?}");
        }
        // the default budget certifies every shape's local solution
        assert_eq!(*by_memory.last().unwrap(), Verdict::Certified, "{name}");
    }
}
