//! Certification speed (issue 4, "Speed"): `cargo bench --bench certify`.
//!
//! 1. A 10^4-node synthetic graph (30000 edges, noise 0.02 rad): local refinement from the planted
//!    truth (a private Riemannian gradient descent, Barzilai-Borwein steps, Armijo), then
//!    `certify_multiple`, timed over several runs.
//! 2. sphere2500 (SE-Sync g2o, rotation part, unit weights) when /work/shared/data is present:
//!    refinement from the file's vertex poses, then certification; both timed.
//!
//! The g2o reader here is a minimal private one (EDGE_SE3:QUAT: R_ij = Z_ij^T, Z_ij from the
//! quaternion qx qy qz qw, scalar last; VERTEX_SE3:QUAT: R_i = W_i^T), see SPEC section 1.

use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use rotavg::Rotation;
use rotavg::certify::multiple::{CertifySettings, certify_multiple, laplacian_times};
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::multiple::{Edge, MultipleProblem};
use rotavg::so3::{exp, vee};
use std::path::Path;
use std::time::Instant;

fn gradient(p: &MultipleProblem, rs: &[Rotation]) -> Vec<Vector3<f64>> {
    laplacian_times(p, rs)
        .iter()
        .zip(rs)
        .map(|(g, r)| {
            let m = g * r.matrix().transpose();
            4.0 * vee(&(0.5 * (m - m.transpose())))
        })
        .collect()
}

/// Returns (rotations, cost, gradient norm, iterations).
fn local_solve(
    p: &MultipleProblem,
    start: &[Rotation],
    max_iter: usize,
    rel_tol: f64,
) -> (Vec<Rotation>, f64, f64, usize) {
    let mut rs = start.to_vec();
    let mut f = p.chordal_cost(&rs);
    let mut g = gradient(p, &rs);
    let mut step = 1e-2;
    let mut prev: Option<(Vec<Vector3<f64>>, f64)> = None;
    let mut it = 0;
    while it < max_iter {
        let gn2: f64 = g.iter().map(|v| v.norm_squared()).sum();
        if gn2.sqrt() <= rel_tol * (1.0 + f) {
            break;
        }
        if let Some((gp, tp)) = &prev {
            let s2 = tp * tp * gp.iter().map(|v| v.norm_squared()).sum::<f64>();
            let sy: f64 = -tp * gp.iter().zip(&g).map(|(a, b)| a.dot(&(b - a))).sum::<f64>();
            if sy > 0.0 {
                step = (s2 / sy).clamp(1e-8, 10.0);
            }
        }
        let mut t = step;
        let mut accepted = None;
        for _ in 0..50 {
            let cand: Vec<Rotation> = rs
                .iter()
                .zip(&g)
                .map(|(r, d)| {
                    let mut x = exp(&(-d * t)) * r;
                    x.renormalize();
                    x
                })
                .collect();
            let fc = p.chordal_cost(&cand);
            // nonmonotone-tolerant Armijo (BB steps may increase f slightly)
            if fc <= f - 1e-4 * t * gn2 {
                accepted = Some((cand, fc));
                break;
            }
            t *= 0.5;
        }
        let Some((cand, fc)) = accepted else { break };
        rs = cand;
        f = fc;
        prev = Some((g.clone(), t));
        g = gradient(p, &rs);
        it += 1;
    }
    let gn = g.iter().map(|v| v.norm_squared()).sum::<f64>().sqrt();
    (rs, f, gn, it)
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

fn quat(v: &[f64]) -> Option<Rotation> {
    let q = UnitQuaternion::from_quaternion(Quaternion::new(v[3], v[0], v[1], v[2]));
    Some(q.to_rotation_matrix())
}

fn load_g2o(path: &Path) -> Option<(MultipleProblem, Vec<Rotation>)> {
    let text = std::fs::read_to_string(path).ok()?;
    let mut verts: Vec<(usize, Rotation)> = vec![];
    let mut edges = vec![];
    for line in text.lines() {
        let tok: Vec<&str> = line.split_whitespace().collect();
        match tok.first() {
            Some(&"VERTEX_SE3:QUAT") => {
                let id: usize = tok[1].parse().ok()?;
                let v: Vec<f64> = tok[5..9].iter().map(|s| s.parse().unwrap()).collect();
                verts.push((id, quat(&v)?.inverse()));
            }
            Some(&"EDGE_SE3:QUAT") => {
                let i: usize = tok[1].parse().ok()?;
                let j: usize = tok[2].parse().ok()?;
                let v: Vec<f64> = tok[6..10].iter().map(|s| s.parse().unwrap()).collect();
                edges.push(Edge {
                    i,
                    j,
                    rotation: quat(&v)?.inverse(),
                    weight: 1.0,
                });
            }
            _ => {}
        }
    }
    let n = verts.iter().map(|v| v.0 + 1).max()?;
    let mut init = vec![Rotation::identity(); n];
    for (id, r) in verts {
        init[id] = r;
    }
    Some((MultipleProblem::new(n, edges).ok()?, init))
}

fn certify_timed(label: &str, p: &MultipleProblem, rs: &[Rotation], runs: usize) {
    let settings = CertifySettings::default();
    let mut times = vec![];
    let mut last = None;
    for _ in 0..runs {
        let t = Instant::now();
        let c = certify_multiple(p, rs, &settings).expect("certify");
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
    let (p, gt) = SyntheticGraph {
        num_rotations: 10_000,
        num_edges: 30_000,
        noise_sigma: 0.02,
        ..Default::default()
    }
    .generate();
    let t = Instant::now();
    let (rs, f, gn, it) = local_solve(&p, &gt, 5000, 1e-12);
    println!(
        "synthetic n=10000 m=30000: local refinement {:.3} s ({it} iterations), cost {f:.6e}, |grad| {gn:.2e}",
        t.elapsed().as_secs_f64()
    );
    certify_timed("synthetic random n=10000", &p, &rs, 1);

    // 1b. a 100 x 100 grid with right, down and diagonal edges (29601 edges): a graph with good
    // separators, like pose graphs
    let (p, gt) = grid_problem(100, 0.02, 7);
    let t = Instant::now();
    let (rs, f, gn, it) = local_solve(&p, &gt, 5000, 1e-12);
    println!(
        "grid n=10000 m={}: local refinement {:.3} s ({it} iterations), cost {f:.6e}, |grad| {gn:.2e}",
        p.num_edges(),
        t.elapsed().as_secs_f64()
    );
    certify_timed("grid n=10000", &p, &rs, 5);

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
        let Some((p, init)) = load_g2o(&base.join(format!("g2o/3d/sesync/{name}.g2o"))) else {
            println!("skipping {name}: could not read");
            continue;
        };
        let t = Instant::now();
        let (rs, f, gn, it) = local_solve(&p, &init, 20000, 1e-12);
        println!(
            "{name} (n={}, m={}, unit weights): gradient-descent refinement {:.3} s ({it} iterations), cost {f:.9e}, |grad| {gn:.2e}",
            p.num_rotations(),
            p.num_edges(),
            t.elapsed().as_secs_f64()
        );
        certify_timed(name, &p, &rs, 3);
    }
}
