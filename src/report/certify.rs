//! The report of `rotavg certify`: an estimate computed elsewhere, certified or bounded
//! **without changing it**.

use super::{CertifiedEstimate, ProblemJson, ProblemKind, Rows, VerdictOf, write_methods};
use crate::certify::{
    Certificate, CertifiedProblem, CertifiedProblemKind, CertifyDetails, CertifySettings, Verdict,
    certify_conjugate, certify_multiple, certify_single,
};
use crate::error::{Error, Result};
use crate::io::detect::{GraphFormat, ReadOptions};
use crate::io::input::{LoadedEstimate, LoadedProblem};
use crate::io::json::Estimate;
use crate::pipeline::{EstimateInlierGraph, certify_estimate_inliers};
use crate::so3::Rotation;
use crate::termination::SolverReport;
use crate::warning::Warning;
use serde::{Serialize, Serializer};
use std::fmt;

/// The certificate of a given estimate, as `rotavg certify` prints it.
///
/// JSON (`--json`): `problem`, `num_rotations`, `num_measurements`, `cost` (of the given
/// estimate: the chordal L2 cost), `estimate` (as given), `node_ids` (multiple only),
/// `solver` = null (no solver ran), `certificate`, `pipeline` (multiple only: the bounding
/// methods that ran, [`CertifyDetails`]).
/// Text: the problem and estimate, the cost, the certificate, and the methods.
///
/// ```
/// use rotavg::certify::CertifySettings;
/// use rotavg::io::input::{read_problem, Input, LoadedEstimate};
/// use rotavg::io::detect::{GraphFormat, ReadOptions};
/// use rotavg::io::json::Estimate;
/// use rotavg::report::CertifyReport;
/// use rotavg::Rotation;
/// let input = Input::new("p.json", r#"{"rotations": [[[1,0,0],[0,1,0],[0,0,1]]]}"#);
/// let problem = read_problem(&input, GraphFormat::Auto, &ReadOptions::default())?;
/// let estimate = LoadedEstimate { name: "e.json".into(), estimate: Estimate::Single(Rotation::identity()), warnings: vec![] };
/// let report = CertifyReport::certify(&input.name, &problem, estimate, &CertifySettings::default())?;
/// assert!(report.certificate.is_certified());
/// let json = serde_json::to_value(&report).unwrap();
/// assert!(json["solver"].is_null() && json.get("pipeline").is_none());
/// assert!(report.to_string().starts_with("p.json: single problem (chordal L2), 1 samples; estimate e.json"));
/// # Ok::<(), rotavg::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct CertifyReport {
    /// Which problem.
    pub problem: ProblemKind,
    /// The problem file as given.
    pub input: String,
    /// The estimate file as given.
    pub estimate_file: String,
    /// Rotations estimated (1 for single and conjugate).
    pub num_rotations: usize,
    /// Edges, samples or pairs.
    pub num_measurements: usize,
    /// The chordal L2 cost of the given estimate.
    pub cost: f64,
    /// The estimate, as given.
    pub estimate: Estimate,
    /// Multiple averaging: the file id of each node.
    pub node_ids: Option<Vec<u64>>,
    /// The certificate (its upper bound is the given estimate's cost).
    pub certificate: Certificate,
    /// Multiple averaging: what the certification did.
    pub details: Option<CertifyDetails>,
    /// The reader's and the estimate's warnings (printed on `warning:` lines).
    pub warnings: Vec<Warning>,
    /// Multiple averaging judged on a robust loss's inlier set ([`Self::certify_on_inliers`],
    /// `rotavg certify --loss`): the given estimate on the chordal L2 problem of its own
    /// inlier graph. `None` otherwise, or when no edge is an inlier.
    pub inlier_graph: Option<EstimateInlierGraph>,
    /// The loss whose inlier set was judged (`--loss`; `None`: all edges only).
    pub loss: Option<String>,
    /// Multiple averaging: the view graph's format and the options it was read with.
    pub read: Option<(GraphFormat, ReadOptions)>,
}

