//! Single rotation averaging: the L1 and L2 means `argmin_R sum_i w_i d(R_i, R)^p` of many
//! estimates `R_i` of one rotation, under the angle (geodesic), chordal and quaternion
//! distances (SPEC sections 1 and 2; `paper-notes/single.md`, labels `[S1]`..`[S8]`).
//!
//! | metric     | p | method                                                        | certificate |
//! |------------|---|---------------------------------------------------------------|-------------|
//! | chordal    | 2 | closed form: det-corrected SVD projection of `sum w_i R_i` `[S1]` | always      |
//! | quaternion | 2 | sign-aligned normalised quaternion sum `[S2]`                 | when all samples lie within pi/2 of the estimate (else a proven bound) |
//! | geodesic   | 2 | Karcher mean, from the chordal L2 mean `[S3]`                 | pi/2 ball `[S4]` |
//! | geodesic   | 1 | Weiszfeld on SO(3) with the sample case handled `[S5]`        | pi/2 ball `[S4]` |
//! | chordal    | 1 | IRLS / majorise-minimise on SO(3) from the projected Euclidean geometric median `[S6]` | Euclidean bound `[S7]` |
//!
//! ```
//! use rotavg::single::{average_single, Norm, SingleProblem, SingleSettings};
//! use rotavg::so3::{exp, perturb_gaussian, Metric};
//! use rand::SeedableRng;
//!
//! let mut rng = rand::rngs::StdRng::seed_from_u64(1);
//! let truth = exp(&nalgebra::Vector3::new(0.3, -0.1, 0.7));
//! let samples: Vec<_> = (0..100).map(|_| perturb_gaussian(&truth, 0.05, &mut rng)).collect();
//! let problem = SingleProblem::new(samples, None)?;
//! let settings = SingleSettings { metric: Metric::Geodesic, norm: Norm::L2, ..Default::default() };
//! let solution = average_single(&problem, &settings)?;
//! assert!(solution.certificate.is_certified());
//! assert!(rotavg::so3::angle_between(&solution.estimate, &truth) < 0.05);
//! println!("{solution}");
//! # Ok::<(), rotavg::Error>(())
//! ```

pub mod certify;
pub mod closed_form;
pub mod iterative;

pub use certify::certify_single;
pub use closed_form::{chordal_l2_mean, quaternion_l2_mean};
pub use iterative::{chordal_l1_mean, geodesic_l1_mean, geodesic_l2_mean};

use crate::certificate::{Certificate, GapTolerance};
use crate::error::{Error, Result};
use crate::report::{SolverReport, Termination};
use crate::so3::{self, DEFAULT_ROTATION_TOLERANCE, Metric, Rotation};
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Instant;

/// The exponent `p` of the L^p mean.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Norm {
    /// `p = 1`: the median-like, outlier-robust mean.
    L1,
    /// `p = 2`: the least-squares mean.
    #[default]
    L2,
}

impl Norm {
    /// The exponent `p` (1 or 2).
    pub fn exponent(self) -> u32 {
        match self {
            Norm::L1 => 1,
            Norm::L2 => 2,
        }
    }

    /// `Norm::L1` for 1, `Norm::L2` for 2, `None` otherwise.
    ///
    /// ```
    /// use rotavg::single::Norm;
    /// assert_eq!(Norm::from_exponent(1), Some(Norm::L1));
    /// assert_eq!(Norm::from_exponent(3), None);
    /// assert_eq!(Norm::L2.apply(3.0), 9.0);
    /// ```
    pub fn from_exponent(p: u32) -> Option<Norm> {
        match p {
            1 => Some(Norm::L1),
            2 => Some(Norm::L2),
            _ => None,
        }
    }

    /// `d^p`.
    pub fn apply(self, d: f64) -> f64 {
        match self {
            Norm::L1 => d,
            Norm::L2 => d * d,
        }
    }
}

impl fmt::Display for Norm {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Norm::L1 => "L1",
            Norm::L2 => "L2",
        })
    }
}

/// Validated data of a single-averaging problem: samples `R_i` and weights `w_i > 0`.
/// (De)serialises as `{"rotations": [R, ...], "weights": [w, ...]}`; deserialisation validates
/// like [`SingleProblem::new`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "RawSingleProblem")]
pub struct SingleProblem {
    #[serde(with = "crate::serde_rot::rotations")]
    rotations: Vec<Rotation>,
    weights: Vec<f64>,
}

