//! `[G13]` checked against dense eigenvalues: whenever the hub comparison proves
//! `lambda_min(S) >= mu`, the smallest eigenvalue of `S = Q - blkdiag(sym Lambda)`, formed here
//! from the definition of `Q` (`[A2]`) and computed densely, is at least `mu`, at the soft
//! solve's point and at points turned off it (where `S` is clearly indefinite); the soft
//! solve's point is proven to a tight target; problems without hub shape are not offered.

use super::*;
use crate::certify::multiple::multipliers::multipliers;
use crate::multiple::MultipleSettings;
use crate::multiple::gravity::{GravityProblem, solve_gravity};
use crate::multiple::synthetic::{SyntheticGraph, SyntheticGravity};
use crate::so3::perturb;
use nalgebra::DMatrix;
use rand::SeedableRng;

/// A soft-prior problem's augmented graph and its solve's point (world node last, at `I`),
/// priors of 2 degrees of noise.
fn instance(
    n: usize,
    edges: usize,
    sigma: f64,
    weight: f64,
    seed: u64,
) -> (MultipleProblem, Vec<Rotation>) {
    instance_with(n, edges, (sigma, 2.0), weight, seed)
}

/// [`instance`] with the graph's noise (rad) and the priors' (degrees).
fn instance_with(
    n: usize,
    edges: usize,
    (sigma, prior_deg): (f64, f64),
    weight: f64,
    seed: u64,
) -> (MultipleProblem, Vec<Rotation>) {
    let (graph, truth) = SyntheticGraph {
        num_rotations: n,
        num_edges: edges,
        noise_sigma: sigma,
        outlier_fraction: 0.0,
        seed,
    }
    .generate();
    let priors = SyntheticGravity {
        noise_deg: prior_deg,
        missing_fraction: 0.25,
        seed,
    }
    .priors(&truth)
    .unwrap()
    .with_weight(weight)
    .unwrap();
    let p = GravityProblem::new(graph, priors).unwrap();
    let solution = solve_gravity(&p, &MultipleSettings::default()).unwrap();
    let augmented = p.soft_augmented(p.problem()).unwrap();
    (augmented, p.soft_point(&solution.rotations))
}

/// `S = Q - blkdiag(sym Lambda)`, dense, `Q` from `[A2]`: per edge `2M = tr(H) I - 2H` on both
/// diagonal blocks and `-2M R_ij^T` at `(i, j)`.
fn dense_certificate(problem: &MultipleProblem, lambdas: &[Matrix3<f64>]) -> DMatrix<f64> {
    let n = problem.num_rotations();
    let mut s = DMatrix::<f64>::zeros(3 * n, 3 * n);
    let info = problem.information().unwrap();
    let mut add = |i: usize, j: usize, block: &Matrix3<f64>| {
        for a in 0..3 {
            for b in 0..3 {
                s[(3 * i + a, 3 * j + b)] += block[(a, b)];
            }
        }
    };
    for (e, h) in problem.edges().iter().zip(info) {
        let h = h.matrix();
        let m2 = Matrix3::identity() * h.trace() - h * 2.0;
        let off = -(m2 * e.rotation.matrix().transpose());
        add(e.i, e.i, &m2);
        add(e.j, e.j, &m2);
        add(e.i, e.j, &off);
        add(e.j, e.i, &off.transpose());
    }
    for (i, l) in lambdas.iter().enumerate() {
        add(i, i, &(-0.5 * (l + l.transpose())));
    }
    s
}

/// The hub comparison at `rotations` (its own multipliers) and the dense `lambda_min(S)`.
fn proven_and_exact(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    target: f64,
) -> (Option<f64>, f64) {
    let lambdas = multipliers(problem, rotations).unwrap();
    let hub = HubGraph::new(problem, usize::MAX)
        .unwrap()
        .unwrap()
        .unwrap();
    let proven = hub
        .compare(problem, rotations, &lambdas, target)
        .ok()
        .map(|c| c.verified_min_eigenvalue);
    let exact = dense_certificate(problem, &lambdas)
        .symmetric_eigenvalues()
        .min();
    (proven, exact)
}

