//! The simultaneous problem: joint Gauss-Newton vs averaging each graph then conjugating, and
//! its SDP certificate `[H12]` (bounds checked against planted points, many-start minima and
//! arbitrary multipliers; budgets refused before Clarabel starts).

use nalgebra::Matrix3;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rotavg::certify::simultaneous::{certify_simultaneous, verify_simultaneous_bound};
use rotavg::certify::{Budget, CertifySettings, Outcome, Refusal, Verdict};
use rotavg::multiple::Edge;
use rotavg::pipeline::average_multiple;
use rotavg::pipeline::simultaneous::{
    SimultaneousProblem, average_simultaneous, average_then_conjugate, solve_simultaneous,
};
use rotavg::so3::{Rotation, angle_between, perturb_gaussian, random_rotation};

/// `n` nodes, chain plus `extra` random edges in each graph, noise `sigma` rad on every edge.
fn instance(
    n: usize,
    extra: usize,
    sigma: f64,
    rng: &mut StdRng,
) -> (SimultaneousProblem, Rotation) {
    let (p, _, s) = planted(n, extra, sigma, rng);
    (p, s)
}

/// [`instance`] with its planted absolutes `R_i` (`R_0 = I`) and `S`.
fn planted(
    n: usize,
    extra: usize,
    sigma: f64,
    rng: &mut StdRng,
) -> (SimultaneousProblem, Vec<Rotation>, Rotation) {
    let mut rs = vec![Rotation::identity()];
    rs.extend((1..n).map(|_| random_rotation(rng)));
    let s = random_rotation(rng);
    let mut pairs: Vec<(usize, usize)> = (0..n - 1).map(|i| (i, i + 1)).collect();
    while pairs.len() < n - 1 + extra {
        let (i, j) = (rng.random_range(0..n), rng.random_range(0..n));
        if i != j {
            pairs.push((i, j));
        }
    }
    let mut right = Vec::new();
    let mut left = Vec::new();
    for &(i, j) in &pairs {
        let rij = rs[j] * rs[i].inverse();
        right.push(Edge {
            i,
            j,
            rotation: perturb_gaussian(&rij, sigma, rng),
            weight: 1.0,
        });
        left.push(Edge {
            i,
            j,
            rotation: perturb_gaussian(&(s * rij * s.inverse()), sigma, rng),
            weight: 1.0,
        });
    }
    (
        SimultaneousProblem {
            num_nodes: n,
            right,
            left,
        },
        rs,
        s,
    )
}

#[test]
fn noise_free_joint_recovery() {
    let mut rng = StdRng::seed_from_u64(61);
    let (p, s) = instance(8, 6, 0.0, &mut rng);
    let sol = solve_simultaneous(&p, 100).unwrap();
    assert!(sol.cost < 1e-18);
    assert!(angle_between(&sol.s, &s) < 1e-8);
}

#[test]
fn joint_beats_average_then_conjugate() {
    // The joint estimate is initialised at the baseline, so its joint cost is never higher; on
    // average its error in S is lower (it uses both graphs' residuals for every unknown).
    let mut rng = StdRng::seed_from_u64(62);
    let (mut eb, mut ej) = (0.0, 0.0);
    let trials = 30;
    for _ in 0..trials {
        let (p, s) = instance(12, 10, 0.05, &mut rng);
        let b = average_then_conjugate(&p).unwrap();
        let j = solve_simultaneous(&p, 100).unwrap();
        assert!(j.cost <= b.cost + 1e-12);
        eb += angle_between(&b.s, &s);
        ej += angle_between(&j.s, &s);
    }
    println!(
        "mean error of S over {trials} instances: average-then-conjugate {:.4} deg, joint {:.4} deg",
        eb.to_degrees() / trials as f64,
        ej.to_degrees() / trials as f64
    );
    assert!(ej < eb);
}

/// The joint cost at the planted point of an instance, computed here from the definition.
fn planted_cost(p: &SimultaneousProblem, rs: &[Rotation], s: &Rotation) -> f64 {
    let mut c = 0.0;
    for e in &p.right {
        c += e.weight * (rs[e.j].matrix() - e.rotation.matrix() * rs[e.i].matrix()).norm_squared();
    }
    for e in &p.left {
        let (sj, si) = (s * rs[e.j], s * rs[e.i]);
        c += e.weight * (sj.matrix() - e.rotation.matrix() * si.matrix()).norm_squared();
    }
    c
}

/// The lowest joint cost of `starts` local solves from random points (the joint Gauss-Newton
/// polishing a random start): an upper bound on the global minimum independent of the SDP.
fn many_start_minimum(p: &SimultaneousProblem, starts: usize, rng: &mut StdRng) -> f64 {
    let mut best = solve_simultaneous(p, 100).unwrap().cost;
    for _ in 0..starts {
        let mut rs = vec![Rotation::identity()];
        rs.extend((1..p.num_nodes).map(|_| random_rotation(rng)));
        best = best.min(planted_cost(p, &rs, &random_rotation(rng)));
    }
    best
}

