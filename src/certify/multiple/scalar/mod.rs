//! The scalar comparison certificate `[D13]` (`paper-notes/certificates.md`): a proof that the
//! certificate matrix `S = Q - blkdiag(Lambda)` of an estimate `R` is (nearly) positive
//! semidefinite from ONE sparse factorisation of an `n x n` scalar matrix instead of the
//! `3n x 3n` matrix `S`.
//!
//! Why: on graphs without small separators (random / expander view graphs) the Cholesky factor of
//! `S` fills badly, and its cost grows like `(3s)^3` for a separator of `s` nodes. The scalar
//! matrix has the same elimination structure with `s` instead of `3s`: about 27 times fewer flops.
//!
//! The argument (all steps rigorous, rounding included):
//! 1. `M = D^T S D` with `D = blkdiag(R_i)` has the same inertia as `S`, and (Ostrowski)
//!    `lambda_min(S) >= lambda_min(M) / sigma_min(D)^2` when `lambda_min(M) < 0`.
//! 2. Edge by edge, with `P_e = R_a^T R_ab^T R_b = A_e + K_e` (symmetric + skew part),
//!    `d = x_b - x_a`, `m = (x_a + x_b) / 2`: the edge's part of `x^T M x` is
//!    `w (d^T A_e d - 2 m^T K_e d)`, and `2 |m^T K d| <= beta |d|^2 + (||K||^2 / beta) |m|^2`.
//!    So `M >= (L' - diag(delta)) (x) I_3`, with `L'` the Laplacian of the kept weights
//!    `w (lambda_min(A_e) - beta)` (`beta = 1/2`; 0.15 on the subgraphs of dense graphs, step 6)
//!    and `delta_i` the charges
//!    `sum_e w ||K_e||^2 / (2 beta)` plus `||G_i||`, `G_i = M_ii - sum_e w A_e`. A residual of
//!    angle `theta` costs `sin^2 theta`: **second order**, exact on a cycle with equal residuals.
//!    Edges whose residual is too large for it (outliers) use the first-order bound instead:
//!    weight `w`, charge `w (||A_e - I|| + ||P_e - I||)`.
//! 3. `M v0 = r'` with `v0 = 1 (x) I_3` and `r'_i = R_i^T (S Y)_i` (zero at a critical point);
//!    `v0^T M v0 = sum_i r'_i = sum_i G_i` is evaluated in double-double when the plain
//!    evaluation's rounding (which grows like `n u d`) would matter.
//! 4. Split `x = v0 a + x1` with `a` the `delta`-weighted mean of the blocks, so every coordinate
//!    slice `y` of `x1` has `delta^T y = 0`. If the scalar matrix `L' - diag(delta)` has exactly
//!    one negative eigenvalue, the pencil `(L', diag(delta))` has second eigenvalue `>= 1` (its
//!    first eigenvector is `1` with eigenvalue 0), so `y^T (L' - diag(delta)) y >= 0` on those
//!    slices and `x1^T M x1 >= 0`. What remains are the cross terms with `r'`:
//!    `x^T M x >= -(2 kappa (1 + sqrt(n) kappa) ||r'|| + kappa^2 ||sum_i r'_i||) |x|^2`,
//!    `kappa = ||delta||_2 / sum delta`.
//! 5. "Exactly one negative eigenvalue" is proven by the inertia of an `LDL^T` factorisation of
//!    `A = L' - diag(delta) - h I` (Sylvester's law of inertia applied to the computed factors,
//!    which are an exact factorisation of `A + dA`, with the a-posteriori bound
//!    `|dA| <= gamma_(k+4) |L||D||L^T|`, Higham 2002, Thm 9.3 / 10.x), and the margin
//!    `h > ||dA|| + forming error` absorbs the perturbation (Weyl).
//!
//! 6. *(subgraphs and splits)* When the whole graph's factor does not fit the budget, step 5
//!    may run on a subgraph (dropped edges keep their charges, [`ScalarAnalysis::sparsified`])
//!    or on `P` sparser parts that each prove a share ([`ScalarAnalysis::split`]): with
//!    `L' = sum_p L'_p` and charges `c_p` (`sum_p c_p >= w`), at most one negative eigenvalue of
//!    every `L'_p - diag(c_p)` gives `y^T (L' - diag(w)) y >= -eps |y|^2` on `w^T y = 0`, with
//!    the split's defect `eps = sum_p ||c_p - s_p w||^2 / 1^T c_p` paid from `zeta`.
//!
//! 7. *(a hub)* An anisotropic problem of one special shape, an isotropic view graph plus one
//!    node joined to others by edges of information `W diag(1, 1, 0)` (soft gravity priors'
//!    world node), is proven slice by slice: the first two coordinates on the view graph's
//!    Laplacian, the third with the hub (`hub.rs`, `paper-notes/gravity.md` `[G13]`).
//!
//! When the residuals are too large for step 4 (noisy data, low algebraic connectivity) the
//! factorisation shows more than one negative pivot and [`scalar_comparison`] returns `None`:
//! the caller falls back to the factorisation of `S` itself. The bound is never weaker than
//! what it proves, and it is never used when it cannot be completed.

