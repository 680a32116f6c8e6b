//! Branch and bound over SO(3) (`paper-notes/branch_and_bound.md`, `[B1]`-`[B6]`): the proven
//! lower bound never exceeds an independent brute-force minimum (dense random sampling plus
//! derivative-free local refinement from many starts), non-optimal estimates are never
//! certified, and better points found by the search are adopted by the pipelines.

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rotavg::certify::{
    BranchAndBoundStop, CertifyMode, CertifySettings, certify_conjugate, certify_single,
};
use rotavg::conjugate::{
    ConjugateProblem, ConjugateSettings, solve_conjugate, synthetic::random_instance,
};
use rotavg::objective::{Loss, Objective};
use rotavg::pipeline::{AverageSettings, average_conjugate, average_single};
use rotavg::single::{SingleProblem, SingleSettings, solve_single};
use rotavg::so3::{
    self, Metric, exp, perturb, perturb_gaussian, random_rotation, random_unit_vector,
};
use rotavg::{BoundMethod, Rotation, Verdict};
use std::f64::consts::PI;
use std::time::Instant;

fn objectives() -> Vec<Objective> {
    let mut v = Vec::new();
    for m in [Metric::Geodesic, Metric::Chordal, Metric::Quaternion] {
        for l in [
            Loss::L1,
            Loss::L2,
            Loss::Huber {
                threshold_deg: 20.0,
            },
            Loss::Cauchy { scale_deg: 30.0 },
        ] {
            v.push(Objective::new(m, l));
        }
    }
    v
}

/// Independent reference: the minimum over `samples` random rotations, then a derivative-free
/// pattern search from the 5 best.
fn brute_force(f: &dyn Fn(&Rotation) -> f64, samples: usize, rng: &mut StdRng) -> f64 {
    let mut pts: Vec<(f64, Rotation)> = (0..samples)
        .map(|_| {
            let r = random_rotation(rng);
            (f(&r), r)
        })
        .collect();
    pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut best = f64::INFINITY;
    for (mut fx, mut x) in pts.into_iter().take(5) {
        let mut step = 0.2;
        while step > 1e-9 {
            let mut moved = false;
            for k in 0..12 {
                let d = if k < 6 {
                    let mut v = nalgebra::Vector3::zeros();
                    v[k % 3] = if k < 3 { 1.0 } else { -1.0 };
                    v
                } else {
                    random_unit_vector(rng)
                };
                let y = x * exp(&(d * step));
                let fy = f(&y);
                if fy < fx {
                    (fx, x, moved) = (fy, y, true);
                }
            }
            if !moved {
                step *= 0.5;
            }
        }
        best = best.min(fx);
    }
    best
}

fn bnb() -> CertifySettings {
    CertifySettings::with_mode(CertifyMode::BranchAndBound)
}

/// Small spread sets, every metric and loss: bound <= brute force; a certified estimate is
/// within the tolerance of the brute-force minimum.
#[test]
fn single_bounds_never_exceed_brute_force() {
    let mut rng = StdRng::seed_from_u64(11);
    for o in objectives() {
        for trial in 0..2 {
            let n = 5 + 3 * trial;
            let rs: Vec<_> = (0..n).map(|_| random_rotation(&mut rng)).collect();
            let w: Vec<f64> = (0..n).map(|_| 0.5 + rng.random::<f64>()).collect();
            let Ok(p) = SingleProblem::new(rs, Some(w)).unwrap().with_objective(o) else {
                continue; // no solver for the objective (robust single losses)
            };
            let fb = brute_force(&|x| p.cost(x), 4000, &mut rng);
            let est = random_rotation(&mut rng);
            let c = certify_single(&p, &est, &bnb()).unwrap();
            let lb = c.certificate.lower_bound.unwrap();
            assert!(
                lb <= fb + 1e-12 * (1.0 + fb),
                "{o}: bound {lb} > brute force {fb}"
            );
            assert_eq!(c.certificate.method, BoundMethod::BranchAndBound);
            let stats = c.certificate.branch_and_bound.unwrap();
            assert_eq!(stats.stop, BranchAndBoundStop::Converged, "{o}: {stats}");
            if c.certificate.is_certified() {
                assert!(p.cost(&est) <= fb + 1e-6 * fb + 1e-9, "{o}");
            } else {
                // the random estimate is not optimal: the search found a better point
                let better = c.improvement.unwrap();
                assert!(
                    better.cost <= fb + 2e-6 * fb + 1e-9,
                    "{o}: {} vs {fb}",
                    better.cost
                );
            }
        }
    }
}

