//! The `conv(SO(3))` dual certificate at an estimate (`paper-notes/anisotropic.md` `[A11]`):
//! its support function against sampling and the Kabsch rotation, its offsets sound for any
//! multipliers (bounds never above a brute-force minimum), the reflection examples closed
//! without an SDP, agreement with the dense `conv(SO(3))` SDP on small graphs, and the pipeline
//! certifying graphs with one well-determined axis per edge where the `O(3)` relaxation fails.

use nalgebra::{Matrix3, Vector3};
use rand::{Rng, SeedableRng};
use rotavg::Rotation;

use crate::common::{anisotropic_graph as graph, best_of_random_starts};
use rotavg::certify::multiple::conv_dual::{
    ConvSearchStop, conv_dual_bound, project_to_cone, search_penalties, special_support, surrogate,
};
use rotavg::certify::{CertifyMode, CertifySettings, Verdict, certify_multiple};
use rotavg::certify::{Outcome, Point, Proof, Refusal};
use rotavg::multiple::synthetic::SyntheticAnisotropic;
use rotavg::multiple::{MultipleSettings, solve_multiple};
use rotavg::so3::{exp, random_rotation};

/// A random information with one strong axis (`ratio` in standard deviation) along a random
/// frame: its `M` is indefinite for `ratio > sqrt(2)`.
fn one_strong_axis(rng: &mut impl Rng, ratio: f64) -> Matrix3<f64> {
    let u = *random_rotation(rng).matrix();
    let h = u
        * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0 / ratio.powi(2), 1.0 / ratio.powi(2)))
        * u.transpose();
    (h + h.transpose()) * 0.5
}

/// `h(D) = max over SO(3) of <D, R>`: never below any sampled rotation's value (soundness), and
/// attained (to rounding) by the rotation of the special orthogonal Procrustes problem written
/// here independently (`U diag(1, 1, det(U V^T)) V^T`).
#[test]
fn special_support_bounds_every_rotation_and_is_attained() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    for case in 0..200 {
        let d = Matrix3::from_fn(|_, _| rng.random::<f64>() - 0.5) * 10f64.powi(case % 7 - 3);
        let h = special_support(&d);
        for _ in 0..200 {
            let r = random_rotation(&mut rng);
            assert!(d.dot(r.matrix()) <= h, "case {case}: a rotation above h");
        }
        let svd = d.svd(true, true);
        let (u, v_t) = (svd.u.unwrap(), svd.v_t.unwrap());
        let s = (u * v_t).determinant().signum();
        let kabsch = u * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, s)) * v_t;
        let attained = d.dot(&kabsch);
        assert!(
            h >= attained && h - attained <= 1e-12 * d.norm(),
            "case {case}: h {h} vs Procrustes {attained}"
        );
    }
    // exact cases: h(I) = 3, h(reflection) = 1 (not 3: a rotation cannot reach it)
    assert!((special_support(&Matrix3::identity()) - 3.0).abs() < 1e-12);
    let f = Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, -1.0));
    assert!((special_support(&f) - 1.0).abs() < 1e-12);
}

/// The projection onto `C = { tr(P) I - P PSD }`: in `C`, idempotent, and no farther from `P`
/// than random points of `C`.
#[test]
fn cone_projection_is_a_projection() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(12);
    let in_cone = |q: &Matrix3<f64>| {
        (Matrix3::identity() * q.trace() - q)
            .symmetric_eigenvalues()
            .min()
    };
    for _ in 0..300 {
        let a = Matrix3::from_fn(|_, _| rng.random::<f64>() - 0.5);
        let p = (a + a.transpose()) * 2.0;
        let q = project_to_cone(&p);
        assert!(in_cone(&q) >= -1e-12 * p.norm(), "{p} -> {q}");
        assert!((project_to_cone(&q) - q).norm() <= 1e-12 * (1.0 + q.norm()));
        for _ in 0..30 {
            let b = Matrix3::from_fn(|_, _| rng.random::<f64>() - 0.5);
            let c = project_to_cone(&((b + b.transpose()) * 3.0));
            assert!(
                (p - q).norm() <= (p - c).norm() + 1e-12,
                "a closer point of C"
            );
        }
    }
}

