//! The inlier graph of an estimate: the edges whose residual is within an inlier threshold,
//! and the chordal L2 problem on its largest connected component, certified. Two uses:
//!
//! - after a robust solve ([`certify_inlier_graph`]): the component is **refined** from the
//!   robust estimate and certified ([`InlierGraph`]), what `rotavg multiple --loss cauchy`
//!   reports;
//! - for an estimate computed elsewhere ([`certify_estimate_inliers`]): the inlier set comes
//!   from **the estimate's own residuals** and the estimate is certified on it **unchanged**
//!   ([`EstimateInlierGraph`]), what `rotavg certify --loss cauchy` reports.
//!
//! Either certificate is about the chordal L2 problem on those edges (`chordal_l2_inliers`),
//! never about the robust cost on all edges.

use super::{AverageSettings, MultipleEstimate, PipelineDetails, PipelineProblem, average};
use crate::certify::{
    Certificate, CertifiedProblem, CertifiedProblemKind, CertifyDetails, CertifySettings,
    certify_multiple,
};
use crate::error::Result;
use crate::multiple::problem::place_component;
use crate::multiple::robust::{EdgeResiduals, ResidualSummary, edge_residuals};
use crate::multiple::{Initialisation, MultipleProblem, MultipleSettings, MultipleSolution};
use crate::objective::Objective;
use crate::so3::Rotation;
use crate::termination::SolverReport;
use serde::{Deserialize, Serialize};
use std::fmt;

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
        let extent = Extent {
            what: "inlier graph",
            problem: p,
            threshold_deg: self.inlier_threshold_deg,
            other_component_sizes: &self.other_component_sizes,
            isolated_nodes: self.isolated_nodes,
            left_out: "not certified",
        };
        write!(f, "{extent}")?;
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
/// exactly as [`super::average_multiple`] certifies a chordal solve (improvements adopted). The
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
    inlier_graph_of(problem, robust, settings)
}