/// Adversarial sets for the geodesic means: antipodal clusters, samples at exactly pi apart,
/// uniform samples, outliers. Pipeline (solve, theory, then branch and bound).
#[test]
fn adversarial_single_sets() {
    let mut rng = StdRng::seed_from_u64(3);
    let c0 = random_rotation(&mut rng);
    let flip = exp(&nalgebra::Vector3::new(PI, 0.0, 0.0));
    let sets: Vec<Vec<Rotation>> = vec![
        // two antipodal clusters (4 vs 3 samples)
        (0..7)
            .map(|k| perturb(&if k < 4 { c0 } else { c0 * flip }, 0.05, &mut rng))
            .collect(),
        // exactly pi apart
        vec![c0, c0 * flip],
        // uniform
        (0..9).map(|_| random_rotation(&mut rng)).collect(),
        // a cluster with 30 % outliers
        (0..10)
            .map(|k| {
                if k < 7 {
                    perturb_gaussian(&c0, 0.05, &mut rng)
                } else {
                    random_rotation(&mut rng)
                }
            })
            .collect(),
    ];
    for (k, rs) in sets.into_iter().enumerate() {
        for loss in [Loss::L1, Loss::L2] {
            let p = SingleProblem::new(rs.clone(), None)
                .unwrap()
                .with_objective(Objective::new(Metric::Geodesic, loss))
                .unwrap();
            let fb = brute_force(&|x| p.cost(x), 4000, &mut rng);
            let est = average_single(&p, &AverageSettings::default()).unwrap();
            let cert = est.certificate.unwrap();
            let lb = cert.lower_bound.unwrap();
            assert!(lb <= fb + 1e-12 * (1.0 + fb), "set {k} {loss}: {lb} > {fb}");
            assert!(est.solution.cost <= fb + 1e-6 * fb + 1e-9, "set {k} {loss}");
            assert!(cert.is_certified(), "set {k} {loss}: {cert}");
        }
    }
}

