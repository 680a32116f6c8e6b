//! The scalar comparison `[D13]` as rungs of the ladder: the whole graph's `n x n` factor, and,
//! when it does not fit the budget or does not prove, a subgraph's or a split's factors
//! (`paper-notes/certificates.md` `[D13]`, "Sparsified comparison", "Split comparison").
//!
//! The family is one rung of the verification ladder (its prediction: the whole graph's
//! factorisation when it fits, else its first fallback's); its attempt climbs its own shapes in
//! order, each logged, each only while what is left of the time budget covers its prediction.

use super::charges::weightless_groups;
use super::forecast::{FORECAST_FAILURE_SUCCESS, forecast_fails};
use super::hub::HubGraph;
use super::hub_rung::{plan_hub, run_hub};
use super::{
    MIN_SPLIT_DEGREE, SECONDS_PER_EDGE, SPARSIFIED_EDGES_PER_NODE, SPLIT_MIN_DEGREES, SPLIT_SHAPES,
    ScalarAnalysis, ScalarFailure, SplitShape, failure_text, proved_bound, scalar_comparison_until,
    subgraph_groups, subgraph_ladder,
};
use crate::certify::log::{FREE_SECONDS, Outcome, Prediction, Refusal};
use crate::certify::multiple::check::{Check, counted_prediction};
use crate::certify::multiple::verified::VerifiedBound;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifySettings;
use crate::error::Result;
use crate::linalg::LanczosResult;
use crate::multiple::MultipleProblem;
use crate::so3::Rotation;
use std::time::Instant;

/// The grouped comparison's coarse correction per edge and column (`3` per region): its
/// conjugate gradients, about 20 iterations of a product with `M` and two projections
/// (measured 1.9e-8 s per edge, column and iteration: 3x10^4 nodes, 3x10^5 edges, 12
/// columns, 14 iterations in 0.94 s, 2026-12-03).
const GROUPED_SECONDS_PER_EDGE_COLUMN: f64 = 4e-7;

/// When the whole graph's factor fits but is predicted to take more than this many seconds, the
/// subgraphs are tried before it, sparsest first, while together they are predicted to take at
/// most [`SUBGRAPHS_BEFORE_THE_WHOLE_FRACTION`] of the whole graph's time (0.1 s: a 10^4-node
/// random graph of degree 7 at 0.05 rad, whole graph predicted 0.77 s, is proven by 2 edges
/// per node in 0.023 s; 1 s until 2026-11-30).
pub const SUBGRAPHS_BEFORE_THE_WHOLE_ABOVE_SECONDS: f64 = 0.1;

/// See [`SUBGRAPHS_BEFORE_THE_WHOLE_ABOVE_SECONDS`].
pub const SUBGRAPHS_BEFORE_THE_WHOLE_FRACTION: f64 = 0.5;

/// The share of the nodes, as negative pivots of the sparsest subgraph in regions, from which
/// the whole graph's sparsest subgraph (the same edges per node, without the regions' cut
/// edges charged) is taken to fail with [`WHOLE_SHARE_OF_REGIONAL_PIVOTS`] of them, and the
/// whole graph's subgraphs jump as after that failure ([`subgraph_after`]): on random graphs
/// of 3 edges per node (`gen_graph.py expander N 6 SIGMA`, 2026-12-05) the regions' 2 edges
/// per node failed with 3.5 % (3x10^4 nodes, 0.1 rad) and 4.4 % (10^5, 0.1 rad) of the nodes,
/// and the whole graph's 2 then failed too (with 1.7 %: 0.38 s and 7.1 s lost), while at 1.1 %
/// (10^5, 0.07 rad), 0.5 % (3x10^4, 0.07 rad) and 0.04 % (10^5, 0.05 rad) it proved. It
/// decides only the cost, never what is proven.
const SKIP_THE_WHOLE_SPARSEST_FROM: f64 = 0.03;

/// The whole graph's negative pivots at its sparsest subgraph as a share of the regions'
/// (measured 0.49 and 0.39 on the two graphs of [`SKIP_THE_WHOLE_SPARSEST_FROM`]).
const WHOLE_SHARE_OF_REGIONAL_PIVOTS: f64 = 0.4;

