//! The certificate object shared by all problems (contract section 3): an upper bound (the cost of
//! the returned estimate), a proven lower bound on the global minimum, the gap, and a verdict.
//!
//! Soundness rule: [`Verdict::Certified`] is only produced by [`Certificate::from_bounds`] from a
//! lower bound that the caller has *verified independently* of any solver's own report (see
//! `paper-notes/certificates.md`). A certificate without a lower bound is never certified.

use super::proof::BoundMethod;
use super::tolerance::{GapTolerance, TolerancePart};
use serde::{Deserialize, Serialize};
use std::fmt;

/// The outcome of certification.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The estimate is globally optimal up to the stated gap tolerance.
    Certified,
    /// A proven lower bound exists, but the gap exceeds the tolerance.
    GapReported,
    /// No decision: no lower bound, or the numerical evidence is too imprecise to decide.
    Inconclusive,
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Verdict::Certified => "certified",
            Verdict::GapReported => "gap_reported",
            Verdict::Inconclusive => "inconclusive",
        })
    }
}

/// Which problem a certificate is about, when it is not the problem whose cost the report
/// states (absent: that problem).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CertifiedProblemKind {
    /// Chordal L2 multiple rotation averaging on the **inlier graph** of a robust solve: the
    /// edges whose residual at the robust estimate is within the inlier threshold (its largest
    /// connected component when they do not connect). The claim is about that problem only,
    /// never about the robust cost on all edges.
    ChordalL2Inliers,
    /// Chordal L2 multiple rotation averaging on every edge of the problem solved (with its
    /// information matrices when it has them). Named in a report's verdict; never set on a
    /// certificate (absent there means this).
    ChordalL2,
    /// Chordal L2 multiple rotation averaging on every edge with the gravity priors held as
    /// constraints (`R_i world_down = g_i` for each image with a prior, `paper-notes/gravity.md`).
    ChordalL2Gravity,
    /// [`CertifiedProblemKind::ChordalL2Inliers`] with the gravity priors of the component's
    /// images held as constraints (a robust solve with gravity priors).
    ChordalL2GravityInliers,
    /// Chordal L2 multiple rotation averaging on every edge plus the gravity priors as soft
    /// terms `2 w ||R_i world_down - g_i||^2` (`paper-notes/gravity.md` `[G10]`): the cost
    /// stated is the view graph's plus the priors'.
    ChordalL2GravitySoft,
    /// [`CertifiedProblemKind::ChordalL2Inliers`] plus the soft gravity priors of the
    /// component's images (a robust solve with soft priors).
    ChordalL2GravitySoftInliers,
    /// The joint chordal L2 cost of a two-sensor rig: the frames on the reference sensor's view
    /// graph and `S R_i` on the other's (`rotavg rig`, `paper-notes/conjugate.md` `[H17]`).
    /// Named in a rig report's verdict; `num_edges` counts both graphs' edges.
    ChordalL2Rig,
    /// The same rig with the other sensor's `sensor_from_rig` held at a given rotation
    /// (`rotavg rig --sensor-from-rig`, `paper-notes/conjugate.md` `[H18]`): exactly the chordal
    /// L2 problem of the frames' view graph, the other sensor's edges turned by `S`.
    /// `num_edges` counts both graphs' edges.
    ChordalL2RigSensorHeld,
    /// The chordal L2 problem of a rig of any number of sensors (`rotavg rig FILE`,
    /// `paper-notes/conjugate.md` `[H19]`): the frames and the unknown `sensor_from_rig`
    /// rotations, on every edge between its images. `num_nodes` counts frames.
    ChordalL2RigImages,
    /// [`CertifiedProblemKind::ChordalL2RigImages`] with every sensor's `sensor_from_rig` known
    /// (held): the frames' view graph plus the within-frame edges' constant cost.
    ChordalL2RigImagesSensorsHeld,
    /// [`CertifiedProblemKind::ChordalL2RigImages`] on the rig's **inlier edges** after a robust
    /// solve (`paper-notes/conjugate.md` `[H20]`): the edges whose residual at the Cauchy
    /// estimate is within the inlier threshold. The claim is about that problem only.
    ChordalL2RigImagesInliers,
    /// [`CertifiedProblemKind::ChordalL2RigImagesSensorsHeld`] with gravity priors on its
    /// images held as constraints (`rotavg rig FILE --gravity`, `paper-notes/gravity.md`
    /// `[G14]`): the frames' gravity problem plus a constant.
    ChordalL2RigGravity,
    /// [`CertifiedProblemKind::ChordalL2RigGravity`] with the priors as soft terms
    /// (`--gravity-weight`): the cost stated is the edges' plus the priors'.
    ChordalL2RigGravitySoft,
    /// [`CertifiedProblemKind::ChordalL2RigGravity`] on the rig's inlier edges (`[H20]`).
    ChordalL2RigGravityInliers,
    /// [`CertifiedProblemKind::ChordalL2RigGravitySoft`] on the rig's inlier edges (`[H20]`).
    ChordalL2RigGravitySoftInliers,
    /// [`CertifiedProblemKind::ChordalL2RigImages`] plus the soft gravity priors on its images:
    /// the frames and the unknown `sensor_from_rig` rotations free (`paper-notes/gravity.md`
    /// `[G16]`), the cost stated the edges' plus the priors'.
    ChordalL2RigImagesGravitySoft,
    /// [`CertifiedProblemKind::ChordalL2RigImagesGravitySoft`] on the rig's inlier edges
    /// (`[H20]`).
    ChordalL2RigImagesGravitySoftInliers,
}

