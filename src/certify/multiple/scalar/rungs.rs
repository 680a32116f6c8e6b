//! The scalar comparison `[D13]` as rungs of the ladder: the whole graph's `n x n` factor, and,
//! when it does not fit the budget or does not prove, a subgraph's or a split's factors
//! (`paper-notes/certificates.md` `[D13]`, "Sparsified comparison", "Split comparison").
//!
//! The family is one rung of the verification ladder (its prediction: the whole graph's
//! factorisation when it fits, else its first fallback's); its attempt climbs its own shapes in
//! order, each logged, each only while what is left of the time budget covers its prediction.

use super::{
    MIN_SPLIT_DEGREE, SPARSIFIED_EDGES_PER_NODE, SPLIT_MIN_DEGREES, SPLIT_SHAPES, ScalarAnalysis,
    ScalarComparison, ScalarFailure, SplitShape, scalar_comparison,
};
use crate::certify::ladder::{Outcome, Prediction, Refusal, Rung};
use crate::certify::multiple::verify::{Check, Proof, Verification, VerifiedBound};
use crate::certify::settings::{Budget, CertifySettings};
use crate::error::Result;
use crate::linalg::{LanczosResult, rayleigh_quotient};
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use std::time::Instant;

/// The comparison's work besides the factorisations, per edge: the edge charges and the
/// double-double gauge block of steps 2 and 3 (measured 4.5e-6 s per edge on a 15k-node grid of
/// 22,216 edges, 2026-11-26, `rotavg multiple`: 0.10 s of which 3e-3 s of factorisation).
pub const SECONDS_PER_EDGE: f64 = 4.5e-6;

/// The scalar comparison's shapes: the whole graph, then the fallbacks (built when needed).
#[derive(Default)]
pub(in crate::certify::multiple) struct ScalarFamily {
    /// The whole graph's analysis when it fits the budget.
    whole: Option<ScalarAnalysis>,
    /// Why the whole graph's factor does not fit, when it does not.
    whole_refused: Option<Refusal>,
    /// The fallback shapes (subgraphs, splits) that fit, in order; `None` until built.
    fallbacks: Option<Vec<ScalarAnalysis>>,
}

impl Proof for ScalarFamily {
    fn rung(&self) -> Rung {
        match &self.whole {
            Some(_) => Rung::ScalarWhole,
            None => self
                .fallbacks
                .as_ref()
                .and_then(|f| f.first())
                .map_or(Rung::ScalarWhole, rung_of),
        }
    }

    fn predict(&mut self, cx: &Check<'_>) -> Result<std::result::Result<Prediction, Refusal>> {
        let Some(rotations) = cx.rotations else {
            return Ok(Err(Refusal::NotApplicable {
                reason: "the estimate's rotations are not known".into(),
            }));
        };
        if cx.problem.is_anisotropic() {
            return Ok(Err(Refusal::NotApplicable {
                reason: "the scalar comparison needs scalar edge weights; these edges carry 3x3 \
                         information matrices"
                    .into(),
            }));
        }
        let max_values = cx
            .settings
            .budget
            .max_factor_values(cx.problem.num_rotations());
        match ScalarAnalysis::new(cx.problem, max_values)? {
            Ok(a) => {
                cx.note_scalar_values(a.factor_len());
                match predict(cx.settings, &a) {
                    Ok(p) => {
                        self.whole = Some(a);
                        return Ok(Ok(p));
                    }
                    Err(refusal) => self.whole_refused = Some(refusal),
                }
            }
            Err(predicted) => {
                cx.note_scalar_values(predicted);
                self.whole_refused = Some(over_ordering(cx, predicted));
            }
        }
        let fallbacks = fallbacks(cx.problem, rotations, max_values, cx.settings)?;
        let first = fallbacks.first().map(|a| predict(cx.settings, a));
        self.fallbacks = Some(fallbacks);
        Ok(match first {
            Some(p) => p,
            None => Err(self
                .whole_refused
                .clone()
                .unwrap_or(Refusal::NotApplicable {
                    reason: "no subgraph or split fits".into(),
                })),
        })
    }