mod analysis;
mod bordered;
mod charges;
mod forecast;
mod groups;
mod hub;
mod hub_rung;
mod inertia;
mod partition;
mod residuals;
pub(in crate::certify) mod rungs;
mod split;
#[cfg(test)]
pub(in crate::certify::multiple) mod tests;

pub use analysis::{
    GROUPED_EDGES_PER_NODE, MIN_SPLIT_DEGREE, SPARSIFIED_EDGES_PER_NODE, SPLIT_MIN_DEGREES,
    SPLIT_SHAPES, SUBGRAPH_GROUP_NODES, SUBGRAPH_MAX_GROUPS, ScalarAnalysis, SplitShape, subgraph,
    subgraph_groups, subgraph_ladder,
};
pub(in crate::certify::multiple) use analysis::{
    components, connect_within, fro, subgraph_edges, subgraph_regions,
};
pub(crate) use bordered::{LowRank, bordered_comparison};
pub(in crate::certify::multiple) use charges::{orthogonality_defect, ostrowski, parallel_groups};
pub(crate) use groups::grouped_dual_bound;
pub(in crate::certify::multiple) use partition::partition_weighted;

use super::check::Check;
use super::coarse::GaugeBounds;
use super::multipliers::GaugeSource;
use super::verified::VerifiedBound;
use crate::certify::log::Prediction;
use crate::certify::proof::Proof;
use crate::error::{Error, Result};
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// The split `beta` of the second-order edge comparison (step 2): each edge keeps
/// `alpha_e - beta` of its weight and charges `k_e^2 / (2 beta)` to its two nodes. `1/2`
/// maximises `beta (1 - beta)`, which makes the condition exact on a cycle with equal residuals
/// (`paper-notes/certificates.md` [D13]).
const SECOND_ORDER_BETA: f64 = 0.5;

/// The split `beta` of the subgraphs of dense graphs (at least [`DENSE_EDGES_PER_NODE`] edges
/// per node, [`ScalarAnalysis::sparsified`]): any `beta > 0` holds edge by edge, and on a
/// subgraph of a well-connected graph the kept weight `alpha_e - beta` is what is short, not
/// the charges `k_e^2 / (2 beta)`. Sweeps of `examples/scalar_sweep.rs` at the least-squares
/// solution (2026-12-02, `paper-notes/certificates.md` `[D13]`): random graphs of 10 edges per
/// node at 0.1 rad proven from 3 edges per node instead of 3.5 (10^4 and 3x10^4 nodes: 5.4e7
/// factor values instead of 8.1e7); 5 edges per node: 2 negative pivots at 2.5 instead of 26;
/// 3 edges per node and SLAM grids are worse with it (their subgraphs keep `1/2`).
const DENSE_SUBGRAPH_BETA: f64 = 0.15;

