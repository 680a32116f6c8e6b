//! The estimate's frames of the edges for the `conv(SO(3))` dual certificate
//! (`paper-notes/anisotropic.md` `[A11]`): each edge's relative rotation and linear coefficient
//! there, and `S'(P) = S - 1/2 sum_e B_e^T P_e B_e` assembled in the analysed pattern of `S`
//! for shift-invert Lanczos (the search of [`super::conv_dual`], the node shifts of
//! [`super::conv_shifts`]).

use crate::error::{Error, Result};
use crate::linalg::cholesky::ShiftedCholesky;
use crate::linalg::{Extreme, LanczosSettings, lanczos};
use crate::multiple::anisotropic::Information;
use crate::multiple::{Edge, MultipleProblem};
use crate::so3::Rotation;
use faer::sparse::SparseColMat;
use nalgebra::Matrix3;
use std::time::Instant;

/// The estimate's relative rotation `X_e = R_j R_i^T` and the edge's linear coefficient in its
/// frame, `K_e = X_e^T N_e`.
pub(super) struct Frame {
    pub(super) x: Matrix3<f64>,
    pub(super) k: Matrix3<f64>,
    /// The edge's `2M` has an exactly zero row (information `w diag(1, 1, 0)`-like: a soft
    /// gravity prior's edge to the world node, `paper-notes/gravity.md` `[G10]`): it carries no
    /// penalty (`P_e = 0` is in the cone), so the surrogate keeps its data exactly and the
    /// world node's two unseen coordinates stay exactly outside every edge (`[A11]` "Edges
    /// that see two coordinates").
    pub(super) fixed: bool,
}

pub(super) fn edge_coefficient(edge: &Edge, h: &Matrix3<f64>) -> Matrix3<f64> {
    edge.rotation.matrix() * (Matrix3::identity() * (2.0 * h.trace()) - h * 4.0)
}

pub(super) fn frames(problem: &MultipleProblem, rotations: &[Rotation]) -> Result<Vec<Frame>> {
    let info = anisotropic(problem)?;
    Ok(problem
        .edges()
        .iter()
        .zip(info)
        .map(|(e, h)| {
            let x = rotations[e.j].matrix() * rotations[e.i].matrix().transpose();
            let k = x.transpose() * edge_coefficient(e, h.matrix());
            let fixed = h.sees_two_coordinates();
            Frame { x, k, fixed }
        })
        .collect())
}

pub(super) fn anisotropic(problem: &MultipleProblem) -> Result<&[Information]> {
    problem.information().ok_or_else(|| Error::InvalidSettings {
        name: "dual.conv".into(),
        reason: "the conv(SO(3)) dual certificate needs information matrices".into(),
    })
}

/// Positions of an edge's 36 entries of `S` in its stored values: the blocks `(i, i)`,
/// `(j, j)`, `(i, j)`, `(j, i)`, each row-major.
type EdgePositions = [usize; 36];

/// Shift-invert rounds: the analysis of `S'`'s pattern, `S`'s values and where each edge adds.
pub(super) struct Inverse {
    pub(super) cholesky: ShiftedCholesky,
    base: Vec<f64>,
    pub(super) positions: Vec<EdgePositions>,
    shift: f64,
}

impl Inverse {
    /// `None` when a block entry is not stored or the factor is too large.
    pub(super) fn new(
        s: &SparseColMat<usize, f64>,
        edges: &[Edge],
        max_values: usize,
    ) -> Result<Option<Inverse>> {
        let cp = s.symbolic().col_ptr();
        let ri = s.symbolic().row_idx();
        let find = |row: usize, col: usize| -> Option<usize> {
            let range = cp[col]..cp[col + 1];
            ri[range.clone()]
                .binary_search(&row)
                .ok()
                .map(|k| range.start + k)
        };
        let mut positions = Vec::with_capacity(edges.len());
        for e in edges {
            let mut p = [0usize; 36];
            let blocks = [(e.i, e.i), (e.j, e.j), (e.i, e.j), (e.j, e.i)];
            for (b, &(r, c)) in blocks.iter().enumerate() {
                for a in 0..3 {
                    for d in 0..3 {
                        match find(3 * r + a, 3 * c + d) {
                            Some(k) => p[9 * b + 3 * a + d] = k,
                            None => return Ok(None),
                        }
                    }
                }
            }
            positions.push(p);
        }
        let base = s.val().to_vec();
        // the forming bound is not used: these factorisations only estimate eigenvectors
        Ok(ShiftedCholesky::new_within(s.clone(), 1, max_values)?
            .ok()
            .map(|cholesky| Inverse {
                cholesky,
                base,
                positions,
                shift: 0.0,
            }))
    }

    /// Overwrite the analysed values with those of `S'(P)`.
    pub(super) fn assemble(&mut self, frames: &[Frame], penalties: &[Matrix3<f64>]) {
        let values = self.cholesky.values_mut();
        values.copy_from_slice(&self.base);
        for ((pos, f), p) in self.positions.iter().zip(frames).zip(penalties) {
            let x = &f.x;
            let blocks = [
                -p * 0.5,
                -(x * p * x.transpose()) * 0.5,
                p * x.transpose() * 0.5,
                x * p * 0.5,
            ];
            for (b, block) in blocks.iter().enumerate() {
                for a in 0..3 {
                    for d in 0..3 {
                        values[pos[9 * b + 3 * a + d]] += block[(a, d)];
                    }
                }
            }
        }
    }
}

/// Ritz pairs `(lambda, vector)` of the assembled matrix's smallest eigenvalues (ascending), and
/// whether Lanczos converged.
pub(super) type Smallest = (Vec<(f64, Vec<f64>)>, bool);

impl Inverse {
    /// The `count` smallest eigenpairs of the assembled matrix (estimates): the largest
    /// eigenvalues `theta` of `(T + sigma I)^-1` by Lanczos (`settings`, deflated by `null`),
    /// `lambda = 1 / theta - sigma`. The smallest shift that factors separates the negative
    /// eigenvalues best (a large one clusters every `1 / (lambda + sigma)` near `1 / sigma`):
    /// `sigma` from a quarter of the last one's, at least `floor`, raised fourfold until it
    /// factors, at most `attempts` times and never past `deadline`; `None` when none did.
    pub(super) fn smallest(
        &mut self,
        (count, floor): (usize, f64),
        (settings, null): (&LanczosSettings, &[Vec<f64>]),
        (attempts, deadline): (usize, Option<Instant>),
    ) -> Option<Smallest> {
        let dim = self.cholesky.dim();
        let mut shift = (self.shift / 4.0).max(floor);
        for _ in 0..attempts {
            if deadline.is_some_and(|d| Instant::now() >= d) {
                return None;
            }
            let Some(factor) = self.cholesky.factor(shift, f64::INFINITY) else {
                shift *= 4.0;
                continue;
            };
            let op = |x: &[f64], y: &mut [f64]| {
                y.copy_from_slice(x);
                factor.solve_in_place(y);
            };
            let est = lanczos(
                dim,
                op,
                Extreme::Largest,
                count,
                1.0 / shift,
                settings,
                null,
                None,
            );
            let mut pairs: Vec<(f64, Vec<f64>)> = (est.values.iter().zip(est.vectors))
                .filter(|(theta, _)| **theta > 0.0)
                .map(|(theta, v)| (1.0 / theta - shift, v))
                .collect();
            pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
            self.shift = shift;
            return Some((pairs, est.stop.converged()));
        }
        None
    }
}
