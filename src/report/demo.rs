//! `rotavg demo`: the three problems on built-in, seeded synthetic instances (no files needed).

use crate::certify::{Certificate, CertifySettings, Verdict, certify_multiple};
use crate::conjugate::synthetic::random_instance;
use crate::error::Result;
use crate::multiple::accuracy::{AccuracyReport, align_and_compare};
use crate::multiple::synthetic::SyntheticGraph;
use crate::multiple::{MultipleSettings, MultipleSolution, solve_multiple};
use crate::objective::{Loss, Objective};
use crate::pipeline::{ConjugateEstimate, SingleEstimate, average_conjugate, average_single};
use crate::single::SingleProblem;
use crate::so3::{Metric, Rotation, angle_between, perturb_gaussian, random_rotation};
use rand::SeedableRng;
use rand::rngs::StdRng;
use std::fmt;

/// Samples of the single-averaging instance.
const SINGLE_SAMPLES: usize = 1000;
/// Pairs of the conjugate instance.
const CONJUGATE_PAIRS: usize = 30;

/// The demo's results: five single means of 1000 noisy samples, a certified view graph, and a
/// certified hand-eye rotation. `Display` is the text `rotavg demo` prints.
///
/// ```
/// use rotavg::report::DemoReport;
/// use rotavg::Verdict;
/// let demo = DemoReport::run(1, 30)?;
/// assert_eq!(demo.verdicts().len(), 8);
/// assert_ne!(demo.worst_verdict(), Verdict::Inconclusive);
/// assert!(demo.to_string().contains("=== summary"));
/// # Ok::<(), rotavg::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct DemoReport {
    /// The rotation the single samples scatter around.
    pub single_truth: Rotation,
    /// The single means (chordal L2, quaternion L2, geodesic L2, geodesic L1, chordal L1).
    pub single: Vec<SingleEstimate>,
    /// The geodesic L1 mean of spread data (the same samples with 20 % replaced by uniform
    /// outliers, beyond the pi/2 ball of the convexity theorem): certified by the branch and
    /// bound over SO(3) (`[B1]`-`[B6]`).
    pub spread: SingleEstimate,
    /// The view graph's number of nodes and edges.
    pub graph_size: (usize, usize),
    /// The local solution of the view graph.
    pub multiple: MultipleSolution,
    /// Its certificate.
    pub multiple_certificate: Certificate,
    /// Its accuracy against the planted rotations.
    pub multiple_accuracy: AccuracyReport,
    /// The planted hand-eye rotation.
    pub conjugate_truth: Rotation,
    /// The hand-eye pipeline's result.
    pub conjugate: ConjugateEstimate,
}

impl DemoReport {
    /// Run the demo: the instances are drawn from `seed`; the view graph has `nodes` nodes
    /// (at least 3) and `4 nodes` edges with 2 degrees of noise.
    pub fn run(seed: u64, nodes: usize) -> Result<Self> {
        let mut rng = StdRng::seed_from_u64(seed);
        let single_truth = random_rotation(&mut rng);
        let samples: Vec<_> = (0..SINGLE_SAMPLES)
            .map(|_| perturb_gaussian(&single_truth, 0.1, &mut rng))
            .collect();
        let problem = SingleProblem::new(samples, None)?;
        let mut single = Vec::new();
        for (metric, loss) in [
            (Metric::Chordal, Loss::L2),
            (Metric::Quaternion, Loss::L2),
            (Metric::Geodesic, Loss::L2),
            (Metric::Geodesic, Loss::L1),
            (Metric::Chordal, Loss::L1),
        ] {
            let p = problem
                .clone()
                .with_objective(Objective::new(metric, loss))?;
            single.push(average_single(&p, &Default::default())?);
        }
        let outlying: Vec<_> = problem
            .rotations()
            .iter()
            .enumerate()
            .map(|(k, r)| {
                if k % 5 == 0 {
                    random_rotation(&mut rng)
                } else {
                    *r
                }
            })
            .collect();
        let spread = average_single(
            &SingleProblem::new(outlying, None)?
                .with_objective(Objective::new(Metric::Geodesic, Loss::L1))?,
            &Default::default(),
        )?;

        let n = nodes.max(3);
        let (graph, truth) = SyntheticGraph {
            num_rotations: n,
            num_edges: 4 * n,
            noise_sigma: 2f64.to_radians(),
            outlier_fraction: 0.0,
            seed,
        }
        .generate();
        let multiple = solve_multiple(&graph, &MultipleSettings::default())?;
        let cert = certify_multiple(&graph, &multiple.rotations, &CertifySettings::default())?;
        let truth: Vec<_> = truth.into_iter().map(Some).collect();
        let multiple_accuracy = align_and_compare(&multiple.rotations, &truth)?;

        let (problem, conjugate_truth) =
            random_instance(CONJUGATE_PAIRS, 1f64.to_radians(), 0.0, &mut rng);
        let conjugate = average_conjugate(&problem, &Default::default())?;
        Ok(DemoReport {
            single_truth,
            single,
            spread,
            graph_size: (graph.num_rotations(), graph.num_edges()),
            multiple,
            multiple_certificate: cert.certificate,
            multiple_accuracy,
            conjugate_truth,
            conjugate,
        })
    }