/// The problem a certificate is about, with its size against the whole input's.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct CertifiedProblem {
    /// What was certified.
    pub kind: CertifiedProblemKind,
    /// Nodes of the certified problem.
    pub num_nodes: usize,
    /// Nodes of the whole problem.
    pub total_nodes: usize,
    /// Edges of the certified problem.
    pub num_edges: usize,
    /// Edges of the whole problem.
    pub total_edges: usize,
}

impl fmt::Display for CertifiedProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.kind {
            CertifiedProblemKind::ChordalL2Inliers
            | CertifiedProblemKind::ChordalL2
            | CertifiedProblemKind::ChordalL2GravityInliers
            | CertifiedProblemKind::ChordalL2Gravity
            | CertifiedProblemKind::ChordalL2GravitySoftInliers
            | CertifiedProblemKind::ChordalL2GravitySoft => self.view_graph(f),
            CertifiedProblemKind::ChordalL2Rig => write!(
                f,
                "the rig's joint chordal L2 problem on all {} edges of its two view graphs ({} \
                 frames and sensor_from_rig)",
                self.num_edges, self.num_nodes
            ),
            CertifiedProblemKind::ChordalL2RigSensorHeld => write!(
                f,
                "the rig's chordal L2 problem with sensor_from_rig held: the frames' view graph of \
                 all {} edges of the two sensors (the other sensor's turned by S), {} frames",
                self.num_edges, self.num_nodes
            ),
            CertifiedProblemKind::ChordalL2RigImages => write!(
                f,
                "the rig's chordal L2 problem on all {} edges between its images ({} frames and \
                 the unknown sensor_from_rig rotations)",
                self.num_edges, self.num_nodes
            ),
            CertifiedProblemKind::ChordalL2RigImagesInliers => write!(
                f,
                "the rig's chordal L2 problem on its inlier edges ({} of {} edges, {} frames)",
                self.num_edges, self.total_edges, self.num_nodes
            ),
            CertifiedProblemKind::ChordalL2RigGravity
            | CertifiedProblemKind::ChordalL2RigGravitySoft
            | CertifiedProblemKind::ChordalL2RigGravityInliers
            | CertifiedProblemKind::ChordalL2RigGravitySoftInliers => self.rig_gravity(f),
            CertifiedProblemKind::ChordalL2RigImagesGravitySoft
            | CertifiedProblemKind::ChordalL2RigImagesGravitySoftInliers => {
                write!(
                    f,
                    "the rig's chordal L2 problem on {} plus the soft gravity priors ({} frames \
                     and the unknown sensor_from_rig rotations)",
                    self.rig_edges(),
                    self.num_nodes
                )
            }
            CertifiedProblemKind::ChordalL2RigImagesSensorsHeld => write!(
                f,
                "the rig's chordal L2 problem on all {} edges between its images with every \
                 sensor_from_rig held ({} frames)",
                self.num_edges, self.num_nodes
            ),
        }
    }
}