    fn attempt(&mut self, cx: &Check<'_>) -> Result<Option<VerifiedBound>> {
        let Some(rotations) = cx.rotations else {
            return Ok(None);
        };
        let target = 0.5 * cx.gap / cx.s.nrows().max(1) as f64;
        if let Some(a) = &self.whole {
            if let Some(b) = run(cx, a, rotations, target)? {
                return Ok(Some(b));
            }
        } else if let Some(refusal) = self.whole_refused.take() {
            cx.log(
                Rung::ScalarWhole,
                None,
                Outcome::Refused(refusal),
                Instant::now(),
            );
        }
        if self.fallbacks.is_none() {
            let max_values = cx
                .settings
                .budget
                .max_factor_values(cx.problem.num_rotations());
            self.fallbacks = Some(fallbacks(cx.problem, rotations, max_values, cx.settings)?);
        }
        for a in self.fallbacks.as_deref().unwrap_or_default() {
            let predicted = predict(cx.settings, a).ok();
            if let Some(refusal) = predicted.as_ref().and_then(|p| cx.time_refusal(p)) {
                cx.log(
                    rung_of(a),
                    predicted,
                    Outcome::Refused(refusal),
                    Instant::now(),
                );
                continue;
            }
            if let Some(b) = run(cx, a, rotations, target)? {
                return Ok(Some(b));
            }
        }
        Ok(None)
    }
}

/// The rung of an analysis: the whole graph, a subgraph or a split.
fn rung_of(a: &ScalarAnalysis) -> Rung {
    match (a.dropped_edges(), a.shape()) {
        (0, None) => Rung::ScalarWhole,
        (_, None) => Rung::ScalarSubgraph {
            edges_per_node: a.edges_per_node(),
        },
        (_, Some(s)) => Rung::ScalarSplit {
            parts: s.parts,
            copies: s.copies,
            min_degree: s.min_degree,
        },
    }
}

/// The refusal of the whole graph's factor by the ordering's prediction of `predicted` values.
fn over_ordering(cx: &Check<'_>, predicted: usize) -> Refusal {
    let n = cx.problem.num_rotations();
    match cx.settings.budget.factorisation_fits(predicted, n) {
        Err(reason) => Refusal::OverBudget { reason },
        Ok(()) => Refusal::OverBudget {
            reason: format!("the ordering predicts {predicted:.1e} factor values"),
        },
    }
}

/// The budget again with the exact factor and scratch (the ordering's prediction checked before
/// the symbolic analysis can be 2x low: 10^5-node random graph, 6e8 predicted, 1.21e9 stored). A
/// split's parts are factorised one after the other: the largest (with scratch) must fit the
/// memory budget, their counted multiply-adds together the time budget.
fn predict(
    settings: &CertifySettings,
    a: &ScalarAnalysis,
) -> std::result::Result<Prediction, Refusal> {
    let scratch = a.scratch_bytes().div_ceil(8);
    let largest = a.factor_len().saturating_add(scratch);
    let total: usize = a.factor_lens().map(|v| v.saturating_add(scratch)).sum();
    let multiply_adds = a.factor_multiply_adds();
    if let Err(reason) = settings
        .budget
        .counted_factorisations_fit(largest, multiply_adds, total)
    {
        return Err(Refusal::OverBudget { reason });
    }
    let cap = settings.dual.max_factor_nonzeros;
    if a.factor_len() > cap {
        return Err(Refusal::OverBudget {
            reason: format!(
                "the proof would need a factor of {:.1e} values; limit dual.max_factor_nonzeros = {cap:.1e}",
                a.factor_len()
            ),
        });
    }
    Ok(Prediction {
        seconds: Budget::predicted_factor_seconds(multiply_adds, total)
            + SECONDS_PER_EDGE * a.num_edges() as f64,
        bytes: Budget::factorisation_bytes(largest),
    })
}

/// Run one analysis: a bound when it proves `lambda_min(S) >= -target`; logged either way.
fn run(
    cx: &Check<'_>,
    a: &ScalarAnalysis,
    rotations: &[Rotation],
    target: f64,
) -> Result<Option<VerifiedBound>> {
    let since = Instant::now();
    let predicted = predict(cx.settings, a).ok();
    cx.notes().factorizations += a.parts();
    let outcome = scalar_comparison(cx.problem, a, rotations, cx.lambdas, target)?;
    let proof = match outcome {
        Ok(p) if p.verified_min_eigenvalue >= -target => p,
        other => {
            let reason = failure(target, other);
            cx.log(rung_of(a), predicted, Outcome::Failed { reason }, since);
            return Ok(None);
        }
    };
    let mut b = VerifiedBound::from_mu(
        cx,
        proof.verified_min_eigenvalue,
        Verification::ScalarComparison,
    );
    b.fp_margin = proof.backward_error;
    b.factorizations = proof.parts;
    b.factor_nonzeros = proof.factor_nonzeros;
    if cx.settings.dual.estimate_when_verified {
        cx.notes().estimate = Some(gauge_estimate(cx, rotations));
    }
    b.scalar_comparison = Some(proof);
    cx.log(rung_of(a), predicted, cx.proved(&b), since);
    Ok(Some(b))
}

