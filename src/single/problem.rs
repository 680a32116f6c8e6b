//! The single-averaging problem: samples `R_i`, weights `w_i > 0`, and the objective
//! `sum_i w_i rho(d(R_i, R))` ([`Objective`]; default chordal L2).

use crate::error::{Error, Result};
use crate::objective::{Loss, Objective};
use crate::so3::{self, Rotation};
use crate::validate::{check_rotation_within, check_weight};
use serde::{Deserialize, Serialize};

/// Validated data of a single-averaging problem: samples `R_i`, weights `w_i > 0` and the
/// objective. (De)serialises as `{"rotations": [R, ...], "weights": [w, ...]}` (the objective
/// is not part of the data file: it is chosen by the caller, [`SingleProblem::with_objective`]);
/// deserialisation validates like [`SingleProblem::new`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawSingleProblem")]
pub struct SingleProblem {
    #[serde(with = "crate::so3::serde_rows::rotations")]
    rotations: Vec<Rotation>,
    weights: Vec<f64>,
    #[serde(skip)]
    objective: Objective,
}

/// Unvalidated serde form of [`SingleProblem`].
#[derive(Deserialize)]
#[serde(
    expecting = "a single-averaging problem {\"rotations\": [R, ...], \"weights\": [w, ...]} (weights optional)"
)]
struct RawSingleProblem {
    #[serde(with = "crate::so3::serde_rows::rotations")]
    rotations: Vec<Rotation>,
    #[serde(default)]
    weights: Option<Vec<f64>>,
}

impl TryFrom<RawSingleProblem> for SingleProblem {
    type Error = Error;
    fn try_from(raw: RawSingleProblem) -> Result<Self> {
        SingleProblem::new(raw.rotations, raw.weights)
    }
}

impl SingleProblem {
    /// The objectives with a solver (every metric with L1 or L2).
    pub const SUPPORTED: &'static str = "chordal, geodesic or quaternion with l2 or l1";

    /// A problem from samples and optional weights (default: all 1), with the chordal L2
    /// objective.
    ///
    /// Errors: [`Error::Empty`] for no samples; [`Error::NonFinite`] / [`Error::NotARotation`]
    /// for a sample that is not a rotation within [`crate::so3::DEFAULT_ROTATION_TOLERANCE`]
    /// (the check is `[C6]`; item name `"rotation k"`, 0-based); [`Error::InvalidWeight`] for a
    /// weight outside `[1e-100, 1e100]` ([`crate::validate::MIN_WEIGHT`],
    /// [`crate::validate::MAX_WEIGHT`]; NaN included); [`Error::InvalidSettings`] when the
    /// numbers of weights and samples differ.
    ///
    /// ```
    /// use rotavg::single::SingleProblem;
    /// use rotavg::Rotation;
    /// assert!(SingleProblem::new(vec![Rotation::identity()], Some(vec![2.0])).is_ok());
    /// assert!(SingleProblem::new(vec![], None).is_err());
    /// assert!(SingleProblem::new(vec![Rotation::identity()], Some(vec![-1.0])).is_err());
    /// ```
    pub fn new(rotations: Vec<Rotation>, weights: Option<Vec<f64>>) -> Result<Self> {
        Self::new_within(rotations, weights, crate::so3::DEFAULT_ROTATION_TOLERANCE)
    }

    /// [`Self::new`] with the tolerance `rotation_tolerance` on `||R^T R - I||_F` and
    /// `|det R - 1|` of every sample (the readers' `--rotation-tolerance`; Python's
    /// `rotation_tolerance`). The samples are used as given (`[C6]`); the certificates
    /// subtract their defect (`[B6]`).
    ///
    /// ```
    /// use rotavg::single::SingleProblem;
    /// use rotavg::Rotation;
    /// let loose = Rotation::from_matrix_unchecked(nalgebra::Matrix3::identity() * (1.0 + 1e-4));
    /// assert!(SingleProblem::new(vec![loose], None).is_err());
    /// assert!(SingleProblem::new_within(vec![loose], None, 1e-3).is_ok());
    /// ```
    pub fn new_within(
        rotations: Vec<Rotation>,
        weights: Option<Vec<f64>>,
        rotation_tolerance: f64,
    ) -> Result<Self> {
        if rotations.is_empty() {
            return Err(Error::Empty {
                what: "the list of rotations".into(),
            });
        }
        for (k, r) in rotations.iter().enumerate() {
            check_rotation_within(|| format!("rotation {k}"), r, rotation_tolerance)?;
        }
        let weights = match weights {
            None => vec![1.0; rotations.len()],
            Some(w) => {
                if w.len() != rotations.len() {
                    return Err(Error::InvalidSettings {
                        name: "weights".into(),
                        reason: format!(
                            "{} weights given for {} rotations",
                            w.len(),
                            rotations.len()
                        ),
                    });
                }
                for (k, &x) in w.iter().enumerate() {
                    check_weight(|| format!("rotation {k}"), x)?;
                }
                w
            }
        };
        Ok(SingleProblem {
            rotations,
            weights,
            objective: Objective::CHORDAL_L2,
        })
    }

