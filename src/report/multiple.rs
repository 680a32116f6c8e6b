//! The report of `rotavg multiple`.

use super::{ProblemJson, ProblemKind, Rows, nested, write_methods};
use crate::certify::{Certificate, Verdict};
use crate::certify::{CertifiedProblem, CertifiedProblemKind};
use crate::error::Result;
use crate::io::detect::{ComponentSelection, GraphFormat, ReadOptions};
use crate::io::input::MultipleInput;
use crate::io::names::MultipleLoss;
use crate::multiple::LinearAlgebraCounts;
#[cfg(feature = "plot")]
use crate::multiple::MultipleProblem;
use crate::multiple::accuracy::{AccuracyReport, align_and_compare};
use crate::multiple::anisotropic::InformationSummary;
use crate::multiple::robust::ResidualSummary;
use crate::pipeline::{MultipleEstimate, PipelineDetails};
use crate::termination::SolverReport;
use crate::warning::Warning;
use serde::{Serialize, Serializer};
use std::fmt;

/// The result of multiple rotation averaging on a view-graph file, as `rotavg multiple`
/// prints it.
///
/// JSON (`--json`): `problem` = `"multiple"`, `num_rotations`, `num_measurements` (edges),
/// `loss` ([`MultipleLoss::name_of`]), `cost` (under the loss), `chordal_cost`, `estimate`
/// (row-major, `R_0 = I`), `node_ids` (the file id of each node of the estimate), `node_names`
/// (only when the format names nodes: COLMAP image names), `solver`,
/// `certificate` (or null), `verdict` ([`VerdictOf`]: the verdict with the problem and estimate
/// it is about, or null), `pipeline` ([`PipelineDetails`]: certification methods, times),
/// `accuracy` (against ground truth, or null), `other_components` (sizes of the components not
/// solved), `format`, `robust` (null for the L2 losses).
///
/// `robust` (L1, Huber, Cauchy): `reported_estimate` (`"robust"`: `estimate` is the robust
/// solver's), `inlier_rule`, the [`ResidualSummary`] fields (`inlier_threshold_deg`,
/// `num_edges`, `num_inliers`, `num_outliers`, residual quantiles `min_deg` .. `max_deg` at
/// the robust estimate), `edges_output` (the per-edge file, or null) and `inlier_graph` (null
/// under `--certify none`): the chordal L2 problem on the inlier graph ([`crate::pipeline::InlierGraph`]) with
/// `certified_problem`, `other_component_sizes`, `isolated_nodes`, `robust_chordal_cost`,
/// `chordal_cost` (of the refined estimate), `solver`, `certificate` (its `certified_problem`
/// says which problem it is about), `accuracy` of the refined estimate, `estimate_output` (the
/// refined estimate's file, or null) and `pipeline`. The top-level `certificate` stays null:
/// the robust cost has no certificate; `verdict` is the inlier graph's. Under the rule `auto`
/// (`--loss auto`) `pipeline.loss_choice` says which loss the data chose
/// ([`crate::pipeline::LossChoice`]).
///
/// Text: the input line, warnings, the solution and certificate, the bounding methods, the
/// residuals and the inlier graph's certificate (robust losses), the accuracy, and the files
/// written.
///
/// ```
/// use rotavg::io::detect::{read_graph, ComponentSelection, GraphFormat, ReadOptions};
/// use rotavg::io::input::MultipleInput;
/// use rotavg::pipeline::{average_multiple, AverageSettings};
/// use rotavg::report::MultipleReport;
/// // A noise-free triangle (1DSfM lines `i j R_i R_j^T`, here all identities).
/// let text = "0 1 1 0 0 0 1 0 0 0 1\n1 2 1 0 0 0 1 0 0 0 1\n2 0 1 0 0 0 1 0 0 0 1\n";
/// let graph = read_graph(text, "EGs.txt", GraphFormat::Auto, &ReadOptions::default())?;
/// let result = average_multiple(&graph.problem, &AverageSettings::default())?;
/// let input = MultipleInput { name: "EGs.txt".into(), selection: ComponentSelection::whole(3), graph, truth: None, init: None };
/// let report = MultipleReport::new(&input, result)?;
/// let json = serde_json::to_value(&report).unwrap();
/// assert_eq!((json["num_rotations"].as_u64(), json["loss"].as_str()), (Some(3), Some("chordal")));
/// assert_eq!(json["format"], "one_dsfm"); // serde's name of GraphFormat::OneDsfm
/// assert!(report.to_string().starts_with("EGs.txt: 1dsfm format, 3 nodes, 3 edges"));
/// # Ok::<(), rotavg::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct MultipleReport {
    /// The pipeline's result.
    pub result: MultipleEstimate,
    /// The input as given (`-` for standard input).
    pub input: String,
    /// The format read.
    pub format: GraphFormat,
    /// The options the graph was read with.
    pub read: ReadOptions,
    /// Edges given twice (same unordered pair).
    pub duplicates: usize,
    /// Edges given with `i > j`.
    pub reversed: usize,
    /// The reader's remarks (printed on `warning:` lines of the text).
    pub warnings: Vec<Warning>,
    /// Warnings of the run printed on stderr by the command line (`output_not_written`); the
    /// outlier diagnosis of a least-squares run is added from the result.
    pub run_warnings: Vec<Warning>,
    /// The file id of each node of the estimate.
    pub node_ids: Vec<u64>,
    /// The file's name of each node (COLMAP image names), or empty.
    pub node_names: Vec<String>,
    /// Number of edges solved.
    pub num_edges: usize,
    /// Which nodes of the file's graph were solved.
    pub selection: ComponentSelection,
    /// Accuracy against the ground truth, when one was given.
    pub accuracy: Option<AccuracyReport>,
    /// Where the estimate was written (`--output`), if it was.
    pub output: Option<String>,
    /// Where the figure was written (`--plot`), if it was.
    pub figure: Option<String>,
    /// Accuracy of the inlier graph's refined estimate against the ground truth.
    pub inlier_accuracy: Option<AccuracyReport>,
    /// Where the per-edge residuals were written (`--edges-output`), if they were.
    pub edges_output: Option<String>,
    /// Where the inlier graph's refined estimate was written (`--inlier-output`), if it was.
    pub inlier_output: Option<String>,
    /// The information matrices' summary, when the measurements are anisotropic.
    pub information: Option<InformationSummary>,
}

