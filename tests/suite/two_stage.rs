//! Robust averaging of anisotropic measurements in two stages (`paper-notes/anisotropic.md`
//! `[A14]`): confidently wrong pairs (outliers whose information is 100x their correct
//! neighbours') must not lead the estimate. Judged against the planted rotations and an oracle
//! (the anisotropic least-squares solve on the planted inliers alone), with the one-stage IRLS
//! from the spectral start as the failure the test can see.

use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::anisotropic::Information;
use rotavg::multiple::synthetic::SyntheticAnisotropic;
use rotavg::multiple::{
    Initialisation, MultipleProblem, MultipleSettings, objective_cost_gradient, solve_multiple,
    spectral,
};
use rotavg::objective::{Loss, Objective};
use rotavg::so3::angle_between;
use rotavg::{Metric, Rotation};

const CAUCHY: Objective = Objective::new(Metric::Geodesic, Loss::Cauchy { scale_deg: 5.0 });

/// Two-view-like anisotropic information, 15 % outliers whose information is scaled by 100,
/// the planted rotations, and which edges are outliers (Mahalanobis angle at the truth over
/// 10 deg: the inliers' is about 0.5 deg, whatever their weak axis).
fn confident_outliers(n: usize) -> (MultipleProblem, Vec<Rotation>, Vec<bool>) {
    let spec = SyntheticAnisotropic {
        seed: 7,
        ..SyntheticAnisotropic::two_view_like(n, 4 * n, 0.15)
    };
    let (p, truth) = spec.generate();
    let outlier: Vec<bool> = p
        .objective_angles(&truth)
        .iter()
        .map(|t| t.to_degrees() > 10.0)
        .collect();
    let info = p.information().expect("anisotropic").iter().zip(&outlier);
    let info = info
        .map(|(h, &o)| Information::new(h.matrix() * if o { 100.0 } else { 1.0 }).expect("PSD"))
        .collect();
    let keep_all = vec![true; p.num_edges()];
    let p = p
        .edge_subset(&keep_all)
        .unwrap()
        .with_information(info)
        .unwrap();
    (p, truth, outlier)
}

fn median_error(estimate: &[Rotation], truth: &[Rotation]) -> f64 {
    let truth: Vec<Option<Rotation>> = truth.iter().copied().map(Some).collect();
    align_and_compare(estimate, &truth)
        .expect("aligned")
        .median_deg
}

#[test]
fn confident_wrong_pairs_do_not_lead_the_anisotropic_robust_solve() {
    let (p, truth, outlier) = confident_outliers(150);
    assert!(
        outlier.iter().filter(|o| **o).count() > 40,
        "the planted outliers"
    );
    // the oracle: anisotropic least squares on the planted inliers
    let inliers: Vec<bool> = outlier.iter().map(|o| !o).collect();
    let oracle = solve_multiple(&p.edge_subset(&inliers).unwrap(), &Default::default()).unwrap();
    let oracle_error = median_error(&oracle.rotations, &truth);
    let robust = p.clone().with_objective(CAUCHY).unwrap();
    let two_stage = solve_multiple(&robust, &MultipleSettings::default()).unwrap();
    let error = median_error(&two_stage.rotations, &truth);
    let kept = two_stage.residuals.as_ref().unwrap().inlier.clone();
    let wrong_kept = kept
        .iter()
        .zip(&outlier)
        .filter(|(k, o)| **k && **o)
        .count();
    let right_dropped = kept
        .iter()
        .zip(&outlier)
        .filter(|(k, o)| !**k && !**o)
        .count();
    assert_eq!(
        wrong_kept, 0,
        "no planted outlier is an inlier of the estimate"
    );
    assert!(
        right_dropped <= 3,
        "{right_dropped} planted inliers dropped"
    );
    assert!(
        error < 1.2 * oracle_error,
        "two stages {error} deg against the oracle's {oracle_error} deg"
    );
    assert!(
        two_stage.report.name.starts_with("two-stage"),
        "{}",
        two_stage.report
    );
    // what the test sees without the first stage: IRLS on every edge from the spectral start
    // (101 deg when written)
    let start = Initialisation::Given(spectral(&robust).unwrap());
    let one = MultipleSettings {
        init: start,
        ..Default::default()
    };
    let one_stage = solve_multiple(&robust, &one).unwrap();
    let one_error = median_error(&one_stage.rotations, &truth);
    assert!(
        one_error > 3.0 * error,
        "one stage {one_error} deg, two {error} deg"
    );
}

