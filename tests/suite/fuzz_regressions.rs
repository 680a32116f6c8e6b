//! Regression tests from fuzzing (`fuzz/README.md`): inputs the fuzz targets found, minimised,
//! as inline bytes, each with the outcome the fixed reader must give; and a check that every
//! committed seed in `fuzz/corpus-seeds/` is still accepted by the reader its selector byte
//! names (so the seeds keep starting the fuzzer from valid files).
//!
//! Fuzz inputs are one selector byte followed by the file text; `dispatch` mirrors the targets'
//! choice of reader from the selector (`fuzz/fuzz_targets/*.rs`) and the reader options
//! (`fuzz/fuzz_targets/common.rs`).

use rotavg::io::detect::{GraphFormat, ReadOptions, WeightSource, read_graph};
use rotavg::io::g2o::read_g2o;
use rotavg::io::handeye::{read_conjugate_json, read_eth_csv, read_tabb_camera, read_tabb_robot};
use rotavg::io::json::{read_estimate, read_problem_json, read_rotations_estimate};
use rotavg::io::sfm::{read_bundler, read_egs, read_rotation_list};
use rotavg::io::single_json::{parse_single_estimate, parse_single_json};
use std::path::Path;

/// `fuzz/fuzz_targets/common.rs::options`.
fn options(selector: u8) -> ReadOptions {
    let mut o = ReadOptions::default();
    if selector & 1 == 1 {
        o.weights = WeightSource::Unit;
    }
    match (selector >> 1) & 3 {
        0 => {}
        1 => {
            o.rotation_tolerance = 1e-2;
            o.quaternion_tolerance = 1e-1;
        }
        2 => {
            o.rotation_tolerance = 0.0;
            o.quaternion_tolerance = 0.0;
        }
        _ => {
            o.rotation_tolerance = 10.0;
            o.quaternion_tolerance = 0.9;
        }
    }
    o
}

/// Run the reader that fuzz target `target` picks for `data`; `Err` carries the reader's
/// message. Panics only if the reader panics (what the regression tests guard against).
fn dispatch(target: &str, data: &[u8]) -> Result<(), String> {
    let (&sel, rest) = data.split_first().ok_or("empty input")?;
    let text = String::from_utf8_lossy(rest);
    let o = options(sel);
    let tol = o.rotation_tolerance;
    let r: rotavg::Result<()> = match target {
        "g2o" => read_g2o(&text, "fuzz.g2o", &o).map(drop),
        "sfm_text" => match (sel >> 3) & 3 {
            0 | 3 => read_egs(&text, "EGs.txt", &o).map(drop),
            1 => read_bundler(&text, "gt_bundle.out", &o).map(drop),
            _ => read_rotation_list(&text, "gt.txt", &o).map(drop),
        },
        "handeye_text" => match (sel >> 3) & 3 {
            0 | 3 => read_tabb_robot(&text, "robot_cali.txt", tol).map(drop),
            1 => read_tabb_camera(&text, "cali.txt", tol).map(drop),
            _ => read_eth_csv(&text, "hand.csv", tol).map(drop),
        },
        "json" => match (sel >> 3) & 7 {
            0 | 6 => read_problem_json(&text, "problem.json", &o).map(drop),
            1 => read_estimate(&text, "estimate.json", &o).map(drop),
            2 => read_rotations_estimate(&text, "estimate.json", &o).map(drop),
            3 | 7 => read_conjugate_json(&text, "pairs.json").map(drop),
            4 => parse_single_json(&text, "single.json").map(drop),
            _ => parse_single_estimate(&text, "estimate.json").map(drop),
        },
        "detect" => {
            const NAMES: [&str; 8] = [
                "-",
                "EGs.txt",
                "graph.g2o",
                "problem.json",
                "x.JSON",
                "sphere.G2O",
                "data",
                ".json.txt",
            ];
            let forced = match sel >> 6 {
                0 | 1 => GraphFormat::Auto,
                2 => GraphFormat::G2o,
                _ => GraphFormat::OneDsfm,
            };
            read_graph(&text, NAMES[usize::from((sel >> 3) & 7)], forced, &o).map(drop)
        }
        other => panic!("unknown fuzz target {other}"),
    };
    r.map_err(|e| e.to_string())
}

