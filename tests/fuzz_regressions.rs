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
