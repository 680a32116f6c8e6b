//! Conjugate averaging: problem, diagnostics, local solvers (no SDP; see conjugate_sdp.rs).

use nalgebra::Vector3;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::Error;
use rotavg::conjugate::synthetic::random_instance;
use rotavg::conjugate::{
    ConjugatePair, ConjugateProblem, ConjugateSettings, DiagnosticSettings, Identifiability,
    quaternion_closed_form, solve_conjugate,
};
use rotavg::objective::{Loss, Objective};
use rotavg::so3::{Metric, Rotation, angle_between, exp, random_rotation, random_unit_vector};

/// The residual angle in degrees whose distance under `metric` is `d` (the objective's
/// thresholds are angles; these tests were written with thresholds in the metric's unit).
fn threshold_deg(metric: Metric, d: f64) -> f64 {
    match metric {
        Metric::Geodesic => d.to_degrees(),
        Metric::Chordal => (2.0 * (d / 8f64.sqrt()).asin()).to_degrees(),
        Metric::Quaternion => (4.0 * (d / 2.0).asin()).to_degrees(),
    }
}

fn exact_pairs(s: &Rotation, rs: &[Rotation]) -> ConjugateProblem {
    let ls: Vec<_> = rs.iter().map(|r| s * r * s.inverse()).collect();
    ConjugateProblem::from_rotations(&ls, rs).unwrap()
}

#[test]
fn cost_definition_matches_chordal_distance_form() {
    // contract section 1: g(S) = sum w ||S R - L S||^2 = sum w d_chord(R_i, S^T L_i S)^2.
    let mut rng = StdRng::seed_from_u64(11);
    let (p, _) = random_instance(7, 0.3, 0.0, &mut rng);
    let s = random_rotation(&mut rng);
    let direct: f64 = p
        .pairs()
        .iter()
        .map(|q| {
            let moved = s.inverse() * q.left * s;
            (q.right.matrix() - moved.matrix()).norm_squared()
        })
        .sum();
    assert!((p.chordal_cost(&s) - direct).abs() < 1e-10 * direct);
}

#[test]
fn noise_free_recovery_all_solvers() {
    let mut rng = StdRng::seed_from_u64(1);
    for trial in 0..50 {
        let (p, s) = random_instance(3 + trial % 5, 0.0, 0.0, &mut rng);
        let cf = quaternion_closed_form(&p, &DiagnosticSettings::default()).unwrap();
        assert!(
            angle_between(&cf.estimate, &s) < 1e-9,
            "closed form trial {trial}"
        );
        for metric in [Metric::Chordal, Metric::Geodesic] {
            for loss in [
                Loss::L2,
                Loss::L1,
                Loss::Huber {
                    threshold_deg: threshold_deg(metric, 0.1),
                },
                Loss::Cauchy {
                    scale_deg: threshold_deg(metric, 0.1),
                },
            ] {
                let q = p
                    .clone()
                    .with_objective(Objective::new(metric, loss))
                    .unwrap();
                let sol = solve_conjugate(&q, &ConjugateSettings::default()).unwrap();
                assert!(
                    angle_between(&sol.estimate, &s) < 1e-8,
                    "{metric:?} {loss:?} trial {trial}"
                );
                assert!(sol.cost < 1e-12, "{metric:?} {loss:?}: cost {}", sol.cost);
            }
        }
    }
}

#[test]
fn local_solver_converges_from_far_start() {
    // From a random start the chordal solver reaches the planted S on exact data (cost 0 is the
    // global minimum, so any converged point with cost ~0 is it).
    let mut rng = StdRng::seed_from_u64(2);
    let mut ok = 0;
    for _ in 0..50 {
        let (p, s) = random_instance(10, 0.0, 0.0, &mut rng);
        let init = random_rotation(&mut rng);
        let from = ConjugateSettings {
            init: Some(init),
            ..Default::default()
        };
        let sol = solve_conjugate(&p, &from).unwrap();
        if angle_between(&sol.estimate, &s) < 1e-8 {
            ok += 1;
        }
    }
    println!("random starts reaching the planted S: {ok}/50");
    assert!(ok >= 40);
}

#[test]
fn chordal_solution_is_stationary_and_beats_perturbations() {
    let mut rng = StdRng::seed_from_u64(3);
    for _ in 0..20 {
        let (p, _) = random_instance(20, 0.1, 0.0, &mut rng);
        let sol = solve_conjugate(&p, &ConjugateSettings::default()).unwrap();
        assert!(sol.report.termination.is_converged(), "{}", sol.report);
        for _ in 0..20 {
            let d = random_unit_vector(&mut rng) * 1e-4;
            let s2 = sol.estimate * exp(&d);
            assert!(p.chordal_cost(&s2) >= sol.cost - 1e-12);
        }
    }
}

