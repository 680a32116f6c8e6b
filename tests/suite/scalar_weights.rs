//! The comparison with scalar weights `[A13]` (issue 35: `--information full` on isotropic files
//! certified 2.4-2.8x slower than the same problem read with scalar weights): information
//! isotropic to rounding is certified through the isotropic problem, and its bound is checked
//! against independent references (the isotropic problem's own certificate, the best of random
//! local solves); estimates above a known point are never certified; anisotropic information
//! is refused by the rung.

use nalgebra::Matrix3;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::certify::{CertifySettings, Outcome, Proof, Refusal, certify_multiple};
use rotavg::multiple::anisotropic::Information;
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::multiple::{MultipleProblem, MultipleSettings, solve_multiple};
use rotavg::so3::exp;
use rotavg::{Rotation, Verdict};

use crate::common::best_of_random_starts;

/// `p` with every weight `w` turned into the information `w (I + eps E)`, `E` a fixed symmetric
/// matrix of norm about 1 (`eps = 0`: exactly `w I`).
fn with_information(p: &MultipleProblem, eps: f64) -> MultipleProblem {
    let e = Matrix3::new(0.3, 0.1, -0.2, 0.1, -0.4, 0.05, -0.2, 0.05, 0.1);
    let info = p
        .edges()
        .iter()
        .map(|edge| Information::new((Matrix3::identity() + e * eps) * edge.weight).expect("valid"))
        .collect();
    p.clone().with_information(info).expect("one per edge")
}

fn proof_that_proved(
    c: &rotavg::certify::Certification<rotavg::multiple::MultipleSolution>,
) -> Vec<Proof> {
    c.details
        .ladder
        .iter()
        .filter(|a| a.within.is_none() && matches!(a.outcome, Outcome::Proved { .. }))
        .map(|a| a.rung)
        .collect()
}

/// Exactly and nearly isotropic information: the comparison (exactly `w I`: the scalar weights
/// themselves) certifies the optimum, its bound
/// is at most the best of 12 random local solves (a feasible cost) and within the tolerance
/// of the isotropic problem's own certified bound; a perturbed estimate is never certified.
#[test]
fn isotropic_information_is_certified_through_scalar_weights() {
    let mut rng = StdRng::seed_from_u64(5);
    for (seed, eps) in [(1, 0.0), (2, 1e-13), (3, 1e-11)] {
        let (iso, _) = SyntheticGraph {
            num_rotations: 40,
            num_edges: 120,
            noise_sigma: 0.05,
            seed,
            ..Default::default()
        }
        .generate();
        let p = with_information(&iso, eps);
        let opt = solve_multiple(&p, &MultipleSettings::default())
            .unwrap()
            .rotations;
        let c = certify_multiple(&p, &opt, &CertifySettings::default()).unwrap();
        assert!(c.certificate.is_certified(), "{eps}: {}", c.certificate);
        if eps == 0.0 {
            // exactly w I: the weights themselves (contract section 1), no rung needed
            assert!(!p.is_anisotropic() && p.edges() == iso.edges());
            assert!(p.information_summary().unwrap().scalar_weights);
        } else {
            assert_eq!(proof_that_proved(&c), vec![Proof::ScalarWeights], "{eps}");
        }
        let lb = c.certificate.lower_bound.unwrap();
        let best = best_of_random_starts(&p, 12, &mut rng);
        assert!(
            lb <= p.chordal_cost(&best) * (1.0 + 1e-12),
            "{lb} above a feasible cost"
        );
        // the isotropic problem (the same weights) certifies about the same bound
        let ci = certify_multiple(&iso, &opt, &CertifySettings::default()).unwrap();
        let lbi = ci.certificate.lower_bound.unwrap();
        assert!(
            (lb - lbi).abs() <= 1e-6 * lbi.abs() + 1e-9,
            "{lb} against {lbi}"
        );
        // 1e-3 rad off every node: the cost is well above the optimum's, never certified
        let off: Vec<Rotation> = opt
            .iter()
            .enumerate()
            .map(|(i, r)| r * exp(&nalgebra::Vector3::new(1e-3, -1e-3 * (i % 3) as f64, 1e-3)))
            .collect();
        let c = certify_multiple(&p, &off, &CertifySettings::default()).unwrap();
        assert_ne!(
            c.certificate.verdict,
            Verdict::Certified,
            "{}",
            c.certificate
        );
        assert!(c.certificate.lower_bound.unwrap() <= p.chordal_cost(&opt) * (1.0 + 1e-12));
    }
}

/// Anisotropic information (spread 1e-6, above the rung's limit) is refused by the rung with
/// the reason, and the anisotropic dual certificate proves instead.
#[test]
fn anisotropic_information_is_refused_by_the_comparison() {
    let (iso, _) = SyntheticGraph {
        num_rotations: 30,
        num_edges: 90,
        noise_sigma: 0.05,
        seed: 9,
        ..Default::default()
    }
    .generate();
    let p = with_information(&iso, 1e-6);
    let opt = solve_multiple(&p, &MultipleSettings::default())
        .unwrap()
        .rotations;
    let c = certify_multiple(&p, &opt, &CertifySettings::default()).unwrap();
    let refused = c
        .details
        .ladder
        .iter()
        .find(|a| a.rung == Proof::ScalarWeights)
        .unwrap();
    match &refused.outcome {
        Outcome::Refused(Refusal::NotApplicable { reason }) => {
            assert!(reason.contains("not isotropic"), "{reason}")
        }
        o => panic!("{o:?}"),
    }
    assert!(c.certificate.is_certified(), "{}", c.certificate);
    assert_eq!(proof_that_proved(&c), vec![Proof::DualCertificate]);
}