/// The scalar comparison's shapes: the whole graph (its analysis is the check's,
/// [`Check::scalar`]), then the fallbacks (analysed when reached).
#[derive(Default)]
pub(in crate::certify::multiple) struct ScalarFamily {
    /// The whole graph's prediction when its factor fits the budget.
    whole: Option<Prediction>,
    /// Why the whole graph's factor does not fit, when it does not.
    whole_refused: Option<Refusal>,
    /// The whole graph without its parallel groups that keep no weight at the estimate
    /// ([`weightless_groups`]: a rig's pseudo-edges `[H21]`), analysed in place of the check's
    /// whole graph (which the `3n` rungs' predictions keep) when there are such groups.
    pruned: Option<std::result::Result<ScalarAnalysis, usize>>,
    /// The first fallback (the sparsest subgraph, else the first split that fits), analysed by
    /// the plan: its prediction is the family's when the whole graph does not fit.
    first_fallback: Option<ScalarAnalysis>,
    /// Where the fallbacks after the first continue.
    fallbacks: Fallbacks,
    planned: Option<std::result::Result<Prediction, Refusal>>,
    /// The hub shape of an anisotropic problem (`[G13]`), when it has one: its only shape.
    hub: Option<HubGraph>,
    /// The first fallback is the sparsest subgraph, analysed instead of the whole graph (dense
    /// graphs, [`Check::take_deferred`]): it runs first, and the whole graph is analysed only
    /// when it does not prove.
    deferred: bool,
    done: bool,
}

impl<'a> Rung<Check<'a>> for ScalarFamily {
    fn proof(&self) -> Proof {
        Proof::ScalarComparison
    }

    fn plan(&mut self, cx: &Check<'a>) -> Result<Plan> {
        if self.done {
            return Ok(Plan::Done);
        }
        if self.planned.is_none() {
            self.planned = Some(self.predict(cx)?);
        }
        let plan = cx.plan_from(self.planned.clone());
        if !matches!(plan, Plan::Run(_)) {
            cx.close_deferred();
        }
        Ok(plan)
    }

    fn attempt(&mut self, cx: &mut Check<'a>) -> Result<Found> {
        self.done = true;
        let bound = self.climb_shapes(cx);
        cx.close_deferred();
        let bound = bound?;
        // every shape tried is in the log
        Ok(Found::logged(match bound {
            Some(b) => cx.offer(b),
            None => Outcome::Failed {
                reason: "no shape proved enough".into(),
            },
        }))
    }
}

impl ScalarFamily {
    /// The whole graph's prediction, else the first fallback's, else why none fits.
    fn predict(&mut self, cx: &Check<'_>) -> Result<std::result::Result<Prediction, Refusal>> {
        let Some(rotations) = cx.rotations else {
            return Ok(Err(Refusal::NotApplicable {
                reason: "the estimate's rotations are not known".into(),
            }));
        };
        if cx.problem.is_anisotropic() {
            if let Some((hub, predicted)) = plan_hub(cx)? {
                self.hub = hub;
                return Ok(predicted);
            }
            return Ok(Err(Refusal::NotApplicable {
                reason: "the scalar comparison needs scalar edge weights; these edges carry 3x3 \
                         information matrices"
                    .into(),
            }));
        }
        if let Some(sub) = cx.take_deferred() {
            self.fallbacks.subgraph = 1;
            if let Ok(p) = predict(cx.settings, &sub) {
                self.first_fallback = Some(sub);
                self.deferred = true;
                return Ok(Ok(p));
            }
            // denser subgraphs have larger factors
            self.fallbacks.subgraph = subgraph_ladder(cx.problem).len();
        }
        if let Some(p) = self.plan_whole(cx, rotations)? {
            return Ok(Ok(p));
        }
        self.first_fallback = self.fallbacks.next(cx, rotations, None)?;
        Ok(match &self.first_fallback {
            Some(a) => predict(cx.settings, a),
            None => Err(self
                .whole_refused
                .clone()
                .unwrap_or(Refusal::NotApplicable {
                    reason: "no subgraph or split fits".into(),
                })),
        })
    }

