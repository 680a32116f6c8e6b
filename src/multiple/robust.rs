//! Robust losses on the residual angle (L1, Huber, Cauchy), minimised by iteratively
//! reweighted Lie-algebraic least squares (`paper-notes/multiple.md`, `[M7]`, `[M9]`); for
//! anisotropic measurements on the Mahalanobis angle (`paper-notes/anisotropic.md` `[A10]`).

use crate::error::Result;
use crate::linalg::linear_solver::SolverKind;
use crate::multiple::MultipleProblem;
use crate::multiple::anisotropic::geodesic_edge;
use crate::multiple::chordal::chordal_gradient;
use crate::multiple::geodesic::lie_algebraic;
use crate::multiple::solve::{MultipleSettings, MultipleSolution};
use crate::objective::{Loss, Objective};
use crate::so3::{Rotation, log};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use std::fmt;

/// `(rho(theta), psi(theta))` for a residual angle `theta` (radians) under `objective` `[M7]`,
/// where the edge cost is `w rho(theta)` ([`Objective::term`]) and `psi = rho'(theta) / theta`
/// is the IRLS weight factor. For L1, `psi = 1 / max(theta, l1_epsilon)` (the smoothing). For
/// chordal L2, `rho = 8 sin^2(theta / 2)` and `psi = 4 sin(theta) / theta`; for the geodesic
/// metric `psi = 2 psi_irls(theta)` with [`Objective::irls_weight`].
pub fn objective_terms(objective: &Objective, theta: f64, l1_epsilon: f64) -> (f64, f64) {
    if objective.is_chordal_l2() {
        let s = (0.5 * theta).sin();
        let psi = if theta < 1e-8 {
            4.0
        } else {
            4.0 * theta.sin() / theta
        };
        return (8.0 * s * s, psi);
    }
    let psi = match objective.loss {
        Loss::L1 => 1.0 / theta.max(l1_epsilon),
        _ => 2.0 * objective.irls_weight(theta, l1_epsilon),
    };
    (objective.term(theta), psi)
}

/// Cost `sum_e w_e rho(theta_e)` under the problem's objective and its gradient in the right-perturbation chart
/// `R_i exp(hat w_i)` `[M8]`: with `r_e = log(R_j^T R_ij R_i)` (so `theta_e = |r_e|`),
/// `grad_i += w_e psi(theta_e) r_e`, `grad_j -= w_e psi(theta_e) r_e`. For
/// chordal L2 this is [`chordal_gradient`]. For L1 the gradient is that of the smoothed
/// cost (the cost returned is the exact `sum w theta`). Anisotropic measurements: the loss of
/// the Mahalanobis angle, `sum wbar rho(theta_H)`, with `grad_j += G^T psi H e`,
/// `grad_i -= G^T psi H e`, `G = J_r^{-1}(e) R_i` (`paper-notes/anisotropic.md` `[A10]`).
/// Panics if `rotations.len() != n`.
///
/// ```
/// use rotavg::multiple::{objective_cost_gradient, synthetic::SyntheticGraph};
/// use rotavg::objective::{Loss, Objective};
/// use rotavg::Metric;
/// let (p, gt) = SyntheticGraph { noise_sigma: 0.0, ..Default::default() }.generate();
/// let p = p.with_objective(Objective::new(Metric::Geodesic, Loss::L2)).unwrap();
/// let (cost, grad) = objective_cost_gradient(&p, &gt, 1e-6);
/// assert!(cost < 1e-20 && grad.iter().all(|g| g.norm() < 1e-12));
/// ```
pub fn objective_cost_gradient(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    l1_epsilon: f64,
) -> (f64, Vec<Vector3<f64>>) {
    if problem.objective().is_chordal_l2() {
        return chordal_gradient(problem, rotations);
    }
    let ev = evaluate(problem, rotations, l1_epsilon);
    (ev.cost, ev.grad)
}

/// Cost, gradient and the reweighting of one (reweighted) Gauss-Newton step of a geodesic
/// objective at an estimate ([`evaluate`]).
pub(crate) struct Eval {
    pub cost: f64,
    pub grad: Vec<Vector3<f64>>,
    /// Isotropic: the edges' factors `psi(theta_e)` (the step's normal matrix is the scalar
    /// Laplacian of the weights `w_e psi_e`, [M8]).
    pub psi: Vec<f64>,
    /// Anisotropic: the edges' 3x3 blocks `psi G^T H G` of the normal matrix `[A10]` (empty for
    /// isotropic problems).
    pub blocks: Vec<Matrix3<f64>>,
}

