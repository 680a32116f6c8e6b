//! Hand-eye pose streams as motion-capture rigs write them (`rotavg conjugate` with Vicon-named
//! files, `--hand` / `--camera`, the pairing flags): a stream pair synthesised from a planted
//! `X` (hand at 100 Hz with nanosecond stamps and a header, camera at 30 Hz with a clock
//! offset, both with repeated time stamps) is recovered, the counts are exact, and bad streams
//! and ambiguous directories give errors that say what to do. The ETH real data (skipped when
//! absent) gives the result it gave before streams were generalised.

use nalgebra::{UnitQuaternion, Vector3};
use rotavg::io::handeye::{MotionSettings, read_pose_stream};
use rotavg::so3::{Rotation, angle_between, exp, rotation_from_rows};
use std::path::{Path, PathBuf};

use crate::common;
use common::{json_of, run};

/// The planted camera-to-hand rotation `X`.
fn planted() -> Rotation {
    exp(&Vector3::new(0.4, -0.3, 0.9))
}

/// The hand pose `H(t)` (rotation), about changing axes.
fn hand_at(t: f64) -> Rotation {
    exp(&Vector3::new(
        0.8 * (1.1 * t).sin(),
        0.6 * (0.7 * t).cos(),
        0.5 * (0.4 * t + 1.0).sin(),
    ))
}

/// The camera pose `E = W H X` (rotation), so that `(H_i^-1 H_j) X = X (E_i^-1 E_j)`.
fn camera_at(t: f64) -> Rotation {
    exp(&Vector3::new(0.2, 0.1, -0.3)) * hand_at(t) * planted()
}

fn quat(r: &Rotation) -> UnitQuaternion<f64> {
    UnitQuaternion::from_rotation_matrix(r)
}

