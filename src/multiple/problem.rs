//! The validated multiple-rotation-averaging problem: nodes, edges, weights, cost.
//!
//! [`MultipleProblem::new`] validates [`Edge`]s (`R_ij R_i = R_j`, weights > 0); the problem
//! then gives the chordal cost [`MultipleProblem::chordal_cost`], residual angles, connected
//! components ([`MultipleProblem::components`], [`MultipleProblem::largest_component`]) and
//! the gauge fix [`fix_gauge`].

use crate::error::{Error, Result};
use crate::multiple::anisotropic::{Information, InformationSummary, chordal_cost_compensated};
use crate::objective::Objective;
use crate::so3::{Metric, Rotation, angle_between};
use crate::validate::check_weight;
use serde::{Deserialize, Serialize};

/// One measured edge: `rotation = R_ij` with `R_ij R_i = R_j`, weight `w_ij` in `[1e-100, 1e100]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Edge {
    /// Tail node `i` (0-based).
    pub i: usize,
    /// Head node `j` (0-based).
    pub j: usize,
    /// The relative rotation `R_ij`, with `R_ij R_i = R_j`.
    #[serde(with = "crate::so3::serde_rows::rotation")]
    pub rotation: Rotation,
    /// Weight `w_ij` (finite, > 0).
    pub weight: f64,
}

/// Compressed adjacency of a view graph ([`MultipleProblem::adjacency`]).
#[derive(Debug, Clone)]
pub(crate) struct Adjacency {
    start: Vec<usize>,
    entries: Vec<(usize, usize)>,
}

impl Adjacency {
    /// `(neighbour, edge index)` of every edge at node `u`.
    pub(crate) fn neighbours(&self, u: usize) -> &[(usize, usize)] {
        &self.entries[self.start[u]..self.start[u + 1]]
    }

    /// Breadth-first search from `root` over its component (`O(n + m)`).
    pub(crate) fn breadth_first(&self, root: usize) -> BreadthFirst {
        let n = self.start.len() - 1;
        let mut parent = vec![usize::MAX; n];
        let mut depth = vec![usize::MAX; n];
        parent[root] = root;
        depth[root] = 0;
        let mut queue = std::collections::VecDeque::from([root]);
        let mut last = root;
        while let Some(u) = queue.pop_front() {
            last = u;
            for &(v, _) in self.neighbours(u) {
                if parent[v] == usize::MAX {
                    parent[v] = u;
                    depth[v] = depth[u] + 1;
                    queue.push_back(v);
                }
            }
        }
        BreadthFirst {
            last,
            parent,
            depth,
        }
    }
}

/// A breadth-first search ([`Adjacency::breadth_first`]): `usize::MAX` marks the nodes outside
/// the root's component.
pub(crate) struct BreadthFirst {
    /// The last node reached: one of the farthest from the root.
    pub last: usize,
    /// Each reached node's parent (the root its own).
    pub parent: Vec<usize>,
    /// Each reached node's hop count from the root.
    pub depth: Vec<usize>,
}

impl Edge {
    /// The same measurement expressed as an edge `(j, i)`: `R_ji = R_ij^T`.
    ///
    /// ```
    /// use rotavg::multiple::Edge;
    /// use rotavg::so3::{angle_between, exp};
    /// let r_i = exp(&nalgebra::Vector3::new(0.1, 0.0, 0.0));
    /// let r_j = exp(&nalgebra::Vector3::new(0.0, 0.2, 0.0));
    /// let e = Edge { i: 0, j: 1, rotation: r_j * r_i.inverse(), weight: 2.0 }; // R_ij R_i = R_j
    /// let back = e.reversed(); // R_ji R_j = R_i
    /// assert_eq!((back.i, back.j, back.weight), (1, 0, 2.0));
    /// assert!(angle_between(&(back.rotation * r_j), &r_i) < 1e-15);
    /// ```
    pub fn reversed(&self) -> Edge {
        Edge {
            i: self.j,
            j: self.i,
            rotation: self.rotation.inverse(),
            weight: self.weight,
        }
    }
}

