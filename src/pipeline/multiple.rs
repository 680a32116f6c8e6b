//! The multiple-rotation-averaging pipeline `[D12]` (`paper-notes/certificates.md`):
//! initialise and solve locally ([`solve_multiple`]), then certify ([`certify_multiple`]: the
//! dual certificate, then the SDP or the staircase when needed) and adopt the refined estimate
//! or the polished SDP rounding when it is better. With a robust loss (L1, Huber, Cauchy) the
//! robust cost has no certificate; the pipeline certifies instead the chordal L2 problem on the
//! edges the robust solver kept ([`InlierGraph`], [`certify_inlier_graph`]).

use super::{
    AverageSettings, Averaged, PipelineDetails, PipelineProblem, PipelineSolution, average,
};
use crate::certify::{
    Certificate, Certification, CertifiedProblem, CertifiedProblemKind, CertifyMode,
    CertifySettings, certify_multiple,
};
use crate::error::Result;
use crate::multiple::robust::{EdgeResiduals, inlier_threshold_deg, suspected_outliers};
use crate::multiple::{
    Initialisation, MultipleProblem, MultipleSettings, MultipleSolution, solve_multiple,
};
use crate::so3::{Rotation, project_to_so3};
use crate::termination::SolverReport;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Instant;

impl PipelineSolution for MultipleSolution {
    fn certified_cost(&self) -> f64 {
        self.chordal_cost
    }
    fn report_mut(&mut self) -> &mut SolverReport {
        &mut self.report
    }
    fn adopt(self, mut better: Self) -> Self {
        better.report.iterations += self.report.iterations;
        better.report.seconds += self.report.seconds;
        better.init_cost = self.init_cost;
        better
    }
}

impl PipelineProblem for MultipleProblem {
    type Settings = MultipleSettings;
    type Solution = MultipleSolution;
    const NAME: &'static str = "multiple";
    const MODES: &'static [CertifyMode] = &[
        CertifyMode::Auto,
        CertifyMode::Dual,
        CertifyMode::Sdp,
        CertifyMode::Staircase,
        CertifyMode::None,
    ];
    fn validate(settings: &MultipleSettings) -> Result<()> {
        settings.validate()
    }
    fn uncertifiable(&self, _mode: CertifyMode) -> Option<String> {
        let objective = self.objective();
        (!objective.is_chordal_l2()).then(|| {
            format!("the {objective} cost has no certificate (only chordal L2 is certifiable)")
        })
    }
    fn solve(&self, settings: &MultipleSettings) -> Result<MultipleSolution> {
        solve_multiple(self, settings)
    }
    fn certify(
        &self,
        solution: &MultipleSolution,
        settings: &CertifySettings,
    ) -> Result<Certification<MultipleSolution>> {
        certify_multiple(self, &solution.rotations, settings)
    }
}

/// Multiple rotation averaging with a certificate: initialise and solve locally
/// ([`solve_multiple`] with `settings.solve`), then, for the chordal L2 objective, certify with
/// [`certify_multiple`] (dual certificate; SDP for `n <= sdp_max_nodes` or the staircase when it
/// fails) and adopt the better solution it may find (a refinement, or the polished SDP rounding).
/// The certificate's lower bound is the largest verified bound computed. Geodesic L2 gets no
/// certificate. The robust losses (L1, Huber, Cauchy) get no certificate of their cost either
/// (`certificate` is `None`); unless the mode is `none`, the pipeline then refines and
/// certifies the chordal L2 problem on their inlier graph with that mode
/// ([`certify_inlier_graph`], in `details.inlier_graph`), leaving the robust estimate as the
/// returned solution. All settings are validated before any work.
///
/// ```
/// use rotavg::pipeline::{average_multiple, AverageSettings};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, _) = SyntheticGraph { num_rotations: 30, num_edges: 90, noise_sigma: 0.05, ..Default::default() }.generate();
/// let est = average_multiple(&p, &AverageSettings::default())?;
/// assert!(est.certificate.unwrap().is_certified());
/// assert!(rotavg::so3::angle(&est.solution.rotations[0]) < 1e-12); // gauge R_0 = I
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_multiple(
    problem: &MultipleProblem,
    settings: &AverageSettings<MultipleSettings>,
) -> Result<Averaged<MultipleSolution>> {
    let objective = problem.objective();
    let mode = settings.certify.mode;
    if let Some(robust) = settings.solve.robust_on_outliers
        && objective.is_chordal_l2()
    {
        return super::loss_choice::average_by_residuals(problem, settings, robust);
    }
    if inlier_threshold_deg(&objective, &settings.solve).is_none() {
        // least squares: say when the residuals look like outliers (a robust loss is then the
        // better tool)
        let mut out = average(problem, settings)?;
        out.details.outliers = suspected_outliers(problem, &out.solution.rotations);
        return Ok(out);
    }
    if mode == CertifyMode::None {
        return average(problem, settings);
    }
    let start = Instant::now();
    settings.certify.validate()?;
    mode.require(
        <MultipleProblem as PipelineProblem>::NAME,
        <MultipleProblem as PipelineProblem>::MODES,
    )?;
    let robust_only = AverageSettings {
        solve: settings.solve.clone(),
        certify: CertifySettings {
            mode: CertifyMode::None,
            ..settings.certify.clone()
        },
    };
    let mut out = average(problem, &robust_only)?;
    let t = Instant::now();
    let graph = certify_inlier_graph(problem, &out.solution, settings)?;
    out.details.skipped_reason = Some(format!(
        "the {objective} cost has no certificate (only chordal L2 is certifiable); {}",
        match &graph {
            Some(_) => "the chordal L2 problem on its inlier graph was certified instead",
            None => "no edge is an inlier, so there is no inlier graph to certify",
        }
    ));
    out.details.inlier_graph = graph.map(Box::new);
    out.details.certify_seconds = t.elapsed().as_secs_f64();
    out.details.total_seconds = start.elapsed().as_secs_f64();
    Ok(out)
}

