//! The numbers every certificate of chordal L2 multiple averaging is made of (contract section 3,
//! `paper-notes/certificates.md` `[D3]`, `[D4]`, `[D15]`): `Q Y` and the multipliers
//! `Lambda_i = sym((Q Y)_i R_i^T)` in double-double, the certificate matrix
//! `S = Q - blkdiag(Lambda)`, the residuals `S Y` with their error bounds, the data defect of
//! measurements that are orthogonal only to the validation tolerance, and the bound
//! `sum tr(Lambda_i) - deficit` with its rounding.

use crate::error::{Error, Result};
use crate::linalg::compensated::Accumulator;
use crate::linalg::{UNIT_ROUNDOFF, gamma};
use crate::multiple::MultipleProblem;
use crate::multiple::anisotropic::exactly_isotropic;
use crate::multiple::laplacian::{edge_blocks, laplacian_plus_diagonal};
use crate::so3::Rotation;
use faer::sparse::SparseColMat;
use nalgebra::Matrix3;

/// `(Q Y)_i` for every node, edge-wise `[D3]`:
/// `(Q Y)_i = d_i R_i - sum_{(i,j)} w R_ij^T R_j - sum_{(j,i)} w R_ji R_j` (plain floating point;
/// the certificates use its double-double evaluation).
pub fn laplacian_times(problem: &MultipleProblem, rotations: &[Rotation]) -> Vec<Matrix3<f64>> {
    laplacian_times_compensated(problem, rotations)
        .iter()
        .map(|node| Matrix3::from_fn(|a, b| node[a][b].value()))
        .collect()
}

/// `(Q Y)_i` for every node, each entry accumulated in double-double `[D3]`, `[D15]`: the
/// heavy terms `w R_i` and `w R_ij^T R_j` cancel to the residual, which plain floating point
/// would know only to `u w` (issue 24: odometry of weight 1e8 against loop closures of weight 1).
pub(super) fn laplacian_times_compensated(
    problem: &MultipleProblem,
    rotations: &[Rotation],
) -> Vec<[[Accumulator; 3]; 3]> {
    let mut acc = vec![[[Accumulator::default(); 3]; 3]; problem.num_rotations()];
    let adjacency = problem.adjacency();
    let (edges, info) = (problem.edges(), problem.information());
    let parallel = edges.len() >= crate::linalg::threads::PARALLEL_EDGES;
    crate::linalg::threads::in_chunks(&mut acc, parallel, |first, nodes| {
        for (k, node) in nodes.iter_mut().enumerate() {
            let v = first + k;
            // the node's edges in the edges' order: each entry sums its terms as an edge-wise
            // pass would
            for &(_, index) in adjacency.neighbours(v) {
                let e = &edges[index];
                // `H = w I` exactly (a rig's couplings, `[H24]`) is the scalar edge of weight
                // `w`: `2M = w I`, the same terms, a sixth of the products
                let h = info.map(|info| info[index].matrix());
                match h.map(|h| (exactly_isotropic(h), h)) {
                    Some((None, h)) => anisotropic_end_times(node, e, h, rotations, v),
                    Some((Some(w), _)) => scalar_end_times(node, e, w, rotations, v),
                    None => scalar_end_times(node, e, e.weight, rotations, v),
                }
            }
        }
    });
    acc
}

/// One scalar edge's part of `(Q Y)_v` at its end `v`: `w (R_i - R_ij^T R_j)` at `i`,
/// `w (R_j - R_ij R_i)` at `j` `[D3]`.
fn scalar_end_times(
    node: &mut [[Accumulator; 3]; 3],
    e: &crate::multiple::Edge,
    w: f64,
    rotations: &[Rotation],
    v: usize,
) {
    let r = e.rotation.matrix();
    let (ri, rj) = (rotations[e.i].matrix(), rotations[e.j].matrix());
    for a in 0..3 {
        for b in 0..3 {
            let entry = &mut node[a][b];
            if v == e.i {
                entry.add_product(w, ri[(a, b)]);
                for c in 0..3 {
                    entry.add_triple(-w, r[(c, a)], rj[(c, b)]);
                }
            } else {
                entry.add_product(w, rj[(a, b)]);
                for c in 0..3 {
                    entry.add_triple(-w, r[(a, c)], ri[(c, b)]);
                }
            }
        }
    }
}

