//! `rotavg conjugate`: hand-eye (conjugate) rotation averaging, `R_i ~ S^-1 L_i S`.

use crate::Outcome;
use crate::common::{Common, WeightSource, read_input};
use clap::{Args as ClapArgs, ValueEnum};
use rotavg::conjugate::{
    AverageSettings, CertifyMode, ConjugatePair, ConjugateProblem, ConjugateSettings,
    DiagnosticSettings, Loss, average_conjugate_from,
};
use rotavg::io::handeye::{MotionSettings, read_conjugate_json, read_eth_dir, read_tabb_dir};
use rotavg::so3::{
    DEFAULT_ROTATION_TOLERANCE, Metric, Rotation, rotation_from_rows, rotation_to_rows,
};
use rotavg::{Error, Result};
use std::path::Path;

/// Input format.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum Format {
    /// Directory with `robot_cali.txt` + `cali.txt` is Tabb, a directory of CSVs is ETH,
    /// anything else JSON.
    #[default]
    Auto,
    /// `{"pairs": [{"left": L, "right": R, "weight": w}]}` (SPEC section 5).
    Json,
    /// Tabb dataset directory (`robot_cali.txt`, `cali.txt`): relative motions of all station pairs.
    Tabb,
    /// ETH ASL directory with a hand CSV (`*base_link*`) and a camera CSV (`*target*`).
    Eth,
}

/// Certification mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum CertifyArg {
    /// SDP certificate for the chordal L2 cost; none for other costs.
    #[default]
    Auto,
    /// SDP certificate (chordal L2 only).
    Sdp,
    /// No certificate.
    None,
}

/// Distance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum MetricArg {
    /// `||S R_i - L_i S||_F` (certified with `--loss l2`).
    #[default]
    Chordal,
    /// Angle of `R_i^T S^T L_i S`.
    Geodesic,
    /// Quaternion closed form.
    Quaternion,
}

/// Loss on each pair's distance.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum, Default)]
pub enum LossArg {
    /// Squared.
    #[default]
    L2,
    /// Absolute value.
    L1,
    /// Huber with threshold `--loss-scale`.
    Huber,
    /// Cauchy with scale `--loss-scale`.
    Cauchy,
}

/// Arguments of `rotavg conjugate`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Input file (or dataset directory for Tabb / ETH), or `-` for standard input (JSON).
    pub input: String,
    /// Input format.
    #[arg(long, value_enum, default_value_t = Format::Auto)]
    pub format: Format,
    /// Certification.
    #[arg(long, value_enum, default_value_t = CertifyArg::Auto)]
    pub certify: CertifyArg,
    /// Distance between R_i and S^T L_i S.
    #[arg(long, value_enum, default_value_t = MetricArg::Chordal)]
    pub metric: MetricArg,
    /// Loss.
    #[arg(long, value_enum, default_value_t = LossArg::L2)]
    pub loss: LossArg,
    /// Huber / Cauchy scale in the metric's unit (geodesic: radians).
    #[arg(long, default_value_t = 0.05)]
    pub loss_scale: f64,
    /// Write an SVG figure: histogram of the residual angles (degrees), the certificate, and
    /// the eigenvalues of the 10x10 certificate matrix with the proven bound.
    #[arg(long, value_name = "FILE.svg")]
    pub plot: Option<String>,
    #[command(flatten)]
    pub common: Common,
}

fn load(args: &Args) -> Result<(ConjugateProblem, String)> {
    let path = Path::new(&args.input);
    let is_dir = args.input != "-" && path.is_dir();
    let format = match args.format {
        Format::Auto if is_dir && path.join("robot_cali.txt").is_file() => Format::Tabb,
        Format::Auto if is_dir => Format::Eth,
        Format::Auto => Format::Json,
        f => f,
    };
    let motion = MotionSettings::default();
    match format {
        Format::Tabb => {
            let (p, s) = read_tabb_dir(path, &motion)?;
            Ok((
                p,
                format!(
                    "Tabb: {} stations, {} pairs ({} skipped: rotation < 0.57 deg)",
                    s.poses, s.pairs, s.skipped_small
                ),
            ))
        }
        Format::Eth => {
            let (p, s) = read_eth_dir(path, &motion)?;
            Ok((
                p,
                format!(
                    "ETH: {} time-matched samples, {} pairs ({} skipped)",
                    s.poses, s.pairs, s.skipped_small
                ),
            ))
        }
        _ => {
            let (name, text) = read_input(&args.input)?;
            let p = read_conjugate_json(&text, &name)?;
            Ok((p, format!("{name}: conjugate JSON")))
        }
    }
}

