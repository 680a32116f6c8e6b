//! The factorised structure of the scalar comparison `[D13]`: the scalar Laplacian pattern of
//! the whole graph, of a subgraph, or of the parts of a split, with each pattern's symbolic
//! `LDL^T` analysis (its exact factor size and multiply-adds, for the budget).

use super::{DENSE_EDGES_PER_NODE, DENSE_SUBGRAPH_BETA, SECOND_ORDER_BETA};
use crate::error::{Error, Result};
use crate::linalg::cholesky::symbolic_cholesky_within;
use crate::multiple::MultipleProblem;
use crate::multiple::union_find::UnionFind;
use crate::so3::Rotation;
use faer::sparse::linalg::cholesky::SymbolicCholesky;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// The scalar weighted Laplacian pattern(s) of `problem` (with every diagonal entry), and the
/// symbolic `LDL^T` analysis of each (AMD ordering). Cheap; also tells the caller how large a
/// `3n x 3n` factor would be (`about 9 x` the whole graph's factor).
///
/// One part for the whole graph ([`ScalarAnalysis::new`]) or a subgraph
/// ([`ScalarAnalysis::sparsified`]); several for a split comparison ([`ScalarAnalysis::split`]),
/// in which every edge's kept weight is shared evenly by the parts that hold it and every part
/// proves its share of the condition with its own factorisation.
pub struct ScalarAnalysis {
    pub(super) parts: Vec<ScalarPart>,
    /// Per edge, how many parts hold it (0: dropped, left out of every pattern).
    pub(super) copies: Vec<u32>,
    /// How the graph was reduced: `None` whole (or a subgraph, `edges_per_node > 0`), `Some`
    /// split.
    shape: Option<SplitShape>,
    edges_per_node: f64,
    /// The second-order split `beta` of its comparison (step 2; [`SECOND_ORDER_BETA`], or
    /// [`DENSE_SUBGRAPH_BETA`] for a subgraph of a dense graph).
    pub(super) beta: f64,
    /// Per node, the connected component of the factorised pattern it is in, for a grouped
    /// comparison ([`ScalarAnalysis::grouped`]; empty otherwise: one component, the whole
    /// graph's or a connected subgraph's).
    pub(super) components: Vec<usize>,
}

/// One factorised scalar matrix of a [`ScalarAnalysis`].
pub(super) struct ScalarPart {
    pub(super) symbolic: SymbolicCholesky<usize>,
    pub(super) pattern: SparseColMat<usize, f64>,
    pub(super) diag_pos: Vec<usize>,
    /// The part's edges `(k, position of (i, j), position of (j, i))` in `pattern`'s values,
    /// by increasing edge index `k`.
    pub(super) edges: Vec<(usize, usize, usize)>,
}

/// The sparsified comparisons, sparsest first (the cheapest factor; denser subgraphs are
/// tried when it fails), when the whole graph's scalar factor does not fit the budget: each
/// node keeps this many of its edges (the fractional part: that fraction of the nodes keeps
/// one more), those with the smallest residuals, plus the edges that connect the result
/// ([`ScalarAnalysis::sparsified`]).
pub const SPARSIFIED_EDGES_PER_NODE: [f64; 7] = [2.0, 2.25, 2.5, 2.75, 3.0, 3.5, 4.0];

/// The subgraphs of graphs split into regions ([`subgraph_groups`] above 1): those of
/// [`SPARSIFIED_EDGES_PER_NODE`] and two denser ones, whose factors in regions still fill like
/// smaller graphs (10^5 nodes of 10 edges per node at 0.1 rad in 8 regions: 4 edges per node
/// fail with 13 negative pivots where 8 are needed, 2026-12-03).
pub const GROUPED_EDGES_PER_NODE: [f64; 9] = [2.0, 2.25, 2.5, 2.75, 3.0, 3.5, 4.0, 5.0, 6.0];

/// The subgraphs the scalar comparison's climb tries on `problem`, sparsest first:
/// [`GROUPED_EDGES_PER_NODE`] when its subgraphs are split into regions, else
/// [`SPARSIFIED_EDGES_PER_NODE`].
pub fn subgraph_ladder(problem: &MultipleProblem) -> &'static [f64] {
    if subgraph_groups(problem) > 1 {
        &GROUPED_EDGES_PER_NODE
    } else {
        &SPARSIFIED_EDGES_PER_NODE
    }
}

/// The nodes per region of a large graph's subgraphs ([`subgraph_groups`]).
pub const SUBGRAPH_GROUP_NODES: usize = 7500;

