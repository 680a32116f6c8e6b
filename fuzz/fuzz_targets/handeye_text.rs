//! Hand-eye text readers (`rotavg::io::handeye`): the first byte's bits 3-4 select
//! `read_tabb_robot` (`robot_cali.txt`), `read_tabb_camera` (`cali.txt`) or `read_eth_csv`,
//! bits 1-2 the rotation tolerance. Accepted pose lists are turned into conjugate problems
//! (`tabb_problem` / `eth_problem`, the file paired with itself) and diagnosed.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rotavg::conjugate::{ConjugateProblem, DiagnosticSettings, quaternion_closed_form};
use rotavg::io::handeye::{
    MotionSettings, eth_problem, read_eth_csv, read_tabb_camera, read_tabb_robot, tabb_problem,
};

mod common;

/// Poses above which the O(N^2) Tabb pairing is skipped (execution time).
const MAX_POSES: usize = 200;

fn check_conjugate(p: &ConjugateProblem) {
    for pair in p.pairs() {
        common::assert_rotation(&pair.left);
        common::assert_rotation(&pair.right);
    }
    let settings = DiagnosticSettings::default();
    let _ = p.diagnose(&settings);
    if let Ok(sol) = quaternion_closed_form(p, &settings) {
        common::assert_rotation(&sol.estimate);
        assert!(p.chordal_cost(&sol.estimate) >= 0.0);
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((selector, text)) = common::split(data) else {
        return;
    };
    let tol = common::tolerance(selector);
    let settings = MotionSettings {
        rotation_tolerance: tol,
        ..MotionSettings::default()
    };
    match (selector >> 3) & 3 {
        0 | 3 => {
            if let Ok(poses) = read_tabb_robot(&text, "robot_cali.txt", tol) {
                poses
                    .iter()
                    .for_each(|p| common::assert_rotation(&p.rotation));
                if poses.len() <= MAX_POSES {
                    if let Ok((p, _)) = tabb_problem(&poses, &poses, &settings) {
                        check_conjugate(&p);
                    }
                }
            }
        }
        1 => {
            if let Ok(poses) = read_tabb_camera(&text, "cali.txt", tol) {
                poses
                    .iter()
                    .for_each(|p| common::assert_rotation(&p.rotation));
                if poses.len() <= MAX_POSES {
                    if let Ok((p, _)) = tabb_problem(&poses, &poses, &settings) {
                        check_conjugate(&p);
                    }
                }
            }
        }
        _ => {
            if let Ok(stream) = read_eth_csv(&text, "hand.csv", tol) {
                assert!(stream.windows(2).all(|w| w[0].time < w[1].time));
                stream
                    .iter()
                    .for_each(|p| common::assert_rotation(&p.pose.rotation));
                let settings = MotionSettings {
                    stride: 1,
                    subsample: 1,
                    max_gap: 1.0,
                    ..settings
                };
                if let Ok((p, _)) = eth_problem(&stream, &stream, &settings) {
                    check_conjugate(&p);
                }
            }
        }
    }
});