/// [`certify_inlier_graph`] for any problem on a view graph ([`ViewGraphProblem`]): the
/// inlier component is refined and certified as a problem of the same kind
/// ([`ViewGraphProblem::restricted`]: with gravity, the component's priors held).
pub(crate) fn inlier_graph_of<P: ViewGraphProblem>(
    problem: &P,
    robust: &MultipleSolution,
    settings: &AverageSettings<MultipleSettings>,
) -> Result<Option<InlierGraph>> {
    let graph = problem.graph();
    let Some(residuals) = &robust.residuals else {
        return Ok(None);
    };
    if !has_inliers(graph, robust, residuals)? {
        return Ok(None);
    }
    let InlierComponent {
        sub,
        nodes,
        problem: certified,
        other_component_sizes,
        isolated_nodes,
    } = InlierComponent::of(graph, &residuals.inlier, problem.inliers_kind())?;
    let init: Vec<Rotation> = nodes.iter().map(|&v| robust.rotations[v]).collect();
    let sub_problem = problem.restricted(sub, &nodes)?;
    let robust_chordal_cost = sub_problem.certified_cost(&init);
    let sub_settings = AverageSettings {
        solve: MultipleSettings {
            init: Initialisation::Given(init),
            robust_on_outliers: None,
            ..settings.solve.clone()
        },
        certify: settings.certify.clone(),
    };
    let refined = average(&sub_problem, &sub_settings)?;
    let estimate = problem.place(&nodes, &refined.solution.rotations, &robust.rotations);
    // the cost of the reported rotations (equal to the refinement's up to rounding: a gauge)
    let reported: Vec<Rotation> = nodes.iter().map(|&v| estimate[v]).collect();
    let chordal_cost = sub_problem.certified_cost(&reported);
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

/// What the rule `auto` and the inlier graph need of a problem on a view graph: multiple
/// averaging, and multiple averaging with gravity priors (one shape for both).
pub(crate) trait ViewGraphProblem:
    PipelineProblem<Settings = MultipleSettings, Solution = MultipleSolution> + Sized
{
    /// The kind of its inlier graph's problem.
    fn inliers_kind(&self) -> CertifiedProblemKind;
    /// The cost its certificate bounds at `rotations`: the view graph's chordal cost (with
    /// soft gravity priors, plus theirs).
    fn certified_cost(&self, rotations: &[Rotation]) -> f64 {
        self.graph().chordal_cost(rotations)
    }
    /// The view graph.
    fn graph(&self) -> &MultipleProblem;
    /// The same problem under another objective.
    fn with_objective(&self, objective: Objective) -> Result<Self>;
    /// Its whole pipeline (`average_multiple`, `average_with_gravity`).
    fn average_all(&self, settings: &AverageSettings<MultipleSettings>)
    -> Result<MultipleEstimate>;
    /// The problem on the component `nodes` (indices of this problem) whose view graph is `sub`.
    fn restricted(&self, sub: MultipleProblem, nodes: &[usize]) -> Result<Self>;
    /// The robust estimate with a component's refinement in place ([`place_component`]).
    fn place(&self, nodes: &[usize], refined: &[Rotation], robust: &[Rotation]) -> Vec<Rotation> {
        place_component(nodes, refined, robust)
    }
}

impl ViewGraphProblem for MultipleProblem {
    fn inliers_kind(&self) -> CertifiedProblemKind {
        CertifiedProblemKind::ChordalL2Inliers
    }
    fn graph(&self) -> &MultipleProblem {
        self
    }
    fn with_objective(&self, objective: Objective) -> Result<Self> {
        self.clone().with_objective(objective)
    }
    fn average_all(
        &self,
        settings: &AverageSettings<MultipleSettings>,
    ) -> Result<MultipleEstimate> {
        super::average_multiple(self, settings)
    }
    fn restricted(&self, sub: MultipleProblem, _nodes: &[usize]) -> Result<Self> {
        Ok(sub)
    }
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

/// An estimate computed elsewhere, judged on the chordal L2 problem of **its own** inlier
/// graph, **unchanged** ([`certify_estimate_inliers`]; `rotavg certify --loss`).
///
/// The inlier set is the edges whose residual at the given estimate (the angle, or the
/// Mahalanobis angle where the problem has information) is at most `inlier_threshold_deg`;
/// `residuals` states it (counts and quantiles). The certificate is that of the given rotations
/// of the inlier graph's largest connected component on the chordal L2 problem of its edges
/// (`certified_problem`: `chordal_l2_inliers`); nodes outside the component are not judged.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimateInlierGraph {
    /// The problem certified: kind and size against the whole graph's.
    pub problem: CertifiedProblem,
    /// The inlier threshold (degrees) that selected the edges.
    pub inlier_threshold_deg: f64,
    /// The given estimate's residuals on every edge (counts and quantiles, degrees).
    pub residuals: ResidualSummary,
    /// The nodes of the certified component (indices of the whole problem, increasing).
    pub nodes: Vec<usize>,
    /// Sizes of the other components of the inlier graph that have edges (not certified).
    pub other_component_sizes: Vec<usize>,
    /// Nodes with no inlier edge.
    pub isolated_nodes: usize,
    /// Chordal cost of the given estimate on the certified component (the certificate's
    /// upper bound).
    pub chordal_cost: f64,
    /// The certificate of the given estimate on the certified component.
    pub certificate: Certificate,
    /// What the certification did.
    pub details: CertifyDetails,
}

impl fmt::Display for EstimateInlierGraph {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let extent = Extent {
            what: "inlier graph of the given estimate",
            problem: &self.problem,
            threshold_deg: self.inlier_threshold_deg,
            other_component_sizes: &self.other_component_sizes,
            isolated_nodes: self.isolated_nodes,
            left_out: "not judged",
        };
        write!(f, "{extent}")?;
        write!(
            f,
            "
residuals of the given estimate: {}",
            self.residuals
        )?;
        write!(
            f,
            "
inlier graph chordal L2 cost of the given estimate: {:.9e}
inlier-graph certificate: ",
            self.chordal_cost
        )?;
        super::nested(f, &self.certificate)
    }
}

