//! The multiple-averaging SDP relaxation (src/relax/, `paper-notes/sdp.md`).

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use faer::{Mat, Side};
use rotavg::Rotation;
use rotavg::multiple::synthetic::{SyntheticGraph, z_cycle};
use rotavg::multiple::{Edge, MultipleProblem};
use rotavg::relax::svec::{smat, svec, svec_len};
use rotavg::relax::{SdpForm, SdpSettings, SdpStatus, relax_multiple};
use rotavg::so3::{angle_between, exp};
use std::time::Instant;

fn graph(n: usize, m: usize, sigma: f64, seed: u64) -> (MultipleProblem, Vec<Rotation>) {
    SyntheticGraph {
        num_rotations: n,
        num_edges: m,
        noise_sigma: sigma,
        outlier_fraction: 0.0,
        seed,
    }
    .generate()
}

fn max_angle(a: &[Rotation], b: &[Rotation]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| angle_between(x, y))
        .fold(0.0, f64::max)
}

/// [P1] svec convention checked against Clarabel itself: `max t s.t. M - t I PSD` has value
/// `lambda_min(M)` only if off-diagonals are encoded with the sqrt(2) factor in Clarabel's order
/// (a wrong order or factor changes the matrix, hence the eigenvalue). The dual variable is
/// `smat(z) = v v^T` for the bottom eigenvector `v`.
#[test]
fn svec_matches_clarabel_psd_triangle_cone() {
    let n = 4;
    // non-symmetric pattern in the upper triangle so a transposed order would be detected
    let m = Mat::from_fn(n, n, |i, j| {
        let (i, j) = (i.min(j), i.max(j));
        if i == j {
            2.0 + i as f64
        } else {
            0.3 * (i + 2 * j) as f64 - 0.5
        }
    });
    let evd = m.as_ref().self_adjoint_eigen(Side::Lower).unwrap();
    let lambda_min = evd.S()[0];
    let b = svec(m.as_ref());
    let id = svec(Mat::<f64>::identity(n, n).as_ref());
    let rows: Vec<usize> = (0..svec_len(n)).filter(|&k| id[k] != 0.0).collect();
    let vals: Vec<f64> = rows.iter().map(|&k| id[k]).collect();
    let a = CscMatrix::new_from_triplets(svec_len(n), 1, rows.clone(), vec![0; rows.len()], vals);
    let p = CscMatrix::zeros((1, 1));
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .unwrap();
    let mut solver = DefaultSolver::new(
        &p,
        &[-1.0],
        &a,
        &b,
        &[SupportedConeT::PSDTriangleConeT(n)],
        settings,
    )
    .unwrap();
    solver.solve();
    assert_eq!(solver.solution.status, SolverStatus::Solved);
    assert!(
        (solver.solution.x[0] - lambda_min).abs() < 1e-7,
        "{} vs {lambda_min}",
        solver.solution.x[0]
    );
    let z = smat(&solver.solution.z, n).unwrap();
    let v = evd.U().col(0);
    for i in 0..n {
        for j in 0..n {
            assert!((z[(i, j)] - v[i] * v[j]).abs() < 1e-5);
        }
    }
}

#[test]
fn noise_free_graph_is_recovered_exactly() {
    // Planted: R_ij = R_j R_i^T exactly, so f* = 0 = SDP value and X = Y Y^T is the unique
    // optimum of a connected graph; rounding recovers the ground truth (gauge R_0 = I).
    for seed in 0..3 {
        let (p, gt) = graph(10, 20, 0.0, seed);
        let sol = relax_multiple(&p, &SdpSettings::default()).unwrap();
        assert_eq!(sol.status, SdpStatus::Solved);
        // interior-point accuracy: the objectives are ~1e-6 off (the dual one even lands above
        // the true optimum 0, which is why it is never used as a bound)
        assert!(sol.dual_objective.abs() < 1e-5, "{}", sol.dual_objective);
        assert!(sol.primal_objective.abs() < 1e-5);
        assert!(max_angle(&sol.rounded, &gt) < 1e-5);
        assert!(sol.rounded_cost < 1e-9);
        assert_eq!(sol.multipliers.len(), 10);
        assert!(sol.x_top_eigenvalues[3] < 1e-6 * sol.x_top_eigenvalues[2]);
    }
}

