//! The block comparison `[A15]` as one rung of the verification ladder: block Laplacians of
//! subgraphs chosen by strength and topped up where weak ([`BLOCK_SHAPES`], sparsest first), one
//! per attempt, each planned with its own prediction; the first that proves ends the rung.
//! Anisotropic problems only (the scalar comparison `[D13]` is the isotropic form).

use super::outcome::BlockFailure;
use super::{BlockAnalysis, BlockShape, block_comparison_with};
use crate::certify::log::{Outcome, Prediction, Refusal};
use crate::certify::multiple::check::{Check, counted_prediction};
use crate::certify::multiple::scalar::ScalarAnalysis;
use crate::certify::multiple::scalar::failure_text;
use crate::certify::multiple::scalar::rungs::skipped_subgraphs;
use crate::certify::multiple::verified::VerifiedBound;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Plan, Rung};
use crate::certify::settings::CertifySettings;
use crate::error::Result;
use crate::so3::Rotation;
use std::time::Instant;

/// The subgraphs tried, sparsest first: each node keeps `edges_per_node` of its edges, chosen
/// by strength, and the nodes weak against their charges more, up to the ratio `top_up`
/// ([`BlockShape`]). Measured on the realistic two-view generator (10^4 cameras, 10^5 edges,
/// 2026-12-02, `block_sweep -- 10000 100000 K [outliers robust]` with the top-up): without
/// it, 3 and 4 edges per node leave 35 and 0 negative pivots (1.26e8 and 1.93e8 factor
/// values), and the robust solve's inlier graph needs 4.5 (2.25e8; 4 leave 4 pivots); 2 edges
/// per node topped up to 14 prove both (1.37e8 and 1.29e8 values; to 12: 1.21e8 and 5 pivots
/// on the inlier graph). A sparser view graph (3000 cameras, 12,000 edges) needs 3 topped up
/// to 16 (2 to 16: 19 pivots).
pub const BLOCK_SHAPES: [BlockShape; 4] = [
    BlockShape {
        edges_per_node: 2.0,
        top_up: 14.0,
    },
    BlockShape {
        edges_per_node: 3.0,
        top_up: 16.0,
    },
    BlockShape {
        edges_per_node: 4.0,
        top_up: 24.0,
    },
    BlockShape {
        edges_per_node: 6.0,
        top_up: 32.0,
    },
];

/// The nodes per region of a large graph's block subgraphs ([`block_groups`]).
pub const BLOCK_GROUP_NODES: usize = 1000;

/// The most regions of a block subgraph. Measured on the realistic two-view class (random view
/// graphs of 10 edges per node, 2026-12-04, `block_sweep -- N 10N 2:14 regions=K`, each
/// region's block bordered and deflated, `[A15]` "Regions"): at 10^4 cameras 3 regions prove
/// the least-squares solution in 3.7-4.3 s (5.2e7 factor values; 2 regions 4.7 s, 7.8e7; the
/// pencil form of 2026-12-03 with 2 regions 5.8 s) and the robust solve's inlier graph in
/// 3.9-4.3 s (2 regions, pencil: 4.4 s), 4 regions need 31 deflated directions in one region
/// (7.2 s with them) and 5 more; at 2x10^4 cameras 3 regions prove in 21 s (2.05e8 values;
/// the pencil's 2 regions took 35 s) and 4 leave 41 negative pivots in one region; at 5000
/// cameras 3 regions 1.2 s against 2.1 s whole, at 3000 0.51 s against 0.80 s, at 2000 2
/// regions 0.33 s against 0.41 s. A random graph has no small separators, so more regions drop
/// more of each node's strong edges.
pub const BLOCK_MAX_GROUPS: usize = 3;

/// The fewest edges per node of a graph whose block subgraphs are split into regions. Measured
/// on the realistic two-view class at 10^4 cameras (2026-12-03, `block_sweep -- 10000 M 2:14
/// [regions=2]`): with 10 edges per node 2 regions prove as the whole subgraph does, and so on
/// the robust solve's inlier graph of 8.99 edges per node; with 8 they leave 7 negative pivots
/// too many (whole: 1), with 6 86 (whole: 5), with 4 about 750 (whole: 152). A sparse graph's
/// node keeps few edges within its region.
pub const BLOCK_REGION_MIN_EDGES_PER_NODE: f64 = 8.5;

