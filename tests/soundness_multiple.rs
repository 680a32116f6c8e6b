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

use nalgebra::Vector3;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rotavg::Rotation;
use rotavg::certify::multiple::{CertifySettings, certify_multiple, laplacian_times};
use rotavg::multiple::MultipleProblem;
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::so3::{exp, random_rotation, vee};

// Minimal private local optimiser: Riemannian gradient descent with Barzilai-Borwein steps and
// Armijo backtracking on SO(3)^n (same as in tests/certify_multiple.rs).
fn gradient(p: &MultipleProblem, rs: &[Rotation]) -> Vec<Vector3<f64>> {
    laplacian_times(p, rs)
        .iter()
        .zip(rs)
        .map(|(g, r)| {
            let m = g * r.matrix().transpose();
            4.0 * vee(&(0.5 * (m - m.transpose())))
        })
        .collect()
}

fn local_solve(p: &MultipleProblem, start: &[Rotation], max_iter: usize) -> (Vec<Rotation>, f64) {
    let mut rs = start.to_vec();
    let mut f = p.chordal_cost(&rs);
    let mut g = gradient(p, &rs);
    let mut step = 1e-2;
    let mut prev: Option<(Vec<Vector3<f64>>, f64)> = None;
    for _ in 0..max_iter {
        let gn2: f64 = g.iter().map(|v| v.norm_squared()).sum();
        if gn2.sqrt() <= 1e-10 * (1.0 + f) {
            break;
        }
        if let Some((gp, tp)) = &prev {
            let s2 = tp * tp * gp.iter().map(|v| v.norm_squared()).sum::<f64>();
            let sy: f64 = -tp * gp.iter().zip(&g).map(|(a, b)| a.dot(&(b - a))).sum::<f64>();
            if sy > 0.0 {
                step = (s2 / sy).clamp(1e-8, 1.0);
            }
        }
        let mut t = step;
        let mut accepted = None;
        for _ in 0..50 {
            let cand: Vec<Rotation> = rs
                .iter()
                .zip(&g)
                .map(|(r, d)| {
                    let mut x = exp(&(-d * t)) * r;
                    x.renormalize();
                    x
                })
                .collect();
            let fc = p.chordal_cost(&cand);
            if fc <= f - 1e-4 * t * gn2 {
                accepted = Some((cand, fc));
                break;
            }
            t *= 0.5;
        }
        let Some((cand, fc)) = accepted else { break };
        rs = cand;
        f = fc;
        prev = Some((g.clone(), t));
        g = gradient(p, &rs);
    }
    (rs, f)
}

#[derive(Default, Debug)]
struct Tally {
    instances: usize,
    solutions: usize,
    certified: usize,
    non_global: usize,
    random_points: usize,
}

fn campaign(seed: u64, instances: usize, outlier_fraction: f64) -> Tally {
    let mut rng = StdRng::seed_from_u64(seed);
    let settings = CertifySettings::default();
    let tol = settings.tolerance;
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
        let mut sols = vec![local_solve(&p, &gt, 400)];
        for _ in 0..4 {
            let start: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
            sols.push(local_solve(&p, &start, 400));
        }
        let best = sols.iter().map(|s| s.1).fold(f64::INFINITY, f64::min);
        let fp_tol = 1e-9 * (1.0 + best);
        let budget = tol.absolute.max(tol.relative * best.abs().max(1e-12));
        for (rs, f) in &sols {
            let c = certify_multiple(&p, rs, &settings).expect("valid input");
            let lb = c.certificate.lower_bound.expect("a bound always exists");
            assert!(lb.is_finite());
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
        let c = certify_multiple(&p, &rnd, &settings).expect("valid input");
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
    let t = campaign(2024, 500, 0.0);
    println!("soundness (no outliers): {t:?}");
    assert_eq!(t.instances, 500);
    // sanity: the campaign exercises both verdicts
    assert!(t.certified > 0);
}

#[test]
fn soundness_ten_percent_outliers() {
    let t = campaign(2025, 350, 0.1);
    println!("soundness (10% outliers): {t:?}");
    assert_eq!(t.instances, 350);
}

#[test]
fn soundness_thirty_percent_outliers() {
    let t = campaign(2026, 350, 0.3);
    println!("soundness (30% outliers): {t:?}");
    assert_eq!(t.instances, 350);
    assert!(
        t.non_global > 0,
        "the campaign should meet non-global local minima"
    );
}