impl MultipleReport {
    /// Name `--edges-output` (`edges`) in the report when a robust solve wrote it; when `--loss
    /// auto` kept least squares and `edges` or `--inlier-output` (`inlier_output`) was asked
    /// for, there is no robust solve to write: the warning `output_not_written` says so.
    pub fn note_robust_outputs(&mut self, edges: Option<&str>, inlier_output: bool) {
        let robust = self.result.solution.residuals.is_some();
        self.edges_output = edges.filter(|_| robust).map(str::to_string);
        let unwritten = usize::from(edges.is_some()) + usize::from(inlier_output);
        if !robust && unwritten > 0 {
            let message = "--edges-output / --inlier-output not written: `--loss auto` kept \
                           least squares (no outliers); `--loss cauchy` forces the robust solve";
            self.run_warnings
                .push(Warning::new("output_not_written", message).with_count(unwritten));
        }
    }

    /// The report of `result`, a solution of `input.graph.problem`; the accuracy is computed
    /// when `input` has ground truth (an error when no node has any).
    pub fn new(input: &MultipleInput, result: MultipleEstimate) -> Result<Self> {
        let accuracy = match &input.truth {
            Some(t) => Some(align_and_compare(&result.solution.rotations, t)?),
            None => None,
        };
        let inlier_accuracy = match (&input.truth, &result.details.inlier_graph) {
            (Some(t), Some(g)) => Some(align_and_compare(&g.estimate, t)?),
            _ => None,
        };
        let g = &input.graph;
        let gravity_warnings = result
            .details
            .gravity
            .as_ref()
            .map(|d| d.warnings())
            .unwrap_or_default();
        Ok(MultipleReport {
            result,
            input: input.name.clone(),
            format: g.format,
            read: g.read,
            duplicates: g.duplicates,
            reversed: g.reversed,
            warnings: [super::input_warnings(g), gravity_warnings].concat(),
            run_warnings: Vec::new(),
            node_ids: g.node_ids.clone(),
            node_names: g.node_names.clone(),
            num_edges: g.problem.num_edges(),
            selection: input.selection.clone(),
            accuracy,
            output: None,
            figure: None,
            inlier_accuracy,
            edges_output: None,
            inlier_output: None,
            information: g.problem.information_summary(),
        })
    }