/// [`Eval`] of `rotations` under the problem's (geodesic or robust) objective.
pub(crate) fn evaluate(problem: &MultipleProblem, rotations: &[Rotation], eps: f64) -> Eval {
    assert_eq!(rotations.len(), problem.num_rotations());
    let objective = problem.objective();
    let mut ev = Eval {
        cost: 0.0,
        grad: vec![Vector3::zeros(); rotations.len()],
        psi: Vec::new(),
        blocks: Vec::new(),
    };
    if let Some(info) = problem.information() {
        for (e, h) in problem.edges().iter().zip(info) {
            let ge = geodesic_edge(h, &e.rotation, &rotations[e.i], &rotations[e.j]);
            let (rho, p) = objective_terms(&objective, ge.angle, eps);
            ev.cost += e.weight * rho; // weight = tr(H) / 3
            let g = ge.g.transpose() * (ge.he * p);
            ev.grad[e.j] += g;
            ev.grad[e.i] -= g;
            ev.blocks.push(ge.g.transpose() * h.matrix() * ge.g * p);
        }
        return ev;
    }
    for e in problem.edges() {
        let v = edge_log(e, rotations);
        let (rho, p) = objective_terms(&objective, v.norm(), eps);
        ev.cost += e.weight * rho;
        let g = v * (e.weight * p);
        ev.grad[e.i] += g;
        ev.grad[e.j] -= g;
        ev.psi.push(p);
    }
    ev
}

/// `r_e = log(R_j^T R_ij R_i)`.
pub(crate) fn edge_log(e: &crate::multiple::Edge, rotations: &[Rotation]) -> Vector3<f64> {
    log(&(rotations[e.j].inverse() * e.rotation * rotations[e.i]))
}

/// IRLS for L1 / Huber / Cauchy from `init` `[M9]`. At most `max_iterations` iterations.
pub(crate) fn solve_robust(
    problem: &MultipleProblem,
    init: Vec<Rotation>,
    settings: &MultipleSettings,
    solver_kind: Option<SolverKind>,
) -> Result<MultipleSolution> {
    let objective = problem.objective();
    let name = match objective.loss {
        _ if objective.is_chordal_l2() => "irls-chordal",
        Loss::L1 => "irls-l1",
        Loss::Huber { .. } => "irls-huber",
        Loss::Cauchy { .. } => "irls-cauchy",
        Loss::L2 => "lie-algebraic",
    };
    lie_algebraic(
        problem,
        init,
        settings,
        name,
        settings.max_iterations,
        solver_kind,
    )
}

/// The inlier threshold of the L1 loss when none is given ([`MultipleSettings::inlier_threshold_deg`]),
/// degrees: the command line's `--loss-threshold` default.
pub const DEFAULT_L1_INLIER_THRESHOLD_DEG: f64 = 5.0;

/// The inlier threshold (degrees) that applies to `objective` under `settings`, for the robust
/// losses: [`MultipleSettings::inlier_threshold_deg`] when set, else the Huber threshold or
/// Cauchy scale, else (L1) [`DEFAULT_L1_INLIER_THRESHOLD_DEG`]. `None` for the L2 losses
/// (chordal, geodesic), which down-weight nothing.
///
/// ```
/// use rotavg::multiple::MultipleSettings;
/// use rotavg::multiple::robust::inlier_threshold_deg;
/// use rotavg::objective::{Loss, Objective};
/// use rotavg::Metric;
/// let s = MultipleSettings::default();
/// let huber = Objective::new(Metric::Geodesic, Loss::Huber { threshold_deg: 3.0 });
/// assert_eq!(inlier_threshold_deg(&huber, &s), Some(3.0));
/// assert_eq!(inlier_threshold_deg(&Objective::new(Metric::Geodesic, Loss::L1), &s), Some(5.0));
/// assert_eq!(inlier_threshold_deg(&Objective::CHORDAL_L2, &s), None);
/// let s = MultipleSettings { inlier_threshold_deg: Some(2.0), ..Default::default() };
/// assert_eq!(inlier_threshold_deg(&huber, &s), Some(2.0));
/// ```
pub fn inlier_threshold_deg(objective: &Objective, settings: &MultipleSettings) -> Option<f64> {
    match objective.loss {
        Loss::L2 => None,
        Loss::L1 => Some(
            settings
                .inlier_threshold_deg
                .unwrap_or(DEFAULT_L1_INLIER_THRESHOLD_DEG),
        ),
        Loss::Huber { .. } | Loss::Cauchy { .. } => settings
            .inlier_threshold_deg
            .or(objective.loss.threshold_deg()),
    }
}