/// Unvalidated serde form of [`SingleProblem`].
#[derive(Deserialize)]
struct RawSingleProblem {
    #[serde(with = "crate::serde_rot::rotations")]
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
    /// A problem from samples and optional weights (default: all 1).
    ///
    /// Errors: [`Error::Empty`] for no samples; [`Error::NonFinite`] / [`Error::NotARotation`]
    /// for a sample that is not a rotation within [`DEFAULT_ROTATION_TOLERANCE`] (the check is
    /// `[C6]`; item name `"rotation k"`, 0-based); [`Error::InvalidWeight`] for a weight outside
    /// `[1e-100, 1e100]` ([`crate::io::MIN_WEIGHT`], [`crate::io::MAX_WEIGHT`]; NaN included); [`Error::InvalidSettings`] when the numbers of weights and samples
    /// differ.
    ///
    /// ```
    /// use rotavg::single::SingleProblem;
    /// use rotavg::Rotation;
    /// assert!(SingleProblem::new(vec![Rotation::identity()], Some(vec![2.0])).is_ok());
    /// assert!(SingleProblem::new(vec![], None).is_err());
    /// assert!(SingleProblem::new(vec![Rotation::identity()], Some(vec![-1.0])).is_err());
    /// ```
    pub fn new(rotations: Vec<Rotation>, weights: Option<Vec<f64>>) -> Result<Self> {
        if rotations.is_empty() {
            return Err(Error::Empty {
                what: "the list of rotations".into(),
            });
        }
        for (k, r) in rotations.iter().enumerate() {
            let m = r.matrix();
            if !m.iter().all(|x| x.is_finite()) {
                return Err(Error::NonFinite {
                    item: format!("rotation {k}"),
                });
            }
            let (orth, det) = so3::rotation_defect(m);
            if !(orth <= DEFAULT_ROTATION_TOLERANCE
                && (det - 1.0).abs() <= DEFAULT_ROTATION_TOLERANCE)
            {
                return Err(Error::NotARotation {
                    item: format!("rotation {k}"),
                    orthogonality_error: orth,
                    determinant: det,
                    tolerance: DEFAULT_ROTATION_TOLERANCE,
                });
            }
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
                if let Some((k, &x)) = w
                    .iter()
                    .enumerate()
                    .find(|(_, x)| crate::io::weight_out_of_range(**x).is_some())
                {
                    return Err(Error::InvalidWeight {
                        item: format!("rotation {k}"),
                        weight: x,
                    });
                }
                w
            }
        };
        Ok(SingleProblem { rotations, weights })
    }

    /// The samples `R_i`.
    pub fn rotations(&self) -> &[Rotation] {
        &self.rotations
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

    /// `W = sum_i w_i`.
    pub fn total_weight(&self) -> f64 {
        self.weights.iter().sum()
    }

    /// The cost `sum_i w_i d(R_i, R)^p` of `estimate` under `metric` and `norm`.
    pub fn cost(&self, estimate: &Rotation, metric: Metric, norm: Norm) -> f64 {
        self.rotations
            .iter()
            .zip(&self.weights)
            .map(|(r, w)| w * norm.apply(metric.distance(r, estimate)))
            .sum()
    }

    /// The sample farthest from `estimate` in angle: `(index, theta)`.
    ///
    /// ```
    /// use rotavg::single::{Norm, SingleProblem};
    /// use rotavg::so3::{exp, Metric, Rotation};
    /// use nalgebra::Vector3;
    /// let p = SingleProblem::new(vec![exp(&Vector3::new(0.0, 0.0, 0.2)), exp(&Vector3::new(0.0, 0.0, -0.5))], Some(vec![1.0, 2.0]))?;
    /// let (k, theta) = p.farthest(&Rotation::identity());
    /// assert_eq!(k, 1);
    /// assert!((theta - 0.5).abs() < 1e-12);
    /// // Cost sum_i w_i theta_i at I: 1 * 0.2 + 2 * 0.5.
    /// assert!((p.cost(&Rotation::identity(), Metric::Geodesic, Norm::L1) - 1.2).abs() < 1e-12);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
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

/// Settings of [`average_single`]. All fields have defaults; use struct update syntax:
/// `SingleSettings { metric: Metric::Geodesic, norm: Norm::L1, ..Default::default() }`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SingleSettings {
    /// The distance (default chordal).
    pub metric: Metric,
    /// `p` (default L2).
    pub norm: Norm,
    /// Iteration limit of the iterative methods (default 1000; >= 1).
    pub max_iterations: usize,
    /// Stop when the step of an iteration is shorter than this angle in radians
    /// (default 1e-12; > 0).
    pub step_tolerance: f64,
    /// Stop when the (minimum-norm sub)gradient norm divided by the total weight is below this
    /// (default 1e-12; >= 0).
    pub gradient_tolerance: f64,
    /// Gap tolerance of the certificate verdict.
    pub gap_tolerance: GapTolerance,
}