    /// Write the `--plot` figure of the estimate, a solution of `problem` (the problem read):
    /// residual angles and the certificate (`rotavg::plot::write_multiple_figure`), and record
    /// its path in [`Self::figure`].
    #[cfg(feature = "plot")]
    pub fn write_figure(&mut self, path: &str, problem: &MultipleProblem) -> Result<()> {
        crate::plot::write_multiple_figure(
            path,
            problem,
            &self.result.solution.rotations,
            self.result.certificate.as_ref(),
            &self.input,
        )?;
        self.figure = Some(path.to_owned());
        Ok(())
    }

    /// The verdict of the run, when a certificate was computed: the returned estimate's, or
    /// for a robust loss (which has none) its inlier graph's ([`Self::verdict_of`]).
    pub fn verdict(&self) -> Option<Verdict> {
        self.verdict_of().map(|v| v.verdict)
    }

    /// Every warning of the run, as the JSON's `warnings`: the reader's (lines of the report)
    /// and [`Self::stderr_warnings`].
    pub fn all_warnings(&self) -> Vec<Warning> {
        [self.warnings.clone(), self.stderr_warnings()].concat()
    }

    /// The warnings the command line prints on stderr: the outlier diagnosis of a
    /// least-squares run (`outliers_suspected`) and [`Self::run_warnings`].
    pub fn stderr_warnings(&self) -> Vec<Warning> {
        let outliers = self.result.details.outliers.as_ref().map(|w| {
            Warning::new("outliers_suspected", format!("{}: {w}", self.input))
                .with_count(w.suspected)
        });
        outliers
            .into_iter()
            .chain(self.run_warnings.iter().cloned())
            .collect()
    }

    /// The verdict with the problem and estimate it is about.
    pub fn verdict_of(&self) -> Option<VerdictOf> {
        let whole = CertifiedProblem {
            kind: CertifiedProblemKind::ChordalL2,
            num_nodes: self.result.solution.rotations.len(),
            total_nodes: self.result.solution.rotations.len(),
            num_edges: self.num_edges,
            total_edges: self.num_edges,
        };
        if let Some(c) = &self.result.certificate {
            return Some(VerdictOf {
                verdict: c.verdict,
                estimate: CertifiedEstimate::Returned,
                problem: c.certified_problem.unwrap_or(whole),
            });
        }
        let g = self.result.details.inlier_graph.as_deref()?;
        let c = g.certificate.as_ref()?;
        Some(VerdictOf {
            verdict: c.verdict,
            estimate: CertifiedEstimate::InlierGraph,
            problem: c.certified_problem.unwrap_or(g.problem),
        })
    }
}

/// A run's verdict and what it is about (`verdict` of the JSON report).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct VerdictOf {
    /// The certificate's verdict.
    pub verdict: Verdict,
    /// The estimate certified.
    pub estimate: CertifiedEstimate,
    /// The problem certified (kind and size against the input's).
    pub problem: CertifiedProblem,
}