/// One anisotropic edge's part of `(Q Y)_v` at its end `v` `[A2]`, every term a product of data
/// entries (no rounded intermediate such as `M`): node i gets `2M R_i - 2M R_ij^T R_j`, node j
/// gets `2M R_j - 2 R_ij M R_i`, with `2M = tr(H) I - 2H` expanded.
fn anisotropic_end_times(
    node: &mut [[Accumulator; 3]; 3],
    e: &crate::multiple::Edge,
    h: &Matrix3<f64>,
    rotations: &[Rotation],
    v: usize,
) {
    let r = e.rotation.matrix();
    let (ri, rj) = (rotations[e.i].matrix(), rotations[e.j].matrix());
    for a in 0..3 {
        for b in 0..3 {
            let entry = &mut node[a][b];
            if v == e.i {
                for k in 0..3 {
                    // tr(H) R_i - tr(H) R_ij^T R_j
                    entry.add_product(h[(k, k)], ri[(a, b)]);
                    for d in 0..3 {
                        entry.add_triple(-h[(k, k)], r[(d, a)], rj[(d, b)]);
                    }
                }
                for c in 0..3 {
                    // - 2 H R_i + 2 H R_ij^T R_j (2 H_ac exact)
                    entry.add_product(-2.0 * h[(a, c)], ri[(c, b)]);
                    for d in 0..3 {
                        entry.add_triple(2.0 * h[(a, c)], r[(d, c)], rj[(d, b)]);
                    }
                }
            } else {
                for k in 0..3 {
                    // tr(H) R_j - tr(H) R_ij R_i
                    entry.add_product(h[(k, k)], rj[(a, b)]);
                    for c in 0..3 {
                        entry.add_triple(-h[(k, k)], r[(a, c)], ri[(c, b)]);
                    }
                }
                for c in 0..3 {
                    // - 2 H R_j + 2 R_ij H R_i
                    entry.add_product(-2.0 * h[(a, c)], rj[(c, b)]);
                    for d in 0..3 {
                        entry.add_triple(2.0 * h[(c, d)], r[(a, c)], ri[(d, b)]);
                    }
                }
            }
        }
    }
}

/// The multipliers `Lambda_i = sym((Q Y)_i R_i^T)` of an estimate `[D3]` (contract section 3),
/// evaluated in double-double and rounded once, so that `sum tr(Lambda_i)` equals the cost to
/// working precision whatever the spread of the weights. Errors if the estimate does not have
/// one rotation per node.
///
/// ```
/// use rotavg::certify::multiple::multipliers;
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, gt) = SyntheticGraph { num_rotations: 5, num_edges: 8, noise_sigma: 0.0, ..Default::default() }.generate();
/// let l = multipliers(&p, &gt).unwrap();
/// // noise-free: every Lambda_i is zero (Q Y = 0)
/// assert!(l.iter().all(|m| m.norm() < 1e-12));
/// ```
pub fn multipliers(problem: &MultipleProblem, rotations: &[Rotation]) -> Result<Vec<Matrix3<f64>>> {
    Ok(FirstOrder::at(problem, rotations)?.lambdas)
}

/// `sqrt(sum_i ||(Q Y)_i - Lambda_i R_i||_F^2)` with `Lambda` from [`multipliers`]: the
/// first-order residual (zero exactly at a critical point of the cost on `O(3)^n`), i.e.
/// `sqrt(sum_i ||skew((Q Y)_i R_i^T)||_F^2)`.
pub fn stationarity_residual(problem: &MultipleProblem, rotations: &[Rotation]) -> Result<f64> {
    Ok(FirstOrder::at(problem, rotations)?.stationarity)
}