/// The relaxation `[H12]` decouples: `X = blkdiag(X_R, X_L)` (coupling blocks zero) satisfies
/// every coupling constraint, so its value is the sum of the two graphs' own relaxations. On
/// rigs at 0.05 rad the verified bound equals the sum of the two graphs' certified optima
/// (computed here by the multiple-averaging pipeline, independently of this SDP), stays below
/// the planted point's cost and the best of many starts, and the gap is reported; noise-free
/// rigs are certified.
#[test]
fn sdp_bound_is_the_sum_of_the_two_graphs_optima() {
    let mut rng = StdRng::seed_from_u64(63);
    for t in 0..6 {
        let (p, rs, s) = planted(10, 8, 0.05, &mut rng);
        let avg = average_simultaneous(&p, &Default::default()).unwrap();
        let c = avg.certificate.clone().unwrap();
        let lb = c.lower_bound.unwrap();
        let best = many_start_minimum(&p, 20, &mut rng);
        assert!(
            lb <= best * (1.0 + 1e-12),
            "trial {t}: bound {lb} above a known cost {best}"
        );
        assert!(lb <= planted_cost(&p, &rs, &s) + 1e-12);
        let (right, left) = p.graphs().unwrap();
        let separate: f64 = [right, left]
            .iter()
            .map(|g| {
                let a = average_multiple(g, &Default::default()).unwrap();
                assert!(a.certificate.unwrap().is_certified());
                a.solution.cost
            })
            .sum();
        println!("trial {t}: separate optima {separate:.9e}; {c}");
        assert!(
            (lb - separate).abs() <= 1e-6 * separate,
            "{lb} vs {separate}"
        );
        assert_eq!(c.verdict, Verdict::GapReported);
    }
    let (p, _, _) = planted(10, 8, 0.0, &mut rng);
    let avg = average_simultaneous(&p, &Default::default()).unwrap();
    assert!(avg.certificate.unwrap().is_certified());
}

/// Any multipliers give a valid bound: random `Lambda`, `Gamma` never bound above the cost of
/// a known point.
#[test]
fn arbitrary_multipliers_never_bound_above_a_known_cost() {
    let mut rng = StdRng::seed_from_u64(64);
    let (p, _) = instance(6, 5, 0.1, &mut rng);
    let (right, left) = p.graphs().unwrap();
    let sol = solve_simultaneous(&p, 100).unwrap();
    for _ in 0..50 {
        let scale = rng.random_range(0.0..3.0);
        let mut m = || Matrix3::from_fn(|_, _| scale * rng.random_range(-1.0..1.0));
        let lambdas: Vec<Matrix3<f64>> = (0..12).map(|_| m()).collect();
        let gammas: Vec<Matrix3<f64>> = (0..5).map(|_| m()).collect();
        let b = verify_simultaneous_bound(&right, &left, &lambdas, &gammas).unwrap();
        assert!(
            b.lower_bound <= sol.cost,
            "{} > {}",
            b.lower_bound,
            sol.cost
        );
    }
    assert!(verify_simultaneous_bound(&right, &left, &[Matrix3::zeros(); 11], &[]).is_none());
}

/// Heavy noise and outlier edges: whatever the verdict, the bound stays below the best known
/// cost; the SDP's rounding, when cheaper, is returned.
#[test]
fn hard_rigs_report_a_sound_gap() {
    let mut rng = StdRng::seed_from_u64(65);
    for t in 0..4 {
        let (mut p, _) = instance(8, 8, 0.3, &mut rng);
        for e in p.left.iter_mut().step_by(4) {
            e.rotation = random_rotation(&mut rng);
        }
        let avg = average_simultaneous(&p, &Default::default()).unwrap();
        let c = avg.certificate.clone().unwrap();
        let best = many_start_minimum(&p, 30, &mut rng).min(avg.solution.cost);
        println!("trial {t}: {c}");
        assert!(c.lower_bound.unwrap() <= best * (1.0 + 1e-12));
        assert_ne!(c.verdict, Verdict::Inconclusive);
    }
}

/// Over the memory budget the SDP is refused before Clarabel starts: `inconclusive`, and the
/// ladder names the refusal.
#[test]
fn over_budget_the_sdp_is_refused() {
    let mut rng = StdRng::seed_from_u64(66);
    let (p, _) = instance(10, 8, 0.05, &mut rng);
    let (right, left) = p.graphs().unwrap();
    let sol = solve_simultaneous(&p, 100).unwrap();
    let settings = CertifySettings {
        budget: Budget {
            max_memory_bytes: 1 << 10,
            max_seconds: None,
        },
        ..Default::default()
    };
    let c = certify_simultaneous(&right, &left, &sol.rotations, &sol.s, &settings).unwrap();
    assert_eq!(c.certificate.verdict, Verdict::Inconclusive);
    assert!(matches!(
        c.details.ladder[0].outcome,
        Outcome::Refused(Refusal::OverBudget { .. })
    ));
}