/// The final IRLS weight of an edge with residual angle `theta` (radians) relative to the
/// edge's own weight, in `(0, 1]` (1: not down-weighted): Huber `min(1, c / theta)`, Cauchy
/// `1 / (1 + theta^2 / c^2)` (the factors [`Objective::irls_weight`] of the iteration), and for
/// L1, whose IRLS factor `1 / theta` has no scale of its own, `min(1, tau / theta)` with `tau`
/// the inlier threshold (the L1 weight relative to that of an edge at the threshold). 1 for
/// the L2 losses.
pub fn relative_weight(objective: &Objective, theta: f64, inlier_threshold_deg: f64) -> f64 {
    match objective.loss {
        Loss::L2 => 1.0,
        Loss::L1 => {
            let tau = inlier_threshold_deg.to_radians();
            if theta <= tau { 1.0 } else { tau / theta }
        }
        Loss::Huber { .. } | Loss::Cauchy { .. } => {
            objective.irls_weight(objective.metric.from_angle(theta), f64::MIN_POSITIVE)
        }
    }
}

/// Counts and quantiles of the per-edge residual angles of an estimate (degrees).
/// Quantiles interpolate linearly between ranks: `q(p)` at rank `p (m - 1)` of the sorted
/// residuals (so the median of an even count is the mean of the two middle values).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ResidualSummary {
    /// The inlier rule's threshold: an edge is an inlier iff `residual_deg <= threshold_deg`.
    pub inlier_threshold_deg: f64,
    /// Number of edges `M`.
    pub num_edges: usize,
    /// Edges with `residual_deg <= inlier_threshold_deg`.
    pub num_inliers: usize,
    /// `M - num_inliers`.
    pub num_outliers: usize,
    /// Smallest residual.
    pub min_deg: f64,
    /// 25 % quantile.
    pub q25_deg: f64,
    /// Median.
    pub median_deg: f64,
    /// 75 % quantile.
    pub q75_deg: f64,
    /// 90 % quantile.
    pub q90_deg: f64,
    /// Largest residual.
    pub max_deg: f64,
}

impl fmt::Display for ResidualSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} inliers, {} outliers of {} edges (inlier: residual <= {} deg); residual quantiles (deg): min {:.3}, 25% {:.3}, median {:.3}, 75% {:.3}, 90% {:.3}, max {:.3}",
            self.num_inliers,
            self.num_outliers,
            self.num_edges,
            self.inlier_threshold_deg,
            self.min_deg,
            self.q25_deg,
            self.median_deg,
            self.q75_deg,
            self.q90_deg,
            self.max_deg
        )
    }
}

/// Per-edge residuals of an estimate, in the problem's edge order: the residual angle
/// `theta(R_ij R_i, R_j)` in degrees (for anisotropic measurements the Mahalanobis angle
/// `theta_H` the loss applies to, [`MultipleProblem::objective_angles`]), the final IRLS weight relative to the edge's own weight
/// ([`relative_weight`]), and the inlier flag `residual_deg <= inlier_threshold_deg`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EdgeResiduals {
    /// Residual angle of each edge, degrees.
    pub residual_deg: Vec<f64>,
    /// Final IRLS weight of each edge relative to its own weight, in `(0, 1]`.
    pub weight: Vec<f64>,
    /// `residual_deg <= inlier_threshold_deg`.
    pub inlier: Vec<bool>,
    /// Counts and quantiles.
    pub summary: ResidualSummary,
}

impl EdgeResiduals {
    /// Indices of the inlier edges, in edge order.
    pub fn inlier_edges(&self) -> Vec<usize> {
        (0..self.inlier.len()).filter(|&k| self.inlier[k]).collect()
    }
}