impl CertifiedProblem {
    /// The view graph's kinds: all edges or the inlier graph, without priors, with them held or
    /// soft (the priors named before the inlier graph, after all edges).
    fn view_graph(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        use CertifiedProblemKind as K;
        let priors = match self.kind {
            K::ChordalL2Gravity | K::ChordalL2GravityInliers => " with the gravity priors held",
            K::ChordalL2GravitySoft | K::ChordalL2GravitySoftInliers => {
                " plus the soft gravity priors"
            }
            _ => "",
        };
        let inliers = matches!(
            self.kind,
            K::ChordalL2Inliers | K::ChordalL2GravityInliers | K::ChordalL2GravitySoftInliers
        );
        let (edges, nodes) = (self.num_edges, self.num_nodes);
        if inliers {
            let (total_edges, total_nodes) = (self.total_edges, self.total_nodes);
            write!(
                f,
                "the chordal L2 problem{priors} on the inlier graph ({edges} of {total_edges} \
                 edges, {nodes} of {total_nodes} nodes)"
            )
        } else {
            write!(
                f,
                "the chordal L2 problem on all {edges} edges ({nodes} nodes){priors}"
            )
        }
    }

    /// A rig's edges: all of them, or its inlier edges.
    fn rig_edges(&self) -> String {
        if self.num_edges < self.total_edges {
            format!(
                "its inlier edges ({} of {})",
                self.num_edges, self.total_edges
            )
        } else {
            format!("all {} edges between its images", self.num_edges)
        }
    }

    /// The rig with gravity priors' kinds (`[G14]`), held or soft, on all edges or the inliers.
    fn rig_gravity(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let soft = matches!(
            self.kind,
            CertifiedProblemKind::ChordalL2RigGravitySoft
                | CertifiedProblemKind::ChordalL2RigGravitySoftInliers
        );
        let edges = self.rig_edges();
        write!(
            f,
            "the rig's chordal L2 problem on {edges} with every sensor_from_rig held ({} frames) \
             {}",
            self.num_nodes,
            [
                "with the gravity priors held",
                "plus the soft gravity priors"
            ][usize::from(soft)]
        )
    }
}

/// A lower bound on a cost that is a sum of nonnegative terms (single and conjugate
/// averaging), capped at the computed cost (a bound above it can only be rounding:
/// `f* <= f(estimate)`). A bound that is not finite (never expected) becomes the trivial bound
/// 0: `f64::min` would turn a NaN into the cost itself, a false certificate.
pub(crate) fn nonnegative_bound_at_most(lower_bound: f64, cost: f64) -> f64 {
    if lower_bound.is_finite() {
        lower_bound.min(cost).max(0.0)
    } else {
        0.0
    }
}

/// A lower bound capped at the computed cost, floored at 0 only where the cost is a sum of
/// nonnegative terms (`nonnegative`: scalar weights). With information matrices the cost is
/// `[A1]`'s trace form, which on data orthogonal only to rounding is negative at its minimum
/// (`-1e-11` on a noise-free pair, `tests/suite/soundness_rig.rs`): a floor at 0 would lift the
/// bound above the minimum. Not finite: 0 with the floor, `-inf` (no bound) without.
pub(crate) fn bound_at_most(lower_bound: f64, cost: f64, nonnegative: bool) -> f64 {
    match (nonnegative, lower_bound.is_finite()) {
        (true, _) => nonnegative_bound_at_most(lower_bound, cost),
        (false, true) => lower_bound.min(cost),
        (false, false) => f64::NEG_INFINITY,
    }
}

