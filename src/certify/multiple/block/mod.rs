//! The block comparison certificate `[A15]` (`paper-notes/anisotropic.md`): the scalar
//! comparison `[D13]` for anisotropic edges. It proves that the certificate matrix
//! `S = Q - blkdiag(Lambda)` of an estimate is (nearly) positive semidefinite from the inertia
//! of a **block Laplacian of a subgraph**, whose `3n x 3n` factor fills far less than `S`'s on
//! graphs without small separators (a 10^4-camera view graph of 10^5 edges: `S`'s factor holds
//! 3.9e8 values).
//!
//! The argument (every step rigorous, rounding included):
//! 1. `M = D^T S D`, `D = blkdiag(R_i)`, has `lambda_min(S) >= lambda_min(M) / (1 - t_max)`
//!    when negative (Ostrowski; `t_max >= ||R_i^T R_i - I||_F`).
//! 2. Edge by edge, with `E_e = R_i^T 2M_e R_ij^T R_j = S_e + K_e` (symmetric + skew part),
//!    `d = x_j - x_i`, `m = (x_i + x_j) / 2`: the edge's part of `x^T M x` is
//!    `q_e = d^T S_e d - 2 m^T K_e d` and the diagonal blocks keep `G_i = M_ii - sum_e S_e`
//!    (zero at the estimate's own multipliers, up to rounding). For any `3 x 3` `W_e`, `Z_e`
//!    with `[[Z_e, -K_e], [-K_e^T, S_e - W_e]] >= 0`:
//!    `q_e >= d^T W_e d - ||Z_e|| (|x_i|^2 + |x_j|^2) / 2`. So `M >= C - diag(delta) (x) I_3`
//!    with `C` the block Laplacian of the kept weights `W_e` (an edge left out of `C` keeps
//!    `W_e = 0`), `delta_i` the charges. With `W_e = S_e / 2` and
//!    `Z_e = 2 K_e S_e^{-1} K_e^T`, the charge is second order in the residual.
//! 3. `M v0 = D^T S Y` with `v0 = 1 (x) I_3`, and `v0^T M v0 = Y^T S Y` (the gauge terms
//!    `[D15]`, in double-double).
//! 4. `C v0 = 0` exactly. If `C - diag(w) (x) I_3` (`w = delta + zeta`) has at most three
//!    negative eigenvalues, it is positive semidefinite on the `w`-orthogonal complement of
//!    `v0` (the pencil lemma of `[D13]` with a three-dimensional null space), and the split
//!    `x = v0 a + x1` bounds the cross terms as in `[D13]` step 4.
//! 5. "At most three" is the inertia of an `LDL^T` of `C - diag(w) - h I` (Sylvester), with
//!    the headroom `h` above its rigorous backward error plus the forming error (Weyl).

mod edges;
mod groups;
mod operator;
mod outcome;
mod regional;
pub mod rungs;
mod subgraph;
#[cfg(test)]
mod tests;

use super::multipliers::{GaugeTerms, gauge_terms};
use super::scalar::{components, fro, orthogonality_defect, ostrowski, subgraph_edges};
use crate::error::{Error, Result};
use crate::linalg::block_pattern::BlockPattern;
use crate::linalg::cholesky::{UNIT_ROUNDOFF, gamma};
use crate::linalg::ldlt::ldlt_inertia;
use crate::linalg::small_symmetric::verified_min_eigenvalue3;
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use faer::sparse::linalg::cholesky::SymbolicCholesky;
use nalgebra::Matrix3;
pub use outcome::{BlockComparison, BlockFailure};
use regional::RegionAnalysis;
#[cfg(test)]
pub(crate) use regional::regional_bound;
pub(crate) use regional::regional_dual_bound;
pub use rungs::{BLOCK_GROUP_NODES, block_groups};
pub use subgraph::{BlockShape, TOP_UP_MAX_EDGES};

/// The factorised structure of a block comparison: the block Laplacian pattern of a subgraph
/// (or of the whole graph) and its symbolic `LDL^T` analysis.
pub struct BlockAnalysis {
    keep: Vec<bool>,
    structure: Structure,
    /// The ordering's count of the factor's values ([`BlockAnalysis::counted_values`]).
    counted_values: usize,
    shape: Option<BlockShape>,
    num_rotations: usize,
    /// Each node's component of the kept edges when the subgraph is split into regions
    /// (`[A15]`, "Regions"; empty otherwise).
    components: Vec<usize>,
    /// The regions asked for (0 without).
    regions: usize,
}