/// The per-edge residuals of `rotations` under `problem`'s objective, with the inlier rule
/// `residual_deg <= inlier_threshold_deg` (any threshold; [`inlier_threshold_deg`] gives the
/// one a solve uses). [`solve_multiple`](crate::multiple::solve_multiple) attaches them to the
/// solution of a robust loss. Panics if `rotations.len() != n`.
///
/// ```
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::multiple::robust::edge_residuals;
/// use rotavg::objective::{Loss, Objective};
/// use rotavg::so3::exp;
/// use rotavg::{Metric, Rotation};
/// // A triangle of identities, one edge measuring a 30-degree turn instead.
/// let e = |i, j, r| Edge { i, j, rotation: r, weight: 2.0 };
/// let turn = exp(&nalgebra::Vector3::new(0.0, 0.0, 30f64.to_radians()));
/// let p = MultipleProblem::new(3, vec![e(0, 1, Rotation::identity()), e(1, 2, Rotation::identity()), e(2, 0, turn)])?
///     .with_objective(Objective::new(Metric::Geodesic, Loss::Huber { threshold_deg: 5.0 }))?;
/// let r = edge_residuals(&p, &[Rotation::identity(); 3], 5.0);
/// assert_eq!(r.inlier, [true, true, false]);
/// assert!((r.residual_deg[2] - 30.0).abs() < 1e-9);
/// assert!((r.weight[2] - 5.0 / 30.0).abs() < 1e-9); // Huber: c / theta
/// assert_eq!((r.summary.num_inliers, r.summary.num_outliers), (2, 1));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn edge_residuals(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    inlier_threshold_deg: f64,
) -> EdgeResiduals {
    let objective = problem.objective();
    let theta = problem.objective_angles(rotations);
    let residual_deg: Vec<f64> = theta.iter().map(|t| t.to_degrees()).collect();
    let weight = theta
        .iter()
        .map(|&t| relative_weight(&objective, t, inlier_threshold_deg))
        .collect();
    let inlier: Vec<bool> = residual_deg
        .iter()
        .map(|&d| d <= inlier_threshold_deg)
        .collect();
    let mut sorted = residual_deg.clone();
    sorted.sort_by(f64::total_cmp);
    let q = |p: f64| crate::validate::quantile_sorted(&sorted, p);
    let num_inliers = inlier.iter().filter(|&&b| b).count();
    let summary = ResidualSummary {
        inlier_threshold_deg,
        num_edges: residual_deg.len(),
        num_inliers,
        num_outliers: residual_deg.len() - num_inliers,
        min_deg: q(0.0),
        q25_deg: q(0.25),
        median_deg: q(0.5),
        q75_deg: q(0.75),
        q90_deg: q(0.9),
        max_deg: q(1.0),
    };
    EdgeResiduals {
        residual_deg,
        weight,
        inlier,
        summary,
    }
}

/// An estimate of a least-squares cost whose residuals look like the data contain outliers
/// (issue 27): the chordal L2 answer is then pulled by them, and a robust loss (with the
/// certificate of its inlier graph) is the better tool. Reported by the pipeline on stderr and in
/// the JSON (`details.outliers`); never part of a certificate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OutlierWarning {
    /// Edges whose residual exceeds `threshold_deg`.
    pub suspected: usize,
    /// Edges in all.
    pub num_edges: usize,
    /// The smallest residual angle among the suspected edges, degrees (each is above 5 degrees
    /// and above six times the median in units of its own noise, [`suspected_outliers`]).
    pub threshold_deg: f64,
    /// The median residual angle, degrees.
    pub median_deg: f64,
    /// What to run instead.
    pub suggestion: String,
}

impl fmt::Display for OutlierWarning {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} of {} edges have residuals of {:.1} deg or more, far outside the noise (median \
             {:.2} deg): the data look like they contain outliers, which pull the least-squares \
             answer; {}",
            self.suspected, self.num_edges, self.threshold_deg, self.median_deg, self.suggestion
        )
    }
}

/// The smallest share of the edges (and count) flagged before [`suspected_outliers`] warns.
const OUTLIER_SHARE: f64 = 0.01;

/// Whether [`suspected_outliers`] judges `problem` at all: at least two edges per node.
pub fn judges_residuals(problem: &MultipleProblem) -> bool {
    problem.num_edges() >= 2 * problem.num_rotations()
}

