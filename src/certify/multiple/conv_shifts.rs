//! The `conv(SO(3))` dual's bound where the search of [`super::conv_dual`] does not certify
//! (`paper-notes/anisotropic.md` `[A11]` "Node shifts"): its edges' multipliers `P_e` kept, a
//! proximal spectral bundle (Helmberg and Rendl) over shifts `D_i` of the nodes' multipliers
//! towards the largest
//!
//! `F(D) = sum_i tr(D_i) + 3n lambda_min(S'(P) - blkdiag(D))`,
//!
//! the bound being `f(estimate) + F` up to the offsets' rounding: where the search keeps the
//! nodes' multipliers at the estimate's (`D = 0`, `F = 3n lambda_min(S')`, a negative eigenvalue
//! charged on every one of the `3n` dimensions), which is all it can do where the relaxation is
//! not tight. An estimate only, like the search: the multipliers it returns are verified by the
//! `O(3)` checks on the surrogate ([`super::verify::multipliers_bound`]), minus the verified
//! offsets.

use super::conv_frames::{Frame, Inverse};
use crate::linalg::LanczosSettings;
use crate::linalg::cholesky::sparse_matvec;
use crate::linalg::dense::orthonormal_columns;
use crate::multiple::Edge;
use crate::relax::spectral_bundle::{Model, Rules, Step, serious_step};
use crate::relax::svec::{svec_entry, svec_len, svec_weight};
use nalgebra::{DMatrix, Matrix3};
use std::time::Instant;

/// The bundle's rules: 100 rounds at most (the graphs of two weak axes at ratio 20 whose
/// search stalls, 200 and 300 nodes: it stops at its stall rule after 38-59 rounds or at 100,
/// 0.05-0.1 s a round, `docs/benchmarks.md` "Two weak axes at ratio 20: node shifts"); 12
/// bottom eigenvectors kept and 4 of the candidate's added (20 and 6 gained less in more time
/// on those graphs); stopped when 8 rounds raised `F` by less than `1e-3 |F|`.
const RULES: Rules = Rules {
    rounds: 100,
    widths: (12, 4),
    stall: (1e-3, 8),
};

/// Failed model steps in a row after which the bundle stops (Clarabel's `NumericalFailure` at
/// a small proximal weight; each failure doubles it).
const FAILURES: usize = 3;

/// The bundle's own memory at its largest on `n` nodes, bytes: the model's derivative matrix
/// and its metric-scaled copy (`6n` rows by the bundle's `svec` entries, 8 bytes each), the
/// bundle's and the candidate's vectors and a Lanczos basis of 60 vectors (`3n` values each),
/// the shifts and the analysed values' copy (`S'` itself is the caller's).
pub(super) fn predicted_bytes(n: usize, stored: usize) -> u64 {
    let width = RULES.widths.0 + RULES.widths.1;
    let model = 2 * 6 * n * svec_len(width);
    let vectors = (3 * width + 60) * 3 * n;
    (8 * (model + vectors + 9 * n + stored)) as u64
}

/// A symmetric `3 x 3` matrix's variables: the diagonal, then the upper triangle.
const UPPER: [(usize, usize); 6] = [(0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2)];

/// What the bundle found: the nodes' shifts, `F` there (an estimate: from Ritz values) and at
/// the start, and the rounds run.
#[derive(Debug, Clone)]
pub(super) struct Shifts {
    pub shifts: Vec<Matrix3<f64>>,
    pub value: f64,
    pub start: f64,
    pub rounds: usize,
}

/// The symmetric matrix of six variables.
fn symmetric(v: &[f64]) -> Matrix3<f64> {
    let mut m = Matrix3::zeros();
    for (&(r, c), x) in UPPER.iter().zip(v) {
        m[(r, c)] = *x;
        m[(c, r)] = *x;
    }
    m
}

/// `T = S'(P) - blkdiag(D)` in the analysed pattern of `inverse` (`S'(P)`'s values kept), and
/// its bottom eigenpairs by shift-invert Lanczos (no deflation: the shifts move the estimate's
/// null space).
struct Spectrum {
    inverse: Inverse,
    base: Vec<f64>,
    nodes: Vec<[usize; 9]>,
    floor: f64,
}