/// A certificate of (sub)optimality for an estimate (contract sections 3 and 5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Certificate {
    /// The verdict.
    pub verdict: Verdict,
    /// Cost of the returned estimate.
    pub upper_bound: f64,
    /// A proven lower bound on the global minimum of the same cost, if one is available.
    pub lower_bound: Option<f64>,
    /// `upper_bound - lower_bound` (>= 0 up to rounding).
    pub gap: Option<f64>,
    /// `gap / max(|upper_bound|, 1e-12)`.
    pub relative_gap: Option<f64>,
    /// Smallest eigenvalue of the certificate matrix, where there is one.
    pub min_eigenvalue: Option<f64>,
    /// Which argument produced the bound.
    pub method: BoundMethod,
    /// The tolerance applied for the verdict.
    pub tolerance: GapTolerance,
    /// Which part of the tolerance decided (the larger one at the cost).
    pub tolerance_part: TolerancePart,
    /// A sentence explaining the verdict (why certified, or why not).
    pub explanation: String,
    /// Time spent certifying, in seconds.
    pub seconds: f64,
    /// A **proven** lower bound on `lambda_min` of the certificate matrix whose multipliers gave
    /// `lower_bound` (Cholesky-verified with a floating-point margin, or Gershgorin, `[D5]`-`[D8]`;
    /// dense eigenvalues minus a rounding margin for the conjugate 10x10 matrix `[H8]`), where
    /// known. Omitted from JSON when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub verified_min_eigenvalue: Option<f64>,
    /// **Estimates** (not bounds) of the smallest eigenvalues of that certificate matrix,
    /// computed only on request (e.g. the CLI's `--plot`), `[D14]`. Omitted from JSON when
    /// absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub smallest_eigenvalues: Option<crate::certify::evidence::SpectrumEstimate>,
    /// What the branch and bound did, when it produced the bound (cells, depth, time, why it
    /// stopped). Omitted from JSON when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub branch_and_bound: Option<crate::certify::evidence::BranchAndBoundStats>,
    /// The problem certified when it is not the one whose cost the report states (the
    /// inlier graph of a robust solve, [`CertifiedProblemKind`]); the bounds are then of that
    /// problem's cost. Omitted from JSON when absent (the report's own problem).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub certified_problem: Option<CertifiedProblem>,
    /// A **Monte Carlo** lower bound `[D16]`, when no deterministic proof fit the budget: it
    /// holds unless an event of probability at most its `failure_probability` (over the test's
    /// own random vectors, whatever the data) occurred. Never a proof: the verdict, `lower_bound`
    /// and `gap` ignore it. Omitted from JSON when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub randomized: Option<RandomizedLowerBound>,
    /// Multiple averaging: whose multipliers gave `lower_bound`, `min_eigenvalue` and
    /// `verified_min_eigenvalue` (the given estimate, its refinement, the SDP, the staircase);
    /// `upper_bound`, `gap` and `verdict` are always the given estimate's. Omitted from JSON
    /// when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bound_from: Option<crate::certify::log::Point>,
}

/// A Monte Carlo lower bound on the global minimum `[D16]` against the certificate's cost.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RandomizedLowerBound {
    /// The lower bound (valid unless the rare event occurred).
    pub lower_bound: f64,
    /// `upper_bound - lower_bound`.
    pub gap: f64,
    /// `gap / max(|upper_bound|, 1e-12)`.
    pub relative_gap: f64,
    /// The gap is within the certificate's tolerance: globally optimal unless the rare event
    /// occurred.
    pub within_tolerance: bool,
    /// The probability of the rare event, over the test's random vectors.
    pub failure_probability: f64,
    /// Seed of the random vectors (`dual.randomized.seed` repeats the run).
    pub seed: u64,
}

impl RandomizedLowerBound {
    /// The bound against `upper_bound` under `tolerance` (the rule of
    /// [`Certificate::from_bounds`]).
    ///
    /// ```
    /// use rotavg::certify::{GapTolerance, RandomizedLowerBound};
    /// let r = RandomizedLowerBound::new(10.0, 10.0 - 5e-6, &GapTolerance::default(), 1e-12, 7);
    /// assert!(r.within_tolerance && (r.relative_gap - 5e-7).abs() < 1e-12);
    /// assert!(!RandomizedLowerBound::new(10.0, 9.0, &GapTolerance::default(), 1e-12, 7).within_tolerance);
    /// ```
    pub fn new(
        upper_bound: f64,
        lower_bound: f64,
        tolerance: &GapTolerance,
        failure_probability: f64,
        seed: u64,
    ) -> Self {
        let gap = upper_bound - lower_bound;
        RandomizedLowerBound {
            lower_bound,
            gap,
            relative_gap: gap / upper_bound.abs().max(1e-12),
            within_tolerance: gap <= tolerance.allowed_gap(upper_bound),
            failure_probability,
            seed,
        }
    }
}

impl fmt::Display for RandomizedLowerBound {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "randomized test [D16] (not a proof): {} unless an event of probability <= {:.0e} \
             occurred (seed {}): lower bound {:.9e}, gap {:.3e} (relative {:.3e})",
            if self.within_tolerance {
                "globally optimal within the tolerance"
            } else {
                "the gap is at most as stated"
            },
            self.failure_probability,
            self.seed,
            self.lower_bound,
            self.gap,
            self.relative_gap
        )
    }
}