/// A validated view graph: every index in range, no self loops, finite positive weights,
/// exact rotations. Multi-edges (several measurements of one pair, in either direction) are
/// kept and all count. Connectivity is *not* required by the type; solvers that need it call
/// [`MultipleProblem::require_connected`]. Deserialisation validates like
/// [`MultipleProblem::new`] and [`MultipleProblem::with_information`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawMultipleProblem")]
pub struct MultipleProblem {
    num_rotations: usize,
    edges: Vec<Edge>,
    /// One 3x3 information matrix per edge, when the measurements are anisotropic
    /// ([`MultipleProblem::with_information`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    information: Option<Vec<Information>>,
    /// `true` when [`MultipleProblem::with_information`] was given `w I` on every edge and kept
    /// the weights `w` instead (only the reports use it).
    #[serde(skip)]
    isotropic_information: bool,
    #[serde(skip)]
    objective: Objective,
    #[serde(skip)]
    adjacency: AdjacencyCache,
}

/// The graph's adjacency, made on the first request and kept with the problem (its edges never
/// change after construction): no part of the problem's value, so equal problems compare
/// equal whether or not it was made, and it is neither serialised nor cloned.
#[derive(Debug, Default)]
struct AdjacencyCache(std::sync::OnceLock<Box<Adjacency>>);

impl Clone for AdjacencyCache {
    fn clone(&self) -> Self {
        AdjacencyCache::default()
    }
}

impl PartialEq for AdjacencyCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// Unvalidated serde form of [`MultipleProblem`].
#[derive(Deserialize)]
#[serde(
    expecting = "a view graph {\"num_rotations\": n, \"edges\": [...], \"information\": [...]} (information optional)"
)]
struct RawMultipleProblem {
    num_rotations: usize,
    edges: Vec<Edge>,
    #[serde(default)]
    information: Option<Vec<Information>>,
}

impl TryFrom<RawMultipleProblem> for MultipleProblem {
    type Error = Error;
    fn try_from(raw: RawMultipleProblem) -> Result<Self> {
        let p = MultipleProblem::new(raw.num_rotations, raw.edges)?;
        match raw.information {
            Some(info) => p.with_information(info),
            None => Ok(p),
        }
    }
}

impl MultipleProblem {
    /// Validate and build. Errors: no nodes, no edges, index out of range, self loop,
    /// non-finite or non-positive weight. Rotations are assumed already validated (they are
    /// [`Rotation`]s; build them with [`crate::so3::rotation_from_matrix`]).
    ///
    /// ```
    /// use rotavg::multiple::{Edge, MultipleProblem};
    /// use rotavg::Rotation;
    /// let e = |i, j| Edge { i, j, rotation: Rotation::identity(), weight: 1.0 };
    /// let p = MultipleProblem::new(3, vec![e(0, 1), e(1, 2), e(2, 0)]).unwrap();
    /// assert_eq!(p.num_edges(), 3);
    /// assert!(MultipleProblem::new(2, vec![e(0, 2)]).is_err());
    /// ```
    pub fn new(num_rotations: usize, edges: Vec<Edge>) -> Result<Self> {
        if num_rotations == 0 {
            return Err(Error::Empty {
                what: "the view graph (0 nodes)".into(),
            });
        }
        if edges.is_empty() {
            return Err(Error::Empty {
                what: "the edge list".into(),
            });
        }
        for (k, e) in edges.iter().enumerate() {
            for idx in [e.i, e.j] {
                if idx >= num_rotations {
                    return Err(Error::IndexOutOfRange {
                        edge: k,
                        index: idx,
                        num_rotations,
                    });
                }
            }
            if e.i == e.j {
                return Err(Error::SelfLoop { edge: k, node: e.i });
            }
            check_weight(|| format!("edge {k} ({}, {})", e.i, e.j), e.weight)?;
            if !e.rotation.matrix().iter().all(|x| x.is_finite()) {
                return Err(Error::NonFinite {
                    item: format!("edge {k} ({}, {})", e.i, e.j),
                });
            }
        }
        Ok(MultipleProblem {
            num_rotations,
            edges,
            information: None,
            isotropic_information: false,
            objective: Objective::CHORDAL_L2,
            adjacency: AdjacencyCache::default(),
        })
    }