#[test]
fn every_proven_bound_is_below_the_dense_smallest_eigenvalue() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    let (mut proofs, mut indefinite) = (0, 0);
    for seed in 0..12u64 {
        let n = 8 + 2 * seed as usize;
        let weight = [0.3, 2.25, 20.0][seed as usize % 3];
        let (problem, point) = instance(n, 3 * n, 0.05, weight, seed);
        for turn in [0.0, 0.02, 0.05, 0.1, 0.2, 0.4] {
            let mut rotations = point.clone();
            let world = rotations.len() - 1;
            for r in &mut rotations[..world] {
                *r = perturb(r, turn, &mut rng);
            }
            let (proven, exact) = proven_and_exact(&problem, &rotations, f64::INFINITY);
            let Some(mu) = proven else { continue };
            proofs += 1;
            indefinite += usize::from(exact < -1e-6);
            let slack = 1e-9 * (1.0 + exact.abs());
            assert!(
                mu <= exact + slack,
                "seed {seed}, turn {turn}: proven {mu:e} above the exact {exact:e}"
            );
        }
    }
    eprintln!("proofs {proofs} indefinite {indefinite}");
    assert!(proofs >= 30, "only {proofs} proofs");
    assert!(
        indefinite >= 10,
        "only {indefinite} proofs where S is clearly indefinite"
    );
}

/// Step 2's inequality itself, densely: `M - C` is positive semidefinite, `M = D^T S D` and
/// `C` the comparison (two slices of the view graph's Laplacian, the third with the spokes and
/// the hub, less the charges; the hub's first two coordinates less theirs).
fn comparison_gap(problem: &MultipleProblem, rotations: &[Rotation]) -> f64 {
    let lambdas = multipliers(problem, rotations).unwrap();
    let hub = HubGraph::new(problem, usize::MAX)
        .unwrap()
        .unwrap()
        .unwrap();
    let c = hub.comparison(problem, rotations, &lambdas, 1e-9).unwrap();
    let n = problem.num_rotations();
    let mut d = DMatrix::<f64>::zeros(3 * n, 3 * n);
    for (i, r) in rotations.iter().enumerate() {
        d.view_mut((3 * i, 3 * i), (3, 3)).copy_from(r.matrix());
    }
    let m = d.transpose() * dense_certificate(problem, &lambdas) * &d;
    let mut comparison = DMatrix::<f64>::zeros(3 * n, 3 * n);
    let mut laplacian = |a: usize, b: usize, w: f64| {
        comparison[(a, a)] += w;
        comparison[(b, b)] += w;
        comparison[(a, b)] -= w;
        comparison[(b, a)] -= w;
    };
    for (e, w) in hub.cameras.edges().iter().zip(&c.reduced) {
        for k in 0..2 {
            laplacian(3 * e.i + k, 3 * e.j + k, *w);
        }
    }
    for (e, w) in problem.edges().iter().zip(&c.kept) {
        laplacian(3 * e.i + 2, 3 * e.j + 2, *w);
    }
    for (i, delta) in c.with_hub.iter().enumerate() {
        for k in 0..3 {
            if i < n - 1 || k == 2 {
                comparison[(3 * i + k, 3 * i + k)] -= delta;
            }
        }
    }
    for k in 0..2 {
        comparison[(3 * (n - 1) + k, 3 * (n - 1) + k)] -= c.dead;
    }
    let scale = 1.0 + m.amax();
    (m - comparison).symmetric_eigenvalues().min() / scale
}

#[test]
fn the_comparison_is_a_lower_bound_of_m() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(9);
    let mut closest = f64::INFINITY;
    for seed in 0..18u64 {
        let weight = [0.3, 2.25, 50.0][seed as usize / 3 % 3];
        // exact edges and priors far off: the spokes' residuals carry the comparison
        let noise = [(0.1, 2.0), (0.0, 30.0), (0.01, 60.0)][seed as usize % 3];
        let (problem, point) = instance_with(
            10 + seed as usize,
            30 + 3 * seed as usize,
            noise,
            weight,
            seed,
        );
        for turn in [0.0, 0.05, 0.3] {
            let mut rotations = point.clone();
            let world = rotations.len() - 1;
            for r in &mut rotations[..world] {
                *r = perturb(r, turn, &mut rng);
            }
            let gap = comparison_gap(&problem, &rotations);
            assert!(gap >= -1e-12, "seed {seed}, turn {turn}: M - C has {gap:e}");
            closest = closest.min(gap);
        }
    }
    eprintln!("closest {closest:e}");
}

#[test]
fn the_soft_solve_is_proven_to_a_tight_target() {
    for seed in 0..4u64 {
        let (problem, point) = instance(40, 120, 0.03, 2.25, seed);
        let (proven, exact) = proven_and_exact(&problem, &point, 1e-8);
        let mu = proven.expect("the hub comparison proves at the soft solve");
        assert!(
            mu >= -1e-8 && mu <= exact + 1e-12,
            "{mu:e} against {exact:e}"
        );
    }
}