/// An estimate of `lambda_min(S)` (never a bound): the smallest Rayleigh quotient of the gauge
/// directions, the near-null vectors at a critical point (better there than a short Lanczos
/// run in the cluster at 0, and `O(nnz)`).
fn gauge_estimate(cx: &Check<'_>, rotations: &[Rotation]) -> LanczosResult {
    let mut best = LanczosResult {
        value: f64::INFINITY,
        vector: Vec::new(),
        residual: f64::INFINITY,
        iterations: 0,
        stop: crate::linalg::LanczosStop::InvariantSubspace { dimension: 3 },
    };
    for k in 0..3 {
        let mut v = crate::certify::multiple::multipliers::gauge_column(rotations, k);
        let nv = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if nv == 0.0 || !nv.is_finite() {
            continue;
        }
        v.iter_mut().for_each(|x| *x /= nv);
        let (rq, res) = rayleigh_quotient(cx.s.as_ref(), &v);
        if rq < best.value {
            best = LanczosResult {
                value: rq,
                vector: v,
                residual: res,
                iterations: 0,
                stop: best.stop,
            };
        }
    }
    best
}

/// The analyses to try when the whole graph's factor does not fit or does not prove, in order:
/// the first subgraph of [`SPARSIFIED_EDGES_PER_NODE`] that fits, alone when it keeps at least
/// half of the edges; otherwise (its dropped charges would outweigh what it keeps: a split
/// charges every part only its share) first the splits, for each minimum degree of
/// [`SPLIT_MIN_DEGREES`] the first shape of [`SPLIT_SHAPES`] that fits, then the subgraph.
/// "Fits" is the budget's test of each one's own prediction, so a larger budget only allows
/// stronger shapes (more edges kept, fewer parts).
fn fallbacks(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    max_values: usize,
    settings: &CertifySettings,
) -> Result<Vec<ScalarAnalysis>> {
    let fits = |a: &ScalarAnalysis| predict(settings, a).is_ok();
    let mut subgraph = None;
    for k in SPARSIFIED_EDGES_PER_NODE {
        if let Ok(a) = ScalarAnalysis::sparsified(problem, rotations, k, max_values)?
            && fits(&a)
        {
            subgraph = Some(a);
            break;
        }
    }
    if subgraph
        .as_ref()
        .is_some_and(|a| 2 * a.dropped_edges() <= problem.num_edges())
    {
        return Ok(subgraph.into_iter().collect());
    }
    let mut candidates = splits(problem, max_values, &fits)?;
    candidates.extend(subgraph);
    Ok(candidates)
}

/// For each minimum degree, the first split shape that fits (a larger minimum degree only adds
/// edges: it starts where the smaller one fitted).
fn splits(
    problem: &MultipleProblem,
    max_values: usize,
    fits: &dyn Fn(&ScalarAnalysis) -> bool,
) -> Result<Vec<ScalarAnalysis>> {
    let degree = 2.0 * problem.num_edges() as f64 / problem.num_rotations().max(1) as f64;
    let mut candidates = Vec::new();
    let mut first = 0;
    for min_degree in SPLIT_MIN_DEGREES {
        let mut fitted = None;
        for (at, &(parts, copies)) in SPLIT_SHAPES.iter().enumerate().skip(first) {
            if (parts as f64) * MIN_SPLIT_DEGREE > degree * copies as f64 {
                break;
            }
            let shape = SplitShape {
                parts,
                copies,
                min_degree,
            };
            if let Ok(a) = ScalarAnalysis::split(problem, shape, max_values)?
                && fits(&a)
            {
                candidates.push(a);
                fitted = Some(at);
                break;
            }
        }
        match fitted {
            Some(at) => first = at,
            None => break,
        }
    }
    Ok(candidates)
}

/// Why a scalar comparison that ran did not prove enough, with the numbers.
fn failure(target: f64, outcome: std::result::Result<ScalarComparison, ScalarFailure>) -> String {
    match outcome {
        Ok(p) => format!(
            "its cross terms give lambda_min(S) >= {:.1e}, below the -{target:.1e} the gap \
             budget allows",
            p.verified_min_eigenvalue
        ),
        Err(ScalarFailure::Inertia { negative_pivots }) => {
            format!("{negative_pivots} negative pivots (its condition needs exactly 1)")
        }
        Err(ScalarFailure::Numerical) => "a zero or non-finite pivot".into(),
        Err(ScalarFailure::BackwardError) => {
            "the factorisation's backward error exceeded its headroom".into()
        }
        Err(ScalarFailure::NotOrthogonal) => "the rotations are too far from orthogonal".into(),
    }
}
