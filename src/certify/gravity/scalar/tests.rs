//! `[G9]` checked against dense eigenvalues: whenever the scalar comparison on the embedding
//! proves `lambda_min(S) >= mu`, the smallest eigenvalue of `S`'s real form, formed here from
//! the planar entries independently of the embedding and computed densely, is at least `mu`;
//! the embedding's certificate matrix is `S`'s real form plus a positive semidefinite scalar
//! Laplacian; and noise-free data are proven to the target.

use super::*;
use crate::certify::gravity::test_support::{dense_planar, instance, lambda_min};
use crate::multiple::laplacian::edge_blocks;
use nalgebra::DMatrix;

#[test]
fn every_proven_bound_is_below_the_dense_smallest_eigenvalue() {
    let (mut proved, mut tried, mut negative, mut tightest) = (0, 0, 0, f64::INFINITY);
    for seed in 0..24u64 {
        let n = 8 + (seed as usize % 5) * 6;
        // from noise-free to noisy: the comparison fails on some, which proves nothing
        let sigma = [0.0, 0.02, 0.1, 0.3][seed as usize % 4];
        let (form, optimal) = instance(n, 3 * n, sigma, seed);
        // the solve's phases, and phases turned away from them (S then has negative
        // eigenvalues, which a sound proof must not hide)
        for turn in [0.0, 0.01, 0.1, 0.5] {
            let x: Vec<(f64, f64)> = optimal
                .iter()
                .enumerate()
                .map(|(i, &(c, s))| {
                    let t = s.atan2(c) + turn * ((i as f64 * 2.39).sin());
                    (t.cos(), t.sin())
                })
                .collect();
            let e = embed(&form, &x).unwrap();
            let analysis = ScalarAnalysis::new(&e.problem, usize::MAX)
                .unwrap()
                .unwrap();
            let exact = lambda_min(dense_planar(&form, &x));
            // a large target (easy to prove) as well as the tolerance's
            for gap in [1e-9, 1e-3, 1.0, 1e3] {
                tried += 1;
                let Ok(mu) = prove(&e, &analysis, gap).unwrap() else {
                    continue;
                };
                proved += 1;
                if exact < -1e-6 {
                    negative += 1;
                    tightest = tightest.min(mu / exact);
                }
                assert!(
                    mu <= exact + 1e-12 * (1.0 + exact.abs()),
                    "seed {seed}, turn {turn}: proven {mu:e} above lambda_min {exact:e}"
                );
            }
        }
    }
    eprintln!(
        "{proved} proofs in {tried} tries, {negative} of a clearly indefinite S (the tightest \
         at mu = {tightest:.3} lambda_min)"
    );
    assert!(proved * 3 >= tried, "{proved} proofs in {tried} tries");
}

/// The embedding's certificate matrix `Q - blkdiag(Lambda)` (formed from the embedded
/// problem by the multiple problem's own blocks) is `S`'s real form in the first two
/// coordinates of every node and the weights' scalar Laplacian in the third.
#[test]
fn the_embedding_is_the_planar_matrix_plus_a_laplacian() {
    let (form, x) = instance(12, 30, 0.1, 3);
    let e = embed(&form, &x).unwrap();
    let n = form.len();
    let mut q = DMatrix::<f64>::zeros(3 * n, 3 * n);
    for (i, j, a, b, c) in edge_blocks(&e.problem) {
        for r in 0..3 {
            for s in 0..3 {
                q[(3 * i + r, 3 * i + s)] += a[(r, s)];
                q[(3 * j + r, 3 * j + s)] += b[(r, s)];
                q[(3 * i + r, 3 * j + s)] += c[(r, s)];
                q[(3 * j + s, 3 * i + r)] += c[(r, s)];
            }
        }
    }
    for (i, l) in e.lambdas.iter().enumerate() {
        for r in 0..3 {
            for s in 0..3 {
                q[(3 * i + r, 3 * i + s)] -= l[(r, s)];
            }
        }
    }
    let planar = dense_planar(&form, &x);
    let scale = planar.amax();
    for i in 0..n {
        for j in 0..n {
            for r in 0..2 {
                for s in 0..2 {
                    let d = q[(3 * i + r, 3 * j + s)] - planar[(2 * i + r, 2 * j + s)];
                    assert!(d.abs() <= 1e-13 * scale, "({i}, {j}) off by {d:e}");
                }
                assert_eq!(q[(3 * i + r, 3 * j + 2)], 0.0);
            }
        }
    }
    // the third coordinates: a Laplacian (rows summing to zero, nonpositive off the diagonal)
    for i in 0..n {
        let row: f64 = (0..n).map(|j| q[(3 * i + 2, 3 * j + 2)]).sum();
        assert!(row.abs() <= 1e-13 * scale);
    }
}

#[test]
fn noise_free_data_are_proven_to_the_target() {
    let (form, x) = instance(40, 120, 0.0, 9);
    let e = embed(&form, &x).unwrap();
    let analysis = ScalarAnalysis::new(&e.problem, usize::MAX)
        .unwrap()
        .unwrap();
    let gap = 1e-8;
    let mu = prove(&e, &analysis, gap).unwrap().unwrap();
    assert!(mu <= 0.0 && 40.0 * -mu <= gap, "mu {mu:e}");
}
