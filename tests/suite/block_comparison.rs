//! The block comparison `[A15]` on the ladder: the realistic two-view class certified by it
//! alone, its bound below the best of several local solutions, an estimate off the optimum
//! never certified, and the default threshold keeping it off graphs whose `S` factors cheaply.

use rand::SeedableRng;
use rand::rngs::StdRng;
use rotavg::Rotation;
use rotavg::certify::{CertifyMode, CertifySettings, Outcome, Proof, certify_multiple};
use rotavg::multiple::synthetic::SyntheticAnisotropic;
use rotavg::multiple::{Initialisation, MultipleProblem, MultipleSettings, solve_multiple};
use rotavg::so3::{perturb_gaussian, random_rotation};

fn block_only() -> CertifySettings {
    let mut s = CertifySettings::with_mode(CertifyMode::Dual);
    s.dual.proofs = vec![Proof::BlockComparison];
    s.dual.block_comparison_above = 0;
    s
}

fn proved_by_block(c: &rotavg::certify::Certification<rotavg::multiple::MultipleSolution>) -> bool {
    c.details
        .ladder
        .iter()
        .any(|a| a.rung == Proof::BlockComparison && matches!(a.outcome, Outcome::Proved { .. }))
}

/// The best of local solutions from the planted truth and from random starts.
fn best_known(p: &MultipleProblem, truth: &[Rotation], rng: &mut StdRng) -> f64 {
    let mut starts = vec![truth.to_vec()];
    for _ in 0..3 {
        starts.push(
            (0..p.num_rotations())
                .map(|_| random_rotation(rng))
                .collect(),
        );
    }
    starts
        .into_iter()
        .filter_map(|s| {
            let settings = MultipleSettings {
                init: Initialisation::Given(s),
                ..Default::default()
            };
            solve_multiple(p, &settings).ok().map(|s| s.cost)
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn realistic_two_view_graphs_are_certified_by_the_block_comparison_alone() {
    let mut rng = StdRng::seed_from_u64(11);
    for (n, m) in [(300, 1500), (1000, 4000)] {
        let (p, truth) = SyntheticAnisotropic::two_view_like(n, m, 0.0).generate();
        let s = solve_multiple(&p, &MultipleSettings::default()).unwrap();
        let c = certify_multiple(&p, &s.rotations, &block_only()).unwrap();
        assert!(c.certificate.is_certified(), "{n}: {}", c.certificate);
        assert!(proved_by_block(&c), "{n}: {:?}", c.details.ladder);
        let best = best_known(&p, &truth, &mut rng);
        let lb = c.certificate.lower_bound.unwrap();
        assert!(lb <= best + 1e-9 * best, "{n}: bound {lb} above {best}");
        assert_off_is_not_certified(&p, &s.rotations, &mut rng);
    }
}

/// 1e-3 rad off the optimum: far above the tolerance, never certified (unless the
/// certification found a better point).
fn assert_off_is_not_certified(p: &MultipleProblem, rotations: &[Rotation], rng: &mut StdRng) {
    let off: Vec<Rotation> = rotations
        .iter()
        .map(|r| perturb_gaussian(r, 1e-3, rng))
        .collect();
    let c = certify_multiple(p, &off, &block_only()).unwrap();
    assert!(
        !c.certificate.is_certified() || c.improvement.is_some(),
        "{} cameras: {}",
        p.num_rotations(),
        c.certificate
    );
}

#[test]
fn the_default_keeps_the_block_comparison_off_graphs_that_factor_cheaply() {
    let (p, _) = SyntheticAnisotropic::two_view_like(300, 1500, 0.0).generate();
    let s = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let c = certify_multiple(&p, &s.rotations, &CertifySettings::default()).unwrap();
    assert!(c.certificate.is_certified(), "{}", c.certificate);
    let block = c
        .details
        .ladder
        .iter()
        .find(|a| a.rung == Proof::BlockComparison);
    assert!(
        matches!(block.map(|a| &a.outcome), Some(Outcome::Refused(_))),
        "{:?}",
        c.details.ladder
    );
}

/// Its subgraph's choice and analysis come before any prediction: refused, with the reason,
/// when even that work would pass the time left.
#[test]
fn the_block_comparison_is_refused_when_its_work_passes_the_time_left() {
    let (p, _) = SyntheticAnisotropic::two_view_like(300, 1500, 0.0).generate();
    let s = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let mut settings = block_only();
    settings.budget.max_seconds = Some(1e-6);
    let c = certify_multiple(&p, &s.rotations, &settings).unwrap();
    assert!(!proved_by_block(&c), "{:?}", c.details.ladder);
    assert!(
        c.details
            .ladder
            .iter()
            .any(|a| a.rung == Proof::BlockComparison && matches!(a.outcome, Outcome::Refused(_))),
        "{:?}",
        c.details.ladder
    );
}

/// From 10^4 cameras the block rung tries its subgraph in 3 regions (`[A15]`, "Regions") first:
/// the realistic class of 10^5 edges is certified by it with the default settings, its bound
/// below the cost at the planted truth's local solution (any feasible point's cost bounds the
/// optimum from above), and an estimate 1e-3 rad off is not certified.
#[test]
fn regions_certify_a_ten_thousand_camera_graph() {
    let (p, truth) = SyntheticAnisotropic::two_view_like(10_000, 100_000, 0.0).generate();
    let s = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let c = certify_multiple(&p, &s.rotations, &CertifySettings::default()).unwrap();
    assert!(c.certificate.is_certified(), "{}", c.certificate);
    let in_regions = c.details.ladder.iter().any(|a| {
        a.rung == Proof::BlockComparison
            && matches!(a.outcome, Outcome::Proved { .. })
            && a.note.contains("in 3 regions")
    });
    assert!(in_regions, "{:?}", c.details.ladder);
    let planted = solve_multiple(
        &p,
        &MultipleSettings {
            init: Initialisation::Given(truth),
            ..Default::default()
        },
    )
    .unwrap()
    .cost;
    let lb = c.certificate.lower_bound.unwrap();
    assert!(lb <= planted * (1.0 + 1e-9), "bound {lb} above {planted}");
    assert_off_is_not_certified(&p, &s.rotations, &mut StdRng::seed_from_u64(12));
}

/// A subgraph whose factor is more than half the whole graph's is not tried while the grounded
/// bound, which factorises the whole graph, is on the ladder (`BLOCK_WHOLE_FRACTION`): on a
/// graph of 6 edges per node the sparsest subgraph is tried and fails (4 negative pivots), the
/// denser ones are most of the graph and are not planned (with the fraction at 10 the next one
/// is planned and logged as not needed: checked), and the grounded bound certifies.
#[test]
fn subgraphs_nearly_as_large_as_the_graph_are_left_to_the_grounded_bound() {
    let ladder = grounded_ladder(1000, 6000);
    let block: Vec<_> = ladder
        .iter()
        .filter(|a| a.rung == Proof::BlockComparison)
        .collect();
    assert!(
        block.len() == 1 && matches!(block[0].outcome, Outcome::Failed { .. }),
        "{ladder:?}"
    );
}

/// On a sparse graph (4 edges per node: fewer than `BLOCK_SPARSE_EDGES_PER_NODE`) the block
/// comparison's first subgraph, which fails on such graphs (the previous test's at 10^4
/// cameras; here as well, where the block comparison alone needs its denser subgraphs), has a
/// chance of 1/4: the grounded bound, predicted below four times its time, runs first and
/// certifies, and no subgraph is factorised (without the rule: one fails first, checked).
#[test]
fn sparse_graphs_go_to_the_grounded_bound_first() {
    let ladder = grounded_ladder(1000, 4000);
    let attempted = ladder.iter().any(|a| {
        a.rung == Proof::BlockComparison
            && matches!(a.outcome, Outcome::Failed { .. } | Outcome::Proved { .. })
    });
    assert!(!attempted, "{ladder:?}");
}

/// The ladder of the least-squares solution of a realistic two-view graph of `n` cameras and
/// `m` edges with the block comparison on at any size (`block_comparison_above` 0), asserted
/// certified by the grounded bound.
fn grounded_ladder(n: usize, m: usize) -> Vec<rotavg::certify::Attempt> {
    let (p, _) = SyntheticAnisotropic::two_view_like(n, m, 0.0).generate();
    let s = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let mut settings = CertifySettings::with_mode(CertifyMode::Dual);
    settings.dual.block_comparison_above = 0;
    let c = certify_multiple(&p, &s.rotations, &settings).unwrap();
    assert!(c.certificate.is_certified(), "{}", c.certificate);
    let ladder = c.details.ladder;
    let grounded = ladder
        .iter()
        .any(|a| a.rung == Proof::Grounded && matches!(a.outcome, Outcome::Proved { .. }));
    assert!(grounded, "{ladder:?}");
    ladder
}
