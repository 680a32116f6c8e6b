//! Local solvers of multiple rotation averaging (`paper-notes/multiple.md`, `[M3]`..`[M10]`).
//! Every expected value is a planted ground truth, a closed form derived in the notes, or a
//! finite-difference quotient.

use nalgebra::Vector3;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::Error;
use rotavg::multiple::synthetic::{SyntheticGraph, SyntheticGrid, z_cycle};
use rotavg::multiple::{
    Edge, Initialisation, MultipleProblem, MultipleSettings, chordal_gradient, fix_gauge,
    initialise, objective_cost_gradient, objective_terms, solve_multiple, spanning_tree,
};
use rotavg::objective::{Loss, Objective};
use rotavg::so3::{exp, perturb, random_rotation, random_unit_vector};
use rotavg::{Metric, Rotation, Termination};

use crate::common;
use common::{max_gauge_error, mean_gauge_error as mean_error};

const GEODESIC_L2: Objective = Objective {
    metric: Metric::Geodesic,
    loss: Loss::L2,
};
const GEODESIC_L1: Objective = Objective {
    metric: Metric::Geodesic,
    loss: Loss::L1,
};

/// Geodesic Huber with threshold `deg`.
fn huber(deg: f64) -> Objective {
    Objective::new(Metric::Geodesic, Loss::Huber { threshold_deg: deg })
}

/// Geodesic Cauchy with scale `deg`.
fn cauchy(deg: f64) -> Objective {
    Objective::new(Metric::Geodesic, Loss::Cauchy { scale_deg: deg })
}

fn all_losses() -> Vec<Objective> {
    vec![
        Objective::CHORDAL_L2,
        GEODESIC_L2,
        GEODESIC_L1,
        huber(5.0),
        cauchy(5.0),
    ]
}

/// The problem's data with another objective.
fn with(p: &MultipleProblem, objective: Objective) -> MultipleProblem {
    p.clone().with_objective(objective).unwrap()
}

/// Planted noise-free graphs: every loss and both initialisations reach cost ~0 and recover the
/// ground truth exactly up to gauge. Expected: 0 (planted).
#[test]
fn noise_free_exact_recovery() {
    // (300, 3000) is dense enough that the PCG path is taken (fill > DIRECT_FILL_PER_NODE)
    for (seed, (n, m)) in [(20, 40), (200, 600), (500, 800), (300, 3000)]
        .into_iter()
        .enumerate()
    {
        let (p, gt) = SyntheticGraph {
            num_rotations: n,
            num_edges: m,
            noise_sigma: 0.0,
            outlier_fraction: 0.0,
            seed: seed as u64,
        }
        .generate();
        for init in [Initialisation::SpanningTree, Initialisation::Spectral] {
            let r0 = initialise(&p, &init).unwrap();
            assert!(max_gauge_error(&r0, &gt) < 1e-8, "{init:?}");
        }
        // start far away: random rotations close to the truth (0.3 rad)
        let mut rng = StdRng::seed_from_u64(seed as u64);
        let start: Vec<Rotation> = gt.iter().map(|r| perturb(r, 0.3, &mut rng)).collect();
        for loss in all_losses() {
            let s = MultipleSettings {
                init: Initialisation::Given(start.clone()),
                max_iterations: 200,
                // noise-free: the gradient can be driven to rounding level, so recovery
                // to 1e-8 rad is a fair demand
                gradient_tolerance: 1e-12,
                ..Default::default()
            };
            let sol = solve_multiple(&with(&p, loss), &s).unwrap();
            let err = max_gauge_error(&sol.rotations, &gt);
            assert!(
                sol.rotations[0] == Rotation::identity(),
                "gauge R_0 = I not fixed"
            );
            // L1's smoothing (eps = 1e-6) and IRLS convergence limit its accuracy
            let tol = if loss == GEODESIC_L1 { 1e-5 } else { 1e-8 };
            assert!(err < tol, "{loss:?}: max error {err}, {sol}");
            assert!(sol.chordal_cost < 1e-10, "{loss:?}: {sol}");
            if loss != GEODESIC_L1 {
                assert!(sol.report.termination.is_converged(), "{loss:?}: {sol}");
            }
        }
    }
}

