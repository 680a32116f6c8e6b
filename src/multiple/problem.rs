//! The validated multiple-rotation-averaging problem: nodes, edges, weights, cost.

use crate::error::{Error, Result};
use crate::so3::{Rotation, angle_between};
use serde::{Deserialize, Serialize};

/// One measured edge: `rotation = R_ij` with `R_ij R_i = R_j`, weight `w_ij > 0`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Edge {
    /// Tail node `i` (0-based).
    pub i: usize,
    /// Head node `j` (0-based).
    pub j: usize,
    /// The relative rotation `R_ij`, with `R_ij R_i = R_j`.
    #[serde(with = "crate::serde_rot::rotation")]
    pub rotation: Rotation,
    /// Weight `w_ij` (finite, > 0).
    pub weight: f64,
}

impl Edge {
    /// The same measurement expressed as an edge `(j, i)`: `R_ji = R_ij^T`.
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
/// [`MultipleProblem::require_connected`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MultipleProblem {
    num_rotations: usize,
    edges: Vec<Edge>,
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
            if !(e.weight.is_finite() && e.weight > 0.0) {
                return Err(Error::InvalidWeight {
                    item: format!("edge {k} ({}, {})", e.i, e.j),
                    weight: e.weight,
                });
            }
            if !e.rotation.matrix().iter().all(|x| x.is_finite()) {
                return Err(Error::NonFinite {
                    item: format!("edge {k} ({}, {})", e.i, e.j),
                });
            }
        }
        Ok(MultipleProblem {
            num_rotations,
            edges,
        })
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

    /// Connected components as node lists, largest first (ties: smallest first node first).
    pub fn components(&self) -> Vec<Vec<usize>> {
        let n = self.num_rotations;
        let mut parent: Vec<usize> = (0..n).collect();
        fn find(p: &mut [usize], mut x: usize) -> usize {
            while p[x] != x {
                p[x] = p[p[x]];
                x = p[x];
            }
            x
        }
        for e in &self.edges {
            let (a, b) = (find(&mut parent, e.i), find(&mut parent, e.j));
            if a != b {
                parent[a.max(b)] = a.min(b);
            }
        }
        let mut by_root: std::collections::BTreeMap<usize, Vec<usize>> = Default::default();
        for v in 0..n {
            let r = find(&mut parent, v);
            by_root.entry(r).or_default().push(v);
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

    /// The sub-problem on the largest connected component, with nodes renumbered `0..k` in
    /// increasing order, and the map new index -> old index.
    pub fn largest_component(&self) -> (MultipleProblem, Vec<usize>) {
        let comps = self.components();
        let keep = comps.into_iter().next().unwrap_or_default();
        let mut new_of_old = vec![usize::MAX; self.num_rotations];
        for (new, &old) in keep.iter().enumerate() {
            new_of_old[old] = new;
        }
        let edges = self
            .edges
            .iter()
            .filter(|e| new_of_old[e.i] != usize::MAX)
            .map(|e| Edge {
                i: new_of_old[e.i],
                j: new_of_old[e.j],
                ..e.clone()
            })
            .collect();
        (
            MultipleProblem {
                num_rotations: keep.len(),
                edges,
            },
            keep,
        )
    }

    /// Chordal L2 cost `sum w_ij ||R_j - R_ij R_i||_F^2` `[M1]`. Panics if `rotations.len() != n`
    /// (a programming error, not user input: check with [`Self::check_estimate`]).
    pub fn chordal_cost(&self, rotations: &[Rotation]) -> f64 {
        assert_eq!(
            rotations.len(),
            self.num_rotations,
            "estimate has the wrong number of rotations"
        );
        self.edges
            .iter()
            .map(|e| {
                e.weight
                    * (rotations[e.j].matrix() - e.rotation.matrix() * rotations[e.i].matrix())
                        .norm_squared()
            })
            .sum()
    }

    /// Residual angles `theta(R_ij R_i, R_j)` per edge, in radians.
    pub fn residual_angles(&self, rotations: &[Rotation]) -> Vec<f64> {
        assert_eq!(
            rotations.len(),
            self.num_rotations,
            "estimate has the wrong number of rotations"
        );
        self.edges
            .iter()
            .map(|e| angle_between(&(e.rotation * rotations[e.i]), &rotations[e.j]))
            .collect()
    }

    /// `Ok(())` if an estimate has one rotation per node.
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

/// Fix the gauge: `R_i -> R_i R_0^T`, so that `R_0 = I`. Costs are invariant.
pub fn fix_gauge(rotations: &mut [Rotation]) {
    if let Some(r0) = rotations.first().copied() {
        let g = r0.inverse();
        for r in rotations.iter_mut() {
            *r *= g;
        }
    }
}