/// What the first-order conditions say at an estimate, from one double-double evaluation of
/// `Q Y` `[D3]`, `[D15]`: the multipliers, the stationarity residual, and (on request) the
/// gauge terms of `S Y`. One per point of a certification (issue 35: `Q Y` was evaluated seven
/// times per dual certificate, most of its time outside the factorisations).
pub(crate) struct FirstOrder {
    /// `(Q Y)_i`, each entry a double-double sum with its error bookkeeping.
    qy: Vec<[[Accumulator; 3]; 3]>,
    /// `Lambda_i = sym((Q Y)_i R_i^T)`, rounded once.
    pub lambdas: Vec<Matrix3<f64>>,
    /// `sqrt(sum_i ||skew((Q Y)_i R_i^T)||_F^2)`.
    pub stationarity: f64,
    /// The gauge terms, made on the first request.
    gauge: std::cell::OnceCell<GaugeTerms>,
}

impl FirstOrder {
    /// The first-order quantities at `rotations` (one per node, else an error).
    pub fn at(problem: &MultipleProblem, rotations: &[Rotation]) -> Result<Self> {
        problem.check_estimate(rotations)?;
        let qy = laplacian_times_compensated(problem, rotations);
        let mut lambdas = Vec::with_capacity(qy.len());
        let mut skew2 = 0.0;
        for (node, r) in qy.iter().zip(rotations) {
            let (sym, skew) = first_order_block(node, r);
            lambdas.push(sym);
            skew2 += skew.norm_squared();
        }
        // coordinates no edge sees: their multipliers' rows are half the stationarity residual
        // there; zero, `S`'s rows are exactly zero, which the grounded bound leaves out [D15]
        for (l, zero) in lambdas.iter_mut().zip(unseen_coordinates(problem)) {
            for a in (0..3).filter(|&a| zero[a]) {
                l.row_mut(a).fill(0.0);
                l.column_mut(a).fill(0.0);
            }
        }
        Ok(FirstOrder {
            qy,
            lambdas,
            stationarity: skew2.sqrt(),
            gauge: std::cell::OnceCell::new(),
        })
    }

    /// The gauge terms of `S Y` for the estimate's own multipliers ([`gauge_terms`]), at
    /// `rotations` (the estimate this was made at), made once.
    pub fn gauge_terms(&self, rotations: &[Rotation]) -> &GaugeTerms {
        self.gauge
            .get_or_init(|| gauge_terms_from(self.qy.clone(), rotations, &self.lambdas))
    }
}

/// Per node, which of its three coordinates no edge sees (an exactly zero row of `Q`: every
/// edge's blocks zero in that row): the world node of soft gravity priors in its first two
/// (`paper-notes/gravity.md` `[G10]`; its edges' `2M = diag(0, 0, 2w)`). Only edges that see
/// two coordinates ([`crate::multiple::anisotropic::Information::sees_two_coordinates`]) can
/// leave one unseen; without them every coordinate is seen (an isolated node's multipliers are
/// zero anyway).
pub(crate) fn unseen_coordinates(problem: &MultipleProblem) -> Vec<[bool; 3]> {
    let n = problem.num_rotations();
    // only an edge whose 2M has a zero row can leave a coordinate unseen: one cheap pass first
    let some = problem
        .information()
        .is_some_and(|info| info.iter().any(|h| h.sees_two_coordinates()));
    if !some {
        return vec![[false; 3]; n];
    }
    let mut seen = vec![[false; 3]; n];
    for (i, j, a, b, c) in edge_blocks(problem) {
        for r in 0..3 {
            seen[i][r] |= (0..3).any(|k| a[(r, k)] != 0.0 || c[(r, k)] != 0.0);
            seen[j][r] |= (0..3).any(|k| b[(r, k)] != 0.0 || c[(k, r)] != 0.0);
        }
    }
    seen.into_iter().map(|s| s.map(|v| !v)).collect()
}