#[test]
fn committed_seeds_are_accepted() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus-seeds");
    let mut count = 0;
    for target in ["g2o", "sfm_text", "handeye_text", "json", "detect"] {
        let dir = root.join(target);
        let mut entries: Vec<_> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .flatten()
            .map(|e| e.path())
            .collect();
        entries.sort();
        assert!(!entries.is_empty(), "no seeds for {target}");
        for path in entries {
            let data = std::fs::read(&path).expect("readable seed");
            if let Err(e) = dispatch(target, &data) {
                panic!("seed {} rejected: {e}", path.display());
            }
            count += 1;
        }
    }
    assert!(count >= 25, "only {count} seeds");
}

/// The reader's error message for a fuzz input (the input must be rejected, not panic).
fn rejected(target: &str, data: &[u8]) -> String {
    match dispatch(target, data) {
        Ok(()) => panic!("input accepted: {:?}", String::from_utf8_lossy(data)),
        Err(e) => e,
    }
}

/// Found by `handeye_text` (2026-11-22, after 6 min): with a very loose tolerance (selector
/// `w`: 10) `read_eth_csv` accepted the zero quaternion `(0, 0, 0, 0)` (|0 - 1| <= 10) and
/// normalised it into a NaN rotation. Now any quaternion of norm <= 1e-12 is rejected, as in
/// the g2o reader.
#[test]
fn eth_zero_quaternion_is_rejected_at_any_tolerance() {
    let input = b"w\n0, 0, 0, 0, 0, 0, 0,1\n0.1, 1, 0, 0, 0, 0, 00, 0\n";
    let e = rejected("handeye_text", input);
    assert!(
        e.starts_with("hand.csv:3:") && e.contains("quaternion norm 0"),
        "{e}"
    );
    // Direct call, default tolerance: unchanged behaviour.
    let e = read_eth_csv("0, 0, 0, 0, 0, 0, 0, 0\n", "h.csv", 1e-5).unwrap_err();
    assert!(e.to_string().contains("quaternion norm 0"), "{e}");
}

/// Found by `json` (2026-11-22, after 9 s): three valid rotations with weights
/// `[1e307, 1e308, 1e307]` made `chordal_l2_mean` and `quaternion_l2_mean` return NaN
/// estimates (the weighted sums overflow inside the SVD / eigen-solver); by hand we then found
/// weights `1e308` (x3) "certified" the identity with cost 1.17e308 although the optimum is
/// 0.774e308 (the unit-weight optimum 0.7737 scaled), and weights `1e-200` "certified" the
/// identity for the chordal L2 mean (cost 8e-200, optimum 5.75e-200). The readers now reject
/// weights outside `[MIN_WEIGHT, MAX_WEIGHT] = [1e-100, 1e100]` (`rotavg::validate`), inside which
/// the estimates are correct (checked below at both ends against the unit-weight answer).
#[test]
fn extreme_single_weights_are_rejected() {
    let input = b" {\"rotations\": [[[1,0,0],[0,1,0],[0,0,1]], [[0,-1,0],[1,0,0],[0,0,1]], \
[[1,0,0],[0,0,-1],[0,1,0]]], \"weights\": [1e307, 1e308, 1e307]}";
    let e = rejected("json", input);
    assert!(
        e.starts_with("single.json:1:") && e.contains("outside"),
        "{e}"
    );
    let rotations = "[[[1,0,0],[0,1,0],[0,0,1]], [[0,-1,0],[1,0,0],[0,0,1]], \
[[1,0,0],[0,0,-1],[0,1,0]]]";
    let with = |w: &str| format!("{{\"rotations\": {rotations}, \"weights\": [{w}, {w}, {w}]}}");
    for w in ["1e308", "1e154", "1e101", "1e-101", "1e-200", "5e-324"] {
        let e = parse_single_json(&with(w), "s.json").unwrap_err();
        assert!(e.to_string().contains("outside"), "{w}: {e}");
    }
    // The window's ends give the unit-weight estimates (equal weights: scale invariant).
    let unit = parse_single_json(&with("1"), "s.json").unwrap();
    for w in ["1e100", "1e-100"] {
        let p = parse_single_json(&with(w), "s.json").unwrap();
        for (metric, name) in [
            (rotavg::Metric::Chordal, "chordal"),
            (rotavg::Metric::Quaternion, "quaternion"),
        ] {
            // the L2 mean under `metric` with its certificate (the pipeline)
            let mean = |p: &rotavg::single::SingleProblem| {
                let objective = rotavg::Objective::new(metric, rotavg::Loss::L2);
                let p = p.clone().with_objective(objective).unwrap();
                rotavg::pipeline::average_single(&p, &Default::default()).unwrap()
            };
            let (a, b) = (mean(&p), mean(&unit));
            let d = rotavg::so3::angle_between(&a.solution.estimate, &b.solution.estimate);
            assert!(
                d < 1e-9,
                "{name} at weight {w}: {d:e} rad from the unit-weight estimate"
            );
            assert_eq!(
                a.certificate.unwrap().verdict,
                b.certificate.unwrap().verdict,
                "{name} at {w}"
            );
        }
    }
}

