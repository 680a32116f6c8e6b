//! The block comparison `[A15]` in regions (`paper-notes/anisotropic.md` `[A15]`, "Regions"):
//! the edges between regions are dropped from the block Laplacian `C` of the kept edges
//! (charged as dropped edges, so `M >= C - blkdiag(Delta)` still holds and `C` has no blocks
//! between regions), and each region's block of `C - blkdiag(Delta)` is proven positive
//! semidefinite with a margin `zeta` off its constant directions by the regional bound's
//! bordered factorisation (`[A16]` (ii), which deflates the factor's columns at extra negative
//! pivots, (D0)-(D2)); the `3k` coarse directions (and the deflated ones) are bounded by the
//! shared coarse correction of `M` itself (`certify/multiple/coarse.rs`).

use super::edges;
use super::operator::{anisotropic_operator, comparison_operator};
use super::regional::bordered_regions;
use super::{BlockAnalysis, BlockComparison, BlockFailure, Structure};
use crate::certify::multiple::coarse::GaugeBounds;
use crate::certify::multiple::multipliers::GaugeTerms;
use crate::certify::multiple::scalar::orthogonality_defect;
use crate::multiple::MultipleProblem;
use crate::multiple::anisotropic::Information;
use crate::so3::Rotation;
use nalgebra::Matrix3;
use std::time::Instant;

/// The block comparison in regions: each region's block of `C - blkdiag(Delta)` (step 2)
/// proven by the bordered factorisation of [`bordered_regions`], then the coarse directions of
/// `M`: a proven `lambda_min(S) >= mu` whatever the regions (they decide only whether it
/// proves), the coarse correction's conjugate gradients stopping at `stop_at` (a weaker bound,
/// never a wrong one).
pub(super) fn compare_bordered(
    (problem, information): (&MultipleProblem, &[Information]),
    analysis: &BlockAnalysis,
    (rotations, lambdas): (&[Rotation], &[Matrix3<f64>]),
    stop_at: Option<Instant>,
    terms: &GaugeTerms,
) -> std::result::Result<BlockComparison, BlockFailure> {
    let t_max = orthogonality_defect(rotations).map_err(|_| BlockFailure::NotOrthogonal)?;
    let c = edges::edge_blocks(problem, information, rotations, lambdas, &analysis.keep)?;
    let blocks = comparison_operator(problem, &analysis.keep, &c);
    let m = anisotropic_operator(problem, information, rotations, lambdas);
    let gauge = GaugeBounds::of(terms, t_max);
    let limits = (usize::MAX, stop_at);
    let Structure::Regions(prepared) = &analysis.structure else {
        return Err(BlockFailure::Numerical); // a whole analysis has one pencil
    };
    let regions = (&analysis.components[..], Some(&prepared[..]));
    let mut proof =
        bordered_regions((&m, &blocks), regions, (gauge, t_max), limits).map_err(|(_, f)| f)?;
    proof.dropped_edges = analysis.dropped_edges();
    proof.max_delta = c.delta.iter().map(|d| d.norm()).fold(0.0, f64::max);
    Ok(proof)
}
