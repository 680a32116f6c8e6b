//! Certify the chordal L2 rotation average of a pose graph given on the command line.
//!
//! ```text
//! cargo run --release --example certify_g2o -- FILE [--unit-weights] [--sdp] [--json]
//! ```
//!
//! `FILE` is any view-graph file [`rotavg::io::detect::load_graph`] reads: g2o / TORO
//! (`EDGE_SE3:QUAT`, `EDGE3`, `EDGE_SE2`), a 1DSfM `EGs.txt`, or the JSON problem format.
//! Weights default to the file's (SE-Sync's `kappa` for g2o); `--unit-weights` sets all to 1.
//!
//! Pipeline: load, keep the largest connected component, solve chordal L2 from the spectral
//! initialisation (Riemannian Newton / LM), certify with the dual certificate (a verified
//! lower bound from a sparse Cholesky factorisation). Prints the time of each stage, the cost,
//! the verdict and the gap.
//!
//! `--sdp` also solves the SDP relaxation with Clarabel (dual form; only for small graphs,
//! a few hundred nodes at most) and certifies its rounded solution with the SDP multipliers.
//! `--json` prints one JSON object instead of text (used by `benches/peers/run.sh`).
//! `--gradient-tolerance X` overrides the solver's relative gradient tolerance (default 1e-8).

use rotavg::BoundMethod;
use rotavg::certify::CertifySettings;
use rotavg::certify::multiple::certify_with_multipliers;
use rotavg::io::detect::{GraphFormat, ReadOptions, WeightSource, load_graph};
use rotavg::pipeline::{AverageMultipleSettings, average_multiple};
use rotavg::relax::{SdpSettings, relax_multiple};
use std::path::PathBuf;
use std::time::Instant;

struct Args {
    path: PathBuf,
    unit_weights: bool,
    sdp: bool,
    json: bool,
    gradient_tolerance: Option<f64>,
}

fn parse_args() -> rotavg::Result<Args> {
    let mut path = None;
    let (mut unit_weights, mut sdp, mut json) = (false, false, false);
    let mut gradient_tolerance = None;
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        match a.as_str() {
            "--gradient-tolerance" => {
                gradient_tolerance = it.next().and_then(|v| v.parse::<f64>().ok());
                if gradient_tolerance.is_none() {
                    return Err(rotavg::Error::InvalidSettings {
                        name: a,
                        reason: "expects a number".into(),
                    });
                }
            }
            "--unit-weights" => unit_weights = true,
            "--sdp" => sdp = true,
            "--json" => json = true,
            s if s.starts_with("--") => {
                return Err(rotavg::Error::InvalidSettings {
                    name: s.into(),
                    reason: "unknown option (expected --unit-weights, --sdp, --json, --gradient-tolerance X)"
                        .into(),
                });
            }
            _ => path = Some(PathBuf::from(&a)),
        }
    }
    let path = path.ok_or_else(|| rotavg::Error::InvalidSettings {
        name: "FILE".into(),
        reason:
            "usage: certify_g2o FILE [--unit-weights] [--sdp] [--json] [--gradient-tolerance X]"
                .into(),
    })?;
    Ok(Args {
        path,
        unit_weights,
        sdp,
        json,
        gradient_tolerance,
    })
}