/// The most regions of a subgraph ([`subgraph_groups`]): each adds three columns to the
/// coarse correction's conjugate gradients, whose cost grows with them while the factors'
/// shrinks, and on expanders each cuts more edges (charged). 8 until the deflated components
/// proved a few extra negative pivots (2026-12-05, one run each of `rotavg multiple` on
/// `gen_graph.py expander 100000 20 0.1 100000`: certify 18.0 s in 8 regions, 16.1 s in 7,
/// 13.6-14.4 s in 6, 13.1 s in 5 (1.77 GB), 13.4 s in 4 (2.12 GB); 13 regions `inconclusive`
/// after 113 s: 50 negative pivots at 6 edges per node).
pub const SUBGRAPH_MAX_GROUPS: usize = 6;

/// The regions the subgraphs of a view graph are split into ([`ScalarAnalysis::grouped_subgraph`]):
/// one per [`SUBGRAPH_GROUP_NODES`] nodes, at most [`SUBGRAPH_MAX_GROUPS`]; 1 (no split) below
/// `2 x` that. Measured at the least-squares solutions of random graphs
/// (`gen_graph.py expander`, 2026-12-03): 3x10^4 nodes of 10 edges per node at 0.1 rad, 3
/// edges per node proved in 6.8 s whole and 3.5 s in 2 regions; 4 edges per node in 4
/// regions 1.9 s; 10^5 nodes of 3 edges per node at 0.02 rad, 2 edges per node: the factor
/// 1.15e8 values (11.8 s) whole, 2.1e7 (0.9 s) in 4 regions.
pub fn subgraph_groups(problem: &MultipleProblem) -> usize {
    (problem.num_rotations() / SUBGRAPH_GROUP_NODES).clamp(1, SUBGRAPH_MAX_GROUPS)
}

/// The subgraph of `edges_per_node` in the regions of [`subgraph_groups`]: what the scalar
/// comparison's climb tries ([`ScalarAnalysis::grouped_subgraph`]).
pub fn subgraph(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    edges_per_node: f64,
    max_values: usize,
) -> Result<std::result::Result<ScalarAnalysis, usize>> {
    let groups = subgraph_groups(problem);
    ScalarAnalysis::grouped_subgraph(problem, rotations, edges_per_node, groups, max_values)
}

/// The regions of [`subgraph_groups`] (`None` for one: no split), for
/// [`ScalarAnalysis::in_regions`].
pub(in crate::certify::multiple) fn subgraph_regions(
    problem: &MultipleProblem,
) -> Option<Vec<usize>> {
    let groups = subgraph_groups(problem);
    (groups > 1).then(|| super::partition::partition(problem, groups))
}

/// The shape of a split comparison ([`ScalarAnalysis::split`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct SplitShape {
    /// Number of parts (factorisations), 1 to 64.
    pub parts: usize,
    /// Parts that hold each edge (each with `1 / copies` of its kept weight), 1 to `parts`:
    /// each part then has `copies / parts` of the edges, so `parts / copies` acts as the
    /// number of parts of a split into whole edges, in half steps for `copies = 2`.
    pub copies: usize,
    /// Every node keeps at least this many edges in every part (all of its edges when it has
    /// fewer), lending edges held by its other parts.
    pub min_degree: usize,
}

/// The split shapes tried, in order, after the subgraphs (for dense view graphs, whose
/// subgraphs drop most of the edges; `(parts, copies)`: each part holds `copies / parts` of the edges, from a half to an
/// eighth); for each minimum degree of [`SPLIT_MIN_DEGREES`] the first one that fits runs.
pub const SPLIT_SHAPES: [(usize, usize); 11] = [
    (2, 1),
    (5, 2),
    (3, 1),
    (7, 2),
    (4, 1),
    (9, 2),
    (5, 1),
    (11, 2),
    (6, 1),
    (13, 2),
    (8, 1),
];

/// A split is tried only while each part keeps at least this average degree (sparser random
/// graphs' spectral gaps, `d - 2 sqrt(d - 1)`, vanish at `d = 2`).
pub const MIN_SPLIT_DEGREE: f64 = 3.0;

impl ScalarAnalysis {
    /// Analyse the graph of `problem`, refused before the symbolic analysis when the factor is
    /// predicted to hold more than `max_values` values: `Ok(Err(predicted))`
    /// ([`crate::linalg::cholesky::symbolic_cholesky_within`]).
    pub fn new(
        problem: &MultipleProblem,
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        Self::analyse(problem, 1, |_| 1, max_values)
    }

