//! The regional bound `[A16]` (`paper-notes/anisotropic.md`): each region's own block of
//! `M = D^T S D`, exactly, less the charges of the blocks between regions, is proven positive
//! semidefinite (with a margin `zeta`) on the vectors whose sum over the region vanishes, by
//! the inertia of that block bordered by the region's constant directions; the `3k` coarse
//! directions are bounded by the shared coarse correction (`certify/multiple/coarse.rs`, with
//! unit weights). Nothing of a region's own edges is compared away, so it proves where the
//! block comparison `[A15]` fails (sparse graphs), with factors of the regions' size: a rig's
//! images split by sensor, whose whole `3n` factor is over the memory budget.

use super::groups::{BlockGroups, anisotropic_operator};
use super::{BlockComparison, BlockFailure};
use crate::certify::multiple::coarse::{
    BlockOperator, COARSE_RELATIVE_RESIDUAL, CoarseSpace, GaugeBounds, ZETA_FRACTION,
    coarse_terms_gauged,
};
use crate::certify::multiple::multipliers::{TraceBound, gauge_terms, multipliers};
use crate::certify::multiple::scalar::{failure_text, fro, orthogonality_defect, ostrowski};
use crate::error::{Error, Result};
use crate::linalg::UNIT_ROUNDOFF as U;
use crate::linalg::block_pattern::BlockPattern;
use crate::linalg::cholesky::gamma;
use crate::linalg::ldlt::ldlt_inertia;
use crate::linalg::small_symmetric::verified_min_eigenvalue;
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use nalgebra::{Matrix3, Matrix6, SymmetricEigen};
use std::collections::HashMap;
use std::time::Instant;

/// The dual bound `[D4]` of the estimate's own multipliers proven by the regional bound
/// (`sum tr(Lambda_i) + 3n min(mu, 0)`, less its rounding and the data defect) with `region[i]`
/// node `i`'s region (each region connected by its own edges), its factors within `limits.0`
/// values and its work within `limits.1` seconds; `Ok(Err(why))` when it does not prove.
pub(crate) fn regional_dual_bound(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    region: &[usize],
    limits: (usize, Option<f64>),
) -> Result<std::result::Result<(f64, BlockComparison), String>> {
    let lambdas = multipliers(problem, rotations)?;
    let stop_at = limits
        .1
        .and_then(|s| Instant::now().checked_add(std::time::Duration::try_from_secs_f64(s).ok()?));
    let found = regional_bound(problem, (rotations, &lambdas), region, (limits.0, stop_at))?;
    Ok(found.map(|proof| {
        let bound = TraceBound::new(problem, &lambdas).at_mu(proof.verified_min_eigenvalue);
        (bound, proof)
    }))
}

