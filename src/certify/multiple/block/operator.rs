//! The matrices the regions' factorisations and the coarse correction read, as `3 x 3` block
//! operators (`certify/multiple/coarse.rs`, `BlockOperator`): `M = D^T S D` itself (`[A15]`
//! step 1, `[A16]`) and the block comparison's `C - blkdiag(Delta)` (`[A15]` step 2).

use super::edges::{self, diagonal_block, edge_matrix};
use crate::certify::multiple::block_operator::BlockOperator;
use crate::certify::multiple::scalar::fro;
use crate::linalg::cholesky::gamma;
use crate::multiple::MultipleProblem;
use crate::multiple::anisotropic::Information;
use crate::so3::Rotation;
use nalgebra::Matrix3;

/// `M = D^T S D` of an anisotropic problem as `3 x 3` blocks (`M_ij = -E_e`, `M_ii = R_i^T
/// (sum_e F_e - sym Lambda_i) R_i`) with its forming errors.
pub(super) fn anisotropic_operator(
    problem: &MultipleProblem,
    information: &[Information],
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
) -> BlockOperator {
    let n = rotations.len();
    let mut f_sum = vec![Matrix3::zeros(); n];
    let mut traces = vec![0.0f64; n];
    let mut degree = vec![0usize; n];
    let mut form_rows = vec![0.0f64; n];
    let mut blocks = Vec::with_capacity(problem.num_edges());
    for (e, h) in problem.edges().iter().zip(information) {
        let (block, eta) = edge_matrix(h, &e.rotation, &rotations[e.i], &rotations[e.j]);
        let f = h.twice_chordal_matrix();
        for v in [e.i, e.j] {
            f_sum[v] += f;
            traces[v] += h.matrix().trace().abs();
            degree[v] += 1;
            form_rows[v] += eta;
        }
        blocks.push((e.i, e.j, -block));
    }
    let diag = (0..n)
        .map(|i| {
            let (block, err) = diagonal_block(
                &rotations[i],
                &lambdas[i],
                &f_sum[i],
                (traces[i], degree[i]),
            );
            form_rows[i] += err;
            block
        })
        .collect();
    let max_degree = degree.iter().copied().max().unwrap_or(0);
    BlockOperator::new(diag, blocks, &form_rows, max_degree)
}

/// `C - blkdiag(Delta)` of step 2 as a block operator: the kept edges' `-W_e` (stored exactly)
/// and the diagonal blocks `fl(sum_e W_e - Delta_i)`, each formed within `gamma(k + 1)` of its
/// `k` terms' Frobenius norms.
pub(super) fn comparison_operator(
    problem: &MultipleProblem,
    keep: &[bool],
    c: &edges::EdgeBlocks,
) -> BlockOperator {
    let mut diag: Vec<Matrix3<f64>> = c.delta.iter().map(|d| -d).collect();
    let mut magnitude: Vec<f64> = c.delta.iter().map(fro).collect();
    let mut terms = vec![1usize; diag.len()];
    let mut blocks = Vec::new();
    for ((e, w), _) in problem
        .edges()
        .iter()
        .zip(&c.kept)
        .zip(keep)
        .filter(|(_, k)| **k)
    {
        for v in [e.i, e.j] {
            diag[v] += w;
            magnitude[v] += fro(w);
            terms[v] += 1;
        }
        blocks.push((e.i, e.j, -w));
    }
    let form_rows: Vec<f64> = magnitude
        .iter()
        .zip(&terms)
        .map(|(m, &k)| gamma(k + 1) * m)
        .collect();
    let max_degree = terms.iter().copied().max().unwrap_or(1);
    BlockOperator::new(diag, blocks, &form_rows, max_degree)
}