/// The symmetric and skew parts of `(Q Y)_i R_i^T`: the multiplier and the stationarity
/// residual `[D3]`, each entry a compensated sum of the double-double `(Q Y)_i` times `R_i^T`
/// (the high parts' products exact, the low parts' rounded: second order), rounded once.
/// Neither is part of a bound (any multipliers give one, `[D4]`).
fn first_order_block(node: &[[Accumulator; 3]; 3], r: &Rotation) -> (Matrix3<f64>, Matrix3<f64>) {
    let m = r.matrix();
    // sum_c (Q Y)_xc R_yc for the pairs (x, y) with their signs, in one accumulator
    let sum = |terms: &[(usize, usize, f64)]| {
        let mut s = Accumulator::default();
        for &(x, y, sign) in terms {
            for c in 0..3 {
                let (hi, lo) = node[x][c].parts();
                s.add_product(sign * hi, m[(y, c)]);
                s.add_low(sign * lo * m[(y, c)]);
            }
        }
        s.value()
    };
    // each entry once (the lower triangle mirrors the upper)
    let mut sym = Matrix3::zeros();
    let mut skew = Matrix3::zeros();
    for a in 0..3 {
        sym[(a, a)] = sum(&[(a, a, 1.0)]);
        for b in a + 1..3 {
            sym[(a, b)] = 0.5 * sum(&[(a, b, 1.0), (b, a, 1.0)]);
            sym[(b, a)] = sym[(a, b)];
            skew[(a, b)] = 0.5 * sum(&[(a, b, 1.0), (b, a, -1.0)]);
            skew[(b, a)] = -skew[(a, b)];
        }
    }
    (sym, skew)
}

/// One finite rotation per node.
pub(crate) fn check_rotations(problem: &MultipleProblem, rotations: &[Rotation]) -> Result<()> {
    problem.check_estimate(rotations)?;
    for (i, r) in rotations.iter().enumerate() {
        if !r.matrix().iter().all(|x| x.is_finite()) {
            return Err(Error::NonFinite {
                item: format!("estimate rotation {i}"),
            });
        }
    }
    Ok(())
}

pub(super) fn check_lambdas(problem: &MultipleProblem, lambdas: &[Matrix3<f64>]) -> Result<()> {
    if lambdas.len() != problem.num_rotations() {
        return Err(Error::InvalidSettings {
            name: "multipliers".into(),
            reason: format!(
                "{} blocks given, the problem has {} nodes",
                lambdas.len(),
                problem.num_rotations()
            ),
        });
    }
    for (i, l) in lambdas.iter().enumerate() {
        if !l.iter().all(|x| x.is_finite()) {
            return Err(Error::NonFinite {
                item: format!("multiplier block {i}"),
            });
        }
    }
    Ok(())
}

/// The certificate matrix `S = Q - blkdiag(Lambda)` (3n x 3n, sparse, both triangles stored,
/// every diagonal entry stored). Each `Lambda_i` is symmetrised first (the bound only depends on
/// the symmetric part).
pub fn certificate_matrix(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
) -> Result<SparseColMat<usize, f64>> {
    check_lambdas(problem, lambdas)?;
    Ok(checked_certificate_matrix(problem, lambdas))
}

/// [`certificate_matrix`] of multipliers [`check_lambdas`] accepted.
pub(super) fn checked_certificate_matrix(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
) -> SparseColMat<usize, f64> {
    laplacian_plus_diagonal(problem, &minus_symmetric(lambdas))
}

/// The diagonal blocks of [`checked_certificate_matrix`] as it stores them (without forming
/// `S`).
pub(super) fn certificate_diagonal_blocks(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
) -> Vec<Matrix3<f64>> {
    crate::multiple::laplacian::diagonal_blocks(problem, &minus_symmetric(lambdas))
}

/// `-sym(Lambda_i)` for every node.
fn minus_symmetric(lambdas: &[Matrix3<f64>]) -> Vec<Matrix3<f64>> {
    lambdas.iter().map(|l| -symmetrize(l)).collect()
}

pub(super) fn symmetrize(l: &Matrix3<f64>) -> Matrix3<f64> {
    0.5 * (l + l.transpose())
}