/// Proven `lambda_min(S) >= mu` by the regional bound at `rotations` and `lambdas`, or why not.
pub(crate) fn regional_bound(
    problem: &MultipleProblem,
    (rotations, lambdas): (&[Rotation], &[Matrix3<f64>]),
    region: &[usize],
    (max_values, stop_at): (usize, Option<Instant>),
) -> Result<std::result::Result<BlockComparison, String>> {
    let Some(information) = problem.information() else {
        return Err(Error::InvalidSettings {
            name: "problem".into(),
            reason: "the regional bound is for edges with information matrices".into(),
        });
    };
    let n = problem.num_rotations();
    if rotations.len() != n || lambdas.len() != n || region.len() != n {
        return Err(Error::InvalidSettings {
            name: "rotations".into(),
            reason: "the regional bound needs one rotation, multiplier and region per node".into(),
        });
    }
    let why = |f: BlockFailure| failure_text(0.0, Err(f), 3);
    let Ok(t_max) = orthogonality_defect(rotations) else {
        return Ok(Err(why(BlockFailure::NotOrthogonal)));
    };
    let m = anisotropic_operator(problem, information, rotations, lambdas);
    let of = largest_last(region);
    let Some(charges) = cross_charges(&m, &of) else {
        return Ok(Err(why(BlockFailure::Numerical)));
    };
    let zeta = ZETA_FRACTION * m.row_abs();
    let shift = (zeta + m.form_error()) * (1.0 + 4.0 * U);
    let count = of.iter().max().map_or(0, |g| g + 1);
    let mut proofs = Vec::with_capacity(count);
    for g in 0..count {
        if stop_at.is_some_and(|t| Instant::now() >= t) {
            return Ok(Err(
                "its time ran out between the regions' factorisations".into()
            ));
        }
        match prove_region(&m, (&of, g), &charges, shift, (max_values, stop_at)) {
            Ok(Ok(p)) => proofs.push(p),
            Ok(Err(over)) => return Ok(Err(over)),
            Err(f) => return Ok(Err(format!("region {g}: {}", why(f)))),
        }
    }
    let weights = vec![Matrix3::identity(); n];
    let Some(space) = BlockGroups::new(&of, &weights) else {
        return Ok(Err(why(BlockFailure::Numerical)));
    };
    let terms = gauge_terms(problem, rotations, lambdas);
    let gauge = GaugeBounds {
        rho0: terms.h,
        rho1: terms.rho * (1.0 + t_max) * (1.0 + 4.0 * U),
    };
    let zeta_free = zeta * (1.0 - 4.0 * U);
    let coarse = (zeta_free, COARSE_RELATIVE_RESIDUAL, stop_at);
    let Some(coarse) = coarse_terms_gauged(&m, &space, gauge, coarse) else {
        return Ok(Err(why(BlockFailure::Numerical)));
    };
    let Some(mu) = ostrowski(coarse.mu(space.kappa()), t_max) else {
        return Ok(Err(why(BlockFailure::Numerical)));
    };
    let largest = |f: fn(&RegionProof) -> f64| proofs.iter().map(f).fold(0.0, f64::max);
    Ok(Ok(BlockComparison {
        verified_min_eigenvalue: mu,
        max_delta: charges.iter().map(|c| c.norm()).fold(0.0, f64::max),
        dropped_edges: problem
            .edges()
            .iter()
            .filter(|e| of[e.i] != of[e.j])
            .count(),
        zeta,
        headroom: largest(|p| p.headroom),
        backward_error: largest(|p| p.backward_error),
        factor_nonzeros: proofs.iter().map(|p| p.factor_values).max().unwrap_or(0),
        kappa: space.kappa(),
        residual_bound: coarse.rho,
        regions: count,
    }))
}

/// The regions renumbered `0..k` in order of first appearance, the largest last (its `kappa`
/// is the one the coarse bound's gauge directions take).
pub(super) fn largest_last(region: &[usize]) -> Vec<usize> {
    let mut ids: HashMap<usize, usize> = HashMap::new();
    let of = region
        .iter()
        .map(|r| {
            let next = ids.len();
            *ids.entry(*r).or_insert(next)
        })
        .collect();
    super::largest_last(of)
}

/// A node pair `(a, b)`, `a < b`, between regions: the sum `B` of its blocks `fl(M_ab)`, the
/// sum of their Frobenius norms and their number.
type Pair = ((usize, usize), (Matrix3<f64>, f64, usize));

/// Passes of [`balanced_splits`].
const SPLIT_PASSES: usize = 3;

/// The range of a pair's split `t` (see [`cross_charges`]).
const SPLIT_RANGE: (f64, f64) = (0.5, 2.0);

/// Per node, a charge `P_i` (symmetric) with `x^T M_cross x >= -sum_i x_i^T P_i x_i` for the
/// blocks of `fl(M)` between regions, exactly: each pair's blocks summed into `B` (the sum's
/// rounding `gamma(k + 1)` of their magnitudes), `[[t |B^T|, B], [B^T, |B| / t]] >= l I`
/// verified (`|B| = (B^T B)^{1/2}` computed: any symmetric pair is valid with its verified `l`),
/// and `t |B^T| + c I`, `|B| / t + c I` charged, `c` the rest. The split `t` moves a pair's
/// charge toward the endpoint less loaded against its own diagonal block (a choice: the
/// verification is of the pair as charged). Each node's sum is raised by its rounding.
pub(super) fn cross_charges(m: &BlockOperator, of: &[usize]) -> Option<Vec<Matrix3<f64>>> {
    let (n, diag) = (of.len(), m.diagonal());
    let mut pairs: HashMap<(usize, usize), (Matrix3<f64>, f64, usize)> = HashMap::new();
    for (i, j, b) in m.blocks().iter().filter(|(i, j, _)| of[*i] != of[*j]) {
        let (key, block) = if i < j {
            ((*i, *j), *b)
        } else {
            ((*j, *i), b.transpose())
        };
        let entry = pairs.entry(key).or_insert((Matrix3::zeros(), 0.0, 0));
        entry.0 += block;
        entry.1 += fro(&block);
        entry.2 += 1;
    }
    let mut pairs: Vec<Pair> = pairs.into_iter().collect();
    pairs.sort_unstable_by_key(|(key, _)| *key);
    let splits = balanced_splits(diag, &pairs);
    let ChargeSums {
        sum,
        magnitude,
        terms,
    } = charge_sums(n, &pairs, &splits)?;
    let raised = sum
        .iter()
        .zip(&magnitude)
        .zip(&terms)
        .map(|((s, &mag), &k)| raise(s, gamma(k + 2) * mag * (1.0 + gamma(k + 2))))
        .collect::<Vec<_>>();
    raised
        .iter()
        .all(|c| c.iter().all(|x| x.is_finite()))
        .then_some(raised)
}