impl Default for SingleSettings {
    fn default() -> Self {
        SingleSettings {
            metric: Metric::Chordal,
            norm: Norm::L2,
            max_iterations: 1000,
            step_tolerance: 1e-12,
            gradient_tolerance: 1e-12,
            gap_tolerance: GapTolerance::default(),
        }
    }
}

impl SingleSettings {
    /// Default settings for the given metric and norm.
    pub fn new(metric: Metric, norm: Norm) -> Self {
        SingleSettings {
            metric,
            norm,
            ..Default::default()
        }
    }

    /// Check every value; [`Error::InvalidSettings`] names the first bad one.
    ///
    /// ```
    /// use rotavg::single::{Norm, SingleSettings};
    /// use rotavg::Metric;
    /// assert!(SingleSettings::new(Metric::Geodesic, Norm::L1).validate().is_ok());
    /// // The quaternion L1 mean is not implemented: refused up front, not at solve time.
    /// assert!(SingleSettings::new(Metric::Quaternion, Norm::L1).validate().is_err());
    /// let bad = SingleSettings { max_iterations: 0, ..Default::default() };
    /// assert!(bad.validate().unwrap_err().to_string().contains("max_iterations"));
    /// ```
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: String| {
            Err(Error::InvalidSettings {
                name: name.into(),
                reason,
            })
        };
        if self.max_iterations == 0 {
            return bad("max_iterations", "must be at least 1".into());
        }
        if !(self.step_tolerance.is_finite() && self.step_tolerance > 0.0) {
            return bad(
                "step_tolerance",
                format!("{} is not finite and > 0", self.step_tolerance),
            );
        }
        if !(self.gradient_tolerance.is_finite() && self.gradient_tolerance >= 0.0) {
            return bad(
                "gradient_tolerance",
                format!("{} is not finite and >= 0", self.gradient_tolerance),
            );
        }
        let g = self.gap_tolerance;
        if !(g.relative.is_finite()
            && g.relative >= 0.0
            && g.absolute.is_finite()
            && g.absolute >= 0.0)
        {
            return bad(
                "gap_tolerance",
                format!(
                    "relative {} and absolute {} must be finite and >= 0",
                    g.relative, g.absolute
                ),
            );
        }
        if self.metric == Metric::Quaternion && self.norm == Norm::L1 {
            return bad(
                "norm",
                "the quaternion L1 mean is not implemented (use chordal or geodesic for L1)".into(),
            );
        }
        Ok(())
    }
}

/// The result of [`average_single`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SingleSolution {
    /// The distance that was used.
    pub metric: Metric,
    /// `p`.
    pub norm: Norm,
    /// Number of samples.
    pub num_samples: usize,
    /// The mean (row-major in JSON).
    #[serde(with = "crate::serde_rot::rotation")]
    pub estimate: Rotation,
    /// `sum_i w_i d(R_i, estimate)^p` under `metric`.
    pub cost: f64,
    /// Solver name, iterations, why it stopped, wall time.
    pub report: SolverReport,
    /// Proven lower bound and verdict (computed independently of the solver by
    /// [`certify_single`]).
    pub certificate: Certificate,
}

impl fmt::Display for SingleSolution {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(
            f,
            "single rotation average: {} {} mean of {} samples",
            self.metric, self.norm, self.num_samples
        )?;
        let v = so3::log(&self.estimate);
        let t = v.norm();
        writeln!(
            f,
            "  estimate     angle {:.6} rad ({:.4} deg) about axis [{:.6}, {:.6}, {:.6}]",
            t,
            t.to_degrees(),
            if t > 0.0 { v.x / t } else { 0.0 },
            if t > 0.0 { v.y / t } else { 0.0 },
            if t > 0.0 { v.z / t } else { 1.0 },
        )?;
        for row in so3::rotation_to_rows(&self.estimate) {
            writeln!(
                f,
                "               [{:>12.9}, {:>12.9}, {:>12.9}]",
                row[0], row[1], row[2]
            )?;
        }
        writeln!(f, "  cost         {:.9e}", self.cost)?;
        writeln!(f, "  solver       {}", self.report)?;
        write!(f, "  certificate  {}", self.certificate)
    }
}

