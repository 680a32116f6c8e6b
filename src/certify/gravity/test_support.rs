//! Instances and dense references shared by the planar certificates' tests (`[G3]`, `[G9]`,
//! `[G17]`).

use super::planar::PlanarForm;
use crate::multiple::anisotropic::Information;
use crate::multiple::gravity::{GravityProblem, solve_gravity};
use crate::multiple::synthetic::{SyntheticGraph, SyntheticGravity};
use crate::multiple::{MultipleProblem, MultipleSettings};
use nalgebra::{DMatrix, Matrix3, Vector3};
use rand::{Rng, SeedableRng};

/// A full-gravity problem, its solve's phases and the planar form.
pub(super) fn instance(
    n: usize,
    edges: usize,
    sigma: f64,
    seed: u64,
) -> (PlanarForm, Vec<(f64, f64)>) {
    instance_with(n, edges, sigma, seed, false)
}

/// [`instance`], with `anisotropic` information matrices of eigenvalue ratios up to `1e4` on
/// random axes (the two-view class of issue 37).
pub(super) fn instance_with(
    n: usize,
    edges: usize,
    sigma: f64,
    seed: u64,
    anisotropic: bool,
) -> (PlanarForm, Vec<(f64, f64)>) {
    let (graph, truth) = SyntheticGraph {
        num_rotations: n,
        num_edges: edges,
        noise_sigma: sigma,
        outlier_fraction: 0.0,
        seed,
    }
    .generate();
    let graph = if anisotropic {
        with_random_information(graph, seed)
    } else {
        graph
    };
    let priors = SyntheticGravity {
        noise_deg: 0.3,
        missing_fraction: 0.0,
        seed,
    }
    .priors(&truth)
    .unwrap();
    let p = GravityProblem::new(graph, priors).unwrap();
    let solution = solve_gravity(&p, &MultipleSettings::default()).unwrap();
    let form = PlanarForm::new(&p).unwrap();
    let x = PlanarForm::phases(&p, &p.to_standard(&solution.rotations));
    (form, x)
}

/// `graph` with an information matrix per edge: `Q diag(l) Q^T`, `Q` a random rotation,
/// eigenvalues `10^U(0, 4)` times `10^U(-1, 2)`.
fn with_random_information(graph: MultipleProblem, seed: u64) -> MultipleProblem {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed ^ 0x5eed);
    let info = (0..graph.num_edges())
        .map(|_| {
            let q = crate::so3::random_rotation(&mut rng).into_inner();
            let scale = 10f64.powf(rng.random_range(-1.0..2.0));
            let l = Vector3::from_fn(|_, _| scale * 10f64.powf(rng.random_range(0.0..4.0)));
            Information::new(q * Matrix3::from_diagonal(&l) * q.transpose()).unwrap()
        })
        .collect();
    graph.with_information(info).unwrap()
}

/// `S`'s real `2n x 2n` form, dense: blocks `[[re, -im], [im, re]]` and their transposes,
/// the diagonal `s_i` twice.
pub(super) fn dense_planar(form: &PlanarForm, x: &[(f64, f64)]) -> DMatrix<f64> {
    let n = form.len();
    let mut m = DMatrix::<f64>::zeros(2 * n, 2 * n);
    for &(i, j, re, im) in form.entries() {
        let block = [[re, -im], [im, re]];
        for (a, row) in block.iter().enumerate() {
            for (b, v) in row.iter().enumerate() {
                m[(2 * i + a, 2 * j + b)] += v;
                m[(2 * j + b, 2 * i + a)] += v;
            }
        }
    }
    for (i, s) in form.certificate_diagonal(x).into_iter().enumerate() {
        m[(2 * i, 2 * i)] += s;
        m[(2 * i + 1, 2 * i + 1)] += s;
    }
    m
}

pub(super) fn lambda_min(m: DMatrix<f64>) -> f64 {
    m.symmetric_eigenvalues().min()
}