/// Graphs with at least this many edges per node are dense for the scalar comparison: the
/// subgraphs of [`ScalarAnalysis::sparsified`] split their second-order edges with
/// `beta = 0.15` instead of `1/2` ([`ScalarAnalysis::second_order_beta`]).
pub const DENSE_EDGES_PER_NODE: f64 = 4.0;

/// Largest `||R_i^T R_i - I||_F` accepted (the rotations are validated far tighter than this).
const MAX_ORTHOGONALITY_DEFECT: f64 = 1e-3;

/// The outcome of a successful scalar comparison `[D13]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScalarComparison {
    /// Proven lower bound on `lambda_min(S)` (non-positive).
    pub verified_min_eigenvalue: f64,
    /// Largest `delta_i`, the charge of the edge comparison (step 2) at one node.
    pub max_delta: f64,
    /// Edges compared to second order (the others, residuals too large for it, to first order).
    pub second_order_edges: usize,
    /// Edges left out of the factorised Laplacian (a sparsified comparison; 0 otherwise).
    pub dropped_edges: usize,
    /// Factorisations run: 1, or the parts of a split comparison, each proving its share.
    #[serde(default = "one_part")]
    pub parts: usize,
    /// Edges held by every part of a split comparison, each with an even share of its kept
    /// weight (0 otherwise).
    #[serde(default)]
    pub shared_edges: usize,
    /// The split's defect `eps`: each part is charged where it is strong (uneven shares),
    /// which costs `eps |y|^2`, paid from `zeta` (0 for one part).
    #[serde(default)]
    pub split_defect: f64,
    /// The uniform `zeta` added to the weights (its positive term absorbs the cross terms).
    pub zeta: f64,
    /// The margin `h` subtracted from the scalar matrix.
    pub headroom: f64,
    /// Rigorous bound on the backward error of the `LDL^T` factorisation plus the forming error
    /// (must be below `headroom`).
    pub backward_error: f64,
    /// Stored values of the scalar `LDL^T` factor.
    pub factor_nonzeros: usize,
    /// `kappa = ||w||_2 / sum(w)`, `w = delta + zeta` (step 4).
    pub kappa: f64,
    /// Upper bound on `||r'||_F` (the stationarity part, step 3).
    pub residual_bound: f64,
    /// Negative pivots of the grouped comparison's factor whose columns were deflated
    /// (`[D13]`, "Deflated components"; 0 when every component proved its own pencil).
    #[serde(default)]
    pub deflated: usize,
}

/// The comparison's work besides the factorisations, per edge: the edge charges and the
/// double-double gauge block of steps 2 and 3 (measured 4.5e-6 s per edge on a 15k-node grid of
/// 22,216 edges, 2026-11-26, `rotavg multiple`: 0.10 s of which 3e-3 s of factorisation).
pub const SECONDS_PER_EDGE: f64 = 4.5e-6;

fn one_part() -> usize {
    1
}

/// Why a scalar comparison did not prove anything (the caller falls back to the `3n` factor).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "reason")]
#[non_exhaustive]
pub enum ScalarFailure {
    /// `L - diag(delta)` has more than one negative pivot: the residuals are too large relative
    /// to the graph's connectivity for this sufficient condition.
    Inertia {
        /// Negative pivots counted.
        negative_pivots: usize,
    },
    /// `nodes` nodes, pairwise not adjacent, whose diagonal entries of `L - diag(delta) - h I`
    /// are below `-h`: at least that many negative eigenvalues within any accepted backward
    /// error, so the factorisation was not run (a forecast of the inertia failure).
    NegativeDiagonal {
        /// Such nodes found (a greedy choice: a lower bound on the negative eigenvalues).
        nodes: usize,
    },
    /// A zero or non-finite pivot, or a non-finite bound.
    Numerical,
    /// The factorisation's backward error exceeded the headroom `h`.
    BackwardError,
    /// The estimate's rotations are too far from orthogonal.
    NotOrthogonal,
    /// Its time ran out before or between its factorisations (a comparison in regions).
    OutOfTime,
    /// The sparsest subgraph in regions, forecast by its charges to fail with about
    /// `negative_pivots` negative pivots (`mean_ratio`, the mean over nodes of each node's
    /// charge over its kept weight, far above where such subgraphs prove), so the
    /// factorisation was not run (`[D13]`, "A forecast for the sparsest regions").
    Forecast {
        /// Negative pivots forecast (what a denser subgraph is chosen by).
        negative_pivots: usize,
        /// The mean charge ratio the forecast comes from.
        mean_ratio: f64,
    },
}

