//! The verified bound of the simultaneous problem from any multipliers `[H14]`, `[H15]`: for
//! any symmetric `Lambda_a` and any numbers `gamma_ij`, every joint point `(R, S)` gives `X_R`
//! (blocks `R_i R_j^T`) and `X_C` (blocks `S R_i R_j^T S^T`) with identity diagonal blocks,
//! equal block traces and `tr X_R = tr X_C = 3n`, so the joint cost
//! `J = tr(Q_R X_R) + tr(Q_C X_C) = sum_a tr(Lambda_a) + tr(Z_R X_R) + tr(Z_C X_C)` is at least
//! `sum_a tr(Lambda_a) + 3n (min(lambda_min(Z_R), 0) + min(lambda_min(Z_C), 0))`, where
//! `Z_R = Q_R - blkdiag(Lambda_R) - sum gamma_ij E_ij` and
//! `Z_C = Q_C - blkdiag(Lambda_C) + sum gamma_ij E_ij` (the coupling terms cancel because the
//! traces are equal): the bound holds for the global minimum of `J`. The eigenvalues are
//! computed densely (faer's symmetric eigensolver), independently of any solver; at a point,
//! each side's grounded bound `[H23]` comes first and the eigenvalues only when they could
//! improve on it.

use super::grounded::grounded;
use crate::certify::multiple::multipliers::data_defect;
use crate::linalg::gamma;
use crate::multiple::MultipleProblem;
use crate::multiple::laplacian::connection_laplacian_triplets;
use crate::relax::simultaneous::coupling_pairs;
use crate::so3::Rotation;
use nalgebra::{DMatrix, Matrix3};
use serde::{Deserialize, Serialize};

/// A lower bound on the global minimum of the joint cost, verified from multipliers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SimultaneousBound {
    /// `sum_a tr(Lambda_a) + 3n (min(verified lambda_min(Z_R), 0) + min(verified
    /// lambda_min(Z_C), 0)) - rounding - the two graphs' data defects` (`[D4]`: measurements
    /// orthogonal only to the validation tolerance).
    pub lower_bound: f64,
    /// The smaller of `lambda_min(Z_R)` and `lambda_min(Z_C)` from faer's dense symmetric
    /// eigenvalue solver; for a side the grounded bound `[H23]` proved without them (at a
    /// point, where the eigenvalue bound could not be better), the point's smallest Rayleigh
    /// quotient there (an upper bound on that side's `lambda_min`). An estimate, never a bound.
    pub min_eigenvalue: f64,
    /// Proven lower bound on that smaller `lambda_min` of the exact matrices: each computed
    /// value minus `10 (3n) eps ||(|Q| + |blkdiag Lambda| + sum |gamma_ij E_ij|)||_F`, which
    /// covers the rounding of forming `Z` (at most three terms per entry) and the eigen
    /// solver's backward error; for graphs with information also the rounding inside their
    /// edges' entries (`information_error`).
    pub verified_min_eigenvalue: f64,
}

/// One side's dense certificate matrix (`Z_R` for the right graph with `sign = -1/2`, `Z_C` for
/// the left with `+1/2`; `lambdas` that side's `n` blocks) and the entrywise magnitudes of its
/// terms.
pub(crate) fn certificate_matrix(
    p: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    couplings: &[f64],
    sign: f64,
) -> (DMatrix<f64>, DMatrix<f64>) {
    let n = p.num_rotations();
    let dim = 3 * n;
    let mut m = DMatrix::zeros(dim, dim);
    let mut mag = DMatrix::zeros(dim, dim);
    let mut add = |r: usize, c: usize, v: f64| {
        m[(r, c)] += v;
        mag[(r, c)] += v.abs();
    };
    for t in connection_laplacian_triplets(p) {
        add(t.row, t.col, t.val);
    }
    for (a, l) in lambdas.iter().enumerate() {
        for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
            add(3 * a + r, 3 * a + c, -l[(r, c)]);
        }
    }
    for ((i, j), g) in coupling_pairs(n).zip(couplings) {
        for d in 0..3 {
            add(3 * i + d, 3 * j + d, sign * g);
            add(3 * j + d, 3 * i + d, sign * g);
        }
    }
    if p.is_anisotropic() {
        // the rounding inside the edges' entries, as `gamma(side_terms)` of these: the grounded
        // bound reads `gamma(terms) mag` as each entry's forming error ([H22] "Information")
        let scale = gamma(8) / gamma(side_terms(p)) * (1.0 + 1e-10);
        for (i, j, b, o) in information_magnitudes(p) {
            for (r, c) in (0..3).flat_map(|r| (0..3).map(move |c| (r, c))) {
                mag[(3 * i + r, 3 * i + c)] += scale * b[(r, c)];
                mag[(3 * j + r, 3 * j + c)] += scale * b[(r, c)];
                mag[(3 * i + r, 3 * j + c)] += scale * o[(r, c)];
                mag[(3 * j + r, 3 * i + c)] += scale * o[(c, r)];
            }
        }
    }
    (m, mag)
}

