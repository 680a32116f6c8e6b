//! Soundness campaign for the dual certificate (issue 4, `paper-notes/certificates.md` [D4]-[D9]).
//!
//! Thousands of seeded random instances with n <= 12, noise 0..90 degrees, with and without
//! outliers. For every instance, several local solutions (from the planted truth and from random
//! starts) and one random (non-critical) point are certified. Checked, each a test that can fail:
//! - every verified lower bound is <= the best cost found by all the restarts (+ fp tolerance);
//! - a certified solution has cost <= best + the gap tolerance (so a non-global local minimum is
//!   never certified);
//! - no lower bound is NaN / the verdict is never Certified without a bound.
//!
//! Instance counts are printed (run with `--nocapture`).

use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rotavg::Rotation;
use rotavg::certify::multiple::dual_certificate;
use rotavg::certify::{CertifySettings, DualSettings, Proof};
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::multiple::{Initialisation, MultipleProblem, MultipleSettings, solve_multiple};
use rotavg::so3::random_rotation;

// Local solutions come from the crate's own chordal solver (Newton-LM on SO(3)^n) started from
// the given rotations: the campaign checks the certificate on exactly the local minima that
// `solve_multiple` produces in practice.
fn local_solve(p: &MultipleProblem, start: &[Rotation]) -> (Vec<Rotation>, f64) {
    let settings = MultipleSettings {
        init: Initialisation::Given(start.to_vec()),
        ..Default::default()
    };
    let s = solve_multiple(p, &settings).expect("connected synthetic graph");
    (s.rotations, s.chordal_cost)
}

#[derive(Default, Debug)]
struct Tally {
    instances: usize,
    solutions: usize,
    certified: usize,
    non_global: usize,
    random_points: usize,
    /// bounds verified by the scalar comparison [D13]
    scalar: usize,
}

fn campaign(seed: u64, instances: usize, outlier_fraction: f64) -> Tally {
    campaign_with(
        seed,
        instances,
        outlier_fraction,
        CertifySettings::default(),
    )
}

fn campaign_with(
    seed: u64,
    instances: usize,
    outlier_fraction: f64,
    settings: CertifySettings,
) -> Tally {
    let mut rng = StdRng::seed_from_u64(seed);
    let mut t = Tally::default();
    for inst in 0..instances {
        let n = rng.random_range(3..=12);
        let max_m = n * (n - 1) / 2 + 2;
        let m = rng.random_range((n - 1)..=(3 * n).min(max_m));
        let noise_deg: f64 = [0.0, 1.0, 5.0, 10.0, 20.0, 45.0, 90.0][inst % 7];
        let (p, gt) = SyntheticGraph {
            num_rotations: n,
            num_edges: m,
            noise_sigma: noise_deg.to_radians(),
            outlier_fraction,
            seed: rng.random(),
        }
        .generate();
        let mut sols = vec![local_solve(&p, &gt)];
        for _ in 0..4 {
            let start: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
            sols.push(local_solve(&p, &start));
        }
        let best = sols.iter().map(|s| s.1).fold(f64::INFINITY, f64::min);
        let tol = settings.tolerance.resolve(p.min_weight());
        let fp_tol = 1e-9 * (1.0 + best);
        let budget = tol.absolute.max(tol.relative * best.abs().max(1e-12));
        for (rs, f) in &sols {
            let c = dual_certificate(&p, rs, &settings).expect("valid input");
            let lb = c.certificate.lower_bound.expect("a bound always exists");
            assert!(lb.is_finite());
            if c.bound.verification == Proof::ScalarComparison {
                t.scalar += 1;
            }
            assert!(
                lb <= best + fp_tol,
                "instance {inst} (n={n}, m={m}, noise {noise_deg} deg): lower bound {lb} > best cost {best}"
            );
            t.solutions += 1;
            let non_global = *f > best + 10.0 * budget + fp_tol;
            if non_global {
                t.non_global += 1;
            }
            if c.certificate.is_certified() {
                t.certified += 1;
                assert!(
                    *f <= best
                        + c.certificate
                            .tolerance
                            .absolute
                            .max(c.certificate.tolerance.relative * f.abs())
                        + fp_tol,
                    "instance {inst}: certified cost {f} but a restart found {best}: {c}"
                );
                assert!(!non_global);
            }
        }
        // a random (non-critical) point: valid bound, never certified unless (absurdly) optimal
        let rnd: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
        let c = dual_certificate(&p, &rnd, &settings).expect("valid input");
        let lb = c.certificate.lower_bound.expect("a bound always exists");
        assert!(
            lb <= best + fp_tol,
            "random point: lower bound {lb} > best {best}"
        );
        if c.certificate.is_certified() {
            assert!(p.chordal_cost(&rnd) <= best + budget + fp_tol);
        }
        t.random_points += 1;
        t.instances += 1;
    }
    t
}

#[test]
fn soundness_no_outliers() {
    let t = campaign(2024, 1000, 0.0);
    println!("soundness (no outliers): {t:?}");
    assert_eq!(t.instances, 1000);
    // sanity: the campaign exercises both verdicts
    assert!(t.certified > 0);
}

#[test]
fn soundness_ten_percent_outliers() {
    let t = campaign(2025, 700, 0.1);
    println!("soundness (10% outliers): {t:?}");
    assert_eq!(t.instances, 700);
}

#[test]
fn soundness_thirty_percent_outliers() {
    let t = campaign(2026, 700, 0.3);
    println!("soundness (30% outliers): {t:?}");
    assert_eq!(t.instances, 700);
    assert!(
        t.non_global > 0,
        "the campaign should meet non-global local minima"
    );
}

/// The same campaign with the scalar comparison [D13] as the only proof of the ladder (by default
/// the grounded bound [D15] is tried first on small graphs): its bounds face the same checks.
#[test]
fn soundness_scalar_comparison_forced() {
    let settings = CertifySettings {
        dual: DualSettings {
            proofs: vec![Proof::ScalarComparison],
            ..Default::default()
        },
        ..Default::default()
    };
    let t = campaign_with(2027, 600, 0.1, settings);
    println!("soundness (scalar comparison forced, 10% outliers): {t:?}");
    assert_eq!(t.instances, 600);
    assert!(t.scalar > 100, "the scalar comparison must be exercised");
    assert!(t.certified > 0);
}