/// What a block comparison factorises: one block Laplacian (its pencil, step 5), or each
/// region's bordered block (`[A15]`, "Regions, bordered"), one after another.
enum Structure {
    Whole {
        pattern: BlockPattern,
        symbolic: Box<SymbolicCholesky<usize>>,
        /// Per kept edge, its slot in the pattern (`usize::MAX` for a dropped edge).
        slots: Vec<usize>,
    },
    Regions(Vec<RegionAnalysis>),
}

impl BlockAnalysis {
    /// The subgraph of `shape` at `rotations` (chosen by strength and topped up with information
    /// matrices, else the scalar comparison's choice `[D13]` of `shape.edges_per_node` edges per
    /// node, where `shape.top_up` has nothing to estimate and is not used), or
    /// the whole graph for `None`; refused before the symbolic analysis when its factor is
    /// predicted above `max_values` values: `Ok(Err(predicted))`.
    pub fn new(
        problem: &MultipleProblem,
        rotations: &[Rotation],
        shape: Option<BlockShape>,
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        Self::grouped(problem, rotations, shape, 1, max_values)
    }

    /// The subgraph of `shape` in `groups` connected regions (`[A15]`, "Regions";
    /// `scalar/partition.rs`): each region's own edges chosen as in [`BlockAnalysis::new`],
    /// the edges between regions dropped (charged), every region's pencil proven apart and
    /// the regions' coarse directions bounded by the shared coarse correction. Its factor
    /// fills like a graph `groups` times smaller. `groups <= 1`, a whole graph (`shape`
    /// `None`) or a problem without information matrices: [`BlockAnalysis::new`]. Refused like
    /// it.
    pub fn grouped(
        problem: &MultipleProblem,
        rotations: &[Rotation],
        shape: Option<BlockShape>,
        groups: usize,
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        problem.check_estimate(rotations)?;
        let (region, keep) = match (shape, problem.information()) {
            (Some(s), _) if !(valid(s.edges_per_node) && valid(s.top_up)) => {
                return Err(Error::InvalidSettings {
                    name: "shape".into(),
                    reason: format!("edges per node and top-up must be numbers >= 0, got {s:?}"),
                });
            }
            (Some(s), Some(info)) if groups > 1 => {
                let (region, keep) =
                    subgraph::strong_regions(problem, info, rotations, (s, groups));
                (Some(region), keep)
            }
            (Some(s), Some(info)) => (
                None,
                subgraph::strong_subgraph_edges(problem, info, rotations, s),
            ),
            // without information matrices (which the comparison itself refuses): no regions
            (Some(s), None) => (None, subgraph_edges(problem, rotations, s.edges_per_node)),
            (None, _) => (None, vec![true; problem.num_edges()]),
        };
        Self::from_kept(
            problem,
            keep,
            (shape, region.is_some().then_some(groups)),
            max_values,
        )
    }

    /// The analysis of the kept edges `keep` (`regions`: the regions asked for, whose kept
    /// edges' components are proven apart; `None`: one pencil).
    fn from_kept(
        problem: &MultipleProblem,
        keep: Vec<bool>,
        (shape, regions): (Option<BlockShape>, Option<usize>),
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        let n = problem.num_rotations();
        let kept = || {
            problem
                .edges()
                .iter()
                .zip(&keep)
                .filter(|(_, k)| **k)
                .map(|(e, _)| (e.i, e.j))
        };
        let (structure, counted_values, components) = match regions {
            Some(_) => {
                let left_out: Vec<bool> = keep.iter().map(|k| !k).collect();
                let of = largest_last(components(problem, &left_out));
                match RegionAnalysis::of_regions(&of, kept(), max_values)? {
                    Ok(r) => {
                        let counted = r.iter().map(RegionAnalysis::counted).sum();
                        (Structure::Regions(r), counted, of)
                    }
                    Err(predicted) => return Ok(Err(predicted)),
                }
            }
            None => {
                let pattern = BlockPattern::new(n, 3, kept());
                let (symbolic, counted) = match pattern.symbolic_within(max_values)? {
                    Ok(s) => s,
                    Err(predicted) => return Ok(Err(predicted)),
                };
                let slots = problem
                    .edges()
                    .iter()
                    .zip(&keep)
                    .map(|(e, &k)| {
                        if k {
                            pattern.slot(e.i, e.j)
                        } else {
                            usize::MAX
                        }
                    })
                    .collect();
                let whole = Structure::Whole {
                    pattern,
                    symbolic: Box::new(symbolic),
                    slots,
                };
                (whole, counted, Vec::new())
            }
        };
        Ok(Ok(BlockAnalysis {
            keep,
            structure,
            counted_values,
            shape,
            num_rotations: n,
            regions: regions.unwrap_or(0),
            components,
        }))
    }