#[test]
fn low_noise_relaxation_is_tight() {
    // Low noise (sigma = 0.05 rad per axis): the relaxation is tight (known empirically and by
    // Eriksson et al. 2018 / Rosen et al. 2019 for small noise), so the rounded estimate's cost
    // equals the SDP value to solver tolerance and X has rank 3.
    for seed in 0..3 {
        let (p, gt) = graph(15, 40, 0.05, 10 + seed);
        let sol = relax_multiple(&p, &SdpSettings::default()).unwrap();
        assert_eq!(sol.status, SdpStatus::Solved);
        let v = sol.primal_objective;
        // solver tolerance: the objectives of an interior-point solution with tol 1e-8 on the
        // scaled problem are observed ~1e-6 relative from the exact value
        let rel = (sol.rounded_cost - v) / v;
        assert!(rel.abs() < 1e-5, "rounded {} vs SDP {v}", sol.rounded_cost);
        assert!(((sol.dual_objective - v) / v).abs() < 1e-5);
        assert!(sol.x_top_eigenvalues[3] < 1e-5 * sol.x_top_eigenvalues[2]);
        // and the estimate is close to the ground truth
        assert!(max_angle(&sol.rounded, &gt) < 0.2);
        // the multipliers reproduce the dual objective (sum of traces)
        let tr: f64 = sol.multipliers.iter().map(|l| l.trace()).sum();
        assert!(((tr - sol.dual_objective) / v).abs() < 1e-9);
    }
}