impl Certificate {
    /// Build a certificate from an upper bound and an (independently verified) lower bound.
    /// The verdict is `Certified` iff a lower bound is given, both bounds are finite, and
    /// `gap <= max(tol.absolute, tol.relative * |ub|)`; `GapReported` when a finite
    /// lower bound exceeds that; `Inconclusive` when there is no usable lower bound.
    ///
    /// ```
    /// use rotavg::{BoundMethod, Certificate, Verdict};
    /// use rotavg::certify::GapTolerance;
    /// let tol = GapTolerance::default(); // relative 1e-6, absolute 1e-9 (smallest weight 1)
    /// // A verified lower bound within 1e-6 relative of the cost: certified.
    /// let c = Certificate::from_bounds(10.0, Some(10.0 - 5e-6), BoundMethod::Dual, None, tol, "example", 0.0);
    /// assert_eq!(c.verdict, Verdict::Certified);
    /// assert!((c.gap.unwrap() - 5e-6).abs() < 1e-12);
    /// // A lower bound 10 % below the cost: the gap is proven but too large.
    /// let c = Certificate::from_bounds(10.0, Some(9.0), BoundMethod::Sdp, None, tol, "", 0.0);
    /// assert_eq!(c.verdict, Verdict::GapReported);
    /// assert!((c.relative_gap.unwrap() - 0.1).abs() < 1e-12);
    /// // A verified bound above the computed cost (the cost's rounding) is capped at it.
    /// let c = Certificate::from_bounds(10.0, Some(10.0 + 1e-14), BoundMethod::Dual, None, tol, "", 0.0);
    /// assert_eq!((c.lower_bound, c.gap), (Some(10.0), Some(0.0)));
    /// // No (finite) lower bound: never certified.
    /// let c = Certificate::from_bounds(10.0, Some(f64::NAN), BoundMethod::Dual, None, tol, "", 0.0);
    /// assert_eq!(c.verdict, Verdict::Inconclusive);
    /// assert!(c.lower_bound.is_none() && !c.is_certified());
    /// ```
    pub fn from_bounds(
        upper_bound: f64,
        lower_bound: Option<f64>,
        method: BoundMethod,
        min_eigenvalue: Option<f64>,
        tolerance: GapTolerance,
        explanation: impl Into<String>,
        seconds: f64,
    ) -> Self {
        // capped at the upper bound: a verified bound above the computed cost is that cost's
        // rounding (`f* <= f(estimate)`; a point critical to ~1e-15 shows it), and lowering a
        // lower bound keeps it valid (a NaN upper bound leaves it as it is)
        let lb = lower_bound
            .filter(|l| l.is_finite())
            .map(|l| if l > upper_bound { upper_bound } else { l });
        let scale = upper_bound.abs().max(1e-12);
        let (gap, rel, verdict) = match lb {
            Some(l) if upper_bound.is_finite() => {
                let gap = upper_bound - l;
                let rel = gap / scale;
                let ok = gap <= tolerance.allowed_gap(upper_bound);
                (
                    Some(gap),
                    Some(rel),
                    if ok {
                        Verdict::Certified
                    } else {
                        Verdict::GapReported
                    },
                )
            }
            _ => (None, None, Verdict::Inconclusive),
        };
        Certificate {
            verdict,
            upper_bound,
            lower_bound: lb,
            gap,
            relative_gap: rel,
            min_eigenvalue,
            method,
            tolerance,
            tolerance_part: tolerance.decisive_part(upper_bound),
            explanation: explanation.into(),
            seconds,
            verified_min_eigenvalue: None,
            smallest_eigenvalues: None,
            branch_and_bound: None,
            certified_problem: None,
            randomized: None,
            bound_from: None,
        }
    }

    /// This certificate, stated as one of `problem` (its bounds are of that problem's cost).
    pub fn for_problem(mut self, problem: CertifiedProblem) -> Certificate {
        self.certified_problem = Some(problem);
        self
    }

    /// This certificate with its lower bound lowered by `amount >= 0` (rounded down): the
    /// bound of a cost that differs from the one certified by at most `amount` at every point
    /// (`paper-notes/gravity.md` `[G10]` "Two forms of the cost"). Gap, relative gap and
    /// verdict are recomputed by the rule of [`Self::from_bounds`].
    pub(crate) fn lowered_by(&self, amount: f64) -> Certificate {
        let lower = self.lower_bound.map(|l| {
            let l = l - amount.max(0.0);
            l - l.abs() * f64::EPSILON
        });
        let mut c = self.rebounded(self.upper_bound, lower);
        c.randomized = self.randomized;
        c
    }