    /// The components its comparison proves apart: the regions of [`BlockAnalysis::grouped`]
    /// (at least one each), 0 for any other analysis.
    pub fn groups(&self) -> usize {
        self.components.iter().max().map_or(0, |m| m + 1)
    }

    /// The regions it was split into (0 without; each holds at least one component).
    pub fn regions(&self) -> usize {
        self.regions
    }

    /// Values of the coarse correction's vectors (0 without regions): `3` columns of length
    /// `3n` per region in its conjugate gradients' seven vectors.
    pub fn coarse_values(&self) -> usize {
        (3 * self.groups())
            .saturating_mul(3 * self.num_rotations)
            .saturating_mul(7)
    }

    /// The negative pivots its factorisation must show: three (the pencil's, or each region's
    /// bordered block's besides its deflated directions).
    pub(super) fn expected_negative_pivots(&self) -> usize {
        3
    }

    /// Stored values of the factor (in regions: of the largest region's, each factorised
    /// apart).
    pub fn factor_len(&self) -> usize {
        self.factorisations()
            .map(|(values, _, _)| values)
            .max()
            .unwrap_or(0)
    }

    /// The minimum-degree ordering's count of the factor's values (without the explicit zeros
    /// of relaxed supernodes that [`Self::factor_len`] stores; in regions, their sum): the
    /// count in which it compares with the whole graph's.
    pub fn counted_values(&self) -> usize {
        self.counted_values
    }

    /// The counted multiply-adds of its numeric factorisations.
    pub fn factor_multiply_adds(&self) -> f64 {
        self.factorisations().map(|(_, _, work)| work).sum()
    }

    /// Edges of the graph it was made for.
    pub fn num_edges(&self) -> usize {
        self.keep.len()
    }

    /// Bytes of numeric scratch the largest `LDL^T` factorisation allocates besides the factor.
    pub fn scratch_bytes(&self) -> usize {
        self.factorisations().map(|(_, b, _)| b).max().unwrap_or(0)
    }

    /// Per factorisation: its stored values, scratch bytes and multiply-adds.
    pub(super) fn factorisations(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        use crate::linalg::cholesky::{factor_multiply_adds, ldlt_scratch_bytes};
        let (whole, regions) = match &self.structure {
            Structure::Whole { symbolic, .. } => (Some(symbolic), &[][..]),
            Structure::Regions(r) => (None, r.as_slice()),
        };
        let whole = whole.map(|s| (s.len_val(), ldlt_scratch_bytes(s), factor_multiply_adds(s)));
        let regions = regions
            .iter()
            .map(|r| (r.len_val(), r.scratch_bytes(), r.multiply_adds()));
        whole.into_iter().chain(regions)
    }

    /// Edges left out of the block Laplacian.
    pub fn dropped_edges(&self) -> usize {
        self.keep.iter().filter(|k| !**k).count()
    }

    /// The subgraph's shape (`None`: the whole graph).
    pub fn shape(&self) -> Option<BlockShape> {
        self.shape
    }
}

/// The components renumbered so that the largest is the last (its `kappa` is the one the
/// coarse bound's gauge directions take, `[A15]` "Regions").
pub(super) fn largest_last(mut of: Vec<usize>) -> Vec<usize> {
    let count = of.iter().max().map_or(0, |m| m + 1);
    let mut size = vec![0usize; count];
    of.iter().for_each(|&g| size[g] += 1);
    let Some(largest) = (0..count).max_by_key(|&g| (size[g], std::cmp::Reverse(g))) else {
        return of;
    };
    let last = count - 1;
    for g in of.iter_mut() {
        if *g == largest {
            *g = last;
        } else if *g == last {
            *g = largest;
        }
    }
    of
}