#[test]
fn problems_without_hub_shape_are_not_offered() {
    let (problem, point) = instance(12, 36, 0.05, 2.25, 1);
    assert!(hub_shape(&problem).is_some());
    let world = point.len() - 1;
    // an anisotropic view-graph edge
    let mut info = problem.information().unwrap().to_vec();
    let k = problem.edges().iter().position(|e| e.i != world).unwrap();
    info[k] = crate::multiple::anisotropic::Information::new(Matrix3::from_diagonal(
        &nalgebra::Vector3::new(1.0, 2.0, 3.0),
    ))
    .unwrap();
    let anisotropic = MultipleProblem::new(problem.num_rotations(), problem.edges().to_vec())
        .unwrap()
        .with_information(info)
        .unwrap();
    assert!(hub_shape(&anisotropic).is_none());
    // an isotropic problem
    let (graph, _) = SyntheticGraph {
        num_rotations: 6,
        num_edges: 12,
        ..Default::default()
    }
    .generate();
    assert!(hub_shape(&graph).is_none());
}

/// Step 3 densely: `M v0` (the gauge columns, the hub's third coordinate in the third) against
/// the bounds: its rows other than the hub's first two, those two, and `v0^T M v0`.
#[test]
fn residual_bounds_cover_the_dense_products() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    for seed in 0..6u64 {
        let (problem, point) = instance(12, 36, 0.1, [0.5, 20.0][seed as usize % 2], seed);
        for turn in [0.0, 0.01, 0.2] {
            let mut rotations = point.clone();
            let n = rotations.len();
            for r in &mut rotations[..n - 1] {
                *r = perturb(r, turn, &mut rng);
            }
            let lambdas = multipliers(&problem, &rotations).unwrap();
            let hub = HubGraph::new(&problem, usize::MAX)
                .unwrap()
                .unwrap()
                .unwrap();
            let deg_n = degrees(&problem);
            let rho = hub.residuals(&rotations[..n - 1], &lambdas, &deg_n[..n - 1]);
            let mut d = DMatrix::<f64>::zeros(3 * n, 3 * n);
            for (i, r) in rotations.iter().enumerate() {
                d.view_mut((3 * i, 3 * i), (3, 3)).copy_from(r.matrix());
            }
            let m = d.transpose() * dense_certificate(&problem, &lambdas) * &d;
            let mut v0 = DMatrix::<f64>::zeros(3 * n, 3);
            for i in 0..n - 1 {
                v0.view_mut((3 * i, 0), (3, 3)).fill_with_identity();
            }
            v0[(3 * n - 1, 2)] = 1.0;
            let mv = &m * &v0;
            let dead = mv.rows(3 * n - 3, 2).norm();
            let live = (mv.norm_squared() - dead * dead).max(0.0).sqrt();
            let gauge = (v0.transpose() * &mv).norm();
            let scale = 1e-12 * (1.0 + m.amax());
            let at = format!("seed {seed}, turn {turn}");
            assert!(
                live <= rho.live + scale,
                "{at}: live {live:e} > {:e}",
                rho.live
            );
            assert!(
                dead <= rho.dead + scale,
                "{at}: dead {dead:e} > {:e}",
                rho.dead
            );
            assert!(
                gauge <= rho.rho0 + scale,
                "{at}: v0^T M v0 {gauge:e} > {:e}",
                rho.rho0
            );
            // the bounds are the products' norms up to rounding
            assert!(
                rho.live <= 1.01 * live + 1e-6 * scale.sqrt(),
                "{at}: live {:e} for {live:e}",
                rho.live
            );
        }
    }
}

/// The comparison does not depend on the gauge: the soft solve's point turned by any rotation
/// (its hub off `I`, as a refinement leaves it) is proven as well, with the same multipliers.
#[test]
fn a_turned_gauge_is_proven_alike() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(12);
    for seed in 0..4u64 {
        let (problem, point) = instance(30, 90, 0.03, 2.25, seed);
        let lambdas = multipliers(&problem, &point).unwrap();
        let hub = HubGraph::new(&problem, usize::MAX)
            .unwrap()
            .unwrap()
            .unwrap();
        let at = hub
            .compare(&problem, &point, &lambdas, 1e-8)
            .unwrap()
            .verified_min_eigenvalue;
        let q = crate::so3::random_rotation(&mut rng);
        let turned: Vec<Rotation> = point.iter().map(|r| r * q).collect();
        let again = multipliers(&problem, &turned).unwrap();
        let mu = hub
            .compare(&problem, &turned, &again, 1e-8)
            .unwrap()
            .verified_min_eigenvalue;
        let exact = dense_certificate(&problem, &again)
            .symmetric_eigenvalues()
            .min();
        assert!(
            mu >= -1e-8 && mu <= exact + 1e-12,
            "seed {seed}: {mu:e} (at I: {at:e}), exact {exact:e}"
        );
    }
}