    /// The whole graph's prediction when its factor fits (kept in `whole`), else why not (kept
    /// in `whole_refused`).
    fn plan_whole(&mut self, cx: &Check<'_>, rotations: &[Rotation]) -> Result<Option<Prediction>> {
        if self.pruned.is_none()
            && let Some(left_out) = weightless_groups(cx.problem, rotations)
        {
            let max_values = cx.max_factor_values();
            self.pruned = Some(ScalarAnalysis::without(cx.problem, &left_out, max_values)?);
        }
        match whole_of(&self.pruned, cx)? {
            Some(Ok(a)) => match predict(cx.settings, a) {
                Ok(mut p) => {
                    // a failure worth avoiding: forecast it (free predictions are not)
                    if p.seconds > FREE_SECONDS && forecast_fails(cx.problem, rotations) {
                        p = p.with_success(FORECAST_FAILURE_SUCCESS);
                    }
                    self.whole = Some(p);
                    return Ok(Some(p));
                }
                Err(refusal) => self.whole_refused = Some(refusal),
            },
            Some(Err(predicted)) => self.whole_refused = Some(over_ordering(cx, predicted)),
            None => {}
        }
        Ok(None)
    }

    /// The deferred sparsest subgraph ([`Self::deferred`]) and the denser ones after it: a
    /// bound, or, when none proves, the whole graph's analysis and plan made now (the climb then
    /// goes on as if it had been analysed first, the subgraphs tried). Every subgraph is sparser
    /// than the whole graph (it defers at
    /// [`crate::certify::multiple::check::DEFER_WHOLE_EDGES_PER_NODE`] edges per node, the
    /// densest subgraph keeps as many), so it is analysed and factored faster; the whole graph's
    /// analysis alone took 0.17 s of a 1.4 s certificate that the subgraph of 4 edges per node
    /// proved (10^4 nodes, 10^5 edges, 0.1 rad).
    fn deferred_first(
        &mut self,
        cx: &Check<'_>,
        rotations: &[Rotation],
        target: f64,
    ) -> Result<Option<VerifiedBound>> {
        self.deferred = false;
        let first = self.first_fallback.take();
        let fallbacks = &mut self.fallbacks;
        let next = |failure| fallbacks.next_subgraph(cx, rotations, failure);
        if let Some(b) = in_turn(cx, first, rotations, target, next)? {
            return Ok(Some(b));
        }
        self.plan_whole(cx, rotations)?;
        Ok(None)
    }

    /// Try the shapes in order, each logged: a verified bound, or `None`.
    fn climb_shapes(&mut self, cx: &Check<'_>) -> Result<Option<VerifiedBound>> {
        let Some(rotations) = cx.rotations else {
            return Ok(None);
        };
        let target = 0.5 * cx.gap / cx.dim().max(1) as f64;
        if let Some(hub) = self.hub.take() {
            return Ok(run_hub(cx, &hub, rotations, target));
        }
        if self.deferred
            && let Some(b) = self.deferred_first(cx, rotations, target)?
        {
            return Ok(Some(b));
        }
        let pruned = self.pruned.take();
        if let (Some(whole), Some(Ok(a))) = (self.whole, whole_of(&pruned, cx)?) {
            if let Some(b) = self.subgraphs_first(cx, rotations, whole, target)? {
                return Ok(Some(b));
            }
            // the subgraphs spent part of the budget: the whole graph still has to fit what is
            // left (the plan checked it before they ran)
            if refused_for_time(cx, Some(whole)) {
                return Ok(None);
            }
            match run(cx, a, rotations, target)? {
                (Some(b), _) => return Ok(Some(b)),
                // a subgraph's or a split's condition is harder than the whole graph's
                (None, Some(f)) if f.negative_count().is_some() => return Ok(None),
                (None, _) => {}
            }
        } else if let Some(refusal) = self.whole_refused.take() {
            let outcome = Outcome::Refused(refusal);
            cx.log(Proof::ScalarComparison, None, outcome, Instant::now());
        }
        self.fallbacks_after(cx, rotations, target)
    }