    /// The whole graph without the edges `left_out` marks (a subgraph that keeps every other
    /// edge: [`ScalarAnalysis::dropped_edges`] counts them), refused like
    /// [`ScalarAnalysis::new`]. For edges that would keep no weight in the comparison (parallel
    /// edges whose mean is a skew block): leaving them out of the pattern charges them as
    /// dropped edges, which costs nothing more, and saves their fill.
    pub(super) fn without(
        problem: &MultipleProblem,
        left_out: &[bool],
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        Self::analyse(problem, 1, |k| u64::from(!left_out[k]), max_values)
    }

    /// The subgraph of the edges within groups of nodes (`group[i]`: node `i`'s), for the
    /// grouped comparison (`[D13]`, "Groups"): its components are proven one negative pivot
    /// each. Refused like [`ScalarAnalysis::new`].
    pub(super) fn grouped(
        problem: &MultipleProblem,
        group: &[usize],
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        let left_out: Vec<bool> = problem
            .edges()
            .iter()
            .map(|e| group[e.i] != group[e.j])
            .collect();
        let analysed = Self::without(problem, &left_out, max_values)?;
        Ok(analysed.map(|a| ScalarAnalysis {
            components: components(problem, &left_out),
            ..a
        }))
    }

    /// The analysis of a **grouped subgraph** (`[D13]`, "Grouped subgraphs"): the nodes in
    /// `groups` connected regions (`scalar/partition.rs`), and in each region the
    /// subgraph of [`ScalarAnalysis::sparsified`] of its own edges; the edges between regions
    /// are dropped (charged), and the grouped comparison proves each region's pencil apart,
    /// the regions' coarse directions by a correction (`groups.rs`). Its factor fills like a
    /// graph `groups` times smaller (3x10^4-node random graph of 10 edges per node at 0.1 rad,
    /// 3 edges per node: 5.4e7 values whole, 1.4e7 in 4 groups). `groups = 1` is the subgraph.
    /// Refused like [`ScalarAnalysis::new`].
    pub fn grouped_subgraph(
        problem: &MultipleProblem,
        rotations: &[Rotation],
        edges_per_node: f64,
        groups: usize,
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        let group = (groups > 1).then(|| super::partition::partition(problem, groups));
        Self::in_regions(
            problem,
            rotations,
            edges_per_node,
            group.as_deref(),
            max_values,
        )
    }

    /// [`ScalarAnalysis::grouped_subgraph`] in the regions `group` (`group[i]`: node `i`'s, as
    /// `scalar/partition.rs` makes them; `None`: the subgraph), made once for a climb's
    /// subgraphs (0.3 s at 10^5 nodes of 10 edges per node).
    pub(in crate::certify::multiple) fn in_regions(
        problem: &MultipleProblem,
        rotations: &[Rotation],
        edges_per_node: f64,
        group: Option<&[usize]>,
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        let Some(group) = group else {
            return Self::sparsified(problem, rotations, edges_per_node, max_values);
        };
        if rotations.len() != problem.num_rotations()
            || group.len() != problem.num_rotations()
            || edges_per_node.is_nan()
            || edges_per_node < 0.0
        {
            return Err(Error::InvalidSettings {
                name: "grouped subgraph".into(),
                reason: "needs one rotation and region per node and edges_per_node >= 0".into(),
            });
        }
        let edges = problem.edges();
        let within = |k: usize| group[edges[k].i] == group[edges[k].j];
        let keep = subgraph_edges_within(problem, rotations, edges_per_node, &within);
        let left_out: Vec<bool> = keep.iter().map(|k| !k).collect();
        let analysed = Self::without(problem, &left_out, max_values)?;
        Ok(analysed.map(|a| ScalarAnalysis {
            components: components(problem, &left_out),
            edges_per_node,
            beta: subgraph_beta(problem),
            ..a
        }))
    }

    /// The regions of a grouped analysis (0 for any other): the number of components its
    /// comparison proves apart.
    pub fn groups(&self) -> usize {
        self.components.iter().max().map_or(0, |m| m + 1)
    }

    /// The negative pivots its factorisation must show: one per component of the pattern.
    pub(super) fn expected_negative_pivots(&self) -> usize {
        self.components.iter().max().map_or(1, |m| m + 1)
    }

    /// The split's shape (`None` for the whole graph or a subgraph).
    pub fn shape(&self) -> Option<SplitShape> {
        self.shape
    }

    /// The second-order split `beta` of the comparison on this analysis (`[D13]` step 2: each
    /// edge compared to second order keeps `alpha_e - beta` of its weight and charges
    /// `k_e^2 / (2 beta)`): `1/2`, or 0.15 for the subgraphs of graphs of at least
    /// [`DENSE_EDGES_PER_NODE`] edges per node ([`ScalarAnalysis::sparsified`]).
    pub fn second_order_beta(&self) -> f64 {
        self.beta
    }