fn run() -> rotavg::Result<()> {
    let args = parse_args()?;
    let total = Instant::now();

    let t = Instant::now();
    let options = ReadOptions {
        weights: if args.unit_weights {
            WeightSource::Unit
        } else {
            WeightSource::File
        },
        ..Default::default()
    };
    let loaded = load_graph(&args.path, GraphFormat::Auto, &options)?;
    let (problem, _kept) = loaded.problem.largest_component();
    let load_s = t.elapsed().as_secs_f64();

    // The whole pipeline: spectral init, Newton-LM, refinement when the stationarity residual
    // is too large for the certificate, dual certificate (SDP / staircase when it fails).
    let mut settings = AverageMultipleSettings::default();
    if let Some(tol) = args.gradient_tolerance {
        settings.solve.gradient_tolerance = tol;
    }
    let estimate = average_multiple(&problem, &settings)?;
    let solution = &estimate.solution;
    let refine_s = estimate
        .details
        .certify
        .as_ref()
        .map_or(0.0, |c| c.refine_seconds);
    let solve_s = estimate.details.solve_seconds + refine_s;
    let certify_s = estimate.details.certify_seconds;
    let c = estimate
        .certificate
        .as_ref()
        .ok_or_else(|| rotavg::Error::Solver {
            message: "no certificate for the chordal cost".into(),
        })?;
    let total_s = total.elapsed().as_secs_f64();

    // Optional: the SDP relaxation (Clarabel), certified by its own multipliers.
    let sdp = if args.sdp {
        let t = Instant::now();
        let relax = relax_multiple(&problem, &SdpSettings::default())?;
        let sdp_cert = certify_with_multipliers(
            &problem,
            &relax.rounded,
            &relax.multipliers,
            BoundMethod::Sdp,
            &CertifySettings::default(),
        )?;
        Some((relax, sdp_cert, t.elapsed().as_secs_f64()))
    } else {
        None
    };

    if args.json {
        let mut out = serde_json::json!({
            "file": args.path.display().to_string(),
            "weights": if args.unit_weights { "unit" } else { "file" },
            "nodes": problem.num_rotations(),
            "edges": problem.num_edges(),
            "nodes_in_file": loaded.problem.num_rotations(),
            "load_seconds": load_s,
            "solve_seconds": solve_s,
            "certify_seconds": certify_s,
            "total_seconds": total_s,
            "iterations": solution.report.iterations,
            "termination": solution.report.termination,
            "cost": solution.chordal_cost,
            "init_cost": solution.init_cost,
            "certified": c.is_certified(),
            "verdict": c.verdict,
            "lower_bound": c.lower_bound,
            "gap": c.gap,
            "relative_gap": c.relative_gap,
            "min_eigenvalue": c.min_eigenvalue,
            "method": c.method,
        });
        if let Some((relax, sc, secs)) = &sdp {
            out["sdp"] = serde_json::json!({
                "status": relax.status,
                "iterations": relax.iterations,
                "solver_seconds": relax.solver_seconds,
                "relax_seconds": relax.seconds,
                "seconds_with_certificate": secs,
                "dual_objective": relax.dual_objective,
                "primal_objective": relax.primal_objective,
                "rounded_cost": relax.rounded_cost,
                "verified_lower_bound": sc.certificate.lower_bound,
                "certified": sc.certificate.is_certified(),
                "gap": sc.certificate.gap,
                "x_top_eigenvalues": relax.x_top_eigenvalues,
            });
        }
        println!("{out}");
        return Ok(());
    }

    println!(
        "{}: {} nodes, {} edges (largest component of {} nodes), {} weights",
        args.path.display(),
        problem.num_rotations(),
        problem.num_edges(),
        loaded.problem.num_rotations(),
        if args.unit_weights { "unit" } else { "file" }
    );
    for w in &loaded.warnings {
        println!("  warning: {w}");
    }
    println!("load     {load_s:9.4} s");
    println!("solve    {solve_s:9.4} s  ({})", solution.report);
    println!("certify  {certify_s:9.4} s");
    println!("total    {total_s:9.4} s");
    println!(
        "cost     {:.9e}  (spectral init {:.6e})",
        solution.chordal_cost, solution.init_cost
    );
    println!("verdict  {:?}", c.verdict);
    println!(
        "bound    {}  gap {}  relative gap {}",
        fmt_opt(c.lower_bound),
        fmt_opt(c.gap),
        fmt_opt(c.relative_gap)
    );
    println!("         {}", c.explanation);
    if let Some((relax, sc, secs)) = &sdp {
        println!(
            "sdp      {secs:9.4} s  status {:?}, {} iterations, rounded cost {:.9e}, verified bound {}, {:?}",
            relax.status,
            relax.iterations,
            relax.rounded_cost,
            fmt_opt(sc.certificate.lower_bound),
            sc.certificate.verdict
        );
    }
    Ok(())
}

fn fmt_opt(x: Option<f64>) -> String {
    x.map_or_else(|| "-".into(), |v| format!("{v:.6e}"))
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