/// Judge `rotations`, an estimate of `problem` computed elsewhere, on the chordal L2 problem of
/// its own inlier graph ([`EstimateInlierGraph`]): the edges whose residual at `rotations` is
/// at most `inlier_threshold_deg` (degrees; the Mahalanobis angle where the problem has
/// information), their largest connected component, and [`certify_multiple`] of the given
/// rotations of that component with `settings`, the estimate unchanged (the certification's
/// improvement, if any, is not adopted). `None` when no edge is an inlier. Errors: an
/// estimate of the wrong size, or not of rotations; a threshold not positive and finite.
///
/// ```
/// use rotavg::certify::{CertifiedProblemKind, CertifySettings};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// use rotavg::pipeline::certify_estimate_inliers;
/// // noise-free data with 20 % of the edges replaced by random rotations: the ground truth
/// // is exact on the inliers, so it is optimal for their chordal L2 problem
/// let spec = SyntheticGraph { num_rotations: 30, num_edges: 120, noise_sigma: 0.0, outlier_fraction: 0.2, ..Default::default() };
/// let (p, truth) = spec.generate();
/// let g = certify_estimate_inliers(&p, &truth, 5.0, &CertifySettings::default())?.unwrap();
/// assert!(g.certificate.is_certified());
/// assert_eq!(g.problem.kind, CertifiedProblemKind::ChordalL2Inliers);
/// assert_eq!(g.problem.num_edges, g.residuals.num_inliers);
/// assert!(g.chordal_cost < 1e-20);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn certify_estimate_inliers(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    inlier_threshold_deg: f64,
    settings: &CertifySettings,
) -> Result<Option<EstimateInlierGraph>> {
    crate::validate::positive("inlier_threshold_deg", inlier_threshold_deg)?;
    problem.check_estimate(rotations)?;
    let residuals = edge_residuals(problem, rotations, inlier_threshold_deg);
    if !residuals.inlier.contains(&true) {
        return Ok(None);
    }
    let component = InlierComponent::of(
        problem,
        &residuals.inlier,
        CertifiedProblemKind::ChordalL2Inliers,
    )?;
    let given: Vec<Rotation> = component.nodes.iter().map(|&v| rotations[v]).collect();
    let c = certify_multiple(&component.sub, &given, settings)?;
    Ok(Some(EstimateInlierGraph {
        problem: component.problem,
        inlier_threshold_deg,
        residuals: residuals.summary,
        chordal_cost: component.sub.chordal_cost(&given),
        certificate: c.certificate.for_problem(component.problem),
        details: c.details,
        nodes: component.nodes,
        other_component_sizes: component.other_component_sizes,
        isolated_nodes: component.isolated_nodes,
    }))
}

/// The first line of an inlier graph's text: its size against the whole graph's, and what its
/// largest component leaves out.
struct Extent<'a> {
    what: &'a str,
    problem: &'a CertifiedProblem,
    threshold_deg: f64,
    other_component_sizes: &'a [usize],
    isolated_nodes: usize,
    /// What happens to the rest (`not certified`, `not judged`).
    left_out: &'a str,
}

impl fmt::Display for Extent<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let p = self.problem;
        write!(
            f,
            "{}: {} of {} edges (residual <= {} deg), {} of {} nodes",
            self.what, p.num_edges, p.total_edges, self.threshold_deg, p.num_nodes, p.total_nodes
        )?;
        if !self.other_component_sizes.is_empty() || self.isolated_nodes > 0 {
            write!(
                f,
                " (its largest component; other components of sizes {:?} and {} nodes without an \
                 inlier edge {})",
                self.other_component_sizes, self.isolated_nodes, self.left_out
            )?;
        }
        Ok(())
    }
}

/// The largest connected component of the edges flagged in `inlier`, as a problem of its own,
/// with what it leaves out.
struct InlierComponent {
    /// The component's problem (its nodes renumbered in increasing order).
    sub: MultipleProblem,
    /// The component's nodes, as indices of the whole problem (increasing).
    nodes: Vec<usize>,
    /// The component against the whole problem (`chordal_l2_inliers`).
    problem: CertifiedProblem,
    /// Sizes of the other components that have edges.
    other_component_sizes: Vec<usize>,
    /// Nodes without an inlier edge.
    isolated_nodes: usize,
}

impl InlierComponent {
    /// The component of `problem`'s edges with `inlier[k]` (chordal L2: the anisotropic
    /// chordal cost with the inliers' information where the problem has it).
    fn of(problem: &MultipleProblem, inlier: &[bool], kind: CertifiedProblemKind) -> Result<Self> {
        let inliers = problem.edge_subset(inlier)?;
        let components = inliers.components();
        let isolated_nodes = components.iter().filter(|c| c.len() == 1).count();
        let other_component_sizes = components
            .iter()
            .skip(1)
            .filter(|c| c.len() > 1)
            .map(Vec::len)
            .collect();
        let (sub, nodes) = inliers.largest_component();
        let certified = CertifiedProblem {
            kind,
            num_nodes: sub.num_rotations(),
            total_nodes: problem.num_rotations(),
            num_edges: sub.num_edges(),
            total_edges: problem.num_edges(),
        };
        Ok(InlierComponent {
            sub,
            nodes,
            problem: certified,
            other_component_sizes,
            isolated_nodes,
        })
    }
}