#[test]
fn the_two_stage_estimate_states_the_problems_cost_on_every_edge() {
    let (p, _, _) = confident_outliers(60);
    let robust = p.with_objective(CAUCHY).unwrap();
    let s = solve_multiple(&robust, &MultipleSettings::default()).unwrap();
    crate::common::assert_in_so3(&s.rotations, "two-stage estimate");
    let (cost, _) = objective_cost_gradient(&robust, &s.rotations, 1e-6);
    assert!(
        (s.cost - cost).abs() <= 1e-12 * cost,
        "{} against {cost}",
        s.cost
    );
    assert!((s.chordal_cost - robust.chordal_cost(&s.rotations)).abs() <= 1e-12 * s.chordal_cost);
    let residuals = s.residuals.expect("robust residuals");
    assert_eq!(residuals.inlier.len(), robust.num_edges());
}

#[test]
fn scaling_all_information_leaves_the_two_stage_estimate() {
    let (p, _, _) = confident_outliers(60);
    let scaled = p.information().unwrap().iter();
    let scaled = scaled
        .map(|h| Information::new(h.matrix() * 1e6).unwrap())
        .collect();
    let keep_all = vec![true; p.num_edges()];
    let q = p
        .edge_subset(&keep_all)
        .unwrap()
        .with_information(scaled)
        .unwrap();
    let a = solve_multiple(&p.with_objective(CAUCHY).unwrap(), &Default::default()).unwrap();
    let b = solve_multiple(&q.with_objective(CAUCHY).unwrap(), &Default::default()).unwrap();
    let worst = a
        .rotations
        .iter()
        .zip(&b.rotations)
        .map(|(x, y)| angle_between(x, y))
        .fold(0.0, f64::max);
    assert!(worst < 1e-7, "estimates differ by {worst} rad");
    assert_eq!(a.residuals.unwrap().inlier, b.residuals.unwrap().inlier);
}

