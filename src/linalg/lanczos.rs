//! Block Lanczos with full reorthogonalisation and Rayleigh-Ritz `[D7]`, `[D14]`: the one
//! eigen-*estimation* engine of the crate (extreme eigenpairs of a symmetric operator: the
//! certificate matrix `S`, its shift-inverse `(S + sigma I)^-1`, a graph Laplacian on the
//! complement of its null space). Its numbers are estimates and never enter a bound by
//! themselves: bounds come from [`super::cholesky`].
//!
//! [`lanczos`] returns the `count` extreme Ritz pairs of a Krylov subspace grown block by block
//! (block size 1 is plain Lanczos); every residual `||A x - theta x||` is exact for the
//! computed subspace (some eigenvalue of `A` lies within it of `theta`), and why it stopped is a
//! [`LanczosStop`] with the measured residual and its threshold. [`lanczos_extreme`] is the
//! one-vector convenience.
//!
//! ```
//! use rotavg::linalg::{lanczos, Extreme, LanczosSettings};
//! // Path-graph Laplacian of 30 nodes: eigenvalues 2 - 2 cos(k pi / 30), k = 0..29; the smallest
//! // (0) has the constant eigenvector. Deflating it, the smallest is 2 - 2 cos(pi / 30).
//! let n = 30;
//! let op = |x: &[f64], y: &mut [f64]| {
//!     for i in 0..n {
//!         let left = if i > 0 { x[i] - x[i - 1] } else { 0.0 };
//!         let right = if i + 1 < n { x[i] - x[i + 1] } else { 0.0 };
//!         y[i] = left + right;
//!     }
//! };
//! let ones = vec![1.0 / (n as f64).sqrt(); n];
//! let e = lanczos(n, op, Extreme::Smallest, 2, 4.0, &LanczosSettings::default(), &[ones], None);
//! let exact = |k: f64| 2.0 - 2.0 * (k * std::f64::consts::PI / n as f64).cos();
//! assert!(e.stop.converged());
//! assert!((e.values[0] - exact(1.0)).abs() < 1e-9 && (e.values[1] - exact(2.0)).abs() < 1e-9);
//! ```

use nalgebra::{DMatrix, SymmetricEigen};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use serde::{Deserialize, Serialize};
use std::fmt;

/// Which end of the spectrum to target.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Extreme {
    /// The smallest (algebraic) eigenvalues.
    Smallest,
    /// The largest (algebraic) eigenvalues.
    Largest,
}

/// Settings of [`lanczos`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LanczosSettings {
    /// Maximum Krylov subspace dimension (each basis vector is stored: memory
    /// `max_iterations * dim` values; also capped at `4e7` values).
    pub max_iterations: usize,
    /// Converged when every wanted Ritz residual `||A x - theta x|| <= tolerance *
    /// max(scale, |theta|)`, `scale` given by the caller (an estimate of `||A||`).
    pub tolerance: f64,
    /// Seed of the random start vectors.
    pub seed: u64,
    /// Block size (>= 1; 1 is plain Lanczos). A block of `b` vectors finds eigenvalues of
    /// multiplicity up to `b` (rotation averaging's certificate matrices come in threes).
    pub block_size: usize,
}

impl LanczosSettings {
    /// Checks `max_iterations >= 1`, `tolerance > 0` and `block_size >= 1`;
    /// [`crate::Error::InvalidSettings`] names `<prefix>.<field>`.
    pub fn validate(&self, prefix: &str) -> crate::Result<()> {
        crate::validate::at_least_one(&format!("{prefix}.max_iterations"), self.max_iterations)?;
        crate::validate::positive(&format!("{prefix}.tolerance"), self.tolerance)?;
        crate::validate::at_least_one(&format!("{prefix}.block_size"), self.block_size)
    }
}

impl Default for LanczosSettings {
    fn default() -> Self {
        LanczosSettings {
            max_iterations: 120,
            tolerance: 1e-10,
            seed: 0x5eed,
            block_size: 1,
        }
    }
}