    /// The verdicts in order: the five single means and the spread geodesic L1 mean
    /// (inconclusive where there is no certificate), the view graph, the hand-eye rotation
    /// (when certified at all).
    pub fn verdicts(&self) -> Vec<Verdict> {
        let mut v: Vec<Verdict> = self
            .single
            .iter()
            .map(|e| {
                e.certificate
                    .as_ref()
                    .map_or(Verdict::Inconclusive, |c| c.verdict)
            })
            .collect();
        v.push(
            self.spread
                .certificate
                .as_ref()
                .map_or(Verdict::Inconclusive, |c| c.verdict),
        );
        v.push(self.multiple_certificate.verdict);
        v.extend(self.conjugate.certificate.as_ref().map(|c| c.verdict));
        v
    }

    /// The worst verdict: inconclusive, then gap reported, then certified.
    pub fn worst_verdict(&self) -> Verdict {
        let v = self.verdicts();
        if v.contains(&Verdict::Inconclusive) {
            Verdict::Inconclusive
        } else if v.contains(&Verdict::GapReported) {
            Verdict::GapReported
        } else {
            Verdict::Certified
        }
    }
}

/// A section title: `\n=== TITLE ====...` (72 columns).
fn rule(f: &mut fmt::Formatter<'_>, title: &str) -> fmt::Result {
    writeln!(
        f,
        "\n=== {title} {}",
        "=".repeat(70usize.saturating_sub(title.len()))
    )
}

/// A single mean's line: objective, cost, error to `truth`, time, verdict and bounding method,
/// `detail` (what the method did) after the method.
fn single_row(
    f: &mut fmt::Formatter<'_>,
    est: &SingleEstimate,
    truth: &Rotation,
    detail: &str,
) -> fmt::Result {
    let (s, c) = (&est.solution, est.certificate.as_ref());
    writeln!(
        f,
        "  {:<15} cost {:12.6}  error to truth {:.4} deg  {:8.3} ms  {} ({}{detail})",
        format!("{}:", s.objective),
        s.cost,
        angle_between(&s.estimate, truth).to_degrees(),
        s.report.seconds * 1e3,
        c.map_or(Verdict::Inconclusive, |c| c.verdict),
        c.map_or("none".to_string(), |c| c.method.to_string()),
    )
}

impl fmt::Display for DemoReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        rule(f, "1. single rotation averaging")?;
        writeln!(
            f,
            "{SINGLE_SAMPLES} noisy estimates of one rotation (Gaussian noise, 0.1 rad per axis)"
        )?;
        for est in &self.single {
            single_row(f, est, &self.single_truth, "")?;
        }

        writeln!(
            f,
            "the same samples with every fifth replaced by a uniform outlier (beyond the pi/2 ball):"
        )?;
        let stats = self
            .spread
            .certificate
            .as_ref()
            .and_then(|c| c.branch_and_bound);
        let search = stats.map_or(String::new(), |b| {
            format!(
                ": {} cells, depth {}, {:.3} s",
                b.cells_explored, b.max_depth, b.seconds
            )
        });
        single_row(f, &self.spread, &self.single_truth, &search)?;

        rule(f, "2. multiple rotation averaging (view graph)")?;
        writeln!(
            f,
            "random connected graph: {} nodes, {} edges, noise 2 deg per axis, R_ij R_i = R_j",
            self.graph_size.0, self.graph_size.1
        )?;
        writeln!(f, "{}", self.multiple)?;
        super::nested(f, &self.multiple_certificate)?;
        writeln!(f)?;
        writeln!(f, "{}", self.multiple_accuracy)?;

        rule(f, "3. conjugate rotation averaging (hand-eye)")?;
        writeln!(
            f,
            "{CONJUGATE_PAIRS} motion pairs (L_i, R_i) with R_i ~ S^-1 L_i S, noise 1 deg per axis"
        )?;
        let s = &self.conjugate.solution;
        writeln!(
            f,
            "  {}: cost {:.6e}, error to planted S {:.4} deg",
            s.report,
            s.cost,
            angle_between(&s.estimate, &self.conjugate_truth).to_degrees()
        )?;
        if let Some(c) = &self.conjugate.certificate {
            write!(f, "  ")?;
            super::nested(f, c)?;
            writeln!(f)?;
        }

        let v = self.verdicts();
        let count = |x: Verdict| v.iter().filter(|&&y| y == x).count();
        rule(f, "summary")?;
        write!(
            f,
            "{} certificates: {} certified, {} gap reported, {} inconclusive",
            v.len(),
            count(Verdict::Certified),
            count(Verdict::GapReported),
            count(Verdict::Inconclusive)
        )
    }
}