/// A local minimum of a bimodal set is never certified; the search finds the global one and
/// the pipeline adopts it. Two clusters (weights 5 and 4) 2.6 rad apart on one great circle:
/// the geodesic L2 cost has a second, worse local minimum on the long arc between them.
#[test]
fn local_minimum_of_a_bimodal_set_is_not_certified() {
    let mut rng = StdRng::seed_from_u64(17);
    let a = random_rotation(&mut rng);
    let e = random_unit_vector(&mut rng);
    let b = a * exp(&(e * 2.6));
    let rs: Vec<_> = (0..9)
        .map(|k| perturb_gaussian(if k < 5 { &a } else { &b }, 0.02, &mut rng))
        .collect();
    let long_arc = a * exp(&(e * -(4.0 * (2.0 * PI - 2.6) / 9.0)));
    let p = SingleProblem::new(rs, None)
        .unwrap()
        .with_objective(Objective::new(Metric::Geodesic, Loss::L2))
        .unwrap();
    let from_long_arc = rotavg::single::SingleSettings {
        init: Some(long_arc),
        ..Default::default()
    };
    let local = rotavg::single::solve_single(&p, &from_long_arc).unwrap();
    let fb = brute_force(&|x| p.cost(x), 4000, &mut rng);
    assert!(
        local.cost > fb + 1.0,
        "not a worse local minimum: {} vs {fb}",
        local.cost
    );
    for mode in [CertifyMode::Auto, CertifyMode::BranchAndBound] {
        let c = certify_single(&p, &local.estimate, &CertifySettings::with_mode(mode)).unwrap();
        assert_ne!(
            c.certificate.verdict,
            Verdict::Certified,
            "{}",
            c.certificate
        );
        assert!(c.certificate.lower_bound.unwrap() <= fb + 1e-9);
        let better = c.improvement.expect("the search finds the global minimum");
        assert!(better.cost <= fb + 1e-6 * fb);
    }
    // The theorem alone cannot decide (samples beyond pi/2): inconclusive, never certified.
    let c = certify_single(
        &p,
        &local.estimate,
        &CertifySettings::with_mode(CertifyMode::Theory),
    )
    .unwrap();
    assert_ne!(c.certificate.verdict, Verdict::Certified);
    // The pipeline from the bad start adopts the better point, certified.
    let est = average_single(
        &p,
        &AverageSettings {
            solve: from_long_arc,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(est.certificate.unwrap().is_certified());
    assert_eq!(
        est.details.improved_by,
        Some(rotavg::certify::ImprovementSource::BranchAndBound)
    );
    assert!(est.solution.cost <= fb + 1e-6 * fb);
}

/// Conjugate averaging, every metric and loss with a solver: bound <= brute force.
#[test]
fn conjugate_bounds_never_exceed_brute_force() {
    let mut rng = StdRng::seed_from_u64(23);
    for o in objectives() {
        let (p, _) = random_instance(6, 0.1, 0.3, &mut rng);
        let Ok(p) = p.with_objective(o) else { continue };
        let fb = brute_force(&|x| p.cost(x), 4000, &mut rng);
        let est = random_rotation(&mut rng);
        let c = certify_conjugate(&p, &est, &bnb()).unwrap();
        let lb = c.certificate.lower_bound.unwrap();
        assert!(lb <= fb + 1e-12 * (1.0 + fb), "{o}: bound {lb} > {fb}");
        if c.certificate.is_certified() {
            assert!(p.cost(&est) <= fb + 1e-6 * fb + 1e-9, "{o}");
        }
        // The pipeline certifies its answer (SDP then branch and bound for chordal L2).
        let avg = average_conjugate(&p, &AverageSettings::default()).unwrap();
        let cert = avg.certificate.unwrap();
        assert!(cert.is_certified(), "{o}: {cert}");
        assert!(avg.solution.cost <= fb + 1e-6 * fb + 1e-9, "{o}");
    }
}

/// Sizes of the issue: 10^4 samples (10 % outliers) and 10^3 pairs (10 % outliers), geodesic
/// L1, certified by the branch and bound. Prints the times (the target is < 1 s each in
/// release on a 2-core machine; the assertion is generous for loaded machines).
#[test]
fn geodesic_l1_at_scale() {
    let mut rng = StdRng::seed_from_u64(1);
    let c0 = random_rotation(&mut rng);
    let rs: Vec<_> = (0..10_000)
        .map(|k| {
            if k % 10 == 0 {
                random_rotation(&mut rng)
            } else {
                perturb_gaussian(&c0, 0.1, &mut rng)
            }
        })
        .collect();
    let p = SingleProblem::new(rs, None)
        .unwrap()
        .with_objective(Objective::new(Metric::Geodesic, Loss::L1))
        .unwrap();
    let sol = rotavg::single::solve_single(&p, &Default::default()).unwrap();
    let t = Instant::now();
    let c = certify_single(&p, &sol.estimate, &bnb()).unwrap();
    let single_s = t.elapsed().as_secs_f64();
    println!(
        "single 10^4 geodesic L1: {single_s:.3} s, {}",
        c.certificate
    );
    assert!(c.certificate.is_certified(), "{}", c.certificate);

    let (p, _) = random_instance(1000, 0.02, 0.1, &mut rng);
    let p = p
        .with_objective(Objective::new(Metric::Geodesic, Loss::L1))
        .unwrap();
    let sol = rotavg::conjugate::solve_conjugate(&p, &Default::default()).unwrap();
    let t = Instant::now();
    let c = certify_conjugate(&p, &sol.estimate, &bnb()).unwrap();
    let conj_s = t.elapsed().as_secs_f64();
    println!(
        "conjugate 10^3 geodesic L1: {conj_s:.3} s, {}",
        c.certificate
    );
    assert!(c.certificate.is_certified(), "{}", c.certificate);
    assert!(single_s < 20.0 && conj_s < 20.0);
}

/// Malformed settings are refused before any work; modes are checked per problem.
#[test]
fn settings_and_modes() {
    let p = SingleProblem::new(vec![Rotation::identity(); 3], None).unwrap();
    let mut s = bnb();
    s.branch_and_bound.max_cells = 0;
    assert!(certify_single(&p, &Rotation::identity(), &s).is_err());
    let c = certify_single(&p, &Rotation::identity(), &bnb()).unwrap();
    assert!(c.certificate.is_certified());
    let json = serde_json::to_value(&c.certificate).unwrap();
    assert_eq!(json["method"], "branch_and_bound");
    assert_eq!(json["branch_and_bound"]["stop"], "converged");
    let q =
        ConjugateProblem::from_rotations(&[Rotation::identity()], &[Rotation::identity()]).unwrap();
    let _ = q;
}

/// The sixth mean `[S10]`: quaternion L1 by sign-aligned Weiszfeld, certified by the branch
/// and bound, equal to the brute-force minimum; a dominant sample is the exact minimiser.
#[test]
fn quaternion_l1_mean() {
    let mut rng = StdRng::seed_from_u64(29);
    let c0 = random_rotation(&mut rng);
    let rs: Vec<_> = (0..40)
        .map(|k| {
            if k % 8 == 0 {
                random_rotation(&mut rng)
            } else {
                perturb_gaussian(&c0, 0.1, &mut rng)
            }
        })
        .collect();
    let p = SingleProblem::new(rs, None)
        .unwrap()
        .with_objective(Objective::new(Metric::Quaternion, Loss::L1))
        .unwrap();
    let est = average_single(&p, &AverageSettings::default()).unwrap();
    let fb = brute_force(&|x| p.cost(x), 4000, &mut rng);
    let cert = est.certificate.unwrap();
    assert!(cert.is_certified(), "{cert}");
    assert_eq!(cert.method, BoundMethod::BranchAndBound);
    assert!(
        est.solution.cost <= fb + 1e-6 * fb,
        "{} {fb}",
        est.solution.cost
    );
    assert!(cert.lower_bound.unwrap() <= fb + 1e-12);
    // weight 5 at one sample against 4 spread ones: that sample is the minimiser
    let a = random_rotation(&mut rng);
    let mut rs = vec![a];
    rs.extend((0..4).map(|_| perturb(&a, 0.5, &mut rng)));
    let p = SingleProblem::new(rs, Some(vec![5.0, 1.0, 1.0, 1.0, 1.0]))
        .unwrap()
        .with_objective(Objective::new(Metric::Quaternion, Loss::L1))
        .unwrap();
    let est = average_single(&p, &AverageSettings::default()).unwrap();
    assert!(rotavg::so3::angle_between(&est.solution.estimate, &a) < 1e-9);
    assert!(est.certificate.unwrap().is_certified());
}

/// Soundness campaign for single and conjugate averaging (issue #14, item 5): seeded random
/// instances of every metric x loss (spread, clustered with outliers, two antipodal clusters),
/// certified in mode `auto` at the pipeline's answer and at perturbed copies of it. Every
/// proven lower bound is at most an independent brute-force minimum, and every certified
/// estimate costs at most that minimum plus the tolerance. Prints the counts.
#[test]
fn single_and_conjugate_soundness_campaign() {
    let mut rng = StdRng::seed_from_u64(2026);
    let auto = CertifySettings::default();
    let (mut certificates, mut certified, mut bounds) = (0usize, 0usize, 0usize);
    let mut check = |lb: Option<f64>, is_certified: bool, cost: f64, fb: f64, what: &str| {
        certificates += 1;
        if let Some(lb) = lb {
            bounds += 1;
            assert!(
                lb <= fb + 1e-12 * (1.0 + fb),
                "{what}: bound {lb} > brute force {fb}"
            );
        }
        if is_certified {
            certified += 1;
            assert!(
                cost <= fb + 1e-6 * fb.abs() + 1e-9,
                "{what}: certified {cost} > {fb}"
            );
        }
    };
    for seed in 0..32u64 {
        let n = 3 + (seed as usize % 8);
        let c = random_rotation(&mut rng);
        let samples: Vec<Rotation> = (0..n)
            .map(|k| match seed % 3 {
                0 => random_rotation(&mut rng),
                1 if k % 4 == 3 => random_rotation(&mut rng),
                1 => perturb_gaussian(&c, 0.2, &mut rng),
                _ => perturb_gaussian(
                    &(c * exp(&nalgebra::Vector3::new(
                        0.0,
                        0.0,
                        if k % 2 == 0 { 0.0 } else { 3.0 },
                    ))),
                    0.1,
                    &mut rng,
                ),
            })
            .collect();
        let w: Vec<f64> = (0..n).map(|_| 0.2 + rng.random::<f64>()).collect();
        for o in objectives() {
            let Ok(p) = SingleProblem::new(samples.clone(), Some(w.clone()))
                .unwrap()
                .with_objective(o)
            else {
                continue;
            };
            let fb = brute_force(&|x| p.cost(x), 1000, &mut rng);
            let Ok(avg) = average_single(&p, &AverageSettings::default()) else {
                continue;
            };
            let what = format!("single seed {seed} {o}");
            let cert = avg.certificate.unwrap();
            check(
                cert.lower_bound,
                cert.is_certified(),
                avg.solution.cost,
                fb,
                &what,
            );
            for sigma in [0.05, 0.5] {
                let est = perturb(&avg.solution.estimate, sigma, &mut rng);
                let c = certify_single(&p, &est, &auto).unwrap().certificate;
                check(c.lower_bound, c.is_certified(), p.cost(&est), fb, &what);
            }
        }
        let (q, _) = random_instance(4 + (seed as usize % 5), 0.1, 0.3, &mut rng);
        for o in objectives() {
            let Ok(p) = q.clone().with_objective(o) else {
                continue;
            };
            let fb = brute_force(&|x| p.cost(x), 1000, &mut rng);
            let Ok(avg) = average_conjugate(&p, &AverageSettings::default()) else {
                continue;
            };
            let what = format!("conjugate seed {seed} {o}");
            let cert = avg.certificate.unwrap();
            check(
                cert.lower_bound,
                cert.is_certified(),
                avg.solution.cost,
                fb,
                &what,
            );
            let est = perturb(&avg.solution.estimate, 0.3, &mut rng);
            let c = certify_conjugate(&p, &est, &auto).unwrap().certificate;
            check(c.lower_bound, c.is_certified(), p.cost(&est), fb, &what);
        }
    }
    println!(
        "campaign: {certificates} certificates, {bounds} lower bounds, {certified} certified, none false"
    );
    assert!(certificates >= 1000, "{certificates}");
}

/// `[B6]` with samples that are rotations only to the validation tolerance (issue 24: the data
/// as given): every metric, including the quaternion distance (a function of the same angle),
/// gets a proven bound of the cost of the matrices as given, at most an independent
/// brute-force minimum of that cost. Chordal L2 (its closed form `[S1]` holds for any matrices)
/// is certified; the angle-based costs carry the data margin of `[B6]` (first order in the
/// samples' defects, here ~1e-5), so their proven gap is at most about that margin.
#[test]
fn inexact_rotations_are_bounded_as_given() {
    let mut rng = StdRng::seed_from_u64(77);
    let c = random_rotation(&mut rng);
    let inexact: Vec<Rotation> = (0..6)
        .map(|_| {
            let mut m = *perturb(&c, 0.2, &mut rng).matrix();
            m[(0, 1)] += 1e-7;
            m *= 1.0 - 2.8e-6;
            Rotation::from_matrix_unchecked(m)
        })
        .collect();
    // the objectives with a single-averaging solver
    for o in objectives()
        .into_iter()
        .filter(|o| matches!(o.loss, Loss::L1 | Loss::L2))
    {
        let p = SingleProblem::new(inexact.clone(), None)
            .unwrap()
            .with_objective(o)
            .unwrap();
        // the cost of the matrices as given, evaluated here from its definition
        let given = |x: &Rotation| -> f64 {
            inexact
                .iter()
                .map(|a| {
                    let t = so3::angle(&Rotation::from_matrix_unchecked(
                        a.matrix().transpose() * x.matrix(),
                    ));
                    o.rho(match o.metric {
                        Metric::Chordal => (a.matrix() - x.matrix()).norm(),
                        m => m.from_angle(t),
                    })
                })
                .sum()
        };
        let brute = brute_force(&given, 4000, &mut rng);
        let solved = solve_single(&p, &SingleSettings::default()).unwrap();
        assert!((p.cost(&solved.estimate) - given(&solved.estimate)).abs() < 1e-12 * (1.0 + brute));
        let cert = certify_single(&p, &solved.estimate, &CertifySettings::default())
            .unwrap()
            .certificate;
        let lb = cert.lower_bound.expect("a bound");
        assert!(
            lb <= brute + 1e-12 * (1.0 + brute),
            "{o}: bound {lb} above {brute}: {cert}"
        );
        if o == Objective::new(Metric::Chordal, Loss::L2) {
            assert!(cert.is_certified(), "{o}: {cert}");
        } else {
            assert!(cert.gap.unwrap() <= 1e-2 * (1.0 + brute), "{o}: {cert}");
        }
    }
}

/// Issue 24, item 6: conjugate quaternion L2 with 20 % outlier pairs. The quaternion closed form
/// fixes the sign of each pair's quaternions, which with outliers is not the quaternion
/// distance's minimum; the pipeline returns the best point it finds (the local solver on the
/// true cost from the closed form, a better point from the branch and bound), so its answer is
/// the brute-force minimum to the tolerance and certified, and a start at that minimum is kept.
#[test]
fn conjugate_quaternion_l2_with_outliers_returns_the_global_minimiser() {
    let o = Objective::new(Metric::Quaternion, Loss::L2);
    let mut rng = StdRng::seed_from_u64(246);
    for case in 0..6 {
        let (p, _) = random_instance(20, 0.05, 0.2, &mut rng);
        let p = p.with_objective(o).unwrap();
        let brute = brute_force(&|s: &Rotation| p.cost(s), 3000, &mut rng);
        let avg = average_conjugate(&p, &AverageSettings::default()).unwrap();
        let c = avg.certificate.clone().unwrap();
        let f = avg.solution.cost;
        assert!(
            f <= brute + 1e-6 * brute,
            "case {case}: {f} above the brute force {brute}: {c}"
        );
        assert!(c.is_certified(), "case {case}: {c}");
        let start = ConjugateSettings {
            init: Some(avg.solution.estimate),
            ..Default::default()
        };
        let again = solve_conjugate(&p, &start).unwrap();
        assert!(
            again.cost <= f * (1.0 + 1e-12),
            "case {case}: {} from {f}",
            again.cost
        );
    }
}