/// What a local method returns before certification.
#[derive(Debug, Clone)]
pub(crate) struct Local {
    pub estimate: Rotation,
    pub iterations: usize,
    pub termination: Termination,
    pub name: &'static str,
}

/// Average the samples of `problem` under `settings.metric` and `settings.norm`, and certify
/// the result (see the module docs for the method used in each case).
///
/// Errors only for invalid settings ([`Error::InvalidSettings`]); non-convergence is reported in
/// `solution.report.termination`, and a missing proof of optimality in `solution.certificate`.
///
/// ```
/// use rotavg::single::{average_single, Norm, SingleProblem, SingleSettings};
/// use rotavg::so3::{exp, Metric};
/// use nalgebra::Vector3;
/// // Rz(0.2), Rz(-0.2) and I: every mean is I by symmetry.
/// let p = SingleProblem::new(
///     vec![exp(&Vector3::new(0.0, 0.0, 0.2)), exp(&Vector3::new(0.0, 0.0, -0.2)), exp(&Vector3::zeros())],
///     None,
/// )?;
/// for (metric, norm) in [(Metric::Chordal, Norm::L2), (Metric::Geodesic, Norm::L1)] {
///     let s = average_single(&p, &SingleSettings::new(metric, norm))?;
///     assert!(rotavg::so3::angle(&s.estimate) < 1e-9);
///     assert!(s.certificate.is_certified());
/// }
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_single(
    problem: &SingleProblem,
    settings: &SingleSettings,
) -> Result<SingleSolution> {
    average_single_from(problem, settings, None)
}

/// [`average_single`] with the iterative methods started from `init` instead of their default
/// start (the closed-form chordal L2 mean ignores `init`).
///
/// ```
/// use rotavg::single::{average_single_from, Norm, SingleProblem, SingleSettings};
/// use rotavg::so3::{exp, Metric};
/// use nalgebra::Vector3;
/// let p = SingleProblem::new(vec![exp(&Vector3::new(0.1, 0.0, 0.0)), exp(&Vector3::new(-0.1, 0.0, 0.0))], None)?;
/// let s = average_single_from(&p, &SingleSettings::new(Metric::Geodesic, Norm::L2), Some(&exp(&Vector3::new(0.0, 0.3, 0.0))))?;
/// assert!(rotavg::so3::angle(&s.estimate) < 1e-9);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_single_from(
    problem: &SingleProblem,
    settings: &SingleSettings,
    init: Option<&Rotation>,
) -> Result<SingleSolution> {
    settings.validate()?;
    let start = Instant::now();
    let local = match (settings.metric, settings.norm) {
        (Metric::Chordal, Norm::L2) => closed_form::chordal_l2_local(problem),
        (Metric::Quaternion, Norm::L2) => closed_form::quaternion_l2_local(problem, settings, init),
        (Metric::Geodesic, Norm::L2) => iterative::geodesic_l2_local(problem, settings, init),
        (Metric::Geodesic, Norm::L1) => iterative::geodesic_l1_local(problem, settings, init),
        (Metric::Chordal, Norm::L1) => iterative::chordal_l1_local(problem, settings, init),
        (Metric::Quaternion, Norm::L1) => unreachable_quaternion_l1()?,
    };
    let seconds = start.elapsed().as_secs_f64();
    let cost = problem.cost(&local.estimate, settings.metric, settings.norm);
    let certificate = certify_single(problem, &local.estimate, settings)?;
    Ok(SingleSolution {
        metric: settings.metric,
        norm: settings.norm,
        num_samples: problem.len(),
        estimate: local.estimate,
        cost,
        report: SolverReport {
            name: local.name.into(),
            iterations: local.iterations,
            termination: local.termination,
            seconds,
        },
        certificate,
    })
}

/// Rejected by `validate`; kept as an error (not a panic) for safety.
fn unreachable_quaternion_l1() -> Result<Local> {
    Err(Error::InvalidSettings {
        name: "norm".into(),
        reason: "the quaternion L1 mean is not implemented".into(),
    })
}