/// The chordal L2 problem on the inlier graph of a robust solve, refined from the robust
/// estimate and certified ([`certify_inlier_graph`]).
///
/// The inlier graph has the edges whose residual at the robust estimate is within the inlier
/// threshold ([`crate::multiple::robust::EdgeResiduals`]). When they do not connect all nodes,
/// its **largest connected component** is refined and certified, and the others are counted
/// (`other_component_sizes`, `isolated_nodes`: nodes with no inlier edge); their nodes keep the
/// robust rotations in [`InlierGraph::estimate`]. The certificate is of the chordal L2 cost
/// `sum w ||R_j - R_ij R_i||_F^2` over that component's edges (its `certified_problem` says so),
/// with the component's smallest weight in the tolerance: "globally optimal for the inlier
/// graph", never a claim about the robust cost on all edges.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct InlierGraph {
    /// The problem certified: kind and size against the whole graph's.
    pub problem: CertifiedProblem,
    /// The inlier threshold (degrees) that selected the edges.
    pub inlier_threshold_deg: f64,
    /// The nodes of the certified component (indices of the whole problem, increasing).
    pub nodes: Vec<usize>,
    /// Sizes of the other components of the inlier graph that have edges (not certified).
    pub other_component_sizes: Vec<usize>,
    /// Nodes with no inlier edge.
    pub isolated_nodes: usize,
    /// Chordal cost of the robust estimate on the certified component.
    pub robust_chordal_cost: f64,
    /// Chordal cost of the refined estimate on the certified component (the certificate's
    /// upper bound).
    pub chordal_cost: f64,
    /// The refined estimate of every node (`R_0 = I`): the refinement on `nodes` in the gauge
    /// `R_0 = I` when node 0 is among them, else aligned to the robust estimate by the best
    /// rotation `G`; the other nodes keep their robust rotations exactly.
    #[serde(with = "crate::so3::serde_rows::rotations")]
    pub estimate: Vec<Rotation>,
    /// The chordal L2 refinement (Newton-LM from the robust estimate), plus any refinement
    /// adopted while certifying.
    pub solver: SolverReport,
    /// The certificate of `estimate` on the certified component (`certified_problem` set).
    pub certificate: Option<Certificate>,
    /// What the refinement's pipeline did (methods, times).
    pub details: PipelineDetails,
}

impl fmt::Display for InlierGraph {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = &self.problem;
        write!(
            f,
            "inlier graph: {} of {} edges (residual <= {} deg), {} of {} nodes",
            p.num_edges, p.total_edges, self.inlier_threshold_deg, p.num_nodes, p.total_nodes
        )?;
        if !self.other_component_sizes.is_empty() || self.isolated_nodes > 0 {
            write!(
                f,
                " (its largest component; other components of sizes {:?} and {} nodes without an inlier edge not certified)",
                self.other_component_sizes, self.isolated_nodes
            )?;
        }
        write!(
            f,
            "\ninlier graph chordal L2: cost {:.6e} (robust estimate {:.6e}); {}",
            self.chordal_cost, self.robust_chordal_cost, self.solver
        )?;
        match &self.certificate {
            Some(c) => {
                write!(f, "\ninlier-graph certificate: ")?;
                super::nested(f, c)?;
                if c.is_certified() {
                    write!(
                        f,
                        "\n=> globally optimal for the inlier graph ({} of {} edges): a claim about the chordal L2 problem on those edges, not about the robust cost",
                        p.num_edges, p.total_edges
                    )?;
                }
                Ok(())
            }
            None => write!(
                f,
                "\ninlier-graph certificate: none ({})",
                self.details
                    .skipped_reason
                    .as_deref()
                    .unwrap_or("not requested")
            ),
        }
    }
}

