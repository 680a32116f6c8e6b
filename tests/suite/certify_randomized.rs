//! The randomized Chebyshev test `[D16]` at the certificate level: when no deterministic proof
//! fits the budget, a Monte Carlo lower bound is reported beside the `inconclusive` verdict,
//! never as its proof. Checked against the deterministic certificate of the same estimate
//! (computed with the default budget), for weight scaling, and at an estimate that is not
//! optimal.

use rotavg::certify::multiple::dual_certificate;
use rotavg::certify::{CertifySettings, RandomizedSettings, certify_multiple};
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::multiple::{Initialisation, MultipleProblem, MultipleSettings, solve_multiple};
use rotavg::so3::exp;
use rotavg::{Rotation, Verdict};

use crate::common;
use common::scale_weights;

fn instance() -> (MultipleProblem, Vec<Rotation>) {
    let (p, _) = SyntheticGraph {
        num_rotations: 60,
        num_edges: 180,
        noise_sigma: 0.1,
        seed: 33,
        ..Default::default()
    }
    .generate();
    let start = rotavg::multiple::spanning_tree(&p);
    let s = solve_multiple(
        &p,
        &MultipleSettings {
            init: Initialisation::Given(start),
            gradient_tolerance: 1e-13,
            ..Default::default()
        },
    )
    .unwrap();
    (p, s.rotations)
}

/// No factorisation fits (budget 1 byte), the randomized test runs with a fixed seed.
fn over_budget(seed: u64) -> CertifySettings {
    let mut s = CertifySettings::default();
    s.budget.max_memory_bytes = 1;
    s.dual.randomized = RandomizedSettings {
        seed: Some(seed),
        ..Default::default()
    };
    s
}

#[test]
fn over_budget_reports_a_randomized_bound_that_agrees_with_the_proof() {
    let (p, rs) = instance();
    let proven = certify_multiple(&p, &rs, &CertifySettings::default()).unwrap();
    assert!(proven.certificate.is_certified(), "{}", proven.certificate);
    let proven_lb = proven.certificate.lower_bound.unwrap();
    let c = certify_multiple(&p, &rs, &over_budget(7))
        .unwrap()
        .certificate;
    // the verdict and its bounds are the deterministic ones: none
    assert_eq!(c.verdict, Verdict::Inconclusive, "{c}");
    assert!(c.lower_bound.is_none() && c.gap.is_none());
    let r = c.randomized.expect("a randomized bound");
    assert!(r.within_tolerance, "{r}");
    assert_eq!(
        (r.seed, r.failure_probability <= 1e-12 * (1.0 + 1e-9)),
        (7, true)
    );
    // below the cost, and within the tolerance of the proven bound (both bound the same
    // global minimum from below, the proven one certifies within 1e-6 |f|)
    let cost = c.upper_bound;
    assert!(r.lower_bound <= cost);
    assert!(
        (r.lower_bound - proven_lb).abs() <= 1e-6 * cost,
        "{} vs {proven_lb}",
        r.lower_bound
    );
    assert!(
        c.explanation.contains("not a proof") && c.explanation.contains("[D16]"),
        "{}",
        c.explanation
    );
    // the JSON carries it under certificate.randomized
    let json = serde_json::to_value(&c).unwrap();
    assert_eq!(json["randomized"]["seed"], 7);
    assert_eq!(json["verdict"], "inconclusive");
}

/// A verdict must not change when all weights are scaled: neither may the randomized one.
#[test]
fn the_randomized_verdict_is_scale_free() {
    let (p, rs) = instance();
    let base = dual_certificate(&p, &rs, &over_budget(3)).unwrap();
    let r0 = base.certificate.randomized.expect("a randomized bound");
    for c in [1e-6, 1e3, 1e9] {
        let q = scale_weights(&p, c);
        let d = dual_certificate(&q, &rs, &over_budget(3)).unwrap();
        let r = d.certificate.randomized.expect("a randomized bound");
        assert_eq!(r.within_tolerance, r0.within_tolerance, "scale {c}: {r}");
        assert!(
            (r.lower_bound / c - r0.lower_bound).abs() <= 1e-9 * r0.lower_bound.abs(),
            "scale {c}: {} vs {}",
            r.lower_bound / c,
            r0.lower_bound
        );
        let (b0, b) = (base.bound.randomized.unwrap(), d.bound.randomized.unwrap());
        assert_eq!(
            (b.test.degree, b.test.vectors),
            (b0.test.degree, b0.test.vectors)
        );
    }
}

/// An estimate 1e-3 above the optimum (moved off the critical point): the randomized bound
/// still lies below the optimum and does not claim the estimate optimal.
#[test]
fn a_suboptimal_estimate_is_not_called_optimal() {
    let (p, rs) = instance();
    let fstar = p.chordal_cost(&rs);
    let moved: Vec<Rotation> = rs
        .iter()
        .enumerate()
        .map(|(i, r)| {
            let t = 0.02 * ((i % 7) as f64 - 3.0);
            r * exp(&nalgebra::Vector3::new(t, -0.5 * t, 0.3 * t))
        })
        .collect();
    let cost = p.chordal_cost(&moved);
    assert!(cost > fstar * (1.0 + 1e-4), "{cost} vs {fstar}");
    let d = dual_certificate(&p, &moved, &over_budget(11)).unwrap();
    assert_ne!(d.certificate.verdict, Verdict::Certified);
    // S is still positive definite on the complement here (the test passes), but the
    // estimate's stationarity residual makes the deficit large
    let r = d.certificate.randomized.expect("a randomized bound");
    assert!(!r.within_tolerance, "{r}");
    assert!(
        r.lower_bound <= fstar * (1.0 + 1e-12),
        "{} > {fstar}",
        r.lower_bound
    );
}