/// A finite number `>= 0`.
fn valid(x: f64) -> bool {
    x.is_finite() && x >= 0.0
}

/// Try to prove `lambda_min(S) >= mu` for `S = Q - blkdiag(sym(Lambda))` of the anisotropic
/// `problem` at `rotations` by the block comparison `[A15]` on `analysis`'s (sub)graph.
/// `target > 0` is the `|mu|` the caller needs (it sets `zeta`). `Ok(Err(..))` says why no
/// proof was found; `Err` only for inconsistent inputs.
pub fn block_comparison(
    problem: &MultipleProblem,
    analysis: &BlockAnalysis,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    target: f64,
) -> Result<std::result::Result<BlockComparison, BlockFailure>> {
    block_comparison_until(problem, analysis, rotations, lambdas, (target, None))
}

/// [`block_comparison`] whose coarse correction (an analysis in regions,
/// [`BlockAnalysis::grouped`]) stops its conjugate gradients at `stop_at`: a weaker bound,
/// still proven.
pub fn block_comparison_until(
    problem: &MultipleProblem,
    analysis: &BlockAnalysis,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    (target, stop_at): (f64, Option<std::time::Instant>),
) -> Result<std::result::Result<BlockComparison, BlockFailure>> {
    check_points(problem, analysis, rotations, lambdas)?;
    let gauge = gauge_terms(problem, rotations, lambdas);
    let points = (rotations, lambdas);
    block_comparison_with(problem, analysis, points, (target, stop_at), &gauge)
}

/// [`block_comparison_until`] with the gauge terms `[D15]` of `S` at these rotations and
/// multipliers already made (the ladder's check keeps them).
pub(in crate::certify::multiple) fn block_comparison_with(
    problem: &MultipleProblem,
    analysis: &BlockAnalysis,
    (rotations, lambdas): (&[Rotation], &[Matrix3<f64>]),
    (target, stop_at): (f64, Option<std::time::Instant>),
    gauge: &GaugeTerms,
) -> Result<std::result::Result<BlockComparison, BlockFailure>> {
    let Some(information) = problem.information() else {
        return Err(Error::InvalidSettings {
            name: "problem".into(),
            reason: "the block comparison is for edges with information matrices".into(),
        });
    };
    check_points(problem, analysis, rotations, lambdas)?;
    let points = (rotations, lambdas);
    if analysis.groups() > 0 {
        return Ok(groups::compare_bordered(
            (problem, information),
            analysis,
            points,
            stop_at,
            gauge,
        ));
    }
    Ok(compare(
        (problem, information),
        analysis,
        points,
        target,
        gauge,
    ))
}

/// One rotation and one multiplier per node, and an analysis of this view graph.
fn check_points(
    problem: &MultipleProblem,
    analysis: &BlockAnalysis,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
) -> Result<()> {
    let n = problem.num_rotations();
    if rotations.len() != n || lambdas.len() != n || analysis.num_rotations != n {
        return Err(Error::InvalidSettings {
            name: "rotations".into(),
            reason: "block comparison needs one rotation and one multiplier per node".into(),
        });
    }
    if analysis.keep.len() != problem.num_edges() {
        return Err(Error::InvalidSettings {
            name: "analysis".into(),
            reason: "the block analysis was made for a different view graph".into(),
        });
    }
    Ok(())
}