/// The offsets make the bound sound for *any* multipliers, in the cone or not: the surrogate's
/// `O(3)` bound minus the offsets never exceeds the best of 30 local solves, on tiny graphs
/// with one strong axis per edge and outliers.
#[test]
fn any_multipliers_give_a_sound_bound() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(13);
    let dual = CertifySettings::with_mode(CertifyMode::Dual);
    for case in 0..16 {
        let n = 3 + case % 3;
        let truth: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
        let mut edges = Vec::new();
        for i in 0..n {
            for j in (i + 1)..n {
                let r = if rng.random::<f64>() < 0.25 {
                    random_rotation(&mut rng)
                } else {
                    let e = Vector3::from_fn(|_, _| 0.4 * (rng.random::<f64>() - 0.5));
                    truth[j] * truth[i].inverse() * exp(&e)
                };
                let ratio = 3.0 + 10.0 * rng.random::<f64>();
                edges.push((i, j, r, one_strong_axis(&mut rng, ratio)));
            }
        }
        let p = graph(n, &edges);
        let best_point = best_of_random_starts(&p, 30, &mut rng);
        let best = p.chordal_cost(&best_point);
        // the estimate the multipliers are recovered at: a random point, and the best one
        let random_point: Vec<Rotation> = (0..n).map(|_| random_rotation(&mut rng)).collect();
        for (label, at) in [("random point", &random_point), ("best point", &best_point)] {
            for scale in [0.0, 0.3, 3.0, 30.0] {
                let penalties: Vec<Matrix3<f64>> = (0..p.num_edges())
                    .map(|_| {
                        let a = Matrix3::from_fn(|_, _| rng.random::<f64>() - 0.5);
                        (a + a.transpose()) * scale
                    })
                    .collect();
                let s = surrogate(&p, at, &penalties).unwrap();
                let c = certify_multiple(&s.problem, at, &dual).unwrap();
                let bound = c.certificate.lower_bound.unwrap() - s.offset;
                assert!(
                    bound <= best + 1e-9 * best.abs().max(1.0),
                    "case {case}, {label}, scale {scale}: bound {bound} above the best {best}"
                );
            }
        }
        let b = conv_dual_bound(
            &p,
            &best_point,
            &CertifySettings::default(),
            Point::ConvDual,
            None,
        )
        .unwrap();
        assert!(
            b.lower_bound <= best + 1e-9 * best.abs().max(1.0),
            "case {case}: {b:?}"
        );
    }
}

/// `[A5]` examples closed without an SDP: two nodes with `H = diag(1, 1, 4)` (the `O(3)` bound
/// is -8, the rotation minimum 0) and the 3-cycle with every `M` definite whose `O(3)` optimum
/// is 0.8 and rotation minimum 6 (nearly: the search converges slowly there).
#[test]
fn conv_dual_closes_the_reflection_examples() {
    let d = |x: f64, y: f64, z: f64| Matrix3::from_diagonal(&Vector3::new(x, y, z));
    let two = graph(2, &[(0, 1, Rotation::identity(), d(1.0, 1.0, 4.0))]);
    let at = [Rotation::identity(); 2];
    let o3 = certify_multiple(&two, &at, &CertifySettings::with_mode(CertifyMode::Dual)).unwrap();
    let c = certify_multiple(&two, &at, &CertifySettings::default()).unwrap();
    assert_eq!(
        c.certificate.verdict,
        Verdict::Certified,
        "{}",
        c.certificate.explanation
    );
    assert_eq!(c.certificate.bound_from, Some(Point::ConvDual));
    let lb = c.certificate.lower_bound.unwrap();
    assert!(lb <= 1e-12 && lb > -1e-9, "{lb}");
    assert!(o3.details.ladder.iter().any(|a| a.rung == Proof::ConvDual));
    let rx = exp(&Vector3::new(std::f64::consts::PI, 0.0, 0.0));
    let cycle = graph(
        3,
        &[
            (0, 1, Rotation::identity(), d(1.0, 1.0, 1.9)),
            (1, 2, Rotation::identity(), d(1.0, 1.9, 1.0)),
            (2, 0, rx, Matrix3::identity()),
        ],
    );
    let mut rng = rand::rngs::StdRng::seed_from_u64(14);
    let best = best_of_random_starts(&cycle, 20, &mut rng);
    assert!((cycle.chordal_cost(&best) - 6.0).abs() < 1e-6);
    let b = conv_dual_bound(
        &cycle,
        &best,
        &CertifySettings::default(),
        Point::ConvDual,
        None,
    )
    .unwrap();
    // the cutting planes approach this degenerate optimum slowly (5.9992 after 300 rounds):
    // nearly closed, never above; mode auto then certifies it by the dense SDP [A6]
    assert!(
        b.lower_bound <= 6.0 + 1e-9 && b.lower_bound > 6.0 - 1e-2,
        "{} after {} rounds ({})",
        b.lower_bound,
        b.search.rounds,
        b.search.stop
    );
    let c = certify_multiple(&cycle, &best, &CertifySettings::default()).unwrap();
    let cert = &c.certificate;
    assert_eq!(cert.verdict, Verdict::Certified, "{}", cert.explanation);
}