/// The same window in every reader that reads weights (multiple JSON, conjugate JSON, g2o);
/// with `WeightSource::Unit` (selector bit 0) the file's weights are not used, not checked.
#[test]
fn extreme_weights_are_rejected_by_every_reader() {
    let z = "[[0,-1,0],[1,0,0],[0,0,1]]";
    let problem = |w: &str| {
        format!(
            "{{\"num_rotations\": 2, \"edges\": [{{\"i\": 0, \"j\": 1, \"rotation\": {z}, \"weight\": {w}}}]}}"
        )
    };
    let input = |sel: u8, text: &str| [&[sel][..], text.as_bytes()].concat();
    for w in ["1e101", "1e-101", "1.7e308"] {
        let e = rejected("json", &input(0, &problem(w)));
        assert!(
            e.contains("edge 0 (0, 1): weight") && e.contains("outside"),
            "{e}"
        );
        assert_eq!(
            dispatch("json", &input(1, &problem(w))),
            Ok(()),
            "unit weights"
        );
        let pairs = format!("{{\"pairs\": [{{\"left\": {z}, \"right\": {z}, \"weight\": {w}}}]}}");
        let e = rejected("json", &input(3 << 3, &pairs));
        assert!(e.contains("pair 0: weight") && e.contains("outside"), "{e}");
    }
    for w in ["1e100", "1e-100", "2.5"] {
        assert_eq!(dispatch("json", &input(0, &problem(w))), Ok(()), "{w}");
    }
    // g2o EDGE_SE2: the weight is I33. kappa = 1e101 is out, 1e100 in.
    let g2o = |w: &str| format!("EDGE_SE2 0 1 1 0 0.5 1 0 0 1 0 {w}\n");
    let e = rejected("g2o", &input(0, &g2o("1e101")));
    assert!(e.starts_with("fuzz.g2o:1:") && e.contains("outside"), "{e}");
    assert_eq!(
        dispatch("g2o", &input(1, &g2o("1e101"))),
        Ok(()),
        "unit weights"
    );
    assert_eq!(dispatch("g2o", &input(0, &g2o("1e100"))), Ok(()));
}