fn read_init(path: &Path) -> Result<Rotation> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
        path: name.clone(),
        message: e.to_string(),
    })?;
    let v: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| Error::parse(Some(&name), Some(e.line()), e.to_string()))?;
    let r = v
        .get("rotation")
        .or_else(|| v.get("estimate"))
        .ok_or_else(|| {
            Error::parse(
                Some(&name),
                None,
                "expected {\"rotation\": R} or {\"estimate\": R}",
            )
        })?;
    let rows: [[f64; 3]; 3] = serde_json::from_value(r.clone())
        .map_err(|e| Error::parse(Some(&name), None, e.to_string()))?;
    rotation_from_rows(&rows, DEFAULT_ROTATION_TOLERANCE, "initial estimate")
        .map_err(|e| e.in_file(&name, None))
}

/// Run the subcommand.
pub fn run(args: &Args) -> Result<Outcome> {
    let (mut problem, source) = load(args)?;
    if args.common.weights == WeightSource::Unit {
        problem = ConjugateProblem::new(
            problem
                .pairs()
                .iter()
                .map(|p| ConjugatePair::new(p.left, p.right))
                .collect(),
        )?;
    }
    let loss = match args.loss {
        LossArg::L2 => Loss::Squared,
        LossArg::L1 => Loss::L1,
        LossArg::Huber => Loss::Huber {
            delta: args.loss_scale,
        },
        LossArg::Cauchy => Loss::Cauchy {
            scale: args.loss_scale,
        },
    };
    let metric = match args.metric {
        MetricArg::Chordal => Metric::Chordal,
        MetricArg::Geodesic => Metric::Geodesic,
        MetricArg::Quaternion => Metric::Quaternion,
    };
    let settings = AverageSettings {
        local: ConjugateSettings {
            metric,
            loss,
            ..Default::default()
        },
        certify: match args.certify {
            CertifyArg::Auto => CertifyMode::Auto,
            CertifyArg::Sdp => CertifyMode::Sdp,
            CertifyArg::None => CertifyMode::None,
        },
        ..Default::default()
    };
    let diag = problem.diagnose(&DiagnosticSettings::default());
    let init = match &args.common.init {
        Some(p) => Some(read_init(p)?),
        None => None,
    };
    let est = average_conjugate_from(&problem, &settings, init.as_ref())?;
    let sol = &est.solution;
    let verdict = est.certificate.as_ref().map(|c| c.verdict);
    if let Some(path) = &args.plot {
        crate::multiple::write_figure(
            path,
            &problem.residual_angles(&sol.estimate),
            "pairs",
            est.certificate.as_ref(),
            1,
            &args.input,
        )?;
    }
    if args.common.json {
        let out = serde_json::json!({
            "problem": "conjugate",
            "num_rotations": 1,
            "num_measurements": problem.num_pairs(),
            "cost": sol.cost,
            "chordal_cost": sol.chordal_cost,
            "metric": sol.metric,
            "loss": sol.loss,
            "estimate": rotation_to_rows(&sol.estimate),
            "solver": sol.report,
            "certificate": est.certificate,
            "sdp": est.sdp,
            "diagnostics": {
                "median_angle_mismatch_deg": diag.median_angle_mismatch.to_degrees(),
                "max_angle_mismatch_deg": diag.max_angle_mismatch.to_degrees(),
                "suspicious_pairs": diag.suspicious_pairs,
                "small_rotation_pairs": diag.small_rotation_pairs,
                "identifiability": diag.identifiability,
            },
        });
        println!("{out}");
    } else if !args.common.quiet {
        println!("{source}");
        println!(
            "pairs: {}; angle mismatch |angle(L) - angle(R)|: median {:.3} deg, max {:.3} deg; {} suspicious (> 5 deg), {} with rotation < 0.57 deg",
            problem.num_pairs(),
            diag.median_angle_mismatch.to_degrees(),
            diag.max_angle_mismatch.to_degrees(),
            diag.suspicious_pairs.len(),
            diag.small_rotation_pairs.len()
        );
        let mut res = problem.residual_angles(&sol.estimate);
        res.sort_by(f64::total_cmp);
        let med = res.get(res.len() / 2).copied().unwrap_or(0.0);
        println!(
            "estimate S (row-major): {:?}",
            rotation_to_rows(&sol.estimate)
        );
        println!(
            "cost ({} {:?}) {:.9e}; chordal cost {:.9e}; median residual {:.4} deg",
            sol.metric,
            sol.loss,
            sol.cost,
            sol.chordal_cost,
            med.to_degrees()
        );
        println!("solver: {}", sol.report);
        if let Some(s) = &est.sdp {
            println!(
                "sdp: {:?}, {} iterations, {:.2} ms, Z eigenvalue ratio {:.1e}{}",
                s.status,
                s.iterations,
                s.solve_seconds * 1e3,
                s.eigenvalue_ratio,
                if s.improved_local {
                    "; SDP rounding improved the local solution"
                } else {
                    ""
                }
            );
        }
        match &est.certificate {
            Some(c) => println!("certificate: {c}"),
            None => println!("certificate: none"),
        }
        if let Some(p) = &args.plot {
            println!("figure written to {p}");
        }
    }
    Ok(Outcome { verdict })
}
