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
//!    `w (lambda_min(A_e) - beta)` (`beta = 1/2`) and `delta_i` the charges
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
//! When the residuals are too large for step 4 (noisy data, low algebraic connectivity) the
//! factorisation shows more than one negative pivot and [`scalar_comparison`] returns `None`:
//! the caller falls back to the factorisation of `S` itself. The bound is never weaker than
//! what it proves, and it is never used when it cannot be completed.

use crate::error::{Error, Result};
use crate::linalg::cholesky::{UNIT_ROUNDOFF, gamma, symbolic_cholesky_within};
use crate::linalg::compensated::Accumulator;
use crate::linalg::ldlt::{LdltFailure, ldlt_inertia};
use crate::multiple::MultipleProblem;
use crate::multiple::union_find::UnionFind;
use crate::so3::Rotation;
use faer::sparse::linalg::cholesky::SymbolicCholesky;
use faer::sparse::{SparseColMat, Triplet};
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};

/// The split `beta` of the second-order edge comparison (step 2): each edge keeps
/// `alpha_e - beta` of its weight and charges `k_e^2 / (2 beta)` to its two nodes. `1/2`
/// maximises `beta (1 - beta)`, which makes the condition exact on a cycle with equal residuals
/// (`paper-notes/certificates.md` [D13]).
const SECOND_ORDER_BETA: f64 = 0.5;

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
}

fn one_part() -> usize {
    1
}

/// Why a scalar comparison did not prove anything (the caller falls back to the `3n` factor).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "reason")]
pub enum ScalarFailure {
    /// `L - diag(delta)` has more than one negative pivot: the residuals are too large relative
    /// to the graph's connectivity for this sufficient condition.
    Inertia {
        /// Negative pivots counted.
        negative_pivots: usize,
    },
    /// A zero or non-finite pivot, or a non-finite bound.
    Numerical,
    /// The factorisation's backward error exceeded the headroom `h`.
    BackwardError,
    /// The estimate's rotations are too far from orthogonal.
    NotOrthogonal,
}

/// The scalar weighted Laplacian pattern(s) of `problem` (with every diagonal entry), and the
/// symbolic `LDL^T` analysis of each (AMD ordering). Cheap; also tells the caller how large a
/// `3n x 3n` factor would be (`about 9 x` the whole graph's factor).
///
/// One part for the whole graph ([`ScalarAnalysis::new`]) or a subgraph
/// ([`ScalarAnalysis::sparsified`]); several for a split comparison ([`ScalarAnalysis::split`]),
/// in which every edge's kept weight is shared evenly by the parts that hold it and every part
/// proves its share of the condition with its own factorisation.
pub struct ScalarAnalysis {
    parts: Vec<ScalarPart>,
    /// Per edge, how many parts hold it (0: dropped, left out of every pattern).
    copies: Vec<u32>,
}

/// One factorised scalar matrix of a [`ScalarAnalysis`].
struct ScalarPart {
    symbolic: SymbolicCholesky<usize>,
    pattern: SparseColMat<usize, f64>,
    diag_pos: Vec<usize>,
    /// The part's edges `(k, position of (i, j), position of (j, i))` in `pattern`'s values,
    /// by increasing edge index `k`.
    edges: Vec<(usize, usize, usize)>,
}

/// The sparsified comparisons tried, in order, when the whole graph's scalar factor does not
/// fit the budget: each node keeps this many of its edges (the fractional part: that fraction
/// of the nodes keeps one more), those with the smallest residuals ([`ScalarAnalysis::sparsified`]).
pub const SPARSIFIED_EDGES_PER_NODE: [f64; 5] = [4.0, 3.5, 3.0, 2.75, 2.5];

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