    /// Subgraphs before the whole graph, sparsest first, while together they are predicted to
    /// take at most a fraction of the whole graph's factorisation (random graphs of 3x10^4
    /// nodes: the whole graph's scalar factor fits but fills).
    fn subgraphs_first(
        &mut self,
        cx: &Check<'_>,
        rotations: &[Rotation],
        whole: Prediction,
        target: f64,
    ) -> Result<Option<VerifiedBound>> {
        if whole.seconds <= SUBGRAPHS_BEFORE_THE_WHOLE_ABOVE_SECONDS {
            return Ok(None);
        }
        let allowed = SUBGRAPHS_BEFORE_THE_WHOLE_FRACTION * whole.seconds;
        let (mut spent, mut failure) = (0.0, None);
        while let Some(sub) = self.fallbacks.next(cx, rotations, failure.take())? {
            let seconds = predict(cx.settings, &sub).map_or(f64::INFINITY, |p| p.seconds);
            if sub.shape().is_some() || spent + seconds > allowed {
                self.first_fallback = Some(sub);
                break;
            }
            spent += seconds;
            match run(cx, &sub, rotations, target)? {
                (Some(b), _) => return Ok(Some(b)),
                (None, failed) => failure = failed,
            }
        }
        Ok(None)
    }

    /// The fallbacks, one after the other while they fit what is left of the time budget.
    fn fallbacks_after(
        &mut self,
        cx: &Check<'_>,
        rotations: &[Rotation],
        target: f64,
    ) -> Result<Option<VerifiedBound>> {
        let first = match self.first_fallback.take() {
            Some(a) => Some(a),
            None => self.fallbacks.next(cx, rotations, None)?,
        };
        let fallbacks = &mut self.fallbacks;
        in_turn(cx, first, rotations, target, |failure| {
            fallbacks.next(cx, rotations, failure)
        })
    }
}

/// The whole graph's analysis for the family: `pruned` when there is one, else the check's.
fn whole_of<'c>(
    pruned: &'c Option<std::result::Result<ScalarAnalysis, usize>>,
    cx: &'c Check<'_>,
) -> Result<Option<std::result::Result<&'c ScalarAnalysis, usize>>> {
    let whole = match pruned {
        Some(p) => Some(p),
        None => cx.scalar()?,
    };
    Ok(whole.map(|w| w.as_ref().map_err(|&predicted| predicted)))
}

/// `first`, then each shape `next` gives after the last one's failure, until one proves (its
/// bound) or none is left; a shape predicted over what is left of the time budget is logged
/// refused and ends the turns (the later shapes are larger, subgraphs, or as large, splits).
fn in_turn(
    cx: &Check<'_>,
    first: Option<ScalarAnalysis>,
    rotations: &[Rotation],
    target: f64,
    mut next: impl FnMut(Option<ScalarFailure>) -> Result<Option<ScalarAnalysis>>,
) -> Result<Option<VerifiedBound>> {
    let mut shape = first;
    while let Some(a) = shape {
        if refused_for_time(cx, predict(cx.settings, &a).ok()) {
            return Ok(None);
        }
        let (bound, failure) = run(cx, &a, rotations, target)?;
        if bound.is_some() {
            return Ok(bound);
        }
        shape = next(failure)?;
    }
    Ok(None)
}

/// Whether `predicted` is over what is left of the time budget; if so, it is logged refused.
fn refused_for_time(cx: &Check<'_>, predicted: Option<Prediction>) -> bool {
    let Some(refusal) = predicted.as_ref().and_then(|p| cx.time_refusal(p)) else {
        return false;
    };
    let outcome = Outcome::Refused(refusal);
    cx.log(Proof::ScalarComparison, predicted, outcome, Instant::now());
    true
}

