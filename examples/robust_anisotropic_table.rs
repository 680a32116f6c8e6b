//! Robust averaging of two-view-like anisotropic information with outliers (issue 37): the
//! default loss (`--loss auto`), Cauchy on the Mahalanobis angle, Cauchy with the scalar
//! weights `tr(H) / 3` and with unit weights, and least squares, against the planted truth.
//!
//! ```text
//! cargo run --release --example robust_anisotropic_table -- [MAX_NODES] [CERTIFY_UP_TO] [EDGES]
//! ```
//!
//! Each size is one graph from [`SyntheticAnisotropic::two_view_like`] with 10 % outliers: 0.5
//! degrees along the well-determined axes, a weak axis whose standard-deviation ratio is
//! log-normal around 9 (eigenvalue ratios around 80 with a tail past 10^5), random axes, the
//! outliers random rotations with their information kept (confident wrong pairs), seed 1. The solve rows
//! are `solve_multiple` alone (seconds, IRLS iterations, median error after the optimal
//! alignment); "auto" is `average_multiple` with the command line's default rule and
//! `--certify auto` (total seconds, of which the solves' and the certificate's, its choice and
//! verdict), run up to `CERTIFY_UP_TO` nodes
//! (default 3000). Rows up to `MAX_NODES` (default 10000); the 10^4-camera row has `EDGES`
//! edges (default 100000; issue 37's sparser reference is 40000). Prints a Markdown table.
use rotavg::Metric;
use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::synthetic::SyntheticAnisotropic;
use rotavg::multiple::{Edge, MultipleProblem, MultipleSettings, solve_multiple};
use rotavg::objective::{Loss, Objective};
use rotavg::pipeline::{AverageSettings, average_multiple};
use rotavg::{Result, Rotation};
use std::time::Instant;

const CAUCHY: Objective = Objective::new(Metric::Geodesic, Loss::Cauchy { scale_deg: 5.0 });

fn main() -> Result<()> {
    let args: Vec<usize> = std::env::args()
        .skip(1)
        .filter_map(|a| a.parse().ok())
        .collect();
    let max_nodes = args.first().copied().unwrap_or(10_000);
    let certify_up_to = args.get(1).copied().unwrap_or(3000);
    let edges_at_10k = args.get(2).copied().unwrap_or(100_000);
    println!("| cameras | edges | run | seconds | iterations | median error (deg) | verdict |");
    println!("|---|---|---|---|---|---|---|");
    for (n, m) in [(1000, 4000), (3000, 12_000), (10_000, edges_at_10k)] {
        if n > max_nodes {
            continue;
        }
        let (p, truth) = SyntheticAnisotropic::two_view_like(n, m, 0.1).generate();
        let truth: Vec<Option<Rotation>> = truth.into_iter().map(Some).collect();
        let scalar = with_weights(&p, |h| h.trace() / 3.0)?;
        let unit = with_weights(&p, |_| 1.0)?;
        for (name, problem) in [
            ("cauchy, information", p.clone().with_objective(CAUCHY)?),
            ("cauchy, weights tr(H)/3", scalar.with_objective(CAUCHY)?),
            ("cauchy, unit weights", unit.with_objective(CAUCHY)?),
            ("least squares, information", p.clone()),
        ] {
            let t = Instant::now();
            let s = solve_multiple(&problem, &MultipleSettings::default())?;
            let seconds = t.elapsed().as_secs_f64();
            let error = align_and_compare(&s.rotations, &truth)?.median_deg;
            let its = s.report.iterations;
            println!("| {n} | {m} | {name} | {seconds:.3} | {its} | {error:.3} | |");
        }
        if n <= certify_up_to {
            auto_row(&p, &truth)?;
        }
    }
    Ok(())
}

/// The default rule with `--certify auto`: total time, the choice and the verdict.
fn auto_row(p: &MultipleProblem, truth: &[Option<Rotation>]) -> Result<()> {
    let settings = AverageSettings {
        solve: MultipleSettings {
            robust_on_outliers: Some(CAUCHY),
            ..Default::default()
        },
        ..Default::default()
    };
    let t = Instant::now();
    let r = average_multiple(p, &settings)?;
    let seconds = t.elapsed().as_secs_f64();
    let error = align_and_compare(&r.solution.rotations, truth)?.median_deg;
    let chosen = r.details.loss_choice.as_ref().map_or("?".into(), |c| {
        rotavg::io::names::MultipleLoss::name_of(&c.chosen)
    });
    let verdict = match (&r.certificate, &r.details.inlier_graph) {
        (Some(c), _) => format!("{} (all edges)", c.verdict),
        (None, Some(g)) => match &g.certificate {
            Some(c) => format!(
                "{} (inlier graph, {} of {} edges)",
                c.verdict, g.problem.num_edges, g.problem.total_edges
            ),
            None => "none".into(),
        },
        _ => "none".into(),
    };
    println!(
        "| {} | {} | auto (chose {chosen}), certify auto | {seconds:.3} (solve {:.3}, certify {:.3}) | {} | {error:.3} | {verdict} |",
        p.num_rotations(),
        p.num_edges(),
        r.details.solve_seconds,
        r.details.certify_seconds,
        r.solution.report.iterations
    );
    Ok(())
}

/// The same graph with scalar weights `w(H)` instead of its information.
fn with_weights(
    p: &MultipleProblem,
    w: impl Fn(&nalgebra::Matrix3<f64>) -> f64,
) -> Result<MultipleProblem> {
    let information = p.information().unwrap_or_default();
    let edges = p
        .edges()
        .iter()
        .zip(information)
        .map(|(e, h)| Edge {
            weight: w(h.matrix()),
            ..e.clone()
        })
        .collect();
    MultipleProblem::new(p.num_rotations(), edges)
}