/// Which estimate a run's verdict is about.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CertifiedEstimate {
    /// The returned estimate (`estimate`, `--output`).
    Returned,
    /// A robust run's refined inlier-graph estimate (`--inlier-output`); the returned one is
    /// the robust estimate, which has no certificate.
    InlierGraph,
    /// `rotavg certify`: the estimate as given (unchanged), on the problem named.
    Given,
}

impl fmt::Display for VerdictOf {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "verdict: {} for {}", self.verdict, self.problem)?;
        if self.estimate == CertifiedEstimate::InlierGraph {
            write!(f, ", at its refined estimate (not the returned robust one)")?;
        }
        Ok(())
    }
}

#[derive(Serialize)]
struct Json<'a> {
    input: super::InputJson<'a>,
    loss: String,
    verdict: Option<VerdictOf>,
    cost: f64,
    chordal_cost: f64,
    estimate: Rows<'a>,
    node_ids: &'a [u64],
    #[serde(skip_serializing_if = "<[String]>::is_empty")]
    node_names: &'a [String],
    solver: &'a SolverReport,
    linear_algebra: Option<&'a LinearAlgebraCounts>,
    certificate: Option<&'a Certificate>,
    pipeline: &'a PipelineDetails,
    accuracy: Option<&'a AccuracyReport>,
    other_components: &'a [usize],
    format: GraphFormat,
    robust: Option<RobustJson<'a>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    information: Option<&'a InformationSummary>,
}

/// `robust` of the JSON report.
#[derive(Serialize)]
struct RobustJson<'a> {
    reported_estimate: &'static str,
    inlier_rule: &'static str,
    #[serde(flatten)]
    summary: &'a ResidualSummary,
    edges_output: Option<&'a str>,
    inlier_graph: Option<InlierGraphJson<'a>>,
}

/// `robust.inlier_graph` of the JSON report: the inlier graph without its estimate (the file of
/// `--inlier-output`) and node list ([`crate::pipeline::InlierGraph`]).
#[derive(Serialize)]
struct InlierGraphJson<'a> {
    certified_problem: &'a CertifiedProblem,
    inlier_threshold_deg: f64,
    other_component_sizes: &'a [usize],
    isolated_nodes: usize,
    robust_chordal_cost: f64,
    chordal_cost: f64,
    solver: &'a SolverReport,
    certificate: Option<&'a Certificate>,
    accuracy: Option<&'a AccuracyReport>,
    estimate_output: Option<&'a str>,
    pipeline: &'a PipelineDetails,
}

impl Serialize for MultipleReport {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        let s = &self.result.solution;
        let graph = self.result.details.inlier_graph.as_deref();
        let robust = s.residuals.as_ref().map(|r| RobustJson {
            reported_estimate: "robust",
            inlier_rule: "residual_deg <= inlier_threshold_deg",
            summary: &r.summary,
            edges_output: self.edges_output.as_deref(),
            inlier_graph: graph.map(|g| InlierGraphJson {
                certified_problem: &g.problem,
                inlier_threshold_deg: g.inlier_threshold_deg,
                other_component_sizes: &g.other_component_sizes,
                isolated_nodes: g.isolated_nodes,
                robust_chordal_cost: g.robust_chordal_cost,
                chordal_cost: g.chordal_cost,
                solver: &g.solver,
                certificate: g.certificate.as_ref(),
                accuracy: self.inlier_accuracy.as_ref(),
                estimate_output: self.inlier_output.as_deref(),
                pipeline: &g.details,
            }),
        });
        // the inlier graph is reported under `robust`, not twice
        let pipeline = PipelineDetails {
            inlier_graph: None,
            ..self.result.details.clone()
        };
        let rest = Json {
            input: super::InputJson {
                path: &self.input,
                format: Some(self.format),
                read: Some(&self.read),
                estimate: None,
            },
            loss: MultipleLoss::name_of(&s.objective),
            verdict: self.verdict_of(),
            cost: s.cost,
            chordal_cost: s.chordal_cost,
            estimate: Rows::Many(&s.rotations),
            node_ids: &self.node_ids,
            node_names: &self.node_names,
            solver: &s.report,
            linear_algebra: s.linear_algebra.as_ref(),
            certificate: self.result.certificate.as_ref(),
            pipeline: &pipeline,
            accuracy: self.accuracy.as_ref(),
            other_components: &self.selection.other_component_sizes,
            format: self.format,
            robust,
            information: self.information.as_ref(),
        };
        ProblemJson::new(
            ProblemKind::Multiple,
            s.rotations.len(),
            self.num_edges,
            rest,
        )
        .with_warnings(self.all_warnings())
        .serialize(serializer)
    }
}

