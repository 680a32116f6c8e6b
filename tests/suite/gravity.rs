//! Gravity priors (`paper-notes/gravity.md`, `[G1]`-`[G7]`): the constrained solve and its
//! certificate against brute force over the yaw angles on tiny graphs, planted truths, the
//! accuracy gravity buys, scale invariance, the mixed problem, another world down direction,
//! and the errors.

use nalgebra::{Matrix3, Vector3};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rotavg::certify::{CertifySettings, certify_gravity};
use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::gravity::{GravityPriors, GravityProblem, solve_gravity};
use rotavg::multiple::synthetic::{SyntheticGraph, SyntheticGravity};
use rotavg::multiple::{Edge, MultipleProblem, MultipleSettings, solve_multiple};
use rotavg::pipeline::{AverageSettings, GravityDetails, average_with_gravity};
use rotavg::so3::{exp, perturb_gaussian, random_rotation};
use rotavg::{Rotation, Verdict};

/// A rotation with third column `g` built here, independently of the crate's frames
/// (Gram-Schmidt from `e_1`, or `e_2` when `g` is nearly parallel to it).
fn frame(g: &Vector3<f64>) -> Matrix3<f64> {
    let a = if g.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = (a - g * a.dot(g)).normalize();
    let v = g.cross(&u);
    Matrix3::from_columns(&[u, v, *g])
}

