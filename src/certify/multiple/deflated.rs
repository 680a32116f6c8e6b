//! The coarse space of a deflated comparison (the regional bound `[A16]`, "Deflation", and the
//! grouped scalar comparison `[D13]`, "Deflated components"): per region `r` the columns
//! `F_r = [E_r, W_r]`, its three constant directions `E_r = 1 (x) I_3` and the directions
//! `W_r` its factorisation deflated (sparse, none in most regions). `U = {x : F_r^T x_r = 0
//! for every r}`, its projector `x - F G^{-1} F^T x` (`G_r = F_r^T F_r`), and `|a_r| <=
//! |x_r| / lambda_min(G_r)^{1/2}` for the coefficients `a_r = G_r^{-1} F_r^T x_r` of any `x`
//! (`F_r G_r^{-1} F_r^T` is a projector), with `lambda_min(G_r)` proven.

use crate::certify::multiple::coarse::{CoarseSpace, Layout, verified_min_eigenvalue};
use crate::linalg::UNIT_ROUNDOFF as U;
use crate::linalg::cholesky::gamma;
use nalgebra::{DMatrix, DVector};

/// A sparse column: `(coordinate, value)` in the whole vector's numbering.
pub(in crate::certify::multiple) type Column = Vec<(usize, f64)>;

/// The regions and their columns (see the module's note).
pub(in crate::certify::multiple) struct RegionSpace<'a> {
    /// The regions; `kappa = max_r lambda_min(G_r)^{-1/2}`, `kappa_last` the last region's.
    layout: Layout<'a>,
    size: Vec<usize>,
    /// Per region, its deflated directions.
    extra: Vec<Vec<Column>>,
    /// Per region, `G_r^{-1}` as computed (only the coefficients' choice: any is valid).
    inverse: Vec<DMatrix<f64>>,
    /// Per region, a proven lower bound on `lambda_min(G_r)` (positive).
    gram_low: Vec<f64>,
}

impl<'a> RegionSpace<'a> {
    /// `None` when a region's columns are not proven independent.
    pub(in crate::certify::multiple) fn new(
        of: &'a [usize],
        extra: Vec<Vec<Column>>,
    ) -> Option<Self> {
        let count = of.iter().max().map_or(1, |m| m + 1);
        let mut size = vec![0usize; count];
        of.iter().for_each(|&g| size[g] += 1);
        let (mut inverse, mut gram_low) = (Vec::with_capacity(count), Vec::with_capacity(count));
        for (g, cols) in extra.iter().enumerate().take(count) {
            let (gram, err) = gram(size[g], cols);
            let low = verified_min_eigenvalue(&gram)? - err;
            if low <= 0.0 || !low.is_finite() {
                return None;
            }
            inverse.push(gram.try_inverse()?);
            gram_low.push(low);
        }
        if extra.len() != count {
            return None;
        }
        let kappa_of = |low: f64| (1.0 / low).sqrt() * (1.0 + 8.0 * U);
        let kappa = gram_low.iter().map(|&l| kappa_of(l)).fold(0.0, f64::max);
        let kappa_last = kappa_of(*gram_low.last()?);
        Some(RegionSpace {
            layout: Layout {
                of,
                count,
                kappa,
                kappa_last,
            },
            size,
            extra,
            inverse,
            gram_low,
        })
    }

    /// Per region, `fl(F_r^T z)` and `|F_r|^T |z|` (its error is at most `gamma(|r| + 2)` of
    /// the latter's entries: sums of at most `|r|` products).
    fn products(&self, z: &[f64]) -> Vec<(DVector<f64>, DVector<f64>)> {
        let magnitudes = self.accumulate(z, |w, v| (w * v).abs());
        self.sums(z).into_iter().zip(magnitudes).collect()
    }

    /// Per region, `fl(F_r^T z)` alone (the projection's hot path, twice per product of the
    /// coarse correction's iterations).
    fn sums(&self, z: &[f64]) -> Vec<DVector<f64>> {
        self.accumulate(z, |w, v| w * v)
    }

    /// Per region, the sums of `term(w, z_i)` over `F_r`'s entries `w` (`1` for the constant
    /// directions), each column's terms summed from zero in the entries' order.
    fn accumulate(&self, z: &[f64], term: impl Fn(f64, f64) -> f64) -> Vec<DVector<f64>> {
        let mut out: Vec<DVector<f64>> = self
            .extra
            .iter()
            .map(|cols| DVector::zeros(3 + cols.len()))
            .collect();
        for (i, &g) in self.layout.of.iter().enumerate() {
            for a in 0..3 {
                out[g][a] += term(1.0, z[3 * i + a]);
            }
        }
        for (g, cols) in self.extra.iter().enumerate() {
            for (k, col) in cols.iter().enumerate() {
                out[g][3 + k] += col.iter().map(|&(idx, w)| term(w, z[idx])).sum::<f64>();
            }
        }
        out
    }

    /// The coefficients `c_r = G_r^{-1} F_r^T y` that [`CoarseSpace::project`] subtracts.
    fn coefficients(&self, y: &[f64]) -> Vec<DVector<f64>> {
        self.sums(y)
            .into_iter()
            .zip(&self.inverse)
            .map(|(v, inv)| inv * v)
            .collect()
    }

    /// The target of coarse column `col`: `E` of region `col / 3` (`col < 3 (k - 1)`), then
    /// the regions' deflated directions in order.
    fn target(&self, col: usize) -> Vec<f64> {
        let mut t = vec![0.0; 3 * self.layout.of.len()];
        let flux = 3 * (self.layout.count - 1);
        if col < flux {
            for (i, &g) in self.layout.of.iter().enumerate() {
                if g == col / 3 {
                    t[3 * i + col % 3] = 1.0;
                }
            }
        } else if let Some(c) = self.extra.iter().flatten().nth(col - flux) {
            c.iter().for_each(|&(idx, w)| t[idx] = w);
        }
        t
    }
}