impl Spectrum {
    /// `S'(penalties)` on `inverse`'s analysis; `floor` the smallest shift tried.
    fn new(
        mut inverse: Inverse,
        (frames, edges): (&[Frame], &[Edge]),
        penalties: &[Matrix3<f64>],
        floor: f64,
    ) -> Self {
        inverse.assemble(frames, penalties);
        // each node's diagonal block, where one of its edges stores it
        let mut nodes = vec![[usize::MAX; 9]; inverse.cholesky.dim() / 3];
        for (e, pos) in edges.iter().zip(&inverse.positions) {
            for (node, first) in [(e.i, 0), (e.j, 9)] {
                if nodes[node][0] == usize::MAX {
                    nodes[node].copy_from_slice(&pos[first..first + 9]);
                }
            }
        }
        let base = inverse.cholesky.values_mut().to_vec();
        Spectrum {
            inverse,
            base,
            nodes,
            floor,
        }
    }

    /// Overwrite the analysed values with those of `S'(P) - blkdiag(d)`.
    fn assemble(&mut self, d: &[Matrix3<f64>]) {
        let values = self.inverse.cholesky.values_mut();
        values.copy_from_slice(&self.base);
        for (pos, d) in self.nodes.iter().zip(d) {
            for (k, p) in pos.iter().enumerate() {
                values[*p] -= d[(k / 3, k % 3)];
            }
        }
    }

    /// The assembled matrix's bottom `RULES.widths.0` eigenpairs (estimates, ascending; shifts from
    /// `floor`, at most 40 of them, see [`Inverse::smallest`]) and its eigenvectors as columns.
    fn bottom(&mut self, deadline: Option<Instant>) -> Option<(Vec<f64>, DMatrix<f64>)> {
        let settings = LanczosSettings {
            max_iterations: 60,
            tolerance: 1e-6,
            block_size: 3,
            ..LanczosSettings::default()
        };
        let (pairs, _) = self.inverse.smallest(
            (RULES.widths.0, self.floor),
            (&settings, &[]),
            (40, deadline),
        )?;
        if pairs.is_empty() {
            return None;
        }
        let dim = self.inverse.cholesky.dim();
        let vectors = DMatrix::from_fn(dim, pairs.len(), |r, c| pairs[c].1[r]);
        Some((pairs.iter().map(|p| p.0).collect(), vectors))
    }

    /// `V^T T V` of the assembled `T`.
    fn restricted(&self, v: &DMatrix<f64>) -> DMatrix<f64> {
        let mut tv = DMatrix::zeros(v.nrows(), v.ncols());
        for (column, mut out) in v.column_iter().zip(tv.column_iter_mut()) {
            sparse_matvec(
                self.inverse.cholesky.matrix(),
                column.as_slice(),
                out.as_mut_slice(),
            );
        }
        let c = v.transpose() * tv;
        0.5 * (&c + c.transpose())
    }
}

/// A point of the bundle: the shifts, the bottom eigenvectors there, `F`.
struct Center {
    d: Vec<Matrix3<f64>>,
    vectors: DMatrix<f64>,
    value: f64,
}

/// `F` of shifts `d` at the smallest eigenvalue `lambda`.
fn objective(d: &[Matrix3<f64>], lambda: f64) -> f64 {
    d.iter().map(Matrix3::trace).sum::<f64>() + 3.0 * d.len() as f64 * lambda
}