    /// The edges each node keeps in a subgraph ([`ScalarAnalysis::sparsified`]; 0 otherwise).
    pub fn edges_per_node(&self) -> f64 {
        self.edges_per_node
    }

    /// The analysis of a **subgraph** for the sparsified comparison (step 2 with dropped edges,
    /// `paper-notes/certificates.md` `[D13]`): every node keeps its `edges_per_node` incident
    /// edges of smallest residual `||R_a^T R_ab^T R_b - I||_F` at `rotations` (a fractional
    /// part `f`: a fixed fraction `f` of the nodes keeps one more); an edge is kept when either
    /// endpoint keeps it. When that subgraph is disconnected, its components are joined by
    /// the edges of smallest residual between them (Kruskal): every further component would
    /// be one more zero eigenvalue of its Laplacian, i.e. one more negative pivot, and the
    /// proof would fail (a 10^5-node random graph at 0.02 rad: one such edge turned 2 negative
    /// pivots into a proof). Which edges are kept only decides whether the proof succeeds and
    /// how large its factor is, never what it proves. On graphs of at least
    /// [`DENSE_EDGES_PER_NODE`] edges per node the comparison splits the second-order edges with
    /// `beta = 0.15` ([`ScalarAnalysis::second_order_beta`]; valid for any `beta > 0`), which
    /// keeps more of their weight. Refused like [`ScalarAnalysis::new`].
    pub fn sparsified(
        problem: &MultipleProblem,
        rotations: &[Rotation],
        edges_per_node: f64,
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        let n = problem.num_rotations();
        if rotations.len() != n {
            return Err(Error::InvalidSettings {
                name: "rotations".into(),
                reason: "sparsified comparison needs one rotation per node".into(),
            });
        }
        if edges_per_node.is_nan() || edges_per_node < 0.0 {
            return Err(Error::InvalidSettings {
                name: "edges_per_node".into(),
                reason: format!("must be a number >= 0, got {edges_per_node}"),
            });
        }
        let keep = subgraph_edges(problem, rotations, edges_per_node);
        let analysed = Self::analyse(problem, 1, |k| u64::from(keep[k]), max_values)?;
        Ok(analysed.map(|a| ScalarAnalysis {
            edges_per_node,
            beta: subgraph_beta(problem),
            ..a
        }))
    }

