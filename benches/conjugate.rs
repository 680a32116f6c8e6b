//! Conjugate averaging timings: closed form, chordal Gauss-Newton, SDP relaxation, pipeline,
//! and the branch and bound of a geodesic L1 problem with 10^3 pairs.

use criterion::{Criterion, criterion_group, criterion_main};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::certify::{CertifyMode, CertifySettings, certify_conjugate};
use rotavg::conjugate::synthetic::random_instance;
use rotavg::conjugate::{ConjugateSettings, quaternion_closed_form, solve_conjugate};
use rotavg::objective::{Loss, Objective};
use rotavg::pipeline::{AverageSettings, average_conjugate};
use rotavg::relax::{SdpSettings, relax_conjugate};
use rotavg::so3::Metric;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let mut rng = StdRng::seed_from_u64(1);
    for n in [10, 100] {
        let (p, _) = random_instance(n, 0.035, 0.0, &mut rng);
        c.bench_function(&format!("conjugate/closed_form/{n}"), |b| {
            b.iter(|| quaternion_closed_form(black_box(&p), &Default::default()))
        });
        c.bench_function(&format!("conjugate/chordal/{n}"), |b| {
            b.iter(|| solve_conjugate(black_box(&p), &ConjugateSettings::default()))
        });
        c.bench_function(&format!("conjugate/sdp/{n}"), |b| {
            b.iter(|| relax_conjugate(black_box(&p), &SdpSettings::default()))
        });
        c.bench_function(&format!("conjugate/pipeline/{n}"), |b| {
            b.iter(|| average_conjugate(black_box(&p), &AverageSettings::default()))
        });
    }
    // Branch and bound [B1]-[B6] (certify only, from the IRLS solution): geodesic L1, 10^3
    // pairs, 0.02 rad noise, 10 % outliers.
    let (p, _) = random_instance(1000, 0.02, 0.1, &mut rng);
    let p = p
        .with_objective(Objective::new(Metric::Geodesic, Loss::L1))
        .expect("supported objective");
    let sol = solve_conjugate(&p, &ConjugateSettings::default()).expect("identifiable");
    let s = CertifySettings::with_mode(CertifyMode::BranchAndBound);
    let mut group = c.benchmark_group("conjugate_bnb");
    group.sample_size(10);
    group.bench_function("geodesic_l1_n1000", |b| {
        b.iter(|| certify_conjugate(black_box(&p), &sol.estimate, &s))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