/// The largest fraction of the whole graph's `3n` factor a subgraph's factor may have to be
/// tried (both as their minimum-degree orderings count them: the whole graph's from its scalar
/// ordering, in `3 x 3` blocks). The comparison proves less
/// than a factorisation of `S` itself, so a subgraph nearly as large as the graph only costs
/// time before the grounded bound. Measured on the realistic two-view class at 10^4 cameras
/// and 4 edges per node (2026-12-03, `anisotropic_ladder -- 10000 40000`): the subgraphs of 2
/// edges per node topped up to 14 (predicted 5.7 s), 4 to 24 (14.2 s) and 6 to 32 (15.1 s)
/// failed with 155, 4 and 4 negative pivots in 5.8, 19.7 and 15.1 s before the grounded bound
/// proved in 14.5 s (one factorisation of about 1.8e8 values).
pub const BLOCK_WHOLE_FRACTION: f64 = 0.5;
/// Fewer edges per node than this make a graph sparse for the block comparison: its first
/// subgraph's chance is then 1/4 and the `3n` rungs do not wait for it.
/// Measured on the realistic two-view class: at 4 edges per node its subgraphs failed at
/// 10^4 cameras (155 negative pivots at 2 edges per node topped up to 14, 4 at 4 to 24 and 6
/// to 32; `anisotropic_ladder -- 10000 40000`, 2026-12-03) and at 1000 (the suite's
/// `block_comparison` test), on the rig of 10^4 frames with about 3 edges per image (1243 in
/// the sensors' regions), and the grounded bound `[D15]` proved; at 9-10 edges per node they
/// prove (10^4 cameras: 4.2 s against a grounded bound predicted past 20 s).
pub const BLOCK_SPARSE_EDGES_PER_NODE: f64 = 5.0;

/// The chance a sparse graph's first subgraph is given ([`BlockFamily`]): the ladder then runs
/// the grounded bound first when it is predicted below `1 / SPARSE_CHANCE` times the subgraph.
const SPARSE_CHANCE: f64 = 0.25;

/// Fewer than [`BLOCK_SPARSE_EDGES_PER_NODE`] edges per node.
fn sparse(problem: &crate::multiple::MultipleProblem) -> bool {
    (problem.num_edges() as f64) < BLOCK_SPARSE_EDGES_PER_NODE * problem.num_rotations() as f64
}

/// The regions the block comparison's subgraphs of `problem` are split into first
/// ([`BlockAnalysis::grouped`]): one per [`BLOCK_GROUP_NODES`] nodes, at most
/// [`BLOCK_MAX_GROUPS`]; 1 (no split) below twice that or below
/// [`BLOCK_REGION_MIN_EDGES_PER_NODE`].
pub fn block_groups(problem: &crate::multiple::MultipleProblem) -> usize {
    let n = problem.num_rotations();
    if (problem.num_edges() as f64) < BLOCK_REGION_MIN_EDGES_PER_NODE * n as f64 {
        return 1;
    }
    (n / BLOCK_GROUP_NODES).clamp(1, BLOCK_MAX_GROUPS)
}

/// The coarse correction's work per edge and column (its conjugate gradients: products with
/// `M` and projections), as the scalar comparison's.
const SECONDS_PER_EDGE_COLUMN: f64 = 4e-7;

/// The `index`-th subgraph the rung tries on `problem` and its regions: the shapes of
/// [`BLOCK_SHAPES`] in regions where [`block_groups`] splits the graph, then the same shapes
/// whole; `None` past the last.
fn attempt(
    problem: &crate::multiple::MultipleProblem,
    index: usize,
) -> Option<(BlockShape, usize)> {
    let groups = block_groups(problem);
    let shapes = BLOCK_SHAPES.len();
    match (groups > 1, index) {
        (true, i) if i < shapes => Some((BLOCK_SHAPES[i], groups)),
        (true, i) => BLOCK_SHAPES.get(i - shapes).map(|&s| (s, 1)),
        (false, i) => BLOCK_SHAPES.get(i).map(|&s| (s, 1)),
    }
}