/// Per node, `fl(sum)` of its pairs' charges, the sum of their Frobenius norms and their
/// number.
struct ChargeSums {
    sum: Vec<Matrix3<f64>>,
    magnitude: Vec<f64>,
    terms: Vec<usize>,
}

/// [`ChargeSums`] of the pairs with their splits `t`.
fn charge_sums(n: usize, pairs: &[Pair], splits: &[f64]) -> Option<ChargeSums> {
    let mut sum = vec![Matrix3::zeros(); n];
    let mut magnitude = vec![0.0f64; n];
    let mut terms = vec![0usize; n];
    for (&((a, b), (block, mag, k)), &t) in pairs.iter().zip(splits) {
        let (p, q, c) = pair_charge(&block, t, gamma(k + 1) * mag)?;
        let (p, q) = (p + Matrix3::identity() * c, q + Matrix3::identity() * c);
        for (v, charge) in [(a, p), (b, q)] {
            sum[v] += charge;
            magnitude[v] += fro(&charge);
            terms[v] += 1;
        }
    }
    Some(ChargeSums {
        sum,
        magnitude,
        terms,
    })
}

/// Each pair's split `t`: `1` for a pair whose block is mostly symmetric (a consistent edge's
/// charge is its own support at both ends), else moved, over [`SPLIT_PASSES`] passes, toward
/// equal shares `t |B^T|`, `|B| / t` of what each endpoint has left without the pair
/// (within [`SPLIT_RANGE`]). Only a choice: the charges are verified as split.
fn balanced_splits(diag: &[Matrix3<f64>], pairs: &[Pair]) -> Vec<f64> {
    // each pair's polar pair once; the passes' sums unverified (a choice only)
    let polar: Vec<(Matrix3<f64>, Matrix3<f64>)> = pairs
        .iter()
        .map(|(_, (b, _, _))| {
            (
                psd_sqrt(&(b * b.transpose())),
                psd_sqrt(&(b.transpose() * b)),
            )
        })
        .collect();
    let mut splits = vec![1.0f64; pairs.len()];
    for _ in 0..SPLIT_PASSES {
        let mut sum = vec![Matrix3::zeros(); diag.len()];
        for (((a, b), _), ((p, q), t)) in pairs.iter().zip(polar.iter().zip(&splits)) {
            sum[*a] += p * *t;
            sum[*b] += q / *t;
        }
        for (((a, b), (block, _, _)), ((p, q), t)) in
            pairs.iter().zip(polar.iter().zip(splits.iter_mut()))
        {
            if fro(&(block + block.transpose())) >= fro(&(block - block.transpose())) {
                continue;
            }
            let (p, q) = (p * *t, q / *t);
            let load_a = relative_load(&(diag[*a] - sum[*a] + p), &p);
            let load_b = relative_load(&(diag[*b] - sum[*b] + q), &q);
            let next = *t * (load_b / load_a).sqrt();
            if next.is_finite() {
                *t = next.clamp(SPLIT_RANGE.0, SPLIT_RANGE.1);
            }
        }
    }
    splits
}

