use rotavg::conjugate::synthetic::random_instance;
use rotavg::io::detect::{GraphFormat, ReadOptions, read_graph};
use rotavg::pipeline::{AverageSettings, average_conjugate, average_multiple};
use rotavg::rand::{SeedableRng, rngs::StdRng};

fn main() -> rotavg::Result<()> {
    // Conjugate averaging: S with R_i ~ S^-1 L_i S from 30 noisy pairs (seeded, planted S),
    // closed form -> Gauss-Newton -> 10x10 SDP with an independently verified bound.
    let mut rng = StdRng::seed_from_u64(1);
    let (pairs, planted) = random_instance(30, 0.01, 0.0, &mut rng);
    let hand_eye = average_conjugate(&pairs, &AverageSettings::default())?;
    let error = rotavg::so3::angle_between(&hand_eye.solution.estimate, &planted);
    let certified = hand_eye.certificate.is_some_and(|c| c.is_certified());
    assert!(error < 0.01 && certified);

    // Any supported view-graph format (here a TORO triangle given inline; `load_graph` reads a
    // path), then the whole multiple-averaging pipeline: solve, certify, fall back to the SDP or
    // the staircase when the dual certificate fails.
    let text = "EDGE3 0 1 0 0 0 0 0 0.1\nEDGE3 1 2 0 0 0 0 0 0.2\nEDGE3 2 0 0 0 0 0 0 -0.25\n";
    let options = ReadOptions::default();
    let graph = read_graph(text, "triangle.g2o", GraphFormat::Auto, &options)?;
    let estimate = average_multiple(&graph.problem, &AverageSettings::default())?;
    println!("{estimate}");
    assert!(estimate.certificate.is_some_and(|c| c.is_certified()));
    Ok(())
}