/// [`OutlierWarning`] for `rotations` when at least 1 % (and 3) of the edges have a residual
/// angle (anisotropic: Mahalanobis angle, [`MultipleProblem::objective_angles`]) above 5 degrees and a weighted residual `sqrt(w) theta` above 6 times the median
/// weighted residual (weights are informations, so `sqrt(w) theta` is in units of each edge's own
/// noise: precise odometry and noisy loop closures are not told apart as outliers); `None`
/// otherwise. Gaussian noise stays below six times its median (the chance is below 1e-9 per
/// edge for 3-D isotropic noise), while a wrong measurement's residual is typically tens of
/// degrees. Only graphs with at least two edges per node are judged: with less redundancy (a
/// SLAM chain with a few loop closures) most edges are tree edges whose residuals vanish at any
/// least-squares answer, so the median says nothing about the noise.
pub fn suspected_outliers(
    problem: &MultipleProblem,
    rotations: &[Rotation],
) -> Option<OutlierWarning> {
    if !judges_residuals(problem) {
        return None;
    }
    let theta = problem.objective_angles(rotations);
    let weighted: Vec<f64> = theta
        .iter()
        .zip(problem.edges())
        .map(|(t, e)| e.weight.sqrt() * t)
        .collect();
    let median = |v: &[f64]| {
        let mut v = v.to_vec();
        v.sort_by(f64::total_cmp);
        crate::validate::quantile_sorted(&v, 0.5)
    };
    let cut = 6.0 * median(&weighted);
    let floor = 5f64.to_radians();
    let suspect: Vec<f64> = theta
        .iter()
        .zip(&weighted)
        .filter(|&(&t, &w)| t > floor && w > cut)
        .map(|(t, _)| t.to_degrees())
        .collect();
    let (suspected, m) = (suspect.len(), theta.len());
    let threshold_deg = suspect.iter().copied().fold(f64::INFINITY, f64::min);
    let median_deg = median(&theta).to_degrees();
    (suspected >= 3 && suspected as f64 >= OUTLIER_SHARE * m as f64).then(|| OutlierWarning {
        suspected,
        num_edges: m,
        threshold_deg,
        median_deg,
        suggestion: "a robust loss (command line `--loss cauchy`, or huber / l1) solves it and \
                     certifies the chordal L2 problem on its inlier graph"
            .into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::multiple::{Edge, MultipleProblem};
    use crate::so3::{Metric, exp};

    /// `[M7]`: the reported robust cost is `sum w rho(theta)` with the table's `rho` (Huber
    /// `theta^2` inside, `2 c theta - c^2` beyond; Cauchy `c^2 ln(1 + theta^2 / c^2)`), evaluated
    /// here from the residual angles planted on a two-node graph.
    #[test]
    fn huber_and_cauchy_costs_follow_the_table() {
        let c = 10f64.to_radians();
        for theta in [0.5 * c, 2.0 * c, 3.0] {
            let e = |w: f64| Edge {
                i: 0,
                j: 1,
                rotation: exp(&(nalgebra::Vector3::z() * theta)),
                weight: w,
            };
            let y = vec![Rotation::identity(); 2];
            let huber = Objective::new(
                Metric::Geodesic,
                Loss::Huber {
                    threshold_deg: 10.0,
                },
            );
            let cauchy = Objective::new(Metric::Geodesic, Loss::Cauchy { scale_deg: 10.0 });
            let expected_huber = if theta <= c {
                theta * theta
            } else {
                2.0 * c * theta - c * c
            };
            let expected_cauchy = c * c * (1.0 + theta * theta / (c * c)).ln();
            for (o, expected) in [(huber, expected_huber), (cauchy, expected_cauchy)] {
                let p = MultipleProblem::new(2, vec![e(3.0)])
                    .unwrap()
                    .with_objective(o)
                    .unwrap();
                let cost = p.cost(&y);
                assert!(
                    (cost - 3.0 * expected).abs() < 1e-12 * cost.max(1.0),
                    "{o} {theta}: {cost}"
                );
                // the IRLS factor psi = rho' / theta of the table
                let (rho, psi) = objective_terms(&o, theta, 1e-6);
                assert!((rho - expected).abs() < 1e-12);
                let derivative = match o.loss {
                    Loss::Huber { .. } if theta <= c => 2.0 * theta,
                    Loss::Huber { .. } => 2.0 * c,
                    _ => 2.0 * theta / (1.0 + theta * theta / (c * c)),
                };
                assert!(
                    (psi - derivative / theta).abs() < 1e-12,
                    "{o} {theta}: psi {psi}"
                );
            }
        }
    }
}
