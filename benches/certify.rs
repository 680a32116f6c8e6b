//! Certification speed (issue 4, "Speed"): `cargo bench --bench certify`.
//!
//! 1. A 10^4-node synthetic graph (30000 edges, noise 0.02 rad) and a 100 x 100 grid: local
//!    solve (`solve_multiple`, spectral init, Newton-LM to relative gradient 1e-12), then
//!    the dual certificate (`certify::multiple::dual_certificate`), timed over several runs. The random graph is certified by the scalar
//!    comparison `[D13]` (its 3n x 3n Cholesky factor would hold 1.1e8 values), the grid by the
//!    sparse Cholesky `[D5]`.
//!    The same random graph with no factorisation allowed (budget 1 byte): the randomized
//!    Chebyshev test `[D16]` instead of a proof.
//! 2. Long chains (`SyntheticChain`: odometry with 2 % loop closures, noise 1e-4 rad), 10^4 and
//!    10^5 nodes, 3-D and planar: the SLAM shape of issue 11, certified by the grounded bound
//!    `[D15]`.
//! 3. sphere2500 and parking-garage (SE-Sync g2o read by `io::detect::load_graph`, unit
//!    weights) when the shared data are present: local solve, then certification; both timed.

use rotavg::Rotation;
use rotavg::certify::CertifySettings;
use rotavg::certify::multiple::dual_certificate;
use rotavg::io::detect::{GraphFormat, ReadOptions, WeightSource, load_graph};
use rotavg::multiple::synthetic::{SyntheticChain, SyntheticGraph};
use rotavg::multiple::{Edge, MultipleProblem, MultipleSettings, solve_multiple};
use std::path::Path;
use std::time::Instant;

/// Local solve with the crate's solver: (rotations, cost, gradient norm, iterations).
fn local_solve(p: &MultipleProblem) -> (Vec<Rotation>, f64, f64, usize) {
    let settings = MultipleSettings {
        gradient_tolerance: 1e-12,
        ..Default::default()
    };
    let s = solve_multiple(p, &settings).expect("connected graph");
    (
        s.rotations,
        s.chordal_cost,
        s.gradient_norm,
        s.report.iterations,
    )
}

fn grid_problem(side: usize, sigma: f64, seed: u64) -> (MultipleProblem, Vec<Rotation>) {
    use rand::SeedableRng;
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let n = side * side;
    let gt: Vec<Rotation> = (0..n)
        .map(|_| rotavg::so3::random_rotation(&mut rng))
        .collect();
    let mut edges = vec![];
    let id = |r: usize, c: usize| r * side + c;
    for r in 0..side {
        for c in 0..side {
            let mut nb = vec![];
            if c + 1 < side {
                nb.push(id(r, c + 1));
            }
            if r + 1 < side {
                nb.push(id(r + 1, c));
            }
            if r + 1 < side && c + 1 < side {
                nb.push(id(r + 1, c + 1));
            }
            for j in nb {
                let i = id(r, c);
                let rotation =
                    rotavg::so3::perturb_gaussian(&(gt[j] * gt[i].inverse()), sigma, &mut rng);
                edges.push(Edge {
                    i,
                    j,
                    rotation,
                    weight: 1.0,
                });
            }
        }
    }
    (MultipleProblem::new(n, edges).expect("valid grid"), gt)
}

fn load_g2o(path: &Path) -> Option<MultipleProblem> {
    let options = ReadOptions {
        weights: WeightSource::Unit,
        ..Default::default()
    };
    load_graph(path, GraphFormat::Auto, &options)
        .ok()
        .map(|g| g.problem)
}

fn certify_timed(label: &str, p: &MultipleProblem, rs: &[Rotation], runs: usize) {
    certify_timed_with(label, p, rs, runs, &CertifySettings::default());
}

