//! The validated conjugate (hand-eye) rotation-averaging problem: pairs `(L_i, R_i)` with
//! weights, `R_i ~ S^-1 L_i S` (contract section 1), the chordal cost `g(S)` and data diagnostics
//! (angle mismatch, uninformative pairs, identifiability). Equations: `paper-notes/conjugate.md`.

use crate::error::{Error, Result};
use crate::objective::{Loss, Objective};
use crate::so3::{Metric, Rotation, angle, log, quaternion_distance};
use crate::validate::{check_weight, non_negative};
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use serde::{Deserialize, Serialize};

/// One measured pair: `left = L_i`, `right = R_i` with `R_i ~ S^-1 L_i S` (equivalently
/// `L_i S ~ S R_i`), weight `w_i > 0`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(expecting = "a pair {\"left\": L, \"right\": R, \"weight\": w} (weight optional)")]
pub struct ConjugatePair {
    /// `L_i`.
    #[serde(with = "crate::so3::serde_rows::rotation")]
    pub left: Rotation,
    /// `R_i`.
    #[serde(with = "crate::so3::serde_rows::rotation")]
    pub right: Rotation,
    /// Weight `w_i` in `[1e-100, 1e100]`; 1 when absent from JSON.
    #[serde(default = "one")]
    pub weight: f64,
}

fn one() -> f64 {
    1.0
}

impl ConjugatePair {
    /// A pair with weight 1.
    pub fn new(left: Rotation, right: Rotation) -> Self {
        ConjugatePair {
            left,
            right,
            weight: 1.0,
        }
    }
}

/// A validated conjugate problem: at least one pair, finite positive weights, exact rotations.
/// Identifiability is *not* required by the type (see [`ConjugateProblem::identifiability`]);
/// the solvers refuse data that do not determine `S`. Deserialisation validates like
/// [`ConjugateProblem::new`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawConjugateProblem")]
pub struct ConjugateProblem {
    pairs: Vec<ConjugatePair>,
    #[serde(skip)]
    objective: Objective,
}

/// Unvalidated serde form of [`ConjugateProblem`].
#[derive(Deserialize)]
#[serde(expecting = "a conjugate problem {\"pairs\": [{\"left\": L, \"right\": R}, ...]}")]
struct RawConjugateProblem {
    pairs: Vec<ConjugatePair>,
}

impl TryFrom<RawConjugateProblem> for ConjugateProblem {
    type Error = Error;
    fn try_from(raw: RawConjugateProblem) -> Result<Self> {
        ConjugateProblem::new(raw.pairs)
    }
}

/// Thresholds of [`ConjugateProblem::diagnose`] and of the identifiability test.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DiagnosticSettings {
    /// A pair whose `L_i` and `R_i` both have rotation angle below this (radians) carries no
    /// information about `S` (default `1e-2` rad = 0.57 deg).
    pub min_rotation_angle: f64,
    /// Axis spread (radians, see [`Identifiability`]) below which the axes count as parallel
    /// (default `1e-2` rad).
    pub min_axis_spread: f64,
    /// A pair whose angle mismatch `|angle(L_i) - angle(R_i)|` exceeds this (radians) is flagged
    /// as suspicious (default `5` degrees).
    pub max_angle_mismatch: f64,
}

impl DiagnosticSettings {
    /// Check every value; [`Error::InvalidSettings`] names the first bad one (each must be
    /// finite and >= 0).
    pub fn validate(&self) -> Result<()> {
        non_negative("diagnostics.min_rotation_angle", self.min_rotation_angle)?;
        non_negative("diagnostics.min_axis_spread", self.min_axis_spread)?;
        non_negative("diagnostics.max_angle_mismatch", self.max_angle_mismatch)
    }
}

impl Default for DiagnosticSettings {
    fn default() -> Self {
        DiagnosticSettings {
            min_rotation_angle: 1e-2,
            min_axis_spread: 1e-2,
            max_angle_mismatch: 5f64.to_radians(),
        }
    }
}