#[test]
fn primal_and_dual_forms_agree() {
    // Same SDP posed two ways [P2]/[P3]: optimal values agree to solver tolerance, on a noisy
    // instance with outliers (value > 0, not necessarily tight).
    for seed in 0..2 {
        let (p, _) = SyntheticGraph {
            num_rotations: 8,
            num_edges: 16,
            noise_sigma: 0.3,
            outlier_fraction: 0.2,
            seed: 20 + seed,
        }
        .generate();
        let dual = relax_multiple(&p, &SdpSettings::default()).unwrap();
        let primal = relax_multiple(
            &p,
            &SdpSettings {
                form: SdpForm::Primal,
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(dual.status, SdpStatus::Solved);
        assert_eq!(primal.status, SdpStatus::Solved);
        let v = primal.primal_objective;
        assert!(v > 0.1);
        for w in [
            primal.dual_objective,
            dual.primal_objective,
            dual.dual_objective,
        ] {
            assert!(((w - v) / v).abs() < 1e-6, "{w} vs {v}");
        }
        // multipliers of both forms: same objective, and rounded estimates have equal cost
        let tp: f64 = primal.multipliers.iter().map(|l| l.trace()).sum();
        assert!(((tp - v) / v).abs() < 1e-6);
        assert!(((primal.rounded_cost - dual.rounded_cost) / v).abs() < 1e-4);
        // dense X (3n = 24 <= default limit) has identity diagonal blocks
        let x = dual.x_dense.as_ref().unwrap();
        for k in 0..24 {
            assert!((x[k * 24 + k] - 1.0).abs() < 1e-6);
        }
    }
}

#[test]
fn three_cycle_with_loop_error_has_closed_form_value() {
    // z_cycle(3, phi): the residual rotations around the cycle compose to a rotation by phi, so
    // their angles sum to >= phi; f = sum 8 sin^2(theta_e / 2) is minimised by the equal split
    // theta_e = phi/3 (sin^2(x/2) is convex on [0, pi/2] and any theta_e >= pi/2 alone costs
    // more), f* = 24 sin^2(phi/6). The relaxation is tight here, so the SDP value is f* too.
    let phi: f64 = 1.0;
    let p = z_cycle(3, phi);
    let want = 24.0 * (phi / 6.0).sin().powi(2);
    let sol = relax_multiple(&p, &SdpSettings::default()).unwrap();
    assert_eq!(sol.status, SdpStatus::Solved);
    assert!(((sol.dual_objective - want) / want).abs() < 1e-6);
    assert!(((sol.rounded_cost - want) / want).abs() < 1e-6);
    // each residual is phi / 3 about z
    for a in p.residual_angles(&sol.rounded) {
        assert!((a - phi / 3.0).abs() < 1e-4);
    }
}

#[test]
fn single_edge_multipliers_vanish() {
    // n = 2, one edge R_01 = R: f* = 0 at R_1 = R. Complementarity S Y = 0 with Y = [I; R] and
    // Q Y = 0 forces blkdiag(Lambda) Y = 0, i.e. Lambda = 0 (hand-checkable).
    let r = exp(&nalgebra::Vector3::new(0.3, -0.2, 0.9));
    let p = MultipleProblem::new(
        2,
        vec![Edge {
            i: 0,
            j: 1,
            rotation: r,
            weight: 2.5,
        }],
    )
    .unwrap();
    let sol = relax_multiple(&p, &SdpSettings::default()).unwrap();
    assert_eq!(sol.status, SdpStatus::Solved);
    for l in &sol.multipliers {
        assert!(l.norm() < 1e-6, "{l}");
    }
    assert!(angle_between(&sol.rounded[0], &Rotation::identity()) < 1e-12);
    assert!(angle_between(&sol.rounded[1], &r) < 1e-6);
}

#[test]
fn invalid_settings_are_rejected() {
    let (p, _) = graph(4, 5, 0.0, 1);
    let s = SdpSettings {
        tol_feas: -1.0,
        ..Default::default()
    };
    assert!(relax_multiple(&p, &s).is_err());
    let json = serde_json::to_string(&SdpSettings::default()).unwrap();
    let back: SdpSettings = serde_json::from_str(&json).unwrap();
    assert_eq!(back, SdpSettings::default());
}

/// Timing table of `paper-notes/sdp.md` (run: `cargo test --release --test suite
/// relax_multiple::timing_table -- --ignored --nocapture`). Prints, asserts only that each
/// solve converged.
#[test]
#[ignore = "benchmark table (minutes)"]
fn timing_table() {
    let only: Option<usize> = std::env::var("ROTAVG_SDP_N")
        .ok()
        .and_then(|s| s.parse().ok());
    let cases = [
        (20, 80, true),
        (40, 160, true),
        (60, 240, true),
        (100, 150, true),
        (150, 225, true),
        (200, 300, true),
        (30, 120, false),
        (30, 120, true),
    ];
    for (n, m, chordal) in cases {
        if only.is_some_and(|k| k != n) {
            continue;
        }
        let (p, _) = graph(n, m, 0.1, 7);
        let t = Instant::now();
        let sol = relax_multiple(
            &p,
            &SdpSettings {
                chordal_decomposition: chordal,
                ..Default::default()
            },
        )
        .unwrap();
        println!(
            "n={n:4} edges={m:4} chordal={chordal:5} status={:?} iters={:3} clarabel={:7.2}s total={:7.2}s rel_gap(rounded vs SDP)={:.1e}",
            sol.status,
            sol.iterations,
            sol.solver_seconds,
            t.elapsed().as_secs_f64(),
            (sol.rounded_cost - sol.primal_objective) / sol.primal_objective
        );
        assert!(sol.status.converged());
    }
}

/// [P6]: the SDP rung is predicted from the graph before Clarabel starts and refused over the
/// memory budget (issue 25: a 150-node, 600-edge graph with 20 % outliers reached 24 GB and was
/// killed). The prediction grows with the cliques; under a budget below it the certification
/// neither solves nor allocates the SDP, and says so in the ladder and the skipped reason.
#[test]
fn sdp_is_refused_over_the_memory_budget() {
    use rotavg::certify::{
        Budget, CertifyMode, CertifySettings, Outcome, Proof, Refusal, certify_multiple,
    };
    use rotavg::relax::predict_relax_multiple;
    let (sparse, _) = graph(150, 225, 0.05, 1);
    // the graph of issue 25: 20 % outliers, so that its dual certificate fails
    let (dense, _) = SyntheticGraph {
        num_rotations: 150,
        num_edges: 600,
        noise_sigma: 0.05,
        outlier_fraction: 0.2,
        seed: 25,
    }
    .generate();
    let (ps, pd) = (
        predict_relax_multiple(&sparse).unwrap(),
        predict_relax_multiple(&dense).unwrap(),
    );
    println!("sparse {ps:?}\ndense {pd:?}");
    assert!(pd.bytes > 10.0 * ps.bytes && pd.largest_clique > ps.largest_clique);
    assert!(pd.bytes > (16u64 << 30) as f64, "{pd:?}");
    let y = rotavg::multiple::solve_multiple(&dense, &Default::default())
        .unwrap()
        .rotations;
    let settings = CertifySettings {
        mode: CertifyMode::Sdp,
        budget: Budget {
            max_memory_bytes: 4 << 30,
            max_seconds: Some(600.0),
        },
        ..Default::default()
    };
    let c = certify_multiple(&dense, &y, &settings).unwrap();
    assert!(c.details.sdp.is_none(), "the SDP ran: {:?}", c.details.sdp);
    let refused = c.details.ladder.iter().any(|a| {
        a.rung == Proof::Sdp && matches!(a.outcome, Outcome::Refused(Refusal::OverBudget { .. }))
    });
    assert!(refused, "{:?}", c.details.ladder);
    let why = c.details.skipped_reason.unwrap_or_default();
    assert!(
        why.contains("SDP relaxation (Clarabel) not run") && why.contains("memory budget"),
        "{why}"
    );
}
