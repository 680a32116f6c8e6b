//! Robust multiple averaging: per-edge residuals, inlier detection against planted outliers,
//! accuracy against the planted rotations, and the certificate of the chordal L2 problem on the
//! inlier graph (checked against an independent rebuild of that problem, a closed-form
//! non-global critical point that must not be certified, and weight scaling).

use rotavg::certify::{CertifiedProblemKind, CertifyMode, CertifySettings, certify_multiple};
use rotavg::multiple::accuracy::align_and_compare;
use rotavg::multiple::synthetic::{SyntheticGraph, z_cycle};
use rotavg::multiple::{Edge, Initialisation, MultipleProblem, MultipleSettings};
use rotavg::objective::{Loss, Objective};
use rotavg::pipeline::{AverageSettings, MultipleEstimate, average_multiple};
use rotavg::so3::{angle_between, exp};
use rotavg::{Metric, Rotation, Verdict};

use crate::common;
use common::{assert_success, json_of, run, scale_weights, temp_file};

const LOSSES: [Loss; 3] = [
    Loss::L1,
    Loss::Huber { threshold_deg: 5.0 },
    Loss::Cauchy { scale_deg: 5.0 },
];

fn with_loss(p: &MultipleProblem, loss: Loss) -> MultipleProblem {
    p.clone()
        .with_objective(Objective::new(Metric::Geodesic, loss))
        .expect("a geodesic robust loss")
}

fn solve(p: &MultipleProblem, mode: CertifyMode, init: Option<Vec<Rotation>>) -> MultipleEstimate {
    let settings = AverageSettings {
        solve: MultipleSettings {
            init: init.map_or(Initialisation::Spectral, Initialisation::Given),
            ..Default::default()
        },
        certify: CertifySettings::with_mode(mode),
    };
    average_multiple(p, &settings).expect("the pipeline runs")
}

/// A 1DSfM-like scene, smaller: 2 degrees RMS noise, 20 % uniformly random edges.
fn scene(n: usize, m: usize, seed: u64) -> (MultipleProblem, Vec<Rotation>, Vec<bool>) {
    SyntheticGraph {
        num_rotations: n,
        num_edges: m,
        noise_sigma: (2.0f64 / 3f64.sqrt()).to_radians(),
        outlier_fraction: 0.2,
        seed,
    }
    .generate_labelled()
}

/// The sub-problem of the edges flagged inlier, rebuilt here from the flags alone (all nodes).
fn inlier_problem(p: &MultipleProblem, inlier: &[bool]) -> MultipleProblem {
    let edges: Vec<Edge> = p
        .edges()
        .iter()
        .zip(inlier)
        .filter(|(_, i)| **i)
        .map(|(e, _)| e.clone())
        .collect();
    MultipleProblem::new(p.num_rotations(), edges).expect("some inliers")
}

