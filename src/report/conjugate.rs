//! The report of `rotavg conjugate`.

use super::{ProblemJson, ProblemKind, Rows};
use crate::certify::{Certificate, SdpSummary, Verdict};
use crate::conjugate::{ConjugateProblem, DiagnosticSettings, Diagnostics, Identifiability};
use crate::io::handeye::{MotionSettings, MotionStats};
use crate::objective::Loss;
use crate::pipeline::ConjugateEstimate;
use crate::so3::{Metric, rotation_to_rows};
use crate::termination::SolverReport;
use serde::{Serialize, Serializer};
use std::fmt;

/// The result of conjugate (hand-eye) rotation averaging, as `rotavg conjugate` prints it.
///
/// JSON (`--json`): `problem` = `"conjugate"`, `num_rotations` = 1, `num_measurements`
/// (pairs), `metric`, `loss` (`{"kind": "l2"}`, `{"kind": "huber", "threshold_deg": 5.0}`,
/// ...), `cost` (under the objective), `chordal_cost`, `estimate` (`S`, row-major), `solver`,
/// `certificate` (or null), `sdp` (the SDP solve, or null), `diagnostics`
/// (`median_angle_mismatch_deg`, `max_angle_mismatch_deg`, `suspicious_pairs`,
/// `small_rotation_pairs`, `identifiability`), `motion` (null for pairs read as such; for Tabb
/// and pose streams the [`MotionStats`] counts `poses`, `pairs`, `skipped_small`, `unmatched`,
/// `hand` and `camera` (per stream: `file`, `samples`, `kept`, `repeated_stamps`,
/// `header_lines`, `time_unit`; null for Tabb), and `settings`, the [`MotionSettings`] used,
/// with `min_angle` in radians and `min_angle_deg` in degrees, as `--min-angle` takes it).
/// Text: where the data came from, the diagnostics, `S`, costs, solver, SDP and certificate.
///
/// ```
/// use rotavg::conjugate::ConjugateProblem;
/// use rotavg::pipeline::{average_conjugate, AverageSettings};
/// use rotavg::report::ConjugateReport;
/// use rotavg::so3::exp;
/// use nalgebra::Vector3;
/// // Noise-free pairs R_i = S^T L_i S about two axes.
/// let s = exp(&Vector3::new(0.2, -0.1, 0.4));
/// let rs = [exp(&Vector3::new(0.5, 0.0, 0.0)), exp(&Vector3::new(0.0, 0.7, 0.1))];
/// let ls: Vec<_> = rs.iter().map(|r| s * r * s.inverse()).collect();
/// let problem = ConjugateProblem::from_rotations(&ls, &rs)?;
/// let result = average_conjugate(&problem, &AverageSettings::default())?;
/// let report = ConjugateReport::new(&problem, "pairs.json: conjugate JSON".into(), result);
/// let json = serde_json::to_value(&report).unwrap();
/// assert_eq!(json["loss"]["kind"], "l2");
/// assert_eq!(json["diagnostics"]["identifiability"]["status"], "determined");
/// assert!(report.to_string().starts_with("pairs.json: conjugate JSON\npairs: 2;"));
/// # Ok::<(), rotavg::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ConjugateReport {
    /// The pipeline's result.
    pub result: ConjugateEstimate,
    /// Where the data came from, in words
    /// ([`crate::io::input::LoadedConjugate`]'s `Display`).
    pub source: String,
    /// Number of pairs.
    pub num_pairs: usize,
    /// The data diagnostics.
    pub diagnostics: Diagnostics,
    /// The thresholds of the diagnostics.
    pub diagnostic_settings: DiagnosticSettings,
    /// Median residual angle of the pairs at the estimate (radians).
    pub median_residual: f64,
    /// Where the figure was written (`--plot`), if it was.
    pub figure: Option<String>,
    /// How the pairs were formed from poses (Tabb, pose streams), with the settings used.
    pub motion: Option<(MotionStats, MotionSettings)>,
}