/// The chordal cost of the answer is never above that of the initialisation (monotone
/// trust-region acceptance, [M6]). Noisy graphs, with outliers, both initialisations.
#[test]
fn chordal_never_above_initialisation() {
    for seed in 0..6 {
        let (p, _) = SyntheticGraph {
            num_rotations: 150,
            num_edges: 450,
            noise_sigma: 0.1,
            outlier_fraction: if seed % 2 == 0 { 0.0 } else { 0.2 },
            seed,
        }
        .generate();
        for init in [Initialisation::SpanningTree, Initialisation::Spectral] {
            let r0 = initialise(&p, &init).unwrap();
            let c0 = p.chordal_cost(&r0);
            let sol = solve_multiple(
                &p,
                &MultipleSettings {
                    init: Initialisation::Given(r0),
                    ..Default::default()
                },
            )
            .unwrap();
            assert!(sol.cost <= c0 * (1.0 + 1e-14), "{} > {c0}", sol.cost);
            assert!((sol.init_cost - c0).abs() <= 1e-12 * c0);
            assert!((sol.cost - p.chordal_cost(&sol.rotations)).abs() <= 1e-9 * sol.cost);
            assert!(sol.report.termination.is_converged(), "{sol}");
        }
    }
}

/// Central finite differences of `t -> f(R_k exp(t hat u))` against `<grad_k, u>` `[M3]`, `[M8]`.
fn check_gradient(p: &MultipleProblem, r: &[Rotation], rng: &mut StdRng) -> f64 {
    let (_, g) = objective_cost_gradient(p, r, 1e-6);
    let h = 1e-6;
    let mut worst: f64 = 0.0;
    for _ in 0..6 {
        let k = rand::Rng::random_range(rng, 0..r.len());
        let u: Vector3<f64> = random_unit_vector(rng);
        let f = |t: f64| {
            let mut rr = r.to_vec();
            rr[k] = r[k] * exp(&(u * t));
            objective_cost_gradient(p, &rr, 1e-6).0
        };
        let fd = (f(h) - f(-h)) / (2.0 * h);
        let an = g[k].dot(&u);
        worst = worst.max((fd - an).abs() / (1.0 + an.abs()));
    }
    worst
}

#[test]
fn gradients_match_finite_differences() {
    let mut rng = StdRng::seed_from_u64(5);
    let (p, gt) = SyntheticGraph {
        num_rotations: 30,
        num_edges: 90,
        noise_sigma: 0.2,
        outlier_fraction: 0.1,
        seed: 3,
    }
    .generate();
    // random points: near the truth, and uniformly random
    let near: Vec<Rotation> = gt.iter().map(|r| perturb(r, 0.5, &mut rng)).collect();
    let random: Vec<Rotation> = (0..gt.len()).map(|_| random_rotation(&mut rng)).collect();
    for loss in all_losses() {
        for r in [&near, &random] {
            let e = check_gradient(&with(&p, loss), r, &mut rng);
            // L1 is non-smooth only where theta_e < eps = 1e-6: not hit at these points
            assert!(e < 1e-6, "{loss:?}: finite-difference mismatch {e}");
        }
    }
    // chordal_gradient is objective_cost_gradient(chordal L2)
    let (c, g) = chordal_gradient(&p, &near);
    assert!((c - p.chordal_cost(&near)).abs() < 1e-10 * c);
    // objective_terms(chordal L2) agrees with the direct chordal gradient
    let (c2, g2) = {
        let mut cost = 0.0;
        let mut grad = vec![Vector3::zeros(); near.len()];
        for e in p.edges() {
            let v = rotavg::so3::log(&(near[e.j].inverse() * e.rotation * near[e.i]));
            let (rho, psi) = objective_terms(&Objective::CHORDAL_L2, v.norm(), 1e-6);
            cost += e.weight * rho;
            grad[e.i] += v * (e.weight * psi);
            grad[e.j] -= v * (e.weight * psi);
        }
        (cost, grad)
    };
    assert!((c - c2).abs() < 1e-9 * c);
    for (a, b) in g.iter().zip(&g2) {
        assert!((a - b).norm() < 1e-9 * (1.0 + a.norm()));
    }
}