/// Why [`lanczos`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "reason", rename_all = "snake_case")]
pub enum LanczosStop {
    /// Every wanted Ritz residual met its threshold.
    Converged {
        /// The largest residual divided by its `max(scale, |theta|)`.
        residual: f64,
        /// The tolerance it met.
        threshold: f64,
    },
    /// The Krylov subspace became invariant (no new direction survives
    /// reorthogonalisation): the Ritz pairs are exact up to rounding.
    InvariantSubspace {
        /// Subspace dimension reached.
        dimension: usize,
    },
    /// The subspace limit (or the dimension of the space) was reached first.
    SubspaceLimit {
        /// Subspace dimension reached.
        dimension: usize,
        /// The largest relative residual left.
        residual: f64,
        /// The tolerance it did not meet.
        threshold: f64,
    },
}

impl LanczosStop {
    /// `true` for [`LanczosStop::Converged`] and [`LanczosStop::InvariantSubspace`].
    pub fn converged(&self) -> bool {
        !matches!(self, LanczosStop::SubspaceLimit { .. })
    }
}

impl fmt::Display for LanczosStop {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LanczosStop::Converged {
                residual,
                threshold,
            } => write!(
                f,
                "converged: relative residual {residual:.3e} <= {threshold:.1e}"
            ),
            LanczosStop::InvariantSubspace { dimension } => {
                write!(f, "invariant subspace of dimension {dimension}")
            }
            LanczosStop::SubspaceLimit {
                dimension,
                residual,
                threshold,
            } => write!(
                f,
                "subspace limit {dimension} reached: relative residual {residual:.3e} > {threshold:.1e}"
            ),
        }
    }
}

/// Extreme Ritz pairs from [`lanczos`]: **estimates**, ordered from the most extreme.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EigenEstimate {
    /// Ritz values (ascending for `Smallest`, descending for `Largest`).
    pub values: Vec<f64>,
    /// Unit Ritz vectors, same order.
    pub vectors: Vec<Vec<f64>>,
    /// Residuals `||A x - theta x||`, same order.
    pub residuals: Vec<f64>,
    /// Krylov subspace dimension reached.
    pub subspace_dim: usize,
    /// Why it stopped.
    pub stop: LanczosStop,
}

/// One extreme eigenpair from [`lanczos_extreme`]: an *estimate*.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LanczosResult {
    /// Ritz value.
    pub value: f64,
    /// Unit Ritz vector.
    pub vector: Vec<f64>,
    /// Ritz residual `||A x - value x||` (a standard bound: some eigenvalue lies within it).
    pub residual: f64,
    /// Krylov dimension reached.
    pub iterations: usize,
    /// Why it stopped.
    pub stop: LanczosStop,
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// Orthogonalise `w` against `against` (each a list of orthonormal vectors) twice ("twice is
/// enough"); returns the norm before and after.
fn orthogonalize(against: &[&[Vec<f64>]], w: &mut [f64]) -> (f64, f64) {
    let before = dot(w, w).sqrt();
    for _ in 0..2 {
        for set in against {
            for v in set.iter() {
                let c = dot(v, w);
                w.iter_mut().zip(v).for_each(|(x, y)| *x -= c * y);
            }
        }
    }
    (before, dot(w, w).sqrt())
}

/// The `count` extreme eigenpairs (estimates) of the symmetric operator `op(x, y): y = A x` of
/// dimension `dim`, restricted to the orthogonal complement of the orthonormal vectors
/// `deflate` (pass `&[]` for none; `A` should leave that complement invariant, e.g. a
/// Laplacian and its constant null vector). Block Lanczos with full reorthogonalisation and
/// Rayleigh-Ritz on the whole basis, block size `settings.block_size`; `start` seeds the first
/// block (randomly perturbed, so a start orthogonal to the target still works). The residual of
/// each Ritz pair is computed from the block's remainder `(I - V V^T) A V c` (exact for the
/// computed subspace). `scale` is an estimate of `||A||` for the relative tests.
#[allow(clippy::too_many_arguments)]
pub fn lanczos(
    dim: usize,
    mut op: impl FnMut(&[f64], &mut [f64]),
    which: Extreme,
    count: usize,
    scale: f64,
    settings: &LanczosSettings,
    deflate: &[Vec<f64>],
    start: Option<&[f64]>,
) -> EigenEstimate {
    let each = |block: &[Vec<f64>]| -> Vec<Vec<f64>> {
        let image = |v: &Vec<f64>| {
            let mut w = vec![0.0; v.len()];
            op(v, &mut w);
            w
        };
        block.iter().map(image).collect()
    };
    lanczos_blocks(dim, each, which, count, scale, settings, deflate, start)
}