    /// The same graph with anisotropic measurements: one information matrix `H` per edge, in
    /// edge order (contract section 1, `paper-notes/anisotropic.md` `[A1]`). The cost becomes the
    /// anisotropic chordal cost `sum 4 (tr M - <R_ij M, R_j R_i^T>)`, `M = tr(H)/2 I - H`; each
    /// edge's `weight` is replaced by `tr(H) / 3`, which only starts and preconditions the
    /// solvers (it is no part of any cost). With a geodesic objective
    /// ([`Self::with_objective`], before or after) the cost is `sum wbar rho(theta_H)` of the
    /// Mahalanobis angles `theta_H = sqrt(e^T H e / wbar)` (`[A10]`; `sum e^T H e` for L2).
    /// Errors: a count that differs from the edges'.
    ///
    /// ```
    /// use rotavg::multiple::{Edge, MultipleProblem, anisotropic::Information};
    /// use rotavg::Rotation;
    /// use nalgebra::{Matrix3, Vector3};
    /// let e = |i, j| Edge { i, j, rotation: Rotation::identity(), weight: 1.0 };
    /// let h = Information::new(Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 10.0)))?;
    /// let p = MultipleProblem::new(3, vec![e(0, 1), e(1, 2)])?.with_information(vec![h; 2])?;
    /// assert!(p.is_anisotropic());
    /// assert_eq!(p.edges()[0].weight, 4.0); // tr(H) / 3
    /// // the smallest eigenvalue of any H (rounded down by its accuracy, [A12])
    /// assert!((p.min_weight() - 1.0).abs() < 1e-6 && p.min_weight() <= 1.0);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn with_information(mut self, information: Vec<Information>) -> Result<Self> {
        if information.len() != self.edges.len() {
            return Err(Error::InvalidSettings {
                name: "information".into(),
                reason: format!(
                    "{} matrices for {} edges (one per edge, in edge order)",
                    information.len(),
                    self.edges.len()
                ),
            });
        }
        let isotropic: Option<Vec<f64>> =
            information.iter().map(Information::scalar_weight).collect();
        if let Some(weights) = isotropic {
            for (e, w) in self.edges.iter_mut().zip(weights) {
                e.weight = w;
            }
            self.isotropic_information = true;
            return Ok(self);
        }
        for (e, h) in self.edges.iter_mut().zip(&information) {
            e.weight = h.mean_weight();
        }
        self.information = Some(information);
        Ok(self)
    }

    /// The graph a start is computed on (`[A17]`): with information, the same edges with scalar
    /// weights [`Information::start_weight`] and no information; else the problem itself.
    pub(crate) fn start_graph(&self) -> std::borrow::Cow<'_, MultipleProblem> {
        let Some(info) = &self.information else {
            return std::borrow::Cow::Borrowed(self);
        };
        let edges = (self.edges.iter().zip(info))
            .map(|(e, h)| Edge {
                weight: h.start_weight(),
                ..*e
            })
            .collect();
        std::borrow::Cow::Owned(MultipleProblem {
            num_rotations: self.num_rotations,
            edges,
            information: None,
            isotropic_information: false,
            objective: self.objective,
            adjacency: AdjacencyCache::default(),
        })
    }

    /// The information matrices, one per edge, when the measurements are anisotropic.
    pub fn information(&self) -> Option<&[Information]> {
        self.information.as_deref()
    }

    /// `true` when the edges carry information matrices ([`Self::with_information`]; not when
    /// every one was exactly `w I`: those are scalar weights).
    pub fn is_anisotropic(&self) -> bool {
        self.information.is_some()
    }

    /// What the reports say about the information matrices given to
    /// [`Self::with_information`], `None` when none were (scalar weights).
    pub fn information_summary(&self) -> Option<InformationSummary> {
        match &self.information {
            Some(info) => InformationSummary::of(info),
            None if self.isotropic_information => {
                Some(InformationSummary::isotropic(self.edges.len()))
            }
            None => None,
        }
    }

    /// The objectives with a solver: chordal L2, and the geodesic metric with any loss.
    pub const SUPPORTED: &'static str = "chordal l2; geodesic with l2, l1, huber or cauchy";

    /// The same graph with another objective (default chordal L2, the certifiable one).
    /// [`Error::InvalidSettings`] (field `objective`) when there is no solver for it or a
    /// robust threshold is bad.
    ///
    /// ```
    /// use rotavg::multiple::synthetic::SyntheticGraph;
    /// use rotavg::objective::{Loss, Objective};
    /// use rotavg::Metric;
    /// let (p, _) = SyntheticGraph::default().generate();
    /// let robust = p.clone().with_objective(Objective::new(Metric::Geodesic, Loss::Huber { threshold_deg: 5.0 }))?;
    /// assert_eq!(robust.objective().loss.name(), "huber");
    /// assert!(p.with_objective(Objective::new(Metric::Chordal, Loss::L1)).is_err());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn with_objective(mut self, objective: Objective) -> Result<Self> {
        objective.validate()?;
        if !(objective.is_chordal_l2() || objective.metric == Metric::Geodesic) {
            return Err(objective.unsupported("multiple", Self::SUPPORTED));
        }
        self.objective = objective;
        Ok(self)
    }

    /// The smallest edge weight: the scale of the absolute part of the certificate's gap
    /// tolerance (contract section 3; adding edges can only lower it).
    pub fn min_weight(&self) -> f64 {
        match &self.information {
            Some(info) => {
                crate::validate::min_weight(info.iter().map(Information::min_positive_eigenvalue))
            }
            None => crate::validate::min_weight(self.edges.iter().map(|e| e.weight)),
        }
    }

    /// The objective minimised.
    pub fn objective(&self) -> Objective {
        self.objective
    }

    /// Number of nodes `n`.
    pub fn num_rotations(&self) -> usize {
        self.num_rotations
    }

    /// Number of measurements `m` (multi-edges counted).
    pub fn num_edges(&self) -> usize {
        self.edges.len()
    }

    /// The edges.
    pub fn edges(&self) -> &[Edge] {
        &self.edges
    }

    /// The graph's adjacency in compressed form ([`Adjacency`]): every edge listed at both
    /// endpoints, in edge order; made once (asked for 10 times in a solve and certificate of
    /// a 10^5-node graph with 10^6 edges, each build 0.02-0.05 s: 0.32 s in all before).
    pub(crate) fn adjacency(&self) -> &Adjacency {
        self.adjacency
            .0
            .get_or_init(|| Box::new(self.build_adjacency()))
    }

    fn build_adjacency(&self) -> Adjacency {
        let n = self.num_rotations;
        let mut start = vec![0usize; n + 1];
        for e in &self.edges {
            start[e.i + 1] += 1;
            start[e.j + 1] += 1;
        }
        for k in 0..n {
            start[k + 1] += start[k];
        }
        let mut fill = start.clone();
        let mut entries = vec![(0usize, 0usize); 2 * self.edges.len()];
        for (k, e) in self.edges.iter().enumerate() {
            entries[fill[e.i]] = (e.j, k);
            fill[e.i] += 1;
            entries[fill[e.j]] = (e.i, k);
            fill[e.j] += 1;
        }
        Adjacency { start, entries }
    }

    /// Connected components as node lists, largest first (ties: smallest first node first).
    ///
    /// ```
    /// use rotavg::multiple::{Edge, MultipleProblem};
    /// use rotavg::Rotation;
    /// let e = |i, j| Edge { i, j, rotation: Rotation::identity(), weight: 1.0 };
    /// // Two triangles {0, 1, 2} and {3, 4, 5} joined by nothing, plus an edge 5-6.
    /// let p = MultipleProblem::new(7, vec![e(0, 1), e(1, 2), e(2, 0), e(3, 4), e(4, 5), e(5, 3), e(5, 6)])?;
    /// assert_eq!(p.components(), vec![vec![3, 4, 5, 6], vec![0, 1, 2]]);
    /// let err = p.require_connected().unwrap_err();
    /// assert_eq!(err, rotavg::Error::Disconnected { component_sizes: vec![4, 3] });
    /// let (big, old_index) = p.largest_component();
    /// assert_eq!((big.num_rotations(), big.num_edges()), (4, 4));
    /// assert_eq!(old_index, vec![3, 4, 5, 6]);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn components(&self) -> Vec<Vec<usize>> {
        let n = self.num_rotations;
        let mut sets = super::union_find::UnionFind::new(n);
        for e in &self.edges {
            sets.union(e.i, e.j);
        }
        let mut by_root: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for v in 0..n {
            by_root.entry(sets.find(v)).or_default().push(v);
        }
        let mut comps: Vec<Vec<usize>> = by_root.into_values().collect();
        comps.sort_by(|a, b| b.len().cmp(&a.len()).then(a[0].cmp(&b[0])));
        comps
    }

    /// `Ok(())` if the graph is connected, else [`Error::Disconnected`] with the component sizes.
    pub fn require_connected(&self) -> Result<()> {
        let comps = self.components();
        if comps.len() == 1 {
            Ok(())
        } else {
            Err(Error::Disconnected {
                component_sizes: comps.iter().map(Vec::len).collect(),
            })
        }
    }

    /// The same nodes with the edges whose `keep` entry is `true` (their information too; the
    /// objective chordal L2, the certifiable one). Panics if `keep.len()` differs from the
    /// number of edges. Errors: none kept ([`Error::Empty`]).
    pub fn edge_subset(&self, keep: &[bool]) -> Result<MultipleProblem> {
        assert_eq!(keep.len(), self.edges.len(), "one flag per edge");
        let edges = self
            .edges
            .iter()
            .zip(keep)
            .filter(|(_, k)| **k)
            .map(|(e, _)| e.clone())
            .collect();
        let sub = MultipleProblem::new(self.num_rotations, edges)?;
        match &self.information {
            Some(info) => sub.with_information(
                info.iter()
                    .zip(keep)
                    .filter(|(_, k)| **k)
                    .map(|(h, _)| *h)
                    .collect(),
            ),
            None => Ok(sub),
        }
    }

    /// The sub-problem on the largest connected component, with nodes renumbered `0..k` in
    /// increasing order, and the map new index -> old index.
    pub fn largest_component(&self) -> (MultipleProblem, Vec<usize>) {
        let keep = self.components().into_iter().next().unwrap_or_default();
        let sub = self
            .induced(&keep)
            .expect("a component's nodes are distinct and in range");
        (sub, keep)
    }

    /// The problem on `nodes` (distinct, each below [`Self::num_rotations`]; node `k` of the
    /// result is `nodes[k]`) with the edges whose both ends are among them, their information
    /// and the objective. Errors: a node out of range or given twice
    /// ([`Error::InvalidSettings`] naming `nodes`).
    ///
    /// ```
    /// use rotavg::multiple::{Edge, MultipleProblem};
    /// use rotavg::Rotation;
    /// let e = |i, j| Edge { i, j, rotation: Rotation::identity(), weight: 1.0 };
    /// let p = MultipleProblem::new(4, vec![e(0, 1), e(2, 3), e(1, 3)])?;
    /// let q = p.induced(&[3, 1])?;
    /// assert_eq!((q.num_rotations(), q.num_edges()), (2, 1));
    /// assert_eq!((q.edges()[0].i, q.edges()[0].j), (1, 0));
    /// assert!(p.induced(&[1, 4]).is_err() && p.induced(&[1, 1]).is_err());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn induced(&self, nodes: &[usize]) -> Result<MultipleProblem> {
        let mut new_of_old = vec![usize::MAX; self.num_rotations];
        for (new, &old) in nodes.iter().enumerate() {
            let bad = |why: &str| Error::InvalidSettings {
                name: "nodes".into(),
                reason: format!("node {old} {why} (the graph has {})", self.num_rotations),
            };
            match new_of_old.get_mut(old) {
                None => return Err(bad("is out of range")),
                Some(slot) if *slot != usize::MAX => return Err(bad("is given twice")),
                Some(slot) => *slot = new,
            }
        }
        let inside = |e: &Edge| new_of_old[e.i] != usize::MAX && new_of_old[e.j] != usize::MAX;
        let kept: Vec<usize> = (0..self.edges.len())
            .filter(|&k| inside(&self.edges[k]))
            .collect();
        let edges = kept
            .iter()
            .map(|&k| Edge {
                i: new_of_old[self.edges[k].i],
                j: new_of_old[self.edges[k].j],
                ..self.edges[k].clone()
            })
            .collect();
        let information = self
            .information
            .as_ref()
            .map(|info| kept.iter().map(|&k| info[k]).collect());
        Ok(MultipleProblem {
            num_rotations: nodes.len(),
            edges,
            information,
            isotropic_information: self.isotropic_information,
            objective: self.objective,
            adjacency: AdjacencyCache::default(),
        })
    }

    /// The same edges with weight `w_e weights[e]` (information `H_e weights[e]`), objective
    /// chordal L2: one pass of iteratively reweighted least squares. Panics if `weights.len()`
    /// differs from the number of edges. Errors: a product outside the weight window.
    pub(crate) fn reweighted(&self, weights: &[f64]) -> Result<MultipleProblem> {
        assert_eq!(weights.len(), self.edges.len(), "one weight per edge");
        let edges = self
            .edges
            .iter()
            .zip(weights)
            .map(|(e, c)| Edge {
                weight: e.weight * c,
                ..e.clone()
            })
            .collect();
        let p = MultipleProblem::new(self.num_rotations, edges)?;
        match &self.information {
            Some(info) => p.with_information(
                info.iter()
                    .zip(weights)
                    .map(|(h, c)| Information::new(h.matrix() * *c))
                    .collect::<Result<_>>()?,
            ),
            None => Ok(p),
        }
    }

    /// The same problem with node `k` renamed `new_of_old[k]` (a permutation of `0..n`; panics
    /// otherwise: a programming error). Edges keep their order, measurements and information.
    pub(crate) fn relabelled(&self, new_of_old: &[usize]) -> MultipleProblem {
        let mut seen = vec![false; self.num_rotations];
        for &k in new_of_old {
            assert!(!std::mem::replace(&mut seen[k], true), "a permutation");
        }
        assert_eq!(new_of_old.len(), self.num_rotations, "a permutation");
        let edges = self
            .edges
            .iter()
            .map(|e| Edge {
                i: new_of_old[e.i],
                j: new_of_old[e.j],
                ..e.clone()
            })
            .collect();
        MultipleProblem {
            edges,
            adjacency: AdjacencyCache::default(),
            ..self.clone()
        }
    }

    /// Chordal L2 cost `sum w_ij ||R_j - R_ij R_i||_F^2` `[M1]` (anisotropic problems: `sum 4 (tr M -
    /// <R_ij M, R_j R_i^T>)`, [`crate::multiple::anisotropic`], evaluated in double-double). Panics if `rotations.len() != n`
    /// (a programming error, not user input: check with [`Self::check_estimate`]).
    ///
    /// ```
    /// use rotavg::multiple::{Edge, MultipleProblem};
    /// use rotavg::so3::{exp, Metric, Rotation};
    /// // One edge measuring a 0.3 rad turn about z; the estimate has both nodes at I.
    /// let rz = exp(&nalgebra::Vector3::new(0.0, 0.0, 0.3));
    /// let p = MultipleProblem::new(2, vec![Edge { i: 0, j: 1, rotation: rz, weight: 2.0 }])?;
    /// let est = vec![Rotation::identity(); 2];
    /// // 2 ||I - Rz||_F^2 = 2 (2 sqrt(2) sin(0.15))^2
    /// assert!((p.chordal_cost(&est) - 2.0 * Metric::Chordal.from_angle(0.3).powi(2)).abs() < 1e-12);
    /// assert!((p.residual_angles(&est)[0] - 0.3).abs() < 1e-12);
    /// assert!(p.chordal_cost(&[Rotation::identity(), rz]) < 1e-24);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn chordal_cost(&self, rotations: &[Rotation]) -> f64 {
        self.assert_estimate(rotations);
        if let Some(info) = &self.information {
            return chordal_cost_compensated(&self.edges, info, rotations);
        }
        self.edges
            .iter()
            .map(|e| {
                e.weight
                    * (rotations[e.j].matrix() - e.rotation.matrix() * rotations[e.i].matrix())
                        .norm_squared()
            })
            .sum()
    }

    /// The cost `sum_e w_e rho(d(R_ij R_i, R_j))` of `rotations` under the problem's objective
    /// (for chordal L2 exactly [`Self::chordal_cost`]). Panics if `rotations.len() != n`.
    pub fn cost(&self, rotations: &[Rotation]) -> f64 {
        if self.objective.is_chordal_l2() {
            return self.chordal_cost(rotations);
        }
        self.objective_angles(rotations)
            .iter()
            .zip(&self.edges)
            .map(|(t, e)| e.weight * self.objective.term(*t))
            .sum()
    }

    /// The angles the objective's loss applies to, per edge, in radians: the residual angles
    /// ([`Self::residual_angles`]) for isotropic weights, the Mahalanobis angles
    /// `theta_H = sqrt(e^T H e / wbar)` for anisotropic measurements (`[A10]`,
    /// [`crate::multiple::anisotropic::mahalanobis_angle`]; equal to the residual angle for
    /// `H = w I`). Robust losses and their inlier thresholds apply to these.
    pub fn objective_angles(&self, rotations: &[Rotation]) -> Vec<f64> {
        let Some(info) = &self.information else {
            return self.residual_angles(rotations);
        };
        self.assert_estimate(rotations);
        self.edges
            .iter()
            .zip(info)
            .map(|(e, h)| {
                crate::multiple::anisotropic::mahalanobis_angle(
                    h,
                    &e.rotation,
                    &rotations[e.i],
                    &rotations[e.j],
                )
            })
            .collect()
    }

    /// Residual angles `theta(R_ij R_i, R_j)` per edge, in radians.
    pub fn residual_angles(&self, rotations: &[Rotation]) -> Vec<f64> {
        self.assert_estimate(rotations);
        self.edges
            .iter()
            .map(|e| angle_between(&(e.rotation * rotations[e.i]), &rotations[e.j]))
            .collect()
    }

    /// Panics unless the estimate has one rotation per node (a programming error: user input
    /// is checked with [`Self::check_estimate`]).
    fn assert_estimate(&self, rotations: &[Rotation]) {
        assert_eq!(
            rotations.len(),
            self.num_rotations,
            "estimate has the wrong number of rotations"
        );
    }

    /// `Ok(())` if an estimate has one rotation per node.
    ///
    /// ```
    /// use rotavg::multiple::{Edge, MultipleProblem};
    /// use rotavg::Rotation;
    /// let p = MultipleProblem::new(2, vec![Edge { i: 0, j: 1, rotation: Rotation::identity(), weight: 1.0 }])?;
    /// assert!(p.check_estimate(&[Rotation::identity(); 2]).is_ok());
    /// assert!(p.check_estimate(&[Rotation::identity(); 3]).is_err());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn check_estimate(&self, rotations: &[Rotation]) -> Result<()> {
        if rotations.len() != self.num_rotations {
            return Err(Error::InvalidSettings {
                name: "estimate".into(),
                reason: format!(
                    "has {} rotations, the problem has {} nodes",
                    rotations.len(),
                    self.num_rotations
                ),
            });
        }
        Ok(())
    }
}