impl CertifyReport {
    /// Certify `estimate` for `problem` (read from the file `input`) with the certifier of its
    /// kind ([`certify_single`], [`certify_multiple`], [`certify_conjugate`]); the estimate is
    /// never changed. A multiple-averaging estimate must have one rotation per node; single
    /// and conjugate estimates are one rotation (errors name the estimate file).
    pub fn certify(
        input: &str,
        problem: &LoadedProblem,
        estimate: LoadedEstimate,
        settings: &CertifySettings,
    ) -> Result<Self> {
        let given = Given::of(input, &estimate);
        match problem {
            LoadedProblem::Multiple(graph) => {
                let rotations = estimate.into_rotations()?;
                Self::certify_graph(given, graph, rotations, None, settings)
            }
            LoadedProblem::Single(p) => {
                let r = estimate.into_rotation()?;
                let c = certify_single(p, &r, settings)?.certificate;
                let cost = c.upper_bound;
                Ok(given.report(ProblemKind::Single, p.len(), cost, Estimate::Single(r), c))
            }
            LoadedProblem::Conjugate(p) => {
                let s = estimate.into_rotation()?;
                let c = certify_conjugate(p, &s, settings)?.certificate;
                let cost = c.upper_bound;
                let inverse = convention_suspected(cost, p.chordal_cost(&s.inverse()));
                let mut report = given.report(
                    ProblemKind::Conjugate,
                    p.num_pairs(),
                    cost,
                    Estimate::Single(s),
                    c,
                );
                report.warnings.extend(inverse);
                Ok(report)
            }
        }
    }

    /// Certify a view graph's estimate (one rotation per node, never changed) for the chordal
    /// L2 problem with the gravity `priors` held ([`crate::certify::certify_gravity`]): the
    /// verdict names that problem, and the priors' check adds its warnings (`[G6]`).
    pub fn certify_with_gravity(
        input: &str,
        graph: &crate::io::detect::LoadedGraph,
        estimate: LoadedEstimate,
        priors: crate::multiple::gravity::GravityPriors,
        settings: &CertifySettings,
    ) -> Result<Self> {
        let given = Given::of(input, &estimate);
        let rotations = estimate.into_rotations()?;
        let p = crate::multiple::gravity::GravityProblem::new(graph.problem.clone(), priors)?;
        Self::certify_graph(given, graph, rotations, Some(&p), settings)
    }

    /// [`Self::certify`] of a view graph's estimate, one rotation per node (with `gravity`:
    /// on the gravity problem).
    fn certify_graph(
        given: Given<'_>,
        graph: &crate::io::detect::LoadedGraph,
        rotations: Vec<Rotation>,
        gravity: Option<&crate::multiple::gravity::GravityProblem>,
        settings: &CertifySettings,
    ) -> Result<Self> {
        let n = graph.problem.num_rotations();
        if rotations.len() != n {
            return Err(Error::parse(
                Some(&given.file),
                None,
                format!(
                    "the estimate has {} rotations, the problem has {n} nodes",
                    rotations.len()
                ),
            ));
        }
        let (c, gravity_warnings) = match gravity {
            Some(p) => gravity_certification(p, &rotations, settings)?,
            None => (
                certify_multiple(&graph.problem, &rotations, settings)?,
                Vec::new(),
            ),
        };
        let graph_cost = graph.problem.chordal_cost(&rotations);
        let transposed = transposed_cost(&graph.problem, &rotations);
        let m = graph.problem.num_edges();
        // soft gravity priors' terms are part of the cost certified ([G10])
        let priors_cost = gravity.map_or(0.0, |p| p.prior_cost(&rotations));
        let mut report = given.report(
            ProblemKind::Multiple,
            m,
            graph_cost + priors_cost,
            Estimate::Multiple(rotations),
            c.certificate,
        );
        report.num_rotations = n;
        report.read = Some((graph.format, graph.read));
        report.node_ids = Some(graph.node_ids.clone());
        report.details = Some(c.details);
        report.warnings = [
            super::input_warnings(graph),
            std::mem::take(&mut report.warnings),
            convention_suspected(graph_cost, transposed),
            gravity_warnings,
        ]
        .concat();
        Ok(report)
    }