impl MultipleReport {
    /// What was read: the input's sizes, the component solved, the reader's warnings and the
    /// information summary.
    fn fmt_input(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = self.result.solution.rotations.len();
        write!(
            f,
            "{}: {} format, {} nodes, {} edges ({} duplicate, {} reversed)",
            self.input, self.format, n, self.num_edges, self.duplicates, self.reversed
        )?;
        let others = &self.selection.other_component_sizes;
        if !others.is_empty() {
            write!(
                f,
                "; solved the largest component ({n} of {} nodes); other components (sizes {others:?}) not solved",
                self.selection.num_read
            )?;
        }
        for w in &self.warnings {
            write!(f, "\nwarning: {w}")?;
        }
        if let Some(choice) = &self.result.details.loss_choice {
            write!(f, "\n{choice}")?;
        }
        if let Some(g) = &self.result.details.gravity {
            write!(f, "\n{g}")?;
        }
        if let Some(s) = &self.information {
            write!(f, "\n{s}")?;
            let objective = self.result.solution.objective;
            if !objective.is_chordal_l2() {
                write!(
                    f,
                    "\n  the {objective} cost applies to each edge's Mahalanobis angle \
                     sqrt(e^T H e / (tr H / 3)) (the residuals and inlier threshold below too)"
                )?;
            }
        }
        Ok(())
    }

    /// Which estimate is reported, and the files written.
    fn fmt_outputs(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(v) = self.verdict_of() {
            write!(f, "\n{v}")?;
        }
        let robust = &self.result.solution;
        if robust.residuals.is_some() {
            write!(
                f,
                "\nreported estimate: the robust ({}) one{}",
                robust.objective.loss.name(),
                match (&self.result.details.inlier_graph, &self.inlier_output) {
                    (Some(_), Some(p)) =>
                        format!("; the inlier graph's refined estimate written to {p}"),
                    (Some(_), None) =>
                        "; the inlier graph's refined estimate: --inlier-output FILE".into(),
                    _ => String::new(),
                }
            )?;
        }
        if let Some(p) = &self.edges_output {
            write!(f, "\nper-edge residuals written to {p}")?;
        }
        if let Some(p) = &self.output {
            write!(f, "\nestimate written to {p}")?;
        }
        if let Some(p) = &self.figure {
            write!(f, "\nfigure written to {p}")?;
        }
        Ok(())
    }
}

impl fmt::Display for MultipleReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.fmt_input(f)?;
        writeln!(f)?;
        nested(f, &self.result)?;
        if let Some(c) = &self.result.details.certify {
            write_methods(f, &c.methods())?;
        }
        let robust = &self.result.solution;
        if let Some(r) = &robust.residuals {
            write!(
                f,
                "\nedges at the {} estimate: {}",
                robust.objective.loss.name(),
                r.summary
            )?;
        }
        if let Some(g) = &self.result.details.inlier_graph {
            writeln!(f)?;
            nested(f, g.as_ref())?;
            if let Some(c) = &g.details.certify {
                write_methods(f, &c.methods())?;
            }
        }
        if let Some(a) = &self.accuracy {
            write!(f, "\n{a}")?;
        }
        if let Some(a) = &self.inlier_accuracy {
            write!(f, "\ninlier graph estimate: {a}")?;
        }
        self.fmt_outputs(f)
    }
}
