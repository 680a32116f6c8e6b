//! `M = D^T S D` as `3 x 3` blocks (`BlockOperator`): the operator of the coarse correction
//! (`coarse.rs`) and of the regions' comparisons, with the bounds on its products' rounding
//! that the coarse bound reads (`paper-notes/certificates.md` `[D13]`, "Groups", "Rigour").
//!
//! A product streams the blocks once, by edges (each block stands for its transpose too), one
//! column at a time: the column's entries (`3n` values, 2.4 MB at 10^5 nodes) stay in the cache
//! while the blocks stream past. Several columns per pass over the blocks by rows, with each
//! node's entries of those columns side by side, were measured slower in place (2026-12-06, the
//! 10^5-node graph of 10^6 edges: four columns in 85-100 ms against 46 ms one by one; 31-53 ms
//! in a scratch bench, where nothing else used the shared cache).

use crate::linalg::cholesky::gamma;
use nalgebra::Matrix3;

/// `M = D^T S D` as `3 x 3` blocks with bounds on its forming error and on `|| |M| ||_2`.
pub(in crate::certify::multiple) struct BlockOperator {
    diag: Vec<Matrix3<f64>>,
    edges: Vec<(usize, usize, Matrix3<f64>)>,
    /// `||fl(M) - M||_2`.
    form: f64,
    /// The largest absolute row sum of `fl(M)` (`>= || |fl(M)| ||_2`).
    row_abs: f64,
    /// Terms of the longest row of a product.
    terms: usize,
}

impl BlockOperator {
    /// `M` from its blocks: `diag[i] = fl(M_ii)`, `edges` the `(i, j, fl(M_ij))` of `i < j` or
    /// any order (each stands for `M_ij` and its transpose `M_ji`), `form_rows[i]` at least the
    /// sum over block row `i` of `||fl(M_ij) - M_ij||_2`, `max_degree` the most edges at a node.
    pub(in crate::certify::multiple) fn new(
        diag: Vec<Matrix3<f64>>,
        edges: Vec<(usize, usize, Matrix3<f64>)>,
        form_rows: &[f64],
        max_degree: usize,
    ) -> Self {
        let mut row_abs = vec![[0.0f64; 3]; diag.len()];
        let mut add = |v: usize, b: &Matrix3<f64>| {
            for (r, sum) in row_abs[v].iter_mut().enumerate() {
                *sum += b.row(r).abs().sum();
            }
        };
        for (i, j, b) in &edges {
            add(*i, b);
            add(*j, &b.transpose());
        }
        for (i, b) in diag.iter().enumerate() {
            add(i, b);
        }
        let terms = max_degree + 1;
        BlockOperator {
            diag,
            edges,
            // symmetric: ||A||_2 <= the largest block row sum of its blocks' norms (twice that)
            form: 2.0 * form_rows.iter().copied().fold(0.0, f64::max),
            // each row sum of at most 3 terms + 2 rounded additions
            row_abs: row_abs.iter().flatten().copied().fold(0.0, f64::max)
                * (1.0 + gamma(3 * terms + 2)),
            terms: 3 * terms + 2,
        }
    }

    /// `y = fl(M x)`.
    pub(in crate::certify::multiple) fn times(&self, x: &[f64], y: &mut [f64]) {
        let block =
            |v: &[f64], i: usize| nalgebra::Vector3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
        for (i, d) in self.diag.iter().enumerate() {
            let r = d * block(x, i);
            y[3 * i..3 * i + 3].copy_from_slice(r.as_slice());
        }
        for (i, j, b) in &self.edges {
            let (xi, xj) = (block(x, *i), block(x, *j));
            let (ri, rj) = (b * xj, b.transpose() * xi);
            for a in 0..3 {
                y[3 * i + a] += ri[a];
                y[3 * j + a] += rj[a];
            }
        }
    }

    /// A bound on `||fl(M x) - M x||_2` per unit of `||x||_2`.
    pub(in crate::certify::multiple) fn product_error(&self) -> f64 {
        (self.form + gamma(self.terms) * self.row_abs) * (1.0 + 1e-10)
    }

    /// The stored diagonal blocks `fl(M_ii)`.
    pub(in crate::certify::multiple) fn diagonal(&self) -> &[Matrix3<f64>] {
        &self.diag
    }

    /// The stored off-diagonal blocks `(i, j, fl(M_ij))`, each standing for its transpose too.
    pub(in crate::certify::multiple) fn blocks(&self) -> &[(usize, usize, Matrix3<f64>)] {
        &self.edges
    }

    /// `||M_stored - M||_2`: the blocks' forming error.
    pub(in crate::certify::multiple) fn form_error(&self) -> f64 {
        self.form
    }

    /// The largest absolute row sum of the stored `M` (`>= || |M| ||_2`).
    pub(in crate::certify::multiple) fn row_abs(&self) -> f64 {
        self.row_abs
    }

    /// A bound on `||M||_2`.
    pub(super) fn norm(&self) -> f64 {
        (self.row_abs + self.form) * (1.0 + 1e-10)
    }
}
