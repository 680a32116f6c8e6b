//! The verdict's tolerance means what it says (issue 11): certified iff
//! `gap <= max(1e-6 |f|, 1e-9 x median weight)`. Scaling every weight by `c` in
//! `[1e-12, 1e12]` never changes a verdict, no single edge can loosen it, and the three false
//! certificates of the old per-total-weight rule are regression tests.

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rotavg::certify::{CertifySettings, certify_conjugate, certify_multiple, certify_single};
use rotavg::conjugate::synthetic::random_instance;
use rotavg::conjugate::{ConjugatePair, ConjugateProblem};
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::multiple::{Edge, MultipleProblem};
use rotavg::pipeline::{AverageSettings, average_multiple};
use rotavg::single::SingleProblem;
use rotavg::so3::{exp, perturb_gaussian, random_rotation};
use rotavg::{Rotation, Verdict};

mod common;
use common::scale_weights;

/// Moves `y` along a fixed random direction until the cost is `(1 + excess) f*`
/// (bisection on the step; the cost grows monotonically along it near the optimum).
fn with_excess(p: &MultipleProblem, opt: &[Rotation], excess: f64, seed: u64) -> Vec<Rotation> {
    let mut rng = StdRng::seed_from_u64(seed);
    let dir: Vec<nalgebra::Vector3<f64>> = opt
        .iter()
        .map(|_| {
            nalgebra::Vector3::new(
                rng.random::<f64>() - 0.5,
                rng.random::<f64>() - 0.5,
                rng.random::<f64>() - 0.5,
            )
        })
        .collect();
    let fstar = p.chordal_cost(opt);
    let at = |t: f64| -> Vec<Rotation> {
        opt.iter()
            .zip(&dir)
            .map(|(r, d)| r * exp(&(d * t)))
            .collect()
    };
    let (mut lo, mut hi) = (0.0, 1.0);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if p.chordal_cost(&at(mid)) < fstar * (1.0 + excess) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    at(hi)
}

/// The three false certificates of the per-total-weight rule, as measured in issue 11.
#[test]
fn the_three_false_certificates_of_the_old_rule_are_gone() {
    let settings = CertifySettings::default();
    // (1) a 6-node graph plus one leaf edge of weight 1e13 (zero residual at every optimum):
    // the old tolerance became 100 and an estimate costing 3.3 x the minimum was certified.
    let (p, _) = SyntheticGraph {
        num_rotations: 6,
        num_edges: 12,
        noise_sigma: 0.1,
        seed: 4,
        ..Default::default()
    }
    .generate();
    let opt = average_multiple(&p, &AverageSettings::default()).unwrap();
    let fstar = opt.solution.chordal_cost;
    let bad = with_excess(&p, &opt.solution.rotations, 2.3, 1);
    let leaf_rotation = exp(&nalgebra::Vector3::new(0.3, 0.2, -0.1));
    let mut edges = p.edges().to_vec();
    edges.push(Edge {
        i: 0,
        j: 6,
        rotation: leaf_rotation,
        weight: 1e13,
    });
    let heavy = MultipleProblem::new(7, edges).unwrap();
    let mut y = bad.clone();
    y.push(leaf_rotation * bad[0]); // the leaf's residual is zero
    let c = certify_multiple(&heavy, &y, &settings).unwrap();
    println!("heavy leaf: {}", c.certificate);
    assert!((heavy.chordal_cost(&y) / fstar - 3.3).abs() < 1e-6);
    assert_ne!(c.certificate.verdict, Verdict::Certified);
    assert!(c.certificate.tolerance.absolute <= 1e-9 * 1.0 + 1e-21); // median weight 1

    // (2) weights spanning 1e-2..1e4: an estimate 1e-4 (relative) above the optimum.
    let mut rng = StdRng::seed_from_u64(2);
    let (p, _) = SyntheticGraph {
        num_rotations: 30,
        num_edges: 90,
        noise_sigma: 0.05,
        seed: 9,
        ..Default::default()
    }
    .generate();
    let edges = p
        .edges()
        .iter()
        .map(|e| Edge {
            weight: 10f64.powf(rng.random_range(-2.0..4.0)),
            ..e.clone()
        })
        .collect();
    let p = MultipleProblem::new(30, edges).unwrap();
    let opt = average_multiple(&p, &AverageSettings::default()).unwrap();
    assert!(opt.certificate.unwrap().is_certified());
    let bad = with_excess(&p, &opt.solution.rotations, 1e-4, 2);
    let c = certify_multiple(&p, &bad, &settings).unwrap();
    println!("spread weights: {}", c.certificate);
    assert_ne!(c.certificate.verdict, Verdict::Certified);

    // (3) all weights scaled by 1e-12: the fixed 1e-9 floor certified a random estimate costing
    // 19 x the optimum.
    let tiny = scale_weights(&p, 1e-12);
    let random: Vec<Rotation> = (0..30).map(|_| random_rotation(&mut rng)).collect();
    let c = certify_multiple(&tiny, &random, &settings).unwrap();
    println!("weights x 1e-12, random estimate: {}", c.certificate);
    assert_ne!(c.certificate.verdict, Verdict::Certified);
}

