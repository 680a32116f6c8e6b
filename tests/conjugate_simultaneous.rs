//! The simultaneous problem: joint Gauss-Newton vs averaging each graph then conjugating.

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rotavg::multiple::Edge;
use rotavg::pipeline::simultaneous::{
    SimultaneousProblem, average_then_conjugate, solve_simultaneous,
};
use rotavg::so3::{Rotation, angle_between, perturb_gaussian, random_rotation};

/// `n` nodes, chain plus `extra` random edges in each graph, noise `sigma` rad on every edge.
fn instance(
    n: usize,
    extra: usize,
    sigma: f64,
    rng: &mut StdRng,
) -> (SimultaneousProblem, Rotation) {
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