fn turn(theta: f64) -> Matrix3<f64> {
    let (s, c) = theta.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

/// `sum w ||R_j - R_ij R_i||_F^2` written out (contract section 1).
fn cost(problem: &MultipleProblem, r: &[Matrix3<f64>]) -> f64 {
    problem
        .edges()
        .iter()
        .map(|e| e.weight * (r[e.j] - e.rotation.matrix() * r[e.i]).norm_squared())
        .sum()
}

/// The minimum over yaw angles (node 0's fixed: the gauge) by a grid of `steps` per angle,
/// then coordinate refinement down to 1e-12 rad.
fn brute_force(problem: &MultipleProblem, g: &[Vector3<f64>], steps: usize) -> f64 {
    let n = g.len();
    let frames: Vec<_> = g.iter().map(frame).collect();
    let at = |t: &[f64]| {
        let r: Vec<_> = (0..n)
            .map(|i| frames[i] * turn(if i == 0 { 0.0 } else { t[i - 1] }))
            .collect();
        cost(problem, &r)
    };
    let h = std::f64::consts::TAU / steps as f64;
    let mut best = (f64::INFINITY, vec![0.0; n - 1]);
    let mut idx = vec![0usize; n - 1];
    'grid: loop {
        let t: Vec<f64> = idx.iter().map(|&k| k as f64 * h).collect();
        let c = at(&t);
        if c < best.0 {
            best = (c, t);
        }
        for k in idx.iter_mut() {
            *k += 1;
            if *k < steps {
                continue 'grid;
            }
            *k = 0;
        }
        break;
    }
    let (mut f, mut t) = best;
    let mut step = h;
    while step > 1e-12 {
        let mut moved = false;
        for k in 0..t.len() {
            for d in [step, -step] {
                let mut c = t.clone();
                c[k] += d;
                let v = at(&c);
                if v < f {
                    (f, t, moved) = (v, c, true);
                }
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    f
}

/// A tiny noisy graph (all pairs, one pair measured twice) with noisy gravity.
fn tiny(n: usize, seed: u64) -> (MultipleProblem, Vec<Vector3<f64>>) {
    let mut rng = StdRng::seed_from_u64(seed);
    let truth: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
    let mut edges = Vec::new();
    for i in 0..n {
        for j in i + 1..n {
            let rij = truth[j] * truth[i].inverse();
            edges.push(Edge {
                i,
                j,
                rotation: perturb_gaussian(&rij, 0.4, &mut rng),
                weight: rng.random_range(0.5..2.0),
            });
        }
    }
    let rij = truth[1] * truth[0].inverse();
    edges.push(Edge {
        i: 1,
        j: 0,
        rotation: perturb_gaussian(&rij.inverse(), 0.4, &mut rng),
        weight: 0.7,
    });
    let g = truth
        .iter()
        .map(|r| {
            let noise = exp(&(Vector3::new(rng.random(), rng.random(), rng.random()) * 0.1));
            noise * (r * Vector3::z())
        })
        .collect();
    (MultipleProblem::new(n, edges).unwrap(), g)
}

fn gravity_problem(graph: MultipleProblem, g: &[Vector3<f64>]) -> GravityProblem {
    let priors = GravityPriors::new(g.iter().map(|v| Some((*v).into())).collect()).unwrap();
    GravityProblem::new(graph, priors).unwrap()
}

/// The solve reaches the brute-force minimum, the bound never exceeds it, and `certified`
/// only within the tolerance of it: 3 and 4 nodes, 12 seeds, noise 0.4 rad and gravity off
/// by up to 0.17 rad (local minima exist on such cycles).
#[test]
fn solve_and_certificate_match_brute_force_on_tiny_graphs() {
    let mut certified = 0;
    for seed in 0..12 {
        let n = if seed % 3 == 2 { 4 } else { 3 };
        let (graph, g) = tiny(n, seed);
        let fstar = brute_force(&graph, &g, if n == 3 { 720 } else { 120 });
        let p = gravity_problem(graph.clone(), &g);
        let est = average_with_gravity(&p, &AverageSettings::default()).unwrap();
        let c = est.certificate.unwrap();
        let lb = c.lower_bound.unwrap();
        let scale = fstar.abs().max(1e-12);
        assert!(
            lb <= fstar + 1e-12 * scale,
            "seed {seed}: bound {lb} above f* {fstar}"
        );
        if c.verdict == Verdict::Certified {
            certified += 1;
            assert!(est.solution.cost <= fstar + c.tolerance.allowed_gap(fstar) + 1e-12 * scale);
        }
        // the local solve finds the minimum on these tiny graphs (or the bound says it did not)
        assert!(
            est.solution.cost <= fstar * (1.0 + 1e-9) || c.verdict != Verdict::Certified,
            "seed {seed}: {} vs {fstar}",
            est.solution.cost
        );
        // a feasible estimate a radian of yaw away is never certified, and its bound is sound
        let mut bad = est.solution.rotations.clone();
        bad[1] *= Rotation::from_axis_angle(&Vector3::z_axis(), 1.0);
        let c = certify_gravity(&p, &bad, &CertifySettings::default()).unwrap();
        assert_ne!(c.certificate.verdict, Verdict::Certified, "seed {seed}");
        assert!(c.certificate.lower_bound.unwrap_or(f64::NEG_INFINITY) <= fstar + 1e-12 * scale);
    }
    assert!(certified >= 8, "{certified} of 12 certified");
}

/// Noise-free data and exact gravity: cost 0, certified by the SO(2) dual, the truth found up
/// to a turn about the world's down axis, every rotation in SO(3) to 1e-12.
#[test]
fn planted_truth_is_found_and_certified() {
    let (graph, truth) = SyntheticGraph {
        num_rotations: 60,
        num_edges: 180,
        noise_sigma: 0.0,
        ..Default::default()
    }
    .generate();
    let p = GravityProblem::from_truth(graph, &truth).unwrap();
    let est = average_with_gravity(&p, &AverageSettings::default()).unwrap();
    let details = est.details.gravity.clone().unwrap();
    let c = est.certificate.unwrap();
    assert_eq!(c.verdict, Verdict::Certified, "{c}");
    assert_eq!(details.kind, "full");
    assert!(est.solution.cost < 1e-20);
    // R_i = T_i Rz(a) for one a: R_i^T T_i is the same turn about e_3 for every i
    let d0 = est.solution.rotations[0].inverse() * truth[0];
    for (r, t) in est.solution.rotations.iter().zip(&truth) {
        let d = r.inverse() * t;
        assert!((d.matrix() - d0.matrix()).norm() < 1e-9);
        let m = r.matrix();
        assert!((m.transpose() * m - Matrix3::identity()).norm() < 1e-12);
        assert!((m.determinant() - 1.0).abs() < 1e-12);
    }
    assert!((d0 * Vector3::z() - Vector3::z()).norm() < 1e-9);
}

/// Gravity known to 0.5 degrees makes the estimate more accurate than the view graph alone
/// (0.1 rad of noise per edge, sparse graph), and the full-gravity run is certified.
#[test]
fn gravity_improves_accuracy() {
    let (graph, truth) = SyntheticGraph {
        num_rotations: 200,
        num_edges: 600,
        noise_sigma: 0.1,
        seed: 3,
        ..Default::default()
    }
    .generate();
    let priors = SyntheticGravity {
        noise_deg: 0.5,
        missing_fraction: 0.0,
        seed: 3,
    }
    .priors(&truth)
    .unwrap();
    let p = GravityProblem::new(graph.clone(), priors).unwrap();
    let est = average_with_gravity(&p, &AverageSettings::default()).unwrap();
    assert_eq!(est.certificate.unwrap().verdict, Verdict::Certified);
    let free = solve_multiple(&graph, &MultipleSettings::default()).unwrap();
    let truth: Vec<_> = truth.into_iter().map(Some).collect();
    let with = align_and_compare(&est.solution.rotations, &truth).unwrap();
    let without = align_and_compare(&free.rotations, &truth).unwrap();
    assert!(
        with.mean_deg < 0.8 * without.mean_deg,
        "with gravity {} deg, without {} deg",
        with.mean_deg,
        without.mean_deg
    );
}

/// Multiplying every weight by 1e-6 or 1e6 changes neither the estimate nor the verdict.
#[test]
fn verdict_is_scale_free() {
    let (graph, truth) = SyntheticGraph {
        num_rotations: 40,
        num_edges: 120,
        noise_sigma: 0.05,
        seed: 5,
        ..Default::default()
    }
    .generate();
    let priors = SyntheticGravity {
        noise_deg: 1.0,
        missing_fraction: 0.0,
        seed: 5,
    }
    .priors(&truth)
    .unwrap();
    let run = |c: f64| {
        let g = crate::common::scale_weights(&graph, c);
        let p = GravityProblem::new(g, priors.clone()).unwrap();
        average_with_gravity(&p, &AverageSettings::default()).unwrap()
    };
    let base = run(1.0);
    for c in [1e-6, 1e6] {
        let other = run(c);
        let (a, b) = (
            base.certificate.as_ref().unwrap(),
            other.certificate.unwrap(),
        );
        assert_eq!(a.verdict, b.verdict, "scale {c}");
        assert!((other.solution.cost / c - base.solution.cost).abs() <= 1e-9 * base.solution.cost);
    }
}

/// Some images without a prior: the returned rotations keep the priors they have, the bound
/// (the tilted surrogate's, `[G12]`) certifies them, the view graph's own bound (`[G7]`) is
/// below it, and the accuracy is still better than without priors.
#[test]
fn mixed_priors_are_held_and_certified() {
    let (graph, truth) = SyntheticGraph {
        num_rotations: 150,
        num_edges: 450,
        noise_sigma: 0.1,
        seed: 9,
        ..Default::default()
    }
    .generate();
    let priors = SyntheticGravity {
        noise_deg: 0.5,
        missing_fraction: 0.3,
        seed: 9,
    }
    .priors(&truth)
    .unwrap();
    assert!(!priors.is_full());
    let p = GravityProblem::new(graph.clone(), priors).unwrap();
    let est = average_with_gravity(&p, &AverageSettings::default()).unwrap();
    let details = est.details.gravity.clone().unwrap();
    assert_eq!(details.kind, "mixed");
    let off = p.max_prior_violation_deg(&est.solution.rotations);
    assert!(off < 1e-10, "{off} degrees off");
    let c = est.certificate.unwrap();
    assert!(c.lower_bound.unwrap() <= est.solution.cost);
    assert_eq!(c.verdict, Verdict::Certified, "{c}");
    let free = solve_multiple(&graph, &MultipleSettings::default()).unwrap();
    // the priors cost something: the held optimum is above the free one, and so is the bound
    assert!(c.lower_bound.unwrap() > free.cost);
    let truth: Vec<_> = truth.into_iter().map(Some).collect();
    let with = align_and_compare(&est.solution.rotations, &truth).unwrap();
    let without = align_and_compare(&free.rotations, &truth).unwrap();
    assert!(
        with.mean_deg < without.mean_deg,
        "{} vs {}",
        with.mean_deg,
        without.mean_deg
    );
}

/// The mixed problem on tiny graphs (3-5 nodes, one or two without a prior, noise 0.4 rad,
/// priors off by up to 0.17 rad): the bound is never above the best of 40 solves from random
/// starts (the local solver, held priors), `certified` only within the tolerance of it, and an
/// estimate turned a radian about its gravity axis is not certified.
#[test]
fn mixed_certificates_on_tiny_graphs_match_random_starts() {
    let mut certified = 0;
    for seed in 0..10u64 {
        let n = 3 + (seed % 3) as usize;
        let (graph, g) = tiny(n, 100 + seed);
        let mut dirs: Vec<Option<[f64; 3]>> = g.iter().map(|v| Some((*v).into())).collect();
        dirs[n - 1] = None;
        if seed % 2 == 1 {
            dirs[0] = None;
        }
        let priors = GravityPriors::new(dirs).unwrap();
        let p = GravityProblem::new(graph.clone(), priors).unwrap();
        let est = average_with_gravity(&p, &AverageSettings::default()).unwrap();
        let mut rng = StdRng::seed_from_u64(seed);
        let mut best = est.solution.cost;
        for _ in 0..40 {
            let init = (0..n).map(|_| random_rotation(&mut rng)).collect();
            let settings = MultipleSettings {
                init: rotavg::multiple::Initialisation::Given(init),
                ..Default::default()
            };
            let s = solve_gravity(&p, &settings).unwrap();
            assert!(p.max_prior_violation_deg(&s.rotations) < 1e-9);
            best = best.min(graph.chordal_cost(&s.rotations));
        }
        let c = est.certificate.unwrap();
        let lb = c.lower_bound.unwrap();
        assert!(
            lb <= best * (1.0 + 1e-12),
            "seed {seed}: bound {lb} above {best}"
        );
        if c.verdict == Verdict::Certified {
            certified += 1;
            let cost = graph.chordal_cost(&est.solution.rotations);
            assert!(cost <= best + c.tolerance.allowed_gap(best) + 1e-12 * best);
        }
        let mut bad = est.solution.rotations.clone();
        let free_node = n - 1;
        bad[1] *= Rotation::from_axis_angle(&Vector3::z_axis(), 1.0);
        bad[free_node] = random_rotation(&mut rng);
        let c = certify_gravity(&p, &bad, &CertifySettings::default()).unwrap();
        assert_ne!(c.certificate.verdict, Verdict::Certified, "seed {seed}");
        assert!(c.certificate.lower_bound.unwrap_or(f64::NEG_INFINITY) <= best * (1.0 + 1e-12));
    }
    assert!(certified >= 7, "{certified} of 10 certified");
}

/// Priors stated against another world down direction: the output satisfies `R_i w = g_i`
/// with that `w`, at the cost of the standard statement of the same data.
#[test]
fn another_world_down_direction() {
    let (graph, truth) = SyntheticGraph {
        num_rotations: 30,
        num_edges: 90,
        noise_sigma: 0.05,
        seed: 2,
        ..Default::default()
    }
    .generate();
    let w = Vector3::new(0.0, -1.0, 0.0);
    let dirs: Vec<_> = truth.iter().map(|r| Some((r * w).into())).collect();
    let priors = GravityPriors::new(dirs.clone()).unwrap();
    let p = GravityProblem::new(graph.clone(), priors.with_world_down(w.into()).unwrap()).unwrap();
    let sol = solve_gravity(&p, &MultipleSettings::default()).unwrap();
    assert!(p.max_prior_violation_deg(&sol.rotations) < 1e-10);
    for (r, g) in sol.rotations.iter().zip(&dirs) {
        assert!((r * w - Vector3::from(g.unwrap())).norm() < 1e-10);
    }
    // the same vectors against e_3: the same problem up to R_i -> R_i W (W e_3 = w)
    let standard = GravityProblem::new(graph, GravityPriors::new(dirs).unwrap()).unwrap();
    let s2 = solve_gravity(&standard, &MultipleSettings::default()).unwrap();
    assert!((sol.cost - s2.cost).abs() <= 1e-9 * s2.cost);
}

/// Bad priors and estimates are errors that say what is wrong.
#[test]
fn bad_priors_and_estimates_are_errors() {
    let (graph, truth) = SyntheticGraph {
        num_rotations: 5,
        num_edges: 8,
        ..Default::default()
    }
    .generate();
    let short = GravityPriors::new(vec![Some([0.0, 0.0, 1.0]); 4]).unwrap();
    let e = GravityProblem::new(graph.clone(), short).unwrap_err();
    assert!(e.to_string().contains("4 gravity entries"), "{e}");
    assert!(GravityPriors::new(vec![Some([f64::NAN, 0.0, 1.0])]).is_err());
    assert!(GravityPriors::new(vec![Some([0.0; 3])]).is_err());
    let p = GravityProblem::from_truth(graph, &truth).unwrap();
    let mut off = truth.clone();
    off[2] *= exp(&Vector3::new(0.01, 0.0, 0.0));
    let e = certify_gravity(&p, &off, &CertifySettings::default()).unwrap_err();
    assert!(e.to_string().contains("off its gravity priors"), "{e}");
}

/// Outliers: under the rule `auto` the least-squares residuals call for the Cauchy loss, the
/// robust estimate holds every prior, the chordal L2 problem with the priors on its inlier
/// graph is certified (`chordal_l2_gravity_inliers`), and the result is more accurate than
/// least squares with gravity and than the robust run without gravity.
#[test]
fn robust_gravity_on_outliers() {
    use rotavg::certify::CertifiedProblemKind;
    let (graph, truth, priors) = crate::common::gravity_outlier_scene();
    let p = GravityProblem::new(graph.clone(), priors).unwrap();
    let auto = crate::common::auto_loss_settings();
    let est = average_with_gravity(&p, &auto).unwrap();
    assert!(est.details.loss_choice.as_ref().unwrap().is_robust());
    let off = p.max_prior_violation_deg(&est.solution.rotations);
    assert!(off < 1e-10, "{off} deg; {}", est.solution.report);
    let g = est.details.inlier_graph.as_ref().expect("an inlier graph");
    assert!(p.max_prior_violation_deg(&g.estimate) < 1e-10);
    let c = g.certificate.as_ref().unwrap();
    assert_eq!(c.verdict, Verdict::Certified, "{c}");
    assert_eq!(
        c.certified_problem.unwrap().kind,
        CertifiedProblemKind::ChordalL2GravityInliers
    );
    let truth: Vec<_> = truth.into_iter().map(Some).collect();
    let err = |r: &[Rotation]| align_and_compare(r, &truth).unwrap().robust.median_deg;
    let least_squares = average_with_gravity(&p, &AverageSettings::default()).unwrap();
    let plain = rotavg::pipeline::average_multiple(&graph, &auto).unwrap();
    let (with, ls, without) = (
        err(&est.solution.rotations),
        err(&least_squares.solution.rotations),
        err(&plain.solution.rotations),
    );
    assert!(with < 0.5 * ls, "robust {with} vs least squares {ls}");
    assert!(with < without, "with gravity {with} vs without {without}");
}

/// A budget that cannot hold one factorisation: nothing is certified and no factorisation runs
/// past it; a serialised problem whose priors do not match its graph is an error, not a panic.
#[test]
fn tiny_budgets_and_bad_serialisations() {
    let (graph, truth) = SyntheticGraph {
        num_rotations: 300,
        num_edges: 1200,
        noise_sigma: 0.02,
        ..Default::default()
    }
    .generate();
    let p = GravityProblem::from_truth(graph.clone(), &truth).unwrap();
    let mut settings = CertifySettings::default();
    settings.budget.max_seconds = Some(1e-9);
    let c = certify_gravity(&p, &truth, &settings).unwrap();
    assert_ne!(
        c.certificate.verdict,
        Verdict::Certified,
        "{}",
        c.certificate
    );
    let mut json = serde_json::to_value(&p).unwrap();
    json["priors"]["directions"].as_array_mut().unwrap().pop();
    let e = serde_json::from_value::<GravityProblem>(json).unwrap_err();
    assert!(e.to_string().contains("299 gravity entries"), "{e}");
}

/// `[G9]`: on a graph large enough for the scalar comparison to run first (4000 cameras, 4
/// edges each), the full-gravity estimate is certified by it; its bound agrees within the
/// allowed gap with the shifted Cholesky's on the same `2n x 2n` matrix (`verify_planar`, the
/// proof of `[G3]`, run here beside it), and scaling every weight by `1e-6` or `1e6` keeps the
/// verdict and the proof.
#[test]
fn large_full_gravity_is_certified_by_the_scalar_comparison() {
    use rotavg::certify::gravity::{PlanarForm, verify_planar};
    use rotavg::certify::{Budget, Deadline};
    let (graph, truth) = SyntheticGraph {
        num_rotations: 4000,
        num_edges: 16000,
        noise_sigma: 0.05,
        seed: 11,
        ..Default::default()
    }
    .generate();
    let priors = SyntheticGravity {
        noise_deg: 0.5,
        missing_fraction: 0.0,
        seed: 11,
    }
    .priors(&truth)
    .unwrap();
    for scale in [1.0, 1e-6, 1e6] {
        let g = crate::common::scale_weights(&graph, scale);
        let p = GravityProblem::new(g, priors.clone()).unwrap();
        let est = solve_gravity(&p, &MultipleSettings::default()).unwrap();
        let c = certify_gravity(&p, &est.rotations, &CertifySettings::default()).unwrap();
        let note = c.details.methods()[0].note.clone();
        assert!(c.certificate.is_certified(), "scale {scale}: {note}");
        assert!(note.contains("[G9]"), "scale {scale}: {note}");
        let lb = c.certificate.lower_bound.unwrap();
        assert!(lb <= est.cost, "scale {scale}");
        if scale == 1.0 {
            let form = PlanarForm::new(&p).unwrap();
            let x = PlanarForm::phases(&p, &est.rotations);
            let allowed = c.certificate.tolerance.allowed_gap(est.cost);
            let budget = Budget::default();
            let cholesky =
                verify_planar(&p, &form, &x, allowed, &budget, &Deadline::start(&budget))
                    .unwrap()
                    .unwrap();
            eprintln!(
                "4000 cameras: [G9] bound {lb:.9e}, [G3] shifted Cholesky {:.9e}, cost {:.9e}",
                cholesky.lower_bound, est.cost
            );
            assert!((cholesky.lower_bound - lb).abs() <= 1e-6 * est.cost);
        }
    }
}

/// The reported start cost is the file's cost at the start, priors' terms included, so a solve
/// never reports that it climbed: `init_cost >= cost` for hard and soft priors, from the
/// default start and from a given one (the cost of the free solve, which it reported before,
/// ignores the priors and is below the prior-held optimum).
#[test]
fn the_start_cost_counts_the_priors() {
    for seed in 0..4 {
        let (graph, g) = tiny(6, seed);
        let perturbed: Vec<Rotation> = solve_multiple(&graph, &MultipleSettings::default())
            .unwrap()
            .rotations;
        for weight in [None, Some(0.5), Some(30.0)] {
            let priors = GravityPriors::new(g.iter().map(|v| Some((*v).into())).collect())
                .unwrap()
                .soft_if(weight)
                .unwrap();
            let p = GravityProblem::new(graph.clone(), priors).unwrap();
            let cold = solve_gravity(&p, &MultipleSettings::default()).unwrap();
            assert!(
                cold.init_cost >= cold.cost * (1.0 - 1e-12),
                "seed {seed} weight {weight:?}: start {} below the solution {}",
                cold.init_cost,
                cold.cost
            );
            if weight.is_some() {
                let settings = MultipleSettings {
                    init: rotavg::multiple::Initialisation::Given(perturbed.clone()),
                    ..Default::default()
                };
                let warm = solve_gravity(&p, &settings).unwrap();
                assert!(warm.init_cost >= warm.cost * (1.0 - 1e-12), "seed {seed}");
            }
        }
    }
}

/// `[G6]`'s check with information: the priors' disagreement with each edge in its standard
/// deviations (the heading left free) is `chi` with 2 degrees of freedom for exact priors on a
/// graph whose noise is drawn from its information (median `sqrt(2 ln 2) = 1.177`); priors of 2
/// degrees against edges of 0.5 degrees are far above it and held ones warn
/// (`gravity_imprecise`), soft ones do not; scalar weights carry no standard deviation (none).
#[test]
fn held_priors_less_precise_than_the_information_warn() {
    use rotavg::multiple::synthetic::SyntheticAnisotropic;
    let spec = SyntheticAnisotropic {
        seed: 4,
        ..SyntheticAnisotropic::two_view_like(300, 1200, 0.0)
    };
    let (graph, truth) = spec.generate();
    let codes = |p: &GravityProblem| -> Vec<String> {
        (GravityDetails::of(p).warnings().into_iter())
            .map(|w| w.code.to_string())
            .collect()
    };
    let exact = GravityProblem::from_truth(graph.clone(), &truth).unwrap();
    let sigma = exact
        .check_conventions()
        .unwrap()
        .information_sigma
        .unwrap();
    assert!((sigma - (2.0 * 2f64.ln()).sqrt()).abs() < 0.1, "{sigma}");
    assert!(!codes(&exact).contains(&"gravity_imprecise".to_string()));
    let noisy = SyntheticGravity {
        noise_deg: 2.0,
        missing_fraction: 0.0,
        seed: 5,
    }
    .priors(&truth)
    .unwrap();
    let held = GravityProblem::new(graph.clone(), noisy.clone()).unwrap();
    let sigma = held.check_conventions().unwrap().information_sigma.unwrap();
    assert!(sigma > 3.0, "{sigma}");
    assert!(codes(&held).contains(&"gravity_imprecise".to_string()));
    let soft = GravityProblem::new(graph, noisy.with_weight(1.0).unwrap()).unwrap();
    assert!(!codes(&soft).contains(&"gravity_imprecise".to_string()));
    let (scalar, truth) = SyntheticGraph::default().generate();
    let scalar = GravityProblem::from_truth(scalar, &truth).unwrap();
    assert_eq!(scalar.check_conventions().unwrap().information_sigma, None);
}

/// Held priors on nine images in ten with strongly anisotropic information (eigenvalue ratio
/// 1e4, 1000 cameras): the light tilted surrogate (`[G12]` "Two weights") certifies, its gap
/// below the stiff one's (whose world node's rows, `w` times 900 priors, set the rounding margin
/// of its verification), and the bound is below the cost of the held solves from the truth
/// and from perturbed truths.
#[test]
fn mixed_priors_with_strong_information_are_certified_by_the_light_surrogate() {
    use rotavg::multiple::gravity::Stiffness;
    use rotavg::multiple::synthetic::SyntheticAnisotropic;
    let (graph, truth) = SyntheticAnisotropic {
        num_rotations: 1000,
        num_edges: 5000,
        sigma: 0.5f64.to_radians(),
        ratio: 1e4,
        seed: 1,
        ..Default::default()
    }
    .generate();
    let priors = SyntheticGravity {
        noise_deg: 0.0,
        missing_fraction: 0.1,
        seed: 1,
    }
    .priors(&truth)
    .unwrap();
    assert!(!priors.is_full());
    let p = GravityProblem::new(graph, priors).unwrap();
    let est = average_with_gravity(&p, &AverageSettings::default()).unwrap();
    let c = est.certificate.clone().unwrap();
    assert_eq!(c.verdict, Verdict::Certified, "{c}");
    let lb = c.lower_bound.unwrap();
    let r = &est.solution.rotations;
    let gap = |s: Stiffness| {
        let (surrogate, constant) = p.tilted_surrogate(r, s).unwrap();
        let inner = certify_gravity(&surrogate, r, &CertifySettings::default()).unwrap();
        est.solution.cost - (inner.certificate.lower_bound.unwrap() - constant)
    };
    let (light, stiff) = (gap(Stiffness::Light), gap(Stiffness::Stiff));
    assert!(light < stiff, "light {light:e}, stiff {stiff:e}");
    let mut rng = StdRng::seed_from_u64(1);
    for k in 0..3 {
        let init = (truth.iter())
            .map(|t| match k {
                0 => *t,
                _ => perturb_gaussian(t, 0.05, &mut rng),
            })
            .collect();
        let settings = MultipleSettings {
            init: rotavg::multiple::Initialisation::Given(init),
            ..Default::default()
        };
        let s = solve_gravity(&p, &settings).unwrap();
        assert!(p.max_prior_violation_deg(&s.rotations) < 1e-9);
        let cost = p.problem().chordal_cost(&s.rotations);
        assert!(lb <= cost * (1.0 + 1e-12), "bound {lb} above {cost}");
    }
}