/// Refine and certify the chordal L2 problem on the inlier graph of `robust`, a solution of
/// `problem` under a robust loss carrying [`MultipleSolution::residuals`] (`None` without
/// residuals or without any inlier edge). The inlier graph's largest connected component
/// ([`InlierGraph`]) is solved by the chordal Newton-LM solver started from the robust
/// estimate (`settings.solve` with `init` replaced), then certified with `settings.certify`
/// exactly as [`average_multiple`] certifies a chordal solve (improvements adopted). The
/// certificate is re-evaluated at the reported (gauge-aligned) estimate's cost.
///
/// ```
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// use rotavg::multiple::{solve_multiple, MultipleSettings};
/// use rotavg::objective::{Loss, Objective};
/// use rotavg::pipeline::{certify_inlier_graph, AverageSettings};
/// use rotavg::Metric;
/// let spec = SyntheticGraph { num_rotations: 40, num_edges: 200, noise_sigma: 0.01, outlier_fraction: 0.1, ..Default::default() };
/// let (p, _) = spec.generate();
/// let p = p.with_objective(Objective::new(Metric::Geodesic, Loss::Huber { threshold_deg: 5.0 }))?;
/// let robust = solve_multiple(&p, &MultipleSettings::default())?;
/// let g = certify_inlier_graph(&p, &robust, &AverageSettings::default())?.unwrap();
/// let c = g.certificate.unwrap();
/// assert!(c.is_certified()); // globally optimal for the chordal L2 problem on the inlier edges
/// assert_eq!(c.certified_problem.unwrap().num_edges, robust.residuals.unwrap().summary.num_inliers);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn certify_inlier_graph(
    problem: &MultipleProblem,
    robust: &MultipleSolution,
    settings: &AverageSettings<MultipleSettings>,
) -> Result<Option<InlierGraph>> {
    let Some(residuals) = &robust.residuals else {
        return Ok(None);
    };
    let n = problem.num_rotations();
    if !has_inliers(problem, robust, residuals)? {
        return Ok(None);
    }
    // chordal L2 (anisotropic chordal with the inliers' information)
    let inliers = problem.edge_subset(&residuals.inlier)?;
    let components = inliers.components();
    let isolated_nodes = components.iter().filter(|c| c.len() == 1).count();
    let other_component_sizes = components
        .iter()
        .skip(1)
        .filter(|c| c.len() > 1)
        .map(Vec::len)
        .collect();
    let (sub, nodes) = inliers.largest_component();
    let init: Vec<Rotation> = nodes.iter().map(|&v| robust.rotations[v]).collect();
    let robust_chordal_cost = sub.chordal_cost(&init);
    let sub_settings = AverageSettings {
        solve: MultipleSettings {
            init: Initialisation::Given(init),
            ..settings.solve.clone()
        },
        certify: settings.certify.clone(),
    };
    let refined = average(&sub, &sub_settings)?;
    let estimate = place_refinement(&nodes, &refined.solution.rotations, &robust.rotations);
    // the cost of the reported rotations (equal to the refinement's up to rounding: a gauge)
    let reported: Vec<Rotation> = nodes.iter().map(|&v| estimate[v]).collect();
    let chordal_cost = sub.chordal_cost(&reported);
    let certified = CertifiedProblem {
        kind: CertifiedProblemKind::ChordalL2Inliers,
        num_nodes: sub.num_rotations(),
        total_nodes: n,
        num_edges: sub.num_edges(),
        total_edges: problem.num_edges(),
    };
    let certificate = refined
        .certificate
        .map(|c| c.with_upper_bound(chordal_cost).for_problem(certified));
    Ok(Some(InlierGraph {
        problem: certified,
        inlier_threshold_deg: residuals.summary.inlier_threshold_deg,
        nodes,
        other_component_sizes,
        isolated_nodes,
        robust_chordal_cost,
        chordal_cost,
        estimate,
        solver: refined.solution.report,
        certificate,
        details: refined.details,
    }))
}

/// Whether the robust solution is an estimate of `problem` with residuals on its every edge
/// (an error when not), and has at least one inlier.
fn has_inliers(
    problem: &MultipleProblem,
    robust: &MultipleSolution,
    residuals: &EdgeResiduals,
) -> Result<bool> {
    problem.check_estimate(&robust.rotations)?;
    if residuals.inlier.len() != problem.num_edges() {
        return Err(crate::error::Error::InvalidSettings {
            name: "robust solution".into(),
            reason: format!(
                "its residuals cover {} edges, the problem has {}",
                residuals.inlier.len(),
                problem.num_edges()
            ),
        });
    }
    Ok(residuals.inlier.contains(&true))
}

/// The robust estimate with the refinement of the component `nodes` in place, in the robust
/// estimate's gauge: `R_0 G = I` when node 0 is in the component (as the robust estimate),
/// else the best alignment to the robust estimate, `max tr(G^T sum R_k^T R_v)`; nodes outside
/// the component keep their robust rotations exactly.
fn place_refinement(nodes: &[usize], refined: &[Rotation], robust: &[Rotation]) -> Vec<Rotation> {
    let g = if nodes.first() == Some(&0) {
        refined[0].inverse()
    } else {
        let mut m = Matrix3::zeros();
        for (k, &v) in nodes.iter().enumerate() {
            m += refined[k].matrix().transpose() * robust[v].matrix();
        }
        project_to_so3(&m).unwrap_or_else(Rotation::identity)
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