/// [`lanczos`] with the operator applied to a block at once, `op(vs)` the images `A v` of the
/// vectors `vs` (at most `settings.block_size` of them): one pass over a factor for a block of
/// solves (shift-invert, the large rigs' search: three right-hand sides per pass).
#[allow(clippy::too_many_arguments)]
pub(crate) fn lanczos_blocks(
    dim: usize,
    mut op: impl FnMut(&[Vec<f64>]) -> Vec<Vec<f64>>,
    which: Extreme,
    count: usize,
    scale: f64,
    settings: &LanczosSettings,
    deflate: &[Vec<f64>],
    start: Option<&[f64]>,
) -> EigenEstimate {
    let space = dim.saturating_sub(deflate.len());
    let k = count.min(space);
    if k == 0 {
        return EigenEstimate {
            values: vec![],
            vectors: vec![],
            residuals: vec![],
            subspace_dim: 0,
            stop: LanczosStop::InvariantSubspace { dimension: 0 },
        };
    }
    let b = settings.block_size.clamp(1, space);
    let mem_cap = (40_000_000 / dim.max(1)).max(k + b);
    let limits = Limits {
        k,
        max_m: settings.max_iterations.max(k).min(mem_cap).min(space),
        tol: settings.tolerance,
    };
    let scale = scale.abs().max(f64::MIN_POSITIVE);
    let mut krylov = Krylov::start(dim, b, settings.seed, start, scale);
    let mut next_check = 0;
    loop {
        let first = krylov.basis.len();
        let images = krylov.extend(&mut op, deflate, limits.max_m);
        let m = krylov.basis.len();
        // remainders (I - V V^T) A v_j of the new block: the next block, and the residuals
        let remainders: Vec<Vec<f64>> = images
            .into_iter()
            .map(|mut w| {
                orthogonalize(&[deflate, &krylov.basis], &mut w);
                w
            })
            .collect();
        let invariant = remainders.iter().all(|r| dot(r, r).sqrt() <= 1e-14 * scale);
        // Rayleigh-Ritz (a dense eigendecomposition of the whole projected matrix) on a
        // geometric schedule, an eighth of the basis apart, and before every stop: done at
        // every step its cost grows as m^4 and dominates long runs
        let due = m >= next_check || invariant || m >= limits.max_m || m == first;
        if !due {
            krylov.refill(remainders);
            continue;
        }
        next_check = m + (m / 8).max(b);
        let (values, coefficients, residuals) =
            rayleigh_ritz(&krylov.h, k, which, first, &remainders);
        let worst = values
            .iter()
            .zip(&residuals)
            .map(|(v, r)| r / scale.max(v.abs()))
            .fold(0.0, f64::max);
        if let Some(stop) = limits.stop(values.len(), worst, invariant, m, first) {
            return EigenEstimate {
                vectors: coefficients
                    .iter()
                    .map(|c| ritz_vector(&krylov.basis, c))
                    .collect(),
                values,
                residuals,
                subspace_dim: m,
                stop,
            };
        }
        krylov.refill(remainders);
    }
}

/// What ends a [`lanczos`] run: `k` wanted pairs, at most `max_m` basis vectors, the relative
/// residual tolerance `tol`.
struct Limits {
    k: usize,
    max_m: usize,
    tol: f64,
}