/// The bundle at the search's multipliers `penalties` (shifts from zero), on the shift-invert
/// analysis `inverse` of the estimate's `S`, shifts tried from `floor`, stopped at `deadline`:
/// `None` when no spectrum could be had at the start or no round raised `F`.
pub(super) fn shift_nodes(
    inverse: Inverse,
    graph: (&[Frame], &[Edge]),
    penalties: &[Matrix3<f64>],
    floor: f64,
    deadline: Option<Instant>,
) -> Option<Shifts> {
    let mut spectrum = Spectrum::new(inverse, graph, penalties, floor);
    let n = spectrum.nodes.len();
    let zero = vec![Matrix3::zeros(); n];
    spectrum.assemble(&zero);
    let (values, vectors) = spectrum.bottom(deadline)?;
    let first = objective(&zero, values[0]);
    let mut center = Center {
        d: zero,
        vectors,
        value: first,
    };
    let mut rho = 1.0 / values[0].abs().max(f64::MIN_POSITIVE);
    let mut bundle = orthonormal_columns(&center.vectors, RULES.widths.0, None);
    let (mut rounds, mut history, mut failures) = (0, vec![first], 0);
    for round in 1..=RULES.rounds {
        if deadline.is_some_and(|d| Instant::now() >= d) {
            break;
        }
        rounds = round;
        spectrum.assemble(&center.d);
        let c = spectrum.restricted(&bundle);
        let Some((step, predicted)) = model_step(&bundle, &c, rho, deadline) else {
            failures += 1;
            if failures > FAILURES {
                break;
            }
            rho *= 2.0;
            continue;
        };
        failures = 0;
        let d: Vec<_> = center.d.iter().zip(&step).map(|(a, b)| a + b).collect();
        spectrum.assemble(&d);
        let Some((values, vectors)) = spectrum.bottom(deadline) else {
            break;
        };
        let value = objective(&d, values[0]);
        // the model's `F` at `D + d`: `C` holds the center's `T`, so `t` is the whole
        // `lambda_min` there, and the center's traces are added
        let predicted = center.d.iter().map(Matrix3::trace).sum::<f64>() + predicted;
        bundle = orthonormal_columns(
            &center.vectors,
            RULES.widths.0,
            Some((&vectors, RULES.widths.1)),
        );
        if serious_step(value - center.value, predicted - center.value, &mut rho) {
            center = Center { d, vectors, value };
            bundle = orthonormal_columns(&center.vectors, RULES.widths.0, None);
        }
        crate::progress::emit(|| crate::progress::Event::Phase {
            phase: crate::progress::Phase::Certify,
            detail: format!(
                "the conv(SO(3)) dual's node shifts [A11]: round {round}, estimated gain {:.3e}",
                center.value - first
            ),
        });
        history.push(center.value);
        if RULES.stalled(&history, center.value.abs()) {
            break;
        }
    }
    (center.value > first).then_some(Shifts {
        shifts: center.d,
        value: center.value,
        start: first,
        rounds,
    })
}

/// One round's model `max sum tr(d_i) + 3n t - rho |d|^2 / 2` (Frobenius norm) with `C - V^T
/// blkdiag(d) V - t I` positive semidefinite (`C = V^T T V` at the center, `V` the bundle),
/// solved through its dual in the bundle's dimension ([`Model::step`], `tr W = 3n`, `A(d) =
/// -V^T blkdiag(d) V`, `g` the gradient of `sum tr(d_i)`, norms in the variables' metric)
/// within the deadline: the shifts and the model's gain `sum tr(d_i) + 3n t`.
fn model_step(
    v: &DMatrix<f64>,
    c: &DMatrix<f64>,
    rho: f64,
    deadline: Option<Instant>,
) -> Option<(Vec<Matrix3<f64>>, f64)> {
    let n = v.nrows() / 3;
    let gt = derivatives(v);
    // the metric's inverse (off-diagonal variables count twice) and `g`
    let metric: Vec<f64> = (0..6 * n)
        .map(|row| if row % 6 < 3 { 1.0 } else { 0.5 })
        .collect();
    let g: Vec<f64> = (0..6 * n)
        .map(|row| if row % 6 < 3 { 1.0 } else { 0.0 })
        .collect();
    let model = Model {
        derivatives: &gt,
        restricted: c,
        linear: Some(&g),
        metric: Some(&metric),
        weight: 3.0 * n as f64,
    };
    let seconds = deadline.map(|d| d.saturating_duration_since(Instant::now()).as_secs_f64());
    let Step { y, t } = model.step(rho, seconds)?;
    let d: Vec<_> = y.chunks(6).map(symmetric).collect();
    let gain = d.iter().map(Matrix3::trace).sum::<f64>() + 3.0 * n as f64 * t;
    Some((d, gain))
}