impl ScalarFailure {
    /// The negative eigenvalues an inertia failure showed (counted pivots, or at least the
    /// nodes of [`ScalarFailure::NegativeDiagonal`], or those of a
    /// [`ScalarFailure::Forecast`]); `None` for the other failures.
    pub fn negative_count(&self) -> Option<usize> {
        match self {
            ScalarFailure::Inertia { negative_pivots } => Some(*negative_pivots),
            ScalarFailure::NegativeDiagonal { nodes } => Some(*nodes),
            ScalarFailure::Forecast {
                negative_pivots, ..
            } => Some(*negative_pivots),
            _ => None,
        }
    }
}

/// Why a comparison that ran did not prove enough, with the numbers: its proven
/// `lambda_min(S)` when the cross terms were too large, else its failure (`needed`: the
/// negative pivots its inertia condition needs, 1 for the scalar comparison, 3 for the block).
pub(in crate::certify::multiple) fn failure_text(
    target: f64,
    outcome: std::result::Result<f64, ScalarFailure>,
    needed: usize,
) -> String {
    match outcome {
        Ok(mu) => format!(
            "its cross terms give lambda_min(S) >= {mu:.1e}, below the -{target:.1e} the gap \
             budget allows"
        ),
        Err(ScalarFailure::Inertia { negative_pivots }) => {
            format!("{negative_pivots} negative pivots (its condition needs exactly {needed})")
        }
        Err(ScalarFailure::NegativeDiagonal { nodes }) => format!(
            "at least {nodes} negative eigenvalues, one per node of negative diagonal with no \
             edge between them (its condition needs exactly {needed}; not factorised)"
        ),
        Err(ScalarFailure::Numerical) => "a zero or non-finite pivot".into(),
        Err(ScalarFailure::BackwardError) => {
            "the factorisation's backward error exceeded its headroom".into()
        }
        Err(ScalarFailure::NotOrthogonal) => "the rotations are too far from orthogonal".into(),
        Err(ScalarFailure::OutOfTime) => "its time ran out before its factorisations".into(),
        Err(ScalarFailure::Forecast {
            negative_pivots,
            mean_ratio,
        }) => format!(
            "forecast to fail with about {negative_pivots} negative pivots (its condition needs \
             exactly {needed}; mean charge ratio {mean_ratio:.3}; not factorised)"
        ),
    }
}

/// The verified bound of a comparison that proved `proof`, logged with its shape `note`.
pub(super) fn proved_bound(
    cx: &Check<'_>,
    proof: ScalarComparison,
    predicted: Option<Prediction>,
    since: Instant,
    note: String,
) -> VerifiedBound {
    let mut b = cx.bound_from_mu(proof.verified_min_eigenvalue, Proof::ScalarComparison);
    b.fp_margin = proof.backward_error;
    b.factorizations = proof.parts;
    b.factor_nonzeros = proof.factor_nonzeros;
    b.scalar_comparison = Some(proof);
    let proved = cx.proved(&b);
    cx.log_with_note(Proof::ScalarComparison, predicted, proved, since, note);
    b
}

/// Try to prove `lambda_min(S) >= mu` for `S = Q - blkdiag(sym(Lambda))` from the estimate
/// `rotations` by the scalar comparison `[D13]`. `target > 0` is the `|mu|` the caller needs: it
/// sets the weight shift `zeta` (a larger target is easier to prove). `Ok(Err(..))` says why no proof was found
/// (never an error of the caller's data); `Err` only for inconsistent sizes.
pub fn scalar_comparison(
    problem: &MultipleProblem,
    analysis: &ScalarAnalysis,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
    target: f64,
) -> Result<std::result::Result<ScalarComparison, ScalarFailure>> {
    let gauge = || crate::certify::multiple::multipliers::gauge_terms(problem, rotations, lambdas);
    scalar_comparison_until(
        problem,
        analysis,
        (rotations, lambdas),
        &gauge,
        (target, None),
        false,
    )
}