/// On graphs of 8-12 nodes with one strong axis per edge (standard deviations 0.5, 10 and 10
/// degrees), the bound recovered at the local solution never exceeds the dense `conv(SO(3))`
/// SDP's objective (Clarabel, independent of the search), and certifies whenever that SDP
/// closes the gap.
#[test]
fn conv_dual_agrees_with_the_conv_sdp() {
    let (mut closed, mut certified) = (0, 0);
    for seed in 0..6 {
        let small = SmallGraph::bounded(seed, 0.0);
        let (cost, sdp, b) = (small.cost, small.sdp, &small.bound);
        if cost - sdp <= 1e-4 * cost {
            closed += 1;
            if cost - b.lower_bound <= 1e-6 * cost {
                certified += 1;
            }
        }
        eprintln!(
            "seed {seed}: cost {cost:.6}, conv SDP {sdp:.6}, conv dual {:.6} ({} rounds, {})",
            b.lower_bound, b.search.rounds, b.search.stop
        );
    }
    assert!(closed >= 4, "the SDP closed {closed} of 6");
    assert_eq!(
        certified, closed,
        "conv dual certified {certified} of the {closed} closed"
    );
}

/// Where the relaxation is not tight (8-12 nodes, two weak axes at ratio 20, 20 % outlier
/// edges), the bound with the nodes' shifts (`[A11]` "Node shifts") never exceeds the dense
/// `conv(SO(3))` SDP's objective (Clarabel, independent of the search and the bundle), which
/// bounds every dual bound of that relaxation; and the shifts run and raise the bound on most of
/// these graphs (8 of 8 on 2026-12-05).
#[test]
fn node_shifts_stay_below_the_conv_sdp() {
    let mut raised = 0;
    for seed in 0..8 {
        let small = SmallGraph::bounded(seed, 0.2);
        raised += usize::from(small.bound.node_shifts.is_some());
        eprintln!(
            "seed {seed}: cost {:.6}, conv SDP {:.6}, bound {:.6}, shifts {:?}",
            small.cost, small.sdp, small.bound.lower_bound, small.bound.node_shifts
        );
    }
    assert!(raised >= 6, "the shifts raised {raised} of 8 bounds");
}

/// A graph of 8-12 nodes with two weak axes at ratio 20 (standard deviations 0.5, 10 and 10
/// degrees) and `outliers` of its edges wrong: the local solution's cost, the dense
/// `conv(SO(3))` SDP's objective (Clarabel) and the `conv(SO(3))` dual bound there, checked
/// never above that objective.
struct SmallGraph {
    cost: f64,
    sdp: f64,
    bound: rotavg::certify::multiple::conv_dual::ConvDualBound,
}

impl SmallGraph {
    fn bounded(seed: u64, outliers: f64) -> Self {
        use rotavg::relax::SdpSettings;
        use rotavg::relax::conv_so3::relax_multiple_conv;
        let n = 8 + 2 * (seed as usize % 3);
        let (p, _) = SyntheticAnisotropic {
            num_rotations: n,
            num_edges: 4 * n,
            ratio: 20.0,
            weak_axes: 2,
            outlier_fraction: outliers,
            seed,
            ..Default::default()
        }
        .generate();
        let est = solve_multiple(&p, &MultipleSettings::default()).unwrap();
        let cost = est.chordal_cost;
        let sdp = relax_multiple_conv(&p, &SdpSettings::default())
            .unwrap()
            .primal_objective;
        let settings = CertifySettings::default();
        let bound = conv_dual_bound(&p, &est.rotations, &settings, Point::ConvDual, None).unwrap();
        assert!(
            bound.lower_bound <= sdp + 1e-5 * cost,
            "seed {seed}: {} above the SDP's value {sdp}",
            bound.lower_bound
        );
        SmallGraph { cost, sdp, bound }
    }
}