/// The fallbacks when the whole graph's factor does not fit or does not prove, analysed one at a
/// time as they are reached: the subgraphs of [`SPARSIFIED_EDGES_PER_NODE`] from the sparsest
/// (the cheapest factor; at 0.02 rad a 10^5-node random graph is proven by the first, at 0.1 rad
/// by the fourth), while they fit the budget, then, for each minimum degree of
/// [`SPLIT_MIN_DEGREES`], the first split shape of [`SPLIT_SHAPES`] that fits (dense view graphs,
/// whose subgraphs drop most of the charges they must carry). A subgraph that fails with `p`
/// negative pivots jumps to a denser one by `p / n` ([`subgraph_after`]), or, when that one does
/// not fit, to the densest between that fits, so that a hopeless start costs one cheap
/// factorisation. "Fits" is the budget's test of each one's own prediction: a
/// larger budget only allows more shapes. Which shapes run decides only whether the proof
/// succeeds and what it costs, never what is proven.
struct Fallbacks {
    /// The next subgraph of [`subgraph_ladder`] to analyse (past the end: none left).
    subgraph: usize,
    /// The sparsest subgraph found not to fit the budget (`usize::MAX` until then): it and
    /// the denser ones are not tried.
    unfit: usize,
    /// The splits, computed when the subgraphs are exhausted; `None` until then.
    splits: Option<std::vec::IntoIter<ScalarAnalysis>>,
    /// The subgraphs in regions ([`subgraph_groups`]) are exhausted: the whole graph's
    /// subgraphs come next (sparse graphs at large noise, whose regions drop too many charged
    /// edges: 10^5 nodes of 3 edges per node at 0.1 rad leave 300-550 extra negative pivots in
    /// 8 regions at 4-6 edges per node, where the whole graph's subgraphs prove).
    plain: bool,
}

impl Default for Fallbacks {
    fn default() -> Self {
        Fallbacks {
            subgraph: 0,
            unfit: usize::MAX,
            splits: None,
            plain: false,
        }
    }
}

impl Fallbacks {
    /// The next analysis to run after the last one's `failure` (`None`: the first), or `None`
    /// when no shape is left that fits.
    fn next(
        &mut self,
        cx: &Check<'_>,
        rotations: &[Rotation],
        failure: Option<ScalarFailure>,
    ) -> Result<Option<ScalarAnalysis>> {
        if let Some(a) = self.next_subgraph(cx, rotations, failure)? {
            return Ok(Some(a));
        }
        if !cx.settings.dual.scalar_fallbacks {
            return Ok(None);
        }
        if self.splits.is_none() {
            let max_values = cx.max_factor_values();
            let fits = |a: &ScalarAnalysis| predict(cx.settings, a).is_ok();
            self.splits = Some(splits(cx.problem, max_values, &fits)?.into_iter());
        }
        Ok(self.splits.as_mut().and_then(Iterator::next))
    }

    /// The next subgraph that fits after the last one's `failure` (its negative pivots skip
    /// some), or `None` when none is left (the splits come next).
    fn next_subgraph(
        &mut self,
        cx: &Check<'_>,
        rotations: &[Rotation],
        failure: Option<ScalarFailure>,
    ) -> Result<Option<ScalarAnalysis>> {
        if !cx.settings.dual.scalar_fallbacks || self.splits.is_some() {
            return Ok(None);
        }
        let mut failure = failure;
        loop {
            let (list, groups) = self.ladder(cx.problem);
            // the regions' sparsest subgraph's failure, when it was their only one
            let sparsest = (groups > 1 && list.len() == 1)
                .then(|| failure.as_ref().and_then(ScalarFailure::negative_count))
                .flatten();
            if let Some(a) = self.next_in(cx, rotations, (list, groups), failure.take())? {
                return Ok(Some(a));
            }
            if groups == 1 {
                return Ok(None);
            }
            (self.plain, self.subgraph, self.unfit) = (true, 0, usize::MAX);
            let n = cx.problem.num_rotations();
            failure = sparsest.and_then(|p| whole_sparsest_failure(p, n));
        }
    }