/// Steps 1 to 5 on consistent inputs.
fn compare(
    (problem, information): (
        &MultipleProblem,
        &[crate::multiple::anisotropic::Information],
    ),
    analysis: &BlockAnalysis,
    (rotations, lambdas): (&[Rotation], &[Matrix3<f64>]),
    target: f64,
    gauge: &GaugeTerms,
) -> std::result::Result<BlockComparison, BlockFailure> {
    let u = UNIT_ROUNDOFF;
    let t_max = orthogonality_defect(rotations).map_err(|_| BlockFailure::NotOrthogonal)?;
    let c = edges::edge_blocks(problem, information, rotations, lambdas, &analysis.keep)?;
    // step 3: ||M v0|| <= ||D|| ||S Y||_F, -lambda_min(Y^T S Y) <= h
    let rho1 = gauge.rho * (1.0 + t_max) * (1.0 + 4.0 * u);
    let rho0 = gauge.h;
    // step 4: zeta makes the absorbed cross terms at most target / 4 (kappa at a tiny zeta
    // is at least kappa at the final one)
    let tiny = 1e-12 * c.d_max.max(f64::MIN_POSITIVE);
    let k0 = block_kappa(&c.delta, tiny).ok_or(BlockFailure::Numerical)?;
    let zeta = if target > 0.0 && target.is_finite() {
        (4.0 * rho1 * rho1 * k0 * k0 / target).max(tiny)
    } else {
        tiny
    };
    let (weights, zeta_free) = pencil_weights(&c.delta, zeta);
    let (headroom, backward_error) = prove_inertia(analysis, problem, &c, &weights)?;
    let kappa = block_kappa(&c.delta, zeta).ok_or(BlockFailure::Numerical)?;
    let nf = problem.num_rotations() as f64;
    let plain = -(2.0 * kappa * (1.0 + nf.sqrt() * kappa) * rho1 + kappa * kappa * rho0);
    let absorbed = if zeta_free > 0.0 {
        -(rho0 + rho1 * rho1 / zeta_free) * kappa * kappa
    } else {
        f64::NEG_INFINITY
    };
    let mu_m = plain.max(absorbed) * (1.0 + 1e-10);
    let proven = Proven {
        mu_m,
        t_max,
        zeta,
        inertia: (headroom, backward_error),
        kappa,
        residual_bound: rho1,
    };
    proven.outcome(&c, analysis)
}

/// The pencil's weights `W_i = fl(Delta_i + zeta I)` and `zeta'`, the part of `zeta` left in
/// them after their rounding (`fl(Delta_i + zeta I) >= Delta_i + zeta I - u |W_i|`, twice that
/// for safety).
fn pencil_weights(delta: &[Matrix3<f64>], zeta: f64) -> (Vec<Matrix3<f64>>, f64) {
    let u = UNIT_ROUNDOFF;
    let weights: Vec<Matrix3<f64>> = delta
        .iter()
        .map(|d| d + Matrix3::identity() * zeta)
        .collect();
    let w_max = weights.iter().map(|w| w.amax()).fold(0.0, f64::max);
    (weights, (zeta - 2.0 * u * w_max) * (1.0 - 4.0 * u))
}

/// What steps 2-5 proved: `mu_M <= lambda_min(M)` and the quantities the report carries.
struct Proven {
    mu_m: f64,
    t_max: f64,
    zeta: f64,
    /// The headroom and the backward error of the inertia's factorisation.
    inertia: (f64, f64),
    kappa: f64,
    residual_bound: f64,
}

impl Proven {
    /// Step 1 (Ostrowski): `lambda_min(S) >= mu_M / (1 - t_max)`, and the report.
    fn outcome(
        self,
        c: &edges::EdgeBlocks,
        analysis: &BlockAnalysis,
    ) -> std::result::Result<BlockComparison, BlockFailure> {
        let mu = ostrowski(self.mu_m, self.t_max).ok_or(BlockFailure::Numerical)?;
        Ok(BlockComparison {
            verified_min_eigenvalue: mu,
            max_delta: c.delta.iter().map(|d| d.norm()).fold(0.0, f64::max),
            dropped_edges: analysis.dropped_edges(),
            zeta: self.zeta,
            headroom: self.inertia.0,
            backward_error: self.inertia.1,
            factor_nonzeros: analysis.factor_len(),
            kappa: self.kappa,
            residual_bound: self.residual_bound,
            regions: analysis.groups(),
            deflated: 0,
        })
    }
}