#[test]
fn closed_form_matches_chordal_optimum_at_tiny_noise() {
    // Both are consistent estimators; at noise 1e-6 rad they differ by O(noise).
    let mut rng = StdRng::seed_from_u64(4);
    for _ in 0..30 {
        let (p, _) = random_instance(15, 1e-6, 0.0, &mut rng);
        let cf = quaternion_closed_form(&p, &DiagnosticSettings::default()).unwrap();
        let ch = solve_conjugate(&p, &ConjugateSettings::default()).unwrap();
        assert!(angle_between(&cf.estimate, &ch.estimate) < 1e-5);
    }
}

#[test]
fn invariance_under_simultaneous_conjugation() {
    // [H10]: L_i -> G L_i G^T, R_i -> H R_i H^T maps the cost g_new(S') = g(G^T S' H), so the
    // optimum moves to S' = G S H^T.
    let mut rng = StdRng::seed_from_u64(5);
    for _ in 0..20 {
        let (p, _) = random_instance(12, 0.2, 0.0, &mut rng);
        let g = random_rotation(&mut rng);
        let h = random_rotation(&mut rng);
        let pairs: Vec<_> = p
            .pairs()
            .iter()
            .map(|q| ConjugatePair::new(g * q.left * g.inverse(), h * q.right * h.inverse()))
            .collect();
        let p2 = ConjugateProblem::new(pairs).unwrap();
        let s1 = solve_conjugate(&p, &ConjugateSettings::default()).unwrap();
        let s2 = solve_conjugate(&p2, &ConjugateSettings::default()).unwrap();
        let mapped = g * s1.estimate * h.inverse();
        assert!(angle_between(&mapped, &s2.estimate) < 1e-7);
        assert!((s1.cost - s2.cost).abs() < 1e-9 * s1.cost.max(1.0));
    }
}

#[test]
fn degenerate_parallel_axes_and_zero_angles_are_refused() {
    let s = exp(&Vector3::new(0.3, 0.2, -0.4));
    let axis = Vector3::new(1.0, 2.0, 2.0).normalize();
    let rs: Vec<_> = [0.3, 0.8, -1.2, 2.0]
        .iter()
        .map(|a| exp(&(axis * *a)))
        .collect();
    let p = exact_pairs(&s, &rs);
    let d = DiagnosticSettings::default();
    match p.identifiability(&d) {
        Identifiability::ParallelAxes { axis: a, .. } => {
            let a = Vector3::new(a[0], a[1], a[2]);
            assert!(a.dot(&axis).abs() > 1.0 - 1e-9);
        }
        other => panic!("expected ParallelAxes, got {other:?}"),
    }
    assert!(matches!(
        solve_conjugate(&p, &ConjugateSettings::default()),
        Err(Error::Degenerate { .. })
    ));
    assert!(matches!(
        quaternion_closed_form(&p, &d),
        Err(Error::Degenerate { .. })
    ));
    // angles ~ 0
    let rs: Vec<_> = (0..5)
        .map(|k| exp(&(Vector3::new(1.0, k as f64, 0.5).normalize() * 1e-4)))
        .collect();
    let p = exact_pairs(&s, &rs);
    assert!(matches!(
        p.identifiability(&d),
        Identifiability::AllAnglesSmall { .. }
    ));
    assert!(solve_conjugate(&p, &ConjugateSettings::default()).is_err());
    // one more pair about another axis makes it identifiable
    let mut rs: Vec<_> = [0.3, 0.8].iter().map(|a| exp(&(axis * *a))).collect();
    rs.push(exp(&Vector3::new(0.0, 0.0, 0.5)));
    let p = exact_pairs(&s, &rs);
    assert!(p.identifiability(&d).is_determined());
    let sol = solve_conjugate(&p, &ConjugateSettings::default()).unwrap();
    assert!(angle_between(&sol.estimate, &s) < 1e-9);
}

#[test]
fn diagnostics_flag_mismatched_and_small_pairs() {
    let mut rng = StdRng::seed_from_u64(6);
    let (p, s) = random_instance(10, 0.0, 0.0, &mut rng);
    let mut pairs = p.pairs().to_vec();
    // pair 3: L squared (angle a -> 2a or 2 pi - 2a; with a in [0.2, 2.0] rad the angle changes
    // by at least 0.2 rad = 11 deg > the 5 deg threshold)
    pairs[3].left = pairs[3].left * pairs[3].left;
    // pair 5: pure translation (both angles ~0)
    let tiny = exp(&Vector3::new(1e-4, 0.0, 0.0));
    pairs[5] = ConjugatePair::new(s * tiny * s.inverse(), tiny);
    let p = ConjugateProblem::new(pairs).unwrap();
    let d = p.diagnose(&DiagnosticSettings::default());
    // Angle mismatch of exact pairs is 0 (conjugation preserves angles, [H4]).
    for (k, m) in d.angle_mismatch.iter().enumerate() {
        if k != 3 {
            assert!(*m < 1e-12, "pair {k}: {m}");
        }
    }
    assert_eq!(d.suspicious_pairs, vec![3]);
    assert_eq!(d.small_rotation_pairs, vec![5]);
    assert!(d.identifiability.is_determined());
}