    /// This certificate with the bounds `upper_bound` and `lower_bound`, its evidence kept
    /// (not the randomized estimate, which depends on the upper bound): gap, relative gap and
    /// verdict by the rule of [`Self::from_bounds`].
    fn rebounded(&self, upper_bound: f64, lower_bound: Option<f64>) -> Certificate {
        let mut c = Certificate::from_bounds(
            upper_bound,
            lower_bound,
            self.method,
            self.min_eigenvalue,
            self.tolerance,
            self.explanation.clone(),
            self.seconds,
        );
        c.verified_min_eigenvalue = self.verified_min_eigenvalue;
        c.smallest_eigenvalues = self.smallest_eigenvalues.clone();
        c.branch_and_bound = self.branch_and_bound;
        c.certified_problem = self.certified_problem;
        c.bound_from = self.bound_from;
        c
    }

    /// The same lower bound (a bound on the global minimum, whatever estimate produced it)
    /// against another upper bound: the certificate of a different estimate, e.g. an improved
    /// one. Gap, relative gap and verdict are recomputed by the rule of [`Self::from_bounds`].
    ///
    /// ```
    /// use rotavg::{BoundMethod, Certificate, Verdict};
    /// use rotavg::certify::GapTolerance;
    /// let c = Certificate::from_bounds(10.0, Some(9.0), BoundMethod::Sdp, None, GapTolerance::default(), "", 0.0);
    /// assert_eq!(c.verdict, Verdict::GapReported);
    /// let better = c.with_upper_bound(9.0 + 1e-9);
    /// assert_eq!(better.verdict, Verdict::Certified);
    /// assert_eq!(better.lower_bound, Some(9.0));
    /// ```
    pub fn with_upper_bound(&self, upper_bound: f64) -> Certificate {
        let mut c = self.rebounded(upper_bound, self.lower_bound);
        c.randomized = self.randomized.map(|r| {
            RandomizedLowerBound::new(
                upper_bound,
                r.lower_bound,
                &c.tolerance,
                r.failure_probability,
                r.seed,
            )
        });
        c
    }

    /// `true` iff the verdict is [`Verdict::Certified`].
    pub fn is_certified(&self) -> bool {
        self.verdict == Verdict::Certified
    }
}

/// The claim of an explanation, for the short text: its first clause (up to the first `; `),
/// without the labels of `paper-notes/` (`[D15]`, `[B1]-[B6]`, `[S4b]`).
fn claim(explanation: &str) -> String {
    /// `D15`, `S4b`, `B1`: capitals, digits, an optional lower-case letter.
    fn is_label(s: &str) -> bool {
        let caps = s.chars().take_while(char::is_ascii_uppercase).count();
        let digits = s[caps..].chars().take_while(char::is_ascii_digit).count();
        let tail = &s[caps + digits..];
        caps > 0
            && digits > 0
            && (tail.is_empty()
                || (tail.len() == 1 && tail.chars().all(|c| c.is_ascii_lowercase())))
    }
    let first = explanation.split("; ").next().unwrap_or("");
    let mut out = String::with_capacity(first.len());
    let mut rest = first;
    while let Some(open) = rest.find('[') {
        let close = rest[open..].find(']').map(|c| open + c);
        match close {
            Some(close) if is_label(&rest[open + 1..close]) => {
                out.push_str(rest[..open].trim_end_matches(['-', ' ']));
                rest = &rest[close + 1..];
            }
            _ => {
                out.push_str(&rest[..=open]);
                rest = &rest[open + 1..];
            }
        }
    }
    out.push_str(rest);
    out
}

#[cfg(test)]
mod claim_tests {
    #[test]
    fn labels_are_left_out() {
        assert_eq!(
            super::claim("branch and bound over SO(3) [B1]-[B6]: proven lower bound 1; more"),
            "branch and bound over SO(3): proven lower bound 1"
        );
        assert_eq!(
            super::claim("certified [S4b] by the ball"),
            "certified by the ball"
        );
        assert_eq!(super::claim("x [not a label] y"), "x [not a label] y");
    }
}

