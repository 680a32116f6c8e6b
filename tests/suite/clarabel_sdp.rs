//! Links Clarabel's SDP cone against the faer-backed BLAS/LAPACK of `rotavg-lapack/` and checks
//! it solves SDPs with known optima. This test calls Clarabel directly, without rotavg, so it
//! names the routine crate itself (what any such binary must do).

#![allow(clippy::needless_range_loop)]

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettings, DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};
use rotavg_lapack as _;
use std::time::Instant;

/// Index of entry (i, j), i <= j, in Clarabel's svec (upper triangle, column by column).
fn svec_index(i: usize, j: usize) -> usize {
    j * (j + 1) / 2 + i
}

/// min tr(C X) s.t. X_ii = 1, X PSD (n x n). Variables x_(ij) = X_ij (i <= j), the PSD cone
/// holds svec(X) = (X_ii, sqrt2 X_ij) as s = b - A x.
fn solve_maxcut_like(
    n: usize,
    c: &[Vec<f64>],
    settings: DefaultSettings<f64>,
) -> (SolverStatus, f64, Vec<f64>, f64) {
    let nv = n * (n + 1) / 2;
    let s2 = 2f64.sqrt();
    let mut q = vec![0.0; nv];
    let mut trip = Vec::new();
    for j in 0..n {
        for i in 0..=j {
            let k = svec_index(i, j);
            // tr(C X) = sum_i C_ii X_ii + 2 sum_{i<j} C_ij X_ij
            q[k] = if i == j { c[i][i] } else { 2.0 * c[i][j] };
            trip.push((k, k, if i == j { -1.0 } else { -s2 }));
        }
    }
    let mut b = vec![0.0; nv];
    for i in 0..n {
        trip.push((nv + i, svec_index(i, i), 1.0));
        b.push(1.0);
    }
    let (rows, cols, vals) = trip.into_iter().fold(
        (Vec::new(), Vec::new(), Vec::new()),
        |(mut r, mut c, mut v), (i, j, x)| {
            r.push(i);
            c.push(j);
            v.push(x);
            (r, c, v)
        },
    );
    let a = CscMatrix::new_from_triplets(nv + n, nv, rows, cols, vals);
    let p = CscMatrix::zeros((nv, nv));
    let cones = [
        SupportedConeT::PSDTriangleConeT(n),
        SupportedConeT::ZeroConeT(n),
    ];
    let t = Instant::now();
    // what rotavg does next to its Clarabel call: keep the routines for order-sensitive linkers
    std::hint::black_box(rotavg_lapack::link_routines());
    let mut solver = DefaultSolver::new(&p, &q, &a, &b, &cones, settings).expect("valid problem");
    solver.solve();
    let secs = t.elapsed().as_secs_f64();
    let sol = &solver.solution;
    (sol.status, sol.obj_val, sol.x.clone(), secs)
}

fn quiet() -> DefaultSettings<f64> {
    DefaultSettingsBuilder::default()
        .verbose(false)
        .build()
        .expect("valid settings")
}

#[test]
fn triangle_sdp_has_closed_form_optimum() {
    // C = J - I (off-diagonal ones): tr(CX) = 1^T X 1 - tr X = 1^T X 1 - 3 >= -3, equality iff
    // X 1 = 0; with unit diagonal this forces three unit vectors at 120 degrees, i.e. the unique
    // optimum X* = (3I - J)/2 (off-diagonals -1/2) with value -3.
    let n = 3;
    let c: Vec<Vec<f64>> = (0..n)
        .map(|i| (0..n).map(|j| if i == j { 0.0 } else { 1.0 }).collect())
        .collect();
    let (status, obj, x, _) = solve_maxcut_like(n, &c, quiet());
    assert_eq!(status, SolverStatus::Solved);
    assert!((obj + 3.0).abs() < 1e-6, "objective {obj}");
    for j in 0..n {
        for i in 0..=j {
            let want = if i == j { 1.0 } else { -0.5 };
            assert!((x[svec_index(i, j)] - want).abs() < 1e-5);
        }
    }
}

#[test]
fn moderate_psd_cone_solves() {
    maxcut_random(30);
}

/// The timing measurement quoted in rotavg-lapack/README.md (run with `--ignored --nocapture`).
#[test]
#[ignore = "timing measurement (tens of seconds)"]
fn psd_cone_60_timing() {
    maxcut_random(60);
}

fn maxcut_random(n: usize) {
    // n x n max-cut SDP on a seeded random graph (edge probability 0.3). Reference values:
    // every feasible X gives tr(CX) >= the optimum, in particular X = I (value 0) and the
    // rank-one cut X = z z^T for the alternating z (value z^T C z);
    // we check both upper bounds.
    let mut state = 12345u64;
    let mut next = move || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut c = vec![vec![0.0; n]; n];
    for i in 0..n {
        for j in i + 1..n {
            if next() < 0.3 {
                c[i][j] = 1.0;
                c[j][i] = 1.0;
            }
        }
    }
    let (status, obj, _, secs) = solve_maxcut_like(n, &c, quiet());
    println!("{n}x{n} PSD cone max-cut SDP: {secs:.3} s, objective {obj:.6}");
    assert_eq!(status, SolverStatus::Solved);
    let z: Vec<f64> = (0..n)
        .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    let cut: f64 = (0..n)
        .flat_map(|i| (0..n).map(move |j| (i, j)))
        .map(|(i, j)| z[i] * c[i][j] * z[j])
        .sum();
    assert!(obj <= 1e-6 && obj <= cut + 1e-6);
    assert!(obj < -1.0, "a random graph has a cut better than X = I");
}