    /// [`Self::certify`], and for a multiple-averaging estimate also the chordal L2 problem of
    /// its own inlier graph under `loss` (its name, as `rotavg certify --loss` takes it): the
    /// edges whose residual at the estimate is at most `inlier_threshold_deg`
    /// ([`certify_estimate_inliers`]). The report's verdict is then that certificate's. The
    /// time budget is shared: the all-edges certification gets half of
    /// `settings.budget.max_seconds`, the inlier graph's what is left, so the whole call keeps
    /// the margin of one certification. Single and conjugate problems are refused
    /// ([`Error::InvalidSettings`], field `loss`), as is a threshold not positive and finite.
    ///
    /// ```
    /// use rotavg::certify::{CertifiedProblemKind, CertifySettings};
    /// use rotavg::io::detect::LoadedGraph;
    /// use rotavg::io::input::{LoadedEstimate, LoadedProblem};
    /// use rotavg::io::json::Estimate;
    /// use rotavg::multiple::synthetic::SyntheticGraph;
    /// use rotavg::report::CertifyReport;
    /// let spec = SyntheticGraph { num_rotations: 20, num_edges: 80, noise_sigma: 0.0, outlier_fraction: 0.2, ..Default::default() };
    /// let (p, truth) = spec.generate();
    /// let problem = LoadedProblem::Multiple(LoadedGraph::from_problem(p));
    /// let estimate = LoadedEstimate { name: "truth".into(), estimate: Estimate::Multiple(truth), warnings: vec![] };
    /// let r = CertifyReport::certify_on_inliers("g.json", &problem, estimate, "cauchy", 5.0, &CertifySettings::default())?;
    /// assert!(!r.certificate.is_certified()); // all edges: the outliers' cost is not minimal
    /// let v = r.verdict_of().unwrap(); // the inlier graph's: the truth is exact on its edges
    /// assert!(v.verdict == rotavg::Verdict::Certified && v.problem.kind == CertifiedProblemKind::ChordalL2Inliers);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn certify_on_inliers(
        input: &str,
        problem: &LoadedProblem,
        estimate: LoadedEstimate,
        loss: &str,
        inlier_threshold_deg: f64,
        settings: &CertifySettings,
    ) -> Result<Self> {
        crate::validate::positive("inlier_threshold_deg", inlier_threshold_deg)?;
        let LoadedProblem::Multiple(graph) = problem else {
            return Err(Error::InvalidSettings {
                name: "loss".into(),
                reason: format!(
                    "a {loss} loss's inlier set judges view graphs (multiple averaging); single \
                     and conjugate problems are certified on their one cost"
                ),
            });
        };
        let start = std::time::Instant::now();
        let mut whole = settings.clone();
        whole.budget.max_seconds = settings.budget.max_seconds.map(|t| t / 2.0);
        let mut report = Self::certify(input, problem, estimate, &whole)?;
        let mut rest = settings.clone();
        rest.budget.max_seconds = settings
            .budget
            .max_seconds
            .map(|t| (t - start.elapsed().as_secs_f64()).max(1e-3));
        if let Estimate::Multiple(rotations) = &report.estimate {
            report.inlier_graph =
                certify_estimate_inliers(&graph.problem, rotations, inlier_threshold_deg, &rest)?;
        }
        report.loss = Some(loss.to_string());
        Ok(report)
    }

    /// The verdict the report gives, with the problem it is about: the inlier graph's when
    /// the estimate was judged on one ([`Self::certify_on_inliers`]), else the certificate's
    /// (multiple averaging: the chordal L2 problem on all edges). `None` for single and
    /// conjugate problems, whose certificate is about the one problem read.
    pub fn verdict_of(&self) -> Option<VerdictOf> {
        if let Some(g) = &self.inlier_graph {
            return Some(VerdictOf {
                verdict: g.certificate.verdict,
                estimate: CertifiedEstimate::Given,
                problem: g.problem,
            });
        }
        (self.problem == ProblemKind::Multiple).then_some(VerdictOf {
            verdict: self.certificate.verdict,
            estimate: CertifiedEstimate::Given,
            problem: self
                .certificate
                .certified_problem
                .unwrap_or(CertifiedProblem {
                    kind: CertifiedProblemKind::ChordalL2,
                    num_nodes: self.num_rotations,
                    total_nodes: self.num_rotations,
                    num_edges: self.num_measurements,
                    total_edges: self.num_measurements,
                }),
        })
    }

    /// The report's verdict: that of [`Self::verdict_of`] for multiple averaging (the inlier
    /// graph's under `--loss`), else the certificate's. Under `--loss` with no inlier edge, the
    /// all-edges certificate's.
    pub fn verdict(&self) -> Verdict {
        self.verdict_of()
            .map_or(self.certificate.verdict, |v| v.verdict)
    }

    /// `Ok` when [`Self::write_figure`] can draw `problem`: multiple and conjugate problems;
    /// single problems have no figure ([`Error::InvalidSettings`], field `plot`), and neither
    /// has a build without the `plot` feature. Checked before certifying, so that a bad
    /// request costs no work.
    ///
    /// ```
    /// use rotavg::io::input::LoadedProblem;
    /// use rotavg::report::CertifyReport;
    /// use rotavg::single::SingleProblem;
    /// let p = LoadedProblem::Single(SingleProblem::new(vec![rotavg::Rotation::identity()], None)?);
    /// assert!(CertifyReport::require_figure(&p).is_err());
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn require_figure(problem: &LoadedProblem) -> Result<()> {
        if !cfg!(feature = "plot") {
            return Err(no_plot_feature());
        }
        match problem {
            LoadedProblem::Single(_) => Err(no_figure()),
            LoadedProblem::Multiple(_) | LoadedProblem::Conjugate(_) => Ok(()),
        }
    }

    /// Write the `--plot` figure of the certified estimate of `problem` (the problem this
    /// report certified): residual angles and the certificate (`rotavg::plot::write_figure`).
    /// Single problems have none ([`Error::InvalidSettings`], field `plot`).
    #[cfg(feature = "plot")]
    pub fn write_figure(&self, path: &str, problem: &LoadedProblem) -> Result<()> {
        match (problem, &self.estimate) {
            (LoadedProblem::Multiple(g), Estimate::Multiple(rs)) => {
                crate::plot::write_multiple_figure(
                    path,
                    &g.problem,
                    rs,
                    Some(&self.certificate),
                    &self.input,
                )
            }
            (LoadedProblem::Conjugate(p), Estimate::Single(s)) => {
                crate::plot::write_conjugate_figure(
                    path,
                    p,
                    s,
                    Some(&self.certificate),
                    &self.input,
                )
            }
            _ => Err(no_figure()),
        }
    }

    /// Without the `plot` feature there are no figures: always [`Error::InvalidSettings`]
    /// (field `plot`).
    #[cfg(not(feature = "plot"))]
    pub fn write_figure(&self, _path: &str, _problem: &LoadedProblem) -> Result<()> {
        Err(no_plot_feature())
    }
}

