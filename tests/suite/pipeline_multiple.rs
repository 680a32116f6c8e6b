//! The multiple-averaging pipeline (`average_multiple`, `certify_multiple`):
//! planted optima certified (noise-free n = 50 and n = 200 exercise the absolute tolerance,
//! `paper-notes/certificates.md` "The pipeline"), z-cycle winding configurations
//! (`[D10]`, known global optimum `f_0 = 8 n sin^2(phi / 2n)`) never certified but repaired by the
//! SDP, and `certify_multiple` never changes its input.

use nalgebra::Vector3;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::Metric;
use rotavg::certify::tolerance::DEFAULT_ABSOLUTE_GAP_PER_MIN_WEIGHT;
use rotavg::certify::{CertifyMode, CertifySettings, ImprovementSource, certify_multiple};
use rotavg::multiple::synthetic::{SyntheticGraph, z_cycle};
use rotavg::multiple::{Initialisation, MultipleSettings};
use rotavg::objective::{Loss, Objective};
use rotavg::pipeline::{AverageMultipleSettings, average_multiple};
use rotavg::so3::{Rotation, exp, perturb};
use rotavg::{BoundMethod, Verdict};

fn winding(n: usize, k: i32) -> Vec<Rotation> {
    (0..n)
        .map(|i| {
            exp(&(Vector3::z() * (i as f64 * 2.0 * std::f64::consts::PI * k as f64 / n as f64)))
        })
        .collect()
}

/// `[D10]`: the global minimum of the z-cycle for `|phi| / n <= 0.8`.
fn f0(n: usize, phi: f64) -> f64 {
    8.0 * n as f64 * (phi / (2.0 * n as f64)).sin().powi(2)
}

#[test]
fn noise_free_planted_is_certified_at_n50_and_n200() {
    for (n, m, seed) in [(50, 150, 1), (200, 600, 2)] {
        let (p, gt) = SyntheticGraph {
            num_rotations: n,
            num_edges: m,
            noise_sigma: 0.0,
            seed,
            ..Default::default()
        }
        .generate();
        let s = AverageMultipleSettings::default();
        // the documented rule: absolute tolerance 1e-9 x the smallest edge weight (unit weights: 1)
        let tol = s.certify.tolerance.resolve(p.min_weight());
        assert_eq!(p.min_weight(), 1.0);
        assert_eq!(tol.absolute, DEFAULT_ABSOLUTE_GAP_PER_MIN_WEIGHT);
        let est = average_multiple(&p, &s).unwrap();
        let c = est.certificate.clone().unwrap();
        println!("n={n}: {c}");
        assert!(c.is_certified(), "n={n}: {c}");
        assert_eq!(c.method, BoundMethod::Dual);
        assert!(est.solution.chordal_cost < 1e-18);
        // a lower bound can never exceed the true minimum (0 here)
        assert!(c.lower_bound.unwrap() <= 1e-18);
        let c2 = certify_multiple(&p, &gt, &s.certify).unwrap();
        assert!(
            c2.certificate.is_certified(),
            "n={n} truth: {}",
            c2.certificate
        );
    }
}

#[test]
fn scaled_tolerance_does_not_certify_a_perturbed_optimum() {
    // Noise-free n = 200: f* = 0. Perturbing one node by 1e-3 rad raises the cost by about
    // deg * 8 sin^2(5e-4) ~ 1e-5 >> the tolerance 1e-9: must not be certified.
    let (p, gt) = SyntheticGraph {
        num_rotations: 200,
        num_edges: 600,
        noise_sigma: 0.0,
        seed: 3,
        ..Default::default()
    }
    .generate();
    let mut rng = StdRng::seed_from_u64(9);
    let mut est = gt.clone();
    est[17] = perturb(&est[17], 1e-3, &mut rng);
    let c = certify_multiple(&p, &est, &CertifySettings::default()).unwrap();
    println!("{}", c.certificate);
    assert_ne!(c.certificate.verdict, Verdict::Certified);
    assert!(c.certificate.lower_bound.unwrap() <= 1e-15);
}

#[test]
fn low_noise_is_certified() {
    for (seed, sigma) in [(4, 0.01), (5, 0.05)] {
        let (p, gt) = SyntheticGraph {
            num_rotations: 100,
            num_edges: 300,
            noise_sigma: sigma,
            seed,
            ..Default::default()
        }
        .generate();
        let est = average_multiple(&p, &AverageMultipleSettings::default()).unwrap();
        let c = est.certificate.clone().unwrap();
        println!("sigma={sigma}: {c}");
        assert!(c.is_certified());
        // the certified optimum is no worse than the planted truth
        assert!(est.solution.chordal_cost <= p.chordal_cost(&gt) + 1e-9);
    }
}

