//! The SO(2) dual certificate of the full-gravity problem (`paper-notes/gravity.md`, `[G2]`,
//! `[G3]`): with every image's gravity known, `R_i = F_i Rz(theta_i)` (standard convention),
//! and the chordal cost is `f = c_0 + x^H H x` over unit complex numbers `x_i = e^{i theta_i}`
//! (`c_0` fixed by the priors, `H` Hermitian `n x n` with the graph's sparsity). For any real
//! multipliers `lambda`, `f* >= c_0 + sum lambda_i + n min(lambda_min(H - diag lambda), 0)`; at the
//! estimate's phases `lambda_i = Re(conj(x_i) (H x)_i)` make `S = H - diag lambda` vanish on
//! `x`, and `S >= 0` certifies it. `lambda_min(S)` is proven by a shifted sparse Cholesky of
//! `S`'s real `2n x 2n` form (`[D5]`, `[D6]`).

use crate::certify::budget::{Budget, Deadline};
use crate::certify::multiple::multipliers::data_defect;
use crate::error::Result;
use crate::linalg::cholesky::gamma;
use crate::linalg::compensated::Accumulator;
use crate::linalg::{
    Extreme, LanczosSettings, ShiftedCholesky, UNIT_ROUNDOFF, lanczos_extreme, sparse_matvec,
};
use crate::multiple::gravity::{GravityProblem, yaw};
use crate::multiple::laplacian::edge_blocks;
use crate::so3::Rotation;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::{Matrix3, Matrix3x2, Vector3};

/// The full-gravity cost in its planar form `[G2]`: `f = c_0 + x^H H x` on `|x_i| = 1`.
pub struct PlanarForm {
    n: usize,
    /// `K = c_0 + sum_i d_i` (`c_0` and `H`'s diagonal: on unit `x` both are constants) as an
    /// unevaluated double-double sum (it cancels against `sum s_i` to the cost, `1e5` times
    /// smaller on confident information) and a bound on its distance to `K` of the exact data
    /// (the compensated sum's error and the blocks' forming error, `[G3]`).
    constant: (f64, f64),
    constant_error: f64,
    /// Per node, a bound on every row sum of `|S_exact - S^|` over the row's off-diagonal
    /// entries (the forming error of `H_ij` from the exact data, `[G3]`; the diagonal is exact
    /// by definition).
    forming: Vec<f64>,
    /// The off-diagonal entries `H_ij` (`i < j` not required; both orders summed): `(i, j,
    /// re, im)` per edge.
    entries: Vec<(usize, usize, f64, f64)>,
    /// The most edges at one node (for the forming error of `S`'s entries).
    max_degree: usize,
    /// An upper bound on `||Q||_2` and on the frames' distance to exact frames (`[G3]`, the
    /// frame term).
    q_norm: f64,
    frame_defect: f64,
}

/// The first two columns of `f` (`B_i`, a basis of the plane orthogonal to `g_i`).
fn basis(f: &Matrix3<f64>) -> Matrix3x2<f64> {
    f.fixed_columns::<2>(0).into()
}

/// `sum |m_kl|`.
fn abs_sum(m: &Matrix3<f64>) -> f64 {
    m.iter().map(|v| v.abs()).sum()
}