/// `lambda_max(D^{-1/2} C D^{-1/2})` for a node's diagonal block `D` (its eigenvalues floored
/// at `1e-9` of the largest) and its charge `C`: how much of its own strength the charge takes.
fn relative_load(d: &Matrix3<f64>, c: &Matrix3<f64>) -> f64 {
    let e = SymmetricEigen::new(0.5 * (d + d.transpose()));
    let floor = 1e-9 * e.eigenvalues.amax();
    let inv_sqrt = e.eigenvalues.map(|v| 1.0 / v.max(floor).sqrt());
    let w = e.eigenvectors * Matrix3::from_diagonal(&inv_sqrt) * e.eigenvectors.transpose();
    let load = SymmetricEigen::new(0.5 * (w * c * w + (w * c * w).transpose()))
        .eigenvalues
        .max();
    if load.is_finite() {
        load.max(1e-300)
    } else {
        f64::INFINITY
    }
}

/// `s` with its diagonal raised by `e` and the rounding of that addition (`u |s_aa|` twice
/// over, as in `edges.rs`).
fn raise(s: &Matrix3<f64>, e: f64) -> Matrix3<f64> {
    let mut r = *s;
    for a in 0..3 {
        r[(a, a)] += e * (1.0 + 4.0 * U) + 4.0 * U * s[(a, a)].abs();
    }
    r
}

/// `(t |B^T|, |B| / t, c)` with `[[t |B^T| + c I, B_exact], [B_exact^T, |B| / t + c I]] >= 0`
/// for every `B_exact` within `err` of `B` in the 2-norm.
fn pair_charge(b: &Matrix3<f64>, t: f64, err: f64) -> Option<(Matrix3<f64>, Matrix3<f64>, f64)> {
    let p = psd_sqrt(&(b * b.transpose())) * t;
    let q = psd_sqrt(&(b.transpose() * b)) / t;
    let six = Matrix6::from_fn(|r, col| match (r < 3, col < 3) {
        (true, true) => p[(r, col)],
        (true, false) => b[(r, col - 3)],
        (false, true) => b[(col, r - 3)],
        (false, false) => q[(r - 3, col - 3)],
    });
    let l = verified_min_eigenvalue(&six)?;
    let c = ((-l).max(0.0) + err) * (1.0 + 8.0 * U);
    c.is_finite().then_some((p, q, c))
}

/// The square root of a symmetric positive semidefinite `a` (negative rounding clipped): only
/// a choice, [`pair_charge`] verifies what it gives.
fn psd_sqrt(a: &Matrix3<f64>) -> Matrix3<f64> {
    let e = SymmetricEigen::new(0.5 * (a + a.transpose()));
    let d = Matrix3::from_diagonal(&e.eigenvalues.map(|v| v.max(0.0).sqrt()));
    let s = e.eigenvectors * d * e.eigenvectors.transpose();
    0.5 * (s + s.transpose())
}

/// What one region's factorisation proved.
struct RegionProof {
    headroom: f64,
    backward_error: f64,
    factor_values: usize,
}