/// Scaling every weight by c in [1e-12, 1e12] never changes a verdict (optima, estimates at
/// 1e-8 .. 1e-2 relative excess, random points), for 12 seeded graphs.
#[test]
fn verdicts_are_invariant_under_weight_scaling() {
    let settings = CertifySettings::default();
    let mut checked = 0;
    for seed in 0..12u64 {
        let (p, truth) = SyntheticGraph {
            num_rotations: 8 + seed as usize,
            num_edges: 20 + 2 * seed as usize,
            noise_sigma: [0.0, 1e-4, 0.02, 0.2][seed as usize % 4],
            seed,
            ..Default::default()
        }
        .generate();
        let opt = average_multiple(&p, &AverageSettings::default()).unwrap();
        let mut points = vec![opt.solution.rotations.clone(), truth];
        for (k, excess) in [1e-8, 1e-6, 1e-4, 1e-2].into_iter().enumerate() {
            points.push(with_excess(
                &p,
                &opt.solution.rotations,
                excess,
                seed * 10 + k as u64,
            ));
        }
        for y in &points {
            let reference = certify_multiple(&p, y, &settings).unwrap().certificate;
            // away from the decision boundary, where the verdict must not depend on rounding
            let tol = reference.tolerance.allowed_gap(reference.upper_bound);
            let gap = reference.gap.unwrap_or(f64::INFINITY);
            if (gap - tol).abs() < 0.1 * tol {
                continue;
            }
            for c in [1e-12, 1e-6, 1e6, 1e12] {
                let v = certify_multiple(&scale_weights(&p, c), y, &settings)
                    .unwrap()
                    .certificate;
                assert_eq!(
                    v.verdict, reference.verdict,
                    "seed {seed} scale {c}: {v} vs {reference}"
                );
                checked += 1;
            }
        }
    }
    println!("{checked} scaled verdicts checked");
    assert!(checked > 200);
}

/// No single edge loosens the tolerance: adding one edge of any weight moves the median to at
/// most an adjacent order statistic, and with it the absolute part.
#[test]
fn one_edge_moves_the_tolerance_at_most_to_an_adjacent_weight() {
    let mut rng = StdRng::seed_from_u64(5);
    let (p, _) = SyntheticGraph {
        num_rotations: 20,
        num_edges: 60,
        ..Default::default()
    }
    .generate();
    let edges: Vec<Edge> = p
        .edges()
        .iter()
        .map(|e| Edge {
            weight: 10f64.powf(rng.random_range(-3.0..3.0)),
            ..e.clone()
        })
        .collect();
    let mut sorted: Vec<f64> = edges.iter().map(|e| e.weight).collect();
    sorted.sort_by(f64::total_cmp);
    let p = MultipleProblem::new(20, edges.clone()).unwrap();
    let m = p.median_weight();
    for extra in [1e-100, 1e-3, 1.0, 1e13, 1e100] {
        let mut e2 = edges.clone();
        e2.push(Edge {
            i: 0,
            j: 1,
            rotation: Rotation::identity(),
            weight: extra,
        });
        let m2 = MultipleProblem::new(20, e2).unwrap().median_weight();
        let k = sorted.iter().position(|w| *w == m).unwrap();
        let neighbours = [
            sorted[k.saturating_sub(1)],
            m,
            sorted[(k + 1).min(sorted.len() - 1)],
        ];
        assert!(
            neighbours.contains(&m2),
            "extra {extra}: median {m} -> {m2}"
        );
    }
}

/// The same rule for single and conjugate averaging (median sample / pair weight): scaling the
/// weights by 1e-12 or 1e12 keeps every verdict.
#[test]
fn single_and_conjugate_verdicts_are_scale_free() {
    let settings = CertifySettings::default();
    let mut rng = StdRng::seed_from_u64(8);
    for _ in 0..10 {
        let truth = random_rotation(&mut rng);
        let samples: Vec<Rotation> = (0..40)
            .map(|_| perturb_gaussian(&truth, 0.1, &mut rng))
            .collect();
        let weights: Vec<f64> = (0..40)
            .map(|_| 10f64.powf(rng.random_range(-2.0..2.0)))
            .collect();
        let base = SingleProblem::new(samples.clone(), Some(weights.clone())).unwrap();
        for estimate in [truth, perturb_gaussian(&truth, 1e-3, &mut rng)] {
            let reference = certify_single(&base, &estimate, &settings)
                .unwrap()
                .certificate;
            for c in [1e-12, 1e12] {
                let p = SingleProblem::new(
                    samples.clone(),
                    Some(weights.iter().map(|w| w * c).collect()),
                )
                .unwrap();
                let v = certify_single(&p, &estimate, &settings)
                    .unwrap()
                    .certificate;
                assert_eq!(v.verdict, reference.verdict, "single x {c}: {v}");
            }
        }
        let (conj, s) = random_instance(15, 0.02, 0.0, &mut rng);
        for estimate in [s, perturb_gaussian(&s, 1e-2, &mut rng)] {
            let reference = certify_conjugate(&conj, &estimate, &settings)
                .unwrap()
                .certificate;
            for c in [1e-12, 1e12] {
                let pairs: Vec<ConjugatePair> = conj
                    .pairs()
                    .iter()
                    .map(|p| ConjugatePair {
                        weight: p.weight * c,
                        ..p.clone()
                    })
                    .collect();
                let p = ConjugateProblem::new(pairs).unwrap();
                let v = certify_conjugate(&p, &estimate, &settings)
                    .unwrap()
                    .certificate;
                assert_eq!(v.verdict, reference.verdict, "conjugate x {c}: {v}");
            }
        }
    }
}