/// Largest number of rounded operations that formed an entry of `S` from the data: the degree
/// sum on the diagonal (and multi-edge sums off it), plus the multiplier subtraction.
pub(super) fn entry_terms(problem: &MultipleProblem) -> usize {
    let mut deg = vec![0usize; problem.num_rotations()];
    for e in problem.edges() {
        deg[e.i] += 1;
        deg[e.j] += 1;
    }
    deg.into_iter().max().unwrap_or(0) + 3
}

/// A bound on `||S_computed - S_exact||_2` beyond the forming error the factorisations charge
/// (`gamma(entry_terms + 2) ||S||_inf`, `[D6]`): zero for isotropic data, whose entries are
/// sums of data entries; for anisotropic data `[A3]`, whose blocks are products with the rounded
/// `2M = tr(H) I - 2H`, `max_i (48 gamma(d_i + 12) T_i + 4 u max|Lambda_i|)` with `T_i` the sum
/// of `tr(H)` over the `d_i` edges at node `i`. Subtracted from every proven `lambda_min(S)`.
pub(super) fn forming_margin(problem: &MultipleProblem, lambdas: &[Matrix3<f64>]) -> f64 {
    forming_margins(problem, lambdas).map_or(0.0, |m| m.iter().copied().fold(0.0, f64::max))
}

/// The per-node forming margins of `[A3]` (each bounds the row sums of the forming error in
/// that node's three rows, so their sum times 3 bounds the trace of a diagonal majorant,
/// `[D6]` (3)); `None` for isotropic problems (no further forming error).
pub(super) fn forming_margins(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
) -> Option<Vec<f64>> {
    let info = problem.information()?;
    let n = problem.num_rotations();
    let mut degree = vec![0usize; n];
    let mut trace = vec![0.0f64; n];
    for (e, h) in problem.edges().iter().zip(info) {
        let t = h.matrix().trace();
        for v in [e.i, e.j] {
            degree[v] += 1;
            trace[v] += t;
        }
    }
    let margins = (0..n)
        .map(|i| {
            let lmax = lambdas.get(i).map_or(0.0, |l| l.amax());
            (48.0 * gamma(degree[i] + 12) * trace[i] + 4.0 * UNIT_ROUNDOFF * lmax) * (1.0 + 1e-3)
        })
        .collect();
    Some(margins)
}

/// Column `a` of the gauge directions `Y = [R_1; ...; R_n]` (length `3n`).
pub(super) fn gauge_column(rotations: &[Rotation], a: usize) -> Vec<f64> {
    rotations
        .iter()
        .flat_map(|r| (0..3).map(move |row| r.matrix()[(row, a)]))
        .collect()
}

/// The gauge terms of an estimate, made on request: a check's (made once per estimate, from
/// its first-order quantities when it has them), or [`gauge_terms`] of the data.
pub(crate) type GaugeSource<'a> = &'a dyn Fn() -> GaugeTerms;

/// The gauge directions' terms of `[D15]` and `[D16]`, for the exact `S` of the data.
#[derive(Debug, Clone, Copy)]
pub(crate) struct GaugeTerms {
    /// Proven `rho >= ||S Y||_F >= ||S Y||_2`.
    pub rho: f64,
    /// Proven `h >= 0` with `Y^T S Y >= -h I`.
    pub h: f64,
    /// `sym(Y^T S Y)` as computed.
    pub sym: Matrix3<f64>,
    /// `||Y||_F` as computed.
    pub y_norm: f64,
    /// Per gauge direction `v_k = Y e_k`, its Rayleigh quotient `v_k^T S v_k / |v_k|^2` and
    /// the residual `|S v_k - q v_k| / |v_k|` as computed (an estimate, never a bound: the
    /// near-null vectors of `S` at a critical point; infinite for a zero column).
    pub rayleigh: [(f64, f64); 3],
}

/// `rho >= ||S Y||_2` and `h >= -lambda_min(Y^T S Y)`: `S Y` evaluated from the data in
/// double-double, with its error bound `[D15]`.
pub(crate) fn gauge_terms(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
) -> GaugeTerms {
    gauge_terms_from(
        laplacian_times_compensated(problem, rotations),
        rotations,
        lambdas,
    )
}