#[test]
fn planted_outliers_are_found_and_the_inlier_graph_is_certified() {
    let (problem, truth, planted) = scene(100, 2500, 3);
    let some_truth: Vec<_> = truth.iter().copied().map(Some).collect();
    let num_planted = planted.iter().filter(|&&o| o).count();
    for loss in LOSSES {
        let p = with_loss(&problem, loss);
        let out = solve(&p, CertifyMode::Auto, None);
        let est = &out.solution.rotations;
        let r = out.solution.residuals.as_ref().expect("robust residuals");
        assert_eq!(r.summary.inlier_threshold_deg, 5.0, "{loss}");
        // residuals recomputed independently at the reported estimate; the documented rule
        for (k, e) in p.edges().iter().enumerate() {
            let theta = angle_between(&(e.rotation * est[e.i]), &est[e.j]).to_degrees();
            assert!((theta - r.residual_deg[k]).abs() < 1e-9, "{loss} edge {k}");
            assert_eq!(r.inlier[k], theta <= 5.0, "{loss} edge {k}");
            assert!(r.weight[k] > 0.0 && r.weight[k] <= 1.0);
            if r.inlier[k] && !matches!(loss, Loss::Cauchy { .. }) {
                assert_eq!(r.weight[k], 1.0, "{loss}: an inlier keeps its weight");
            }
        }
        let inliers = r.inlier.iter().filter(|&&i| i).count();
        assert_eq!(
            (r.summary.num_inliers, r.summary.num_outliers),
            (inliers, p.num_edges() - inliers)
        );
        // detection against the planted outliers
        let detected = p.num_edges() - inliers;
        let hits = (0..p.num_edges())
            .filter(|&k| planted[k] && !r.inlier[k])
            .count();
        let (precision, recall) = (
            hits as f64 / detected as f64,
            hits as f64 / num_planted as f64,
        );
        assert!(
            recall >= 0.98 && precision >= 0.95,
            "{loss}: {precision} {recall}"
        );
        // accuracy with the robust alignment: robust estimate and the inlier refinement
        let a = align_and_compare(est, &some_truth).unwrap();
        assert!(a.robust.median_deg < 1.0, "{loss}: {}", a.robust.median_deg);
        let g = out.details.inlier_graph.as_ref().expect("auto certifies");
        let b = align_and_compare(&g.estimate, &some_truth).unwrap();
        assert!(b.robust.median_deg < 1.0, "{loss}: {}", b.robust.median_deg);
        // the robust cost itself is never certified
        assert!(out.certificate.is_none());
        let c = g.certificate.as_ref().expect("an inlier certificate");
        assert_eq!(c.verdict, Verdict::Certified, "{loss}: {c}");
        let cp = c.certified_problem.expect("says which problem");
        assert_eq!(cp.kind, CertifiedProblemKind::ChordalL2Inliers);
        assert_eq!((cp.total_edges, cp.total_nodes), (2500, 100));
        // the inlier graph rebuilt from the flags: same edges, same cost at the estimate, and
        // an independent certificate of the reported estimate on it
        let q = inlier_problem(&p, &r.inlier);
        assert_eq!(q.components().len(), 1, "{loss}: connected here");
        assert_eq!((cp.num_edges, cp.num_nodes), (q.num_edges(), 100));
        let f = q.chordal_cost(&g.estimate);
        assert!(
            (f - c.upper_bound).abs() <= 1e-9 * f,
            "{f} {}",
            c.upper_bound
        );
        let again = certify_multiple(&q, &g.estimate, &CertifySettings::default()).unwrap();
        assert!(again.certificate.is_certified());
        // a lower bound on the global minimum: not above any point's cost, e.g. the truth's
        let lb = c.lower_bound.unwrap();
        assert!(lb <= q.chordal_cost(&truth) && lb <= f);
        assert!(f <= q.chordal_cost(est) * (1.0 + 1e-12)); // the refinement does not get worse
    }
}

#[test]
fn noise_free_inliers_give_the_planted_rotations_and_exact_outliers() {
    let (problem, truth, planted) = SyntheticGraph {
        num_rotations: 40,
        num_edges: 400,
        noise_sigma: 0.0,
        outlier_fraction: 0.2,
        seed: 5,
    }
    .generate_labelled();
    let p = with_loss(&problem, Loss::Huber { threshold_deg: 5.0 });
    let out = solve(&p, CertifyMode::Auto, None);
    let r = out.solution.residuals.as_ref().unwrap();
    let outliers: Vec<bool> = r.inlier.iter().map(|i| !i).collect();
    assert_eq!(outliers, planted);
    let g = out.details.inlier_graph.as_ref().unwrap();
    // closed form: the planted rotations have cost 0 on the inlier graph; the estimate is them
    assert!(g.chordal_cost < 1e-16, "{}", g.chordal_cost);
    assert!(common::max_gauge_error(&g.estimate, &truth) < 1e-7);
    assert!(g.certificate.as_ref().unwrap().is_certified());
}

/// On a cycle of identities, the "winding" configuration `R_i = Rz(2 pi i / n)` is a
/// critical point of every loss (each edge has residual `2 pi / n`, by symmetry), and for
/// `n = 10` a local minimum of the chordal cost `10 x 8 sin^2(pi / 10)`, while the global
/// minimum is 0. Its inlier graph (all edges within 60 degrees) must not be certified by the
/// dual certificate; `auto` (SDP) finds the global minimum and certifies that instead.
#[test]
fn a_non_global_minimum_of_the_inlier_graph_is_never_certified() {
    let n = 10;
    let cycle = with_loss(
        &z_cycle(n, 0.0),
        Loss::Huber {
            threshold_deg: 60.0,
        },
    );
    let winding: Vec<Rotation> = (0..n)
        .map(|i| exp(&(nalgebra::Vector3::z() * (std::f64::consts::TAU * i as f64 / n as f64))))
        .collect();
    let local = 10.0 * 8.0 * (std::f64::consts::PI / 10.0).sin().powi(2);
    for c in [1.0, 1e-9, 1e9] {
        let p = with_loss(
            &scale_weights(&cycle, c),
            Loss::Huber {
                threshold_deg: 60.0,
            },
        );
        let out = solve(&p, CertifyMode::Dual, Some(winding.clone()));
        let r = out.solution.residuals.as_ref().unwrap();
        assert!(r.inlier.iter().all(|&i| i) && (r.summary.median_deg - 36.0).abs() < 1e-6);
        let g = out.details.inlier_graph.as_ref().unwrap();
        assert!(
            (g.chordal_cost - c * local).abs() < 1e-6 * c * local,
            "{}",
            g.chordal_cost
        );
        let cert = g.certificate.as_ref().unwrap();
        assert_ne!(cert.verdict, Verdict::Certified, "scale {c}: {cert}");
        if let Some(lb) = cert.lower_bound {
            assert!(lb <= 1e-9 * c, "a bound above the global minimum 0: {lb}");
        }
        let out = solve(&p, CertifyMode::Auto, Some(winding.clone()));
        let g = out.details.inlier_graph.as_ref().unwrap();
        let cert = g.certificate.as_ref().unwrap();
        assert!(
            cert.is_certified() && g.chordal_cost < 1e-9 * c,
            "scale {c}: {cert}"
        );
    }
}