#[test]
fn winding_configuration_is_bounded_not_certified_and_unchanged() {
    for (n, phi, k) in [(8, 1.0, 1), (12, 0.3, 2)] {
        let p = z_cycle(n, phi);
        let y = winding(n, k);
        let copy = y.clone();
        let f_0 = f0(n, phi);
        for mode in [
            CertifyMode::Dual,
            CertifyMode::Auto,
            CertifyMode::Staircase,
            CertifyMode::Sdp,
        ] {
            let s = CertifySettings::with_mode(mode);
            let c = certify_multiple(&p, &y, &s).unwrap();
            println!("n={n} k={k} {mode:?}: {c}");
            assert_ne!(c.certificate.verdict, Verdict::Certified);
            // the bound is below the known optimum (small slack for the verified rounding)
            let lb = c.certificate.lower_bound.unwrap();
            assert!(lb <= f_0 + 1e-9 * f_0, "lb {lb} > f0 {f_0}");
            // cost of the given estimate, bitwise; estimate untouched
            assert_eq!(
                c.certificate.upper_bound.to_bits(),
                p.chordal_cost(&y).to_bits()
            );
            assert!(y.iter().zip(&copy).all(|(a, b)| {
                a.matrix()
                    .as_slice()
                    .iter()
                    .zip(b.matrix().as_slice())
                    .all(|(x, z)| x.to_bits() == z.to_bits())
            }));
            if mode == CertifyMode::Auto {
                // the staircase ran (auto: before any SDP), and its rounding, polished, is the
                // cheaper estimate: the global optimum f_0, certified by its dual certificate
                let run = c
                    .details
                    .methods()
                    .into_iter()
                    .find(|m| m.method == BoundMethod::Staircase)
                    .expect("the staircase ran");
                let stair_lb = run.lower_bound.unwrap();
                let better = c.improvement.as_ref().expect("a cheaper estimate");
                assert!(better.chordal_cost < f_0 * (1.0 + 1e-6));
                assert_eq!(
                    c.details.improvement.map(|i| i.source),
                    Some(ImprovementSource::StaircaseRounding)
                );
                // the staircase bound is nearly tight (the relaxation is tight on the cycle)
                assert!(stair_lb >= f_0 * (1.0 - 1e-4), "lb {stair_lb} f0 {f_0}");
                assert!(lb >= stair_lb, "lb {lb} < staircase bound {stair_lb}");
                assert!(c.details.sdp.is_none(), "no SDP needed");
                assert!(lb >= f_0 * (1.0 - 1e-4), "lb {lb} f0 {f_0}");
            }
            if mode == CertifyMode::Sdp {
                let sdp = c.details.sdp.as_ref().expect("the SDP ran");
                assert!(sdp.polished_cost.unwrap() < f_0 * (1.0 + 1e-6));
            }
        }
    }
}

#[test]
fn pipeline_from_a_winding_start_ends_certified_at_the_global_optimum() {
    for (n, phi, k) in [(8, 1.0, 1), (12, 0.3, 2)] {
        let p = z_cycle(n, phi);
        let f_0 = f0(n, phi);
        let s = AverageMultipleSettings {
            solve: MultipleSettings {
                init: Initialisation::Given(winding(n, k)),
                ..Default::default()
            },
            ..Default::default()
        };
        let est = average_multiple(&p, &s).unwrap();
        let c = est.certificate.clone().unwrap();
        println!("n={n} k={k}: {est}");
        assert_eq!(
            est.details.improved_by,
            Some(ImprovementSource::StaircaseRounding)
        );
        assert!(c.is_certified(), "{c}");
        assert!((est.solution.chordal_cost - f_0).abs() <= 1e-7 * f_0);
        // the SDP's rounding gets there too
        let s2 = s.clone().with_mode(CertifyMode::Sdp);
        let est2 = average_multiple(&p, &s2).unwrap();
        assert_eq!(
            est2.details.improved_by,
            Some(ImprovementSource::SdpRounding)
        );
        assert!(est2.certificate.unwrap().is_certified());
        assert!((est2.solution.chordal_cost - f_0).abs() <= 1e-7 * f_0);
    }
}

#[test]
fn other_losses_and_mode_none_have_no_certificate() {
    let (p, _) = SyntheticGraph {
        num_rotations: 30,
        num_edges: 90,
        noise_sigma: 0.02,
        ..Default::default()
    }
    .generate();
    let geodesic = p
        .clone()
        .with_objective(Objective::new(Metric::Geodesic, Loss::L2))
        .unwrap();
    let e = average_multiple(&geodesic, &AverageMultipleSettings::default()).unwrap();
    assert!(e.certificate.is_none() && e.details.skipped_reason.is_some());
    let s = AverageMultipleSettings::default().with_mode(CertifyMode::None);
    assert!(average_multiple(&p, &s).unwrap().certificate.is_none());
}

#[test]
fn wrong_estimate_length_is_an_error() {
    let (p, gt) = SyntheticGraph {
        num_rotations: 10,
        num_edges: 20,
        ..Default::default()
    }
    .generate();
    assert!(certify_multiple(&p, &gt[..9], &CertifySettings::default()).is_err());
}