fn certify_timed_with(
    label: &str,
    p: &MultipleProblem,
    rs: &[Rotation],
    runs: usize,
    settings: &CertifySettings,
) {
    let mut times = vec![];
    let mut last = None;
    for _ in 0..runs {
        let t = Instant::now();
        let c = dual_certificate(p, rs, settings).expect("certify");
        times.push(t.elapsed().as_secs_f64());
        last = Some(c);
    }
    times.sort_by(f64::total_cmp);
    let c = last.expect("at least one run");
    println!(
        "{label}: certify median {:.3} s (min {:.3}, max {:.3}) over {runs} runs; factorizations {}, lanczos iterations {}, factor nnz {}, shift {:?}, fp margin {:.2e}",
        times[runs / 2],
        times[0],
        times[runs - 1],
        c.bound.factorizations,
        c.bound.lanczos_iterations,
        c.bound.factor_nonzeros,
        c.bound.shift,
        c.bound.fp_margin
    );
    println!("{label}: {c}");
}

fn main() {
    // 1. synthetic 10^4 nodes
    let (p, _truth) = SyntheticGraph {
        num_rotations: 10_000,
        num_edges: 30_000,
        noise_sigma: 0.02,
        ..Default::default()
    }
    .generate();
    let t = Instant::now();
    let (rs, f, gn, it) = local_solve(&p);
    println!(
        "synthetic n=10000 m=30000: local solve {:.3} s ({it} iterations), cost {f:.6e}, |grad| {gn:.2e}",
        t.elapsed().as_secs_f64()
    );
    certify_timed("synthetic random n=10000", &p, &rs, 1);
    // 1a. the same graph with no factorisation allowed: the randomized Chebyshev test [D16]
    // (Lanczos estimate on the complement, then its products with S)
    let mut over = CertifySettings::default();
    over.budget.max_memory_bytes = 1;
    over.dual.randomized.seed = Some(1);
    certify_timed_with(
        "synthetic random n=10000, randomized [D16]",
        &p,
        &rs,
        3,
        &over,
    );

    // 1b. a 100 x 100 grid with right, down and diagonal edges (29601 edges): a graph with good
    // separators, like pose graphs
    let (p, _truth) = grid_problem(100, 0.02, 7);
    let t = Instant::now();
    let (rs, f, gn, it) = local_solve(&p);
    println!(
        "grid n=10000 m={}: local solve {:.3} s ({it} iterations), cost {f:.6e}, |grad| {gn:.2e}",
        p.num_edges(),
        t.elapsed().as_secs_f64()
    );
    certify_timed("grid n=10000", &p, &rs, 5);

    // 1c. long chains with few loop closures
    for (n, planar) in [(10_000, false), (10_000, true), (100_000, false)] {
        let (p, _truth) = SyntheticChain {
            num_rotations: n,
            loop_closure_fraction: 0.02,
            noise_sigma: 1e-4,
            planar,
            seed: 3,
            ..Default::default()
        }
        .generate();
        let t = Instant::now();
        let (rs, f, gn, it) = local_solve(&p);
        let kind = if planar { "planar" } else { "3-D" };
        println!(
            "chain {kind} n={n} m={}: local solve {:.3} s ({it} iterations), cost {f:.6e}, |grad| {gn:.2e}",
            p.num_edges(),
            t.elapsed().as_secs_f64()
        );
        certify_timed(&format!("chain {kind} n={n}"), &p, &rs, 3);
    }

    // 2. sphere2500
    let base = [
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data"),
        Path::new("/work/shared/data").to_path_buf(),
    ]
    .into_iter()
    .find(|d| d.exists());
    let Some(base) = base else {
        println!("skipping sphere2500: shared data not found");
        return;
    };
    for name in ["sphere2500", "parking-garage"] {
        let Some(p) = load_g2o(&base.join(format!("g2o/3d/sesync/{name}.g2o"))) else {
            println!("skipping {name}: could not read");
            continue;
        };
        let t = Instant::now();
        let (rs, f, gn, it) = local_solve(&p);
        println!(
            "{name} (n={}, m={}, unit weights): local solve {:.3} s ({it} iterations), cost {f:.9e}, |grad| {gn:.2e}",
            p.num_rotations(),
            p.num_edges(),
            t.elapsed().as_secs_f64()
        );
        certify_timed(name, &p, &rs, 3);
    }
}