/// The short form (`{}`): verdict, method, cost, lower bound, gap and the claim, on lines of at
/// most about 100 characters. The alternate form (`{:#}`, `--verbose`): one line with the
/// lowest eigenvalue, the tolerance rule and the whole explanation of the proof.
impl fmt::Display for Certificate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if !f.alternate() {
            write!(f, "{} (method {})", self.verdict, self.method)?;
            if let Some(p) = &self.certified_problem {
                write!(f, " of {p}")?;
            }
            write!(f, "\n  cost {:.9e}", self.upper_bound)?;
            match (self.lower_bound, self.gap, self.relative_gap) {
                (Some(lb), Some(g), Some(r)) => {
                    write!(f, ", lower bound {lb:.9e}, gap {g:.3e} (relative {r:.3e})")?
                }
                _ => write!(f, ", no lower bound")?,
            }
            let claim = claim(&self.explanation);
            if !claim.is_empty() {
                write!(f, "\n  {claim}")?;
            }
            if let Some(r) = &self.randomized {
                write!(
                    f,
                    "\n  Monte Carlo bound (not a proof; wrong with probability <= {:.0e}): {:.9e}",
                    r.failure_probability, r.lower_bound
                )?;
            }
            return Ok(());
        }
        write!(
            f,
            "{} (method {}): cost {:.9e}",
            self.verdict, self.method, self.upper_bound
        )?;
        if let Some(p) = &self.certified_problem {
            write!(f, " of {p}")?;
        }
        match (self.lower_bound, self.gap, self.relative_gap) {
            (Some(lb), Some(g), Some(r)) => {
                write!(f, ", lower bound {lb:.9e}, gap {g:.3e} (relative {r:.3e})")?
            }
            _ => write!(f, ", no lower bound")?,
        }
        if let Some(mu) = self.min_eigenvalue {
            write!(f, ", lambda_min {mu:.3e}")?;
        }
        write!(
            f,
            "; tolerance: {}; {}",
            self.tolerance.describe(self.upper_bound),
            self.explanation
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts() {
        let t = GapTolerance::default();
        let c =
            Certificate::from_bounds(1.0, Some(1.0 - 1e-8), BoundMethod::Dual, None, t, "", 0.0);
        assert_eq!(c.verdict, Verdict::Certified);
        let c = Certificate::from_bounds(1.0, Some(0.9), BoundMethod::Dual, None, t, "", 0.0);
        assert_eq!(c.verdict, Verdict::GapReported);
        let c = Certificate::from_bounds(1.0, None, BoundMethod::Dual, None, t, "", 0.0);
        assert_eq!(c.verdict, Verdict::Inconclusive);
        let c = Certificate::from_bounds(1.0, Some(f64::NAN), BoundMethod::Dual, None, t, "", 0.0);
        assert_eq!(c.verdict, Verdict::Inconclusive);
        let c = Certificate::from_bounds(f64::NAN, Some(0.0), BoundMethod::Dual, None, t, "", 0.0);
        assert_eq!(c.verdict, Verdict::Inconclusive);
        // noise-free: cost ~ 0, absolute tolerance applies
        let c = Certificate::from_bounds(1e-12, Some(-1e-11), BoundMethod::Dual, None, t, "", 0.0);
        assert_eq!(c.verdict, Verdict::Certified);
    }
}

#[cfg(test)]
mod bound_cap_tests {
    use super::nonnegative_bound_at_most as cap;

    /// A bound that is not finite must never become the cost (which would certify anything).
    #[test]
    fn non_finite_bounds_are_trivial_never_the_cost() {
        assert_eq!(cap(f64::NAN, 2.0), 0.0);
        assert_eq!(cap(f64::INFINITY, 2.0), 0.0);
        assert_eq!(cap(f64::NEG_INFINITY, 2.0), 0.0);
        assert_eq!(cap(3.0, 2.0), 2.0);
        assert_eq!(cap(1.5, 2.0), 1.5);
        assert_eq!(cap(-1.0, 2.0), 0.0);
    }

    /// Without the floor (information matrices) a negative bound stays, a bound that is not
    /// finite is no bound, and the cap at the cost holds.
    #[test]
    fn without_the_floor_negative_bounds_stay() {
        use super::bound_at_most;
        assert_eq!(bound_at_most(-1e-11, -5e-12, false), -1e-11);
        assert_eq!(bound_at_most(-1e-11, -5e-12, true), 0.0);
        assert_eq!(bound_at_most(1.0, -5e-12, false), -5e-12);
        assert_eq!(bound_at_most(f64::NAN, 2.0, false), f64::NEG_INFINITY);
        assert_eq!(bound_at_most(f64::INFINITY, 2.0, false), f64::NEG_INFINITY);
    }
}