/// The pipeline's certificate at scale: 300 nodes, one strong axis per edge (ratio 10): the
/// `O(3)` relaxation prefers reflections (its dual bound is far below), the `conv(SO(3))` dual
/// certificate certifies the estimate, below the planted truth's cost.
#[test]
fn one_strong_axis_graphs_are_certified_at_scale() {
    let (p, truth) = SyntheticAnisotropic {
        num_rotations: 300,
        num_edges: 1200,
        ratio: 10.0,
        weak_axes: 2,
        seed: 3,
        ..Default::default()
    }
    .generate();
    let est = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let c = certify_multiple(&p, &est.rotations, &CertifySettings::default()).unwrap();
    let cert = &c.certificate;
    assert_eq!(cert.verdict, Verdict::Certified, "{}", cert.explanation);
    assert_eq!(cert.bound_from, Some(Point::ConvDual));
    assert!(cert.lower_bound.unwrap() <= p.chordal_cost(&truth));
    let o3 = certify_multiple(
        &p,
        &est.rotations,
        &CertifySettings {
            dual: rotavg::certify::DualSettings {
                conv: rotavg::certify::ConvDualSettings {
                    enabled: false,
                    ..Default::default()
                },
                ..Default::default()
            },
            ..CertifySettings::with_mode(CertifyMode::Dual)
        },
    )
    .unwrap();
    assert_ne!(o3.certificate.verdict, Verdict::Certified);
    assert!(o3.certificate.lower_bound.unwrap() < 0.0);
}

/// The search's memory is predicted and refused over the budget, with the reason on the ladder.
#[test]
fn the_search_is_refused_over_the_memory_budget() {
    let (p, _) = SyntheticAnisotropic {
        num_rotations: 50,
        num_edges: 200,
        ratio: 10.0,
        weak_axes: 2,
        seed: 4,
        ..Default::default()
    }
    .generate();
    let est = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let mut settings = CertifySettings::default();
    settings.dual.conv.cuts_kept = 10_000_000;
    // the dual rungs alone: the staircase that follows in `auto` (13 s) is not what is tested
    settings.mode = CertifyMode::Dual;
    let c = certify_multiple(&p, &est.rotations, &settings).unwrap();
    let refused = c
        .details
        .ladder
        .iter()
        .find(|a| a.rung == Proof::ConvDual)
        .unwrap();
    match &refused.outcome {
        Outcome::Refused(Refusal::OverBudget { reason }) => {
            assert!(reason.contains("GB"), "{reason}")
        }
        o => panic!("{o:?}"),
    }
}

/// The shift-invert factor of the search counts against the memory budget: with 4 GiB it is
/// used, with a budget that only fits the search's own vectors the rounds run Lanczos on `S'`
/// itself (and still certify this graph, whose initial prices suffice).
#[test]
fn the_search_factor_fits_the_memory_budget() {
    use rotavg::certify::Budget;
    use rotavg::certify::ConvDualSettings;
    use rotavg::certify::multiple::conv_dual::{predict_search, search_penalties};
    let (p, _) = SyntheticAnisotropic {
        num_rotations: 100,
        num_edges: 400,
        ratio: 20.0,
        weak_axes: 2,
        seed: 5,
        ..Default::default()
    }
    .generate();
    let est = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let settings = ConvDualSettings::default();
    let roomy = Budget::default();
    let s = search_penalties(&p, &est.rotations, &settings, None, &roomy).unwrap();
    assert!(s.shift_invert);
    let tight = Budget {
        max_memory_bytes: predict_search(&p, &settings).bytes as u64 + 1000,
        max_seconds: None,
    };
    let s = search_penalties(&p, &est.rotations, &settings, None, &tight).unwrap();
    assert!(!s.shift_invert, "{s:?}");
}