/// The terms of an entry of one side's `Z` that `mag` bounds the sum of (the edges, the
/// multiplier, the coupling and the gauge's): the grounded bound's `gamma(terms)`.
pub(super) fn side_terms(p: &MultipleProblem) -> usize {
    p.num_edges() + 4
}

/// Each anisotropic edge's magnitude blocks `(i, j, B, O)` (`[H22]` "Information"): `2M =
/// tr(H) I - 2H` and `-2M R^T` are computed within `gamma(8)` of `B = |tr H| I + 2|H|` and `O =
/// B |R|^T` entrywise (a value can be far below them where its terms cancel).
fn information_magnitudes(
    p: &MultipleProblem,
) -> impl Iterator<Item = (usize, usize, Matrix3<f64>, Matrix3<f64>)> + '_ {
    let info = p.information().unwrap_or_default();
    (p.edges().iter().zip(info)).map(|(e, h)| {
        let b = Matrix3::identity() * h.matrix().trace().abs() + h.matrix().abs() * 2.0;
        let o = b * e.rotation.matrix().transpose().abs();
        (e.i, e.j, b, o)
    })
}

/// A bound on the rounding inside the anisotropic edges' entries beyond what `[H14]`'s margin
/// covers: `||E||_2 <= ||E||_F <= gamma(8) sum_e 2 (||B_e||_F + ||O_e||_F)`
/// ([`information_magnitudes`]; the triangle inequality over the edges). Zero for scalar
/// weights.
fn information_error(p: &MultipleProblem) -> f64 {
    let sum: f64 = information_magnitudes(p)
        .map(|(_, _, b, o)| 2.0 * (b.norm() + o.norm()))
        .sum();
    gamma(8) * sum * (1.0 + 1e-10)
}

/// One side's proven part of the bound: `floor <= min tr(Z X)` over the relaxation's `X`,
/// `verified <= lambda_min(Z)`, and `estimate` (the eigensolver's `lambda_min`, or the
/// point's smallest Rayleigh quotient where the eigenvalues were not needed).
pub(super) struct SideBound {
    pub floor: f64,
    pub verified: f64,
    pub estimate: f64,
}

/// The point's blocks on one side: `R_i` (right) or `S R_i` (left).
fn side_point(r: &[Rotation], s: &Rotation, left_side: bool) -> Vec<Matrix3<f64>> {
    r.iter()
        .map(|r| {
            if left_side {
                s.matrix() * r.matrix()
            } else {
                *r.matrix()
            }
        })
        .collect()
}

/// One side's bound: with a point (isotropic graphs), the grounded bound `[H23]` first (no
/// eigenvalues: a Lanczos estimate and a Cholesky factorisation); the dense eigenvalues of
/// `[H14]` only when it fails or when the eigenvalue bound could be better, which it cannot be
/// when the grounded floor is at least `3n min(q - margin, 0)` with `q` the point's smallest
/// Rayleigh quotient (`>= lambda_min(Z)`): at a critical point `q` is about 0 and the margin
/// `10 (3n) eps ||mag||_F` decides (at 1000 frames 3.7 s of eigenvalues per side skipped).
/// Both bounds are proven; this only chooses which to compute, and the larger is kept.
pub(super) fn side_bound(
    m: &DMatrix<f64>,
    mag: &DMatrix<f64>,
    (terms, extra): (usize, f64),
    y: Option<&[Matrix3<f64>]>,
) -> Option<SideBound> {
    let dim = m.nrows() as f64;
    // `extra`: rounding inside the entries that `mag` does not bound for the eigenvalues
    // (`information_error`); the grounded bound's `mag` carries it itself
    let margin = 10.0 * dim * f64::EPSILON * mag.norm() + extra;
    let first = y.and_then(|y| grounded(m, mag, terms, y));
    if let Some(g) = &first
        && g.floor >= dim * (g.rayleigh - margin).min(0.0)
    {
        return Some(SideBound {
            floor: g.floor,
            verified: g.min_eigenvalue,
            estimate: g.rayleigh,
        });
    }
    let values = crate::linalg::dense::symmetric_eigenvalues(m)?;
    let l = values.first().copied().unwrap_or(f64::INFINITY);
    let mut verified = l - margin;
    let mut floor = dim * verified.min(0.0);
    if let Some(g) = first {
        floor = floor.max(g.floor);
        verified = verified.max(g.min_eigenvalue);
    }
    Some(SideBound {
        floor,
        verified,
        estimate: l,
    })
}