impl PlanarForm {
    /// The planar form of a full-gravity problem (standard convention), `None` when some image
    /// has no prior.
    pub fn new(problem: &GravityProblem) -> Option<Self> {
        let n = problem.problem().num_rotations();
        let frames: Vec<Matrix3<f64>> = (0..n)
            .map(|i| problem.frame(i).map(|f| f.into_inner()))
            .collect::<Option<_>>()?;
        let graph = problem.problem();
        let mut degree = vec![0usize; n];
        let mut row_abs = vec![0.0f64; n];
        let mut forming = vec![0.0f64; n];
        let (mut constant, mut forming_constant) = (Accumulator::default(), 0.0);
        let mut entries = Vec::with_capacity(graph.num_edges());
        let multiplicity = pair_multiplicity(graph);
        let per_entry_sum = if graph.information().is_some() {
            1.0
        } else {
            1.0 / 3.0
        };
        for (k, (i, j, a, b, c)) in edge_blocks(graph).enumerate() {
            let (fi, fj) = (&frames[i], &frames[j]);
            let (gi, gj) = (fi.column(2), fj.column(2));
            let (bi, bj) = (basis(fi), basis(fj));
            // K's edge terms, every product error-free: g_i^T a g_i + tr(B_i^T a B_i) + (j, b)
            // + 2 g_i^T c g_j
            for (u, m, v, w) in [(gi, &a, gi, 1.0), (gj, &b, gj, 1.0), (gi, &c, gj, 2.0)] {
                add_form(&mut constant, &u.clone_owned(), m, &v.clone_owned(), w);
            }
            for col in 0..2 {
                let (ui, uj) = (bi.column(col).clone_owned(), bj.column(col).clone_owned());
                add_form(&mut constant, &ui, &a, &ui, 1.0);
                add_form(&mut constant, &uj, &b, &uj, 1.0);
            }
            // T_e >= tr(H_e) (anisotropic: sum |2M| >= |tr 2M| = tr H) or w (isotropic: 2M = w I)
            // bounds the blocks' forming error
            let t = abs_sum(&a).max(abs_sum(&b)) * per_entry_sum * (1.0 + 1e-10);
            forming_constant += CONSTANT_FORMING * t;
            let entry = (ENTRY_FORMING + PAIR_FORMING * (multiplicity[k] - 1) as f64) * t;
            forming[i] += 2.0 * entry;
            forming[j] += 2.0 * entry;
            let m = bi.transpose() * c * bj;
            entries.push((i, j, m[(0, 0)] + m[(1, 1)], m[(1, 0)] - m[(0, 1)]));
            degree[i] += 1;
            degree[j] += 1;
            row_abs[i] += abs_sum(&a) + abs_sum(&c);
            row_abs[j] += abs_sum(&b) + abs_sum(&c);
        }
        let u = UNIT_ROUNDOFF;
        let inflate = 1.0 + gamma(n + graph.num_edges() + 4);
        forming.iter_mut().for_each(|f| *f *= u * inflate);
        let frame_defect = (0..n)
            .map(|i| {
                let f = &frames[i];
                let g = problem.priors().direction(i).unwrap_or(Vector3::z());
                (f.transpose() * f - Matrix3::identity()).norm() + (f.column(2) - g).norm()
            })
            .fold(0.0, f64::max)
            + 8.0 * UNIT_ROUNDOFF;
        Some(PlanarForm {
            n,
            constant: constant.parts(),
            constant_error: constant.parts_bound() + forming_constant * u * inflate,
            forming,
            entries,
            max_degree: degree.into_iter().max().unwrap_or(0),
            q_norm: row_abs.into_iter().fold(0.0, f64::max) * (1.0 + 1e-12),
            frame_defect,
        })
    }