    /// The analysis of a **split** comparison (`paper-notes/certificates.md` `[D13]`, split): the
    /// edges are divided among `parts` spanning subgraphs, each node's weight as evenly as the
    /// edges allow (greedy, in a fixed pseudo-random order), and every part proves its share
    /// of the condition with its own factorisation (one after the other: one factor in memory
    /// at a time). A node lends edges to the parts where it has fewer than `min_degree` (all
    /// of its edges when it has fewer; [`SPLIT_MIN_DEGREES`]), and every edge of a node
    /// outside a part's largest connected component is held by every part; an edge held by
    /// several parts is **shared**, each with an even share of its kept weight. Each part is
    /// charged where it is strong (its share of every node's kept weight), so its condition is
    /// about as strong as the whole graph's, while its factor fills like a graph `parts` times
    /// sparser. Which edges go where decides only whether the proof succeeds and how large its
    /// factors are, never what it proves. Refused like [`ScalarAnalysis::new`] when any part's
    /// factor is predicted above `max_values`; `parts` must be 1 to 64.
    ///
    /// ```
    /// use rotavg::certify::multiple::scalar::{ScalarAnalysis, SplitShape};
    /// use rotavg::multiple::synthetic::SyntheticGraph;
    /// let (p, _) = SyntheticGraph { num_rotations: 200, num_edges: 2000, ..Default::default() }
    ///     .generate();
    /// let shape = SplitShape { parts: 4, copies: 1, min_degree: 2 };
    /// let split = ScalarAnalysis::split(&p, shape, usize::MAX)?.expect("within usize::MAX");
    /// let whole = ScalarAnalysis::new(&p, usize::MAX)?.expect("within usize::MAX");
    /// assert_eq!((split.parts(), split.dropped_edges()), (4, 0));
    /// assert!(split.factor_len() < whole.factor_len());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn split(
        problem: &MultipleProblem,
        shape: SplitShape,
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        let SplitShape {
            parts,
            copies,
            min_degree,
        } = shape;
        if parts == 0 || parts > 64 || copies == 0 || copies > parts {
            return Err(Error::InvalidSettings {
                name: "split".into(),
                reason: format!(
                    "a split comparison needs 1 to 64 parts and 1 to parts copies of each edge, \
                     got {parts} parts and {copies} copies"
                ),
            });
        }
        let membership = split_edges(problem, parts, copies, min_degree);
        let analysed = Self::analyse(problem, parts, |k| membership[k], max_values)?;
        Ok(analysed.map(|a| ScalarAnalysis {
            shape: Some(shape),
            ..a
        }))
    }

    /// Analyse `num_parts` parts (at most 64); bit `p` of `member(k)` says whether part `p`
    /// holds edge `k` (none: dropped).
    fn analyse(
        problem: &MultipleProblem,
        num_parts: usize,
        member: impl Fn(usize) -> u64,
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        let m = problem.num_edges();
        let copies: Vec<u32> = (0..m).map(|k| member(k).count_ones()).collect();
        let mut parts = Vec::with_capacity(num_parts);
        for part in 0..num_parts {
            let holds = |k: usize| member(k) >> part & 1 == 1;
            match ScalarPart::analyse(problem, holds, max_values)? {
                Ok(p) => parts.push(p),
                Err(predicted) => return Ok(Err(predicted)),
            }
        }
        Ok(Ok(ScalarAnalysis {
            parts,
            copies,
            shape: None,
            edges_per_node: 0.0,
            beta: SECOND_ORDER_BETA,
            components: Vec::new(),
        }))
    }

    /// `true` when this analysis was made for `problem`'s graph: same size, and in every part
    /// every edge's two entries sit in its own rows and columns of the pattern, and each edge
    /// is held by as many parts as `copies` says (O(m) per part).
    pub(super) fn describes(&self, problem: &MultipleProblem) -> bool {
        let n = problem.num_rotations();
        let edges = problem.edges();
        if self.copies.len() != edges.len() {
            return false;
        }
        let mut held = vec![0u32; edges.len()];
        for part in &self.parts {
            if part.pattern.nrows() != n {
                return false;
            }
            let (cp, ri) = (
                part.pattern.symbolic().col_ptr(),
                part.pattern.symbolic().row_idx(),
            );
            let at = |p: usize, row: usize, col: usize| {
                (cp[col]..cp[col + 1]).contains(&p) && ri[p] == row
            };
            for &(k, p_ij, p_ji) in &part.edges {
                match edges.get(k) {
                    Some(e) if at(p_ij, e.i, e.j) && at(p_ji, e.j, e.i) => held[k] += 1,
                    _ => return false,
                }
            }
        }
        held == self.copies
    }

    /// Edges of the graph analysed (held or dropped).
    pub fn num_edges(&self) -> usize {
        self.copies.len()
    }

    /// Edges left out of every pattern (0 for [`ScalarAnalysis::new`] and
    /// [`ScalarAnalysis::split`]).
    pub fn dropped_edges(&self) -> usize {
        self.copies.iter().filter(|&&c| c == 0).count()
    }

    /// Number of factorisations the comparison runs (1, or the parts of a split).
    pub fn parts(&self) -> usize {
        self.parts.len()
    }

    /// Edges held by more than one part of a split, each part with an even share of its kept
    /// weight (0 otherwise).
    pub fn shared_edges(&self) -> usize {
        self.copies.iter().filter(|&&c| c > 1).count()
    }

    /// Stored values of the largest scalar factor (exact, from the symbolic analysis:
    /// supernodal storage, more than the ordering's prediction). The parts of a split are
    /// factorised one after the other: only one factor is in memory at a time.
    pub fn factor_len(&self) -> usize {
        self.factor_lens().max().unwrap_or(0)
    }

    /// The values the grouped comparison's coarse correction holds besides the factor (0 for
    /// other analyses): `3` columns of length `3n` per region in its conjugate gradients' seven
    /// vectors (right-hand side, iterate, residual, preconditioned residual, direction,
    /// product, the coarse columns).
    pub fn coarse_values(&self) -> usize {
        (3 * self.groups())
            .saturating_mul(3 * self.components.len())
            .saturating_mul(7)
    }

    /// Multiply-adds of all the factorisations ([`crate::linalg::cholesky::factor_multiply_adds`]),
    /// for the time model.
    pub fn factor_multiply_adds(&self) -> f64 {
        self.parts
            .iter()
            .map(|p| crate::linalg::cholesky::factor_multiply_adds(&p.symbolic))
            .sum()
    }

    /// Stored values of each part's scalar factor.
    pub fn factor_lens(&self) -> impl Iterator<Item = usize> + '_ {
        self.parts.iter().map(|p| p.symbolic.len_val())
    }

    /// Bytes of numeric scratch the largest `LDL^T` factorisation allocates besides the factor.
    pub fn scratch_bytes(&self) -> usize {
        self.parts
            .iter()
            .map(|p| crate::linalg::cholesky::ldlt_scratch_bytes(&p.symbolic))
            .max()
            .unwrap_or(0)
    }
}