/// [`scalar_comparison`], whose grouped analyses' conjugate gradients stop at `stop_at` (a
/// weaker bound, never a wrong one); with `forecast` (the climb's choice for the sparsest
/// subgraph in regions) a grouped comparison whose charges forecast its failure is not
/// factorised ([`ScalarFailure::Forecast`]; `forecast.rs`, `sparsest_regions_forecast`).
pub(in crate::certify::multiple) fn scalar_comparison_until(
    problem: &MultipleProblem,
    analysis: &ScalarAnalysis,
    (rotations, lambdas): (&[Rotation], &[Matrix3<f64>]),
    gauge: GaugeSource<'_>,
    (target, stop_at): (f64, Option<Instant>),
    forecast: bool,
) -> Result<std::result::Result<ScalarComparison, ScalarFailure>> {
    let n = problem.num_rotations();
    if rotations.len() != n || lambdas.len() != n {
        return Err(Error::InvalidSettings {
            name: "rotations".into(),
            reason: "scalar comparison needs one rotation and one multiplier per node".into(),
        });
    }
    // an analysis of another graph would place these weights at the wrong entries
    if !analysis.describes(problem) {
        return Err(Error::InvalidSettings {
            name: "analysis".into(),
            reason: "the scalar analysis was made for a different view graph".into(),
        });
    }
    Ok(compare(
        problem,
        analysis,
        (rotations, lambdas),
        gauge,
        (target, stop_at),
        forecast,
    ))
}

/// Steps 1 to 5 of [`scalar_comparison`] on consistent inputs (`gauge`: the estimate's gauge
/// terms, made only by the deflated bounds).
fn compare(
    problem: &MultipleProblem,
    analysis: &ScalarAnalysis,
    estimate: (&[Rotation], &[Matrix3<f64>]),
    gauge: GaugeSource<'_>,
    (target, stop_at): (f64, Option<Instant>),
    forecast: bool,
) -> std::result::Result<ScalarComparison, ScalarFailure> {
    if analysis.groups() > 0 {
        return groups::compare_grouped(problem, analysis, estimate, gauge, (stop_at, forecast));
    }
    let deflating = one_region_applies(problem, analysis).then_some(gauge);
    compare_plain(problem, analysis, estimate, (target, stop_at), deflating)
}