    /// The phases `x_i = (cos theta_i, sin theta_i)` of `rotations` (standard convention):
    /// `theta_i` the turn of `F_i^T R_i` about `e_3`.
    pub fn phases(problem: &GravityProblem, rotations: &[Rotation]) -> Vec<(f64, f64)> {
        rotations
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let f = problem.frame(i).unwrap_or_else(Rotation::identity);
                let t = yaw((f.inverse() * r).matrix());
                (t.cos(), t.sin())
            })
            .collect()
    }

    /// The number of images `n`.
    pub fn len(&self) -> usize {
        self.n
    }

    /// Whether there is no image.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The off-diagonal entries `H_ij` as `(i, j, re, im)`, one per edge (repeated pairs
    /// summed by the matrix).
    pub fn entries(&self) -> &[(usize, usize, f64, f64)] {
        &self.entries
    }

    /// The diagonal `s_i = -Re(conj(x_i) sum_j H_ij x_j)` of `S = H - diag(lambda)` at phases
    /// `x`, stored exactly: it defines `lambda_i = d_i - s_i`.
    pub fn certificate_diagonal(&self, x: &[(f64, f64)]) -> Vec<f64> {
        let mut s = vec![0.0f64; self.n];
        for &(i, j, re, im) in &self.entries {
            // conj(x_i) z x_j and conj(x_j) conj(z) x_i
            let zx = (re * x[j].0 - im * x[j].1, re * x[j].1 + im * x[j].0);
            s[i] -= x[i].0 * zx.0 + x[i].1 * zx.1;
            let zx = (re * x[i].0 + im * x[i].1, re * x[i].1 - im * x[i].0);
            s[j] -= x[j].0 * zx.0 + x[j].1 * zx.1;
        }
        s
    }

    /// `S = H - diag(lambda)` at phases `x` in its real `2n x 2n` form (both triangles), its
    /// diagonal [`Self::certificate_diagonal`].
    pub(super) fn certificate_matrix(&self, x: &[(f64, f64)]) -> SparseColMat<usize, f64> {
        let s = self.certificate_diagonal(x);
        let mut t = Vec::with_capacity(8 * self.entries.len() + 2 * self.n);
        for &(i, j, re, im) in &self.entries {
            // block (i, j) = [[re, -im], [im, re]], block (j, i) its transpose
            for (a, b, v) in [(0, 0, re), (0, 1, -im), (1, 0, im), (1, 1, re)] {
                t.push(Triplet::new(2 * i + a, 2 * j + b, v));
                t.push(Triplet::new(2 * j + b, 2 * i + a, v));
            }
        }
        for (i, si) in s.iter().enumerate() {
            t.push(Triplet::new(2 * i, 2 * i, *si));
            t.push(Triplet::new(2 * i + 1, 2 * i + 1, *si));
        }
        SparseColMat::try_new_from_triplets(2 * self.n, 2 * self.n, &t).expect("indices within 2n")
    }

    /// The bound with `lambda_min(S^) >= mu` proven on the stored matrix: [`Self::bound_with`]
    /// with the deficit `n max(-mu, 0)`.
    pub(super) fn bound_at(&self, graph_defect: f64, x: &[(f64, f64)], mu: f64) -> f64 {
        let deficit = self.n as f64 * (-mu).max(0.0);
        self.bound_with(graph_defect, x, deficit)
    }

    /// `K - sum s_i - deficit` less every rounding and data term (`[G3]`): `deficit` bounds
    /// `-<S^, X>` over the relaxation's `X` (`n max(-mu, 0)`, or the grounded deficit
    /// `[G17]`); then the forming error of `S`'s entries (`sum_i` of [`Self::forming`]'s row
    /// sums), the constant's and the sum's rounding, the data defect of the measurements
    /// ([`data_defect`]) and the frame term `||Q|| (2 sqrt(3) n d (1 + d) + n d^2)`.
    pub(super) fn bound_with(&self, graph_defect: f64, x: &[(f64, f64)], deficit: f64) -> f64 {
        let n = self.n as f64;
        let d = self.frame_defect;
        let frames = self.q_norm * (2.0 * 3f64.sqrt() * n * d * (1.0 + d) + n * d * d);
        // K - sum s_i in double-double: the two cancel to the cost
        let mut value = Accumulator::default();
        value.add_product(self.constant.0, 1.0);
        value.add_low(self.constant.1);
        for si in self.certificate_diagonal(x) {
            value.add_product(si, -1.0);
        }
        let forming: f64 = self.forming.iter().sum::<f64>() * (1.0 + gamma(self.n));
        let charges = (value.bound() + self.constant_error + graph_defect + frames + forming)
            * (1.0 + 8.0 * UNIT_ROUNDOFF);
        // the last three subtractions, each within u of its result's magnitude
        let v = value.value();
        let rounding = 4.0 * UNIT_ROUNDOFF * (v.abs() + deficit + charges);
        v - deficit - charges - rounding
    }

    /// The largest row sum of the forming error `|S_exact - S^|` (every row of node `i`: the
    /// `i`-th of [`Self::forming`]): `lambda_min(S_exact) >= lambda_min(S^)` less it.
    pub(super) fn max_forming(&self) -> f64 {
        self.forming.iter().copied().fold(0.0, f64::max)
    }

    /// An upper bound on `||S||_2` and on every entry (the largest absolute row sum of `Q`).
    pub(super) fn q_norm(&self) -> f64 {
        self.q_norm
    }

    /// The entry terms of `[D6]`(b) for `S`'s real form (the shifts' forming).
    pub(super) fn entry_terms(&self) -> usize {
        30 * self.max_degree + 16
    }
}

/// Per edge, the number of edges on its pair of images (in either order): repeated pairs are
/// summed into one entry of `H`, one more rounding per repeat.
fn pair_multiplicity(graph: &crate::multiple::MultipleProblem) -> Vec<usize> {
    let key = |k: usize| {
        let e = &graph.edges()[k];
        (e.i.min(e.j), e.i.max(e.j))
    };
    let mut order: Vec<usize> = (0..graph.num_edges()).collect();
    order.sort_unstable_by_key(|&k| key(k));
    let mut count = vec![1usize; graph.num_edges()];
    for run in order.chunk_by(|&a, &b| key(a) == key(b)) {
        run.iter().for_each(|&k| count[k] = run.len());
    }
    count
}