#[test]
fn invalid_input_is_rejected() {
    let r = Rotation::identity();
    assert!(matches!(
        ConjugateProblem::new(vec![]),
        Err(Error::Empty { .. })
    ));
    let mut p = ConjugatePair::new(r, r);
    p.weight = -1.0;
    assert!(matches!(
        ConjugateProblem::new(vec![p.clone()]),
        Err(Error::InvalidWeight { .. })
    ));
    p.weight = f64::NAN;
    assert!(ConjugateProblem::new(vec![p]).is_err());
    let mut rng = StdRng::seed_from_u64(8);
    let (prob, _) = random_instance(5, 0.0, 0.0, &mut rng);
    let bad = Objective::new(
        Metric::Chordal,
        Loss::Huber {
            threshold_deg: -1.0,
        },
    );
    assert!(matches!(
        prob.with_objective(bad),
        Err(Error::InvalidSettings { .. })
    ));
}

#[test]
fn robust_losses_resist_outliers() {
    // 20 % outliers: L1 / Cauchy estimates are closer to the planted S than chordal L2.
    let mut rng = StdRng::seed_from_u64(9);
    let (mut e2, mut e1, mut ec) = (0.0, 0.0, 0.0);
    for _ in 0..10 {
        let (p, s) = random_instance(50, 0.01, 0.2, &mut rng);
        let l2 = solve_conjugate(&p, &ConjugateSettings::default()).unwrap();
        let robust = |loss| {
            let q = p
                .clone()
                .with_objective(Objective::new(Metric::Geodesic, loss))
                .unwrap();
            solve_conjugate(&q, &ConjugateSettings::default()).unwrap()
        };
        let g1 = robust(Loss::L1);
        let gc = robust(Loss::Cauchy {
            scale_deg: threshold_deg(Metric::Geodesic, 0.05),
        });
        e2 += angle_between(&l2.estimate, &s);
        e1 += angle_between(&g1.estimate, &s);
        ec += angle_between(&gc.estimate, &s);
    }
    println!(
        "mean errors (deg): chordal L2 {:.3}, geodesic L1 {:.3}, geodesic Cauchy {:.3}",
        e2.to_degrees() / 10.0,
        e1.to_degrees() / 10.0,
        ec.to_degrees() / 10.0
    );
    assert!(e1 < e2 && ec < e2);
}

mod qcqp {
    //! The 10x10 QCQP data, checked against the definitions (no SDP solve here).
    use super::*;
    use nalgebra::Matrix3;
    use rand::Rng;
    use rotavg::certify::conjugate::{refine_multipliers, verify_lower_bound};
    use rotavg::relax::conjugate::{constraint_matrices, cost_matrix, lift};

    fn random_matrix(rng: &mut StdRng) -> Matrix3<f64> {
        Matrix3::from_fn(|_, _| rng.random::<f64>() * 2.0 - 1.0)
    }