/// Found by `json` (2026-11-22, at start-up, on the seed `problem-min-weights`): a problem
/// with weights at the window's lower end `1e-100`, written with `write_g2o` (information
/// `2w`) and read back, gave `kappa = 3 / (2 tr(Omega^-1)) = 9.999999999999999e-101` and was
/// rejected. The window now has a relative rounding slack of `1e-12`; both ends round-trip.
#[test]
fn weights_at_the_window_ends_round_trip_through_g2o() {
    use rotavg::io::g2o::write_g2o;
    use rotavg::io::json::write_problem_json;
    let z = "[[0,-1,0],[1,0,0],[0,0,1]]";
    for w in ["1e-100", "1e100"] {
        let text = format!(
            "{{\"num_rotations\": 3, \"edges\": [{{\"i\":0,\"j\":1,\"rotation\":{z},\"weight\":{w}}},\
             {{\"i\":1,\"j\":2,\"rotation\":{z},\"weight\":{w}}}]}}"
        );
        let o = ReadOptions::default();
        let g = read_problem_json(&text, "p.json", &o).unwrap();
        let identity = vec![rotavg::Rotation::identity(); 3];
        let back = read_g2o(&write_g2o(&g.problem, Some(&identity)), "p.g2o", &o)
            .unwrap_or_else(|e| panic!("weight {w}: {e}"));
        let json_back = read_problem_json(&write_problem_json(&g.problem), "p.json", &o).unwrap();
        for (a, b) in g.problem.edges().iter().zip(back.problem.edges()) {
            assert!((a.weight - b.weight).abs() <= 1e-12 * a.weight, "{w}");
        }
        for (a, b) in g.problem.edges().iter().zip(json_back.problem.edges()) {
            assert_eq!(a.weight, b.weight, "JSON keeps weights exactly");
            assert!(rotavg::so3::angle_between(&a.rotation, &b.rotation) < 1e-12);
        }
    }
    // Beyond the slack: still rejected.
    let g2o = |w: &str| format!("EDGE_SE2 0 1 1 0 0.5 1 0 0 1 0 {w}\n");
    for w in ["0.99999999e-100", "1.00000001e100"] {
        assert!(
            read_g2o(&g2o(w), "x.g2o", &ReadOptions::default()).is_err(),
            "{w}"
        );
    }
}

/// The weight window holds for problems built in code too, not only for files: the fuzzer's
/// weights `1e308` made the quaternion L2 mean certify a wrong estimate and `1e-200` the chordal
/// L2 mean (overflow / underflow). Every constructor now rejects weights outside
/// `[MIN_WEIGHT, MAX_WEIGHT]` with `Error::InvalidWeight`.
#[test]
fn constructors_reject_weights_outside_the_window() {
    use rotavg::conjugate::{ConjugatePair, ConjugateProblem};
    use rotavg::multiple::{Edge, MultipleProblem};
    use rotavg::single::SingleProblem;
    use rotavg::{Error, Rotation};
    let r = Rotation::identity();
    for w in [1e308, 1e-200, 0.0, -1.0, f64::NAN, f64::INFINITY] {
        let s = SingleProblem::new(vec![r, r, r], Some(vec![w, 1.0, 1.0]));
        assert!(matches!(s, Err(Error::InvalidWeight { .. })), "single {w}");
        let m = MultipleProblem::new(
            2,
            vec![Edge {
                i: 0,
                j: 1,
                rotation: r,
                weight: w,
            }],
        );
        assert!(
            matches!(m, Err(Error::InvalidWeight { .. })),
            "multiple {w}"
        );
        let c = ConjugateProblem::new(vec![ConjugatePair {
            left: r,
            right: r,
            weight: w,
        }]);
        assert!(
            matches!(c, Err(Error::InvalidWeight { .. })),
            "conjugate {w}"
        );
    }
    // the window's ends are accepted
    for w in [1e-100, 1e100] {
        assert!(SingleProblem::new(vec![r, r], Some(vec![w, 1.0])).is_ok());
        assert!(
            MultipleProblem::new(
                2,
                vec![Edge {
                    i: 0,
                    j: 1,
                    rotation: r,
                    weight: w
                }]
            )
            .is_ok()
        );
    }
}