/// The index after the family (in regions, or whole) that `index` belongs to.
fn family_end(problem: &crate::multiple::MultipleProblem, index: usize) -> usize {
    let shapes = BLOCK_SHAPES.len();
    if block_groups(problem) > 1 && index < shapes {
        shapes
    } else {
        usize::MAX
    }
}

/// The comparison's work besides the factorisation, per edge (the `6 x 6` checks, the
/// double-double gauge terms and the choice of the subgraph): measured 2.3e-5 s on the
/// 10^4-camera case above (0.23 s of choice and analysis, 0.4 s of edge checks for 10^5 edges).
pub const SECONDS_PER_EDGE: f64 = 2.3e-5;

/// The block comparison's subgraphs, one per attempt: the ladder plans again after each, so a
/// cheaper rung (the grounded bound of `S` itself) overtakes the next, denser subgraph once the
/// failures make it unlikely to prove.
#[derive(Default)]
pub(in crate::certify::multiple) struct BlockFamily {
    /// The next [`attempt`] to analyse.
    next: usize,
    /// The subgraph the next attempt runs, analysed by the plan.
    pending: Option<BlockAnalysis>,
    /// The negative pivots of the failures so far.
    failures: Vec<usize>,
    /// The last plan (refusals are kept: a refused rung is dropped).
    planned: Option<std::result::Result<Prediction, Refusal>>,
    done: bool,
    /// An attempt was made (the `3n` rungs wait only for the first, [`Check::block_runs_first`]).
    attempted: bool,
    /// The whole graph's `3n` factor, predicted (values; [`whole_factor`]); infinite when the
    /// grounded bound is off the ladder ([`BLOCK_WHOLE_FRACTION`] does not apply).
    whole_values: Option<f64>,
}

impl<'a> Rung<Check<'a>> for BlockFamily {
    fn proof(&self) -> Proof {
        Proof::BlockComparison
    }

    fn plan(&mut self, cx: &Check<'a>) -> Result<Plan> {
        // scalar weights: the scalar comparison is the isotropic form (not logged: every
        // isotropic ladder would carry the line)
        if self.done || !cx.problem.is_anisotropic() {
            return Ok(Plan::Done);
        }
        if self.planned.is_none() {
            self.planned = Some(self.predict(cx)?);
        }
        let plan = match self.planned.clone() {
            // no denser subgraph fits after a failure: the rung is done (its refusal was not
            // the reason it did not prove)
            Some(Err(_)) if !self.failures.is_empty() => Plan::Done,
            planned => cx.plan_from(planned),
        };
        // on sparse graphs the `3n` rungs plan beside it (their order decides)
        if matches!(plan, Plan::Run(_)) && !self.attempted && !sparse(cx.problem) {
            cx.block_runs_first();
        }
        Ok(plan)
    }

    fn attempt(&mut self, cx: &mut Check<'a>) -> Result<Found> {
        self.planned = None;
        self.attempted = true;
        let (Some(a), Some(rotations)) = (self.pending.take(), cx.rotations) else {
            self.done = true;
            return Ok(Found::logged(Outcome::Failed {
                reason: "no subgraph to try".into(),
            }));
        };
        let predicted = predict(cx.settings, &a).ok();
        let target = 0.5 * cx.gap / cx.dim().max(1) as f64;
        Ok(Found::logged(
            match run(cx, &a, rotations, target, predicted)? {
                Ok(b) => {
                    self.done = true;
                    cx.offer(b)
                }
                Err(failure) => {
                    match failure {
                        Some(BlockFailure::Inertia { negative_pivots }) => {
                            let end = family_end(cx.problem, self.next.saturating_sub(1));
                            self.next = (self.next + skipped_subgraphs(negative_pivots)).min(end);
                            self.failures.push(negative_pivots);
                        }
                        // not a question of the subgraph: the denser ones fail alike
                        _ => self.done = true,
                    }
                    Outcome::Failed {
                        reason: format!("{}: did not prove", shape_of(&a)),
                    }
                }
            },
        ))
    }
}