/// Region `g`'s block `A = fl(M)_gg - blkdiag(P) - shift I` is positive semidefinite on the
/// vectors whose sum over the region vanishes: its bordered matrix `K = [[A, E], [E^T, 0]]`
/// (`E = 1 (x) I_3`) less `h I` shows exactly three negative pivots, `h` above the `LDL^T`'s
/// backward error and the forming error, so `K >= LDL^T` has at most three negative
/// eigenvalues, and a bordered matrix has as many as `A` has on `E^perp` plus three (Gould).
/// `Ok(Err(why))`: its factor is over `max_values`, or its predicted time past `stop_at`.
fn prove_region(
    m: &BlockOperator,
    (of, g): (&[usize], usize),
    charges: &[Matrix3<f64>],
    shift: f64,
    (max_values, stop_at): (usize, Option<Instant>),
) -> std::result::Result<std::result::Result<RegionProof, String>, BlockFailure> {
    let nodes: Vec<usize> = (0..of.len()).filter(|&i| of[i] == g).collect();
    let mut local = vec![usize::MAX; of.len()];
    nodes.iter().enumerate().for_each(|(a, &i)| local[i] = a);
    let hub = nodes.len();
    let own: Vec<(usize, usize, Matrix3<f64>)> = m
        .blocks()
        .iter()
        .filter(|(i, j, _)| of[*i] == g && of[*j] == g)
        .map(|(i, j, b)| (local[*i], local[*j], *b))
        .collect();
    let pairs = own
        .iter()
        .map(|(a, b, _)| (*a, *b))
        .chain((0..hub).map(|a| (hub, a)));
    let pattern = BlockPattern::new(hub + 1, 3, pairs);
    let (symbolic, _) = match pattern.symbolic_within(max_values) {
        Ok(Ok(s)) => s,
        Ok(Err(predicted)) => {
            return Ok(Err(format!(
                "region {g}'s factor is predicted at {predicted:.1e} values, above the \
                 {max_values:.1e} the budget allows"
            )));
        }
        Err(_) => return Err(BlockFailure::Numerical),
    };
    let time = crate::certify::budget::Budget {
        max_memory_bytes: u64::MAX,
        max_seconds: stop_at.map(|t| t.saturating_duration_since(Instant::now()).as_secs_f64()),
    };
    let (values, work) = (
        symbolic.len_val(),
        crate::linalg::cholesky::factor_multiply_adds(&symbolic),
    );
    if let Err(why) = time.counted_factorisations_fit(values, work, values) {
        return Ok(Err(format!("region {g}: {why}")));
    }
    let row = |b: &Matrix3<f64>| (0..3).map(|r| b.row(r).abs().sum()).fold(0.0, f64::max);
    let region = Region {
        pattern: &pattern,
        own: &own,
        diag: nodes
            .iter()
            .map(|&i| {
                (
                    m.diagonal()[i] - charges[i],
                    row(&m.diagonal()[i]) + row(&charges[i]),
                )
            })
            .collect(),
    };
    let mut h = 1e-6 * m.row_abs().max(f64::MIN_POSITIVE);
    for _ in 0..2 {
        let bound = region.inertia(&symbolic, shift, h)?;
        if bound <= h {
            return Ok(Ok(RegionProof {
                headroom: h,
                backward_error: bound,
                factor_values: symbolic.len_val(),
            }));
        }
        h = 4.0 * bound;
    }
    Err(BlockFailure::BackwardError)
}

/// A region's bordered matrix: its pattern (the region's nodes, then the border's), its own
/// blocks in local numbering and its diagonal blocks `fl(M_ii - P_i)` less the charges, with
/// the magnitudes they were formed from (`|M_ii| + |P_i|`, largest row sums).
struct Region<'a> {
    pattern: &'a BlockPattern,
    own: &'a [(usize, usize, Matrix3<f64>)],
    diag: Vec<(Matrix3<f64>, f64)>,
}

impl Region<'_> {
    /// The `LDL^T` of `K - h I` (the diagonal less `shift + h`): the backward error plus twice
    /// the forming error when exactly three pivots are negative.
    fn inertia(
        &self,
        symbolic: &faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
        shift: f64,
        h: f64,
    ) -> std::result::Result<f64, BlockFailure> {
        let p = self.pattern;
        let hub = self.diag.len();
        let mut val = vec![0.0f64; p.nnz()];
        let mut magnitude = vec![0.0f64; hub + 1];
        let mut terms = vec![2usize; hub + 1];
        let row = |b: &Matrix3<f64>| (0..3).map(|r| b.row(r).abs().sum()).fold(0.0, f64::max);
        for (a, (d, formed_from)) in self.diag.iter().enumerate() {
            let block = d - Matrix3::identity() * (shift + h);
            p.add(&mut val, a, a, 0, &block);
            magnitude[a] += formed_from + shift + h;
            p.add(&mut val, hub, a, p.slot(hub, a), &Matrix3::identity());
            magnitude[a] += 1.0;
            magnitude[hub] += 1.0;
        }
        p.add(&mut val, hub, hub, 0, &(-Matrix3::identity() * h));
        magnitude[hub] += h;
        for (a, b, block) in self.own {
            p.add(&mut val, *a, *b, p.slot(*a, *b), block);
            for v in [*a, *b] {
                magnitude[v] += row(block).max(row(&block.transpose()));
                terms[v] += 1;
            }
        }
        let inertia =
            ldlt_inertia(symbolic, p.matrix(&val)).map_err(|_| BlockFailure::Numerical)?;
        if inertia.negative != 3 {
            return Err(BlockFailure::Inertia {
                negative_pivots: inertia.negative,
            });
        }
        let most = terms.iter().copied().max().unwrap_or(2);
        let forming = gamma(most + 4) * magnitude.iter().copied().fold(0.0, f64::max);
        let bound = inertia.backward_error + 2.0 * forming;
        bound
            .is_finite()
            .then_some(bound)
            .ok_or(BlockFailure::Numerical)
    }
}