/// The rule `auto` judges the least-squares estimate at the first of `JUDGE_AT_ITERATIONS`
/// (5 Newton iterations) when the solve has not converged by then and its residuals already show
/// outliers (`[D17]`): confident wrong pairs make least squares slow, and its estimate is then
/// discarded for the robust one. The robust run is the same as without the early judgement.
/// The graph: a generated 100-image scene with correspondences (`[F16]`) read with
/// `--information full` (least squares: 52 Newton iterations, seed 2; seed 1 took 35 when
/// written).
#[test]
fn auto_judges_a_slow_least_squares_solve_early() {
    use rotavg::io::colmap::read_colmap_database;
    use rotavg::io::colmap::scene::SfmScene;
    use rotavg::io::detect::ReadOptions;
    use rotavg::pipeline::loss_choice::{JUDGE_AFTER_ITERATIONS, JUDGE_AT_ITERATIONS};
    use rotavg::pipeline::{AverageSettings, average_multiple};
    let dir =
        crate::common::scratch_root().join(format!("rotavg-two-stage-{}", std::process::id()));
    // the cost at 30 iterations 8.6 % above the converged one (seed 1 took 31 with the starts
    // of [A17], converged in cost by 30)
    let scene = SfmScene {
        cameras: 100,
        seed: 2,
        ..SfmScene::default()
    };
    scene.generate().unwrap().write(&dir).unwrap();
    let options = ReadOptions {
        full_information: Some(true),
        ..Default::default()
    };
    let p = read_colmap_database(&dir.join("database.db"), &options)
        .unwrap()
        .problem;
    std::fs::remove_dir_all(&dir).ok();
    let full = solve_multiple(&p, &MultipleSettings::default()).unwrap();
    assert!(
        full.report.iterations > JUDGE_AFTER_ITERATIONS,
        "{}",
        full.report
    );
    let auto = AverageSettings {
        solve: MultipleSettings {
            robust_on_outliers: Some(CAUCHY),
            ..Default::default()
        },
        ..Default::default()
    };
    let out = average_multiple(&p, &auto).unwrap();
    let choice = out.details.loss_choice.expect("the rule ran");
    assert!(choice.is_robust(), "{choice}");
    // the robust loss at the scale the rule chose ([D20]), solved on its own with the rule's
    // inlier threshold (the edges [A14]'s first stage sets aside): the same estimate to
    // rounding (the rule hands its L1 start over instead of solving it again)
    let robust = solve_multiple(
        &p.clone().with_objective(choice.chosen).unwrap(),
        &MultipleSettings {
            inlier_threshold_deg: choice.scale.as_ref().map(|s| s.inlier_threshold_deg),
            ..Default::default()
        },
    );
    let worst = (out
        .solution
        .rotations
        .iter()
        .zip(&robust.unwrap().rotations))
    .map(|(a, b)| rotavg::so3::angle_between(a, b))
    .fold(0.0, f64::max);
    assert!(worst < 1e-9, "{worst:e} rad");
    // judged early: the estimate judged is not the converged one (no timed assertion: the
    // machine's load would decide it)
    // at the first checkpoint: the cost of least squares stopped there, solved apart
    let first = solve_multiple(
        &p,
        &MultipleSettings {
            max_iterations: JUDGE_AT_ITERATIONS[0],
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(first.report.iterations, JUDGE_AT_ITERATIONS[0]);
    assert!(
        (choice.least_squares_cost - first.cost).abs() <= 1e-12 * first.cost,
        "judged at cost {}, {} iterations give {}",
        choice.least_squares_cost,
        JUDGE_AT_ITERATIONS[0],
        first.cost
    );
    assert!(
        choice.least_squares_cost > full.cost,
        "judged at {} (the converged cost {})",
        choice.least_squares_cost,
        full.cost
    );
}

/// `[A14]` with gravity priors (`[G8]`): the reweighted constrained solve keeps the edges the
/// unconstrained two-stage estimate kept; the confidently wrong pairs it set aside no longer
/// lead through their Cauchy weight times `tr(H) / 3` (a generated 1000-image scene with exact
/// priors: 6.72 deg median error held and 8.78 soft before, 0.58 and 0.70 after). Judged
/// against the planted rotations and an oracle: the same priors on the planted inliers alone,
/// by least squares. Exact priors, held and soft.
#[test]
fn confident_wrong_pairs_do_not_lead_the_robust_solve_with_gravity() {
    use rotavg::multiple::gravity::{GravityPriors, GravityProblem, solve_gravity};
    let (p, truth, outlier) = confident_outliers(150);
    let down = nalgebra::Vector3::z();
    let directions: Vec<Option<[f64; 3]>> = truth.iter().map(|r| Some((r * down).into())).collect();
    let median_weight = {
        let mut w: Vec<f64> = (p.information().unwrap().iter())
            .map(|h| h.matrix().trace() / 3.0)
            .collect();
        w.sort_by(f64::total_cmp);
        w[w.len() / 2]
    };
    let inliers: Vec<bool> = outlier.iter().map(|o| !o).collect();
    for soft in [false, true] {
        let mut priors = GravityPriors::new(directions.clone()).unwrap();
        if soft {
            priors = priors.with_weight(median_weight).unwrap();
        }
        let gravity = |q: MultipleProblem| GravityProblem::new(q, priors.clone()).unwrap();
        let oracle = gravity(p.edge_subset(&inliers).unwrap());
        let oracle = solve_gravity(&oracle, &Default::default()).unwrap();
        let oracle_error = median_error(&oracle.rotations, &truth);
        let robust = gravity(p.clone().with_objective(CAUCHY).unwrap());
        let s = solve_gravity(&robust, &Default::default()).unwrap();
        let error = median_error(&s.rotations, &truth);
        assert!(
            error < 1.2 * oracle_error,
            "soft {soft}: {error} deg against the oracle's {oracle_error} deg ({})",
            s.report
        );
        crate::common::assert_in_so3(&s.rotations, "robust estimate with gravity");
    }
}
