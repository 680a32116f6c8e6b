//! The dual certificate of the simultaneous problem at the estimate `[H15]`
//! (`paper-notes/conjugate.md`): multipliers of the trace-coupled relaxation `[H14]` read off a
//! critical point `(R, S)` of the joint cost, without an SDP.
//!
//! Complementary slackness at the point (`Z_R Y_R = 0`, `Z_C Y_C = 0`, `Y_R = [R_i]`,
//! `Y_C = [S R_i]`) fixes each `Lambda_a` once the couplings are chosen:
//! `Lambda_R,i = sym((G_R,i - 1/2 sum_j gamma_ij R_j) R_i^T)`,
//! `Lambda_C,i = sym((G_C,i + 1/2 sum_j gamma_ij C_j) C_i^T)` (`G = Q Y`), and the skew parts
//! must vanish: `a_i = 1/2 sum_j gamma_ij u_ij` with `a_i = vee(G_R,i R_i^T)`,
//! `b_i = S^T vee(G_C,i C_i^T)`, `u_ij = vee(R_j R_i^T)` (`u_ji = -u_ij`), and `b_i = -a_i`,
//! which is the joint stationarity in `R_i`; solvable because `sum_i a_i = 0` is the
//! stationarity in `S`. Of the couplings that solve it, this takes the one of least norm,
//! `gamma = A^T (A A^T)^+ (a - b) / 2` (`A A^T` is a `3n x 3n` Laplacian of the complete graph
//! with `u_ij u_ij^T / 4` weights; its kernel, the constant vectors and the gauge directions
//! `(R_i w)_i`, is filled by multiples of their projectors). Whether `Z_R` and `Z_C` are then positive semidefinite is what the
//! verification decides ([`super::bound::verify_simultaneous_bound`], which recomputes everything
//! from the multipliers); on noisy rigs where the relaxation is tight this choice usually is
//! (docs/benchmarks.md), and when it is not the SDP is the next rung.

use crate::certify::multiple::multipliers::laplacian_times;
use crate::linalg::dense::DenseCholesky;
use crate::multiple::MultipleProblem;
use crate::relax::simultaneous::coupling_pairs;
use crate::so3::{Rotation, vee};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// The multipliers `(Lambda_a for a = 0..2n, gamma_ij in the order of [`coupling_pairs`])`
/// at the point `(rotations, s)`, or `None` when the point does not fit the graphs or the
/// coupling system is numerically singular.
pub fn multipliers_at_estimate(
    right: &MultipleProblem,
    left: &MultipleProblem,
    rotations: &[Rotation],
    s: &Rotation,
) -> Option<(Vec<Matrix3<f64>>, Vec<f64>)> {
    let at = EstimateMultipliers::new(PointTerms::new(right, left, rotations, s)?)?;
    let couplings = at.least_norm.clone();
    let lambdas = at.lambdas(&couplings);
    let finite = lambdas.iter().all(|l| l.iter().all(|x| x.is_finite()))
        && couplings.iter().all(|g| g.is_finite());
    finite.then_some((lambdas, couplings))
}

/// What complementary slackness at a critical point `(R, S)` makes of the multipliers: the
/// affine set of couplings `A gamma = (a - b) / 2` (its least-norm point, and the projection of
/// a direction onto the kernel of `A`), and the `Lambda_a` each coupling vector fixes. The
/// search over couplings ([`super::search`]) moves within that set.
pub(crate) struct EstimateMultipliers {
    /// `R_i` and `C_i = S R_i`.
    pub rs: Vec<Matrix3<f64>>,
    pub cs: Vec<Matrix3<f64>>,
    /// `G = Q Y` per side (double-double).
    gr: Vec<Matrix3<f64>>,
    gc: Vec<Matrix3<f64>>,
    /// The pairs of [`coupling_pairs`] and their axes `u_ij = vee(R_j R_i^T)`.
    pub pairs: Vec<(usize, usize)>,
    us: Vec<Vector3<f64>>,
    /// `A A^T` plus multiples of its kernel's projectors, factorised.
    k: DenseCholesky,
    /// The couplings of least norm.
    pub least_norm: Vec<f64>,
}

