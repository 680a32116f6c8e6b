//! Property tests of single rotation averaging (`rotavg::single`, `paper-notes/single.md`),
//! extending `tests/suite/single.rs` (which has brute-force optima, planted symmetric data,
//! fixed-instance left/right invariance for all five means and a proptest of bi-invariance for
//! chordal and geodesic L2 only).
//!
//! Independent sources: exact symmetries of the cost `F(R) = sum_i w_i d(R_i, R)^p`, which only
//! depends on the angles `theta(R_i, R)` ([C2]); and the definition of a global minimum (its
//! cost is at most the cost at any other point, and a proven lower bound is at most the cost at
//! every point).

use proptest::prelude::*;
use proptest::test_runner::RngSeed;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rotavg::objective::{Loss, Objective};
use rotavg::pipeline::{AverageSettings, average_single};
use rotavg::single::SingleProblem;
use rotavg::so3::{Metric, angle_between, perturb_gaussian, random_rotation};
use rotavg::{Certificate, Rotation};

/// Deterministic proptest configuration: a fixed RNG seed (so a failure reproduces and the suite
/// is not flaky) unless `PROPTEST_RNG_SEED` is set to explore other cases; no regression files.
fn config(cases: u32) -> ProptestConfig {
    let mut c = ProptestConfig::with_cases(cases);
    if std::env::var_os("PROPTEST_RNG_SEED").is_none() {
        c.rng_seed = RngSeed::Fixed(0x726f_7461_7667);
    }
    c.failure_persistence = None;
    c
}

const ALL: [(Metric, Loss); 5] = [
    (Metric::Chordal, Loss::L2),
    (Metric::Quaternion, Loss::L2),
    (Metric::Geodesic, Loss::L2),
    (Metric::Geodesic, Loss::L1),
    (Metric::Chordal, Loss::L1),
];

/// `n` samples `C exp(w_k)`, `w_k` Gaussian with `sigma` rad per axis, weights in `[0.2, 5]`.
fn concentrated(seed: u64, n: usize, sigma: f64) -> SingleProblem {
    let mut rng = StdRng::seed_from_u64(seed);
    let c = random_rotation(&mut rng);
    let rs = (0..n)
        .map(|_| perturb_gaussian(&c, sigma, &mut rng))
        .collect();
    let ws = (0..n).map(|_| 0.2 + 4.8 * rng.random::<f64>()).collect();
    SingleProblem::new(rs, Some(ws)).unwrap()
}

/// A mean, its cost and its certificate (the pipeline's result).
struct Mean {
    estimate: Rotation,
    cost: f64,
    certificate: Certificate,
}

fn solve(p: &SingleProblem, metric: Metric, norm: Loss) -> Mean {
    let p = p
        .clone()
        .with_objective(Objective::new(metric, norm))
        .unwrap();
    let est = average_single(&p, &AverageSettings::default()).unwrap();
    Mean {
        estimate: est.solution.estimate,
        cost: est.solution.cost,
        certificate: est.certificate.unwrap(),
    }
}

/// Agreement of two means: the L1 methods stop on a step / subgradient tolerance, the L2 ones
/// are accurate to ~1e-12; 1e-6 rad is far below any difference a wrong transformation makes
/// (the transformations below move the mean by O(1) rad).
const ANGLE_TOL: f64 = 1e-6;

fn cost_close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * (1.0 + a.abs())
}

