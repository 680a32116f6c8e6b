//! The regional bound `[A16]` (`paper-notes/anisotropic.md`): each region's own block of
//! `M = D^T S D`, exactly, less the charges of the blocks between regions, is proven positive
//! semidefinite (with a margin `zeta`) on the vectors whose sum over the region vanishes, by
//! the inertia of that block bordered by the region's constant directions; the `3k` coarse
//! directions are bounded by the shared coarse correction (`certify/multiple/coarse.rs`, with
//! unit weights). Nothing of a region's own edges is compared away, so it proves where the
//! block comparison `[A15]` fails (sparse graphs), with factors of the regions' size: a rig's
//! images split by sensor, whose whole `3n` factor is over the memory budget.

use super::operator::anisotropic_operator;
use super::{BlockComparison, BlockFailure};
use crate::certify::multiple::block_operator::BlockOperator;
use crate::certify::multiple::coarse::verified_min_eigenvalue as verified_min_eigenvalue_dense;
use crate::certify::multiple::coarse::{
    COARSE_RELATIVE_RESIDUAL, CoarseSpace, GaugeBounds, ZETA_FRACTION, coarse_terms_gauged,
};
use crate::certify::multiple::deflated::{Column, RegionSpace, scaled_to_constant};
use crate::certify::multiple::multipliers::{TraceBound, gauge_terms, multipliers};
use crate::certify::multiple::scalar::{failure_text, fro, orthogonality_defect, ostrowski};
use crate::error::{Error, Result};
use crate::linalg::UNIT_ROUNDOFF as U;
use crate::linalg::block_pattern::BlockPattern;
use crate::linalg::cholesky::gamma;
use crate::linalg::ldlt::{
    FactorStorage, NegativeColumn, NegativePivots, Trailing, ldlt_negative_columns,
};
use crate::linalg::small_symmetric::verified_negative_part;
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use nalgebra::{DMatrix, Matrix3, Matrix6, SymmetricEigen};
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
    let gauge = GaugeBounds::of(&gauge_terms(problem, rotations, lambdas), t_max);
    let found = bordered_regions((&m, &m), (&of, None), (gauge, t_max), (max_values, stop_at));
    Ok(found
        .map(|mut proof| {
            proof.dropped_edges = problem
                .edges()
                .iter()
                .filter(|e| of[e.i] != of[e.j])
                .count();
            proof
        })
        .map_err(|(why, _)| why))
}