impl ConjugateReport {
    /// The report of `result`, a solution of `problem` read from `source` (default
    /// diagnostics thresholds).
    pub fn new(problem: &ConjugateProblem, source: String, result: ConjugateEstimate) -> Self {
        let diagnostic_settings = DiagnosticSettings::default();
        let mut residuals = problem.residual_angles(&result.solution.estimate);
        residuals.sort_by(f64::total_cmp);
        ConjugateReport {
            median_residual: residuals.get(residuals.len() / 2).copied().unwrap_or(0.0),
            diagnostics: problem.diagnose(&diagnostic_settings),
            diagnostic_settings,
            num_pairs: problem.num_pairs(),
            source,
            result,
            figure: None,
            motion: None,
        }
    }

    /// The report with the counts of forming the pairs from poses
    /// ([`crate::io::input::LoadedConjugate::motion`]) and the settings used; `None` keeps none.
    ///
    /// ```
    /// use rotavg::conjugate::ConjugateProblem;
    /// use rotavg::io::handeye::{MotionSettings, MotionStats};
    /// use rotavg::pipeline::{average_conjugate, AverageSettings};
    /// use rotavg::report::ConjugateReport;
    /// use rotavg::so3::exp;
    /// use nalgebra::Vector3;
    /// let rs = [exp(&Vector3::new(0.5, 0.0, 0.0)), exp(&Vector3::new(0.0, 0.7, 0.1))];
    /// let problem = ConjugateProblem::from_rotations(&rs, &rs)?;
    /// let result = average_conjugate(&problem, &AverageSettings::default())?;
    /// let stats = MotionStats { poses: 3, pairs: 2, unmatched: 1, ..Default::default() };
    /// let report = ConjugateReport::new(&problem, "streams".into(), result)
    ///     .with_motion(Some(stats), MotionSettings::default());
    /// let json = serde_json::to_value(&report).unwrap();
    /// assert_eq!(json["motion"]["unmatched"], 1);
    /// assert_eq!(json["motion"]["settings"]["stride"], 15);
    /// # Ok::<(), rotavg::Error>(())
    /// ```
    pub fn with_motion(mut self, stats: Option<MotionStats>, settings: MotionSettings) -> Self {
        self.motion = stats.map(|s| (s, settings));
        self
    }

    /// Write the `--plot` figure of the estimate, a solution of `problem` read from `input`:
    /// residual angles and the certificate (`rotavg::plot::write_conjugate_figure`), and
    /// record its path in [`Self::figure`].
    #[cfg(feature = "plot")]
    pub fn write_figure(
        &mut self,
        path: &str,
        problem: &ConjugateProblem,
        input: &str,
    ) -> crate::Result<()> {
        let (s, certificate) = (
            &self.result.solution.estimate,
            self.result.certificate.as_ref(),
        );
        crate::plot::write_conjugate_figure(path, problem, s, certificate, input)?;
        self.figure = Some(path.to_owned());
        Ok(())
    }

    /// The certificate's verdict, when one was computed.
    pub fn verdict(&self) -> Option<Verdict> {
        self.result.certificate.as_ref().map(|c| c.verdict)
    }

    /// The SDP solve, when one ran.
    fn sdp(&self) -> Option<&SdpSummary> {
        self.result
            .details
            .certify
            .as_ref()
            .and_then(|c| c.sdp.as_ref())
    }
}

#[derive(Serialize)]
struct DiagnosticsJson<'a> {
    median_angle_mismatch_deg: f64,
    max_angle_mismatch_deg: f64,
    suspicious_pairs: &'a [usize],
    small_rotation_pairs: &'a [usize],
    identifiability: &'a Identifiability,
}

#[derive(Serialize)]
struct Json<'a> {
    metric: Metric,
    loss: &'a Loss,
    cost: f64,
    chordal_cost: f64,
    estimate: Rows<'a>,
    solver: &'a SolverReport,
    certificate: Option<&'a Certificate>,
    sdp: Option<&'a SdpSummary>,
    diagnostics: DiagnosticsJson<'a>,
    motion: Option<MotionJson<'a>>,
}