#[test]
fn a_disconnected_inlier_graph_certifies_its_largest_component() {
    // 30 nodes with noise-free edges, plus node 30 measured twice, 90 degrees apart: the
    // Huber estimate puts it half way (45 degrees from each), so it has no inlier edge.
    let (core, truth) = SyntheticGraph {
        num_rotations: 30,
        num_edges: 120,
        noise_sigma: 0.0,
        ..Default::default()
    }
    .generate();
    let r30 = exp(&nalgebra::Vector3::new(0.3, -0.4, 0.2));
    let mut edges = core.edges().to_vec();
    let turn = exp(&nalgebra::Vector3::new(
        0.0,
        0.0,
        std::f64::consts::FRAC_PI_2,
    ));
    edges.push(Edge {
        i: 0,
        j: 30,
        rotation: r30 * truth[0].inverse(),
        weight: 1.0,
    });
    edges.push(Edge {
        i: 1,
        j: 30,
        rotation: turn * r30 * truth[1].inverse(),
        weight: 1.0,
    });
    let p = with_loss(
        &MultipleProblem::new(31, edges).unwrap(),
        Loss::Huber { threshold_deg: 5.0 },
    );
    let out = solve(&p, CertifyMode::Auto, None);
    let r = out.solution.residuals.as_ref().unwrap();
    assert_eq!(r.summary.num_outliers, 2, "{:?}", &r.residual_deg[120..]);
    let g = out.details.inlier_graph.as_ref().unwrap();
    assert_eq!((g.problem.num_nodes, g.problem.total_nodes), (30, 31));
    assert_eq!((g.problem.num_edges, g.isolated_nodes), (120, 1));
    assert_eq!(g.nodes, (0..30).collect::<Vec<_>>());
    // node 30 keeps its robust rotation; the others are the planted ones
    assert!(angle_between(&g.estimate[30], &out.solution.rotations[30]) < 1e-12);
    assert!(common::max_gauge_error(&g.estimate[..30], &truth) < 1e-7);
    assert!(g.certificate.as_ref().unwrap().is_certified());
    assert!(g.to_string().contains("its largest component"));
}

#[test]
fn scaling_all_weights_changes_neither_the_inliers_nor_the_verdict() {
    let (problem, _, _) = scene(60, 900, 7);
    let p = with_loss(&problem, Loss::Cauchy { scale_deg: 5.0 });
    let base = solve(&p, CertifyMode::Auto, None);
    let flags = &base.solution.residuals.as_ref().unwrap().inlier;
    let verdict = base
        .details
        .inlier_graph
        .as_ref()
        .unwrap()
        .certificate
        .as_ref()
        .unwrap()
        .verdict;
    assert_eq!(verdict, Verdict::Certified);
    for c in [1e-10, 1e10] {
        let q = with_loss(&scale_weights(&problem, c), Loss::Cauchy { scale_deg: 5.0 });
        let out = solve(&q, CertifyMode::Auto, None);
        assert_eq!(
            &out.solution.residuals.as_ref().unwrap().inlier,
            flags,
            "scale {c}"
        );
        let g = out.details.inlier_graph.as_ref().unwrap();
        assert_eq!(
            g.certificate.as_ref().unwrap().verdict,
            verdict,
            "scale {c}"
        );
    }
}

