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
use crate::linalg::dense::{orthonormal_columns, symmetric_eigenvalues};
use crate::multiple::Edge;
use crate::relax::clarabel::{Cone, csc, solve_quadratic_conic};
use crate::relax::settings::SdpSettings;
use crate::relax::svec::{svec_entry, svec_index, svec_len, svec_weight};
use nalgebra::{DMatrix, DVector, Matrix3};
use std::time::Instant;

/// Most rounds of the bundle (the graphs of two weak axes at ratio 20 whose search stalls, 200
/// and 300 nodes: it stops at its stall rule after 38-59 rounds or here, 0.05-0.1 s a round,
/// `docs/benchmarks.md` "Two weak axes at ratio 20: node shifts").
const ROUNDS: usize = 100;

/// Bottom eigenvectors kept in the bundle, and the candidate's added each round (20 and 6
/// gained less in more time on those graphs).
const KEPT: usize = 12;
const ADDED: usize = 4;

/// The bundle stops when [`STALL_ROUNDS`] rounds raised `F` by less than this fraction of
/// `|F|`.
const STALL: f64 = 1e-3;
const STALL_ROUNDS: usize = 8;

/// Failed model steps in a row after which the bundle stops (Clarabel's `NumericalFailure` at
/// a small proximal weight; each failure doubles it).
const FAILURES: usize = 3;

/// The bundle's own memory at its largest on `n` nodes, bytes: the model's derivative matrix
/// and its metric-scaled copy (`6n` rows by the bundle's `svec` entries, 8 bytes each), the
/// bundle's and the candidate's vectors and a Lanczos basis of 60 vectors (`3n` values each),
/// the shifts and the analysed values' copy (`S'` itself is the caller's).
pub(super) fn predicted_bytes(n: usize, stored: usize) -> u64 {
    let width = KEPT + ADDED;
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

    /// The assembled matrix's bottom `KEPT` eigenpairs (estimates, ascending; shifts from
    /// `floor`, at most 40 of them, see [`Inverse::smallest`]) and its eigenvectors as columns.
    fn bottom(&mut self, deadline: Option<Instant>) -> Option<(Vec<f64>, DMatrix<f64>)> {
        let settings = LanczosSettings {
            max_iterations: 60,
            tolerance: 1e-6,
            block_size: 3,
            ..LanczosSettings::default()
        };
        let (pairs, _) =
            self.inverse
                .smallest((KEPT, self.floor), (&settings, &[]), (40, deadline))?;
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
    let mut bundle = orthonormal_columns(&center.vectors, KEPT, None);
    let (mut rounds, mut history, mut failures) = (0, vec![first], 0);
    for round in 1..=ROUNDS {
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
        bundle = orthonormal_columns(&center.vectors, KEPT, Some((&vectors, ADDED)));
        let serious = value - center.value >= 0.1 * (predicted - center.value);
        if serious {
            center = Center { d, vectors, value };
            bundle = orthonormal_columns(&center.vectors, KEPT, None);
            rho *= 0.5;
        } else {
            rho *= 2.0;
        }
        crate::progress::emit(|| crate::progress::Event::Phase {
            phase: crate::progress::Phase::Certify,
            detail: format!(
                "the conv(SO(3)) dual's node shifts [A11]: round {round}, estimated gain {:.3e}",
                center.value - first
            ),
        });
        history.push(center.value);
        let done = history.len() - 1;
        if done > STALL_ROUNDS
            && center.value - history[done - STALL_ROUNDS] < STALL * center.value.abs()
        {
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
/// solved through its dual in the bundle's dimension: `min <W, C> + |g + A*(W)|^2 / (2 rho)`
/// over `W >= 0`, `tr W = 3n` (`A(d) = -V^T blkdiag(d) V`, `g` the gradient of `sum tr(d_i)`,
/// norms in the variables' metric), by Clarabel within the deadline; then `d = (g + A*(W)) /
/// rho` and `t = lambda_min(C + A(d))`: the shifts and the model's gain `sum tr(d_i) + 3n t`.
fn model_step(
    v: &DMatrix<f64>,
    c: &DMatrix<f64>,
    rho: f64,
    deadline: Option<Instant>,
) -> Option<(Vec<Matrix3<f64>>, f64)> {
    let (n, r) = (v.nrows() / 3, v.ncols());
    let len = svec_len(r);
    let gt = derivatives(v);
    // the metric's inverse (off-diagonal variables count twice) and `g`
    let metric = |row: usize| if row % 6 < 3 { 1.0 } else { 0.5 };
    let g = |row: usize| if row % 6 < 3 { 1.0 } else { 0.0 };
    let scaled = DMatrix::from_fn(gt.nrows(), len, |row, col| gt[(row, col)] * metric(row));
    let gram = gt.tr_mul(&scaled) / rho;
    let q: Vec<f64> = (0..len)
        .map(|col| {
            let (i, j) = svec_entry(col);
            let linear: f64 = (0..gt.nrows()).map(|row| g(row) * scaled[(row, col)]).sum();
            svec_weight(i, j) * c[(i, j)] + linear / rho
        })
        .collect();
    // solved for `W / 3n` (unit trace) with the objective over its largest coefficient:
    // Clarabel's `NumericalFailure` otherwise at small `rho` on graphs of 8-12 nodes
    let trace = 3.0 * n as f64;
    let largest = (gram.amax() * trace * trace)
        .max(q.iter().fold(0.0_f64, |m, x| m.max(x.abs())) * trace)
        .max(f64::MIN_POSITIVE);
    let (quadratic, linear) = (trace * trace / largest, trace / largest);
    let upper = (0..len).flat_map(|b| (0..=b).map(move |a| (a, b)));
    let p = csc(
        len,
        len,
        upper
            .map(|(a, b)| (a, b, quadratic * gram[(a, b)]))
            .collect(),
    );
    let q: Vec<f64> = q.iter().map(|x| linear * x).collect();
    // `1 - tr W = 0`, then `0 - (-w)` in the PSD cone
    let mut triplets: Vec<(usize, usize, f64)> =
        (0..r).map(|i| (0, svec_index(i, i), 1.0)).collect();
    triplets.extend((0..len).map(|row| (1 + row, row, -1.0)));
    let mut b = vec![0.0; 1 + len];
    b[0] = 1.0;
    let settings = SdpSettings {
        chordal_decomposition: false,
        time_limit_seconds: deadline
            .map(|d| d.saturating_duration_since(Instant::now()).as_secs_f64()),
        ..SdpSettings::default()
    };
    let cones = [Cone::Zero(1), Cone::Psd(r)];
    let a = csc(1 + len, len, triplets);
    let solution = solve_quadratic_conic((&p, &q), a, &b, &cones, &settings, "none").ok()?;
    if !solution.status.converged() {
        return None;
    }
    let w = DVector::from_column_slice(&solution.x) * trace;
    let y: Vec<f64> = (&gt * w)
        .iter()
        .enumerate()
        .map(|(row, x)| (g(row) + x) * metric(row) / rho)
        .collect();
    let ay = gt.tr_mul(&DVector::from_column_slice(&y));
    let model = DMatrix::from_fn(r, r, |i, j| {
        c[(i, j)] + ay[svec_index(i, j)] / svec_weight(i, j)
    });
    let t = symmetric_eigenvalues(&model)?[0];
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