#[derive(Serialize)]
struct MotionJson<'a> {
    #[serde(flatten)]
    stats: &'a MotionStats,
    settings: MotionSettingsJson<'a>,
}

/// The motion settings with the unit of `min_angle` stated: `min_angle` stays in radians (the
/// library's field, as before), `min_angle_deg` is the same angle as `--min-angle` takes it.
#[derive(Serialize)]
struct MotionSettingsJson<'a> {
    #[serde(flatten)]
    settings: &'a MotionSettings,
    min_angle_deg: f64,
}

impl Serialize for ConjugateReport {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        let s = &self.result.solution;
        let d = &self.diagnostics;
        let rest = Json {
            metric: s.objective.metric,
            loss: &s.objective.loss,
            cost: s.cost,
            chordal_cost: s.chordal_cost,
            estimate: Rows::One(&s.estimate),
            solver: &s.report,
            certificate: self.result.certificate.as_ref(),
            sdp: self.sdp(),
            diagnostics: DiagnosticsJson {
                median_angle_mismatch_deg: d.median_angle_mismatch.to_degrees(),
                max_angle_mismatch_deg: d.max_angle_mismatch.to_degrees(),
                suspicious_pairs: &d.suspicious_pairs,
                small_rotation_pairs: &d.small_rotation_pairs,
                identifiability: &d.identifiability,
            },
            motion: self.motion.as_ref().map(|(stats, settings)| MotionJson {
                stats,
                settings: MotionSettingsJson {
                    settings,
                    min_angle_deg: settings.min_angle.to_degrees(),
                },
            }),
        };
        ProblemJson::new(ProblemKind::Conjugate, 1, self.num_pairs, rest).serialize(serializer)
    }
}

/// An angle in degrees with at most two decimals and no trailing zeros (`5`, `0.57`).
fn short_deg(radians: f64) -> String {
    let s = format!("{:.2}", radians.to_degrees());
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

impl fmt::Display for ConjugateReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let (s, d) = (&self.result.solution, &self.diagnostics);
        writeln!(f, "{}", self.source)?;
        writeln!(
            f,
            "pairs: {}; angle mismatch |angle(L) - angle(R)|: median {:.3} deg, max {:.3} deg; {} suspicious (> {} deg), {} with rotation < {} deg",
            self.num_pairs,
            d.median_angle_mismatch.to_degrees(),
            d.max_angle_mismatch.to_degrees(),
            d.suspicious_pairs.len(),
            short_deg(self.diagnostic_settings.max_angle_mismatch),
            d.small_rotation_pairs.len(),
            short_deg(self.diagnostic_settings.min_rotation_angle),
        )?;
        writeln!(
            f,
            "estimate S (row-major): {:?}",
            rotation_to_rows(&s.estimate)
        )?;
        writeln!(
            f,
            "cost ({}) {:.9e}; chordal cost {:.9e}; median residual {:.4} deg",
            s.objective,
            s.cost,
            s.chordal_cost,
            self.median_residual.to_degrees()
        )?;
        writeln!(f, "solver: {}", s.report)?;
        if let Some(sdp) = self.sdp() {
            writeln!(
                f,
                "sdp: {:?}, {} iterations, {:.2} ms, Z eigenvalue ratio {:.1e}{}",
                sdp.status,
                sdp.iterations,
                sdp.seconds * 1e3,
                sdp.eigenvalue_ratio,
                if self.result.details.improved_by.is_some() {
                    "; SDP rounding improved the local solution"
                } else {
                    ""
                }
            )?;
        }
        match &self.result.certificate {
            Some(c) => {
                write!(f, "certificate: ")?;
                super::nested(f, c)?;
            }
            None => write!(f, "certificate: none")?,
        }
        if let Some(p) = &self.figure {
            write!(f, "\nfigure written to {p}")?;
        }
        Ok(())
    }
}
