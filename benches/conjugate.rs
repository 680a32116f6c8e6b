//! Conjugate averaging timings: closed form, chordal Gauss-Newton, SDP relaxation, pipeline.

use criterion::{Criterion, criterion_group, criterion_main};
use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::conjugate::synthetic::random_instance;
use rotavg::conjugate::{ConjugateSettings, quaternion_closed_form, solve_conjugate};
use rotavg::pipeline::{AverageSettings, average_conjugate};
use rotavg::relax::{SdpSettings, relax_conjugate};
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
}

criterion_group!(benches, bench);
criterion_main!(benches);