/// Whether the data determine `S` `[H5]`. `L_i = S R_i S^T` maps the rotation axis of `R_i` to
/// that of `L_i`; `S` is unique iff the axes of the informative pairs (angle above
/// `min_rotation_angle`) are not all parallel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum Identifiability {
    /// `S` is determined. `axis_spread = 2 atan(sqrt(lambda_2 / lambda_1))` of the weighted axis
    /// scatter matrix of the `R_i` (for two axes at angle `phi`, the spread is `phi`).
    Determined {
        /// Axis spread in radians.
        axis_spread: f64,
        /// Number of informative pairs.
        informative_pairs: usize,
    },
    /// No pair has a rotation angle above the threshold: nothing constrains `S`.
    AllAnglesSmall {
        /// The largest rotation angle among the pairs (radians).
        max_angle: f64,
    },
    /// All informative axes are (nearly) parallel: `S` is determined only up to a rotation about
    /// the common axis (planar or single-axis motion).
    ParallelAxes {
        /// The common axis of the `R_i` (unit vector).
        axis: [f64; 3],
        /// Axis spread in radians (below the threshold).
        axis_spread: f64,
    },
}

impl Identifiability {
    /// `true` for [`Identifiability::Determined`].
    pub fn is_determined(&self) -> bool {
        matches!(self, Identifiability::Determined { .. })
    }

    /// An error explaining why `S` is not determined (`None` when it is).
    pub fn to_error(&self) -> Option<Error> {
        match self {
            Identifiability::Determined { .. } => None,
            Identifiability::AllAnglesSmall { max_angle } => Some(Error::Degenerate {
                reason: format!(
                    "every pair has a rotation angle of at most {:.3e} deg: the data carry no information about S (move the robot through rotations, not only translations)",
                    max_angle.to_degrees()
                ),
            }),
            Identifiability::ParallelAxes { axis, axis_spread } => Some(Error::Degenerate {
                reason: format!(
                    "all rotation axes are parallel (axis spread {:.3e} deg, common axis of R_i [{:.4}, {:.4}, {:.4}]): S is determined only up to a rotation about that axis; add motions about a second axis",
                    axis_spread.to_degrees(),
                    axis[0],
                    axis[1],
                    axis[2]
                ),
            }),
        }
    }
}

/// Data diagnostics of a conjugate problem (see [`ConjugateProblem::diagnose`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Diagnostics {
    /// `|angle(L_i) - angle(R_i)|` per pair (radians): zero for exact data, because conjugation
    /// preserves the rotation angle `[H4]`.
    pub angle_mismatch: Vec<f64>,
    /// Median of `angle_mismatch`.
    pub median_angle_mismatch: f64,
    /// Maximum of `angle_mismatch`.
    pub max_angle_mismatch: f64,
    /// Pairs whose mismatch exceeds the threshold (mis-paired or corrupted data), 0-based.
    pub suspicious_pairs: Vec<usize>,
    /// Pairs whose `L_i` and `R_i` both have angle below the threshold (no information).
    pub small_rotation_pairs: Vec<usize>,
    /// Whether `S` is determined.
    pub identifiability: Identifiability,
}

impl ConjugateProblem {
    /// Validate and build. Errors: no pairs, a non-finite or non-positive weight.
    ///
    /// ```
    /// use rotavg::conjugate::{ConjugatePair, ConjugateProblem};
    /// use rotavg::so3::exp;
    /// use nalgebra::Vector3;
    /// let s = exp(&Vector3::new(0.1, 0.2, 0.3));
    /// let pair = |v: Vector3<f64>| {
    ///     let r = exp(&v);
    ///     ConjugatePair::new(s * r * s.inverse(), r)
    /// };
    /// let p = ConjugateProblem::new(vec![pair(Vector3::x()), pair(Vector3::y())]).unwrap();
    /// assert!(p.chordal_cost(&s) < 1e-20);
    /// assert!(ConjugateProblem::new(vec![]).is_err());
    /// ```
    pub fn new(pairs: Vec<ConjugatePair>) -> Result<Self> {
        if pairs.is_empty() {
            return Err(Error::Empty {
                what: "the list of conjugate pairs".into(),
            });
        }
        for (k, p) in pairs.iter().enumerate() {
            check_weight(|| format!("pair {k}"), p.weight)?;
            let finite = p.left.matrix().iter().all(|x| x.is_finite())
                && p.right.matrix().iter().all(|x| x.is_finite());
            if !finite {
                return Err(Error::NonFinite {
                    item: format!("pair {k}"),
                });
            }
        }
        Ok(ConjugateProblem {
            pairs,
            objective: Objective::CHORDAL_L2,
        })
    }