/// [`gauge_terms`] from the double-double `Q Y` already evaluated.
fn gauge_terms_from(
    qy: Vec<[[Accumulator; 3]; 3]>,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
) -> GaugeTerms {
    let u = UNIT_ROUNDOFF;
    let n3 = 3 * rotations.len();
    let (sy, sy_error) = residual_products_from(qy, rotations, lambdas);
    let sy_norm = sy.iter().map(|m| m.norm_squared()).sum::<f64>().sqrt();
    let rho = (sy_norm + sy_error) * (1.0 + 4.0 * u);
    let y_norm = rotations
        .iter()
        .map(|r| r.matrix().norm_squared())
        .sum::<f64>()
        .sqrt();
    let mut gm = Matrix3::<f64>::zeros();
    let mut abs_gm = Matrix3::<f64>::zeros();
    for (r, syi) in rotations.iter().zip(&sy) {
        gm += r.matrix().transpose() * syi;
        abs_gm += r.matrix().abs().transpose() * syi.abs();
    }
    let g_error = (y_norm * sy_error + gamma(n3) * abs_gm.norm()) * (1.0 + 4.0 * u);
    let sym = 0.5 * (gm + gm.transpose());
    let lambda_min = sym.symmetric_eigenvalues().min();
    let h = ((-lambda_min).max(0.0) + g_error + 16.0 * u * gm.norm()) * (1.0 + 4.0 * u);
    GaugeTerms {
        rho,
        h,
        sym,
        y_norm,
        rayleigh: std::array::from_fn(|k| gauge_rayleigh(rotations, &sy, gm[(k, k)], k)),
    }
}

/// The Rayleigh quotient and residual of the gauge direction `v = Y e_k` from `S Y` (`sy`) and
/// `v^T S v` (`vsv`): `S v = (S Y) e_k`, no product with `S`.
fn gauge_rayleigh(rotations: &[Rotation], sy: &[Matrix3<f64>], vsv: f64, k: usize) -> (f64, f64) {
    let norm2: f64 = rotations
        .iter()
        .map(|r| r.matrix().column(k).norm_squared())
        .sum();
    let q = vsv / norm2;
    if !(norm2 > 0.0 && q.is_finite()) {
        return (f64::INFINITY, f64::INFINITY);
    }
    let residual2: f64 = rotations
        .iter()
        .zip(sy)
        .map(|(r, s)| (s.column(k) - r.matrix().column(k) * q).norm_squared())
        .sum();
    (q, (residual2 / norm2).sqrt())
}

/// `(S Y)_i = (Q Y)_i - sym(Lambda_i) R_i` for every node, evaluated from the data in
/// double-double (the `S` of [`certificate_matrix`] from the exact data), and a bound on the
/// Frobenius norm of the whole error `[D15]`.
fn residual_products_from(
    mut acc: Vec<[[Accumulator; 3]; 3]>,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
) -> (Vec<Matrix3<f64>>, f64) {
    let mut error2 = 0.0;
    let out = acc
        .iter_mut()
        .zip(rotations.iter().zip(lambdas))
        .map(|(node, (rot, l))| {
            let l = symmetrize(l);
            let rm = rot.matrix();
            Matrix3::from_fn(|a, b| {
                let cell = &mut node[a][b];
                for c in 0..3 {
                    cell.add_product(-l[(a, c)], rm[(c, b)]);
                }
                error2 += cell.bound() * cell.bound();
                cell.value()
            })
        })
        .collect();
    (out, error2.sqrt() * (1.0 + 4.0 * UNIT_ROUNDOFF))
}

/// `sum tr(Lambda_i) - deficit` with the rounding of evaluating it and the data defect
/// subtracted: the bound of `[D15]` and `[D16]` from a proven `deficit >= 0`.
pub(super) fn bound_with_deficit(
    problem: &MultipleProblem,
    lambdas: &[Matrix3<f64>],
    deficit: f64,
) -> f64 {
    TraceBound::new(problem, lambdas).with_deficit(deficit)
}

