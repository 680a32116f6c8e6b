//! The report of `rotavg single`.

use super::{ProblemJson, ProblemKind, Rows};
use crate::certify::{Certificate, Verdict};
use crate::objective::Loss;
use crate::pipeline::SingleEstimate;
use crate::so3::Metric;
use crate::termination::SolverReport;
use serde::{Serialize, Serializer};
use std::fmt;

/// The result of single rotation averaging, as `rotavg single` prints it.
///
/// JSON (`--json`): `problem` = `"single"`, `num_rotations` = 1 (one rotation is estimated),
/// `num_measurements` (samples), `metric`, `p` (1 or 2: the L^p mean), `cost`, `estimate`
/// (row-major), `solver` (name, iterations, termination, seconds), `certificate` (or null).
/// Text: the solution, its certificate and the times ([`crate::pipeline::Averaged`]'s
/// `Display`).
///
/// ```
/// use rotavg::pipeline::{average_single, AverageSettings};
/// use rotavg::report::SingleReport;
/// use rotavg::single::SingleProblem;
/// use rotavg::{Loss, Metric, Objective, Rotation};
/// let problem = SingleProblem::new(vec![Rotation::identity(); 3], None)?
///     .with_objective(Objective::new(Metric::Geodesic, Loss::L1))?;
/// let report = SingleReport::new(average_single(&problem, &AverageSettings::default())?);
/// let json = serde_json::to_value(&report).unwrap();
/// assert_eq!((json["metric"].as_str(), json["p"].as_u64()), (Some("geodesic"), Some(1)));
/// assert_eq!(json["num_measurements"], 3);
/// # Ok::<(), rotavg::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SingleReport {
    /// The pipeline's result.
    pub result: SingleEstimate,
}

impl SingleReport {
    /// The report of a result.
    pub fn new(result: SingleEstimate) -> Self {
        SingleReport { result }
    }

    /// The certificate's verdict, when one was computed.
    pub fn verdict(&self) -> Option<Verdict> {
        self.result.certificate.as_ref().map(|c| c.verdict)
    }
}

#[derive(Serialize)]
struct Json<'a> {
    metric: Metric,
    p: Option<u32>,
    cost: f64,
    estimate: Rows<'a>,
    solver: &'a SolverReport,
    certificate: Option<&'a Certificate>,
}

impl Serialize for SingleReport {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let s = &self.result.solution;
        let rest = Json {
            metric: s.objective.metric,
            p: match s.objective.loss {
                Loss::L1 => Some(1),
                Loss::L2 => Some(2),
                Loss::Huber { .. } | Loss::Cauchy { .. } => None,
            },
            cost: s.cost,
            estimate: Rows::One(&s.estimate),
            solver: &s.report,
            certificate: self.result.certificate.as_ref(),
        };
        ProblemJson::new(ProblemKind::Single, 1, s.num_samples, rest).serialize(serializer)
    }
}

impl fmt::Display for SingleReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        super::nested(f, &self.result)
    }
}