proptest! {
    #![proptest_config(config(48))]

    /// Bi-equivariance of every mean: each distance is a function of `theta(R_i, R)` only, and
    /// `theta(A R_i B, A R B) = theta(R_i, R)` ([C2]: all three metrics are bi-invariant). So
    /// `F'(A R B) = F(R)` for the moved data `A R_i B`, the minimisers map as `R* -> A R* B`, and
    /// the minimum value is unchanged. Left-only (`B = I`) and right-only (`A = I`) are special
    /// cases and are checked too. Concentrated data (sigma <= 0.3) make the minimiser unique.
    #[test]
    fn every_mean_is_bi_equivariant(
        seed in any::<u64>(), n in 1usize..12, sigma in 0.0f64..0.3, which in 0usize..3
    ) {
        let p = concentrated(seed, n, sigma);
        let mut rng = StdRng::seed_from_u64(seed ^ 0x5eed);
        let a = if which == 2 { Rotation::identity() } else { random_rotation(&mut rng) };
        let b = if which == 1 { Rotation::identity() } else { random_rotation(&mut rng) };
        let moved = SingleProblem::new(
            p.rotations().iter().map(|r| a * r * b).collect(),
            Some(p.weights().to_vec()),
        ).unwrap();
        for (metric, norm) in ALL {
            let s = solve(&p, metric, norm);
            let t = solve(&moved, metric, norm);
            prop_assert!(cost_close(s.cost, t.cost), "{metric} {norm}: {} vs {}", s.cost, t.cost);
            let d = angle_between(&t.estimate, &(a * s.estimate * b));
            prop_assert!(d < ANGLE_TOL, "{metric} {norm}: {d}");
            // The verdicts must agree too, except for chordal L1: its bound [S7] comes from a
            // Euclidean Weiszfeld iterate that stops when the cost stalls at rounding level, with
            // a subgradient norm ~1e-9 W that differs between the two runs, and its relative gap
            // on near-noise-free data is ~1e-6, i.e. at the verdict tolerance (observed: one run
            // certified, the other gap_reported). Both bounds must remain below the (equal) costs.
            if (metric, norm) != (Metric::Chordal, Loss::L1) {
                prop_assert_eq!(s.certificate.verdict, t.certificate.verdict, "{} {}", metric, norm);
            }
            for x in [&s, &t] {
                if let Some(lb) = x.certificate.lower_bound {
                    prop_assert!(lb <= s.cost.min(t.cost) + 1e-9 * (1.0 + s.cost), "{metric} {norm}");
                }
            }
        }
    }

    /// Permutation invariance: `F` is a sum over the samples, so reordering the (sample, weight)
    /// pairs does not change `F` at any point, hence neither the minimiser nor the minimum.
    #[test]
    fn every_mean_is_permutation_invariant(
        seed in any::<u64>(), n in 2usize..12, sigma in 0.0f64..0.3
    ) {
        let p = concentrated(seed, n, sigma);
        let mut rng = StdRng::seed_from_u64(seed ^ 0xbeef);
        let mut perm: Vec<usize> = (0..n).collect();
        for k in (1..n).rev() {
            perm.swap(k, rng.random_range(0..=k));
        }
        let q = SingleProblem::new(
            perm.iter().map(|&k| p.rotations()[k]).collect(),
            Some(perm.iter().map(|&k| p.weights()[k]).collect()),
        ).unwrap();
        for (metric, norm) in ALL {
            let s = solve(&p, metric, norm);
            let t = solve(&q, metric, norm);
            prop_assert!(cost_close(s.cost, t.cost), "{metric} {norm}");
            prop_assert!(angle_between(&s.estimate, &t.estimate) < ANGLE_TOL, "{metric} {norm}");
        }
    }

    /// Weight scaling: `F_{c w} = c F_w` pointwise, so the minimiser is unchanged and the
    /// minimum and any valid lower bound scale by `c`. (The verdict is not compared.)
    #[test]
    fn every_mean_is_invariant_to_weight_scaling(
        seed in any::<u64>(), n in 1usize..12, sigma in 0.0f64..0.3, log_c in -3.0f64..3.0
    ) {
        let c = 10f64.powf(log_c);
        let p = concentrated(seed, n, sigma);
        let q = SingleProblem::new(
            p.rotations().to_vec(),
            Some(p.weights().iter().map(|w| w * c).collect()),
        ).unwrap();
        for (metric, norm) in ALL {
            let s = solve(&p, metric, norm);
            let t = solve(&q, metric, norm);
            // a zero cost is only zero up to rounding: the angle of a computed `R_i^T R` is ~eps,
            // an L1 cost therefore ~eps x (total weight)
            let rounding = 1e-12 * c * p.total_weight();
            prop_assert!((t.cost - c * s.cost).abs() <= 1e-9 * c * s.cost + rounding, "{metric} {norm}: {} vs {}", t.cost, c * s.cost);
            prop_assert!(angle_between(&s.estimate, &t.estimate) < ANGLE_TOL, "{metric} {norm}");
            // (chordal L1: the bound depends on where the Euclidean Weiszfeld iteration stalls,
            // see `every_mean_is_bi_equivariant`; only its validity is checked, elsewhere)
            if let (Some(a), Some(b), false) = (
                s.certificate.lower_bound,
                t.certificate.lower_bound,
                (metric, norm) == (Metric::Chordal, Loss::L1),
            ) {
                // bounds are costs minus a proven gap and minus floating-point safety margins
                // [S8] of order eps x (total weight), which also scale with c: allow the relative
                // verdict tolerance on the cost plus 1e-12 per unit of total weight
                let slack = 1e-6 * c * s.cost + 1e-12 * c * p.total_weight();
                prop_assert!((b - c * a).abs() <= slack, "{metric} {norm}: {b} vs {}", c * a);
            }
        }
    }

    /// The mean of `n` copies of `R` (any positive weights) is `R` with cost 0: `F >= 0` with
    /// equality iff every `d(R_i, R) = 0`, i.e. only at `R`.
    #[test]
    fn mean_of_identical_rotations_is_that_rotation(
        seed in any::<u64>(), n in 1usize..10, ws in prop::collection::vec(0.01f64..100.0, 10)
    ) {
        let r = random_rotation(&mut StdRng::seed_from_u64(seed));
        let p = SingleProblem::new(vec![r; n], Some(ws[..n].to_vec())).unwrap();
        for (metric, norm) in ALL {
            let s = solve(&p, metric, norm);
            prop_assert!(angle_between(&s.estimate, &r) < 1e-9, "{metric} {norm}");
            prop_assert!(s.cost.abs() < 1e-12, "{metric} {norm}: {}", s.cost);
            prop_assert!(s.certificate.is_certified(), "{metric} {norm}");
        }
    }

    /// The returned mean is (for concentrated data) the global minimiser, so its cost is at most
    /// the cost at each sample `R_k` (each sample is a feasible point). Independently of
    /// optimality, a *proven* lower bound on the minimum is at most the cost at every sample and
    /// at the returned estimate; on spread data (sigma up to 1.5 rad, where the geodesic
    /// certificates may be inconclusive) only the bound property is asserted, plus the cost
    /// property for certified results.
    #[test]
    fn mean_cost_is_below_cost_at_every_sample(
        seed in any::<u64>(), n in 1usize..12, sigma in 0.0f64..1.5
    ) {
        let p = concentrated(seed, n, sigma);
        for (metric, norm) in ALL {
            let s = solve(&p, metric, norm);
            let at_samples: Vec<f64> = p.rotations().iter().map(|r| p.cost_under(r, Objective::new(metric, norm))).collect();
            let min_sample = at_samples.iter().copied().fold(f64::INFINITY, f64::min);
            let slack = 1e-9 * (1.0 + min_sample);
            if sigma <= 0.3 || s.certificate.is_certified() {
                prop_assert!(s.cost <= min_sample + slack, "{metric} {norm}: {} > {min_sample}", s.cost);
            }
            if let Some(lb) = s.certificate.lower_bound {
                prop_assert!(lb <= min_sample + slack, "{metric} {norm}: lb {lb} > {min_sample}");
                prop_assert!(lb <= s.cost + slack, "{metric} {norm}");
            }
        }
    }
}