/// The split shapes tried, in order, when a subgraph would drop more than half of the edges
/// (`(parts, copies)`: each part holds `copies / parts` of the edges, from a half to an
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

    /// The analysis of a **subgraph** for the sparsified comparison (step 2 with dropped edges,
    /// `paper-notes/certificates.md` `[D13]`): every node keeps its `edges_per_node` incident
    /// edges of smallest residual `||R_a^T R_ab^T R_b - I||_F` at `rotations` (a fractional
    /// part `f`: a fixed fraction `f` of the nodes keeps one more); an edge is kept when either
    /// endpoint keeps it. Which edges are kept only decides whether the proof succeeds and how
    /// large its factor is, never what it proves. Refused like [`ScalarAnalysis::new`].
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
            incident.extend(adjacency.neighbours(v).iter().map(|&(_, k)| k));
            incident.sort_by(|&a, &b| residual[a].total_cmp(&residual[b]).then(a.cmp(&b)));
            // a fixed pseudo-random subset of the nodes (Knuth's multiplicative hash)
            let extra = ((v as u64).wrapping_mul(2_654_435_761) % 1000) as f64 / 1000.0 < fraction;
            for &k in incident.iter().take(whole + usize::from(extra)) {
                keep[k] = true;
            }
        }
        Self::analyse(problem, 1, |k| u64::from(keep[k]), max_values)
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
        Self::analyse(problem, parts, |k| membership[k], max_values)
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
        Ok(Ok(ScalarAnalysis { parts, copies }))
    }

    /// `true` when this analysis was made for `problem`'s graph: same size, and in every part
    /// every edge's two entries sit in its own rows and columns of the pattern, and each edge
    /// is held by as many parts as `copies` says (O(m) per part).
    fn describes(&self, problem: &MultipleProblem) -> bool {
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
            .map(|p| {
                p.symbolic
                    .factorize_numeric_ldlt_scratch::<f64>(
                        crate::linalg::factor_parallelism(p.symbolic.len_val()),
                        Default::default(),
                    )
                    .size_bytes()
            })
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
fn split_edges(
    problem: &MultipleProblem,
    parts: usize,
    copies: usize,
    min_degree: usize,
) -> Vec<u64> {
    let n = problem.num_rotations();
    let edges = problem.edges();
    let m = edges.len();
    let all: u64 = if parts >= 64 {
        u64::MAX
    } else {
        (1u64 << parts) - 1
    };
    if parts <= 1 {
        return vec![all; m];
    }
    let adjacency = problem.adjacency();
    let mut weight = vec![0.0f64; n];
    for e in edges {
        weight[e.i] += e.weight;
        weight[e.j] += e.weight;
    }
    // 1. greedy balance, in a fixed pseudo-random order (multiplication by an odd constant is
    // a bijection mod 2^64; sorting by it shuffles the edges reproducibly)
    let mut member = vec![0u64; m];
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by_key(|&k| (k as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
    let mut load = vec![0.0f64; n * parts];
    let mut total = vec![0.0f64; parts];
    let copies = copies.clamp(1, parts);
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
    // 2. at least min_degree edges per node and part
    let mut count = vec![0usize; n * parts];
    for (k, e) in edges.iter().enumerate() {
        for p in (0..parts).filter(|&p| member[k] >> p & 1 == 1) {
            count[e.i * parts + p] += 1;
            count[e.j * parts + p] += 1;
        }
    }
    let mut incident = Vec::new();
    for v in 0..n {
        for p in 0..parts {
            while count[v * parts + p] < min_degree {
                // an edge of v that part p lacks, from the part where v has the most edges
                incident.clear();
                incident.extend(
                    adjacency
                        .neighbours(v)
                        .iter()
                        .map(|&(_, k)| k)
                        .filter(|&k| member[k] >> p & 1 == 0),
                );
                let lend = incident.iter().copied().max_by_key(|&k| {
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
    // 3. every part connected
    let mut outside = vec![false; n];
    for p in 0..parts {
        let mut uf = UnionFind::new(n);
        for (k, e) in edges.iter().enumerate() {
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
    for (k, e) in edges.iter().enumerate() {
        if outside[e.i] || outside[e.j] {
            member[k] = all;
        }
    }
    member
}

/// Frobenius norm.
fn fro(m: &Matrix3<f64>) -> f64 {
    m.iter().map(|v| v * v).sum::<f64>().sqrt()
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
    let u = UNIT_ROUNDOFF;
    // -- step 1: orthogonality defects t_i >= ||R_i^T R_i - I||_F (entries of R^T R are inner
    // products of 3 terms bounded by ~1: error <= gamma_3 * 3 + u per entry; 1e-14 covers 3x that)
    let mut t = Vec::with_capacity(n);
    for r in rotations {
        let m = r.matrix();
        let g = m.transpose() * m - Matrix3::identity();
        let ti = fro(&g) * (1.0 + 4.0 * u) + 1e-14;
        if ti.is_nan() || ti >= MAX_ORTHOGONALITY_DEFECT {
            return Ok(Err(ScalarFailure::NotOrthogonal));
        }
        t.push(ti);
    }
    let t_max = t.iter().copied().fold(0.0, f64::max);

    // -- step 2 (second order): per edge e = (a, b), P_e = R_a^T R_ab^T R_b = A_e + K_e
    // (symmetric + skew part). With d = x_b - x_a and m = (x_a + x_b) / 2 the edge's part of
    // x^T M x is w (d^T A_e d - 2 m^T K_e d) >= w (alpha_e - beta) |d|^2 - w k_e^2 / (2 beta)
    // (|x_a|^2 + |x_b|^2), alpha_e <= lambda_min(A_e), k_e >= ||K_e||_2; the rest of the diagonal
    // blocks is G_i = M_ii - sum_e w A_e, ||G_i||_2 <= g_i. Hence
    // M >= (L' - diag(delta)) (x) I_3 with L' the Laplacian of the weights w (alpha_e - beta).
    // The error of fl(P_e) against the exact product: entries of the exact product are <= 3.3
    // in magnitude (|R| entries <= 1 + 1e-3); the two 3-term products err by < 2e-14 per entry,
    // 6e-14 in Frobenius; 2e-13 also covers forming the symmetric and skew parts.
    const PRODUCT_ERROR: f64 = 2e-13;
    let beta = SECOND_ORDER_BETA;
    let mut deg_w = vec![0.0f64; n];
    let mut deg_n = vec![0usize; n];
    let mut delta = vec![0.0f64; n];
    let mut sym_sum = vec![Matrix3::zeros(); n];
    let mut sym_err = vec![0.0f64; n];
    let mut reduced = Vec::with_capacity(problem.num_edges());
    let mut second_order_edges = 0usize;
    for e in problem.edges() {
        let (ri, rj, rij) = (
            rotations[e.i].matrix(),
            rotations[e.j].matrix(),
            e.rotation.matrix(),
        );
        let pm = ri.transpose() * (rij.transpose() * rj);
        let sym = 0.5 * (pm + pm.transpose());
        // the axial vector of the skew part: ||K||_2 = |k| for a 3 x 3 skew matrix
        let axial = nalgebra::Vector3::new(
            0.5 * (pm[(2, 1)] - pm[(1, 2)]),
            0.5 * (pm[(0, 2)] - pm[(2, 0)]),
            0.5 * (pm[(1, 0)] - pm[(0, 1)]),
        );
        let k_e = axial.norm() * (1.0 + 8.0 * u) + PRODUCT_ERROR;
        // lambda_min(A) >= 1 - ||A - I||_2 >= 1 - ||A - I||_F
        let alpha = 1.0 - (fro(&(sym - Matrix3::identity())) * (1.0 + 4.0 * u) + PRODUCT_ERROR);
        // first order: w (|d|^2 + x_a^T (A - I) x_a + x_b^T (A - I) x_b - 2 x_a^T (P - I) x_b)
        // >= w |d|^2 - w c1 (|x_a|^2 + |x_b|^2), c1 >= ||A - I||_2 + ||P - I||_2
        let c1 = (fro(&(sym - Matrix3::identity())) + fro(&(pm - Matrix3::identity())))
            * (1.0 + 4.0 * u)
            + 2.0 * PRODUCT_ERROR;
        // each edge takes the bound with the smaller charge per unit of weight kept (the
        // condition is roughly lambda_2 >= charge / weight): second order for small residuals,
        // first order for outliers, whose alpha_e - beta is negative
        let dropped = analysis.copies[reduced.len()] == 0;
        let coeff = alpha - beta;
        let charge2 = k_e * k_e / (2.0 * beta);
        let (coeff, charge) = if dropped {
            // left out of L': its kept weight w (alpha - beta') >= 0 is dropped, a lower bound,
            // so beta' = alpha (the largest allowed) minimises its charge k^2 / (2 beta')
            if alpha > 0.0 {
                (0.0, c1.min(k_e * k_e / (2.0 * alpha) * (1.0 + 8.0 * u)))
            } else {
                (0.0, c1)
            }
        } else if coeff > 0.0 && charge2 < c1 * coeff {
            second_order_edges += 1;
            (coeff, charge2)
        } else {
            (1.0, c1)
        };
        // rounded towards -inf: a smaller weight only weakens the comparison
        let w_red = e.weight * coeff * (1.0 - 4.0 * u);
        reduced.push(w_red);
        let dk = e.weight * charge * (1.0 + 8.0 * u);
        delta[e.i] += dk;
        delta[e.j] += dk;
        sym_sum[e.i] += e.weight * sym;
        sym_sum[e.j] += e.weight * sym;
        sym_err[e.i] += e.weight * PRODUCT_ERROR;
        sym_err[e.j] += e.weight * PRODUCT_ERROR;
        deg_w[e.i] += e.weight;
        deg_w[e.j] += e.weight;
        deg_n[e.i] += 1;
        deg_n[e.j] += 1;
    }
    for i in 0..n {
        // the sums above err by <= gamma(deg + 2) of the sums of magnitudes (weights are
        // positive, entries of A_e <= 3.3: the magnitudes sum to <= 3.3 d_i per entry)
        let g = gamma(deg_n[i] + 2);
        let d_i = deg_w[i] * (1.0 + g);
        let ri = rotations[i].matrix();
        let lam = 0.5 * (lambdas[i] + lambdas[i].transpose());
        // G_i = d_i R_i^T R_i - R_i^T sym(Lambda_i) R_i - sum_e w_e A_e, evaluated with an
        // entrywise error of at most gamma(12) times the magnitudes (3 x 3 products of entries
        // <= 1.001 with Lambda's, and three subtractions), plus the sums' errors above
        let gm = (ri.transpose() * ri) * deg_w[i] - ri.transpose() * lam * ri - sym_sum[i];
        let magnitude = 1.01 * deg_w[i] + 9.1 * lambdas[i].amax() + 3.3 * d_i;
        let entry_err = gamma(12) * magnitude * 3.0 + g * 3.3 * d_i * 2.0;
        let g_i = fro(&gm) * (1.0 + 4.0 * u) + 3.0 * entry_err + sym_err[i] * (1.0 + g);
        delta[i] = (delta[i] * (1.0 + g) + g_i) * (1.0 + 4.0 * u);
    }
    let d_max = deg_w.iter().copied().fold(0.0, f64::max);
    // a positive floor keeps diag(delta) definite (raising delta only weakens the argument)
    let floor = 1e-14 * d_max.max(f64::MIN_POSITIVE);
    for d in delta.iter_mut() {
        *d = d.max(floor);
    }
    if !delta.iter().chain(&reduced).all(|d| d.is_finite()) {
        return Ok(Err(ScalarFailure::Numerical));
    }
    let max_delta = delta.iter().copied().fold(0.0, f64::max);

    // -- step 3: r'_i = R_i^T (S Y)_i, (S Y)_i = (Q Y)_i - sym(Lambda_i) R_i, evaluated here with
    // a running entrywise error bound (Higham Lemma 3.1 and 3.5, |R| entries <= 1 + 1e-3):
    // each edge term w (R_i - R_ij^T R_j) has entries <= 4.4 w and is formed with error
    // <= w (gamma_3 3.4 + 2u 4.4) per entry; summing the deg_i terms adds gamma(deg_i + 1) times
    // the sum of their magnitudes.
    let mut qy = vec![Matrix3::zeros(); n];
    let mut qy_err = vec![0.0f64; n];
    let mut qy_abs = vec![0.0f64; n];
    let edge_err = gamma(3) * 3.4 + 2.0 * u * 4.4;
    for e in problem.edges() {
        let rij = e.rotation.matrix();
        let (ri, rj) = (rotations[e.i].matrix(), rotations[e.j].matrix());
        let ti = e.weight * (ri - rij.transpose() * rj);
        let tj = e.weight * (rj - rij * ri);
        qy[e.i] += ti;
        qy[e.j] += tj;
        qy_err[e.i] += e.weight * edge_err;
        qy_err[e.j] += e.weight * edge_err;
        qy_abs[e.i] += ti.amax();
        qy_abs[e.j] += tj.amax();
    }
    let mut rho1_sq = 0.0f64;
    let mut sum_r = Matrix3::zeros();
    let mut err_sum = 0.0f64;
    let mut abs_sum = 0.0f64;
    for i in 0..n {
        let ri = rotations[i].matrix();
        let lam = 0.5 * (lambdas[i] + lambdas[i].transpose());
        let sy = qy[i] - lam * ri;
        let r = ri.transpose() * sy;
        // entrywise error of sy: the Q Y sum, the symmetrisation (u |Lambda|), the product
        // Lambda R (gamma_3 3.4 |Lambda|max) and the subtraction (u |sy|)
        let lam_max = lambdas[i].amax();
        let e_sy = (qy_err[i] + gamma(deg_n[i] + 2) * qy_abs[i]) * (1.0 + 4.0 * u)
            + (gamma(4) * 3.4 + 2.0 * u) * lam_max * 3.0
            + 2.0 * u * sy.amax();
        // R^T sy: gamma_3 (|R^T| |sy|) <= gamma_3 3.4 |sy|max, plus |R^T| e_sy <= 3.4 e_sy;
        // Frobenius of a 3x3 error <= 3 x its largest entry bound
        let e_r = 3.0 * (gamma(4) * 3.4 * sy.amax() + 3.4 * e_sy) * (1.0 + 1e-12);
        let rn = fro(&r) * (1.0 + 4.0 * u) + e_r;
        rho1_sq += rn * rn;
        sum_r += r;
        err_sum += e_r;
        abs_sum += fro(&r);
    }
    let rho1 = rho1_sq.sqrt() * (1.0 + gamma(n + 4));
    let nf = n as f64;
    let rho0_plain = (fro(&sum_r) + err_sum + gamma(n + 4) * abs_sum) * (1.0 + 8.0 * u);
    // the plain bound's rounding grows like n u d: above a tiny fraction of the target, evaluate
    // v0^T M v0 in double-double instead (its true size is the rounding of Lambda, ~sqrt(n) u d)
    let rho0 = if rho0_plain * 1e3 > target.max(0.0) * nf {
        rho0_plain.min(gauge_block_bound(problem, rotations, lambdas))
    } else {
        rho0_plain
    };

    // -- step 4: the split weights w = delta + zeta. A uniform zeta > 0 buys the positive term
    // zeta |x1|^2, which absorbs the cross terms: x^T M x >= -(rho0 + rho1^2 / zeta) kappa^2 |x|^2.
    // zeta is chosen so that this is at most target / 4 (with kappa ~ its zeta = 0 value).
    let kappa_of = |zeta: f64| {
        let sum: f64 = delta.iter().map(|d| d + zeta).sum::<f64>() * (1.0 - gamma(n + 2));
        let norm = delta
            .iter()
            .map(|d| (d + zeta) * (d + zeta))
            .sum::<f64>()
            .sqrt()
            * (1.0 + gamma(n + 2));
        (norm / sum) * (1.0 + 4.0 * u)
    };
    let k0 = kappa_of(0.0);
    let zeta_needed = if target > 0.0 && target.is_finite() {
        (4.0 * rho1 * rho1 * k0 * k0 / target).max(1e-12 * d_max)
    } else {
        0.0
    };

    // -- step 5 (split): part p proves lambda_2(L'_p - diag(c_p)) >= 0 with the charges
    // c_p = w * f_p, f_p(i) = (part p's kept weight at i) / (node i's kept weight): every part
    // is charged where it is strong. By the pencil lemma without orthogonality,
    // y^T (L'_p - C_p) y >= -(c_p^T y)^2 / 1^T c_p for every y, and for w^T y = 0,
    // c_p^T y = (c_p - s_p w)^T y: summed over the parts (sum_p c_p >= w),
    // y^T (L' - diag(w)) y >= -eps |y|^2, eps = sum_p ||c_p - s_p w||^2 / 1^T c_p (the split's
    // defect, 0 for one part). A larger zeta pays for it: zeta - eps is what absorbs the cross
    // terms below.
    let shares = part_shares(analysis, problem, &reduced, n);
    let defect_of = |zeta: f64| -> f64 {
        let w: Vec<f64> = delta.iter().map(|d| d + zeta).collect();
        split_defect(&shares, &w)
    };
    let mut zeta = zeta_needed;
    let mut defect = 0.0f64;
    if shares.len() > 1 {
        // eps grows with zeta (w does): twice the first estimate, then the exact one checked
        zeta = zeta_needed + 2.0 * defect_of(zeta_needed);
        defect = defect_of(zeta);
    }
    let weights: Vec<f64> = delta.iter().map(|d| d + zeta).collect();
    // what the weights add to delta: fl(delta_i + zeta) >= delta_i + zeta - u w_i (twice that
    // for safety), less the split's defect; x1^T M x1 >= zeta_free |x1|^2 needs it >= 0
    let w_max = weights.iter().copied().fold(0.0, f64::max);
    let zeta_free = (zeta - 2.0 * u * w_max - defect) * (1.0 - 4.0 * u);
    if !(zeta_free.is_finite() && (zeta_free >= 0.0 || shares.len() <= 1)) {
        return Ok(Err(ScalarFailure::Numerical));
    }

    // -- step 5: inertia of A_p = L'_p - diag(c_p) - h I for each of the P parts (one part,
    // c = w, for the whole graph or a subgraph: the pencil lemma, step 4's premise). L' =
    // sum_p L'_p (each edge's kept weight shared evenly by the parts that hold it).
    // h only needs to exceed the backward error (typically ~1e-10 d_max at 10^4 nodes); it
    // tightens the condition by a negligible 1e-6 d_max
    let num_parts = analysis.parts.len().max(1);
    let mut headroom = 0.0f64;
    let mut backward = 0.0f64;
    for (p, part) in analysis.parts.iter().enumerate() {
        let charges = match shares.get(p) {
            Some(f) => part_charges(&weights, f, num_parts),
            None => weights.clone(),
        };
        let mut h = 1e-6 * d_max.max(f64::MIN_POSITIVE) / num_parts as f64;
        let mut attempt = 0;
        let bound = loop {
            attempt += 1;
            match factor_inertia(
                part,
                problem,
                &analysis.copies,
                &reduced,
                &charges,
                h,
                &deg_n,
            ) {
                Ok((_, bound)) => {
                    if bound <= h {
                        break bound;
                    }
                    if attempt >= 2 {
                        return Ok(Err(ScalarFailure::BackwardError));
                    }
                    h = 4.0 * bound;
                }
                Err(f) => return Ok(Err(f)),
            }
        };
        headroom = headroom.max(h);
        backward = backward.max(bound);
    }

    // the cross terms (both bounds hold; the better is used); x1^T M x1 >= (zeta - eps) |x1|^2
    let kappa = kappa_of(zeta);
    let plain = -(2.0 * kappa * (1.0 + nf.sqrt() * kappa) * rho1 + kappa * kappa * rho0);
    let absorbed = if zeta_free > 0.0 {
        -(rho0 + rho1 * rho1 / zeta_free) * kappa * kappa
    } else {
        f64::NEG_INFINITY
    };
    let mu_m = plain.max(absorbed) * (1.0 + 1e-10);
    // Ostrowski: lambda_min(S) >= lambda_min(M) / sigma_min(D)^2, sigma_min(D)^2 >= 1 - t_max
    let mu = mu_m / (1.0 - t_max) * (1.0 + 1e-10);
    if !mu.is_finite() {
        return Ok(Err(ScalarFailure::Numerical));
    }
    Ok(Ok(ScalarComparison {
        verified_min_eigenvalue: mu.min(0.0),
        max_delta,
        second_order_edges,
        dropped_edges: analysis.dropped_edges(),
        parts: analysis.parts(),
        shared_edges: analysis.shared_edges(),
        split_defect: defect,
        zeta,
        headroom,
        backward_error: backward,
        factor_nonzeros: analysis.factor_len(),
        kappa,
        residual_bound: rho1,
    }))
}

/// Per part of a split (none for one part), every node's share `f_p(i)` of its kept weight:
/// part `p`'s kept weight at `i` over the node's, `1 / P` where a node keeps none.
fn part_shares(
    analysis: &ScalarAnalysis,
    problem: &MultipleProblem,
    reduced: &[f64],
    n: usize,
) -> Vec<Vec<f64>> {
    let parts = analysis.parts.len();
    if parts <= 1 {
        return Vec::new();
    }
    let edges = problem.edges();
    let mut kept = vec![vec![0.0f64; n]; parts];
    for (part, kept) in analysis.parts.iter().zip(kept.iter_mut()) {
        for &(k, _, _) in &part.edges {
            let w = reduced[k].max(0.0) / analysis.copies[k].max(1) as f64;
            kept[edges[k].i] += w;
            kept[edges[k].j] += w;
        }
    }
    let mut total = vec![0.0f64; n];
    for kept in &kept {
        for (t, k) in total.iter_mut().zip(kept) {
            *t += k;
        }
    }
    kept.into_iter()
        .map(|kept| {
            kept.iter()
                .zip(&total)
                .map(|(&k, &t)| if t > 0.0 { k / t } else { 1.0 / parts as f64 })
                .collect()
        })
        .collect()
}

/// A part's charges `c_p = w f_p`, rounded up by `1 + gamma(P + 4)` so that
/// `sum_p c_p >= w` holds in floating point (the shares `f_p` sum to 1 up to `(P + 2) u`).
/// Step 5 factorises with exactly these numbers and [`split_defect`] bounds their defect.
fn part_charges(w: &[f64], f: &[f64], parts: usize) -> Vec<f64> {
    w.iter()
        .zip(f)
        .map(|(w, f)| w * f * (1.0 + gamma(parts + 4)))
        .collect()
}

/// The split's defect `eps >= sum_p ||c_p - s_p w||^2 / 1^T c_p` with `c_p` from
/// [`part_charges`] and `s_p = c_p^T w / w^T w` (any `s_p` is valid; this one minimises the
/// norm), rounded up: every difference's rounding is bounded by `gamma(4)` times the
/// magnitudes.
fn split_defect(shares: &[Vec<f64>], w: &[f64]) -> f64 {
    let parts = shares.len();
    let n = w.len();
    let g = gamma(n + 4);
    let ww: f64 = w.iter().map(|x| x * x).sum();
    let mut eps = 0.0f64;
    for f in shares {
        let c = part_charges(w, f, parts);
        let cw: f64 = c.iter().zip(w).map(|(c, w)| c * w).sum();
        let sp = cw / ww;
        let (mut sq, mut mag) = (0.0f64, 0.0f64);
        for (c, w) in c.iter().zip(w) {
            let d = c - sp * w;
            sq += d * d;
            mag += (c.abs() + (sp * w).abs()).powi(2);
        }
        let norm = sq.sqrt() * (1.0 + g) + gamma(4) * mag.sqrt() * (1.0 + g);
        let sum: f64 = c.iter().sum::<f64>() * (1.0 - g);
        if sum <= 0.0 {
            return f64::INFINITY;
        }
        eps += norm * norm / sum;
    }
    eps * (1.0 + gamma(2 * parts + 4))
}

/// A rigorous upper bound on `||v0^T M v0||_F = ||sum_i r'_i||_F` (step 3), evaluated in
/// double-double from the data: `v0^T M v0 = sum_i G_i` with
/// `G_i = sum_{e at i} w_e (R_i^T R_i - (P_e + P_e^T) / 2) - R_i^T sym(Lambda_i) R_i`, each a
/// symmetric 3 x 3 matrix whose entries are sums of triple and quadruple products of stored
/// numbers ([`Accumulator`]). Summed per node first: each `G_i` cancels to the rounding of
/// `Lambda_i`, so the compensated sum's error bound (quadratic in the number of terms) stays
/// at the level of that rounding instead of growing with the number of edges.
fn gauge_block_bound(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    lambdas: &[Matrix3<f64>],
) -> f64 {
    // the six entries p <= q
    const ENTRIES: [(usize, usize); 6] = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)];
    let adjacency = problem.adjacency();
    let mut total = [Accumulator::default(); 6];
    let mut node_bounds = 0.0f64;
    for (i, (r, lam)) in rotations.iter().zip(lambdas).enumerate() {
        let r = r.matrix();
        let mut acc = [Accumulator::default(); 6];
        for &(_, k) in adjacency.neighbours(i) {
            let e = &problem.edges()[k];
            let (ra, rb, rab) = (
                rotations[e.i].matrix(),
                rotations[e.j].matrix(),
                e.rotation.matrix(),
            );
            // P_e = R_a^T R_ab^T R_b; halving the weight is exact
            let half = -0.5 * e.weight;
            for (x, &(p, q)) in acc.iter_mut().zip(&ENTRIES) {
                for k in 0..3 {
                    x.add_triple(e.weight, r[(k, p)], r[(k, q)]);
                    for l in 0..3 {
                        x.add_quad(half, ra[(k, p)], rab[(l, k)], rb[(l, q)]);
                        x.add_quad(half, ra[(k, q)], rab[(l, k)], rb[(l, p)]);
                    }
                }
            }
        }
        for (x, &(p, q)) in acc.iter_mut().zip(&ENTRIES) {
            for k in 0..3 {
                for l in 0..3 {
                    // sym(Lambda)_kl = Lambda_kl / 2 + Lambda_lk / 2 (halving is exact)
                    x.add_triple(-0.5 * lam[(k, l)], r[(k, p)], r[(l, q)]);
                    x.add_triple(-0.5 * lam[(l, k)], r[(k, p)], r[(l, q)]);
                }
            }
        }
        for (t, x) in total.iter_mut().zip(&acc) {
            let (hi, lo) = x.parts();
            t.add_product(hi, 1.0);
            t.add_product(lo, 1.0);
            node_bounds += x.parts_bound();
        }
    }
    let sq: f64 = total
        .iter()
        .zip(&ENTRIES)
        .map(|(x, &(p, q))| {
            let v = x.value().abs() + x.bound();
            if p == q { v * v } else { 2.0 * v * v }
        })
        .sum();
    // every entry's error: the total's own bound plus the nodes' bounds (all of them charged
    // to every entry), with 1 + gamma(6n) for summing the nodes' bounds in floating point
    let node_bounds = node_bounds * (1.0 + gamma(6 * rotations.len() + 2));
    let bound = (sq.sqrt() + 3.0 * node_bounds) * (1.0 + 8.0 * UNIT_ROUNDOFF);
    if bound.is_finite() {
        bound
    } else {
        f64::INFINITY
    }
}

/// `LDL^T` of `A = L'_p - diag(delta) - h I` without pivoting (AMD order), `L'_p` the Laplacian
/// of `part`'s edges with the weights `reduced / copies` (any sign). Returns (negative pivots, rigorous bound on
/// `||A_exact - P^T L D L^T P||_2`) when exactly one pivot is negative and none is zero; a
/// failure otherwise.
fn factor_inertia(
    part: &ScalarPart,
    problem: &MultipleProblem,
    copies: &[u32],
    reduced: &[f64],
    delta: &[f64],
    h: f64,
    deg_n: &[usize],
) -> std::result::Result<(usize, f64), ScalarFailure> {
    let n = delta.len();
    let mut a = part.pattern.clone();
    // row sums of the magnitudes of the terms that form each entry (the forming error)
    let mut magnitude = vec![0.0f64; n];
    {
        let val = a.val_mut();
        val.iter_mut().for_each(|v| *v = 0.0);
        let edges = problem.edges();
        for &(k, p_ij, p_ji) in &part.edges {
            let e = &edges[k];
            // a shared edge's even share (one division: its rounding is in the forming error)
            let w = reduced[k] / copies[k].max(1) as f64;
            val[p_ij] -= w;
            val[p_ji] -= w;
            val[part.diag_pos[e.i]] += w;
            val[part.diag_pos[e.j]] += w;
            magnitude[e.i] += 2.0 * w.abs();
            magnitude[e.j] += 2.0 * w.abs();
        }
        for i in 0..n {
            val[part.diag_pos[i]] -= delta[i] + h;
            magnitude[i] += delta[i] + h;
        }
    }
    let inertia = ldlt_inertia(&part.symbolic, a.as_ref()).map_err(|f| match f {
        LdltFailure::Numerical => ScalarFailure::Numerical,
    })?;
    let negative = inertia.negative;
    if negative != 1 {
        return Err(ScalarFailure::Inertia {
            negative_pivots: negative,
        });
    }
    // every entry of A is a sum of at most deg + 3 rounded terms; a row's entries err by at
    // most gamma(terms + 2) times the magnitudes of their terms
    // (one more rounding for the division of a shared edge's weight)
    let terms = deg_n.iter().copied().max().unwrap_or(0) + 4;
    let forming = gamma(terms + 2) * magnitude.iter().copied().fold(0.0, f64::max);
    // doubled to cover the rounding in evaluating the bounds themselves
    let bound = inertia.backward_error + 2.0 * forming;
    if !bound.is_finite() {
        return Err(ScalarFailure::Numerical);
    }
    Ok((negative, bound))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::certify::multiple::{certificate_matrix, multipliers};
    use crate::multiple::synthetic::SyntheticGraph;
    use crate::multiple::{MultipleSettings, solve_multiple};
    use nalgebra::{DMatrix, SymmetricEigen};

    fn dense_lambda_min(p: &MultipleProblem, lambdas: &[Matrix3<f64>]) -> f64 {
        let s = certificate_matrix(p, lambdas).unwrap();
        let n3 = s.nrows();
        let mut m = DMatrix::zeros(n3, n3);
        let (cp, ri, v) = (s.col_ptr(), s.row_idx(), s.val());
        for c in 0..n3 {
            for k in cp[c]..cp[c + 1] {
                m[(ri[k], c)] = v[k];
            }
        }
        SymmetricEigen::new(m).eigenvalues.min()
    }

    /// The split analysis of `p` with the shape `(parts, copies, min_degree)`, unbounded.
    fn split_of(
        p: &MultipleProblem,
        (parts, copies, min_degree): (usize, usize, usize),
    ) -> ScalarAnalysis {
        let shape = SplitShape {
            parts,
            copies,
            min_degree,
        };
        ScalarAnalysis::split(p, shape, usize::MAX)
            .unwrap()
            .unwrap()
    }

    /// The all-identity point of `p` with its multipliers and the dense `lambda_min(S)`, which
    /// must be clearly negative (the independent check of the planted indefinite cases).
    fn indefinite_at_identity(p: &MultipleProblem) -> (Vec<Rotation>, Vec<Matrix3<f64>>, f64) {
        let rs = vec![Rotation::identity(); p.num_rotations()];
        let l = multipliers(p, &rs).unwrap();
        let exact = dense_lambda_min(p, &l);
        assert!(
            exact < -1e-3,
            "independent check: S is indefinite ({exact})"
        );
        (rs, l, exact)
    }

    /// Soundness against a dense eigensolver (independent of the argument): whenever the scalar
    /// comparison proves `mu`, the dense `lambda_min(S)` is >= mu (up to the dense solver's own
    /// error 1e-12 |S|). Over noise levels from 0 to 0.3 rad, local minima and non-critical points.
    #[test]
    fn scalar_comparison_is_sound_against_dense_eigenvalues() {
        let (mut proven, mut failed, mut instances, mut sparsified) = (0, 0, 0, 0);
        let mut split = 0;
        // largest mu / lambda_min over proofs at clearly indefinite S (1 = tight)
        let mut tightest = 0.0f64;
        for seed in 0..150u64 {
            let n = 6 + (seed as usize % 20);
            let sigma = [0.0, 0.01, 0.05, 0.1, 0.2, 0.3][seed as usize % 6];
            let (p, gt) = SyntheticGraph {
                num_rotations: n,
                num_edges: 2 * n + (seed as usize % 7),
                noise_sigma: sigma,
                seed,
                ..Default::default()
            }
            .generate();
            // every other instance: non-uniform weights in [0.1, 3.1)
            let p = if seed % 2 == 1 {
                let edges = p
                    .edges()
                    .iter()
                    .enumerate()
                    .map(|(k, e)| crate::multiple::Edge {
                        weight: 0.1
                            + 3.0 * (((k as u64 * 2654435761 + seed) % 1000) as f64 / 1000.0),
                        ..e.clone()
                    })
                    .collect();
                MultipleProblem::new(n, edges).unwrap()
            } else {
                p
            };
            instances += 1;
            let sol = solve_multiple(&p, &MultipleSettings::default()).unwrap();
            let an = ScalarAnalysis::new(&p, usize::MAX).unwrap().unwrap();
            // sparsified comparisons on subgraphs (every edge still charged)
            let mut sparse: Vec<ScalarAnalysis> = [1.5, 2.0, 3.0]
                .iter()
                .map(|&k| {
                    ScalarAnalysis::sparsified(&p, &sol.rotations, k, usize::MAX)
                        .unwrap()
                        .unwrap()
                })
                .collect();
            // ... and splits, every part proving its (uneven) share
            sparse.extend([(2, 1, 2), (3, 1, 3), (5, 2, 2)].map(|shape| split_of(&p, shape)));
            // the local solution, the ground truth (not critical when noisy), a perturbed point
            let perturbed: Vec<Rotation> = sol
                .rotations
                .iter()
                .enumerate()
                .map(|(k, r)| {
                    crate::so3::exp(&nalgebra::Vector3::new(1e-4 * (k % 3) as f64, 0.0, 1e-4)) * r
                })
                .collect();
            // ... and the local solution with multipliers that are not its own (Lambda + 1e-2 I:
            // S drops by 1e-2, so it is indefinite; only the G_i term of step 2 sees it)
            let shifted: Vec<Matrix3<f64>> = multipliers(&p, &sol.rotations)
                .unwrap()
                .iter()
                .map(|l| l + Matrix3::identity() * 1e-2)
                .collect();
            for (rs, own) in [
                (&sol.rotations, true),
                (&gt, true),
                (&perturbed, true),
                (&sol.rotations, false),
            ] {
                let l = if own {
                    multipliers(&p, rs).unwrap()
                } else {
                    shifted.clone()
                };
                let exact = dense_lambda_min(&p, &l);
                let scale: f64 = l.iter().map(|m| m.norm()).sum::<f64>() + 20.0 * n as f64;
                let analyses = std::iter::once(&an).chain(&sparse);
                for (target, an) in (0..12)
                    .map(|k| 10f64.powi(-k))
                    .flat_map(|t| analyses.clone().map(move |a| (t, a)))
                {
                    match scalar_comparison(&p, an, rs, &l, target).unwrap() {
                        Ok(c) => {
                            proven += 1;
                            sparsified += usize::from(c.dropped_edges > 0);
                            split += usize::from(c.parts > 1);
                            if exact < -1e-12 {
                                tightest = tightest.max(c.verified_min_eigenvalue / exact);
                            }
                            assert!(
                                c.verified_min_eigenvalue <= exact + 1e-13 * scale,
                                "seed {seed}: proven {} > dense {exact}",
                                c.verified_min_eigenvalue
                            );
                        }
                        Err(_) => failed += 1,
                    }
                }
            }
        }
        println!(
            "scalar comparison: {instances} instances, {proven} proofs ({sparsified} on \
             subgraphs, {split} split), {failed} not proven; tightest mu / lambda_min = \
             {tightest:.3}"
        );
        assert!(sparsified > 100, "proofs on subgraphs must be exercised");
        assert!(split > 100, "split proofs must be exercised");
        assert!(proven > 300, "the condition should hold at low noise");
        assert!(failed > 50, "and fail at high noise");
        assert!(
            tightest > 0.0,
            "some proofs must be at indefinite S (cross terms exercised)"
        );
    }

    /// The split's parts: every edge held by some part; every part connected; every node keeps
    /// its minimum degree of edges in every part (all of its edges when it has fewer); and on a
    /// dense random graph, few edges shared and the parts' sizes balanced. Checked with the
    /// problem's own component search on each part's edges (not the union-find of the split).
    #[test]
    fn split_parts_are_connected_balanced_and_keep_their_minimum_degree() {
        for (n, m, parts, copies, min_degree) in [
            (400, 4000, 4, 1, 2),
            (400, 4000, 6, 1, 3),
            (400, 4000, 7, 2, 2),
            (30, 60, 3, 1, 2),
            (12, 14, 2, 1, 3),
        ] {
            let (p, _) = SyntheticGraph {
                num_rotations: n,
                num_edges: m,
                seed: 5,
                ..Default::default()
            }
            .generate();
            let member = split_edges(&p, parts, copies, min_degree);
            assert!(member.iter().all(|&b| b != 0 && b < 1 << parts));
            assert!(member.iter().all(|&b| b.count_ones() as usize >= copies));
            let mut sizes = vec![0usize; parts];
            for (part, size) in sizes.iter_mut().enumerate() {
                let edges: Vec<_> = p
                    .edges()
                    .iter()
                    .zip(&member)
                    .filter(|&(_, &b)| b >> part & 1 == 1)
                    .map(|(e, _)| e.clone())
                    .collect();
                *size = edges.len();
                let sub = MultipleProblem::new(n, edges).unwrap();
                assert_eq!(
                    sub.components().len(),
                    1,
                    "part {part} of {parts} connected"
                );
                for v in 0..n {
                    let degree = p.adjacency().neighbours(v).len();
                    let kept = sub.adjacency().neighbours(v).len();
                    assert!(
                        kept >= degree.min(min_degree),
                        "node {v}: {kept} of {degree} edges in part {part}"
                    );
                }
            }
            if m >= 10 * n {
                let shared = member
                    .iter()
                    .filter(|b| b.count_ones() as usize > copies)
                    .count();
                assert!(shared * 5 < m, "{shared} of {m} edges shared");
                let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
                assert!(hi * 10 < lo * 11, "part sizes {sizes:?}");
            }
        }
    }

    /// The split's defect bounds what uneven shares cost (step 5): for `y` with `w^T y = 0`,
    /// `sum_p (c_p^T y)^2 / 1^T c_p <= eps |y|^2` with `c_p = w f_p`, checked on random
    /// shares, weights and vectors (the inequality itself, evaluated independently).
    #[test]
    fn split_defect_bounds_the_uneven_shares() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand::rngs::StdRng::seed_from_u64(3);
        let mut tightest = 0.0f64;
        for _ in 0..200 {
            let (n, parts) = (rng.random_range(2..30), rng.random_range(2..6));
            let w: Vec<f64> = (0..n).map(|_| rng.random_range(1e-3..2.0)).collect();
            let raw: Vec<Vec<f64>> = (0..parts)
                .map(|_| (0..n).map(|_| rng.random_range(0.0..1.0)).collect())
                .collect();
            let shares: Vec<Vec<f64>> = raw
                .iter()
                .map(|r| {
                    r.iter()
                        .enumerate()
                        .map(|(i, x)| x / raw.iter().map(|q| q[i]).sum::<f64>())
                        .collect()
                })
                .collect();
            let eps = split_defect(&shares, &w);
            for _ in 0..50 {
                let mut y: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
                let t = y.iter().zip(&w).map(|(y, w)| y * w).sum::<f64>()
                    / w.iter().map(|w| w * w).sum::<f64>();
                y.iter_mut().zip(&w).for_each(|(y, w)| *y -= t * w);
                let yy: f64 = y.iter().map(|y| y * y).sum();
                let cost: f64 = shares
                    .iter()
                    .map(|f| {
                        let cy: f64 = (0..n).map(|i| w[i] * f[i] * y[i]).sum();
                        let c1: f64 = (0..n).map(|i| w[i] * f[i]).sum();
                        cy * cy / c1
                    })
                    .sum();
                assert!(
                    cost <= eps * yy * (1.0 + 1e-12),
                    "{cost} > {eps} |y|^2 = {}",
                    eps * yy
                );
                tightest = tightest.max(cost / (eps * yy));
            }
        }
        assert!(tightest > 0.05, "the bound is not vacuous: {tightest}");
    }

    /// Non-global local minima (random restarts on noisy small graphs with outliers): `S` is
    /// indefinite there (checked by dense eigenvalues) while the point is critical, so only the
    /// comparison of step 2 stands between them and a false proof. Every proof, on the whole
    /// graph or on subgraphs (where the dropped edges' charges carry their frustration), must
    /// stay below the dense `lambda_min(S)`.
    #[test]
    fn no_proof_at_non_global_minima_whole_sparsified_or_split() {
        use crate::multiple::Initialisation;
        use rand::SeedableRng;
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        let (mut points, mut attempts, mut proofs) = (0, 0, 0);
        for seed in 0..120u64 {
            let n = 5 + (seed as usize % 8);
            let (p, _) = SyntheticGraph {
                num_rotations: n,
                num_edges: 2 * n + (seed as usize % 5),
                noise_sigma: [0.3, 0.6, 1.0][seed as usize % 3],
                outlier_fraction: 0.15,
                seed,
            }
            .generate();
            let sols: Vec<_> = (0..6)
                .map(|_| {
                    let start = (0..n)
                        .map(|_| crate::so3::random_rotation(&mut rng))
                        .collect();
                    let settings = MultipleSettings {
                        init: Initialisation::Given(start),
                        ..Default::default()
                    };
                    solve_multiple(&p, &settings).unwrap()
                })
                .collect();
            let best = sols
                .iter()
                .map(|s| s.chordal_cost)
                .fold(f64::INFINITY, f64::min);
            for sol in sols
                .iter()
                .filter(|s| s.chordal_cost > best * (1.0 + 1e-6) + 1e-9)
            {
                let l = multipliers(&p, &sol.rotations).unwrap();
                let exact = dense_lambda_min(&p, &l);
                if exact > -1e-9 {
                    continue; // a non-global point whose S is not (clearly) indefinite
                }
                points += 1;
                let mut analyses = vec![ScalarAnalysis::new(&p, usize::MAX).unwrap().unwrap()];
                for k in [1.0, 1.5, 2.0, 3.0] {
                    analyses.push(
                        ScalarAnalysis::sparsified(&p, &sol.rotations, k, usize::MAX)
                            .unwrap()
                            .unwrap(),
                    );
                }
                analyses.extend(
                    [(2, 1, 2), (3, 1, 3), (4, 1, 2), (5, 2, 2)].map(|shape| split_of(&p, shape)),
                );
                for an in &analyses {
                    for target in [1e-2, 1e-6, 1e-10] {
                        attempts += 1;
                        if let Ok(c) =
                            scalar_comparison(&p, an, &sol.rotations, &l, target).unwrap()
                        {
                            proofs += 1;
                            assert!(
                                c.verified_min_eigenvalue <= exact + 1e-12,
                                "seed {seed}: proven {} above dense {exact} ({} edges dropped)",
                                c.verified_min_eigenvalue,
                                c.dropped_edges
                            );
                        }
                    }
                }
            }
        }
        println!("non-global minima: {points} points, {attempts} attempts, {proofs} proofs");
        assert!(
            points > 50,
            "the campaign must reach non-global minima ({points})"
        );
    }

    /// A frustrated cycle whose frustration lives only on the edges a sparsified comparison
    /// drops: the 8-cycle with loop error 1.2 pi (winding-0 point, `S` indefinite) plus
    /// consistent chords `(i, i+2)`, `(i, i+3)` of weight 0.01 (zero residual). Keeping 4 edges
    /// per node keeps exactly the chords; the dropped cycle edges must still be charged, or the
    /// chords' Laplacian would "prove" `S >= 0`.
    #[test]
    fn dropped_edges_keep_their_charge() {
        let base = crate::multiple::synthetic::z_cycle(8, 1.2 * std::f64::consts::PI);
        let mut edges = base.edges().to_vec();
        for i in 0..8 {
            for step in [2, 3] {
                edges.push(crate::multiple::Edge {
                    i,
                    j: (i + step) % 8,
                    rotation: Rotation::identity(),
                    weight: 0.01,
                });
            }
        }
        let p = MultipleProblem::new(8, edges).unwrap();
        let (rs, l, exact) = indefinite_at_identity(&p);
        let an = ScalarAnalysis::sparsified(&p, &rs, 4.0, usize::MAX)
            .unwrap()
            .unwrap();
        assert_eq!(an.dropped_edges(), 8, "the cycle edges are dropped");
        for target in [1.0, 1e-3, 1e-9] {
            if let Ok(c) = scalar_comparison(&p, &an, &rs, &l, target).unwrap() {
                assert!(
                    c.verified_min_eigenvalue <= exact + 1e-12,
                    "{c:?} vs {exact}"
                );
            }
        }
    }

    /// An analysis made for another graph is refused with a typed error, never used (its
    /// entries would receive the wrong weights) and never a panic: same size with other edges,
    /// and a different number of edges.
    #[test]
    fn an_analysis_of_another_graph_is_refused() {
        let graph = |seed| {
            SyntheticGraph {
                num_rotations: 12,
                num_edges: 30,
                noise_sigma: 0.01,
                seed,
                ..Default::default()
            }
            .generate()
        };
        let ((p, gt), (q, _)) = (graph(1), graph(2));
        let l = multipliers(&p, &gt).unwrap();
        let other = ScalarAnalysis::new(&q, usize::MAX).unwrap().unwrap();
        let fewer = MultipleProblem::new(12, p.edges()[..25].to_vec()).unwrap();
        let short = ScalarAnalysis::new(&fewer, usize::MAX).unwrap().unwrap();
        for an in [&other, &short] {
            let e = scalar_comparison(&p, an, &gt, &l, 1e-6).unwrap_err();
            assert!(e.to_string().contains("different view graph"), "{e}");
        }
        let own = ScalarAnalysis::new(&p, usize::MAX).unwrap().unwrap();
        assert!(scalar_comparison(&p, &own, &gt, &l, 1e-6).is_ok());
    }

    /// The double-double evaluation of `v0^T M v0` against an exact value: signed permutation
    /// rotations with consistent measurements make every `P_e = I` exactly, and
    /// `Lambda_i = c_i I` with `c = (1e16, 1, -1e16, 0.5)` gives `v0^T M v0 = -(sum c) I = -1.5 I`,
    /// which plain summation gets wrong (it returns `-0.5 I`).
    #[test]
    fn gauge_block_bound_is_exact_under_cancellation() {
        // exact entries (a validating constructor may re-orthonormalise in floating point)
        let perm =
            |m: [[f64; 3]; 3]| Rotation::from_matrix_unchecked(Matrix3::from_fn(|a, b| m[a][b]));
        let rs = vec![
            perm([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]),
            perm([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]),
            perm([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]),
            perm([[-1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]),
        ];
        let edges = [(0, 1), (1, 2), (2, 3), (3, 0), (0, 2)]
            .iter()
            .map(|&(i, j)| crate::multiple::Edge {
                i,
                j,
                rotation: rs[j] * rs[i].inverse(),
                weight: 0.75,
            })
            .collect();
        let p = MultipleProblem::new(4, edges).unwrap();
        let c = [1e16, 1.0, -1e16, 0.5];
        let lambdas: Vec<Matrix3<f64>> = c.iter().map(|&x| Matrix3::identity() * x).collect();
        assert_eq!(c.iter().sum::<f64>(), 0.5, "plain summation loses the 1");
        let exact = 1.5 * 3f64.sqrt();
        let b = gauge_block_bound(&p, &rs, &lambdas);
        // the error bound charges gamma^2 sum |terms| ~ 1e-10 for terms of size 1e16
        assert!(b >= exact && b <= exact * (1.0 + 1e-9), "{b} vs {exact}");
    }

    /// The second-order comparison is exact on a cycle with equal residuals: the winding-0
    /// critical point (all identity) of an 8-cycle with loop error `phi` about one axis has
    /// `S >= 0` iff `phi <= pi` (the dense eigenvalues check it here). At `0.5 pi` and `0.8 pi`
    /// it is proven; a first-order comparison (`delta ~ 2 ||P_e - I||` per node, 1.8 at
    /// `0.8 pi`, against `lambda_2(L) = 0.59`) cannot. Past `pi`, `S` is indefinite and nothing
    /// is proven. The same for splits into 2 and 3 parts: every node has only its two cycle
    /// edges, so every part holds all of them with `1 / P` of their weight and `1 / P` of every
    /// charge, the whole graph's condition again (this fails when a shared edge's weight is not
    /// divided among the parts that hold it: each part would count it whole).
    #[test]
    fn second_order_comparison_is_tight_on_a_cycle_whole_or_split() {
        for (fraction, provable) in [(0.5, true), (0.8, true), (1.05, false), (1.2, false)] {
            let p = crate::multiple::synthetic::z_cycle(8, fraction * std::f64::consts::PI);
            let rs = vec![Rotation::identity(); 8];
            let l = multipliers(&p, &rs).unwrap();
            let exact = dense_lambda_min(&p, &l);
            assert_eq!(
                exact > -1e-12,
                provable,
                "independent check at {fraction} pi: {exact}"
            );
            let whole = ScalarAnalysis::new(&p, usize::MAX).unwrap().unwrap();
            for an in [whole, split_of(&p, (2, 1, 2)), split_of(&p, (3, 1, 2))] {
                let parts = an.parts();
                assert_eq!(an.shared_edges(), if parts > 1 { 8 } else { 0 });
                match scalar_comparison(&p, &an, &rs, &l, 1e-9).unwrap() {
                    Ok(c) => {
                        assert!(
                            provable,
                            "{fraction} pi, {parts} parts: proven {c:?} at indefinite S ({exact})"
                        );
                        assert!(c.verified_min_eigenvalue <= exact + 1e-12);
                        assert!(c.verified_min_eigenvalue >= -1e-9, "{c:?}");
                        assert_eq!(c.parts, parts);
                    }
                    Err(f) => assert!(!provable, "{fraction} pi, {parts} parts: {f:?}"),
                }
            }
        }
    }

    /// A planted point that is NOT a global minimum: a cycle with a large loop error at its
    /// winding local minimum. Its S is indefinite, so a proof must not exist.
    #[test]
    fn no_proof_for_an_indefinite_certificate() {
        // loop error 1.2 pi on an 8-cycle: all-identity (winding 0) is a critical point by
        // symmetry with cost above the winding-1 solution, so its S must be indefinite
        let p = crate::multiple::synthetic::z_cycle(8, 1.2 * std::f64::consts::PI);
        let (rs, l, exact) = indefinite_at_identity(&p);
        let an = ScalarAnalysis::new(&p, usize::MAX).unwrap().unwrap();
        if let Ok(c) = scalar_comparison(&p, &an, &rs, &l, 1e-9).unwrap() {
            assert!(c.verified_min_eigenvalue <= exact + 1e-12);
        }
    }
}