    /// The objectives with a solver: chordal or geodesic with any loss, quaternion with l2.
    pub const SUPPORTED: &'static str =
        "chordal or geodesic with l2, l1, huber or cauchy; quaternion with l2";

    /// The same pairs with another objective (default chordal L2, the certifiable one).
    /// [`Error::InvalidSettings`] (field `objective`) when there is no solver for it or a
    /// robust threshold is bad.
    ///
    /// ```
    /// use rotavg::conjugate::ConjugateProblem;
    /// use rotavg::objective::{Loss, Objective};
    /// use rotavg::so3::{exp, Metric, Rotation};
    /// use nalgebra::Vector3;
    /// // One pair with L = Rz(0.3), R = I: for S = I the residual angle is 0.3.
    /// let p = ConjugateProblem::from_rotations(&[exp(&Vector3::new(0.0, 0.0, 0.3))], &[Rotation::identity()])?;
    /// let id = Rotation::identity();
    /// let l1 = p.clone().with_objective(Objective::new(Metric::Geodesic, Loss::L1))?;
    /// assert!((l1.cost(&id) - 0.3).abs() < 1e-12);
    /// // Chordal L2 (the default) is g(S).
    /// assert!((p.cost(&id) - p.chordal_cost(&id)).abs() < 1e-12);
    /// assert!(p.with_objective(Objective::new(Metric::Quaternion, Loss::L1)).is_err());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn with_objective(mut self, objective: Objective) -> Result<Self> {
        objective.validate()?;
        if objective.metric == Metric::Quaternion && objective.loss != Loss::L2 {
            return Err(objective.unsupported("conjugate", Self::SUPPORTED));
        }
        self.objective = objective;
        Ok(self)
    }

    /// The objective minimised.
    pub fn objective(&self) -> Objective {
        self.objective
    }

    /// The cost `sum_i w_i rho(d(R_i, S^T L_i S))` of `s` under the problem's objective (for
    /// chordal L2 this is `g(S)` `[H1]`).
    pub fn cost(&self, s: &Rotation) -> f64 {
        self.cost_under(s, self.objective)
    }

    /// The cost of `s` under another objective.
    pub fn cost_under(&self, s: &Rotation, objective: Objective) -> f64 {
        self.pairs
            .iter()
            .map(|p| {
                p.weight * objective.rho(pair_distance(objective.metric, s, &p.left, &p.right))
            })
            .sum()
    }

    /// Build from parallel slices of `L_i` and `R_i`, all weights 1.
    ///
    /// ```
    /// use rotavg::conjugate::ConjugateProblem;
    /// use rotavg::so3::{exp, Rotation};
    /// use nalgebra::Vector3;
    /// let s = exp(&Vector3::new(0.1, 0.2, 0.3));
    /// let r = exp(&Vector3::new(0.0, 0.5, 0.0));
    /// let p = ConjugateProblem::from_rotations(&[s * r * s.inverse()], &[r])?;
    /// assert!(p.chordal_cost(&s) < 1e-28 && p.residual_angles(&s)[0] < 1e-7);
    /// assert!(ConjugateProblem::from_rotations(&[Rotation::identity()], &[]).is_err()); // lengths differ
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn from_rotations(left: &[Rotation], right: &[Rotation]) -> Result<Self> {
        if left.len() != right.len() {
            return Err(Error::InvalidSettings {
                name: "pairs".into(),
                reason: format!(
                    "{} left rotations but {} right rotations",
                    left.len(),
                    right.len()
                ),
            });
        }
        Self::new(
            left.iter()
                .zip(right)
                .map(|(l, r)| ConjugatePair::new(*l, *r))
                .collect(),
        )
    }

    /// The pairs.
    pub fn pairs(&self) -> &[ConjugatePair] {
        &self.pairs
    }

    /// Number of pairs.
    pub fn num_pairs(&self) -> usize {
        self.pairs.len()
    }

    /// The smallest pair weight: the scale of the absolute part of the certificate's gap
    /// tolerance (contract section 3; adding pairs can only lower it).
    pub fn min_weight(&self) -> f64 {
        crate::validate::min_weight(self.pairs.iter().map(|p| p.weight))
    }

    /// Sum of the weights.
    pub fn total_weight(&self) -> f64 {
        self.pairs.iter().map(|p| p.weight).sum()
    }

    /// The chordal cost `g(S) = sum_i w_i ||S R_i - L_i S||_F^2` `[H1]`.
    pub fn chordal_cost(&self, s: &Rotation) -> f64 {
        let sm = s.matrix();
        self.pairs
            .iter()
            .map(|p| p.weight * (sm * p.right.matrix() - p.left.matrix() * sm).norm_squared())
            .sum()
    }

    /// Residual angles `theta(R_i, S^T L_i S)` (radians), one per pair.
    pub fn residual_angles(&self, s: &Rotation) -> Vec<f64> {
        self.pairs
            .iter()
            .map(|p| angle(&(p.left.inverse() * s * p.right * s.inverse())))
            .collect()
    }

    /// Identifiability test `[H5]` with the given thresholds.
    ///
    /// ```
    /// use rotavg::conjugate::{ConjugateProblem, Identifiability};
    /// use rotavg::so3::exp;
    /// use nalgebra::Vector3;
    /// // Every R_i about the z axis (planar motion): S is not determined about z.
    /// let rs = [exp(&Vector3::new(0.0, 0.0, 0.5)), exp(&Vector3::new(0.0, 0.0, 1.0))];
    /// let p = ConjugateProblem::from_rotations(&rs, &rs)?;
    /// let id = p.identifiability(&Default::default());
    /// assert!(matches!(id, Identifiability::ParallelAxes { .. }));
    /// assert!(p.require_identifiable(&Default::default()).is_err());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn identifiability(&self, settings: &DiagnosticSettings) -> Identifiability {
        let mut scatter = Matrix3::zeros();
        let mut informative = 0usize;
        let mut max_angle: f64 = 0.0;
        for p in &self.pairs {
            let a = angle(&p.right).max(angle(&p.left));
            max_angle = max_angle.max(a);
            if a < settings.min_rotation_angle {
                continue;
            }
            let v: Vector3<f64> = log(&p.right);
            let n = v.norm();
            if n == 0.0 {
                continue;
            }
            let u = v / n;
            scatter += u * u.transpose() * p.weight;
            informative += 1;
        }
        if informative == 0 {
            return Identifiability::AllAnglesSmall { max_angle };
        }
        let eig = SymmetricEigen::new(scatter);
        let mut idx = [0usize, 1, 2];
        idx.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
        let l1 = eig.eigenvalues[idx[0]].max(f64::MIN_POSITIVE);
        let l2 = eig.eigenvalues[idx[1]].max(0.0);
        let spread = 2.0 * (l2 / l1).sqrt().atan();
        if spread < settings.min_axis_spread {
            let ax = eig.eigenvectors.column(idx[0]);
            Identifiability::ParallelAxes {
                axis: [ax[0], ax[1], ax[2]],
                axis_spread: spread,
            }
        } else {
            Identifiability::Determined {
                axis_spread: spread,
                informative_pairs: informative,
            }
        }
    }

    /// `Ok(())` when `S` is determined, otherwise [`Error::Degenerate`] explaining why.
    pub fn require_identifiable(&self, settings: &DiagnosticSettings) -> Result<()> {
        match self.identifiability(settings).to_error() {
            None => Ok(()),
            Some(e) => Err(e),
        }
    }

    /// Data diagnostics: per-pair angle mismatch `[H4]`, uninformative pairs, identifiability.
    ///
    /// ```
    /// use rotavg::conjugate::ConjugateProblem;
    /// use rotavg::so3::exp;
    /// use nalgebra::Vector3;
    /// // Pair 1 is mis-paired: its L and R rotate by different angles (0.5 vs 1.0 rad), which no
    /// // conjugation can explain.
    /// let l = [exp(&Vector3::new(0.5, 0.0, 0.0)), exp(&Vector3::new(0.0, 0.5, 0.0))];
    /// let r = [exp(&Vector3::new(0.0, 0.5, 0.0)), exp(&Vector3::new(0.0, 0.0, 1.0))];
    /// let d = ConjugateProblem::from_rotations(&l, &r)?.diagnose(&Default::default());
    /// assert_eq!(d.suspicious_pairs, vec![1]);
    /// assert!((d.max_angle_mismatch - 0.5).abs() < 1e-12);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn diagnose(&self, settings: &DiagnosticSettings) -> Diagnostics {
        let mismatch: Vec<f64> = self
            .pairs
            .iter()
            .map(|p| (angle(&p.left) - angle(&p.right)).abs())
            .collect();
        let mut sorted = mismatch.clone();
        sorted.sort_by(f64::total_cmp);
        let median = if sorted.is_empty() {
            0.0
        } else {
            crate::validate::quantile_sorted(&sorted, 0.5)
        };
        let max = sorted.last().copied().unwrap_or(0.0);
        let suspicious = mismatch
            .iter()
            .enumerate()
            .filter(|(_, m)| **m > settings.max_angle_mismatch)
            .map(|(k, _)| k)
            .collect();
        let small = self
            .pairs
            .iter()
            .enumerate()
            .filter(|(_, p)| {
                angle(&p.left) < settings.min_rotation_angle
                    && angle(&p.right) < settings.min_rotation_angle
            })
            .map(|(k, _)| k)
            .collect();
        Diagnostics {
            angle_mismatch: mismatch,
            median_angle_mismatch: median,
            max_angle_mismatch: max,
            suspicious_pairs: suspicious,
            small_rotation_pairs: small,
            identifiability: self.identifiability(settings),
        }
    }
}