/// `A*` as a matrix: a row per variable (each node's six), a column per `svec` entry `(i, j)`
/// of the bundle's dimension: the derivative of `svec(A(d))`'s entry (its weight included),
/// `A(d) = -V^T blkdiag(d) V`.
fn derivatives(v: &DMatrix<f64>) -> DMatrix<f64> {
    let (n, r) = (v.nrows() / 3, v.ncols());
    let mut gt = DMatrix::zeros(6 * n, svec_len(r));
    for i in 0..n {
        let u = v.fixed_rows::<3>(3 * i);
        for (k, &(x, y)) in UPPER.iter().enumerate() {
            for col in 0..svec_len(r) {
                let (a, b) = svec_entry(col);
                let entry = if x == y {
                    u[(x, a)] * u[(x, b)]
                } else {
                    u[(x, a)] * u[(y, b)] + u[(y, a)] * u[(x, b)]
                };
                gt[(6 * i + k, col)] = -svec_weight(a, b) * entry;
            }
        }
    }
    gt
}

#[cfg(test)]
mod tests {
    use super::{model_step, symmetric};
    use crate::linalg::dense::symmetric_eigenvalues;
    use nalgebra::{DMatrix, Matrix3};
    use rand::{Rng, SeedableRng, rngs::StdRng};

    /// The model step through its dual is the primal's maximiser: `sum tr(d_i) + 3n t - rho
    /// |d|^2 / 2` with `t = lambda_min(C - V^T blkdiag(d) V)`, formed here from `d` directly,
    /// is at least its value at nearby shifts and at `d = 0`, and the step's gain is that
    /// objective without the proximal term.
    #[test]
    fn the_models_dual_gives_the_primal_maximiser() {
        let mut rng = StdRng::seed_from_u64(3);
        let (n, r, rho) = (7, 6, 0.7);
        let v = DMatrix::from_fn(3 * n, r, |_, _| rng.random::<f64>() - 0.5)
            .qr()
            .q();
        let c = DMatrix::from_fn(r, r, |_, _| rng.random::<f64>() - 0.5);
        let c = &c + c.transpose();
        let value = |d: &[Matrix3<f64>]| {
            let mut block = DMatrix::zeros(3 * n, 3 * n);
            for (i, d) in d.iter().enumerate() {
                block.fixed_view_mut::<3, 3>(3 * i, 3 * i).copy_from(d);
            }
            let t = symmetric_eigenvalues(&(&c - v.transpose() * block * &v)).unwrap()[0];
            let gain = d.iter().map(Matrix3::trace).sum::<f64>() + 3.0 * n as f64 * t;
            (
                gain,
                gain - 0.5 * rho * d.iter().map(|x| x.norm_squared()).sum::<f64>(),
            )
        };
        let (d, gain) = model_step(&v, &c, rho, None).unwrap();
        let (direct, at) = value(&d);
        assert!(
            (gain - direct).abs() <= 1e-6 * direct.abs().max(1.0),
            "{gain} {direct}"
        );
        assert!(at > value(&vec![Matrix3::zeros(); n]).1 + 1e-3, "{at}");
        let norm = d.iter().map(|x| x.norm_squared()).sum::<f64>().sqrt();
        for _ in 0..30 {
            let near: Vec<_> = d
                .iter()
                .map(|x| {
                    let e: Vec<f64> = (0..6).map(|_| rng.random::<f64>() - 0.5).collect();
                    x + symmetric(&e) * (0.05 * norm / (n as f64).sqrt())
                })
                .collect();
            assert!(
                value(&near).1 <= at + 1e-6 * at.abs().max(1.0),
                "{} > {at}",
                value(&near).1
            );
        }
    }
}