/// More rounds of the multiplier search never return worse penalties by the search's own
/// estimate, and their verified bound follows: on issue 37's strongly anisotropic SLAM class
/// (every `M` indefinite, the search far from a certificate) the verified bound is
/// non-decreasing in `max_rounds` (the deterministic stand-in for a larger time budget), and
/// the kept round is reported. Before, the last round's penalties were returned and a 20 s
/// budget ended weaker than a 10 s one (2000 poses: -2.130654e9 against -2.130546e9).
#[test]
fn more_search_rounds_never_weaken_the_conv_bound() {
    use rotavg::multiple::synthetic::SyntheticAnisotropicSlam;
    let slam = SyntheticAnisotropicSlam::strongly_anisotropic(1000, 1)
        .generate()
        .0;
    // two weak axes, std ratio 20: the search needs several rounds to certify (100 nodes)
    let two_weak = SyntheticAnisotropic {
        num_rotations: 100,
        num_edges: 400,
        weak_axes: 2,
        ratio: 20.0,
        ..Default::default()
    };
    for p in [slam, two_weak.generate().0] {
        let est = solve_multiple(&p, &MultipleSettings::default()).unwrap();
        let mut last = f64::NEG_INFINITY;
        for rounds in [1, 3, 9, 27] {
            let mut settings = CertifySettings::default();
            settings.dual.conv.max_rounds = rounds;
            settings.dual.conv.stall_rounds = usize::MAX;
            let b = conv_dual_bound(&p, &est.rotations, &settings, Point::ConvDual, None).unwrap();
            let s = &b.search;
            eprintln!(
                "{} nodes, {rounds} rounds: bound {:.6e} (cost {:.6e}), kept round {} of {}, \
                 estimated {:?}, stop {}",
                p.num_rotations(),
                b.lower_bound,
                est.chordal_cost,
                s.kept_round,
                s.rounds,
                s.estimated_bound,
                s.stop
            );
            assert!(s.kept_round <= s.rounds);
            assert!(
                b.lower_bound >= last,
                "{rounds} rounds: {} after {last}",
                b.lower_bound
            );
            last = b.lower_bound;
        }
    }
}

/// Strongly anisotropic SLAM information (issue 37 item 4; eigenvalue ratios 1e3-1e7, every
/// `M` indefinite): the default local solve converges (it stopped at its old limit of 100
/// iterations far from critical, stationarity residual 384, and no rung then found a useful
/// bound) and the pipeline's verified bound is below the cost of every local solve from
/// perturbed truths (independent feasible points), which in turn are no cheaper than the
/// default solve by more than `1e-6`; and it certifies (until the offsets were bounded in
/// the estimate's frame, `[A11]`, their rounding bounds alone left a gap of `5.2e-5` of the
/// cost, 50 times the tolerance: `gap_reported`).
#[test]
fn strongly_anisotropic_slam_converges_and_gets_a_useful_bound() {
    use rotavg::multiple::synthetic::SyntheticAnisotropicSlam;
    use rotavg::pipeline::{AverageSettings, average_multiple};
    let (p, truth) = SyntheticAnisotropicSlam::strongly_anisotropic(200, 1).generate();
    let sol = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    assert!(sol.report.termination.is_converged(), "{}", sol.report);
    let rho = rotavg::certify::multiple::stationarity_residual(&p, &sol.rotations).unwrap();
    assert!(rho < 1e-3, "stationarity residual {rho}");
    let mut rng = rand::rngs::StdRng::seed_from_u64(8);
    let others: Vec<f64> = (0..4)
        .map(|_| {
            let init = truth
                .iter()
                .map(|r| r * exp(&(Vector3::from_fn(|_, _| rng.random_range(-0.05..0.05)))))
                .collect();
            let local = MultipleSettings {
                init: rotavg::multiple::Initialisation::Given(init),
                ..Default::default()
            };
            solve_multiple(&p, &local).unwrap().chordal_cost
        })
        .collect();
    let best_other = others.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(
        sol.chordal_cost <= best_other * (1.0 + 1e-6),
        "{others:?} vs {}",
        sol.chordal_cost
    );
    let out = average_multiple(&p, &AverageSettings::default()).unwrap();
    let c = out.certificate.unwrap();
    let lb = c.lower_bound.unwrap();
    eprintln!(
        "{}: bound {lb}, cost {}, others {others:?}",
        c.verdict, c.upper_bound
    );
    assert!(lb <= best_other && lb <= c.upper_bound);
    assert!(lb >= c.upper_bound * (1.0 - 1e-4), "{c}");
    assert_eq!(c.verdict, Verdict::Certified, "{c}");
}