/// At the answer the gradient is ~0 (finite differences of the cost too).
#[test]
fn gradient_vanishes_at_answer() {
    let mut rng = StdRng::seed_from_u64(8);
    let (p, _) = SyntheticGraph {
        num_rotations: 100,
        num_edges: 300,
        noise_sigma: 0.1,
        seed: 9,
        ..Default::default()
    }
    .generate();
    let w: f64 = p.edges().iter().map(|e| e.weight).sum();
    for loss in [Objective::CHORDAL_L2, GEODESIC_L2, huber(3.0), cauchy(3.0)] {
        let p = with(&p, loss);
        let sol = solve_multiple(
            &p,
            &MultipleSettings {
                max_iterations: 500,
                ..Default::default()
            },
        )
        .unwrap();
        assert!(sol.report.termination.is_converged(), "{sol}");
        if let Termination::Converged { measure, .. } = &sol.report.termination {
            // the gradient test, or (chordal Newton) the predicted decrease with the gradient
            // test met: "... (with ||grad|| / sum(w) <= its tolerance)"
            assert!(measure.contains("grad"), "{sol}");
        }
        assert!(sol.gradient_norm / w <= 1e-8, "{sol}");
        let (_, g) = objective_cost_gradient(&p, &sol.rotations, 1e-6);
        let gn = g.iter().map(|v| v.norm_squared()).sum::<f64>().sqrt();
        assert!((gn - sol.gradient_norm).abs() <= 1e-6 * w * 1e-8 + 1e-9 * gn);
        // finite differences: the directional derivative is ~0 along random directions
        let e = check_gradient(&p, &sol.rotations, &mut rng);
        assert!(e < 1e-6, "{loss:?}: {e}");
    }
}

/// Gauge invariance: data of the gauge-transformed problem (R_i -> R_i G leaves R_ij unchanged,
/// so transform instead the *labels*: relabel nodes by a permutation and reverse some edges)
/// give the same costs; and starting from a gauge-transformed start gives the same answer.
#[test]
fn gauge_and_relabelling_invariance() {
    let mut rng = StdRng::seed_from_u64(21);
    let (p, gt) = SyntheticGraph {
        num_rotations: 80,
        num_edges: 240,
        noise_sigma: 0.15,
        seed: 4,
        ..Default::default()
    }
    .generate();
    let start: Vec<Rotation> = gt.iter().map(|r| perturb(r, 0.2, &mut rng)).collect();
    let g = random_rotation(&mut rng);
    let start_g: Vec<Rotation> = start.iter().map(|r| r * g).collect();
    for loss in all_losses() {
        let p = with(&p, loss);
        let solve = |init: Vec<Rotation>| {
            solve_multiple(
                &p,
                &MultipleSettings {
                    init: Initialisation::Given(init),
                    max_iterations: 300,
                    ..Default::default()
                },
            )
            .unwrap()
        };
        let a = solve(start.clone());
        let b = solve(start_g.clone());
        let tol = if loss == GEODESIC_L1 { 1e-4 } else { 1e-7 };
        assert!(
            max_gauge_error(&a.rotations, &b.rotations) < tol,
            "{loss:?}"
        );
        assert!(
            (a.cost - b.cost).abs() <= 1e-8 * a.cost.max(1e-12),
            "{loss:?}"
        );
    }
    // relabelled + reversed edges: chordal optimum has the same cost
    let n = p.num_rotations();
    let mut perm: Vec<usize> = (0..n).collect();
    perm.reverse();
    let edges: Vec<Edge> = p
        .edges()
        .iter()
        .enumerate()
        .map(|(k, e)| {
            let e = Edge {
                i: perm[e.i],
                j: perm[e.j],
                ..e.clone()
            };
            if k % 2 == 0 { e.reversed() } else { e }
        })
        .collect();
    let q = MultipleProblem::new(n, edges).unwrap();
    let a = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let b = solve_multiple(&q, &MultipleSettings::default()).unwrap();
    assert!(
        (a.cost - b.cost).abs() < 1e-9 * a.cost,
        "{} vs {}",
        a.cost,
        b.cost
    );
    // same rotations up to the relabelling and gauge
    let mut b_back: Vec<Rotation> = (0..n).map(|i| b.rotations[perm[i]]).collect();
    fix_gauge(&mut b_back);
    assert!(max_gauge_error(&a.rotations, &b_back) < 1e-7);
}