/// The regions' proofs and the coarse bound: each region `g`'s block of `blocks` less the
/// charges of `blocks`' blocks between regions is proven positive semidefinite with the margin
/// `zeta` on the complement of its constant (and deflated) directions, and the coarse bound
/// of `m` on the regions' space gives `lambda_min(S)` (step 1 with `t_max`). Sound when `x^T M
/// x >= x^T B x` for every `x` (`B` the exact matrix `blocks` stores, up to its forming
/// error): `blocks = m` (`[A16]`), or the block comparison's `C - blkdiag(Delta)` (`[A15]`,
/// "Regions, bordered"), whose regions have no blocks between them. `dropped_edges` is left 0
/// for the caller. `Err` says why not, with the failure it counts as.
pub(super) fn bordered_regions(
    (m, blocks): (&BlockOperator, &BlockOperator),
    (of, prepared): (&[usize], Option<&[RegionAnalysis]>),
    (gauge, t_max): (GaugeBounds, f64),
    (max_values, stop_at): (usize, Option<Instant>),
) -> std::result::Result<BlockComparison, (String, BlockFailure)> {
    let why = |f: BlockFailure| (failure_text(0.0, Err(f.clone()), 3), f);
    let charges = cross_charges(blocks, of).ok_or_else(|| why(BlockFailure::Numerical))?;
    let zeta = ZETA_FRACTION * blocks.row_abs();
    let shift = region_shift(blocks);
    let count = of.iter().max().map_or(0, |g| g + 1);
    let mut proofs = Vec::with_capacity(count);
    let mut storage = FactorStorage::default();
    for g in 0..count {
        let out_of_time = |why: String| (why, BlockFailure::OutOfTime);
        if stop_at.is_some_and(|t| Instant::now() >= t) {
            return Err(out_of_time(
                "its time ran out between the regions' factorisations".into(),
            ));
        }
        let analysed = prepared.and_then(|p| p.get(g));
        let limits = ((max_values, stop_at), analysed);
        match prove_region(blocks, (of, g), &charges, shift, limits, &mut storage) {
            Ok(Ok(p)) => proofs.push(p),
            Ok(Err(over)) => return Err(out_of_time(over)),
            Err(f) => {
                let (text, f) = why(f);
                return Err((format!("region {g}: {text}"), f));
            }
        }
    }
    // the largest region's factor values, not held through the coarse correction
    drop(storage);
    let deflated: Vec<Vec<Column>> = proofs
        .iter_mut()
        .map(|p| std::mem::take(&mut p.deflated))
        .collect();
    let deflated_count = deflated.iter().map(Vec::len).sum();
    let space = RegionSpace::new(of, deflated).ok_or_else(|| why(BlockFailure::Numerical))?;
    let zeta_free = zeta * (1.0 - 4.0 * U);
    let coarse = (zeta_free, COARSE_RELATIVE_RESIDUAL, stop_at);
    let coarse = coarse_terms_gauged(m, &space, gauge, coarse)
        .ok_or_else(|| why(BlockFailure::Numerical))?;
    let mu =
        ostrowski(coarse.mu(space.kappa()), t_max).ok_or_else(|| why(BlockFailure::Numerical))?;
    let largest = |f: fn(&RegionProof) -> f64| proofs.iter().map(f).fold(0.0, f64::max);
    Ok(BlockComparison {
        verified_min_eigenvalue: mu,
        max_delta: charges.iter().map(|c| c.norm()).fold(0.0, f64::max),
        dropped_edges: 0,
        zeta,
        headroom: largest(|p| p.headroom),
        backward_error: largest(|p| p.backward_error),
        factor_nonzeros: proofs.iter().map(|p| p.factor_values).max().unwrap_or(0),
        kappa: space.kappa(),
        residual_bound: coarse.rho,
        regions: count,
        deflated: deflated_count,
    })
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
    let l = verified_negative_part(&six)?;
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

/// The shift every region's block is proven above: the margin `zeta` ([`ZETA_FRACTION`] of
/// the largest row sum) and the operator's forming error.
fn region_shift(m: &BlockOperator) -> f64 {
    (ZETA_FRACTION * m.row_abs() + m.form_error()) * (1.0 + 4.0 * U)
}

/// The headroom `h` of a region's first factorisation: `1e-6` of the largest row sum.
fn first_headroom(m: &BlockOperator) -> f64 {
    1e-6 * m.row_abs().max(f64::MIN_POSITIVE)
}

/// What one region's factorisation proved, and the directions it deflated (sparse, in the
/// whole vector's numbering, each of norm about `|r|^{1/2}`; none in most regions).
struct RegionProof {
    headroom: f64,
    backward_error: f64,
    factor_values: usize,
    deflated: Vec<Column>,
}

/// The most negative pivots a region's first factorisation may show and still be deflated
/// (`[A16]`, "Deflation"): its factor's columns at them, up to eight blocks of border. 12
/// until 2026-12-04; the block comparison's three regions of the robust solve's inlier graph
/// at 10^4 cameras showed 14 in one region and prove with them (`[A15]`, "Regions").
const DEFLATION_MOST: usize = 24;

/// The deflated directions' border strength `|w|^2 / h` against the operator's largest row
/// sum: their penalty must dominate the negative curvature they take away (at `|w|^2 = |r|`,
/// as strong as the constant directions', one extra negative pivot of `-3.6e4` stayed on a
/// `3000 x 6` rig where `lambda_max` is `4.4e5`).
const DEFLATION_STRENGTH: f64 = 1e2;

/// Region `g`'s block `A = fl(M)_gg - blkdiag(P) - shift I` is positive semidefinite on the
/// vectors orthogonal to its border `F = [E, W]` (`E = 1 (x) I_3`, `W` the deflated directions,
/// none at first): the bordered matrix `K = [[A, F], [F^T, 0]]` less `h I` shows exactly as
/// many negative pivots as `F` has columns, `h` above the `LDL^T`'s backward error and the
/// forming error, so `K >= LDL^T` has at most that many negative eigenvalues, and a bordered
/// matrix has as many as `A` has on `F^perp` plus the rank of `F` (Gould; `F`'s rank proven in
/// [`RegionSpace::new`]). When the first factorisation shows at most [`DEFLATION_MOST`]
/// negative pivots, its factor's columns at them (where `LDL^T` is positive semidefinite off
/// them) become `W` and the region is factorised again. `Ok(Err(why))`: its factor is over
/// `max_values`, or its predicted time past `stop_at`.
fn prove_region(
    m: &BlockOperator,
    (of, g): (&[usize], usize),
    charges: &[Matrix3<f64>],
    shift: f64,
    (limits, prepared): ((usize, Option<Instant>), Option<&RegionAnalysis>),
    storage: &mut FactorStorage,
) -> std::result::Result<std::result::Result<RegionProof, String>, BlockFailure> {
    let (mut region, nodes) = Region::new(m, (of, g), charges);
    let h0 = first_headroom(m);
    // a proof's deflated directions in the whole vector's numbering
    let global = |mut proof: RegionProof| {
        for c in proof.deflated.iter_mut() {
            c.iter_mut()
                .for_each(|(a, _)| *a = 3 * nodes[*a / 3] + *a % 3);
        }
        proof
    };
    let directions = match region.prove(g, (shift, h0), (limits, prepared), storage)? {
        Ok(Attempt::Proven(proof)) => return Ok(Ok(global(proof))),
        Ok(Attempt::Negative { directions, .. }) if !directions.is_empty() => directions,
        Ok(Attempt::Negative { pivots, .. }) => {
            return Err(BlockFailure::Inertia {
                negative_pivots: pivots,
            });
        }
        Err(over) => return Ok(Err(over)),
    };
    region.border = deflation_border(directions, nodes.len());
    match region.prove(g, (shift, h0), (limits, None), storage)? {
        Ok(Attempt::Proven(mut proof)) => {
            proof.deflated = std::mem::take(&mut region.border);
            Ok(Ok(global(proof)))
        }
        Ok(Attempt::Negative { pivots, .. }) => Err(BlockFailure::Inertia {
            negative_pivots: pivots,
        }),
        Err(over) => Ok(Err(over)),
    }
}

/// The deflated directions (local coordinates) orthonormalised (modified Gram-Schmidt, those
/// nearly dependent dropped), scaled to norm `n^{1/2}` (`n` the region's nodes, the constant
/// directions' own), and padded to a multiple of three with coordinate vectors of nodes
/// outside their support: only a choice, the factorisation and [`RegionSpace::new`] verify.
fn deflation_border(directions: Vec<Vec<f64>>, n: usize) -> Vec<Column> {
    let mut kept: Vec<Vec<f64>> = Vec::new();
    for mut d in directions {
        let before = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        for q in &kept {
            let dot: f64 = d.iter().zip(q).map(|(a, b)| a * b).sum();
            d.iter_mut().zip(q).for_each(|(a, b)| *a -= dot * b);
        }
        let after = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        if after > 1e-3 * before && after > 0.0 {
            d.iter_mut().for_each(|v| *v /= after);
            kept.push(d);
        }
    }
    let used: Vec<bool> = (0..n)
        .map(|a| {
            kept.iter()
                .any(|d| d[3 * a..3 * a + 3].iter().any(|v| *v != 0.0))
        })
        .collect();
    let mut free = (0..n).filter(|&a| !used[a]);
    let mut columns: Vec<Column> = kept
        .iter()
        .map(|d| {
            d.iter()
                .enumerate()
                // no entry near underflow: its scaled copy in the border must be exact
                .filter(|(_, v)| v.abs() > 1e-150)
                .map(|(i, v)| (i, v * (n as f64).sqrt()))
                .collect()
        })
        .collect();
    while !columns.len().is_multiple_of(3) {
        let Some(a) = free.next() else {
            columns.truncate(columns.len() - columns.len() % 3);
            break;
        };
        columns.push(vec![(3 * a + columns.len() % 3, (n as f64).sqrt())]);
    }
    columns
}

/// A factorisation of a region's bordered matrix `K - h I`: its negative pivots, its backward
/// error plus twice the forming error, and (see [`Region::factor`]) its columns at them.
struct Factored {
    negative: usize,
    bound: f64,
    pivots: NegativePivots,
}

/// The deflation without a second factorisation (`[A16]`, "Deflation", (D1)): with `p`
/// negative pivots more than the three of the constant border, and the border's three rows
/// last in the elimination (pivots `D_h`, unit lower block `L_h`), `p` of the factor's columns
/// at negative pivots `k` become the vectors `P^T L (e_k - z_k)` (`z_k` on the border's
/// positions, about `L_h^{-1} c_k` for the column's border part `c_k`): their region parts are
/// the columns' own, `w_k`, their border parts `r_k = c_k - L_h z_k` (rounding-small), and
/// `Y^T D^{-1} Y = D_J^{-1} + Z^T D_h^{-1} Z` exactly for `Y = [e_k - z_k]`. With `H = ||R||_F^2
/// / (h - b)` (`b` the factorisation's bound), `Q = |D_J|^{-1} - Z^T D_h^{-1} Z - H I` positive
/// definite (proven with its rounding) makes `A - s >= 0` on `[E, W]^perp`
/// ([`RegionSpace::new`] proves `[E, W]` of full rank). The columns with the least `|d_k|
/// z_k^T |D_h|^{-1} z_k` are tried; `W` is scaled by a power of two to about `n^{1/2}`
/// (exactly the same span).
fn schur_deflation(f: &Factored, h: f64, n: usize) -> Option<Vec<Column>> {
    let t = &f.pivots.trailing;
    [border_last(t, n).then_some(t), None]
        .into_iter()
        .find_map(|t| deflation_with(f, h, n, t))
}

/// Whether the border's three rows are the last in the elimination: the trailing positions are
/// exactly rows `3n..3n+3`.
fn border_last(t: &Trailing, n: usize) -> bool {
    t.rows.len() == 3 && t.rows.iter().all(|&r| r >= 3 * n && r < 3 * n + 3)
}

/// The deflation of the leading block (`[A16]`, "Deflation", (D0)): with the border's rows last
/// in the elimination, the factor's leading block is the region's own, `L_r D_r L_r^T = A -
/// h I + Delta` (`x^T Delta x <= b |x|^2`, `b <= h` the factorisation's bound), so `A >= 0` on the
/// vectors orthogonal to the region parts of the factor's columns at **every** negative pivot
/// of a region row (the negative terms of `sum_j d_j (l_j^T y)^2` vanish there): no condition,
/// no second factorisation; `W` holds `p + 3` columns where (D1) needs `p`. `None` when the
/// border is not last or a negative pivot's column is missing.
fn leading_deflation(f: &Factored, h: f64, n: usize) -> Option<Vec<Column>> {
    let columns = &f.pivots.columns;
    if !border_last(&f.pivots.trailing, n) || f.bound > h || columns.len() != f.negative {
        return None;
    }
    let region = |c: &NegativeColumn| -> Column {
        c.entries
            .iter()
            .filter(|(r, _)| *r < 3 * n)
            .copied()
            .collect()
    };
    Some(
        columns
            .iter()
            .filter(|c| c.entries.first().is_some_and(|(r, _)| *r < 3 * n))
            .map(|c| scaled_to_constant(region(c), n))
            .collect(),
    )
}

/// [`schur_deflation`] with `z_k = L_h^{-1} c_k` (`trailing` given) or `z_k = 0` (`None`:
/// the columns themselves, whose border parts `C` then need `||C||_F^2 max |d_k| < h - b`).
fn deflation_with(f: &Factored, h: f64, n: usize, t: Option<&Trailing>) -> Option<Vec<Column>> {
    let p = f.negative.checked_sub(3).filter(|&p| p > 0)?;
    let slack = h - f.bound;
    if slack <= 0.0 {
        return None;
    }
    let none = Trailing {
        rows: (3 * n..3 * n + 3).collect(),
        pivots: vec![f64::INFINITY; 3],
        lower: vec![vec![0.0; 3]; 3],
    };
    let (t, eliminate) = match t {
        Some(t) => (t, true),
        None => (&none, false),
    };
    let mut chosen: Vec<Candidate> = f
        .pivots
        .columns
        .iter()
        .filter_map(|c| Candidate::new(c, t, (3 * n, eliminate), slack))
        .collect();
    if chosen.len() < p {
        return None;
    }
    chosen.sort_by(|a, b| a.weight.total_cmp(&b.weight));
    chosen.truncate(p);
    // ||R||_F^2, R = C - L_h Z with its rounding (sums of at most 3 products)
    let mut r_sq = 0.0f64;
    for c in &chosen {
        for i in 0..3 {
            let (mut v, mut mag) = (c.border[i] - c.z[i], c.border[i].abs() + c.z[i].abs());
            for j in 0..i {
                v -= t.lower[i][j] * c.z[j];
                mag += (t.lower[i][j] * c.z[j]).abs();
            }
            r_sq += (v.abs() + gamma(4) * mag).powi(2);
        }
    }
    let big_h = r_sq * (1.0 + 8.0 * U) / (slack * (1.0 - 4.0 * U));
    // Q = |D_J|^{-1} - Z^T D_h^{-1} Z - H I, each entry with its rounding
    let mut q = DMatrix::zeros(p, p);
    let mut err_sq = 0.0f64;
    for (a, ca) in chosen.iter().enumerate() {
        for (b, cb) in chosen.iter().enumerate() {
            let terms = (0..3).map(|i| ca.z[i] * cb.z[i] / t.pivots[i]);
            let (sum, mag) = terms.fold((0.0, 0.0), |(s, m), v| (s + v, m + v.abs()));
            let own = if a == b {
                1.0 / ca.pivot.abs() - big_h
            } else {
                0.0
            };
            q[(a, b)] = own - sum;
            let e = gamma(8) * (mag + own.abs() + 2.0 * big_h);
            err_sq += e * e;
        }
    }
    let low = verified_min_eigenvalue_dense(&q)? - err_sq.sqrt() * (1.0 + 1e-10);
    if low.is_nan() || low <= 0.0 {
        return None;
    }
    Some(
        chosen
            .into_iter()
            .map(|c| scaled_to_constant(c.region, n))
            .collect(),
    )
}

/// A factor column at a negative pivot `d_k` off the border: its border part `c` (by trailing
/// position), `z = L_h^{-1} c` or zero (computed: only a choice), its region part, and the
/// weight `|d_k| (sum_i z_i^2 / |d_h,i| + |c - L_h z|^2 / (h - b))` it is chosen by.
struct Candidate {
    pivot: f64,
    border: [f64; 3],
    z: [f64; 3],
    region: Column,
    weight: f64,
}

impl Candidate {
    fn new(
        c: &NegativeColumn,
        t: &Trailing,
        (hub, eliminate): (usize, bool),
        slack: f64,
    ) -> Option<Self> {
        if c.entries.first().is_none_or(|(r, _)| *r >= hub) {
            return None; // a pivot of the border itself
        }
        let mut border = [0.0; 3];
        let mut region = Column::new();
        for &(r, v) in &c.entries {
            match t.rows.iter().position(|&x| x == r) {
                Some(i) => border[i] = v,
                None => region.push((r, v)),
            }
        }
        let mut z = [0.0; 3];
        if eliminate {
            z = border;
            for i in 0..3 {
                for j in 0..i {
                    z[i] -= t.lower[i][j] * z[j];
                }
            }
        }
        let left: f64 = if eliminate {
            0.0
        } else {
            border.iter().map(|v| v * v).sum()
        };
        let weight = c.pivot.abs()
            * ((0..3).map(|i| z[i] * z[i] / t.pivots[i].abs()).sum::<f64>() + left / slack);
        (!region.is_empty() && weight.is_finite()).then_some(Candidate {
            pivot: c.pivot,
            border,
            z,
            region,
            weight,
        })
    }
}

/// A region's bordered pattern without deflated columns (its own blocks and its constant
/// directions' border node last) and its symbolic analysis, made before its values: the block
/// comparison's analysis in regions predicts from them and the region's first factorisation
/// reuses them ([`Region::prove`] checks that the pattern is the same).
pub(super) struct RegionAnalysis {
    pattern: BlockPattern,
    symbolic: faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
    counted: usize,
}

impl RegionAnalysis {
    /// Per region of `of` (numbered `0..k`), the analysis of its bordered pattern with the
    /// node pairs `pairs` of its own (pairs between regions are left out), each within
    /// `max_values`; `Ok(Err(predicted))` for the first that is not.
    pub(super) fn of_regions(
        of: &[usize],
        pairs: impl Iterator<Item = (usize, usize)>,
        max_values: usize,
    ) -> Result<std::result::Result<Vec<Self>, usize>> {
        let count = of.iter().max().map_or(0, |g| g + 1);
        let (mut local, mut size) = (vec![0usize; of.len()], vec![0usize; count]);
        for (i, &g) in of.iter().enumerate() {
            local[i] = size[g];
            size[g] += 1;
        }
        let mut own: Vec<Vec<(usize, usize)>> = vec![Vec::new(); count];
        for (i, j) in pairs.filter(|(i, j)| of[*i] == of[*j]) {
            own[of[i]].push((local[i], local[j]));
        }
        // the regions' orderings are independent: on the machine's threads (0.05 s of 0.11 s
        // at 10^4 cameras in 3 regions)
        let analyses = crate::linalg::threads::in_chunks(&mut own, count > 1, |first, part| {
            let analyse = |(k, pairs): (usize, &mut Vec<(usize, usize)>)| {
                let pattern = bordered_pattern(size[first + k], pairs.drain(..), 0, &[]);
                Ok(pattern
                    .symbolic_within(max_values)?
                    .map(|(symbolic, counted)| RegionAnalysis {
                        pattern,
                        symbolic,
                        counted,
                    }))
            };
            part.iter_mut().enumerate().map(analyse).collect::<Vec<_>>()
        });
        let mut out = Vec::with_capacity(count);
        for analysis in analyses.into_iter().flatten() {
            match analysis? {
                Ok(region) => out.push(region),
                Err(predicted) => return Ok(Err(predicted)),
            }
        }
        Ok(Ok(out))
    }

    /// Stored values of its factor.
    pub(super) fn len_val(&self) -> usize {
        self.symbolic.len_val()
    }

    /// The ordering's count of its factor's values.
    pub(super) fn counted(&self) -> usize {
        self.counted
    }

    /// The counted multiply-adds of its numeric factorisation.
    pub(super) fn multiply_adds(&self) -> f64 {
        crate::linalg::cholesky::factor_multiply_adds(&self.symbolic)
    }

    /// Bytes of numeric scratch its `LDL^T` factorisation allocates besides the factor.
    pub(super) fn scratch_bytes(&self) -> usize {
        crate::linalg::cholesky::ldlt_scratch_bytes(&self.symbolic)
    }
}

/// A region's bordered pattern: its `hub` nodes with the pairs `own` (local numbering), the
/// constant directions' border node `hub`, then `border_blocks` nodes of deflated columns,
/// each joined to the nodes of `support`.
fn bordered_pattern(
    hub: usize,
    own: impl Iterator<Item = (usize, usize)>,
    border_blocks: usize,
    support: &[usize],
) -> BlockPattern {
    let constant = (0..hub).map(|a| (hub, a));
    let deflated = (0..border_blocks).flat_map(|k| support.iter().map(move |&a| (hub + 1 + k, a)));
    BlockPattern::new(
        hub + 1 + border_blocks,
        3,
        own.chain(constant).chain(deflated),
    )
}

/// One factorisation of a region's bordered matrix: proven, or its negative pivots (with the
/// region parts of the factor's columns at them when there are at most [`DEFLATION_MOST`]).
enum Attempt {
    Proven(RegionProof),
    Negative {
        pivots: usize,
        directions: Vec<Vec<f64>>,
    },
}

/// A region's bordered matrix: its own blocks in local numbering, its diagonal blocks
/// `fl(M_ii - P_i)` less the charges with the magnitudes they were formed from (`|M_ii| +
/// |P_i|`, largest row sums), and its deflated border columns `W` (local coordinates, a
/// multiple of three), scaled in the matrix to `|w|^2 = strength h`.
struct Region {
    own: Vec<(usize, usize, Matrix3<f64>)>,
    diag: Vec<(Matrix3<f64>, f64)>,
    border: Vec<Column>,
    strength: f64,
}

impl Region {
    /// Region `g`'s bordered matrix without deflated columns, and its nodes (local numbering
    /// is their order).
    fn new(
        m: &BlockOperator,
        (of, g): (&[usize], usize),
        charges: &[Matrix3<f64>],
    ) -> (Self, Vec<usize>) {
        let nodes: Vec<usize> = (0..of.len()).filter(|&i| of[i] == g).collect();
        let mut local = vec![usize::MAX; of.len()];
        nodes.iter().enumerate().for_each(|(a, &i)| local[i] = a);
        let row = |b: &Matrix3<f64>| (0..3).map(|r| b.row(r).abs().sum()).fold(0.0, f64::max);
        let region = Region {
            own: m
                .blocks()
                .iter()
                .filter(|(i, j, _)| of[*i] == g && of[*j] == g)
                .map(|(i, j, b)| (local[*i], local[*j], *b))
                .collect(),
            diag: nodes
                .iter()
                .map(|&i| {
                    let (d, c) = (m.diagonal()[i], charges[i]);
                    (d - c, row(&d) + row(&c))
                })
                .collect(),
            border: Vec::new(),
            strength: DEFLATION_STRENGTH * m.row_abs(),
        };
        (region, nodes)
    }

    /// The pattern: the region's nodes, the constant directions' border node, then one border
    /// node per three deflated columns.
    fn pattern(&self) -> BlockPattern {
        let own = self.own.iter().map(|(a, b, _)| (*a, *b));
        bordered_pattern(self.diag.len(), own, self.border.len() / 3, &self.support())
    }

    /// The progress line of region `g`'s factorisation (`values` its factor's).
    fn announce(&self, g: usize, values: usize) {
        crate::progress::phase(crate::progress::Phase::Certify, || {
            let deflated = match self.border.len() {
                0 => String::new(),
                k => format!(", {k} deflated directions"),
            };
            format!(
                "regional bound: region {g} ({} nodes{deflated}), a factor of {:.1e} values",
                self.diag.len(),
                values as f64
            )
        });
    }

    /// The nodes where a deflated column is nonzero.
    fn support(&self) -> Vec<usize> {
        let mut s: Vec<usize> = self.border.iter().flatten().map(|(i, _)| i / 3).collect();
        s.sort_unstable();
        s.dedup();
        s
    }

    /// Its symbolic analysis (`prepared`'s when made for the same pattern, else its own within
    /// `max_values`) and the time left, then [`Region::factorise`].
    fn prove(
        &self,
        g: usize,
        (shift, h0): (f64, f64),
        ((max_values, stop_at), prepared): ((usize, Option<Instant>), Option<&RegionAnalysis>),
        storage: &mut FactorStorage,
    ) -> std::result::Result<std::result::Result<Attempt, String>, BlockFailure> {
        let pattern = self.pattern();
        let own;
        let symbolic = match prepared.filter(|p| p.pattern.same_as(&pattern)) {
            Some(p) => &p.symbolic,
            None => match pattern.symbolic_within(max_values) {
                Ok(Ok((s, _))) => {
                    own = s;
                    &own
                }
                Ok(Err(predicted)) => {
                    return Ok(Err(format!(
                        "region {g}'s factor is predicted at {predicted:.1e} values, above the \
                         {max_values:.1e} the budget allows"
                    )));
                }
                Err(_) => return Err(BlockFailure::Numerical),
            },
        };
        self.announce(g, symbolic.len_val());
        let time = crate::certify::budget::Budget {
            max_memory_bytes: u64::MAX,
            max_seconds: stop_at.map(|t| t.saturating_duration_since(Instant::now()).as_secs_f64()),
        };
        let (values, work) = (
            symbolic.len_val(),
            crate::linalg::cholesky::factor_multiply_adds(symbolic),
        );
        if let Err(why) = time.counted_factorisations_fit(values, work, values) {
            return Ok(Err(format!("region {g}: {why}")));
        }
        self.factorise((&pattern, symbolic), (shift, h0), storage)
            .map(Ok)
    }

    /// `LDL^T` at `h0` and, when the backward error is above it, once more at 4 times the
    /// error: proven, or its negative pivots and the region parts of the factor's columns at
    /// them (unless a deflation without a second factorisation proves).
    fn factorise(
        &self,
        (pattern, symbolic): (
            &BlockPattern,
            &faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
        ),
        (shift, h0): (f64, f64),
        storage: &mut FactorStorage,
    ) -> std::result::Result<Attempt, BlockFailure> {
        let mut h = h0;
        for _ in 0..2 {
            let f = self.factor((pattern, symbolic), (shift, h), storage)?;
            if f.bound > h {
                h = 4.0 * f.bound;
                continue;
            }
            let proof = |deflated| RegionProof {
                headroom: h,
                backward_error: f.bound,
                factor_values: symbolic.len_val(),
                deflated,
            };
            if f.negative == 3 + self.border.len() {
                return Ok(Attempt::Proven(proof(Vec::new())));
            }
            if self.border.is_empty()
                && let Some(w) = schur_deflation(&f, h, self.diag.len())
                    .or_else(|| leading_deflation(&f, h, self.diag.len()))
            {
                return Ok(Attempt::Proven(proof(w)));
            }
            let hub = 3 * self.diag.len();
            let directions = f
                .pivots
                .columns
                .iter()
                .map(|c| {
                    let mut d = vec![0.0; hub];
                    c.entries
                        .iter()
                        .filter(|(r, _)| *r < hub)
                        .for_each(|&(r, v)| d[r] = v);
                    d
                })
                .filter(|d| d.iter().any(|v| *v != 0.0))
                .collect();
            return Ok(Attempt::Negative {
                pivots: f.negative,
                directions,
            });
        }
        Err(BlockFailure::BackwardError)
    }

    /// The `LDL^T` of `K - h I` (the diagonal less `shift + h`): its negative pivots, its
    /// backward error plus twice the forming error, and on a first factorisation (no deflated
    /// border) showing more than three but at most [`DEFLATION_MOST`] negative pivots, the
    /// factor's columns at them.
    fn factor(
        &self,
        (p, symbolic): (
            &BlockPattern,
            &faer::sparse::linalg::cholesky::SymbolicCholesky<usize>,
        ),
        (shift, h): (f64, f64),
        storage: &mut FactorStorage,
    ) -> std::result::Result<Factored, BlockFailure> {
        let (val, magnitude, terms) = self.values(p, shift, h);
        let most = if self.border.is_empty() {
            DEFLATION_MOST
        } else {
            0
        };
        let expected = 3 + self.border.len();
        let (inertia, pivots) =
            ldlt_negative_columns(symbolic, p.matrix(&val), (expected, most), storage)
                .map_err(|_| BlockFailure::Numerical)?;
        let most = terms.iter().copied().max().unwrap_or(2);
        let forming = gamma(most + 4) * magnitude.iter().copied().fold(0.0, f64::max);
        let bound = inertia.backward_error + 2.0 * forming;
        if !bound.is_finite() {
            return Err(BlockFailure::Numerical);
        }
        Ok(Factored {
            negative: inertia.negative,
            bound,
            pivots,
        })
    }

    /// The values of `K - h I` with each block row's magnitudes and terms.
    fn values(&self, p: &BlockPattern, shift: f64, h: f64) -> (Vec<f64>, Vec<f64>, Vec<usize>) {
        let hub = self.diag.len();
        let blocks = hub + 1 + self.border.len() / 3;
        let mut val = vec![0.0f64; p.nnz()];
        let mut magnitude = vec![0.0f64; blocks];
        let mut terms = vec![2usize; blocks];
        let row = |b: &Matrix3<f64>| (0..3).map(|r| b.row(r).abs().sum()).fold(0.0, f64::max);
        for (a, (d, formed_from)) in self.diag.iter().enumerate() {
            let block = d - Matrix3::identity() * (shift + h);
            p.add(&mut val, a, a, 0, &block);
            magnitude[a] += formed_from + shift + h;
            p.add(&mut val, hub, a, p.slot(hub, a), &Matrix3::identity());
            magnitude[a] += 1.0;
            magnitude[hub] += 1.0;
        }
        for (k, mag) in magnitude.iter_mut().enumerate().skip(hub) {
            p.add(&mut val, k, k, 0, &(-Matrix3::identity() * h));
            *mag += h;
        }
        for (a, b, block) in &self.own {
            p.add(&mut val, *a, *b, p.slot(*a, *b), block);
            for v in [*a, *b] {
                magnitude[v] += row(block).max(row(&block.transpose()));
                terms[v] += 1;
            }
        }
        // the deflated columns scaled to about |w|^2 = strength h (their norm is n^{1/2}) by a
        // power of two, so the stored border is exactly `W` scaled: its `F^perp` is
        // [`RegionSpace`]'s
        let scale = (self.strength * h / hub as f64)
            .sqrt()
            .log2()
            .round()
            .exp2();
        // exact only if no scaled entry leaves the normal range: else unscaled (still exact)
        let (low, high) = self
            .border
            .iter()
            .flatten()
            .fold((f64::INFINITY, 0.0f64), |(l, m), (_, w)| {
                (l.min(w.abs()), m.max(w.abs()))
            });
        let scale = if scale.is_normal() && (low * scale).is_normal() && (high * scale).is_finite()
        {
            scale
        } else {
            1.0
        };
        let mut entries: Vec<Matrix3<f64>> = Vec::new();
        for k in 0..self.border.len() / 3 {
            entries.clear();
            entries.resize(hub, Matrix3::zeros());
            for c in 0..3 {
                for &(i, w) in &self.border[3 * k + c] {
                    entries[i / 3][(c, i % 3)] = w * scale;
                }
            }
            for a in self.support() {
                let r = hub + 1 + k;
                p.add(&mut val, r, a, p.slot(r, a), &entries[a]);
                magnitude[a] += row(&entries[a].transpose());
                magnitude[r] += row(&entries[a]);
            }
        }
        (val, magnitude, terms)
    }
}

/// Test-only: per region, the dense block `fl(M)_gg - blkdiag(P) - shift I` (local numbering)
/// and the directions each form of the deflation without a second factorisation takes from its
/// first factorisation (the Schur form (D1) with `z_k = L_h^{-1} c_k`, then with `z_k = 0`, then
/// the leading block's (D0); empty when it proved without or that form fails).
#[cfg(test)]
pub(super) fn schur_deflations(
    problem: &MultipleProblem,
    (rotations, lambdas): (&[Rotation], &[Matrix3<f64>]),
    region: &[usize],
) -> Vec<(nalgebra::DMatrix<f64>, [Vec<Column>; 3])> {
    let information = problem.information().expect("information");
    let m = anisotropic_operator(problem, information, rotations, lambdas);
    let of = largest_last(region);
    let charges = cross_charges(&m, &of).expect("charges");
    let (shift, h0) = (region_shift(&m), first_headroom(&m));
    let count = of.iter().max().map_or(0, |g| g + 1);
    (0..count)
        .map(|g| {
            let (r, nodes) = Region::new(&m, (&of, g), &charges);
            let n = nodes.len();
            let mut a = nalgebra::DMatrix::zeros(3 * n, 3 * n);
            for (i, (d, _)) in r.diag.iter().enumerate() {
                let d = d - Matrix3::identity() * shift;
                a.fixed_view_mut::<3, 3>(3 * i, 3 * i).copy_from(&d);
            }
            for (i, j, b) in &r.own {
                let at = a.fixed_view::<3, 3>(3 * i, 3 * j) + b;
                a.fixed_view_mut::<3, 3>(3 * i, 3 * j).copy_from(&at);
                let at = a.fixed_view::<3, 3>(3 * j, 3 * i) + b.transpose();
                a.fixed_view_mut::<3, 3>(3 * j, 3 * i).copy_from(&at);
            }
            let pattern = r.pattern();
            let (symbolic, _) = pattern.symbolic_within(usize::MAX).unwrap().unwrap();
            let f = r
                .factor(
                    (&pattern, &symbolic),
                    (shift, h0),
                    &mut FactorStorage::default(),
                )
                .expect("factor");
            let t = &f.pivots.trailing;
            let mut found = [Vec::new(), Vec::new(), Vec::new()];
            if f.bound <= h0 && f.negative > 3 {
                found[0] = border_last(t, n)
                    .then(|| deflation_with(&f, h0, n, Some(t)))
                    .flatten()
                    .unwrap_or_default();
                found[1] = deflation_with(&f, h0, n, None).unwrap_or_default();
                found[2] = leading_deflation(&f, h0, n).unwrap_or_default();
            }
            (a, found)
        })
        .collect()
}