/// A fresh directory for one test.
fn dir(name: &str) -> PathBuf {
    let d = common::temp_dir().join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Epoch of the synthetic recording (seconds; the hand stream writes it in nanoseconds).
const EPOCH_S: i64 = 1_700_000_000;
/// The camera clock runs this far behind: camera stamp = true time - LAG.
const LAG: f64 = 0.013;
/// Hand samples 0..=HAND_N at 100 Hz; every `HAND_REPEAT`-th is sent twice (same stamp, a
/// different pose: the first must be kept).
const HAND_N: i64 = 500;
const HAND_REPEAT: i64 = 50;
/// Camera samples 0..=CAM_N at 30 Hz from 0.502 s; every `CAM_REPEAT`-th is sent twice.
const CAM_N: usize = 150;
const CAM_REPEAT: usize = 40;

fn cam_time(j: usize) -> f64 {
    0.502 + j as f64 / 30.0
}

/// The Vicon-style hand stream (header line, comma separated, nanosecond stamps, `qx qy qz
/// qw`, or `qw qx qy qz` in both streams with `wxyz`) and the camera stream (whitespace
/// separated, seconds), with the number of repeated stamps written into each.
fn write_streams(d: &Path, hand_name: &str, camera_name: &str, wxyz: bool) -> (usize, usize) {
    let mut hand = String::from("time_ns,tx,ty,tz,qx,qy,qz,qw\n");
    let mut hand_repeats = 0;
    for k in 0..=HAND_N {
        let ns = EPOCH_S * 1_000_000_000 + k * 10_000_000;
        let q = quat(&hand_at(k as f64 * 0.01));
        let (a, b, c, e) = if wxyz {
            (q.w, q.i, q.j, q.k)
        } else {
            (q.i, q.j, q.k, q.w)
        };
        hand += &format!("{ns},0.1,0.2,0.3,{a:.17},{b:.17},{c:.17},{e:.17}\n");
        if k % HAND_REPEAT == 25 {
            // Same stamp, another pose: keeping it (or averaging) would spoil the data.
            let bad = quat(&exp(&Vector3::new(1.0, 0.0, 0.0)));
            hand += &format!("{ns},9,9,9,{},{},{},{}\n", bad.i, bad.j, bad.k, bad.w);
            hand_repeats += 1;
        }
    }
    let mut camera = String::from("# t x y z quaternion\n");
    let mut camera_repeats = 0;
    for j in 0..=CAM_N {
        let t = cam_time(j);
        let q = quat(&camera_at(t));
        let ns = EPOCH_S * 1_000_000_000 + ((t - LAG) * 1e9).round() as i64;
        let stamp = format!("{}.{:09}", ns / 1_000_000_000, ns % 1_000_000_000);
        let line = if wxyz {
            format!(
                "{stamp} 1 2 3 {:.17} {:.17} {:.17} {:.17}\n",
                q.w, q.i, q.j, q.k
            )
        } else {
            format!(
                "{stamp} 1 2 3 {:.17} {:.17} {:.17} {:.17}\n",
                q.i, q.j, q.k, q.w
            )
        };
        camera += &line;
        if j % CAM_REPEAT == 7 {
            camera += &line;
            camera += &line;
            camera_repeats += 2;
        }
    }
    std::fs::write(d.join(hand_name), hand).unwrap();
    std::fs::write(d.join(camera_name), camera).unwrap();
    (hand_repeats, camera_repeats)
}

fn estimate(v: &serde_json::Value) -> Rotation {
    let rows: [[f64; 3]; 3] = serde_json::from_value(v["estimate"].clone()).unwrap();
    rotation_from_rows(&rows, 1e-6, "estimate").unwrap()
}

fn path(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Camera samples whose true time lies at or beyond the last hand sample (not matched).
fn expected_unmatched() -> usize {
    (0..=CAM_N)
        .filter(|&j| cam_time(j) >= HAND_N as f64 * 0.01)
        .count()
}

#[test]
fn vicon_stream_pair_recovers_the_planted_rotation_with_exact_counts() {
    let d = dir("vicon");
    let (hr, cr) = write_streams(&d, "run3_vicon_tool.csv", "run3_camera.txt", false);
    assert!(hr > 5 && cr > 5);
    let offset = format!("{LAG}");
    let out = run(&["conjugate", path(&d), "--time-offset", &offset, "--json"]);
    let v = json_of(&out);
    let error = angle_between(&estimate(&v), &planted()).to_degrees();
    assert!(error < 0.01, "error {error} deg");
    assert_eq!(v["certificate"]["verdict"], "certified");
    let m = &v["motion"];
    assert_eq!(m["hand"]["samples"], HAND_N as usize + 1 + hr);
    assert_eq!(m["hand"]["repeated_stamps"], hr);
    assert_eq!(m["hand"]["kept"], HAND_N as usize + 1);
    assert_eq!(m["hand"]["header_lines"], 1);
    assert_eq!(m["hand"]["time_unit"], "nanoseconds");
    assert_eq!(m["camera"]["repeated_stamps"], cr);
    assert_eq!(m["camera"]["kept"], CAM_N + 1);
    assert_eq!(m["camera"]["header_lines"], 0); // the `#` line is a comment
    assert_eq!(m["camera"]["time_unit"], "seconds");
    let unmatched = expected_unmatched();
    assert!(unmatched > 10);
    assert_eq!(m["unmatched"], unmatched);
    let matched = CAM_N + 1 - unmatched;
    assert_eq!(m["poses"], matched);
    // Pairs start at 0, 3, 6, ... while start + 15 < matched.
    let starts = (matched - 15).div_ceil(3);
    let (pairs, skipped) = (
        m["pairs"].as_u64().unwrap(),
        m["skipped_small"].as_u64().unwrap(),
    );
    assert_eq!((pairs + skipped) as usize, starts);
    assert_eq!(v["num_measurements"], pairs);
    assert_eq!(m["settings"]["time_offset"], LAG);
    // The text report states the counts too (--verbose: its lines unbroken).
    let out = run(&["conjugate", path(&d), "--time-offset", &offset, "--verbose"]);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains(&format!(
            "hand (L): run3_vicon_tool.csv: {} samples, {hr} repeated time stamps dropped, 1 header lines, time in ns",
            HAND_N as usize + 1 + hr
        )),
        "{text}"
    );
    assert!(
        text.contains(&format!("({unmatched} camera samples unmatched)")),
        "{text}"
    );
    // The offset is applied with the documented sign: without it (or with the opposite sign)
    // the pairs fit worse.
    let cost = |offset: &str| {
        let v = json_of(&run(&[
            "conjugate",
            path(&d),
            "--time-offset",
            offset,
            "--certify",
            "none",
            "--json",
        ]));
        v["cost"].as_f64().unwrap()
    };
    let (right, none, wrong) = (cost(&offset), cost("0"), cost(&format!("-{LAG}")));
    assert!(
        right * 100.0 < none && none < wrong,
        "{right} {none} {wrong}"
    );
}

#[test]
fn explicit_files_and_pairing_flags() {
    let d = dir("explicit");
    // Names that detection does not know, scalar-first quaternions (`--quaternion-order` applies
    // to both streams).
    write_streams(&d, "arm.csv", "eye.csv", true);
    let (hand, camera) = (d.join("arm.csv"), d.join("eye.csv"));
    let offset = format!("{LAG}");
    let base = [
        "conjugate",
        "--hand",
        path(&hand),
        "--camera",
        path(&camera),
        "--time-offset",
        &offset,
    ];
    let v = json_of(&run(&[
        &base[..],
        &["--quaternion-order", "wxyz", "--json"],
    ]
    .concat()));
    assert!(angle_between(&estimate(&v), &planted()).to_degrees() < 0.01);
    let pairs = v["num_measurements"].as_u64().unwrap();
    // Scalar-first streams read as scalar-last: the same wrong order in both streams still
    // gives consistent pairs (residuals as small), but of another `S`; the residuals cannot
    // tell, so the order must be known.
    let wrong = json_of(&run(&[&base[..], &["--certify", "none", "--json"]].concat()));
    assert!(angle_between(&estimate(&wrong), &planted()).to_degrees() > 10.0);
    // Stride and subsample change which pairs are formed.
    let v2 = json_of(&run(&[
        &base[..],
        &[
            "--quaternion-order",
            "wxyz",
            "--stride",
            "10",
            "--subsample",
            "1",
            "--json",
        ],
    ]
    .concat()));
    let m = &v2["motion"];
    let matched = m["poses"].as_u64().unwrap();
    assert_eq!(
        m["pairs"].as_u64().unwrap() + m["skipped_small"].as_u64().unwrap(),
        matched - 10
    );
    assert!(v2["num_measurements"].as_u64().unwrap() > pairs);
    assert!(angle_between(&estimate(&v2), &planted()).to_degrees() < 0.01);
    // A file name relative to the directory, the other detected... or not: `eye.csv` has no
    // camera word, so detection fails and says how to name it.
    let out = run(&["conjugate", path(&d), "--hand", "arm.csv"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("camera candidates") && err.contains("--camera FILE"),
        "{err}"
    );
    std::fs::rename(&camera, d.join("eye_camera.csv")).unwrap();
    let out = run(&[
        "conjugate",
        path(&d),
        "--hand",
        "arm.csv",
        "--quaternion-order",
        "wxyz",
        "--time-offset",
        &offset,
        "--json",
    ]);
    assert!(angle_between(&estimate(&json_of(&out)), &planted()).to_degrees() < 0.01);
    // A max gap below the hand's sample spacing matches nothing.
    let out = run(&[
        "conjugate",
        path(&d),
        "--hand",
        "arm.csv",
        "--max-gap",
        "0.001",
    ]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("0 time-matched samples") && err.contains("max gap 0.001"),
        "{err}"
    );
    // Settings out of range and flags that do not apply are errors.
    for (flags, what) in [
        (&["--stride", "0"][..], "stride"),
        (&["--max-gap=-1"][..], "max_gap"),
        (&["--min-angle=-2"][..], "min_angle"),
        (&["--format", "tabb"][..], "hand/camera"),
    ] {
        let out = run(&[&["conjugate", path(&d), "--hand", "arm.csv"], flags].concat());
        assert_eq!(out.status.code(), Some(1), "{flags:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(what), "{flags:?}: {err}");
    }
    // Without a directory both files are needed (a usage error).
    let out = run(&["conjugate", "--hand", path(&hand)]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn ambiguous_or_missing_streams_name_the_candidates_and_the_flags() {
    let d = dir("ambiguous");
    write_streams(&d, "a_vicon.csv", "a_camera.csv", false);
    write_streams(&d, "b_vicon.csv", "b_target.csv", false);
    let out = run(&["conjugate", path(&d)]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    for needle in [
        "a_vicon.csv, b_vicon.csv",
        "a_camera.csv, b_target.csv",
        "`vicon`",
        "--hand FILE and --camera FILE",
    ] {
        assert!(err.contains(needle), "{needle}: {err}");
    }
    // Naming both resolves it.
    let out = run(&[
        "conjugate",
        path(&d),
        "--hand",
        "b_vicon.csv",
        "--camera",
        "b_target.csv",
        "--time-offset",
        &format!("{LAG}"),
        "--json",
    ]);
    assert!(angle_between(&estimate(&json_of(&out)), &planted()).to_degrees() < 0.01);
    // No candidates at all.
    let empty = dir("no_streams");
    std::fs::write(empty.join("poses.csv"), "0,0,0,0,0,0,0,1\n").unwrap();
    let out = run(&["conjugate", path(&empty), "--format", "eth"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("hand candidates") && err.contains(": none;") && err.contains("--hand"),
        "{err}"
    );
}

#[test]
fn repeated_stamps_are_counted_and_decreasing_stamps_name_their_line() {
    // Runs of equal stamps: 3 at t = 1 (2 dropped), 2 at t = 3 (1 dropped).
    let text = "0 0 0 0 0 0 0 1\n1 0 0 0 0 0 0 1\n1 5 0 0 0 0 0 1\n1 6 0 0 0 0 0 1\n\
                2 0 0 0 0 0 0 1\n3 0 0 0 0 0 0 1\n3 7 0 0 0 0 0 1\n";
    let s = read_pose_stream(text, "h.txt", &MotionSettings::default()).unwrap();
    assert_eq!(
        (s.stats.samples, s.stats.kept, s.stats.repeated_stamps),
        (7, 4, 3)
    );
    let times: Vec<f64> = s.poses.iter().map(|p| p.time).collect();
    assert_eq!(times, [0.0, 1.0, 2.0, 3.0]);
    assert!(s.poses.iter().all(|p| p.pose.translation.x == 0.0)); // the first of each stamp
    // A decreasing stamp is an error naming its line and the previous one, also in ns files
    // and through the command line.
    let bad = "t,x,y,z,qx,qy,qz,qw\n0.0,0,0,0,0,0,0,1\n\n0.5,0,0,0,0,0,0,1\n0.5,0,0,0,0,0,0,1\n0.4,0,0,0,0,0,0,1\n";
    let err = read_pose_stream(bad, "h.csv", &MotionSettings::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("h.csv:6: ") && err.contains("(line 4)"),
        "{err}"
    );
    let ns = "1700000000000000000 0 0 0 0 0 0 1\n1699999999990000000 0 0 0 0 0 0 1\n";
    let err = read_pose_stream(ns, "n.txt", &MotionSettings::default())
        .unwrap_err()
        .to_string();
    assert!(err.starts_with("n.txt:2: "), "{err}");
    // A seconds value in a nanosecond file, a wrong field count, a header after data.
    for (text, line) in [
        (
            "1700000000000000000 0 0 0 0 0 0 1\n1700000000.5 0 0 0 0 0 0 1\n",
            2,
        ),
        ("0 0 0 0 0 0 0 1\n1 0 0 0 0 0 1\n", 2),
        ("0 0 0 0 0 0 0 1\ntime x y z qx qy qz qw\n", 2),
    ] {
        let err = read_pose_stream(text, "f.txt", &MotionSettings::default())
            .unwrap_err()
            .to_string();
        assert!(err.starts_with(&format!("f.txt:{line}: ")), "{err}");
    }
    // Only a header: "no poses" says what was skipped.
    let err = read_pose_stream("time,x\n", "f.csv", &MotionSettings::default())
        .unwrap_err()
        .to_string();
    assert!(err.contains("skipped as a header"), "{err}");
    let d = dir("decreasing");
    write_streams(&d, "x_hand.csv", "x_camera.csv", false);
    let hand = std::fs::read_to_string(d.join("x_hand.csv")).unwrap();
    let mut lines: Vec<&str> = hand.lines().collect();
    lines.swap(10, 11); // data lines 10 and 11 (file lines 11 and 12)
    std::fs::write(d.join("x_hand.csv"), lines.join("\n")).unwrap();
    let out = run(&["conjugate", path(&d)]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("x_hand.csv:12: "), "{err}");
}

/// The ETH robot-arm recording gives what it gave before pose streams were generalised
/// (measured with the previous build: 1688 matched samples, 551 pairs, 7 skipped, cost
/// 2.411079374e-1, this `S`).
#[test]
fn real_eth_data_unchanged() {
    let Some(d) = common::shared("handeye/ethz_robot_arm_real") else {
        println!("skipping: shared data handeye/ethz_robot_arm_real not found");
        return;
    };
    let v = json_of(&run(&["conjugate", path(&d), "--json"]));
    let m = &v["motion"];
    assert_eq!(m["poses"], 1688);
    assert_eq!(m["pairs"], 551);
    assert_eq!(m["skipped_small"], 7);
    assert_eq!(m["hand"]["repeated_stamps"], 0);
    assert_eq!(m["camera"]["repeated_stamps"], 0);
    assert_eq!(m["unmatched"], 1703 - 1688);
    assert!((v["cost"].as_f64().unwrap() - 2.411079374e-1).abs() < 1e-9);
    let before = rotation_from_rows(
        &[
            [
                0.45544500193807025,
                -0.011132920590297246,
                0.8901943092880122,
            ],
            [
                -0.8902629522146361,
                -0.004219771109294168,
                0.4554273481532104,
            ],
            [
                -0.0013138202736476812,
                -0.9999291232937039,
                -0.011833100412539821,
            ],
        ],
        1e-6,
        "S before",
    )
    .unwrap();
    assert!(angle_between(&estimate(&v), &before) < 1e-9);
    assert_eq!(v["certificate"]["verdict"], "certified");
    // Naming the same files explicitly gives the same pairs.
    let names: Vec<PathBuf> = ["base_link", "target"]
        .iter()
        .map(|w| {
            std::fs::read_dir(&d)
                .unwrap()
                .flatten()
                .map(|e| e.path())
                .find(|p| p.to_string_lossy().contains(w))
                .unwrap()
        })
        .collect();
    let v2 = json_of(&run(&[
        "conjugate",
        "--hand",
        path(&names[0]),
        "--camera",
        path(&names[1]),
        "--json",
    ]));
    assert_eq!(v2["motion"]["pairs"], 551);
    // the same pairs give the same estimate (the pinned `S` above is that of an earlier build:
    // the minimum is flat to rounding over ~1e-9 rad, where the solver's stopping test lands)
    assert!(angle_between(&estimate(&v2), &estimate(&v)) < 1e-12);
}

/// Pairing flags at the edge of `usize` and millisecond / microsecond stamps: a typed error or
/// a result, never a panic (the subsample step once overflowed into an out-of-bounds index).
#[test]
fn extreme_pairing_flags_and_ambiguous_integer_stamps() {
    let d = dir("extreme");
    write_streams(&d, "arm_vicon.csv", "eye_camera.csv", false);
    let (hand, camera) = (d.join("arm_vicon.csv"), d.join("eye_camera.csv"));
    for (stride, subsample) in [("1", "18446744073709551615"), ("18446744073709551615", "1")] {
        let out = run(&[
            "conjugate",
            "--hand",
            path(&hand),
            "--camera",
            path(&camera),
            "--stride",
            stride,
            "--subsample",
            subsample,
        ]);
        let code = out.status.code();
        assert!(
            code == Some(0) || code == Some(1),
            "stride {stride}, subsample {subsample}: exit {code:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // millisecond epoch stamps are neither seconds nor nanoseconds: refused, with the line
    let ms = "1700000000000 0 0 0 0 0 0 1\n1700000000010 0 0 0 0 0 0 1\n";
    let err = read_pose_stream(ms, "ms.txt", &MotionSettings::default())
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("ms.txt:1: ") && err.contains("milliseconds or microseconds"),
        "{err}"
    );
    // nanoseconds and seconds still read
    let ns = "1700000000000000000 0 0 0 0 0 0 1\n1700000000010000000 0 0 0 0 0 0 1\n";
    assert_eq!(
        read_pose_stream(ns, "ns.txt", &MotionSettings::default())
            .unwrap()
            .poses
            .len(),
        2
    );
}

#[test]
fn conjugate_writes_its_estimate_and_certify_reads_the_same_streams() {
    let d = dir("output_certify");
    write_streams(&d, "arm_hand.csv", "arm_camera.txt", false);
    let (hand, camera) = (d.join("arm_hand.csv"), d.join("arm_camera.txt"));
    let streams = [
        "--hand",
        path(&hand),
        "--camera",
        path(&camera),
        "--time-offset",
        &format!("{LAG}"),
    ];
    let out_file = d.join("out/s.json");
    let solved = json_of(&run(&[
        &["conjugate", "--output", path(&out_file), "--json"][..],
        &streams[..],
    ]
    .concat()));
    // the file holds exactly the reported estimate, in the estimate format certify reads
    let text = std::fs::read_to_string(&out_file).expect("--output written");
    let written: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(written["rotation"], solved["estimate"]);
    let certified = json_of(&run(&[
        &["certify", "--estimate", path(&out_file), "--json"][..],
        &streams[..],
    ]
    .concat()));
    assert_eq!(certified["problem"], "conjugate");
    assert_eq!(certified["num_measurements"], solved["num_measurements"]);
    assert_eq!(certified["certificate"]["verdict"], "certified");
    let cost = |v: &serde_json::Value| v["certificate"]["upper_bound"].as_f64().unwrap();
    assert!((cost(&certified) - cost(&solved)).abs() <= 1e-12 * cost(&solved).max(1e-300));
    // the planted rotation, judged on the same pairs: its cost is above the proven bound,
    // within the pairing's interpolation error of the optimum
    let planted_file = d.join("planted.json");
    let rows = rotavg::so3::rotation_to_rows(&planted());
    std::fs::write(
        &planted_file,
        serde_json::json!({ "rotation": rows }).to_string(),
    )
    .unwrap();
    let judged = json_of(&run(&[
        &["certify", "--estimate", path(&planted_file), "--json"][..],
        &streams[..],
    ]
    .concat()));
    let lb = judged["certificate"]["lower_bound"].as_f64().unwrap();
    assert!(lb <= cost(&judged) && lb <= cost(&solved) * (1.0 + 1e-9));
    // a failed run (an estimate that is not a rotation) leaves no folder
    let failed = d.join("failed/deeper/s.json");
    let out = run(&[
        &[
            "conjugate",
            "--output",
            path(&failed),
            "--init",
            path(&hand),
        ][..],
        &streams[..],
    ]
    .concat());
    assert_eq!(out.status.code(), Some(1));
    assert!(!d.join("failed").exists());
}