/// z_cycle(n, phi): planar critical configuration k has all residuals equal to
/// `delta_k = (phi + 2 pi k) / n` about z; chordal cost `8 n sin^2(delta_k / 2)`, geodesic cost
/// `(phi + 2 pi k)^2 / n` ([M10]). Started near configuration k (perturbations about z only)
/// the solver returns to it.
#[test]
fn z_cycle_local_minima() {
    let n = 12;
    let phi = 1.0;
    let p = z_cycle(n, phi);
    let mut rng = StdRng::seed_from_u64(2);
    for k in [-1i32, 0, 1, 2] {
        let delta = (phi + 2.0 * std::f64::consts::PI * k as f64) / n as f64;
        // alpha_i = i (phi / n - delta): residual of edge (i, i+1) is -delta about z
        let config: Vec<Rotation> = (0..n)
            .map(|i| exp(&(Vector3::z() * (i as f64 * (phi / n as f64 - delta)))))
            .collect();
        let chordal = 8.0 * n as f64 * (0.5 * delta).sin().powi(2);
        let geodesic = (phi + 2.0 * std::f64::consts::PI * k as f64).powi(2) / n as f64;
        assert!((p.chordal_cost(&config) - chordal).abs() < 1e-12 * chordal.max(1.0));
        let start: Vec<Rotation> = config
            .iter()
            .map(|r| r * exp(&(Vector3::z() * (0.05 * rotavg::so3::gaussian(&mut rng)))))
            .collect();
        for (loss, expected) in [(Objective::CHORDAL_L2, chordal), (GEODESIC_L2, geodesic)] {
            let sol = solve_multiple(
                &with(&p, loss),
                &MultipleSettings {
                    init: Initialisation::Given(start.clone()),
                    max_iterations: 300,
                    ..Default::default()
                },
            )
            .unwrap();
            assert!(
                (sol.cost - expected).abs() < 1e-9 * expected.max(1.0),
                "k = {k}, {loss:?}: cost {} expected {expected}; {sol}",
                sol.cost
            );
            assert!(
                max_gauge_error(&sol.rotations, &config) < 1e-6,
                "k = {k} {loss:?}"
            );
        }
    }
}

/// 10-20% outliers: the robust losses' error to the ground truth is below chordal L2's.
/// The geodesic L1 problem of a planted graph of 200 nodes and 1000 edges, 20 % of them
/// outliers, and its truth.
fn l1_with_outliers() -> (rotavg::multiple::MultipleProblem, Vec<Rotation>) {
    let (p, truth) = SyntheticGraph {
        num_rotations: 200,
        num_edges: 1000,
        noise_sigma: 0.02,
        outlier_fraction: 0.2,
        seed: 5,
    }
    .generate();
    (with(&p, GEODESIC_L1), truth)
}

/// The L1 IRLS stops on its cost decrease over a window of iterations: the cost it stops at is
/// within 1e-8 (relative) of the cost a run 10x longer (decrease test disabled) reaches, and
/// no worse than the start.
#[test]
fn l1_stops_on_cost_decrease_near_the_long_run_cost() {
    let (p, _) = l1_with_outliers();
    let short = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let long = solve_multiple(
        &p,
        &MultipleSettings {
            irls_decrease_tolerance: f64::MIN_POSITIVE,
            max_iterations: 1000,
            ..Default::default()
        },
    )
    .unwrap();
    eprintln!("default: {short}\nlong: {long}");
    assert!(short.report.termination.is_converged(), "{short}");
    assert!(short.report.iterations <= long.report.iterations);
    assert!(short.cost <= short.init_cost);
    assert!(
        (short.cost - long.cost).abs() <= 1e-8 * long.cost,
        "{} vs {}",
        short.cost,
        long.cost
    );
}