/// Verify a lower bound on the global minimum of the joint cost from any multipliers (the SDP's,
/// or any other): `None` when they are not finite or do not match the problem's size
/// (`2n` matrices `Lambda_a`, `n (n - 1) / 2` couplings in the order of
/// [`coupling_pairs`]).
///
/// ```
/// use rotavg::certify::simultaneous::verify_simultaneous_bound;
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::Rotation;
/// use nalgebra::Matrix3;
/// let e = |i, j| Edge { i, j, rotation: Rotation::identity(), weight: 1.0 };
/// let p = MultipleProblem::new(3, vec![e(0, 1), e(1, 2)])?;
/// // zero multipliers: the bound is 3n (lambda_min(Q_R) + lambda_min(Q_C)) = 0 for PSD Laplacians
/// let b = verify_simultaneous_bound(&p, &p, &[Matrix3::zeros(); 6], &[0.0; 3]).unwrap();
/// assert!(b.lower_bound <= 0.0 && b.lower_bound > -1e-9);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn verify_simultaneous_bound(
    right: &MultipleProblem,
    left: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    couplings: &[f64],
) -> Option<SimultaneousBound> {
    verify_simultaneous_bound_at(right, left, lambdas, couplings, None)
}

/// [`verify_simultaneous_bound`], and with the point `(R, S)` the multipliers were read at
/// also the grounded bound of each side (`[H23]`: no `3n` factor on the eigenvalue margin; the
/// larger of the two is kept, each proven). With information, `mag` holds the rounding inside the
/// edges' entries too (`certificate_matrix`, `[H22]` "Information").
pub fn verify_simultaneous_bound_at(
    right: &MultipleProblem,
    left: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    couplings: &[f64],
    point: Option<(&[Rotation], &Rotation)>,
) -> Option<SimultaneousBound> {
    let n = right.num_rotations();
    let finite = |m: &Matrix3<f64>| m.iter().all(|x| x.is_finite());
    if left.num_rotations() != n
        || lambdas.len() != 2 * n
        || couplings.len() != n * (n - 1) / 2
        || !lambdas.iter().all(finite)
        || !couplings.iter().all(|g| g.is_finite())
        || point.is_some_and(|(r, _)| r.len() != n)
    {
        return None;
    }
    let (mut lam, mut verified, mut floor) = (f64::INFINITY, f64::INFINITY, 0.0);
    // one side at a time (two dense matrices alive, not four); eigenvalues only
    for (p, side, sign, left_side) in [
        (right, &lambdas[..n], -0.5, false),
        (left, &lambdas[n..], 0.5, true),
    ] {
        let (m, mag) = certificate_matrix(p, side, couplings, sign);
        let y = point.map(|(r, s)| side_point(r, s, left_side));
        let one = side_bound(
            &m,
            &mag,
            (side_terms(p), information_error(p)),
            y.as_deref(),
        )?;
        lam = lam.min(one.estimate);
        verified = verified.min(one.verified);
        floor += one.floor;
    }
    joint_bound(right, left, lambdas, floor, lam, verified)
}

/// The bound from both sides' floors (`floor`, their sum) and the multipliers' traces:
/// `sum_a tr(Lambda_a) + floor`, less the trace sum's rounding and the two graphs' data defects
/// (`[D4]`: measurements orthogonal only to the validation tolerance); `lam` and `verified`
/// the smaller side's estimate and proven `lambda_min`.
pub(super) fn joint_bound(
    right: &MultipleProblem,
    left: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    floor: f64,
    lam: f64,
    verified: f64,
) -> Option<SimultaneousBound> {
    let dim = 3.0 * right.num_rotations() as f64;
    let (mut trace, mut trace_abs) = (0.0, 0.0);
    for l in lambdas {
        trace += l.trace();
        trace_abs += l[(0, 0)].abs() + l[(1, 1)].abs() + l[(2, 2)].abs();
    }
    // the joint cost is tr(Q_R X_R) + tr(Q_C X_C) minus each graph's data defect
    // sum w (3 - ||R_ij||_F^2) (measurements orthogonal only to the validation tolerance, [D4])
    let defect = data_defect(right) + data_defect(left);
    let lb = trace + floor - 2.0 * dim * f64::EPSILON * trace_abs - defect;
    lb.is_finite().then_some(SimultaneousBound {
        lower_bound: lb,
        min_eigenvalue: lam,
        verified_min_eigenvalue: verified,
    })
}