impl ScalarPart {
    /// The pattern of the edges `holds` selects (every diagonal entry included) and its
    /// symbolic analysis, refused when the factor is predicted above `max_values`.
    fn analyse(
        problem: &MultipleProblem,
        holds: impl Fn(usize) -> bool,
        max_values: usize,
    ) -> Result<std::result::Result<Self, usize>> {
        let n = problem.num_rotations();
        let mut t = Vec::with_capacity(2 * problem.num_edges() + n);
        for (_, e) in problem
            .edges()
            .iter()
            .enumerate()
            .filter(|(k, _)| holds(*k))
        {
            t.push(Triplet::new(e.i, e.j, -e.weight));
            t.push(Triplet::new(e.j, e.i, -e.weight));
        }
        for i in 0..n {
            t.push(Triplet::new(i, i, 0.0));
        }
        let pattern = SparseColMat::try_new_from_triplets(n, n, &t).map_err(|e| Error::Solver {
            message: format!("could not assemble the scalar Laplacian: {e:?}"),
        })?;
        drop(t);
        let cp = pattern.symbolic().col_ptr();
        let ri = pattern.symbolic().row_idx();
        let mut diag_pos = Vec::with_capacity(n);
        for c in 0..n {
            match (cp[c]..cp[c + 1]).find(|&k| ri[k] == c) {
                Some(k) => diag_pos.push(k),
                None => {
                    return Err(Error::Solver {
                        message: "scalar Laplacian lost a diagonal entry".into(),
                    });
                }
            }
        }
        let position = |row: usize, col: usize| {
            ri[cp[col]..cp[col + 1]]
                .binary_search(&row)
                .map(|k| cp[col] + k)
                .map_err(|_| Error::Solver {
                    message: "scalar Laplacian lost an edge entry".into(),
                })
        };
        let edges = problem
            .edges()
            .iter()
            .enumerate()
            .filter(|(k, _)| holds(*k))
            .map(|(k, e)| Ok((k, position(e.i, e.j)?, position(e.j, e.i)?)))
            .collect::<Result<Vec<_>>>()?;
        let symbolic = match symbolic_cholesky_within(pattern.symbolic(), max_values)? {
            Ok(symbolic) => symbolic,
            Err(predicted) => return Ok(Err(predicted)),
        };
        Ok(Ok(ScalarPart {
            symbolic,
            pattern,
            diag_pos,
            edges,
        }))
    }
}

/// The minimum degrees tried for the parts of a split, in order: every node keeps at least
/// this many edges in every part (all of its edges when it has fewer). Sparse random parts are
/// weakest at their chains of nodes of degree 1 and 2. Measured on a 10^5-node graph with 10^6
/// edges at 0.1 rad, 6 parts: without this rule the first part's second eigenvector sat on a
/// pendant path of four such nodes (2 negative pivots); with 2 it proves with factors of 4.5e8
/// values; with 3 too, with 5.9e8 (more edges shared). With 6x10^5 edges (4 parts of average
/// degree 3), 2 fails and 3 is needed.
pub const SPLIT_MIN_DEGREES: [usize; 2] = [2, 3];

/// The edge split of [`ScalarAnalysis::split`], as a bit mask of the parts holding each edge.
/// 1. Each edge to the part that holds the smallest fractions of its two endpoints' weights so
///    far (edges in a fixed pseudo-random order, ties to the lighter part).
/// 2. A node with fewer than `min_degree` edges in a part lends it edges held by its
///    other parts (those of the parts where it has the most), which are then shared.
/// 3. Every edge of a node outside the largest connected component of some part is held by
///    every part (so every part is connected: the view graph is).
pub(super) fn split_edges(
    problem: &MultipleProblem,
    parts: usize,
    copies: usize,
    min_degree: usize,
) -> Vec<u64> {
    let all: u64 = if parts >= 64 {
        u64::MAX
    } else {
        (1u64 << parts) - 1
    };
    if parts <= 1 {
        return vec![all; problem.num_edges()];
    }
    let mut member = balance(problem, parts, copies.clamp(1, parts));
    lend_min_degree(problem, parts, min_degree, &mut member);
    let outside = outside_largest_components(problem, parts, &member);
    for (k, e) in problem.edges().iter().enumerate() {
        if outside[e.i] || outside[e.j] {
            member[k] = all;
        }
    }
    member
}