/// Where a certified estimate came from: the problem file, the estimate file and the
/// estimate's own warnings.
struct Given<'a> {
    input: &'a str,
    file: String,
    warnings: Vec<Warning>,
}

impl<'a> Given<'a> {
    /// The estimate file of `estimate`, read for the problem file `input`.
    fn of(input: &'a str, estimate: &LoadedEstimate) -> Self {
        Given {
            input,
            file: estimate.name.clone(),
            warnings: estimate.warnings.clone(),
        }
    }

    /// The report of one certification (one rotation estimated; [`CertifyReport::certify_graph`]
    /// sets the view graph's fields).
    fn report(
        self,
        problem: ProblemKind,
        num_measurements: usize,
        cost: f64,
        estimate: Estimate,
        certificate: Certificate,
    ) -> CertifyReport {
        CertifyReport {
            problem,
            input: self.input.to_string(),
            estimate_file: self.file,
            num_rotations: 1,
            num_measurements,
            cost,
            estimate,
            node_ids: None,
            certificate,
            details: None,
            warnings: self.warnings,
            inlier_graph: None,
            loss: None,
            read: None,
        }
    }
}

/// The chordal cost of `rotations` with every rotation transposed (the other convention:
/// camera-to-world instead of world-to-camera).
fn transposed_cost(problem: &crate::multiple::MultipleProblem, rotations: &[Rotation]) -> f64 {
    let transposed: Vec<Rotation> = rotations.iter().map(Rotation::inverse).collect();
    problem.chordal_cost(&transposed)
}

/// The warning `convention_suspected` when the estimate transposed costs less than a quarter
/// of the estimate as given: it is likely in the other convention (`R^T`: camera-to-world, or
/// the inverse hand-eye rotation), which the certificate does not guess.
fn convention_suspected(given: f64, transposed: f64) -> Vec<Warning> {
    // NaN costs (impossible for rotations) never warn
    let far_better = transposed < 0.25 * given;
    if !far_better {
        return Vec::new();
    }
    vec![Warning::new(
        "convention_suspected",
        format!(
            "the estimate transposed (every R -> R^T) costs {transposed:.6e}, {:.1}x less than \
             as given ({given:.6e}): it may be in the other convention (rotavg's R_i is \
             world-to-camera, R_ij R_i = R_j; conjugate: R_i ~ S^-1 L_i S); certify its \
             transpose if so",
            given / transposed.max(f64::MIN_POSITIVE)
        ),
    )]
}