/// Strongly anisotropic SLAM information, 1500 poses, seed 13: the multipliers' search at its
/// coarse resolution (Ritz values below `1e-9` of its scale, about 1e9 here, are cut) sees
/// none, yet its surrogate is not positive semidefinite (`gap_reported`, relative gap 1.5,
/// before the fine resolution); refined at `1e-13` it certifies. The bound is checked against
/// an independent feasible point: the local solve from a perturbed truth.
#[test]
fn the_fine_search_certifies_what_the_coarse_one_cannot_see() {
    use rotavg::multiple::synthetic::SyntheticAnisotropicSlam;
    let (p, truth) = SyntheticAnisotropicSlam::strongly_anisotropic(1500, 13).generate();
    let sol = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let settings = CertifySettings::default();
    let coarse = search_penalties(
        &p,
        &sol.rotations,
        &settings.dual.conv,
        None,
        &settings.budget,
    )
    .unwrap();
    assert!(
        matches!(coarse.stop, ConvSearchStop::NoNegativeRitzValue { .. }),
        "{:?}",
        coarse.stop
    );
    let b = conv_dual_bound(&p, &sol.rotations, &settings, Point::ConvDual, None).unwrap();
    assert!(b.search.refined, "{:?}", b.search.stop);
    let cost = p.chordal_cost(&sol.rotations);
    assert!(
        b.lower_bound >= cost * (1.0 - 1e-6),
        "{} vs {cost}",
        b.lower_bound
    );
    let other = perturbed_truth_solve(&p, &truth, 3);
    assert!(
        b.lower_bound <= other.chordal_cost,
        "{} vs {}",
        b.lower_bound,
        other.chordal_cost
    );
    let cert = certify_multiple(&p, &sol.rotations, &settings).unwrap();
    assert_eq!(
        cert.certificate.verdict,
        Verdict::Certified,
        "{}",
        cert.certificate.explanation
    );
}

/// Strongly anisotropic SLAM information, 1500 poses, seed 18: the local solve converges by
/// its decrease test with a stationarity residual of 0.96 (information up to 1e9), too far
/// from critical for the surrogate's grounded bound; the `O(3)` matrix is indefinite there as
/// at any point of such data, which used to count as hopeless for the refinement. Now the
/// refinement runs and is adopted for being ten times more critical at a cost within half the
/// tolerance (`gap_reported` with a relative gap of 2.9e7 before), and the bound stays below
/// the cost of a local solve from a perturbed truth.
#[test]
fn a_more_critical_refinement_is_adopted_on_reflective_data() {
    use rotavg::multiple::synthetic::SyntheticAnisotropicSlam;
    let (p, truth) = SyntheticAnisotropicSlam::strongly_anisotropic(1500, 18).generate();
    let sol = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let rho = rotavg::certify::multiple::stationarity_residual(&p, &sol.rotations).unwrap();
    assert!(rho > 0.1, "the case needs a non-critical estimate: {rho}");
    let cert = certify_multiple(&p, &sol.rotations, &CertifySettings::default()).unwrap();
    let c = cert.certificate;
    assert_eq!(c.verdict, Verdict::Certified, "{}", c.explanation);
    let lb = c.lower_bound.unwrap();
    let other = perturbed_truth_solve(&p, &truth, 5);
    assert!(lb <= other.chordal_cost, "{lb} vs {}", other.chordal_cost);
}

/// A local solve from the truth turned by up to 0.02 rad per axis (seeded): an independent
/// feasible point whose cost every verified bound must stay below.
fn perturbed_truth_solve(
    p: &rotavg::multiple::MultipleProblem,
    truth: &[Rotation],
    seed: u64,
) -> rotavg::multiple::MultipleSolution {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let init = truth
        .iter()
        .map(|r| r * exp(&(Vector3::from_fn(|_, _| rng.random_range(-0.02..0.02)))))
        .collect();
    let local = MultipleSettings {
        init: rotavg::multiple::Initialisation::Given(init),
        ..Default::default()
    };
    solve_multiple(p, &local).unwrap()
}