/// The right-hand side of the coupling system: `rhs_i = (a_i - b_i) / 2` (`a_i =
/// vee(G_R,i R_i^T)`, `b_i = S^T vee(G_C,i C_i^T)`), its mean and its component along the
/// gauge directions `(R_i w)_i` removed (both zero at an exact critical point).
fn coupling_rhs(
    gr: &[Matrix3<f64>],
    gc: &[Matrix3<f64>],
    rs: &[Matrix3<f64>],
    cs: &[Matrix3<f64>],
    sm: &Matrix3<f64>,
) -> Vec<Vector3<f64>> {
    let n = rs.len();
    let mut rhs: Vec<Vector3<f64>> = (0..n)
        .map(|i| {
            let a = vee(&(gr[i] * rs[i].transpose()));
            let b = sm.transpose() * vee(&(gc[i] * cs[i].transpose()));
            (a - b) * 0.5
        })
        .collect();
    let mean = rhs.iter().sum::<Vector3<f64>>() / n as f64;
    rhs.iter_mut().for_each(|r| *r -= mean);
    let gauge = rs
        .iter()
        .zip(&rhs)
        .map(|(r, v)| r.transpose() * v)
        .sum::<Vector3<f64>>()
        / n as f64;
    for (r, v) in rs.iter().zip(rhs.iter_mut()) {
        *v -= r * gauge;
    }
    rhs
}

/// `A A^T` (a `3n x 3n` Laplacian of the complete graph with `u_ij u_ij^T / 4` weights) plus
/// multiples of its kernel's projectors: the constant vectors and the gauge directions
/// `(R_i w)_i` (because `u_ij` is the axis of `R_j R_i^T`, `u_ij . (R_i w - R_j w) = 0`); the
/// right-hand side is orthogonal to both at a critical point (stationarity in `S`, and the gauge
/// invariance), and is projected onto their complement by [`coupling_rhs`].
fn coupling_gram(
    pairs: &[(usize, usize)],
    us: &[Vector3<f64>],
    rs: &[Matrix3<f64>],
) -> DMatrix<f64> {
    let n = rs.len();
    let d = 3 * n;
    let mut k = DMatrix::<f64>::zeros(d, d);
    for (&(i, j), u) in pairs.iter().zip(us) {
        let uu = u * u.transpose() * 0.25;
        for (bi, bj, sign) in [(i, i, 1.0), (j, j, 1.0), (i, j, -1.0), (j, i, -1.0)] {
            let mut blk = k.fixed_view_mut::<3, 3>(3 * bi, 3 * bj);
            blk += uu * sign;
        }
    }
    let fill = k.trace() / d as f64 / n as f64;
    for bi in 0..n {
        for bj in 0..n {
            let mut blk = k.fixed_view_mut::<3, 3>(3 * bi, 3 * bj);
            blk += (Matrix3::identity() + rs[bi] * rs[bj].transpose()) * fill;
        }
    }
    k
}

/// What complementary slackness reads off a point `(R, S)`: `R_i`, `C_i = S R_i`, `G = Q Y` of
/// both sides (double-double, `[D3]`) and the coupling system's right side ([`coupling_rhs`]).
pub(crate) struct PointTerms {
    pub rs: Vec<Matrix3<f64>>,
    pub cs: Vec<Matrix3<f64>>,
    pub gr: Vec<Matrix3<f64>>,
    pub gc: Vec<Matrix3<f64>>,
    pub rhs: Vec<Vector3<f64>>,
}

impl PointTerms {
    /// `None` when the point does not fit the graphs (or has fewer than two nodes).
    pub fn new(
        right: &MultipleProblem,
        left: &MultipleProblem,
        rotations: &[Rotation],
        s: &Rotation,
    ) -> Option<Self> {
        let n = rotations.len();
        if right.num_rotations() != n || left.num_rotations() != n || n < 2 {
            return None;
        }
        let c_rotations: Vec<Rotation> = rotations.iter().map(|r| s * r).collect();
        let (gr, gc) = (
            laplacian_times(right, rotations),
            laplacian_times(left, &c_rotations),
        );
        let rs: Vec<Matrix3<f64>> = rotations.iter().map(|r| *r.matrix()).collect();
        let cs: Vec<Matrix3<f64>> = c_rotations.iter().map(|r| *r.matrix()).collect();
        let rhs = coupling_rhs(&gr, &gc, &rs, &cs, s.matrix());
        Some(PointTerms {
            rs,
            cs,
            gr,
            gc,
            rhs,
        })
    }
}