impl BlockFamily {
    /// The next subgraph's prediction (its chance from the failures so far), or why the rung
    /// does not apply.
    fn predict(&mut self, cx: &Check<'_>) -> Result<std::result::Result<Prediction, Refusal>> {
        let Some(rotations) = cx.rotations else {
            return Ok(Err(Refusal::NotApplicable {
                reason: "the estimate's rotations are not known".into(),
            }));
        };
        if self.next == 0 && self.whole_values.is_none() {
            match whole_factor(cx)? {
                // the fraction's reason is the grounded bound (off the ladder: no limit)
                Ok(values) if cx.settings.dual.proofs.contains(&Proof::Grounded) => {
                    self.whole_values = Some(values)
                }
                Ok(_) => self.whole_values = Some(f64::INFINITY),
                Err(refusal) => return Ok(Err(refusal)),
            }
        }
        // the choice of a subgraph and its analysis are work before any prediction: refused
        // when even the per-edge work would pass the time left
        let work = SECONDS_PER_EDGE * cx.problem.num_edges() as f64;
        if let Some(left) = cx.deadline.left()
            && work > left
        {
            return Ok(Err(Refusal::OverBudget {
                reason: format!(
                    "its per-edge work alone is predicted at {work:.1} s, {left:.1} s are left"
                ),
            }));
        }
        self.pending = self.next_analysis(cx, rotations)?;
        Ok(match &self.pending {
            Some(a) => match self.near_whole(a) {
                Some(refusal) => {
                    self.pending = None;
                    Err(refusal)
                }
                None => predict(cx.settings, a).map(|p| p.with_success(self.chance(cx.problem))),
            },
            None => Err(Refusal::OverBudget {
                reason: "no subgraph's block factor fits the budget".into(),
            }),
        })
    }

    /// The refusal of a subgraph whose factor is more than [`BLOCK_WHOLE_FRACTION`] of the
    /// whole graph's: the grounded bound factorises `S` itself in about the same time and
    /// proves where the comparison's sufficient condition may not (denser subgraphs are larger
    /// still).
    fn near_whole(&self, a: &BlockAnalysis) -> Option<Refusal> {
        let whole = self.whole_values?;
        let values = a.counted_values() as f64;
        (values > BLOCK_WHOLE_FRACTION * whole).then(|| Refusal::NotApplicable {
            reason: format!(
                "{}: its factor ({values:.1e} values) is more than {BLOCK_WHOLE_FRACTION} of the \
                 whole graph's (about {whole:.1e}), which the grounded bound factorises",
                shape_of(a)
            ),
        })
    }

    /// The chance that the next subgraph proves, from the failures so far: before any,
    /// [`SPARSE_CHANCE`] on a sparse graph ([`sparse`]) and 1 otherwise; after a near miss (at
    /// most 16 negative pivots: the next subgraph is not skipped) 1/2, and 1/10 when the last
    /// two near misses had the same count (a node the comparison cannot cover, not the
    /// subgraph's connectivity: measured on a 3000-camera graph, 4 negative pivots at 5, 6 and 8
    /// edges per node).
    fn chance(&self, problem: &crate::multiple::MultipleProblem) -> f64 {
        match self.failures.as_slice() {
            [.., a, b] if a == b && *b <= 16 => 0.1,
            [.., b] if *b <= 16 => 0.5,
            [] if sparse(problem) => SPARSE_CHANCE,
            _ => 1.0,
        }
    }

    /// The next subgraph that fits the budget, or `None`.
    fn next_analysis(
        &mut self,
        cx: &Check<'_>,
        rotations: &[Rotation],
    ) -> Result<Option<BlockAnalysis>> {
        let max_values = cx
            .settings
            .budget
            .max_factor_values(3 * cx.problem.num_rotations());
        while let Some((shape, groups)) = attempt(cx.problem, self.next) {
            let end = family_end(cx.problem, self.next);
            self.next += 1;
            match BlockAnalysis::grouped(cx.problem, rotations, Some(shape), groups, max_values)? {
                Ok(a) if predict(cx.settings, &a).is_ok() => return Ok(Some(a)),
                // denser subgraphs have larger factors
                _ => self.next = end,
            }
        }
        Ok(None)
    }
}