/// Add `w u^T m v` to `acc`, every product error-free (`w` a power of two).
fn add_form(acc: &mut Accumulator, u: &Vector3<f64>, m: &Matrix3<f64>, v: &Vector3<f64>, w: f64) {
    for k in 0..3 {
        for l in 0..3 {
            acc.add_triple(w * m[(k, l)], u[k], v[l]);
        }
    }
}

/// Per edge, `|K(stored blocks) - K(exact data)| <= CONSTANT_FORMING u T_e` (`[G3]`, the
/// blocks' forming error; about 199 derived).
const CONSTANT_FORMING: f64 = 256.0;
/// Per edge, `|fl(re) - re|` and `|fl(im) - im|` at most `ENTRY_FORMING u T_e` (about 475
/// derived), plus `PAIR_FORMING u T_e` per other edge on the same pair (the sum of repeats).
const ENTRY_FORMING: f64 = 512.0;
const PAIR_FORMING: f64 = 48.0;

/// A verified bound of the planar dual, and how it was proven.
#[derive(Debug, Clone, Copy)]
pub struct PlanarBound {
    /// The lower bound on the full-gravity problem's minimum.
    pub lower_bound: f64,
    /// The proven `lambda_min(S) >= mu`.
    pub verified_min_eigenvalue: f64,
}

/// The bound `[G3]` at phases `x`: the shifts `sigma` tried from the one whose deficit
/// `n sigma` is a quarter of `allowed_gap`, then at Lanczos's estimate of `-lambda_min(S)`,
/// then doubled (at most 40 factorisations); `Err` with the reason when no factorisation
/// succeeds, the factor is over the memory budget, or the next factorisation is predicted past
/// the deadline.
pub fn verify_planar(
    problem: &GravityProblem,
    form: &PlanarForm,
    x: &[(f64, f64)],
    allowed_gap: f64,
    budget: &Budget,
    deadline: &Deadline,
) -> Result<std::result::Result<PlanarBound, String>> {
    let s = form.certificate_matrix(x);
    let terms = form.entry_terms();
    let max_values = budget.max_factor_values(s.nrows());
    let mut ch = match ShiftedCholesky::new_within(s, terms, max_values)? {
        Ok(ch) => ch,
        Err(predicted) => {
            return Ok(Err(format!(
                "its factor ({predicted} values) is over the memory budget ({max_values})"
            )));
        }
    };
    // each factorisation must fit the time left (`[D5]`'s prediction), else stop
    let one = Budget::predicted_factor_seconds(ch.multiply_adds(), ch.factor_len());
    let floor = 0.25 * allowed_gap / form.n as f64;
    let graph_defect = data_defect(problem.problem());
    let mut shift = floor;
    for attempt in 0..40 {
        if deadline.left().is_some_and(|l| l < one) {
            return Ok(Err(format!(
                "a factorisation is predicted at {one:.2e} s, past the time left (after {attempt})"
            )));
        }
        if let Some(f) = ch.factor(shift, 0.1 * floor) {
            let mu = f.verified_lower_bound();
            return Ok(Ok(PlanarBound {
                lower_bound: form.bound_at(graph_defect, x, mu),
                verified_min_eigenvalue: mu - form.max_forming(),
            }));
        }
        shift = match attempt {
            // not positive semidefinite at the tolerance: start from Lanczos's estimate
            0 => shift.max(-smallest_eigenvalue(&ch, form.q_norm) * (1.0 + 1e-6)),
            _ => 2.0 * shift,
        };
    }
    Ok(Err(
        "no shifted factorisation of the SO(2) certificate matrix succeeded".into(),
    ))
}

/// An estimate (never a bound) of `lambda_min(S)`, less its Ritz residual.
fn smallest_eigenvalue(ch: &ShiftedCholesky, q_norm: f64) -> f64 {
    let s = ch.matrix();
    let e = lanczos_extreme(
        s.nrows(),
        |v, y| sparse_matvec(s, v, y),
        Extreme::Smallest,
        2.0 * q_norm.max(f64::MIN_POSITIVE),
        &LanczosSettings::default(),
        None,
    );
    e.value - e.residual
}