/// Step 1 of [`split_edges`]: each edge to the `copies` parts that hold the smallest fractions
/// of its endpoints' weights so far (a fixed pseudo-random order: multiplication by an odd
/// constant is a bijection mod 2^64, so sorting by it shuffles the edges reproducibly).
fn balance(problem: &MultipleProblem, parts: usize, copies: usize) -> Vec<u64> {
    let n = problem.num_rotations();
    let edges = problem.edges();
    let mut weight = vec![0.0f64; n];
    for e in edges {
        weight[e.i] += e.weight;
        weight[e.j] += e.weight;
    }
    let mut member = vec![0u64; edges.len()];
    let mut order: Vec<usize> = (0..edges.len()).collect();
    order.sort_by_key(|&k| (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let mut load = vec![0.0f64; n * parts];
    let mut total = vec![0.0f64; parts];
    let mut ranked: Vec<usize> = (0..parts).collect();
    for &k in &order {
        let e = &edges[k];
        let w = e.weight / copies as f64;
        let share = |v: usize, p: usize| (load[v * parts + p] + w) / weight[v];
        let cost = |p: usize| share(e.i, p).max(share(e.j, p)) + share(e.i, p) + share(e.j, p);
        ranked.sort_by(|&p, &q| {
            cost(p)
                .total_cmp(&cost(q))
                .then(total[p].total_cmp(&total[q]))
                .then(p.cmp(&q))
        });
        for &best in &ranked[..copies] {
            load[e.i * parts + best] += w;
            load[e.j * parts + best] += w;
            total[best] += w;
            member[k] |= 1 << best;
        }
    }
    member
}

/// Step 2 of [`split_edges`]: a node with fewer than `min_degree` edges in a part borrows
/// edges it has in other parts (from the part where it has the most), which are then shared.
fn lend_min_degree(problem: &MultipleProblem, parts: usize, min_degree: usize, member: &mut [u64]) {
    let edges = problem.edges();
    let adjacency = problem.adjacency();
    let mut count = vec![0usize; problem.num_rotations() * parts];
    for (k, e) in edges.iter().enumerate() {
        for p in (0..parts).filter(|&p| member[k] >> p & 1 == 1) {
            count[e.i * parts + p] += 1;
            count[e.j * parts + p] += 1;
        }
    }
    for v in 0..problem.num_rotations() {
        for p in 0..parts {
            while count[v * parts + p] < min_degree {
                let lend = adjacency
                    .neighbours(v)
                    .iter()
                    .map(|&(_, k)| k)
                    .filter(|&k| member[k] >> p & 1 == 0)
                    .max_by_key(|&k| {
                        let most = (0..parts)
                            .filter(|&q| member[k] >> q & 1 == 1)
                            .map(|q| count[v * parts + q])
                            .max()
                            .unwrap_or(0);
                        (most, std::cmp::Reverse(k))
                    });
                let Some(k) = lend else { break };
                member[k] |= 1 << p;
                count[edges[k].i * parts + p] += 1;
                count[edges[k].j * parts + p] += 1;
            }
        }
    }
}

/// Step 3 of [`split_edges`]: the nodes outside the largest connected component of some part
/// (their edges are then held by every part, so every part is connected: the view graph is).
fn outside_largest_components(
    problem: &MultipleProblem,
    parts: usize,
    member: &[u64],
) -> Vec<bool> {
    let n = problem.num_rotations();
    let mut outside = vec![false; n];
    for p in 0..parts {
        let mut uf = UnionFind::new(n);
        for (k, e) in problem.edges().iter().enumerate() {
            if member[k] >> p & 1 == 1 {
                uf.union(e.i, e.j);
            }
        }
        let root: Vec<usize> = (0..n).map(|v| uf.find(v)).collect();
        let mut size = vec![0usize; n];
        for &r in &root {
            size[r] += 1;
        }
        let largest = (0..n).max_by_key(|&v| size[v]).unwrap_or(0);
        for (v, &r) in root.iter().enumerate() {
            if r != largest {
                outside[v] = true;
            }
        }
    }
    outside
}

/// Whether `problem` has at least [`DENSE_EDGES_PER_NODE`] edges per node.
pub(super) fn is_dense(problem: &MultipleProblem) -> bool {
    problem.num_edges() as f64 >= DENSE_EDGES_PER_NODE * problem.num_rotations() as f64
}

/// The second-order split `beta` of `problem`'s subgraphs: [`DENSE_SUBGRAPH_BETA`] on dense
/// graphs ([`is_dense`]), else [`SECOND_ORDER_BETA`].
fn subgraph_beta(problem: &MultipleProblem) -> f64 {
    if is_dense(problem) {
        DENSE_SUBGRAPH_BETA
    } else {
        SECOND_ORDER_BETA
    }
}

/// The components of the edges not `left_out`, numbered from 0 in the order of their first node.
pub(in crate::certify::multiple) fn components(
    problem: &MultipleProblem,
    left_out: &[bool],
) -> Vec<usize> {
    let n = problem.num_rotations();
    let mut union = UnionFind::new(n);
    for (e, out) in problem.edges().iter().zip(left_out) {
        if !out {
            union.union(e.i, e.j);
        }
    }
    let mut id = vec![usize::MAX; n];
    let mut next = 0;
    (0..n)
        .map(|i| {
            let root = union.find(i);
            if id[root] == usize::MAX {
                id[root] = next;
                next += 1;
            }
            id[root]
        })
        .collect()
}

/// Frobenius norm.
pub(in crate::certify::multiple) fn fro(m: &Matrix3<f64>) -> f64 {
    m.iter().map(|v| v * v).sum::<f64>().sqrt()
}

/// The edges of the subgraph of [`ScalarAnalysis::sparsified`] (also the block comparison's,
/// `[A15]`): every node keeps its `edges_per_node` (`>= 0`, fractional part: a fixed fraction of
/// the nodes keeps one more) incident edges of smallest residual `||R_a^T R_ab^T R_b - I||_F`,
/// an edge is kept when either endpoint keeps it, and the components are joined by the dropped
/// edges of smallest residual between them. `rotations` has one rotation per node.
pub(in crate::certify::multiple) fn subgraph_edges(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    edges_per_node: f64,
) -> Vec<bool> {
    subgraph_edges_within(problem, rotations, edges_per_node, &|_| true)
}

/// [`subgraph_edges`] among the edges `k` with `within(k)` only (the others never kept, nor
/// used to join components).
fn subgraph_edges_within(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    edges_per_node: f64,
    within: &dyn Fn(usize) -> bool,
) -> Vec<bool> {
    let n = problem.num_rotations();
    let residual: Vec<f64> = problem
        .edges()
        .iter()
        .map(|e| {
            let (ra, rb) = (rotations[e.i].matrix(), rotations[e.j].matrix());
            let pm = ra.transpose() * (e.rotation.matrix().transpose() * rb);
            fro(&(pm - Matrix3::identity()))
        })
        .collect();
    let adjacency = problem.adjacency();
    let mut keep = vec![false; problem.num_edges()];
    let whole = edges_per_node.floor() as usize;
    let fraction = edges_per_node - edges_per_node.floor();
    let mut incident = Vec::new();
    for v in 0..n {
        incident.clear();
        incident.extend(
            adjacency
                .neighbours(v)
                .iter()
                .map(|&(_, k)| k)
                .filter(|&k| within(k)),
        );
        incident.sort_by(|&a, &b| residual[a].total_cmp(&residual[b]).then(a.cmp(&b)));
        // a fixed pseudo-random subset of the nodes (Knuth's multiplicative hash)
        let extra = ((v as u64).wrapping_mul(2_654_435_761) % 1000) as f64 / 1000.0 < fraction;
        for &k in incident.iter().take(whole + usize::from(extra)) {
            keep[k] = true;
        }
    }
    connect_within(problem, &residual, &mut keep, within);
    keep
}

/// Join the components of the kept edges with the dropped edges `k` with `within(k)` of
/// smallest `residual` between them (Kruskal's rule on the components), so that a connected
/// graph's (or region's) subgraph is connected.
pub(in crate::certify::multiple) fn connect_within(
    problem: &MultipleProblem,
    residual: &[f64],
    keep: &mut [bool],
    within: &dyn Fn(usize) -> bool,
) {
    let mut components = UnionFind::new(problem.num_rotations());
    for (e, _) in problem.edges().iter().zip(keep.iter()).filter(|(_, k)| **k) {
        components.union(e.i, e.j);
    }
    let mut dropped: Vec<usize> = (0..keep.len()).filter(|&k| !keep[k] && within(k)).collect();
    dropped.sort_by(|&a, &b| residual[a].total_cmp(&residual[b]).then(a.cmp(&b)));
    for k in dropped {
        let e = &problem.edges()[k];
        if components.find(e.i) != components.find(e.j) {
            components.union(e.i, e.j);
            keep[k] = true;
        }
    }
}