/// Two weak axes at ratio 20 (residual deviations 0.5, 10 and 10 degrees along a random frame
/// per edge), 200 nodes and 800 edges, seed 1: `anisotropic_table`'s row that ends
/// `gap_reported`. The `conv(SO(3))` relaxation is not tight at the estimate: with the nodes'
/// multipliers at the estimate's, the best edge multipliers leave `lambda_min(S')` near -13.5
/// (a proximal bundle over them converged there, `paper-notes/anisotropic.md` `[A11]` "Node
/// shifts"), and the search's bound was -15,920 against a cost of 3702 (relative gap 5.3).
/// With the nodes' multipliers shifted by the spectral bundle the bound is above half the
/// cost, and still below the cost of every feasible point at hand: the estimate, the truth and
/// a local solve from a perturbed truth.
#[test]
fn node_shifts_bound_a_relaxation_that_is_not_tight() {
    let (p, truth) = ratio_20_graph();
    let sol = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let settings = CertifySettings::default();
    let b = conv_dual_bound(&p, &sol.rotations, &settings, Point::ConvDual, None).unwrap();
    let shifts = b.node_shifts.expect("the bundle ran and raised the bound");
    assert!(
        shifts.rounds > 0 && shifts.estimated_gain > 0.0,
        "{shifts:?}"
    );
    let cost = p.chordal_cost(&sol.rotations);
    assert!(b.lower_bound > 0.5 * cost, "{} vs {cost}", b.lower_bound);
    let other = perturbed_truth_solve(&p, &truth, 7);
    let feasible = cost.min(p.chordal_cost(&truth)).min(other.chordal_cost);
    assert!(b.lower_bound <= feasible, "{} vs {feasible}", b.lower_bound);
}

/// The node shifts' bundle keeps within the memory budget: under 6 MiB (its own memory on 200
/// nodes is predicted at 3.3 MB, over half of that, and its factor would have what is left
/// beside the search's charge) it does not run and the bound is the search's, still below the
/// estimate's cost. Under 8 MiB it runs (the command line, `--max-memory 8M`: bound 2730).
#[test]
fn node_shifts_stay_within_the_memory_budget() {
    let (p, _) = ratio_20_graph();
    let sol = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let mut settings = CertifySettings::default();
    settings.budget.max_memory_bytes = 6 << 20;
    let b = conv_dual_bound(&p, &sol.rotations, &settings, Point::ConvDual, None).unwrap();
    assert!(b.node_shifts.is_none(), "{:?}", b.node_shifts);
    assert!(b.lower_bound <= p.chordal_cost(&sol.rotations));
}

/// `anisotropic_table`'s graph of two weak axes at ratio 20, 200 nodes and 800 edges, seed 1.
fn ratio_20_graph() -> (rotavg::multiple::MultipleProblem, Vec<Rotation>) {
    SyntheticAnisotropic {
        num_rotations: 200,
        num_edges: 800,
        sigma: 0.5f64.to_radians(),
        ratio: 20.0,
        random_axes: true,
        outlier_fraction: 0.0,
        seed: 1,
        weak_axes: 2,
        ratio_spread: 0.0,
    }
    .generate()
}

/// The search runs once at one point: on the 200-node graph at ratio 20 the refined estimate and
/// the staircase's polished rounding are the given estimate to `1e-6` in every edge's relative
/// rotation, and the `conv(SO(3))` rung says so instead of searching again (three searches of
/// about 5 s each gave the same bound before, 2026-12-05).
#[test]
fn the_search_runs_once_at_one_point() {
    let (p, _) = ratio_20_graph();
    let sol = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    let c = certify_multiple(&p, &sol.rotations, &CertifySettings::default()).unwrap();
    let conv: Vec<_> = (c.details.ladder.iter())
        .filter(|a| a.rung == Proof::ConvDual)
        .collect();
    let searched = (conv.iter())
        .filter(|a| matches!(a.outcome, Outcome::Proved { .. }))
        .count();
    let same = (conv.iter())
        .filter(|a| {
            matches!(&a.outcome, Outcome::Refused(Refusal::NotApplicable { reason })
                if reason.contains("the same point"))
        })
        .count();
    assert_eq!(searched, 1, "{conv:?}");
    assert!(same >= 1, "{conv:?}");
}