/// `[M9]` over-relaxation: L1's IRLS with its default step multiple (1.8) and with the plain
/// step (1.0) end at the same cost to 1e-4 relative (L1's IRLS stops at points that depend on
/// its path by about that much: here the over-relaxed one 6.6e-5 lower) and as accurate against
/// the planted truth (within 5 %) on a graph with 20 % outliers, the default in fewer
/// iterations (150 against 319); multiples outside `[1, 2)` are refused.
#[test]
fn l1_over_relaxation_reaches_the_plain_steps_minimum_in_fewer_iterations() {
    let (p, gt) = l1_with_outliers();
    let plain = MultipleSettings {
        l1_overrelaxation: 1.0,
        ..Default::default()
    };
    let (fast, slow) = (
        solve_multiple(&p, &MultipleSettings::default()).unwrap(),
        solve_multiple(&p, &plain).unwrap(),
    );
    eprintln!("over-relaxed: {fast}\nplain: {slow}");
    assert!(fast.report.termination.is_converged() && slow.report.termination.is_converged());
    assert!(fast.report.iterations < slow.report.iterations);
    assert!(
        (fast.cost - slow.cost).abs() <= 1e-4 * slow.cost,
        "{} vs {}",
        fast.cost,
        slow.cost
    );
    let errors = (
        mean_error(&fast.rotations, &gt),
        mean_error(&slow.rotations, &gt),
    );
    eprintln!("mean error against the truth: over-relaxed {errors:?}");
    assert!(errors.0 <= 1.05 * errors.1, "{errors:?}");
    for bad in [0.9, 2.0, f64::NAN] {
        let s = MultipleSettings {
            l1_overrelaxation: bad,
            ..Default::default()
        };
        assert!(s.validate().is_err(), "{bad}");
    }
}

#[test]
fn robust_losses_reject_outliers() {
    for (seed, frac) in [(1u64, 0.1), (2, 0.2)] {
        let (p, gt) = SyntheticGraph {
            num_rotations: 200,
            num_edges: 1000,
            noise_sigma: 0.02,
            outlier_fraction: frac,
            seed,
        }
        .generate();
        let chordal = solve_multiple(&p, &MultipleSettings::default()).unwrap();
        let e_chordal = mean_error(&chordal.rotations, &gt);
        for loss in [GEODESIC_L1, huber(3.0), cauchy(3.0)] {
            let sol = solve_multiple(&with(&p, loss), &MultipleSettings::default()).unwrap();
            let e = mean_error(&sol.rotations, &gt);
            eprintln!("outliers {frac}: {loss:?} mean error {e:.4} vs chordal {e_chordal:.4}");
            assert!(e < 0.5 * e_chordal, "{loss:?}: {e} vs chordal {e_chordal}");
            assert!(sol.cost <= sol.init_cost);
        }
    }
}

#[test]
fn errors_are_typed() {
    let e = |i, j| Edge {
        i,
        j,
        rotation: Rotation::identity(),
        weight: 1.0,
    };
    let p = MultipleProblem::new(5, vec![e(0, 1), e(1, 2), e(3, 4)]).unwrap();
    match solve_multiple(&p, &MultipleSettings::default()) {
        Err(Error::Disconnected { component_sizes }) => assert_eq!(component_sizes, vec![3, 2]),
        other => panic!("expected Disconnected, got {other:?}"),
    }
    let q = MultipleProblem::new(3, vec![e(0, 1), e(1, 2)]).unwrap();
    assert!(matches!(
        q.clone().with_objective(huber(-1.0)),
        Err(Error::InvalidSettings { .. })
    ));
    let bad = MultipleSettings {
        init: Initialisation::Given(vec![Rotation::identity(); 2]),
        ..Default::default()
    };
    assert!(matches!(
        solve_multiple(&q, &bad),
        Err(Error::InvalidSettings { .. })
    ));
    // serde round trip of settings, objective and solution
    let s = MultipleSettings {
        init: Initialisation::SpanningTree,
        max_iterations: 7,
        ..Default::default()
    };
    let js = serde_json::to_string(&s).unwrap();
    assert_eq!(serde_json::from_str::<MultipleSettings>(&js).unwrap(), s);
    let o = cauchy(2.0);
    let js = serde_json::to_string(&o).unwrap();
    assert_eq!(serde_json::from_str::<Objective>(&js).unwrap(), o);
    let sol = solve_multiple(&q, &MultipleSettings::default()).unwrap();
    let js = serde_json::to_string(&sol).unwrap();
    let back: rotavg::multiple::MultipleSolution = serde_json::from_str(&js).unwrap();
    assert_eq!(back.rotations.len(), 3);
}