/// `G = F^T F` of a region of `n` nodes with its deflated columns (`E^T E = n I` exactly) and
/// a bound on the Frobenius norm of its rounding.
fn gram(n: usize, cols: &[Column]) -> (DMatrix<f64>, f64) {
    let d = 3 + cols.len();
    let mut g = DMatrix::zeros(d, d);
    let mut err_sq = 0.0f64;
    for a in 0..3 {
        g[(a, a)] = n as f64;
    }
    let dense: Vec<std::collections::HashMap<usize, f64>> =
        cols.iter().map(|c| c.iter().copied().collect()).collect();
    for (k, col) in cols.iter().enumerate() {
        let e = gamma(col.len() + 2);
        for a in 0..3 {
            let (s, mag) = col
                .iter()
                .filter(|(idx, _)| idx % 3 == a)
                .fold((0.0, 0.0), |(s, m), (_, w)| (s + w, m + w.abs()));
            g[(a, 3 + k)] = s;
            g[(3 + k, a)] = s;
            err_sq += 2.0 * (e * mag).powi(2);
        }
        for (l, other) in dense.iter().enumerate() {
            let (s, mag) = col.iter().fold((0.0, 0.0), |(s, m), (idx, w)| {
                let p = w * other.get(idx).copied().unwrap_or(0.0);
                (s + p, m + p.abs())
            });
            g[(3 + k, 3 + l)] = s;
            err_sq += (e * mag).powi(2);
        }
    }
    let g = (&g + g.transpose()) * 0.5;
    let err = err_sq.sqrt() + 2.0 * U * g.norm();
    (g, err * (1.0 + 1e-10))
}

impl CoarseSpace for RegionSpace<'_> {
    fn layout(&self) -> &Layout<'_> {
        &self.layout
    }

    fn extra_columns(&self) -> Vec<Vec<f64>> {
        let flux = 3 * (self.layout.count - 1);
        let total: usize = self.extra.iter().map(Vec::len).sum();
        (flux..flux + total).map(|c| self.target(c)).collect()
    }

    fn project(&self, z: &mut [f64]) {
        let c = self.coefficients(z);
        for (i, &g) in self.layout.of.iter().enumerate() {
            for a in 0..3 {
                z[3 * i + a] -= c[g][a];
            }
        }
        for (g, cols) in self.extra.iter().enumerate() {
            for (k, col) in cols.iter().enumerate() {
                for &(idx, w) in col {
                    z[idx] -= w * c[g][3 + k];
                }
            }
        }
    }

    /// Each entry of `p` is a sum of `y_i`, `-c_E` and at most `q` products `-w c_k` (`q` a
    /// region's deflated directions): its error at most `gamma(q + 2)` of their magnitudes.
    fn projection_error(&self, y: &[f64], p: &[f64]) -> f64 {
        let c = self.coefficients(y);
        let q = self.extra.iter().map(Vec::len).max().unwrap_or(0);
        let y_norm = y.iter().map(|v| v * v).sum::<f64>().sqrt();
        let mean: f64 = (0..self.layout.count)
            .map(|g| self.size[g] as f64 * c[g].rows(0, 3).norm_squared())
            .sum::<f64>()
            .sqrt();
        let products: f64 = self
            .extra
            .iter()
            .enumerate()
            .flat_map(|(g, cols)| {
                let c = &c[g];
                cols.iter().enumerate().map(move |(k, col)| {
                    c[3 + k].abs() * col.iter().map(|(_, w)| w * w).sum::<f64>().sqrt()
                })
            })
            .sum();
        let p_norm = p.iter().map(|v| v * v).sum::<f64>().sqrt();
        (gamma(q + 2) * (y_norm + mean + products) + U * p_norm) * (1.0 + gamma(p.len() + 2))
    }

    /// `||(I - P) d||^2 = sum_r v_r^T G_r^{-1} v_r <= sum_r |v_r|^2 / lambda_min(G_r)` for
    /// `v_r = F_r^T d_r`, `d = z - target`; `fl(v_r)` errs by `gamma(|r| + 3)` of `|F_r|^T |fl(d)|`
    /// (the subtraction's rounding included).
    fn off_space(&self, z: &[Vec<f64>]) -> f64 {
        let mut total = 0.0f64;
        for (col, zc) in z.iter().enumerate() {
            let t = self.target(col);
            let d: Vec<f64> = zc.iter().zip(&t).map(|(a, b)| a - b).collect();
            for (g, (v, mag)) in self.products(&d).into_iter().enumerate() {
                // a deflated column's product: at most `3 |r|` terms
                let e = gamma(3 * self.size[g] + 3);
                let norm = v.norm() * (1.0 + gamma(v.len() + 1)) + e * mag.norm() * (1.0 + e);
                total += norm * norm / self.gram_low[g];
            }
        }
        total.sqrt() * (1.0 + gamma(2 * self.layout.count + 8))
    }
}

/// A deflated direction scaled by a power of two (upward only: no entry may round by
/// underflowing) to about the constant directions' norm `n^{1/2}`: exactly the same span.
pub(in crate::certify::multiple) fn scaled_to_constant(column: Column, n: usize) -> Column {
    let norm = column.iter().map(|(_, v)| v * v).sum::<f64>().sqrt();
    let scale = ((n as f64).sqrt() / norm).log2().round().exp2().max(1.0);
    column.into_iter().map(|(r, v)| (r, v * scale)).collect()
}