/// `kappa >= ||sum_i W_i x_i|| / (lambda_min(sum_i W_i) |x|)` for the weights
/// `W_i = Delta_i + zeta I`: `sqrt(sum_i ||W_i||_F^2) / lambda_min(sum_i W_i)`, the sum's
/// rounding (`gamma(n + 2)` of the magnitudes) taken from its verified smallest eigenvalue;
/// `None` when that is not positive.
fn block_kappa(delta: &[Matrix3<f64>], zeta: f64) -> Option<f64> {
    let n = delta.len();
    let g = gamma(n + 4);
    let mut sum = Matrix3::zeros();
    let (mut sq, mut abs) = (0.0f64, 0.0f64);
    for d in delta {
        let w = d + Matrix3::identity() * zeta;
        let f = fro(&w) * (1.0 + 4.0 * UNIT_ROUNDOFF);
        sum += w;
        sq += f * f;
        abs += f;
    }
    let low = verified_min_eigenvalue3(&sum)? - 3.0 * g * abs * (1.0 + g);
    (low > 0.0).then(|| sq.sqrt() * (1.0 + g) / low * (1.0 + 8.0 * UNIT_ROUNDOFF))
}

/// Step 5: `(headroom, backward error)` when `C - blkdiag(W) - h I` shows exactly three
/// negative pivots within its headroom; `h` starts at `1e-6 d_max` and is retried once at 4
/// times the error.
fn prove_inertia(
    analysis: &BlockAnalysis,
    problem: &MultipleProblem,
    c: &edges::EdgeBlocks,
    weights: &[Matrix3<f64>],
) -> std::result::Result<(f64, f64), BlockFailure> {
    let mut h = 1e-6 * c.d_max.max(f64::MIN_POSITIVE);
    let mut retried = false;
    loop {
        let bound = factor_inertia(analysis, problem, c, weights, h)?;
        if bound <= h {
            return Ok((h, bound));
        }
        if retried {
            return Err(BlockFailure::BackwardError);
        }
        retried = true;
        h = 4.0 * bound;
    }
}

/// `LDL^T` of `C - blkdiag(W) - h I` (AMD order, no pivoting): a rigorous bound on
/// `||A_exact - P^T L D L^T P||_2` when exactly three pivots are negative and none is zero.
fn factor_inertia(
    analysis: &BlockAnalysis,
    problem: &MultipleProblem,
    c: &edges::EdgeBlocks,
    weights: &[Matrix3<f64>],
    h: f64,
) -> std::result::Result<f64, BlockFailure> {
    let Structure::Whole {
        pattern,
        symbolic,
        slots,
    } = &analysis.structure
    else {
        return Err(BlockFailure::Numerical); // an analysis in regions has no one pencil
    };
    let mut val = vec![0.0f64; pattern.nnz()];
    // row sums of the magnitudes of the terms that form each block row (the forming error)
    let mut magnitude = vec![0.0f64; weights.len()];
    for ((e, w), &slot) in problem.edges().iter().zip(&c.kept).zip(slots) {
        if slot == usize::MAX {
            continue;
        }
        pattern.add(&mut val, e.i, e.i, 0, w);
        pattern.add(&mut val, e.j, e.j, 0, w);
        pattern.add(&mut val, e.j, e.i, slot, &(-w));
        let row = (0..3).map(|r| w.row(r).abs().sum()).fold(0.0, f64::max);
        magnitude[e.i] += 2.0 * row;
        magnitude[e.j] += 2.0 * row;
    }
    for (i, w) in weights.iter().enumerate() {
        let shift = -(w + Matrix3::identity() * h);
        pattern.add(&mut val, i, i, 0, &shift);
        magnitude[i] += (0..3).map(|r| w.row(r).abs().sum()).fold(0.0, f64::max) + h;
    }
    let inertia =
        ldlt_inertia(symbolic, pattern.matrix(&val)).map_err(|_| BlockFailure::Numerical)?;
    if inertia.negative != analysis.expected_negative_pivots() {
        return Err(BlockFailure::Inertia {
            negative_pivots: inertia.negative,
        });
    }
    // every entry is a sum of at most 2 deg + 2 rounded terms
    let terms = 2 * c.deg_n.iter().copied().max().unwrap_or(0) + 4;
    let forming = gamma(terms + 2) * magnitude.iter().copied().fold(0.0, f64::max);
    let bound = inertia.backward_error + 2.0 * forming;
    bound
        .is_finite()
        .then_some(bound)
        .ok_or(BlockFailure::Numerical)
}