/// What every bound from one set of multipliers shares (`[D4]`): `sum tr(Lambda_i)`, the sum
/// of the magnitudes its rounding is bounded by, and the data defect; made once per check
/// (the defect is a double-double sum over the edges).
#[derive(Debug, Clone, Copy)]
pub(super) struct TraceBound {
    n3: usize,
    trace: f64,
    abs_trace: f64,
    defect: f64,
}

impl TraceBound {
    /// `sum tr(Lambda_i)`, rounded.
    pub(super) fn trace(&self) -> f64 {
        self.trace
    }

    /// The shared terms of `lambdas` for `problem`.
    pub(super) fn new(problem: &MultipleProblem, lambdas: &[Matrix3<f64>]) -> Self {
        TraceBound {
            n3: 3 * lambdas.len(),
            trace: lambdas.iter().map(|l| l.trace()).sum(),
            abs_trace: lambdas
                .iter()
                .map(|l| l[(0, 0)].abs() + l[(1, 1)].abs() + l[(2, 2)].abs())
                .sum(),
            defect: data_defect(problem),
        }
    }

    /// `sum tr(Lambda_i) - deficit`, less the evaluation's rounding and the data defect.
    pub(super) fn with_deficit(&self, deficit: f64) -> f64 {
        self.trace - deficit - 2.0 * gamma(self.n3 + 4) * (self.abs_trace + deficit) - self.defect
    }

    /// The bound from a proven `mu <= lambda_min(S)`: the deficit `3n max(-mu, 0)`. `[D4]` with
    /// rounding: `sum tr(Lambda_i) + 3n min(mu, 0)`, minus the rounding error of evaluating
    /// it: the trace sum of `3n` terms has error `<= gamma(3n) sum |Lambda_aa|`, the product
    /// and final subtraction `<= gamma(3n + 2) (sum |Lambda_aa| + 3n |mu|)`; doubled.
    pub(super) fn at_mu(&self, mu: f64) -> f64 {
        self.with_deficit(self.n3 as f64 * (-mu).max(0.0))
    }
}

/// An upper bound on `c_0 = sum_e w_e (3 - ||R_ij||_F^2)` `[D4]`: the measured rotations are
/// orthogonal only to rounding, and for rotations `R_i` the chordal cost is
/// `f(Y) = tr(Y^T Q Y) - c_0`, so a lower bound on `min tr(Y^T Q Y)` bounds `min f` after
/// subtracting `c_0` (of order `u m w`, either sign). Evaluated in double-double.
pub(crate) fn data_defect(problem: &MultipleProblem) -> f64 {
    if problem.is_anisotropic() {
        // [A2]: the anisotropic Q carries the constant in its diagonal blocks, exactly
        return 0.0;
    }
    let mut acc = Accumulator::default();
    for e in problem.edges() {
        acc.add_product(e.weight, 3.0);
        for v in e.rotation.matrix().iter() {
            acc.add_triple(-e.weight, *v, *v);
        }
    }
    (acc.value() + acc.bound()) * (1.0 + 4.0 * UNIT_ROUNDOFF)
}

#[cfg(test)]
mod tests {
    use super::laplacian_times;
    use crate::multiple::anisotropic::Information;
    use crate::multiple::{Edge, MultipleProblem};
    use crate::so3::{Rotation, exp, random_rotation};
    use nalgebra::{Matrix3, Vector3};
    use rand::{Rng, SeedableRng, rngs::StdRng};