/// Distance between `R_i` and `S^T L_i S` under `metric` (chordal: `||S R_i - L_i S||_F`).
fn pair_distance(metric: Metric, s: &Rotation, l: &Rotation, r: &Rotation) -> f64 {
    match metric {
        Metric::Chordal => (s.matrix() * r.matrix() - l.matrix() * s.matrix()).norm(),
        Metric::Geodesic => angle(&(r.inverse() * s.inverse() * l * s)),
        Metric::Quaternion => quaternion_distance(r, &(s.inverse() * l * s)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deserialisation validates like [`ConjugateProblem::new`]: no pairs or a bad weight is an
    /// error.
    #[test]
    fn deserialisation_validates() {
        let p = ConjugateProblem::new(vec![ConjugatePair::new(
            Rotation::identity(),
            Rotation::identity(),
        )])
        .unwrap();
        let text = serde_json::to_string(&p).unwrap();
        assert_eq!(serde_json::from_str::<ConjugateProblem>(&text).unwrap(), p);
        assert!(serde_json::from_str::<ConjugateProblem>(r#"{"pairs": []}"#).is_err());
        let bad = text.replace("\"weight\":1.0", "\"weight\":-1.0");
        assert_ne!(bad, text);
        assert!(serde_json::from_str::<ConjugateProblem>(&bad).is_err());
    }
}
