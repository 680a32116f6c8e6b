//! Benchmarks of every single-averaging method on 10^3, 10^5 and 10^6 samples (Gaussian noise
//! of 0.1 rad around a random rotation, seeded). Run with
//! `cargo bench --features bench --bench single`.
//! Sample counts are reduced for the large sizes to keep the run short.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::certify::{CertifyMode, CertifySettings, certify_single};
use rotavg::objective::{Loss, Objective};
use rotavg::pipeline::{AverageSettings, average_single};
use rotavg::single::{SingleProblem, SingleSettings, solve_single};
use rotavg::so3::{Metric, perturb_gaussian, random_rotation};
use std::hint::black_box;
use std::time::Duration;

fn problem(n: usize) -> SingleProblem {
    let mut rng = StdRng::seed_from_u64(n as u64);
    let truth = random_rotation(&mut rng);
    let rs = (0..n)
        .map(|_| perturb_gaussian(&truth, 0.1, &mut rng))
        .collect();
    SingleProblem::new(rs, None).expect("valid rotations")
}

fn bench(c: &mut Criterion) {
    let methods = [
        ("chordal_l2", Metric::Chordal, Loss::L2),
        ("quaternion_l2", Metric::Quaternion, Loss::L2),
        ("geodesic_l2", Metric::Geodesic, Loss::L2),
        ("geodesic_l1", Metric::Geodesic, Loss::L1),
        ("chordal_l1", Metric::Chordal, Loss::L1),
    ];
    for n in [1_000usize, 100_000, 1_000_000] {
        let p = problem(n);
        let mut group = c.benchmark_group(format!("single_n{n}"));
        if n >= 100_000 {
            group.sample_size(10);
            group.warm_up_time(Duration::from_millis(500));
            group.measurement_time(Duration::from_secs(if n >= 1_000_000 { 8 } else { 3 }));
        }
        for (name, metric, norm) in methods {
            let p = p
                .clone()
                .with_objective(Objective::new(metric, norm))
                .expect("supported objective");
            let s = AverageSettings::default();
            group.bench_with_input(BenchmarkId::new(name, n), &p, |b, p| {
                b.iter(|| black_box(average_single(black_box(p), &s).expect("valid settings")))
            });
        }
        group.finish();
    }
    bench_branch_and_bound(c);
}

/// Branch and bound `[B1]`-`[B6]` (certify only, from the Weiszfeld mean) of the geodesic L1
/// mean of 10^4 samples: 0.1 rad noise with 10 % uniform outliers (so that the pi/2-ball
/// theorem does not apply).
fn bench_branch_and_bound(c: &mut Criterion) {
    let mut rng = StdRng::seed_from_u64(1);
    let truth = random_rotation(&mut rng);
    let rs = (0..10_000)
        .map(|k| {
            if k % 10 == 0 {
                random_rotation(&mut rng)
            } else {
                perturb_gaussian(&truth, 0.1, &mut rng)
            }
        })
        .collect();
    let p = SingleProblem::new(rs, None)
        .expect("valid rotations")
        .with_objective(Objective::new(Metric::Geodesic, Loss::L1))
        .expect("supported objective");
    let sol = solve_single(&p, &SingleSettings::default()).expect("valid settings");
    let s = CertifySettings::with_mode(CertifyMode::BranchAndBound);
    let mut group = c.benchmark_group("single_bnb");
    group.sample_size(10);
    group.bench_function("geodesic_l1_n10000", |b| {
        b.iter(|| black_box(certify_single(black_box(&p), &sol.estimate, &s).expect("valid")))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