impl Limits {
    /// Why the run stops after a Rayleigh-Ritz step that found `found` pairs with the largest
    /// relative residual `worst` on a basis of `m` vectors (`first` before the last block), if
    /// it does.
    fn stop(
        &self,
        found: usize,
        worst: f64,
        invariant: bool,
        m: usize,
        first: usize,
    ) -> Option<LanczosStop> {
        if found == self.k && worst <= self.tol {
            Some(LanczosStop::Converged {
                residual: worst,
                threshold: self.tol,
            })
        } else if invariant && m >= self.k {
            Some(LanczosStop::InvariantSubspace { dimension: m })
        } else if m >= self.max_m || m == first {
            Some(LanczosStop::SubspaceLimit {
                dimension: m,
                residual: worst,
                threshold: self.tol,
            })
        } else {
            None
        }
    }
}

/// The Krylov basis of a [`lanczos`] run, its projected matrix and the block waiting to join.
struct Krylov {
    dim: usize,
    /// A norm estimate: a remainder below `1e-14 scale` is a deflated direction.
    scale: f64,
    rng: StdRng,
    basis: Vec<Vec<f64>>,
    /// `h[j][i] = v_i^T A v_j` for `i <= j`.
    h: Vec<Vec<f64>>,
    pending: Vec<Vec<f64>>,
}

impl Krylov {
    /// The first block of `b` vectors: `start` (randomly perturbed, so a start orthogonal to
    /// the target still works) when given and nonzero, then random vectors from `seed`.
    fn start(dim: usize, b: usize, seed: u64, start: Option<&[f64]>, scale: f64) -> Krylov {
        let mut rng = StdRng::seed_from_u64(seed);
        let mut pending: Vec<Vec<f64>> = Vec::with_capacity(b);
        if let Some(s) = start.filter(|s| s.len() == dim && s.iter().any(|x| *x != 0.0)) {
            pending.push(
                s.iter()
                    .map(|x| x + 1e-3 * (rng.random::<f64>() - 0.5) / (dim as f64).sqrt())
                    .collect(),
            );
        }
        let mut krylov = Krylov {
            dim,
            scale,
            rng,
            basis: Vec::new(),
            h: Vec::new(),
            pending,
        };
        while krylov.pending.len() < b {
            let r = krylov.random();
            krylov.pending.push(r);
        }
        krylov
    }

    fn random(&mut self) -> Vec<f64> {
        (0..self.dim)
            .map(|_| self.rng.random::<f64>() - 0.5)
            .collect()
    }

    /// Add the pending block (orthonormalised against `deflate` and the basis; a vector that
    /// does not survive is dropped) while the basis holds fewer than `max_m` vectors, and
    /// apply the operator to the vectors added, at once: their images `A v`.
    fn extend(
        &mut self,
        op: &mut impl FnMut(&[Vec<f64>]) -> Vec<Vec<f64>>,
        deflate: &[Vec<f64>],
        max_m: usize,
    ) -> Vec<Vec<f64>> {
        let first = self.basis.len();
        for mut v in std::mem::take(&mut self.pending) {
            if self.basis.len() >= max_m {
                break;
            }
            let (before, after) = orthogonalize(&[deflate, &self.basis], &mut v);
            if !(after.is_finite() && after > 1e-10 * before) {
                continue;
            }
            v.iter_mut().for_each(|x| *x /= after);
            self.basis.push(v);
        }
        if self.basis.len() == first {
            return Vec::new();
        }
        let images = op(&self.basis[first..]);
        for (p, w) in (first..).zip(&images) {
            let row = self.basis[..=p].iter().map(|vi| dot(vi, w)).collect();
            self.h.push(row);
        }
        images
    }

    /// The next block: the remainders; a random vector replaces a deflated one, and stands in
    /// for an empty block.
    fn refill(&mut self, remainders: Vec<Vec<f64>>) {
        for r in remainders {
            let n = dot(&r, &r).sqrt();
            if n > 1e-14 * self.scale {
                self.pending.push(r);
            } else {
                let r = self.random();
                self.pending.push(r);
            }
        }
        if self.pending.is_empty() {
            let r = self.random();
            self.pending.push(r);
        }
    }
}