/// The whole graph's `3n` factor, predicted as 9 times its scalar factor (the same
/// elimination in `3 x 3` blocks, whose ordering costs a ninth; the minimum-degree count, no
/// symbolic analysis); or the refusal of the rung when it is at most
/// `DualSettings::block_comparison_above` values: certainly so when even a dense lower
/// triangle of `n` blocks is (no ordering needed: graphs of up to about 3300 nodes at the
/// default, the shared SLAM files among them).
fn whole_factor(cx: &Check<'_>) -> Result<std::result::Result<f64, Refusal>> {
    let above = cx.settings.dual.block_comparison_above;
    let n = cx.problem.num_rotations() as f64;
    let values = if 4.5 * n * (n + 1.0) <= above as f64 {
        4.5 * n * (n + 1.0)
    } else {
        match ScalarAnalysis::new(cx.problem, above / 9)? {
            Ok(a) => 9.0 * a.factor_len() as f64,
            // the count of the quotient's ordering: 9 values per block below the diagonal, 6
            // per diagonal block
            Err(predicted) => return Ok(Ok(9.0 * predicted as f64 - 3.0 * n)),
        }
    };
    Ok(Err(Refusal::NotApplicable {
        reason: format!(
            "the whole graph's 3n factor (at most about {values:.1e} values) is small enough to \
             factorise directly"
        ),
    }))
}

/// The budget's verdict on one subgraph's factorisation, and its predicted time.
fn predict(
    settings: &CertifySettings,
    a: &BlockAnalysis,
) -> std::result::Result<Prediction, Refusal> {
    // in regions the factorisations run one after another: the largest is the memory's
    let (mut values, mut largest) = (0usize, a.coarse_values());
    for (len, scratch, _) in a.factorisations() {
        let one = len.saturating_add(scratch.div_ceil(8));
        values = values.saturating_add(one);
        largest = largest.max(one);
    }
    let columns = 3 * a.groups();
    let other =
        (SECONDS_PER_EDGE + SECONDS_PER_EDGE_COLUMN * columns as f64) * a.num_edges() as f64;
    counted_prediction(
        settings,
        largest,
        values,
        a.factor_multiply_adds(),
        a.factor_len(),
        other,
    )
}

/// Run one subgraph: a bound when it proves `lambda_min(S) >= -target`, else why not (`None`
/// when its cross terms were too large); logged either way.
fn run(
    cx: &Check<'_>,
    a: &BlockAnalysis,
    rotations: &[Rotation],
    target: f64,
    predicted: Option<Prediction>,
) -> Result<std::result::Result<VerifiedBound, Option<BlockFailure>>> {
    let since = Instant::now();
    cx.notes().factorizations += 1;
    let until = (target, cx.deadline.instant());
    let gauge = cx.gauge_terms(rotations);
    let points = (rotations, cx.lambdas);
    let outcome = block_comparison_with(cx.problem, a, points, until, gauge)?;
    let proof = match outcome {
        Ok(p) if p.verified_min_eigenvalue >= -target => p,
        other => {
            let failed = other.as_ref().err().cloned();
            let mu = other.map(|p| p.verified_min_eigenvalue);
            let reason = format!(
                "{}: {}",
                shape_of(a),
                failure_text(target, mu, a.expected_negative_pivots())
            );
            let outcome = Outcome::Failed { reason };
            cx.log(Proof::BlockComparison, predicted, outcome, since);
            return Ok(Err(failed));
        }
    };
    let mut b = cx.bound_from_mu(proof.verified_min_eigenvalue, Proof::BlockComparison);
    b.fp_margin = proof.backward_error;
    b.factorizations = 1;
    b.factor_nonzeros = proof.factor_nonzeros;
    b.block_comparison = Some(proof);
    let outcome = cx.proved(&b);
    cx.log_with_note(
        Proof::BlockComparison,
        predicted,
        outcome,
        since,
        shape_of(a),
    );
    Ok(Ok(b))
}

/// The subgraph in words.
fn shape_of(a: &BlockAnalysis) -> String {
    match (a.shape(), a.regions(), a.groups()) {
        (Some(shape), 0, _) => shape.to_string(),
        (Some(shape), r, k) if r == k => format!("{shape} in {r} regions"),
        (Some(shape), r, k) => format!("{shape} in {r} regions ({k} components)"),
        (None, _, _) => "whole graph".into(),
    }
}
