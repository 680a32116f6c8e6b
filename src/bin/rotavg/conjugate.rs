//! `rotavg conjugate INPUT [--format auto|json|tabb|eth] [--certify auto|sdp|branch_and_bound|none] [--json]`:
//! hand-eye (conjugate) rotation averaging, `R_i ~ S^-1 L_i S`
//! (`rotavg::pipeline::average_conjugate`, printed as `rotavg::report::ConjugateReport`).

use crate::Outcome;
use crate::common::{Common, choice};
use clap::Args as ClapArgs;
use rotavg::certify::{CertifyMode, CertifySettings};
use rotavg::conjugate::ConjugateSettings;
use rotavg::io::input::{load_conjugate, load_estimate};
use rotavg::io::names::{Choice, ConjugateFormat, LossKind};
use rotavg::pipeline::{AverageSettings, average_conjugate};
#[cfg(feature = "plot")]
use rotavg::plot::write_conjugate_figure;
use rotavg::report::ConjugateReport;
use rotavg::{Metric, Objective, Result};

/// Arguments of `rotavg conjugate`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Input file (or dataset directory for Tabb / ETH), or `-` for standard input (JSON).
    pub input: String,
    /// Input format.
    #[arg(long, value_parser = choice(ConjugateFormat::choices()), default_value_t = ConjugateFormat::Auto)]
    pub format: ConjugateFormat,
    /// Certification: `auto` (the SDP for the chordal L2 cost, then branch and bound over SO(3)
    /// when it does not certify; branch and bound for every other cost), `sdp`,
    /// `branch_and_bound`, `none`.
    #[arg(long, value_parser = choice(vec![CertifyMode::Auto, CertifyMode::Sdp, CertifyMode::BranchAndBound, CertifyMode::None]), default_value_t = CertifyMode::Auto)]
    pub certify: CertifyMode,
    /// Distance between R_i and S^T L_i S (chordal with `--loss l2` is certified; quaternion
    /// has the closed form).
    #[arg(long, value_parser = choice(vec![Metric::Chordal, Metric::Geodesic, Metric::Quaternion]), default_value_t = Metric::Chordal)]
    pub metric: Metric,
    /// Loss.
    #[arg(long, value_parser = choice(LossKind::choices()), default_value_t = LossKind::L2)]
    pub loss: LossKind,
    /// Huber threshold / Cauchy scale as a residual angle in degrees (converted to the
    /// metric's unit).
    #[arg(long, value_name = "DEG", default_value_t = 5.0)]
    pub loss_threshold: f64,
    /// Write an SVG figure: histogram of the residual angles (degrees), the certificate, and
    /// the eigenvalues of the 10x10 certificate matrix with the proven bound.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<Outcome> {
    crate::common::check_plot(args.plot.as_ref())?;
    let options = args.common.read_options();
    let loaded = load_conjugate(&args.input, args.format, &options)?;
    let objective = Objective::new(
        args.metric,
        args.loss.with_threshold_deg(args.loss_threshold),
    );
    let problem = loaded.problem.clone().with_objective(objective)?;
    let init = match &args.common.init {
        Some(path) => Some(load_estimate(path, &options)?.into_rotation()?),
        None => None,
    };
    let settings = AverageSettings {
        solve: ConjugateSettings {
            init,
            ..Default::default()
        },
        certify: CertifySettings {
            budget: args.common.budget(),
            ..CertifySettings::with_mode(args.certify)
        },
    };
    let result = average_conjugate(&problem, &settings)?;
    #[cfg_attr(not(feature = "plot"), allow(unused_mut))] // the figure path is recorded
    let mut report = ConjugateReport::new(&problem, loaded.to_string(), result);
    #[cfg(feature = "plot")]
    if let Some(path) = &args.plot {
        let (s, certificate) = (
            &report.result.solution.estimate,
            report.result.certificate.as_ref(),
        );
        write_conjugate_figure(path, &problem, s, certificate, &args.input)?;
        report.figure = Some(path.clone());
    }
    args.common.print(&report)?;
    Ok(Outcome {
        verdict: report.verdict(),
    })
}