/// `robust` with the estimate `refined` of the component `nodes` in place, in `robust`'s
/// gauge: `R_0 G = I` when node 0 is in the component (as the robust estimate),
/// else the best alignment to the robust estimate, `max tr(G^T sum R_k^T R_v)`; nodes outside
/// the component keep their robust rotations exactly.
pub(crate) fn place_component(
    nodes: &[usize],
    refined: &[Rotation],
    robust: &[Rotation],
) -> Vec<Rotation> {
    let g = if nodes.first() == Some(&0) {
        refined[0].inverse()
    } else {
        let mut m = nalgebra::Matrix3::zeros();
        for (k, &v) in nodes.iter().enumerate() {
            m += refined[k].matrix().transpose() * robust[v].matrix();
        }
        crate::so3::project_to_so3(&m).unwrap_or_else(Rotation::identity)
    };
    let mut estimate = robust.to_vec();
    for (k, &v) in nodes.iter().enumerate() {
        estimate[v] = refined[k] * g;
    }
    if nodes.first() == Some(&0) {
        estimate[0] = Rotation::identity();
    }
    estimate
}

/// Fix the gauge: `R_i -> R_i R_0^T`, so that `R_0 = I`. Costs are invariant.
///
/// ```
/// use rotavg::multiple::{fix_gauge, synthetic::SyntheticGraph};
/// use rotavg::so3::{angle, exp};
/// let (p, truth) = SyntheticGraph { num_rotations: 5, num_edges: 8, ..Default::default() }.generate();
/// let g = exp(&nalgebra::Vector3::new(0.5, 0.1, -0.3));
/// let mut rotated: Vec<_> = truth.iter().map(|r| r * g).collect(); // R_i -> R_i G
/// assert!((p.chordal_cost(&rotated) - p.chordal_cost(&truth)).abs() < 1e-12);
/// fix_gauge(&mut rotated);
/// assert!(angle(&rotated[0]) < 1e-15);
/// ```
pub fn fix_gauge(rotations: &mut [Rotation]) {
    if let Some(r0) = rotations.first().copied() {
        let g = r0.inverse();
        for r in rotations.iter_mut() {
            *r *= g;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The adjacency made once is the graph's: a problem asked for it equals one never asked,
    /// a relabelled or reweighted copy makes its own (each edge at both endpoints, against the
    /// edge list), and the lists are those of a fresh build.
    #[test]
    fn the_kept_adjacency_is_the_graphs() {
        let e = |i, j| Edge {
            i,
            j,
            rotation: Rotation::identity(),
            weight: 1.0,
        };
        let p = MultipleProblem::new(4, vec![e(0, 1), e(1, 2), e(2, 3), e(3, 0), e(0, 2)]).unwrap();
        let fresh = p.clone();
        let _ = p.adjacency();
        assert_eq!(p, fresh);
        let listed = |q: &MultipleProblem| -> Vec<Vec<(usize, usize)>> {
            (0..q.num_rotations())
                .map(|v| q.adjacency().neighbours(v).to_vec())
                .collect()
        };
        let expected = |q: &MultipleProblem| -> Vec<Vec<(usize, usize)>> {
            let mut at = vec![Vec::new(); q.num_rotations()];
            for (k, e) in q.edges().iter().enumerate() {
                at[e.i].push((e.j, k));
                at[e.j].push((e.i, k));
            }
            at
        };
        assert_eq!(listed(&p), expected(&p));
        let moved = p.relabelled(&[3, 2, 1, 0]);
        assert_eq!(listed(&moved), expected(&moved));
        assert_ne!(listed(&moved), listed(&p));
        let heavier = p.reweighted(&[2.0; 5]).unwrap();
        assert_eq!(listed(&heavier), expected(&heavier));
    }

    /// Deserialisation validates: a problem round-trips (with its information), and a bad
    /// index, a missing information or a non-positive weight is an error, never a panic or an
    /// unvalidated problem.
    #[test]
    fn deserialisation_validates() {
        let (p, _) = crate::multiple::synthetic::SyntheticAnisotropic {
            num_rotations: 5,
            num_edges: 8,
            ..Default::default()
        }
        .generate();
        let text = serde_json::to_string(&p).unwrap();
        let back: MultipleProblem = serde_json::from_str(&text).unwrap();
        assert_eq!(back, p);
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["information"].as_array_mut().unwrap().pop();
        let err = serde_json::from_value::<MultipleProblem>(v).unwrap_err();
        assert!(err.to_string().contains("7 matrices for 8 edges"), "{err}");
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v["edges"][0]["j"] = serde_json::json!(9);
        assert!(serde_json::from_value::<MultipleProblem>(v).is_err());
        let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
        v.as_object_mut().unwrap().remove("information");
        v["edges"][0]["weight"] = serde_json::json!(-1.0);
        assert!(serde_json::from_value::<MultipleProblem>(v).is_err());
    }
}