    /// The subgraphs to climb and their regions: those of [`subgraph_ladder`] in the regions
    /// of [`subgraph_groups`] (on graphs of fewer than [`DENSE_EDGES_PER_NODE`] edges per node
    /// only the sparsest: proven in regions at 0.02 rad, 10^5 nodes and 3 edges per node, but
    /// none at 0.1 rad, where 2-6 edges per node in regions cost 15 s before the whole graph's
    /// subgraphs proved), then (`plain`) the whole graph's.
    fn ladder(&self, problem: &crate::multiple::MultipleProblem) -> (&'static [f64], usize) {
        let dense = super::analysis::is_dense(problem);
        match subgraph_groups(problem) {
            groups if groups > 1 && !self.plain && dense => (subgraph_ladder(problem), groups),
            groups if groups > 1 && !self.plain => (&subgraph_ladder(problem)[..1], groups),
            _ => (&SPARSIFIED_EDGES_PER_NODE, 1),
        }
    }

    /// The next subgraph of `list` in `groups` regions that fits, after the last one's
    /// `failure`.
    fn next_in(
        &mut self,
        cx: &Check<'_>,
        rotations: &[Rotation],
        (list, groups): (&[f64], usize),
        failure: Option<ScalarFailure>,
    ) -> Result<Option<ScalarAnalysis>> {
        self.unfit = self.unfit.min(list.len());
        let lowest = self.subgraph;
        if let Some(negative_pivots) = failure.and_then(|f| f.negative_count()) {
            let n = cx.problem.num_rotations();
            let jump = subgraph_after(list, lowest.saturating_sub(1), negative_pivots, n);
            self.subgraph = jump.min(self.unfit.saturating_sub(1)).max(lowest);
        }
        let max_values = cx.max_factor_values();
        while self.subgraph < self.unfit {
            let at = self.subgraph;
            let k = list[at];
            let group = cx.subgraph_regions().filter(|_| groups > 1);
            match ScalarAnalysis::in_regions(cx.problem, rotations, k, group, max_values)? {
                Ok(a) if predict(cx.settings, &a).is_ok() => {
                    self.subgraph = at + 1;
                    return Ok(Some(a));
                }
                // denser subgraphs have larger factors; a sparser one jumped over may fit
                _ => {
                    self.unfit = at;
                    self.subgraph = if at > lowest { at - 1 } else { self.unfit };
                }
            }
        }
        Ok(None)
    }
}

/// After subgraph `failed` of `list` (a [`subgraph_ladder`]) fails with `p` negative pivots on a
/// graph of `n` nodes, the index of the next to try: the first that keeps at least `Delta` more
/// edges per node, `Delta = 0.5` for `p / n < 0.01`, else `max(0.75, 0.35 + 8 p / n)` (the next
/// one when `p < n / 1000`). Fitted on random graphs of 10^4 to 10^5 nodes, 3 to 15 edges per
/// node, 0.05 to 0.1 rad (2026-12-01, `examples/scalar_sweep.rs`): from the sparsest it picks
/// the first that proves on all of them but one (`p / n = 0.017`, where 2.5 proves and it picks
/// 2.75); 4 edges per node proved at `p / n = 0.20` at the sparsest, 3.5 at 0.13, 2.75 at
/// 0.016-0.049, 2.5 at 0.009-0.017. Which subgraph runs decides only the cost, never what is
/// proven.
pub(in crate::certify::multiple) fn subgraph_after(
    list: &[f64],
    failed: usize,
    negative_pivots: usize,
    n: usize,
) -> usize {
    let next = failed + 1;
    let fraction = negative_pivots as f64 / n.max(1) as f64;
    if fraction < 1e-3 || failed >= list.len() {
        return next;
    }
    let more = if fraction < 1e-2 {
        0.5
    } else {
        (0.35 + 8.0 * fraction).max(0.75)
    };
    let wanted = list[failed] + more;
    let last = list.len() - 1;
    (next..=last)
        .find(|&k| list[k] >= wanted)
        .unwrap_or(last)
        .max(next)
}

/// The whole graph's sparsest subgraph taken to fail after the regions' failed with
/// `regional_pivots` negative pivots on a graph of `n` nodes (see
/// [`SKIP_THE_WHOLE_SPARSEST_FROM`]), `None` when it is still tried.
fn whole_sparsest_failure(regional_pivots: usize, n: usize) -> Option<ScalarFailure> {
    let p = regional_pivots as f64;
    (p >= SKIP_THE_WHOLE_SPARSEST_FROM * n as f64).then_some(ScalarFailure::Inertia {
        negative_pivots: (p * WHOLE_SHARE_OF_REGIONAL_PIVOTS) as usize,
    })
}