/// Rayleigh-Ritz on the basis `V` with `V^T A V` in `h`: the `k` most extreme Ritz values,
/// their coefficient vectors `c` (Ritz vector `V c`), and their residuals `||sum_j c_j r_j||`
/// over the last block (columns `first..`) with remainders `r_j` (the other columns'
/// remainders are in the span of `V`).
#[allow(clippy::type_complexity)]
fn rayleigh_ritz(
    h: &[Vec<f64>],
    k: usize,
    which: Extreme,
    first: usize,
    remainders: &[Vec<f64>],
) -> (Vec<f64>, Vec<Vec<f64>>, Vec<f64>) {
    let m = h.len();
    let t = DMatrix::<f64>::from_fn(m, m, |i, j| {
        let (lo, hi) = if i <= j { (i, j) } else { (j, i) };
        h[hi][lo]
    });
    let eig = SymmetricEigen::new(t);
    let mut idx: Vec<usize> = (0..m).collect();
    idx.sort_by(|&p, &q| {
        let (a, b) = (eig.eigenvalues[p], eig.eigenvalues[q]);
        match which {
            Extreme::Smallest => a.total_cmp(&b),
            Extreme::Largest => b.total_cmp(&a),
        }
    });
    let dim = remainders.first().map_or(0, Vec::len);
    let mut values = Vec::with_capacity(k);
    let mut coefficients = Vec::with_capacity(k);
    let mut residuals = Vec::with_capacity(k);
    for &i in idx.iter().take(k) {
        let c: Vec<f64> = eig.eigenvectors.column(i).iter().copied().collect();
        let mut r = vec![0.0; dim];
        for (j, rem) in remainders.iter().enumerate() {
            let cj = c[first + j];
            r.iter_mut().zip(rem).for_each(|(ri, x)| *ri += cj * x);
        }
        values.push(eig.eigenvalues[i]);
        residuals.push(dot(&r, &r).sqrt());
        coefficients.push(c);
    }
    (values, coefficients, residuals)
}

/// The unit Ritz vector `V c / ||V c||`.
fn ritz_vector(basis: &[Vec<f64>], c: &[f64]) -> Vec<f64> {
    let dim = basis.first().map_or(0, Vec::len);
    let mut x = vec![0.0; dim];
    for (cj, v) in c.iter().zip(basis) {
        x.iter_mut().zip(v).for_each(|(xi, vi)| *xi += cj * vi);
    }
    let nx = dot(&x, &x).sqrt();
    if nx > 0.0 {
        x.iter_mut().for_each(|xi| *xi /= nx);
    }
    x
}

/// The most extreme eigenpair (estimate) of `op` by plain Lanczos ([`lanczos`] with block size
/// 1, one wanted pair, no deflation). `value >= lambda_min` for `Smallest` in exact arithmetic
/// (Cauchy interlacing).
pub fn lanczos_extreme(
    dim: usize,
    op: impl FnMut(&[f64], &mut [f64]),
    which: Extreme,
    scale: f64,
    settings: &LanczosSettings,
    start: Option<&[f64]>,
) -> LanczosResult {
    let one = LanczosSettings {
        block_size: 1,
        ..*settings
    };
    let e = lanczos(dim, op, which, 1, scale, &one, &[], start);
    LanczosResult {
        value: e.values.first().copied().unwrap_or(0.0),
        vector: e.vectors.into_iter().next().unwrap_or_default(),
        residual: e.residuals.first().copied().unwrap_or(0.0),
        iterations: e.subspace_dim,
        stop: e.stop,
    }
}

/// [`lanczos_extreme`] for the smallest eigenpair of a sparse symmetric matrix (both triangles
/// stored), with `scale` an estimate of its norm.
pub fn smallest_eigenpair(
    a: faer::sparse::SparseColMatRef<'_, usize, f64>,
    scale: f64,
    settings: &LanczosSettings,
) -> LanczosResult {
    lanczos_extreme(
        a.nrows(),
        |x, y| super::cholesky::sparse_matvec(a, x, y),
        Extreme::Smallest,
        scale,
        settings,
        None,
    )
}