    /// The same data with another objective. [`Error::InvalidSettings`] (field `objective`)
    /// when there is no solver for it, or for a bad robust threshold.
    ///
    /// ```
    /// use rotavg::single::SingleProblem;
    /// use rotavg::objective::{Loss, Objective};
    /// use rotavg::{Metric, Rotation};
    /// let p = SingleProblem::new(vec![Rotation::identity(); 2], None)?
    ///     .with_objective(Objective::new(Metric::Geodesic, Loss::L1))?;
    /// assert_eq!(p.objective().to_string(), "geodesic l1");
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn with_objective(mut self, objective: Objective) -> Result<Self> {
        objective.validate()?;
        match (objective.metric, objective.loss) {
            (_, Loss::L2 | Loss::L1) => {}
            _ => return Err(objective.unsupported("single", Self::SUPPORTED)),
        }
        self.objective = objective;
        Ok(self)
    }

    /// The objective minimised.
    pub fn objective(&self) -> Objective {
        self.objective
    }

    /// The samples `R_i`.
    pub fn rotations(&self) -> &[Rotation] {
        &self.rotations
    }

    /// `(i, R_i, w_i)` for every sample.
    pub fn samples(&self) -> impl Iterator<Item = (usize, &Rotation, f64)> {
        self.rotations
            .iter()
            .zip(&self.weights)
            .enumerate()
            .map(|(k, (r, &w))| (k, r, w))
    }

    /// The weights `w_i` (all > 0).
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// Number of samples (>= 1).
    pub fn len(&self) -> usize {
        self.rotations.len()
    }

    /// Always `false`: a validated problem has at least one sample.
    pub fn is_empty(&self) -> bool {
        self.rotations.is_empty()
    }

    /// The smallest sample weight: the scale of the absolute part of the certificate's gap
    /// tolerance (contract section 3; adding samples can only lower it).
    pub fn min_weight(&self) -> f64 {
        crate::validate::min_weight(self.weights.iter().copied())
    }

    /// `W = sum_i w_i`.
    pub fn total_weight(&self) -> f64 {
        self.weights.iter().sum()
    }

    /// The cost `sum_i w_i rho(d(R_i, R))` of `estimate` under the problem's objective.
    pub fn cost(&self, estimate: &Rotation) -> f64 {
        self.cost_under(estimate, self.objective)
    }

    /// The cost of `estimate` under another objective.
    ///
    /// ```
    /// use rotavg::single::SingleProblem;
    /// use rotavg::objective::{Loss, Objective};
    /// use rotavg::so3::{exp, Metric, Rotation};
    /// use nalgebra::Vector3;
    /// let p = SingleProblem::new(vec![exp(&Vector3::new(0.0, 0.0, 0.2)), exp(&Vector3::new(0.0, 0.0, -0.5))], Some(vec![1.0, 2.0]))?;
    /// let (k, theta) = p.farthest(&Rotation::identity());
    /// assert_eq!(k, 1);
    /// assert!((theta - 0.5).abs() < 1e-12);
    /// // Cost sum_i w_i theta_i at I: 1 * 0.2 + 2 * 0.5.
    /// let l1 = Objective::new(Metric::Geodesic, Loss::L1);
    /// assert!((p.cost_under(&Rotation::identity(), l1) - 1.2).abs() < 1e-12);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn cost_under(&self, estimate: &Rotation, objective: Objective) -> f64 {
        self.rotations
            .iter()
            .zip(&self.weights)
            .map(|(r, w)| w * objective.rho(objective.metric.distance(r, estimate)))
            .sum()
    }

    /// The sample farthest from `estimate` in angle: `(index, theta)`.
    pub fn farthest(&self, estimate: &Rotation) -> (usize, f64) {
        let mut best = (0, f64::NEG_INFINITY);
        for (k, r) in self.rotations.iter().enumerate() {
            let t = so3::angle_between(estimate, r);
            if t > best.1 {
                best = (k, t);
            }
        }
        best
    }
}