/// Subgraphs to skip after one fails with `negative_pivots` (`floor(log16 p)`; 0 for `p < 16`):
/// the block comparison's rule (`[A15]`; the scalar comparison's is [`subgraph_after`]).
pub(in crate::certify::multiple) fn skipped_subgraphs(negative_pivots: usize) -> usize {
    let mut skip = 0;
    let mut p = negative_pivots;
    while p >= 16 {
        p /= 16;
        skip += 1;
    }
    skip
}

/// The shape of an analysis in words: the whole graph, a subgraph or a split.
fn shape_of(a: &ScalarAnalysis) -> String {
    match (a.dropped_edges(), a.shape()) {
        (0, None) => "whole graph".into(),
        (d, None) if a.edges_per_node() == 0.0 => {
            format!("whole graph without {d} weightless parallel edges")
        }
        (_, None) if a.groups() > 1 => format!(
            "subgraph of {} edges per node in {} regions (beta {}) [D13, grouped subgraphs]",
            a.edges_per_node(),
            a.groups(),
            a.second_order_beta()
        ),
        (_, None) => format!(
            "subgraph of {} edges per node (beta {})",
            a.edges_per_node(),
            a.second_order_beta()
        ),
        (_, Some(s)) => format!(
            "split into {} parts ({} per edge, degree >= {})",
            s.parts, s.copies, s.min_degree
        ),
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
    // the coarse correction's vectors are held beside the (freed) factor: the larger counts
    let largest = a
        .factor_len()
        .saturating_add(scratch)
        .max(a.coarse_values());
    let total: usize = a.factor_lens().map(|v| v.saturating_add(scratch)).sum();
    let columns = 3 * a.groups();
    let other = (SECONDS_PER_EDGE + GROUPED_SECONDS_PER_EDGE_COLUMN * columns as f64)
        * a.num_edges() as f64;
    let multiply_adds = a.factor_multiply_adds();
    counted_prediction(
        settings,
        largest,
        total,
        multiply_adds,
        a.factor_len(),
        other,
    )
}

/// Run one analysis: a bound when it proves `lambda_min(S) >= -target`, else why not (`None`
/// when it ran but its cross terms were too large); logged either way.
fn run(
    cx: &Check<'_>,
    a: &ScalarAnalysis,
    rotations: &[Rotation],
    target: f64,
) -> Result<(Option<VerifiedBound>, Option<ScalarFailure>)> {
    let since = Instant::now();
    let predicted = predict(cx.settings, a).ok();
    cx.notes().factorizations += a.parts();
    let stop_at = cx.deadline.instant();
    let gauge = || *cx.gauge_terms(rotations);
    let estimate = (rotations, cx.lambdas);
    // the sparsest subgraph in regions is skipped where its charges forecast its failure
    let forecast = a.groups() > 1 && a.edges_per_node() == SPARSIFIED_EDGES_PER_NODE[0];
    let limits = (target, stop_at);
    let outcome = scalar_comparison_until(cx.problem, a, estimate, &gauge, limits, forecast)?;
    let proof = match outcome {
        Ok(p) if p.verified_min_eigenvalue >= -target => p,
        other => {
            let failed = other.as_ref().err().cloned();
            let mu = other.map(|p| p.verified_min_eigenvalue);
            let needed = a.groups().max(1);
            let reason = format!("{}: {}", shape_of(a), failure_text(target, mu, needed));
            cx.log(
                Proof::ScalarComparison,
                predicted,
                Outcome::Failed { reason },
                since,
            );
            return Ok((None, failed));
        }
    };
    if cx.settings.dual.estimate_when_verified {
        cx.notes().estimate = Some(gauge_estimate(cx, rotations));
    }
    let b = proved_bound(cx, proof, predicted, since, shape_of(a));
    Ok((Some(b), None))
}

/// An estimate of `lambda_min(S)` (never a bound): the smallest Rayleigh quotient of the gauge
/// directions, the near-null vectors at a critical point (better there than a short Lanczos
/// run in the cluster at 0), from the estimate's gauge terms: `S Y` in double-double, already
/// made by the first-order conditions, so `S` itself is not formed.
fn gauge_estimate(cx: &Check<'_>, rotations: &[Rotation]) -> LanczosResult {
    let rayleigh = cx.gauge_terms(rotations).rayleigh;
    let k = (0..3)
        .min_by(|&a, &b| rayleigh[a].0.total_cmp(&rayleigh[b].0))
        .unwrap_or(0);
    let (value, residual) = rayleigh[k];
    let mut vector = Vec::new();
    if value.is_finite() {
        vector = crate::certify::multiple::multipliers::gauge_column(rotations, k);
        let nv = vector.iter().map(|x| x * x).sum::<f64>().sqrt();
        vector.iter_mut().for_each(|x| *x /= nv);
    }
    LanczosResult {
        value,
        vector,
        residual,
        iterations: 0,
        stop: crate::linalg::LanczosStop::InvariantSubspace { dimension: 3 },
    }
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

#[cfg(test)]
mod tests {
    use super::skipped_subgraphs;
    use crate::certify::multiple::scalar::SPARSIFIED_EDGES_PER_NODE;

    fn subgraph_after(failed: usize, p: usize, n: usize) -> usize {
        super::subgraph_after(&SPARSIFIED_EDGES_PER_NODE, failed, p, n)
    }

    /// `floor(log16 p)`: a near miss goes on to the next subgraph, a hopeless start skips ahead.
    #[test]
    fn failed_subgraphs_skip_by_their_negative_pivots() {
        let skips: Vec<usize> = [2, 5, 15, 16, 90, 255, 256, 1546, 5760, usize::MAX]
            .into_iter()
            .map(skipped_subgraphs)
            .collect();
        assert_eq!(skips, [0, 0, 0, 1, 1, 1, 2, 2, 3, 15]);
    }

    /// The measured cases of `subgraph_after`'s fit (indices of 2, 2.25, 2.5, 2.75, 3, 3.5, 4).
    #[test]
    fn failed_subgraphs_jump_by_their_share_of_negative_pivots() {
        let n = 10_000;
        let after = |failed, p| subgraph_after(failed, p, n);
        assert_eq!(after(0, 5), 1, "a near miss: the next");
        assert_eq!(after(0, 87), 2, "p / n = 0.009: 2.5");
        assert_eq!(after(0, 155), 3, "p / n = 0.016: 2.75");
        assert_eq!(after(0, 493), 3, "p / n = 0.049: 2.75");
        assert_eq!(after(0, 1291), 5, "p / n = 0.13: 3.5");
        assert_eq!(after(0, 2013), 6, "p / n = 0.20: 4");
        assert_eq!(after(0, 9000), 6, "past the list: the last");
        assert_eq!(after(5, 162), 6, "from 3.5: 4");
        assert_eq!(after(6, 430), 7, "after the last: none left");
    }

    /// The regions' failures measured on graphs of 3 edges per node (`SKIP_THE_WHOLE_SPARSEST_FROM`):
    /// the whole graph's sparsest is skipped where it failed, and the jump is the one its own
    /// failure gave (2.75 of the fit's list, as after its 511 and 1729 negative pivots); tried
    /// where it proved.
    #[test]
    fn the_whole_sparsest_is_skipped_where_the_regions_failed_widely() {
        let jump = |regional, n| {
            super::whole_sparsest_failure(regional, n)
                .and_then(|f| f.negative_count())
                .map(|p| subgraph_after(0, p, n))
        };
        assert_eq!(jump(1038, 30_000), Some(subgraph_after(0, 511, 30_000)));
        assert_eq!(jump(4405, 100_000), Some(subgraph_after(0, 1729, 100_000)));
        assert_eq!(jump(4405, 100_000), Some(3), "2.75");
        for (regional, n) in [(1087, 100_000), (147, 30_000), (42, 100_000)] {
            assert_eq!(jump(regional, n), None, "{regional} of {n}: proved");
        }
    }
}