/// The error for `--plot` in a build without the `plot` feature.
pub fn no_plot_feature() -> Error {
    Error::InvalidSettings {
        name: "plot".into(),
        reason: "this build of rotavg draws no figures: rebuild it with the `plot` feature \
                 (on by default)"
            .into(),
    }
}

/// The error for a figure of a single problem.
fn no_figure() -> Error {
    Error::InvalidSettings {
        name: "plot".into(),
        reason: "--plot is available for multiple and conjugate problems only".into(),
    }
}

#[derive(Serialize)]
struct Json<'a> {
    input: super::InputJson<'a>,
    #[serde(skip_serializing_if = "Option::is_none")]
    verdict: Option<VerdictOf>,
    #[serde(skip_serializing_if = "Option::is_none")]
    loss: Option<&'a str>,
    cost: f64,
    estimate: Rows<'a>,
    #[serde(skip_serializing_if = "Option::is_none")]
    node_ids: Option<&'a [u64]>,
    solver: Option<&'a SolverReport>,
    certificate: &'a Certificate,
    #[serde(skip_serializing_if = "Option::is_none")]
    pipeline: Option<&'a CertifyDetails>,
    #[serde(skip_serializing_if = "Option::is_none")]
    inlier_graph: Option<&'a EstimateInlierGraph>,
}

impl Serialize for CertifyReport {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        let rest = Json {
            input: super::InputJson {
                path: &self.input,
                format: self.read.map(|(f, _)| f),
                read: self.read.as_ref().map(|(_, r)| r),
                estimate: Some(&self.estimate_file),
            },
            verdict: self.verdict_of(),
            loss: self.loss.as_deref(),
            cost: self.cost,
            estimate: match &self.estimate {
                Estimate::Single(r) => Rows::One(r),
                Estimate::Multiple(rs) => Rows::Many(rs),
            },
            node_ids: self.node_ids.as_deref(),
            solver: None,
            certificate: &self.certificate,
            pipeline: self.details.as_ref(),
            inlier_graph: self.inlier_graph.as_ref(),
        };
        ProblemJson::new(
            self.problem,
            self.num_rotations,
            self.num_measurements,
            rest,
        )
        .with_warnings(self.warnings.clone())
        .serialize(serializer)
    }
}

impl fmt::Display for CertifyReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.problem {
            ProblemKind::Multiple => write!(
                f,
                "{}: multiple problem, {} nodes, {} edges",
                self.input, self.num_rotations, self.num_measurements
            )?,
            ProblemKind::Single => write!(
                f,
                "{}: single problem (chordal L2), {} samples",
                self.input, self.num_measurements
            )?,
            ProblemKind::Conjugate => write!(
                f,
                "{}: conjugate problem (chordal L2), {} pairs",
                self.input, self.num_measurements
            )?,
        }
        writeln!(f, "; estimate {}", self.estimate_file)?;
        for w in &self.warnings {
            writeln!(f, "warning: {w}")?;
        }
        writeln!(
            f,
            "cost of the given estimate: {:.9e}",
            self.certificate.upper_bound
        )?;
        write!(f, "certificate: ")?;
        super::nested(f, &self.certificate)?;
        if let Some(d) = &self.details {
            write_methods(f, &d.methods())?;
        }
        if let Some(loss) = &self.loss {
            match &self.inlier_graph {
                Some(g) => write!(f, "\nloss {loss}: {g}")?,
                None => write!(
                    f,
                    "\nloss {loss}: no edge is an inlier at the given estimate; only the all-edges problem was judged"
                )?,
            }
        }
        if let Some(v) = self.verdict_of() {
            write!(f, "\n{v}")?;
        }
        Ok(())
    }
}

/// The gravity problem's certification of `rotations`, stated as one of that problem, and the
/// priors' warnings.
fn gravity_certification(
    p: &crate::multiple::gravity::GravityProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
) -> Result<(
    crate::certify::Certification<crate::multiple::MultipleSolution>,
    Vec<Warning>,
)> {
    let mut c = crate::certify::certify_gravity(p, rotations, settings)?;
    let g = p.problem();
    c.certificate = c.certificate.for_problem(crate::certify::CertifiedProblem {
        kind: crate::certify::gravity_problem_kind(p, false),
        num_nodes: g.num_rotations(),
        total_nodes: g.num_rotations(),
        num_edges: g.num_edges(),
        total_edges: g.num_edges(),
    });
    let details = crate::pipeline::GravityDetails::of(p);
    Ok((c, details.warnings()))
}
