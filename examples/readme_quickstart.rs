use rotavg::Metric;
use rotavg::certify::{CertifySettings, certify_multiple};
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::multiple::{MultipleSettings, solve_multiple};
use rotavg::nalgebra::Vector3;
use rotavg::objective::{Loss, Objective};
use rotavg::pipeline::{AverageSettings, average_single};
use rotavg::single::SingleProblem;
use rotavg::so3::exp;

fn main() -> rotavg::Result<()> {
    // Multiple rotation averaging on a seeded random view graph (R_ij R_i = R_j).
    let spec = SyntheticGraph {
        num_rotations: 200,
        num_edges: 800,
        noise_sigma: 0.02,
        ..Default::default()
    };
    let (problem, _truth) = spec.generate();
    let solution = solve_multiple(&problem, &MultipleSettings::default())?; // spectral init + Newton-LM
    let cert = certify_multiple(&problem, &solution.rotations, &CertifySettings::default())?;
    println!("{solution}\n{}", cert.certificate);
    assert!(cert.certificate.is_certified()); // proven globally optimal

    // Certify an estimate computed elsewhere, without changing it: here a rotated copy of ours
    // (same cost by gauge invariance) and a corrupted one (never certified, but its gap is bounded).
    let g = exp(&Vector3::new(0.3, -0.2, 0.1));
    let theirs: Vec<_> = solution.rotations.iter().map(|r| r * g).collect();
    let settings = CertifySettings::default();
    let rotated = certify_multiple(&problem, &theirs, &settings)?.certificate;
    assert!(rotated.is_certified());
    let mut bad = theirs.clone();
    bad[5] *= exp(&Vector3::new(0.0, 0.0, 0.5));
    let verdict = certify_multiple(&problem, &bad, &settings)?.certificate;
    let bounded = verdict
        .lower_bound
        .is_some_and(|lb| lb <= cert.certificate.upper_bound);
    assert!(!verdict.is_certified() && bounded);

    // Single rotation averaging: the geodesic L1 mean (Weiszfeld on SO(3)).
    let samples = solution.rotations[..10].to_vec();
    let single = SingleProblem::new(samples, None)?
        .with_objective(Objective::new(Metric::Geodesic, Loss::L1))?;
    let mean = average_single(&single, &AverageSettings::default())?; // solve, then certify
    println!("{mean}");
    Ok(())
}
