//! Criterion benchmarks of the multiple-averaging SDP relaxation (dual form, chordal
//! decomposition, faer KKT solver). Larger sizes take seconds to minutes per solve: their
//! single-run timings are produced by `tests/suite/relax_multiple.rs::timing_table` and recorded in
//! `paper-notes/sdp.md`.

use criterion::{Criterion, criterion_group, criterion_main};
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::relax::{SdpSettings, relax_multiple};

fn bench_sdp(c: &mut Criterion) {
    let mut group = c.benchmark_group("relax_multiple");
    group.sample_size(10);
    for (n, m) in [(20usize, 80usize), (100, 150)] {
        let (p, _) = SyntheticGraph {
            num_rotations: n,
            num_edges: m,
            noise_sigma: 0.1,
            outlier_fraction: 0.0,
            seed: 7,
        }
        .generate();
        let settings = SdpSettings::default();
        group.bench_function(format!("n{n}_m{m}"), |b| {
            b.iter(|| relax_multiple(&p, &settings).expect("solves"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_sdp);
criterion_main!(benches);