    /// `(Q Y)_i` of a graph whose edges mix `H = w I` (taken by the scalar terms) and general
    /// information matrices, against `[A2]`'s formula in plain floating point for every edge
    /// (`2M = tr(H) I - 2H`: node `i` gets `2M R_i - 2M R_ij^T R_j`, node `j` gets
    /// `2M R_j - R_ij 2M R_i`), weights from 1e-3 to 1e5.
    #[test]
    fn isotropic_information_takes_the_scalar_terms_of_the_same_value() {
        let mut rng = StdRng::seed_from_u64(7);
        let n = 6;
        let x: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
        let (mut edges, mut info) = (Vec::new(), Vec::new());
        for k in 0..14 {
            let (i, j) = (k % n, (k * 5 + 1) % n);
            if i == j {
                continue;
            }
            let noise = exp(&Vector3::new(0.1, -0.2, 0.05 * k as f64));
            let rotation = noise * x[j] * x[i].inverse();
            let w = 10f64.powi(k as i32 % 9 - 3);
            let h = if k % 2 == 0 {
                Matrix3::identity() * w
            } else {
                let a = Matrix3::from_fn(|_, _| rng.random::<f64>() - 0.5);
                a * a.transpose() * w + Matrix3::identity() * 1e-3 * w
            };
            edges.push(Edge {
                i,
                j,
                rotation,
                weight: 1.0,
            });
            info.push(Information::new(h).unwrap());
        }
        let p = MultipleProblem::new(n, edges).unwrap();
        let p = p.with_information(info.clone()).unwrap();
        assert!(p.is_anisotropic());
        let mut expected = vec![Matrix3::<f64>::zeros(); n];
        let mut scale = vec![0.0f64; n];
        for (e, h) in p.edges().iter().zip(&info) {
            let m2 = Matrix3::identity() * h.matrix().trace() - h.matrix() * 2.0;
            let (r, ri, rj) = (e.rotation.matrix(), x[e.i].matrix(), x[e.j].matrix());
            expected[e.i] += m2 * ri - m2 * r.transpose() * rj;
            expected[e.j] += m2 * rj - r * m2 * ri;
            scale[e.i] += h.matrix().trace();
            scale[e.j] += h.matrix().trace();
        }
        let got = laplacian_times(&p, &x);
        for v in 0..n {
            let error = (got[v] - expected[v]).amax();
            assert!(
                error <= 1e-13 * scale[v],
                "node {v}: {error:e} of {:e}",
                scale[v]
            );
        }
    }

    /// The gauge terms' Rayleigh quotients and residuals (from `S Y`, no product with `S`)
    /// against the formed `S`'s own (`rayleigh_quotient` of the normalised gauge column), on
    /// noisy graphs at random estimates and at a critical one, where both are near zero.
    #[test]
    fn the_gauge_rayleigh_quotients_are_those_of_the_formed_matrix() {
        use crate::multiple::synthetic::SyntheticGraph;
        let mut rng = StdRng::seed_from_u64(3);
        for seed in 0..6u64 {
            let (p, truth) = SyntheticGraph {
                num_rotations: 15,
                num_edges: 40,
                noise_sigma: 0.2,
                seed,
                ..Default::default()
            }
            .generate();
            let solved = crate::multiple::solve_multiple(&p, &Default::default()).unwrap();
            let random: Vec<Rotation> = (0..15).map(|_| random_rotation(&mut rng)).collect();
            for x in [&truth, &solved.rotations, &random] {
                let first = super::FirstOrder::at(&p, x).unwrap();
                let s = super::certificate_matrix(&p, &first.lambdas).unwrap();
                let scale = first.lambdas.iter().map(|l| l.norm()).fold(1.0, f64::max);
                for (k, &(q, residual)) in first.gauge_terms(x).rayleigh.iter().enumerate() {
                    let mut v = super::gauge_column(x, k);
                    let nv = v.iter().map(|a| a * a).sum::<f64>().sqrt();
                    v.iter_mut().for_each(|a| *a /= nv);
                    let (q0, r0) = crate::linalg::rayleigh_quotient(s.as_ref(), &v);
                    assert!(
                        (q - q0).abs() <= 1e-12 * scale,
                        "seed {seed} k {k}: {q} {q0}"
                    );
                    assert!(
                        (residual - r0).abs() <= 1e-12 * scale,
                        "seed {seed} k {k}: {residual} {r0}"
                    );
                }
            }
        }
    }
}
