//! `rotavg conjugate INPUT`: hand-eye (conjugate) rotation averaging, `R_i ~ S^-1 L_i S`
//! (`rotavg::pipeline::average_conjugate`, printed as `rotavg::report::ConjugateReport`), from
//! JSON, Tabb or ETH datasets, or pose streams (`rotavg::io::input::load_conjugate_with`).

use crate::Outcome;
use crate::common::{Common, InitArgs, PlotArgs, RotationOutputArgs, choice};
use clap::Args as ClapArgs;
use rotavg::certify::CertifyMode;
use rotavg::conjugate::ConjugateSettings;
use rotavg::io::handeye::{MotionSettings, QuaternionOrder};
use rotavg::io::input::{HandEyeOptions, load_conjugate_with};
use rotavg::io::names::{Choice, ConjugateFormat, LossKind};
use rotavg::pipeline::{AverageSettings, average_conjugate};
use rotavg::report::ConjugateReport;
use rotavg::{Metric, Objective, Result};

/// Arguments of `rotavg conjugate`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Input file (or dataset directory for Tabb / ETH / pose streams), or `-` for standard
    /// input (JSON). Optional when both `--hand` and `--camera` are given.
    #[arg(required_unless_present_all = ["hand", "camera"])]
    pub input: Option<String>,
    /// Input format.
    #[arg(long, value_parser = choice(ConjugateFormat::choices()), default_value_t = ConjugateFormat::Auto)]
    pub format: ConjugateFormat,
    /// Certification (`auto`: the SDP for the chordal L2 cost, then branch and bound).
    #[arg(long, value_parser = choice(vec![CertifyMode::Auto, CertifyMode::Sdp, CertifyMode::BranchAndBound, CertifyMode::None]), default_value_t = CertifyMode::Auto)]
    pub certify: CertifyMode,
    /// Distance between R_i and S^T L_i S (quaternion has the closed form).
    #[arg(long, value_parser = choice(vec![Metric::Chordal, Metric::Geodesic, Metric::Quaternion]), default_value_t = Metric::Chordal)]
    pub metric: Metric,
    /// Loss.
    #[arg(long, value_parser = choice(LossKind::choices()), default_value_t = LossKind::L2)]
    pub loss: LossKind,
    /// Huber threshold / Cauchy scale, a residual angle in degrees (in the metric's unit).
    #[arg(long, value_name = "DEG", default_value_t = 5.0)]
    pub loss_threshold: f64,
    #[command(flatten)]
    pub plot: PlotArgs,
    #[command(flatten)]
    pub streams: StreamArgs,
    #[command(flatten)]
    pub init: InitArgs,
    #[command(flatten)]
    pub output: RotationOutputArgs,
    #[command(flatten)]
    pub common: Common,
}

/// Hand-eye pose streams (ETH, Vicon and other motion-capture CSVs): which files, and how
/// their samples are paired into motions `(L_i, R_i)` (`rotavg::io::handeye::MotionSettings`).
#[derive(ClapArgs, Debug)]
pub struct StreamArgs {
    /// Hand pose stream (hand in robot base, or the tracked body in the capture world); its
    /// relative motions are L_i. Default: the file in INPUT whose name contains `base_link`,
    /// `hand` or `vicon`.
    #[arg(long, value_name = "FILE")]
    pub hand: Option<String>,
    /// Camera pose stream (camera in the target frame); its relative motions are R_i. Default:
    /// the file in INPUT whose name contains `target` or `camera`.
    #[arg(long, value_name = "FILE")]
    pub camera: Option<String>,
    /// Pair time-matched samples i and i + N (streams).
    #[arg(long, value_name = "N", default_value_t = MotionSettings::default().stride)]
    pub stride: usize,
    /// Start a pair at every K-th time-matched sample (streams).
    #[arg(long, value_name = "K", default_value_t = MotionSettings::default().subsample)]
    pub subsample: usize,
    /// Match a camera sample only when hand samples lie within this many seconds on both sides
    /// (streams).
    #[arg(long, value_name = "SECONDS", default_value_t = MotionSettings::default().max_gap)]
    pub max_gap: f64,
    /// Seconds added to camera time stamps before matching them to the hand stream (streams).
    #[arg(long, value_name = "SECONDS", default_value_t = MotionSettings::default().time_offset, allow_negative_numbers = true)]
    pub time_offset: f64,
    /// Skip pairs whose hand and camera motions both rotate by less than this (degrees; Tabb
    /// and streams).
    #[arg(long, value_name = "DEG", default_value_t = MotionSettings::default().min_angle.to_degrees())]
    pub min_angle: f64,
    /// Order of the quaternion fields after `t, x, y, z` (streams).
    #[arg(long, value_parser = choice(QuaternionOrder::choices()), default_value_t = QuaternionOrder::default())]
    pub quaternion_order: QuaternionOrder,
}

impl StreamArgs {
    /// The library's hand-eye options.
    pub fn options(&self) -> HandEyeOptions {
        HandEyeOptions {
            hand: self.hand.clone(),
            camera: self.camera.clone(),
            motion: MotionSettings {
                stride: self.stride,
                subsample: self.subsample,
                max_gap: self.max_gap,
                time_offset: self.time_offset,
                min_angle: self.min_angle.to_radians(),
                quaternion_order: self.quaternion_order,
                ..Default::default()
            },
        }
    }
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<Outcome> {
    args.plot.check()?;
    let report = args
        .output
        .around(|| solve(args), |r| r.result.solution.estimate)?;
    args.common.finish(&report, report.verdict())
}

/// Read, solve, certify, and draw the figure.
fn solve(args: &Args) -> Result<ConjugateReport> {
    let options = args.common.read_options();
    let loaded = load_conjugate_with(
        args.input.as_deref(),
        args.format,
        &options,
        &args.streams.options(),
    )?;
    let objective = Objective::new(
        args.metric,
        args.loss.with_threshold_deg(args.loss_threshold),
    );
    let problem = loaded.problem.clone().with_objective(objective)?;
    let settings = AverageSettings {
        solve: ConjugateSettings {
            init: args.init.rotation(&options)?,
            max_seconds: args.common.solve_seconds(),
            ..Default::default()
        },
        certify: args.common.settings(args.certify),
    };
    let result = average_conjugate(&problem, &settings)?;
    #[cfg_attr(not(feature = "plot"), allow(unused_mut))] // the figure path is recorded
    let mut report = ConjugateReport::new(&problem, loaded.to_string(), result)
        .with_motion(loaded.motion, loaded.motion_settings);
    #[cfg(feature = "plot")]
    if let Some(path) = &args.plot.plot {
        report.write_figure(path, &problem, &loaded.name)?;
    }
    Ok(report)
}