impl EstimateMultipliers {
    /// The multipliers at `point`; `None` when the coupling system is singular.
    pub fn new(point: PointTerms) -> Option<Self> {
        let PointTerms {
            rs,
            cs,
            gr,
            gc,
            rhs,
        } = point;
        let n = rs.len();
        let pairs: Vec<(usize, usize)> = coupling_pairs(n).collect();
        let us: Vec<Vector3<f64>> = pairs
            .iter()
            .map(|&(i, j)| vee(&(rs[j] * rs[i].transpose())))
            .collect();
        let d = 3 * n;
        let k = coupling_gram(&pairs, &us, &rs);
        let k = DenseCholesky::new(&k)?;
        let y = k.solve(&DVector::from_iterator(
            d,
            rhs.iter().flat_map(|v| v.iter().copied()),
        ));
        let mut at = EstimateMultipliers {
            rs,
            cs,
            gr,
            gc,
            pairs,
            us,
            k,
            least_norm: Vec::new(),
        };
        at.least_norm = at.a_transpose(&y);
        Some(at)
    }

    /// `A^T y`: per pair, `u_ij . (y_i - y_j) / 2`.
    fn a_transpose(&self, y: &DVector<f64>) -> Vec<f64> {
        let yb = |i: usize| Vector3::new(y[3 * i], y[3 * i + 1], y[3 * i + 2]);
        self.pairs
            .iter()
            .zip(&self.us)
            .map(|(&(i, j), u)| 0.5 * u.dot(&(yb(i) - yb(j))))
            .collect()
    }

    /// A direction of couplings projected onto the kernel of `A` (moves that keep
    /// complementary slackness): `d - A^T (A A^T + P)^-1 A d`, `P` the kernel's fill, which
    /// `A d` is orthogonal to.
    pub fn project(&self, d: &mut [f64]) {
        let n = self.rs.len();
        let mut ad = DVector::<f64>::zeros(3 * n);
        for ((&(i, j), u), g) in self.pairs.iter().zip(&self.us).zip(d.iter()) {
            for a in 0..3 {
                ad[3 * i + a] += 0.5 * g * u[a];
                ad[3 * j + a] -= 0.5 * g * u[a];
            }
        }
        let y = self.k.solve(&ad);
        for (x, c) in d.iter_mut().zip(self.a_transpose(&y)) {
            *x -= c;
        }
    }

    /// The `2n` multipliers complementary slackness fixes for `couplings`:
    /// `Lambda_R,i = sym((G_R,i - 1/2 sum_j gamma_ij R_j) R_i^T)`,
    /// `Lambda_C,i = sym((G_C,i + 1/2 sum_j gamma_ij C_j) C_i^T)`.
    pub fn lambdas(&self, couplings: &[f64]) -> Vec<Matrix3<f64>> {
        let n = self.rs.len();
        let (mut hr, mut hc) = (vec![Matrix3::zeros(); n], vec![Matrix3::zeros(); n]);
        for (&(i, j), g) in self.pairs.iter().zip(couplings) {
            hr[i] += self.rs[j] * *g;
            hr[j] += self.rs[i] * *g;
            hc[i] += self.cs[j] * *g;
            hc[j] += self.cs[i] * *g;
        }
        let sym = |m: Matrix3<f64>| (m + m.transpose()) * 0.5;
        let mut lambdas: Vec<Matrix3<f64>> = (0..n)
            .map(|i| sym((self.gr[i] - hr[i] * 0.5) * self.rs[i].transpose()))
            .collect();
        lambdas.extend((0..n).map(|i| sym((self.gc[i] + hc[i] * 0.5) * self.cs[i].transpose())));
        lambdas
    }
}
