//! Trace couplings between two frames of a rig (`paper-notes/conjugate.md` `[H21]`, "Trace
//! couplings"): on every rig point `tr(X_(g,s)^T X_(f,s)) = tr(F_g^T F_f)` is the same for every
//! sensor `s`, so scalars `mu_s` of zero sum over the sensors, as pseudo-edges of weighted sum
//! `-mu_s I` from image `(f, s)` to image `(g, s)`, add a constant to the images' view graph's
//! cost (the relaxation's redundant constraints `[H14]` couples for two graphs). Their torques
//! at the two frames are opposite in rig coordinates and of zero sum over each frame's sensors:
//! flows within each frame balance them (so the estimate stays critical), and those flows sum to
//! zero over the frames (so the within-frame couplings' identity holds).

use crate::linalg::compensated::Accumulator;
use crate::multiple::Edge;
use crate::so3::{Rotation, vee};
use nalgebra::{DMatrix, Matrix3, Vector3};

/// Pairs of frames coupled by their traces, and each pair's scalars, one per local sensor (the
/// frames' sensors in the same order).
#[derive(Debug, Clone, Default)]
pub(crate) struct Traces {
    pub pairs: Vec<(usize, usize)>,
    pub mu: Vec<Vec<f64>>,
}

/// Most pairs of frames coupled by traces in the search (its variables: one per pair and
/// sensor).
const MAX_TRACE_PAIRS: usize = 2000;

impl Traces {
    /// No trace couplings.
    pub fn none() -> Self {
        Self::default()
    }

    /// The pairs of frames joined by an edge of the images' view graph within one sensor
    /// (`image` maps an image to its frame and local sensor), at most [`MAX_TRACE_PAIRS`], their
    /// scalars zero.
    pub fn between(
        edges: impl Iterator<Item = (usize, usize)>,
        image: &[(usize, usize)],
        sensors: usize,
    ) -> Self {
        let mut pairs: Vec<(usize, usize)> = edges
            .filter_map(|(a, b)| {
                let ((f, s), (g, t)) = (*image.get(a)?, *image.get(b)?);
                (s == t && f != g).then_some((f.min(g), f.max(g)))
            })
            .collect();
        pairs.sort_unstable();
        pairs.dedup();
        pairs.truncate(MAX_TRACE_PAIRS);
        let mu = vec![vec![0.0; sensors]; pairs.len()];
        Traces { pairs, mu }
    }

    /// The scalars `a + b`.
    pub fn added(&self, other: &Traces) -> Traces {
        let mu = (self.mu.iter().zip(&other.mu))
            .map(|(a, b)| a.iter().zip(b).map(|(a, b)| a + b).collect())
            .collect();
        Traces {
            pairs: self.pairs.clone(),
            mu,
        }
    }

    /// Every pair's scalars with their mean over the sensors removed.
    pub fn project(&mut self) {
        for m in &mut self.mu {
            let mean = m.iter().sum::<f64>() / m.len().max(1) as f64;
            m.iter_mut().for_each(|v| *v -= mean);
        }
    }

    /// `tau_p = vee(skew(F_g F_f^T))` of each pair in rig coordinates (from the images of
    /// local sensor 0, `X = S F`: `S_s^T vee(skew(X_b X_a^T))`): the demand at `(f, s)` changes
    /// by `-mu_s tau_p` and at `(g, s)` by `+mu_s tau_p`.
    pub fn torques(
        &self,
        per_frame: &[Vec<(usize, usize)>],
        x: &[Rotation],
        sensors: &[Rotation],
    ) -> Vec<Vector3<f64>> {
        self.pairs
            .iter()
            .map(|&(f, g)| {
                let (s, a) = per_frame[f][0];
                let b = per_frame[g][0].1;
                let m = x[b].matrix() * x[a].matrix().transpose();
                sensors[s].matrix().transpose() * vee(&m)
            })
            .collect()
    }

    /// Each frame's change of demand per local sensor (rig coordinates), `tau` from
    /// [`Self::torques`] already in rig coordinates.
    pub fn demands(&self, frames: usize, tau: &[Vector3<f64>]) -> Vec<Vec<Vector3<f64>>> {
        let k = self.mu.first().map_or(0, Vec::len);
        let mut d = vec![vec![Vector3::zeros(); k]; frames];
        for ((&(f, g), m), t) in self.pairs.iter().zip(&self.mu).zip(tau) {
            for (i, mu) in m.iter().enumerate() {
                d[f][i] -= *mu * t;
                d[g][i] += *mu * t;
            }
        }
        d
    }

