//! The JSON readers: the first byte's bits 3-5 select `read_problem_json` (multiple
//! averaging), `read_estimate`, `read_rotations_estimate`, `read_conjugate_json`,
//! `parse_single_json` or `parse_single_estimate`; its low bits the reader options.
//!
//! Beyond "no panic", accepted inputs are checked: problems go through `common::check_graph`
//! and must survive a write/read round trip (JSON, and g2o with identity vertices) with the
//! same nodes, edges, rotations and weights; single problems go through the closed-form
//! chordal and quaternion L2 means; conjugate problems through diagnosis and the quaternion
//! closed form.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rotavg::Rotation;
use rotavg::conjugate::{DiagnosticSettings, quaternion_closed_form};
use rotavg::io::detect::{LoadedGraph, ReadOptions};
use rotavg::io::g2o::{read_g2o, write_g2o};
use rotavg::io::handeye::read_conjugate_json;
use rotavg::io::json::{
    Estimate, read_estimate, read_problem_json, read_rotations_estimate, write_estimate_json,
    write_problem_json,
};
use rotavg::io::single_json::{parse_single_estimate, parse_single_json, to_single_json};
use rotavg::single::{chordal_l2_mean, quaternion_l2_mean};
use rotavg::so3::angle_between;

mod common;

/// Samples above which the single-averaging means are skipped (execution time).
const MAX_SAMPLES: usize = 200;

fn same_problem(a: &LoadedGraph, b: &LoadedGraph, what: &str) {
    let (p, q) = (&a.problem, &b.problem);
    assert_eq!(p.num_rotations(), q.num_rotations(), "{what}: nodes");
    assert_eq!(p.num_edges(), q.num_edges(), "{what}: edges");
    for (e, f) in p.edges().iter().zip(q.edges()) {
        assert_eq!((e.i, e.j), (f.i, f.j), "{what}: endpoints");
        assert!(
            angle_between(&e.rotation, &f.rotation) < 1e-9,
            "{what}: rotation {} vs {}",
            e.rotation,
            f.rotation
        );
        assert!(
            (e.weight - f.weight).abs() <= 1e-9 * e.weight,
            "{what}: weight {} vs {}",
            e.weight,
            f.weight
        );
    }
}

fn problem(text: &str, options: &ReadOptions) {
    let Ok(g) = read_problem_json(text, "problem.json", options) else {
        return;
    };
    common::check_graph(&g);
    if g.problem.num_edges() > common::DOWNSTREAM_LIMIT {
        return;
    }
    let defaults = ReadOptions::default();
    let back = read_problem_json(
        &write_problem_json(&g.problem),
        "round-trip.json",
        &defaults,
    )
    .expect("JSON round trip");
    same_problem(&g, &back, "JSON round trip");
    // g2o stores 2w in the information matrix: stay clear of overflow and subnormals.
    let weights_ok = g
        .problem
        .edges()
        .iter()
        .all(|e| (1e-200..=1e200).contains(&e.weight));
    if weights_ok {
        let identity = vec![Rotation::identity(); g.problem.num_rotations()];
        let text = write_g2o(&g.problem, Some(&identity));
        let back = read_g2o(&text, "round-trip.g2o", &defaults).expect("g2o round trip");
        same_problem(&g, &back, "g2o round trip");
    }
}

fn estimate(text: &str, options: &ReadOptions, list_only: bool) {
    let rotations = if list_only {
        match read_rotations_estimate(text, "estimate.json", options) {
            Ok(rs) => rs,
            Err(_) => return,
        }
    } else {
        match read_estimate(text, "estimate.json", options) {
            Ok(Estimate::Multiple(rs)) => rs,
            Ok(Estimate::Single(r)) => vec![r],
            Err(_) => return,
        }
    };
    assert!(!rotations.is_empty());
    rotations.iter().for_each(common::assert_rotation);
    let back = read_rotations_estimate(
        &write_estimate_json(&rotations),
        "round-trip.json",
        &ReadOptions::default(),
    )
    .expect("estimate round trip");
    assert_eq!(back.len(), rotations.len());
    for (a, b) in rotations.iter().zip(&back) {
        assert!(angle_between(a, b) < 1e-12);
    }
}

fn conjugate(text: &str) {
    let Ok(p) = read_conjugate_json(text, "pairs.json") else {
        return;
    };
    for pair in p.pairs() {
        common::assert_rotation(&pair.left);
        common::assert_rotation(&pair.right);
        assert!(pair.weight.is_finite() && pair.weight > 0.0);
    }
    let settings = DiagnosticSettings::default();
    let _ = p.diagnose(&settings);
    if let Ok(sol) = quaternion_closed_form(&p, &settings) {
        common::assert_rotation(&sol.estimate);
    }
}

fn single(text: &str) {
    let Ok(p) = parse_single_json(text, "single.json") else {
        return;
    };
    p.rotations().iter().for_each(common::assert_rotation);
    let back = parse_single_json(&to_single_json(&p), "round-trip.json").expect("round trip");
    assert_eq!(back.len(), p.len());
    if p.len() <= MAX_SAMPLES {
        for solution in [chordal_l2_mean(&p), quaternion_l2_mean(&p)]
            .into_iter()
            .flatten()
        {
            common::assert_rotation(&solution.estimate);
            assert!(solution.cost >= 0.0, "cost {}", solution.cost);
        }
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((selector, text)) = common::split(data) else {
        return;
    };
    let options = common::options(selector);
    match (selector >> 3) & 7 {
        0 | 6 => problem(&text, &options),
        1 => estimate(&text, &options, false),
        2 => estimate(&text, &options, true),
        3 | 7 => conjugate(&text),
        4 => single(&text),
        _ => {
            if let Ok(r) = parse_single_estimate(&text, "estimate.json") {
                common::assert_rotation(&r);
            }
        }
    }
});
