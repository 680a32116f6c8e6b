//! The report of `rotavg certify`: an estimate computed elsewhere, certified or bounded
//! **without changing it**.

use super::{ProblemJson, ProblemKind, Rows, write_methods};
use crate::certify::{
    Certificate, CertifyDetails, CertifySettings, Verdict, certify_conjugate, certify_multiple,
    certify_single,
};
use crate::error::{Error, Result};
use crate::io::input::{LoadedEstimate, LoadedProblem};
use crate::io::json::Estimate;
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
        let estimate_file = estimate.name.clone();
        let estimate_warnings = estimate.warnings.clone();
        let report =
            |problem, num_rotations, num_measurements, cost, estimate, certificate| CertifyReport {
                problem,
                input: input.to_string(),
                estimate_file: estimate_file.clone(),
                num_rotations,
                num_measurements,
                cost,
                estimate,
                node_ids: None,
                certificate,
                details: None,
                warnings: estimate_warnings.clone(),
            };
        match problem {
            LoadedProblem::Multiple(graph) => {
                let rotations = estimate.into_rotations()?;
                let n = graph.problem.num_rotations();
                if rotations.len() != n {
                    return Err(Error::parse(
                        Some(&estimate_file),
                        None,
                        format!(
                            "the estimate has {} rotations, the problem has {n} nodes",
                            rotations.len()
                        ),
                    ));
                }
                let c = certify_multiple(&graph.problem, &rotations, settings)?;
                let cost = graph.problem.chordal_cost(&rotations);
                Ok(CertifyReport {
                    node_ids: Some(graph.node_ids.clone()),
                    details: Some(c.details),
                    warnings: [graph.warnings.clone(), estimate_warnings.clone()].concat(),
                    ..report(
                        ProblemKind::Multiple,
                        n,
                        graph.problem.num_edges(),
                        cost,
                        Estimate::Multiple(rotations),
                        c.certificate,
                    )
                })
            }
            LoadedProblem::Single(p) => {
                let r = estimate.into_rotation()?;
                let c = certify_single(p, &r, settings)?.certificate;
                let cost = c.upper_bound;
                Ok(report(
                    ProblemKind::Single,
                    1,
                    p.len(),
                    cost,
                    Estimate::Single(r),
                    c,
                ))
            }
            LoadedProblem::Conjugate(p) => {
                let s = estimate.into_rotation()?;
                let c = certify_conjugate(p, &s, settings)?.certificate;
                let cost = c.upper_bound;
                Ok(report(
                    ProblemKind::Conjugate,
                    1,
                    p.num_pairs(),
                    cost,
                    Estimate::Single(s),
                    c,
                ))
            }
        }
    }

    /// The certificate's verdict.
    pub fn verdict(&self) -> Verdict {
        self.certificate.verdict
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
    cost: f64,
    estimate: Rows<'a>,
    #[serde(skip_serializing_if = "Option::is_none")]
    node_ids: Option<&'a [u64]>,
    solver: Option<&'a SolverReport>,
    certificate: &'a Certificate,
    #[serde(skip_serializing_if = "Option::is_none")]
    pipeline: Option<&'a CertifyDetails>,
}

impl Serialize for CertifyReport {
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        let rest = Json {
            cost: self.cost,
            estimate: match &self.estimate {
                Estimate::Single(r) => Rows::One(r),
                Estimate::Multiple(rs) => Rows::Many(rs),
            },
            node_ids: self.node_ids.as_deref(),
            solver: None,
            certificate: &self.certificate,
            pipeline: self.details.as_ref(),
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
        Ok(())
    }
}