    /// Adds the couplings' part of `S` (the pseudo-edges' Laplacian less the multipliers they
    /// add): `mu I` in blocks `(a, b)` and `(b, a)`, `-mu sym(X_b X_a^T)` on `a`'s diagonal
    /// block and `-mu sym(X_a X_b^T)` on `b`'s.
    pub fn add_to(&self, s: &mut DMatrix<f64>, per_frame: &[Vec<(usize, usize)>], x: &[Rotation]) {
        for (&(f, g), m) in self.pairs.iter().zip(&self.mu) {
            for (i, &mu) in m.iter().enumerate() {
                let (a, b) = (per_frame[f][i].1, per_frame[g][i].1);
                let ba = x[b].matrix() * x[a].matrix().transpose();
                let sym = 0.5 * (ba + ba.transpose());
                for (r, c, block) in [
                    (a, b, mu * Matrix3::identity()),
                    (b, a, mu * Matrix3::identity()),
                    (a, a, -mu * sym),
                    (b, b, -mu * sym),
                ] {
                    let mut view = s.fixed_view_mut::<3, 3>(3 * r, 3 * c);
                    view += block;
                }
            }
        }
    }

    /// The gradient of `tr(W S)` (`W = sym(v w^T)`, `block(r, c)` its `3 x 3` block) in the
    /// scalars through the blocks of [`Self::add_to`] alone (the balancing flows' part is the
    /// caller's, through [`Self::demands`]' adjoint).
    pub fn gradient(
        &self,
        per_frame: &[Vec<(usize, usize)>],
        x: &[Rotation],
        block: impl Fn(usize, usize) -> Matrix3<f64>,
    ) -> Vec<Vec<f64>> {
        (self.pairs.iter().zip(&self.mu))
            .map(|(&(f, g), m)| {
                (0..m.len())
                    .map(|i| {
                        let (a, b) = (per_frame[f][i].1, per_frame[g][i].1);
                        let ba = x[b].matrix() * x[a].matrix().transpose();
                        let sym = 0.5 * (ba + ba.transpose());
                        (block(a, b) + block(b, a)).trace()
                            - (block(a, a) + block(b, b)).component_mul(&sym).sum()
                    })
                    .collect()
            })
            .collect()
    }

    /// The pseudo-edges: for `mu < 0` one edge `(f, s) -> (g, s)` of rotation `I` and weight
    /// `|mu|`; for `mu > 0` three of weight `mu`, the half-turns about the axes (`diag(1, -1, -1)`
    /// and its permutations, summing to `-I`); both exact in floating point, so the pair's sum is
    /// `-mu I` exactly. Those outside `[1e-100, 1e100]` are dropped (any pseudo-edges give a
    /// sound bound).
    pub fn pseudo_edges(&self, per_frame: &[Vec<(usize, usize)>]) -> Vec<Edge> {
        let mut out = Vec::new();
        for (&(f, g), m) in self.pairs.iter().zip(&self.mu) {
            for (i, &mu) in m.iter().enumerate() {
                if !(mu.abs() >= 1e-100 && mu.abs() <= 1e100) {
                    continue;
                }
                let (a, b) = (per_frame[f][i].1, per_frame[g][i].1);
                let rotations: Vec<Matrix3<f64>> = if mu < 0.0 {
                    vec![Matrix3::identity()]
                } else {
                    (0..3)
                        .map(|axis| {
                            let mut d = Vector3::from_element(-1.0);
                            d[axis] = 1.0;
                            Matrix3::from_diagonal(&d)
                        })
                        .collect()
                };
                for r in rotations {
                    out.push(Edge {
                        i: a,
                        j: b,
                        rotation: Rotation::from_matrix_unchecked(r),
                        weight: mu.abs(),
                    });
                }
            }
        }
        out
    }

    /// What the pseudo-edges add on a rig point beyond their constant `6 sum c`: `2 (sum_s mu_s)
    /// tr(F_g^T F_f)` per pair, at most `6 |sum_s mu_s|`, each sum in double-double with its error
    /// bound: the charge.
    pub fn charge(&self) -> f64 {
        let mut charge = 0.0;
        for m in &self.mu {
            let mut sum = Accumulator::default();
            m.iter().for_each(|&v| sum.add_product(v, 1.0));
            charge += 6.0 * (sum.value().abs() + sum.bound());
        }
        charge * (1.0 + 1e-14)
    }
}
