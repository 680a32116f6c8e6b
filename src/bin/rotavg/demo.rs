//! `rotavg demo`: the three problems on built-in, seeded synthetic instances (no files needed).

use crate::Outcome;
use clap::Args as ClapArgs;
use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::certify::multiple::{CertifySettings, certify_multiple};
use rotavg::conjugate::{average_conjugate, synthetic::random_instance};
use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::multiple::{MultipleSettings, solve_multiple};
use rotavg::single::{Norm, SingleProblem, SingleSettings, average_single};
use rotavg::so3::{angle_between, perturb_gaussian, random_rotation};
use rotavg::{Metric, Verdict};

/// Arguments of `rotavg demo`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Seed of the synthetic instances.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Number of nodes of the multiple-averaging instance.
    #[arg(long, default_value_t = 1000)]
    pub nodes: usize,
}

fn rule(title: &str) {
    println!(
        "\n=== {title} {}",
        "=".repeat(70usize.saturating_sub(title.len()))
    );
}

/// Run the demo. The verdict returned is the worst of the three certificates.
pub fn run(args: &Args) -> rotavg::Result<Outcome> {
    let mut rng = StdRng::seed_from_u64(args.seed);
    let mut verdicts = Vec::new();

    rule("1. single rotation averaging");
    let truth = random_rotation(&mut rng);
    let samples: Vec<_> = (0..1000)
        .map(|_| perturb_gaussian(&truth, 0.1, &mut rng))
        .collect();
    println!("1000 noisy estimates of one rotation (Gaussian noise, 0.1 rad per axis)");
    let problem = SingleProblem::new(samples, None)?;
    for (metric, norm) in [
        (Metric::Chordal, Norm::L2),
        (Metric::Quaternion, Norm::L2),
        (Metric::Geodesic, Norm::L2),
        (Metric::Geodesic, Norm::L1),
        (Metric::Chordal, Norm::L1),
    ] {
        let s = average_single(&problem, &SingleSettings::new(metric, norm))?;
        println!(
            "  {:<14} cost {:12.6}  error to truth {:.4} deg  {:8.3} ms  {} ({})",
            format!("{metric} {norm}:"),
            s.cost,
            angle_between(&s.estimate, &truth).to_degrees(),
            s.report.seconds * 1e3,
            s.certificate.verdict,
            s.certificate.method,
        );
        verdicts.push(s.certificate.verdict);
    }

    rule("2. multiple rotation averaging (view graph)");
    let n = args.nodes.max(3);
    let spec = SyntheticGraph {
        num_rotations: n,
        num_edges: 4 * n,
        noise_sigma: 2f64.to_radians(),
        outlier_fraction: 0.0,
        seed: args.seed,
    };
    let (problem, truth) = spec.generate();
    println!(
        "random connected graph: {} nodes, {} edges, noise 2 deg per axis, R_ij R_i = R_j",
        problem.num_rotations(),
        problem.num_edges()
    );
    let solution = solve_multiple(&problem, &MultipleSettings::default())?;
    println!("{solution}");
    let cert = certify_multiple(&problem, &solution.rotations, &CertifySettings::default())?;
    println!("{}", cert.certificate);
    let truth: Vec<_> = truth.into_iter().map(Some).collect();
    let acc = align_and_compare(&solution.rotations, &truth)?;
    println!("{acc}");
    verdicts.push(cert.certificate.verdict);

    rule("3. conjugate rotation averaging (hand-eye)");
    let (problem, s_true) = random_instance(30, 1f64.to_radians(), 0.0, &mut rng);
    println!("30 motion pairs (L_i, R_i) with R_i ~ S^-1 L_i S, noise 1 deg per axis");
    let est = average_conjugate(&problem, &Default::default())?;
    println!(
        "  {}: cost {:.6e}, error to planted S {:.4} deg",
        est.solution.report,
        est.solution.cost,
        angle_between(&est.solution.estimate, &s_true).to_degrees()
    );
    if let Some(c) = &est.certificate {
        println!("  {c}");
        verdicts.push(c.verdict);
    }

    let worst = if verdicts.contains(&Verdict::Inconclusive) {
        Verdict::Inconclusive
    } else if verdicts.contains(&Verdict::GapReported) {
        Verdict::GapReported
    } else {
        Verdict::Certified
    };
    rule("summary");
    println!(
        "{} certificates: {} certified, {} gap reported, {} inconclusive",
        verdicts.len(),
        verdicts
            .iter()
            .filter(|v| **v == Verdict::Certified)
            .count(),
        verdicts
            .iter()
            .filter(|v| **v == Verdict::GapReported)
            .count(),
        verdicts
            .iter()
            .filter(|v| **v == Verdict::Inconclusive)
            .count()
    );
    Ok(Outcome {
        verdict: Some(worst),
    })
}