    /// The polynomial each constraint states, evaluated directly with nalgebra: returns
    /// `p_k(S, y)` such that the constraint is `p_k = b_k`, in the order of
    /// `constraint_matrices`.
    fn definitions(s: &Matrix3<f64>, y: f64) -> Vec<f64> {
        let mut out = vec![y * y];
        let sts = s.transpose() * s;
        let sst = s * s.transpose();
        for m in [sts, sst] {
            for a in 0..3 {
                for b in a..3 {
                    out.push(m[(a, b)] - if a == b { y * y } else { 0.0 });
                }
            }
        }
        let u = |v: usize| -> Vector3<f64> { s.column(v).into_owned() };
        for (a, b, c) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)] {
            let d = u(a).cross(&u(b)) - u(c) * y;
            out.extend(d.iter());
        }
        out
    }

    /// Why there is no row handedness family: for ANY 3x3 matrix S and scalar y, the 9 row
    /// equations `row_a x row_b - y row_c` (cyclic) are the 9 column equations
    /// `col_a x col_b - y col_c` transposed entry for entry (both are `cof(S) - y S`).
    #[test]
    fn row_handedness_equals_column_handedness() {
        let mut rng = StdRng::seed_from_u64(35);
        for _ in 0..100 {
            let s = random_matrix(&mut rng);
            let y = rng.random::<f64>() * 2.0 - 1.0;
            let mut col = Matrix3::zeros();
            let mut row = Matrix3::zeros();
            for (a, b, c) in [(0, 1, 2), (1, 2, 0), (2, 0, 1)] {
                let dc = s.column(a).cross(&s.column(b)) - s.column(c) * y;
                let dr =
                    s.row(a).transpose().cross(&s.row(b).transpose()) - s.row(c).transpose() * y;
                for k in 0..3 {
                    col[(k, c)] = dc[k];
                    row[(c, k)] = dr[k];
                }
            }
            assert!((col - row).abs().max() < 1e-14, "{col} vs {row}");
        }
    }

    #[test]
    fn constraint_matrices_match_definitions_entry_by_entry() {
        let cons = constraint_matrices();
        assert_eq!(cons.len(), 22);
        let mut rng = StdRng::seed_from_u64(31);
        for _ in 0..100 {
            // arbitrary (non-orthogonal) S and y: z^T A_k z must equal the polynomial exactly
            let s = random_matrix(&mut rng);
            let y = rng.random::<f64>() * 2.0 - 1.0;
            let z = lift(&s, y);
            let defs = definitions(&s, y);
            for (k, (con, d)) in cons.iter().zip(&defs).enumerate() {
                assert!(
                    con.matrix == con.matrix.transpose(),
                    "{} not symmetric",
                    con.name
                );
                let rhs_part = if k == 0 { 0.0 } else { con.rhs };
                assert!(
                    ((z.transpose() * con.matrix * z)[0] - (d + rhs_part)).abs() < 1e-12,
                    "{}",
                    con.name
                );
            }
            // random rotation, y = 1: every constraint holds, z^T A z = b
            let r = random_rotation(&mut rng);
            let z = lift(r.matrix(), 1.0);
            for con in &cons {
                assert!(
                    ((z.transpose() * con.matrix * z)[0] - con.rhs).abs() < 1e-12,
                    "{}",
                    con.name
                );
            }
            // a reflection violates a handedness constraint (only orthogonality would allow it)
            let f = -*r.matrix();
            let z = lift(&f, 1.0);
            let worst = cons
                .iter()
                .map(|c| ((z.transpose() * c.matrix * z)[0] - c.rhs).abs())
                .fold(0.0, f64::max);
            assert!(worst > 0.5);
        }
    }

    #[test]
    fn cost_matrix_matches_cost() {
        // [H2]: s^T M s = sum w ||S R - L S||^2 for every 3x3 S (column-major vec).
        let mut rng = StdRng::seed_from_u64(32);
        let (p, _) = random_instance(9, 0.4, 0.0, &mut rng);
        let m = cost_matrix(&p);
        for _ in 0..20 {
            let s = random_matrix(&mut rng);
            let v = nalgebra::SVector::<f64, 9>::from_column_slice(s.as_slice());
            let direct: f64 = p
                .pairs()
                .iter()
                .map(|q| q.weight * (s * q.right.matrix() - q.left.matrix() * s).norm_squared())
                .sum();
            assert!(((v.transpose() * m * v)[0] - direct).abs() < 1e-10 * direct);
            let r = random_rotation(&mut rng);
            let v = nalgebra::SVector::<f64, 9>::from_column_slice(r.matrix().as_slice());
            assert!(((v.transpose() * m * v)[0] - p.chordal_cost(&r)).abs() < 1e-10);
        }
    }

    #[test]
    fn any_multipliers_give_a_valid_bound() {
        // [H8] holds for arbitrary nu: the verified bound never exceeds g at any rotation.
        let mut rng = StdRng::seed_from_u64(33);
        let cons = constraint_matrices();
        for _ in 0..200 {
            let (p, _) = random_instance(6, 0.5, 0.0, &mut rng);
            let m = cost_matrix(&p);
            let nu: Vec<f64> = (0..cons.len())
                .map(|_| rng.random::<f64>() * 4.0 - 2.0)
                .collect();
            let b = verify_lower_bound(&m, &cons, &nu).unwrap();
            let s = random_rotation(&mut rng);
            assert!(b.lower_bound <= p.chordal_cost(&s));
            // refined at a noise-free optimum: the dual value equals the cost there
            let (q, s0) = random_instance(6, 0.0, 0.0, &mut rng);
            let mq = cost_matrix(&q);
            let nu2 = refine_multipliers(&mq, &cons, &nu, &s0).unwrap();
            let b2 = verify_lower_bound(&mq, &cons, &nu2).unwrap();
            assert!(b2.lower_bound <= q.chordal_cost(&s0) + 1e-12);
        }
    }
}