#[test]
fn command_line_writes_the_edges_and_the_inlier_estimate() {
    // a 1DSfM file (ids 10, 20, ...): 12 cameras, noise-free edges and 3 contradicting ones
    let (core, truth) = SyntheticGraph {
        num_rotations: 12,
        num_edges: 50,
        noise_sigma: 0.0,
        ..Default::default()
    }
    .generate();
    let mut text = String::new();
    let line = |i: usize, j: usize, rij: &Rotation| {
        // EGs.txt holds R_i R_j^T = R_ij^T
        let m = rij.matrix().transpose();
        let v: Vec<String> = m.transpose().iter().map(|x| format!("{x:.17}")).collect();
        format!("{} {} {}\n", 10 * (i + 1), 10 * (j + 1), v.join(" "))
    };
    for e in core.edges() {
        text.push_str(&line(e.i, e.j, &e.rotation));
    }
    let bad = exp(&nalgebra::Vector3::new(1.0, 0.5, -0.7));
    for (i, j) in [(0, 5), (2, 9), (3, 11)] {
        text.push_str(&line(i, j, &(bad * truth[j] * truth[i].inverse())));
    }
    let dir = common::temp_dir();
    let egs = temp_file("robust_EGs.txt", &text);
    let csv = dir.join("robust_edges.csv");
    let json = dir.join("robust_edges.json");
    let inl = dir.join("robust_inliers.json");
    let egs = egs.to_str().unwrap();
    let out = run(&[
        "multiple",
        egs,
        "--loss",
        "l1",
        "--loss-threshold",
        "2",
        "--edges-output",
        csv.to_str().unwrap(),
        "--inlier-output",
        inl.to_str().unwrap(),
        "--json",
    ]);
    assert_success(&out);
    let v = json_of(&out);
    let rob = &v["robust"];
    assert_eq!(rob["reported_estimate"], "robust");
    assert_eq!(
        (rob["num_inliers"].as_u64(), rob["num_outliers"].as_u64()),
        (Some(50), Some(3))
    );
    assert_eq!(rob["inlier_threshold_deg"], 2.0);
    assert!(
        v["certificate"].is_null(),
        "the robust cost is not certified"
    );
    let c = &rob["inlier_graph"]["certificate"];
    assert_eq!(c["verdict"], "certified");
    assert_eq!(c["certified_problem"]["kind"], "chordal_l2_inliers");
    assert_eq!(c["certified_problem"]["num_edges"], 50);
    let rows: Vec<String> = std::fs::read_to_string(&csv)
        .unwrap()
        .lines()
        .map(String::from)
        .collect();
    assert_eq!(rows[0], "i,j,residual_deg,weight,inlier");
    assert_eq!(rows.len(), 54);
    for row in &rows[51..] {
        let f: Vec<&str> = row.split(',').collect();
        assert!(["10", "30", "40"].contains(&f[0]), "{row}");
        assert!(f[2].parse::<f64>().unwrap() > 2.0 && f[4] == "0", "{row}");
    }
    assert!(rows[1..51].iter().all(|r| r.ends_with(",1,1")));
    let est = std::fs::read_to_string(&inl).unwrap();
    let est: serde_json::Value = serde_json::from_str(&est).unwrap();
    assert_eq!(est["rotations"].as_array().unwrap().len(), 12);
    assert_eq!(est["node_ids"][11], 120);
    // JSON edges, and the text report
    let out = run(&[
        "multiple",
        egs,
        "--loss",
        "huber",
        "--loss-threshold",
        "2",
        "--edges-output",
        json.to_str().unwrap(),
    ]);
    assert_success(&out);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("globally optimal for the inlier graph (50 of 53 edges)"),
        "{text}"
    );
    assert!(
        text.contains("reported estimate: the robust (huber) one"),
        "{text}"
    );
    let e: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(e["edges"].as_array().unwrap().len(), 53);
    assert_eq!(e["edges"][0]["inlier"], true);
    // the flags need a robust loss; the inlier estimate needs the inlier graph
    let out = run(&[
        "multiple",
        egs,
        "--loss",
        "chordal",
        "--edges-output",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("needs a robust loss"));
    let out = run(&[
        "multiple",
        egs,
        "--loss",
        "l1",
        "--certify",
        "none",
        "--inlier-output",
        inl.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("--inlier-output"));
}

/// A 1DSfM-like scene with 20 % random edges: median error under 1 degree after the robust
/// alignment, for every robust loss and for the inlier refinement (the README's robust table
/// measures the 300-camera, 20,000-edge version).
#[test]
fn accuracy_on_a_1dsfm_like_scene() {
    let (problem, truth, _) = scene(150, 5000, 11);
    let truth: Vec<_> = truth.into_iter().map(Some).collect();
    for loss in LOSSES {
        let out = solve(&with_loss(&problem, loss), CertifyMode::Auto, None);
        let a = align_and_compare(&out.solution.rotations, &truth).unwrap();
        let g = out.details.inlier_graph.as_ref().unwrap();
        let b = align_and_compare(&g.estimate, &truth).unwrap();
        assert!(
            a.robust.median_deg < 1.0 && b.robust.median_deg < 1.0,
            "{loss}"
        );
        // the chordal L2 refinement on the inliers is at least as accurate as 2x the robust one
        assert!(b.robust.mean_deg <= 2.0 * a.robust.mean_deg, "{loss}");
    }
    // plain chordal L2 on all edges is pulled by the outliers
    let out = solve(&problem, CertifyMode::None, None);
    let a = align_and_compare(&out.solution.rotations, &truth).unwrap();
    assert!(a.robust.median_deg > 1.0, "{}", a.robust.median_deg);
}

/// Issue 27: a least-squares run on data with outliers says so (in the pipeline's details and, on
/// the command line, on stderr) and names the robust loss to run instead; clean data, at any
/// noise level up to 0.2 rad, raise no warning.
#[test]
fn least_squares_on_outlier_data_is_flagged() {
    for (noise, outliers, flagged) in [(0.01, 0.0, false), (0.2, 0.0, false), (0.02, 0.2, true)] {
        let (p, _) = SyntheticGraph {
            num_rotations: 120,
            num_edges: 480,
            noise_sigma: noise,
            outlier_fraction: outliers,
            seed: 27,
        }
        .generate();
        let out = average_multiple(&p, &AverageSettings::default()).unwrap();
        let w = out.details.outliers.clone();
        assert_eq!(
            w.is_some(),
            flagged,
            "noise {noise}, outliers {outliers}: {w:?}"
        );
        if let Some(w) = w {
            println!("{w}");
            // the flagged edges are (mostly) the planted outliers: about 96 of 480
            assert!(w.suspected >= 40 && w.suspected <= 140, "{w}");
            assert!(w.suggestion.contains("--loss cauchy"));
        }
    }
}

/// `[M9]`: without a given start, Huber and Cauchy start from the L1 solution of the same
/// problem: the estimate equals the solve given that L1 solution as its start (to the solvers'
/// convergence: the given start is gauge-fixed and projected first); Cauchy's is at least as
/// accurate against the planted rotations as its L1 start (Huber, not redescending, may not be:
/// printed only).
#[test]
fn robust_solves_start_from_the_l1_solution() {
    use rotavg::multiple::solve_multiple;
    let (p, truth, _) = scene(200, 1600, 4);
    let truth: Vec<Option<Rotation>> = truth.into_iter().map(Some).collect();
    let median = |rs: &[Rotation]| align_and_compare(rs, &truth).unwrap().median_deg;
    // the L1 start takes plain IRLS steps (`MultipleSettings::l1_overrelaxation` 1.0)
    let plain = MultipleSettings {
        l1_overrelaxation: 1.0,
        ..Default::default()
    };
    let l1 = solve_multiple(&with_loss(&p, Loss::L1), &plain).unwrap();
    for loss in [
        Loss::Huber { threshold_deg: 5.0 },
        Loss::Cauchy { scale_deg: 5.0 },
    ] {
        let robust = with_loss(&p, loss);
        let default = solve_multiple(&robust, &MultipleSettings::default()).unwrap();
        let given = MultipleSettings {
            init: Initialisation::Given(l1.rotations.clone()),
            ..Default::default()
        };
        let from_l1 = solve_multiple(&robust, &given).unwrap();
        let apart = default
            .rotations
            .iter()
            .zip(&from_l1.rotations)
            .map(|(a, b)| angle_between(a, b))
            .fold(0.0, f64::max);
        assert!(apart < 1e-6, "{loss:?}: {apart} rad apart");
        let (e_robust, e_l1) = (median(&default.rotations), median(&l1.rotations));
        eprintln!("{loss:?}: median error {e_robust:.4} deg, its L1 start {e_l1:.4} deg");
        if matches!(loss, Loss::Cauchy { .. }) {
            assert!(e_robust <= e_l1 * 1.05, "{loss:?}: {e_robust} vs L1 {e_l1}");
        }
    }
}