/// Steps 1 to 5 of the plain (ungrouped) comparison; with the estimate's gauge terms
/// (`deflating`) as one region (`[D13]`, "One region"): the pencil's `zeta` at least the
/// grouped one's, and a factor with up to [`groups::DEFLATION_EXTRA`] negative pivots beyond
/// the gauge's one proven by deflating the factor's columns at them, kept only when that
/// reaches `-target`.
pub(super) fn compare_plain(
    problem: &MultipleProblem,
    analysis: &ScalarAnalysis,
    (rotations, lambdas): (&[Rotation], &[Matrix3<f64>]),
    (target, stop_at): (f64, Option<Instant>),
    deflating: Option<GaugeSource<'_>>,
) -> std::result::Result<ScalarComparison, ScalarFailure> {
    let t_max = charges::orthogonality_defect(rotations)?;
    let c = charges::edge_charges(problem, rotations, lambdas, &analysis.copies, analysis.beta)?;
    let (rho1, rho0) = residuals::residual_bounds(problem, rotations, lambdas, &c.deg_n, target);
    let (floor, most) = match deflating {
        Some(_) => groups::one_region_pencil(analysis, c.d_max),
        None => (0.0, 0),
    };
    let pencil = split::pencil_weights(
        analysis,
        problem,
        (&c.reduced, &c.delta),
        (rho1, c.d_max, floor),
        target,
    )
    .ok_or(ScalarFailure::Numerical)?;
    let (headroom, backward_error, columns) =
        inertia::prove_charged(analysis, problem, &c, &pencil, most)?;
    let inertia = (headroom, backward_error);
    if !columns.is_empty() {
        // columns come only from a deflating factorisation (`most` above the gauge's one)
        let gauge = deflating.ok_or(ScalarFailure::Numerical)?;
        let negative_pivots = columns.len();
        let at = (rotations, lambdas, GaugeBounds::of(&gauge(), t_max));
        let (mu_m, kappa, residual) =
            groups::one_region_bound(problem, at, &c, columns, (pencil.zeta_free, stop_at))?;
        let proven = Proven {
            mu_m,
            t_max,
            inertia,
            kappa,
            residual,
            deflated: negative_pivots,
        };
        // kept only when it proves what the plain comparison would: `-target` or above
        return (proven.outcome(&c, analysis, &pencil).ok())
            .filter(|c| c.verified_min_eigenvalue >= -target)
            .ok_or(ScalarFailure::Inertia { negative_pivots });
    }
    // the cross terms (both bounds hold; the better is used); x1^T M x1 >= (zeta - eps) |x1|^2
    let kappa = split::kappa(&c.delta, pencil.zeta);
    let nf = problem.num_rotations() as f64;
    let plain = -(2.0 * kappa * (1.0 + nf.sqrt() * kappa) * rho1 + kappa * kappa * rho0);
    let absorbed = if pencil.zeta_free > 0.0 {
        -(rho0 + rho1 * rho1 / pencil.zeta_free) * kappa * kappa
    } else {
        f64::NEG_INFINITY
    };
    let mu_m = plain.max(absorbed) * (1.0 + 1e-10);
    let proven = Proven {
        mu_m,
        t_max,
        inertia,
        kappa,
        residual: rho1,
        deflated: 0,
    };
    proven.outcome(&c, analysis, &pencil)
}

/// Whether a plain comparison is one region (`[D13]` "One region"): a subgraph's (one part) of
/// a graph large enough for regions (the sparse graphs of 10^5 nodes whose regions fail by
/// hundreds of pivots and whose whole subgraph by one or a few).
fn one_region_applies(problem: &MultipleProblem, analysis: &ScalarAnalysis) -> bool {
    analysis.parts() == 1
        && analysis.edges_per_node() > 0.0
        && analysis::subgraph_groups(problem) > 1
}

/// What steps 1-5 proved: `lambda_min(M) >= mu_m`, the rotations' orthogonality defect
/// `t_max`, step 5's `(headroom, backward error)`, step 4's `kappa` and residual bound.
struct Proven {
    mu_m: f64,
    t_max: f64,
    inertia: (f64, f64),
    kappa: f64,
    residual: f64,
    /// Negative pivots deflated (the grouped comparison's; 0 otherwise).
    deflated: usize,
}

impl Proven {
    /// The comparison's outcome: `mu` for `S` by Ostrowski (`lambda_min(S) >= lambda_min(M) /
    /// sigma_min(D)^2`, `sigma_min(D)^2 >= 1 - t_max`), with its numbers.
    fn outcome(
        &self,
        c: &charges::EdgeCharges,
        analysis: &ScalarAnalysis,
        pencil: &split::PencilWeights,
    ) -> std::result::Result<ScalarComparison, ScalarFailure> {
        let mu = charges::ostrowski(self.mu_m, self.t_max).ok_or(ScalarFailure::Numerical)?;
        Ok(ScalarComparison {
            verified_min_eigenvalue: mu,
            max_delta: c.delta.iter().copied().fold(0.0, f64::max),
            second_order_edges: c.second_order_edges,
            dropped_edges: analysis.dropped_edges(),
            parts: analysis.parts(),
            shared_edges: analysis.shared_edges(),
            split_defect: pencil.defect,
            zeta: pencil.zeta,
            headroom: self.inertia.0,
            backward_error: self.inertia.1,
            factor_nonzeros: analysis.factor_len(),
            kappa: self.kappa,
            residual_bound: self.residual,
            deflated: self.deflated,
        })
    }
}