/// `[M4]`: the start propagates along shortest paths for lengths `1 / w` from a central node.
/// A light edge carrying a wrong measurement (0.3 rad off) closes a triangle; every other
/// measurement is exact. The shortest path for `1 / w` avoids the light edge (length 100
/// against 2), so the start is exact; a tree by hop count from the centre (node 2, the middle
/// of the double sweep 0 -> 3 -> 0) would use it and be 0.3 rad off at node 0.
#[test]
fn spanning_tree_follows_shortest_paths_for_inverse_weights() {
    let mut rng = StdRng::seed_from_u64(11);
    let truth: Vec<Rotation> = (0..4).map(|_| random_rotation(&mut rng)).collect();
    let exact = |i: usize, j: usize, weight: f64| Edge {
        i,
        j,
        rotation: truth[j] * truth[i].inverse(),
        weight,
    };
    let mut wrong = exact(0, 2, 0.01);
    wrong.rotation = exp(&Vector3::new(0.3, 0.0, 0.0)) * wrong.rotation;
    let p = MultipleProblem::new(
        4,
        vec![exact(0, 1, 1.0), exact(1, 2, 1.0), wrong, exact(2, 3, 1.0)],
    )
    .unwrap();
    let start = spanning_tree(&p);
    assert!(max_gauge_error(&start, &truth) < 1e-12);
    // gauge R_0 = I
    assert!((start[0].matrix() - nalgebra::Matrix3::identity()).norm() < 1e-15);
}

/// `[M4]`: on a grid sweep (odometry listed first, unit weights) the start does not drift along
/// the sweep. Independent expectation: noise of `sigma` per axis gives a random-walk error of
/// about `1.6 sigma sqrt(k)` after `k` edges; the 40 x 40 sweep's own chain has 1599 edges
/// (about 0.64 rad at the far end), while shortest paths from the centre have at most about 40
/// (about 0.1 rad). The mean error over all nodes must stay below 0.15 rad, and well below that
/// of the tree of the first edges in listed order (the maximum-weight tree of unit weights,
/// the start before [M4] was changed), built here independently.
#[test]
fn spanning_tree_start_does_not_drift_along_a_sweep() {
    let (p, truth) = SyntheticGrid {
        width: 40,
        height: 40,
        noise_sigma: 0.01,
        seed: 5,
        ..Default::default()
    }
    .generate();
    let start = spanning_tree(&p);
    let mean = mean_error(&start, &truth);
    let listed = listed_order_tree(&p);
    let mean_listed = mean_error(&listed, &truth);
    assert!(
        mean < 0.15 && 2.0 * mean < mean_listed,
        "mean error of the start {mean} rad, of the listed-order tree {mean_listed} rad"
    );
}

/// Rotations propagated from node 0 along the spanning tree of the first edges in listed
/// order (union-find), for comparison.
fn listed_order_tree(p: &MultipleProblem) -> Vec<Rotation> {
    let n = p.num_rotations();
    let mut root: Vec<usize> = (0..n).collect();
    fn find(root: &mut [usize], mut x: usize) -> usize {
        while root[x] != x {
            x = root[x];
        }
        x
    }
    let mut adjacent: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (k, e) in p.edges().iter().enumerate() {
        let (a, b) = (find(&mut root, e.i), find(&mut root, e.j));
        if a != b {
            root[a] = b;
            adjacent[e.i].push(k);
            adjacent[e.j].push(k);
        }
    }
    let mut r = vec![Rotation::identity(); n];
    let mut seen = vec![false; n];
    seen[0] = true;
    let mut stack = vec![0usize];
    while let Some(u) = stack.pop() {
        for &k in &adjacent[u] {
            let e = &p.edges()[k];
            let v = if e.i == u { e.j } else { e.i };
            if !seen[v] {
                seen[v] = true;
                r[v] = if e.i == u {
                    e.rotation * r[u]
                } else {
                    e.rotation.inverse() * r[u]
                };
                stack.push(v);
            }
        }
    }
    r
}
