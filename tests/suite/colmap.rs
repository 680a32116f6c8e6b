//! COLMAP input and output `[F12]`: databases written here with COLMAP's documented schema
//! (the `CREATE TABLE` statements of COLMAP's `database.cc`) through rusqlite, with planted
//! absolute rotations; sparse models (`images.txt`, `images.bin`) in COLMAP's layout; the
//! command line end to end; and the errors of malformed inputs.

use crate::common;

use common::{assert_success, json_of, max_gauge_error, run, temp_dir};
use rotavg::Rotation;
use rotavg::io::colmap::{
    image_pair_to_pair_id, load_images, read_colmap_database, read_images_binary, read_images_text,
    write_images_text,
};
use rotavg::io::detect::{GraphFormat, ReadOptions, load_graph};
use rotavg::multiple::{MultipleSettings, solve_multiple};
use rotavg::rand::{SeedableRng, rngs::StdRng};
use rotavg::so3::{perturb, random_rotation, to_quaternion};
use std::path::{Path, PathBuf};

/// COLMAP's schema (database.cc of COLMAP 3.8-3.11: `images` with pose priors, and
/// `two_view_geometries` with `qvec` / `tvec`).
const SCHEMA: &str = "
CREATE TABLE IF NOT EXISTS cameras (camera_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, model INTEGER NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL, params BLOB, prior_focal_length INTEGER NOT NULL);
CREATE TABLE IF NOT EXISTS images (image_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, name TEXT NOT NULL UNIQUE, camera_id INTEGER NOT NULL, prior_qw REAL, prior_qx REAL, prior_qy REAL, prior_qz REAL, prior_tx REAL, prior_ty REAL, prior_tz REAL, CONSTRAINT image_id_check CHECK(image_id >= 0 and image_id < 2147483647), FOREIGN KEY(camera_id) REFERENCES cameras(camera_id));
CREATE TABLE IF NOT EXISTS keypoints (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS descriptors (image_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, FOREIGN KEY(image_id) REFERENCES images(image_id) ON DELETE CASCADE);
CREATE TABLE IF NOT EXISTS matches (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB);
CREATE TABLE IF NOT EXISTS two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, config INTEGER NOT NULL, F BLOB, E BLOB, H BLOB, qvec BLOB, tvec BLOB);
CREATE UNIQUE INDEX IF NOT EXISTS index_name ON images(name);
";

fn blob(values: &[f64]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// COLMAP's `(w, x, y, z)` of a rotation.
fn wxyz(r: &Rotation) -> [f64; 4] {
    let q = to_quaternion(r);
    [q.w, q.i, q.j, q.k]
}

/// One row of `two_view_geometries`.
struct Row {
    pair_id: i64,
    config: i64,
    qvec: Option<Vec<u8>>,
    tvec: Option<Vec<u8>>,
}

/// The geometry of images `a < b` (their world-to-camera rotations `ra`, `rb`) as COLMAP
/// stores it: `cam2_from_cam1 = R_b R_a^T`, a unit translation.
fn row(a: u32, b: u32, ra: &Rotation, rb: &Rotation, config: i64) -> Row {
    Row {
        pair_id: image_pair_to_pair_id(a, b) as i64,
        config,
        qvec: Some(blob(&wxyz(&(rb * ra.inverse())))),
        tvec: Some(blob(&[0.0, 0.0, 1.0])),
    }
}

fn write_db(path: &Path, schema: &str, images: &[(u32, String)], rows: &[Row]) {
    let _ = std::fs::remove_file(path);
    let db = rusqlite::Connection::open(path).expect("create the database");
    db.execute_batch(schema).expect("schema");
    db.execute(
        "INSERT INTO cameras VALUES (1, 0, 640, 480, ?1, 0)",
        [blob(&[500.0, 320.0, 240.0])],
    )
    .expect("camera");
    for (id, name) in images {
        db.execute(
            "INSERT INTO images (image_id, name, camera_id) VALUES (?1, ?2, 1)",
            rusqlite::params![id, name],
        )
        .expect("image");
    }
    for r in rows {
        db.execute(
            "INSERT INTO two_view_geometries VALUES (?1, 0, 2, NULL, ?2, NULL, NULL, NULL, ?3, ?4)",
            rusqlite::params![r.pair_id, r.config, r.qvec, r.tvec],
        )
        .expect("two-view geometry");
    }
}

/// A planted scene: image ids with gaps, names, world-to-camera rotations.
struct Scene {
    ids: Vec<u32>,
    names: Vec<String>,
    truth: Vec<Rotation>,
}

fn scene(n: usize, seed: u64) -> Scene {
    let mut rng = StdRng::seed_from_u64(seed);
    let ids: Vec<u32> = (0..n as u32).map(|k| 1 + 3 * k + k % 2).collect();
    Scene {
        names: ids
            .iter()
            .map(|id| format!("frames/img_{id:04}.jpg"))
            .collect(),
        truth: (0..n).map(|_| random_rotation(&mut rng)).collect(),
        ids,
    }
}

/// Every pair `k < l` with `(k + l) % 3 != 0` plus a chain (connected), optionally noisy; and
/// rows that must be skipped: configs 0, 1, 7, 8, 42, a zero quaternion, COLMAP's default pose,
/// a NULL qvec.
fn rows(s: &Scene, noise: f64, seed: u64) -> (Vec<Row>, usize) {
    let mut rng = StdRng::seed_from_u64(seed);
    let n = s.ids.len();
    let mut out = Vec::new();
    for k in 0..n {
        for l in k + 1..n {
            if l == k + 1 || (k + l) % 3 != 0 {
                let rb = perturb(&s.truth[l], noise, &mut rng);
                let config = [2, 3, 4, 5, 6, 9][(k + l) % 6];
                out.push(row(s.ids[k], s.ids[l], &s.truth[k], &rb, config));
            }
        }
    }
    let used = out.len();
    // skipped rows: on pairs not used above ((k + l) % 3 == 0, l > k + 1)
    let spare: Vec<(usize, usize)> = (0..n)
        .flat_map(|k| (k + 2..n).map(move |l| (k, l)))
        .filter(|(k, l)| (k + l) % 3 == 0)
        .collect();
    let bad = Rotation::identity(); // would be a wrong measurement if it were read
    for (slot, &(k, l)) in spare.iter().enumerate().take(8) {
        let mut r = row(s.ids[k], s.ids[l], &bad, &s.truth[k], 2);
        match slot {
            0 => r.config = 0,
            1 => r.config = 1,
            2 => r.config = 42,
            3 => r.config = 7,
            4 => r.config = 8,
            5 => r.qvec = Some(blob(&[0.0; 4])),
            6 => {
                r.qvec = Some(blob(&[1.0, 0.0, 0.0, 0.0]));
                r.tvec = Some(blob(&[0.0; 3]));
            }
            _ => r.qvec = None,
        }
        out.push(r);
    }
    (out, used)
}

fn images_of(s: &Scene) -> Vec<(u32, String)> {
    s.ids.iter().copied().zip(s.names.iter().cloned()).collect()
}

fn db_path(name: &str) -> PathBuf {
    temp_dir().join(name)
}

/// A COLMAP `images.txt` of the scene in COLMAP's layout (header, image line, points line).
fn images_txt(s: &Scene) -> String {
    let mut t = String::from(
        "# Image list with two lines of data per image:\n#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n#   POINTS2D[] as (X, Y, POINT3D_ID)\n",
    );
    t += &format!(
        "# Number of images: {}, mean observations per image: 2\n",
        s.ids.len()
    );
    for (k, id) in s.ids.iter().enumerate() {
        let q = wxyz(&s.truth[k]);
        t += &format!(
            "{id} {} {} {} {} 0.5 -1.25 3 1 {}\n",
            q[0], q[1], q[2], q[3], s.names[k]
        );
        t += if k % 2 == 0 {
            "10.5 20.25 7 30 40 -1\n"
        } else {
            "\n"
        };
    }
    t
}

/// The same model as `images.bin` (COLMAP's binary layout, with 2-D points).
fn images_bin(s: &Scene) -> Vec<u8> {
    let mut b = (s.ids.len() as u64).to_le_bytes().to_vec();
    for (k, id) in s.ids.iter().enumerate() {
        b.extend(id.to_le_bytes());
        b.extend(blob(&wxyz(&s.truth[k])));
        b.extend(blob(&[0.5, -1.25, 3.0]));
        b.extend(1u32.to_le_bytes());
        b.extend(s.names[k].as_bytes());
        b.push(0);
        let points = k as u64 % 3;
        b.extend(points.to_le_bytes());
        for p in 0..points {
            b.extend(blob(&[10.0 * p as f64, 20.0]));
            b.extend(u64::MAX.to_le_bytes()); // COLMAP's invalid point3D_id
        }
    }
    b
}

#[test]
fn database_convention_recovers_planted_rotations() {
    let s = scene(12, 1);
    let (rows, used) = rows(&s, 0.0, 2);
    let path = db_path("planted.db");
    write_db(&path, SCHEMA, &images_of(&s), &rows);
    let g = read_colmap_database(&path, &ReadOptions::default()).expect("read the database");
    assert_eq!(g.format, GraphFormat::Colmap);
    assert_eq!(
        g.node_ids,
        s.ids.iter().map(|&i| u64::from(i)).collect::<Vec<_>>()
    );
    assert_eq!(g.node_names, s.names);
    assert_eq!(g.problem.num_edges(), used);
    let w = g.warnings.join("\n");
    assert!(
        w.contains("skipped 5 of")
            && w.contains("1 UNDEFINED (0)")
            && w.contains("1 MULTIPLE (8)")
            && w.contains("1 UNKNOWN (42)"),
        "{w}"
    );
    assert!(
        w.contains("skipped 3 of") && w.contains("without a stored relative pose"),
        "{w}"
    );
    // The planted rotations are a zero-cost solution: R_ij R_i = R_j with R_ij = cam2_from_cam1.
    let cost = g.problem.chordal_cost(&s.truth);
    assert!(cost < 1e-24, "planted cost {cost:e}");
    // The other convention (R_ij = its transpose) does not fit.
    let transposed: Vec<Rotation> = s.truth.iter().map(|r| r.inverse()).collect();
    assert!(g.problem.chordal_cost(&transposed) > 1.0);
    // The solver recovers them up to the gauge.
    let sol = solve_multiple(&g.problem, &MultipleSettings::default()).expect("solve");
    let err = max_gauge_error(&sol.rotations, &s.truth);
    assert!(err < 1e-12, "gauge error {err:e}");
    // Auto-detection from the SQLite header, and a folder holding database.db.
    let auto = load_graph(&path, GraphFormat::Auto, &ReadOptions::default()).expect("auto");
    assert_eq!(auto.problem, g.problem);
    let dir = temp_dir().join("colmap_project");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(&path, dir.join("database.db")).unwrap();
    let from_dir = load_graph(&dir, GraphFormat::Auto, &ReadOptions::default()).expect("dir");
    assert_eq!(from_dir.problem, g.problem);
}

#[test]
fn cli_solves_a_noisy_database_with_ground_truth_and_writes_images_txt() {
    let s = scene(15, 3);
    let (rows, _) = rows(&s, 0.01, 4);
    let path = db_path("noisy.db");
    write_db(&path, SCHEMA, &images_of(&s), &rows);
    let truth_txt = temp_dir().join("truth_images.txt");
    std::fs::write(&truth_txt, images_txt(&s)).unwrap();
    let truth_bin = temp_dir().join("truth_images.bin");
    std::fs::write(&truth_bin, images_bin(&s)).unwrap();
    let out_txt = temp_dir().join("estimate_images.txt");
    let p = path.to_str().unwrap();
    let out = run(&[
        "multiple",
        p,
        "--json",
        "--ground-truth",
        truth_txt.to_str().unwrap(),
        "--output",
        out_txt.to_str().unwrap(),
    ]);
    assert_success(&out);
    let j = json_of(&out);
    assert_eq!(j["format"], "colmap");
    assert_eq!(j["certificate"]["verdict"], "certified");
    assert_eq!(j["node_names"][3], s.names[3].as_str());
    assert_eq!(j["node_ids"][3], s.ids[3]);
    let mean = j["accuracy"]["mean_deg"].as_f64().expect("accuracy");
    assert!(mean < 1.0, "mean error {mean} deg");
    assert_eq!(j["accuracy"]["num_compared"], 15);
    // The images.txt written reads back: names, ids, and the estimate (world-to-camera).
    let written = load_images(out_txt.to_str().unwrap(), &ReadOptions::default()).unwrap();
    assert_eq!(written.len(), 15);
    let est: Vec<Rotation> = j["estimate"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| {
            let v: Vec<f64> = m
                .as_array()
                .unwrap()
                .iter()
                .flat_map(|r| r.as_array().unwrap().iter().map(|x| x.as_f64().unwrap()))
                .collect();
            Rotation::from_matrix_unchecked(rotavg::nalgebra::Matrix3::from_row_slice(&v))
        })
        .collect();
    for (k, im) in written.iter().enumerate() {
        assert_eq!(
            (im.image_id, im.name.as_str()),
            (s.ids[k], s.names[k].as_str())
        );
        assert!((im.rotation.matrix() - est[k].matrix()).norm() < 1e-12);
        assert_eq!(im.translation, [0.0; 3]);
    }
    let text = std::fs::read_to_string(&out_txt).unwrap();
    assert!(text.contains("translations are not estimated"), "{text}");
    // images.bin as ground truth gives the same accuracy; images.txt as --init starts there.
    let out_bin = run(&[
        "multiple",
        p,
        "--json",
        "--ground-truth",
        truth_bin.to_str().unwrap(),
    ]);
    assert_success(&out_bin);
    let jb = json_of(&out_bin);
    assert!((jb["accuracy"]["mean_deg"].as_f64().unwrap() - mean).abs() < 1e-9);
    let init = run(&["multiple", p, "--json", "--init", out_txt.to_str().unwrap()]);
    assert_success(&init);
    let ji = json_of(&init);
    // started at the optimum: at most one Newton step to confirm it
    assert!(
        ji["solver"]["iterations"].as_u64().unwrap() <= 1,
        "{}",
        ji["solver"]
    );
    // rotavg info describes the database (the folder holding it too)
    let dir = temp_dir().join("info_project");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(&path, dir.join("database.db")).unwrap();
    let info = run(&["info", dir.to_str().unwrap(), "--json"]);
    assert_success(&info);
    let ji = json_of(&info);
    assert_eq!(
        (ji["format"].as_str(), ji["num_rotations"].as_u64()),
        (Some("colmap"), Some(15))
    );
    // --output-format colmap with another name; the text summary names the format.
    let other = temp_dir().join("rotations.txt");
    let text_out = run(&[
        "multiple",
        p,
        "--output",
        other.to_str().unwrap(),
        "--output-format",
        "colmap",
    ]);
    assert_success(&text_out);
    let stdout = String::from_utf8_lossy(&text_out.stdout);
    assert!(stdout.contains("colmap format, 15 nodes"), "{stdout}");
    assert!(stdout.contains("warning: skipped 5 of"), "{stdout}");
    let again = read_images_text(
        &std::fs::read_to_string(&other).unwrap(),
        "rotations.txt",
        &ReadOptions::default(),
    )
    .unwrap();
    assert_eq!(again.len(), 15);
}

#[test]
fn sparse_models_read_in_both_layouts_and_round_trip() {
    let s = scene(7, 5);
    let o = ReadOptions::default();
    let from_txt = read_images_text(&images_txt(&s), "images.txt", &o).unwrap();
    let from_bin = read_images_binary(&images_bin(&s), "images.bin", &o).unwrap();
    assert_eq!(from_txt.len(), 7);
    for (a, b) in from_txt.iter().zip(&from_bin) {
        assert_eq!(
            (a.image_id, &a.name, a.camera_id),
            (b.image_id, &b.name, b.camera_id)
        );
        assert!((a.rotation.matrix() - b.rotation.matrix()).norm() < 1e-15);
        assert_eq!(a.translation, [0.5, -1.25, 3.0]);
    }
    for (k, im) in from_txt.iter().enumerate() {
        assert!((im.rotation.matrix() - s.truth[k].matrix()).norm() < 1e-14);
    }
    // write -> read
    let ids: Vec<u64> = s.ids.iter().map(|&i| u64::from(i)).collect();
    let text = write_images_text(&s.truth, &ids, &s.names).unwrap();
    let back = read_images_text(&text, "images.txt", &o).unwrap();
    for (k, im) in back.iter().enumerate() {
        assert_eq!(
            (im.image_id, im.name.as_str()),
            (s.ids[k], s.names[k].as_str())
        );
        assert!((im.rotation.matrix() - s.truth[k].matrix()).norm() < 1e-15);
    }
}

fn err_of(out: &std::process::Output) -> String {
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stdout)
    );
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn malformed_databases_are_clear_errors() {
    let s = scene(4, 7);
    let images = images_of(&s);
    let o = ReadOptions::default();
    let read = |name: &str, schema: &str, rows: &[Row]| {
        let p = db_path(name);
        write_db(&p, schema, &images, rows);
        read_colmap_database(&p, &o).unwrap_err().to_string()
    };
    let good = |a: usize, b: usize| row(s.ids[a], s.ids[b], &s.truth[a], &s.truth[b], 2);

    // an SQLite file without COLMAP's tables
    let other = db_path("other.db");
    let _ = std::fs::remove_file(&other);
    rusqlite::Connection::open(&other)
        .unwrap()
        .execute_batch("CREATE TABLE images (image_id INTEGER, name TEXT, camera_id INTEGER);")
        .unwrap();
    let e = err_of(&run(&["multiple", other.to_str().unwrap()]));
    assert!(
        e.contains("not a COLMAP database: no table `two_view_geometries`"),
        "{e}"
    );

    // every calibrated row has a NULL qvec
    let mut nulls = vec![good(0, 1), good(1, 2)];
    for r in &mut nulls {
        r.qvec = None;
    }
    let e = read("null_qvec.db", SCHEMA, &nulls);
    assert!(
        e.contains("no relative rotations") && e.contains("2 without a stored relative pose"),
        "{e}"
    );
    assert!(e.contains("compute_relative_pose"), "{e}");

    // an older COLMAP: no qvec / tvec columns
    let old_schema = SCHEMA.replace(", qvec BLOB, tvec BLOB", "");
    let p = db_path("old.db");
    let _ = std::fs::remove_file(&p);
    let db = rusqlite::Connection::open(&p).unwrap();
    db.execute_batch(&old_schema).unwrap();
    drop(db);
    let e = read_colmap_database(&p, &o).unwrap_err().to_string();
    assert!(e.contains("has no column `qvec`"), "{e}");

    // a quaternion that is not a unit one, a blob of the wrong size
    let mut scaled = vec![good(0, 1), good(1, 2)];
    scaled[1].qvec = Some(blob(&[0.5, 0.0, 0.0, 0.0]));
    let e = read("scaled.db", SCHEMA, &scaled);
    let pair = image_pair_to_pair_id(s.ids[1], s.ids[2]);
    assert!(
        e.contains(&format!("pair_id {pair}")) && e.contains("not a rotation"),
        "{e}"
    );
    let mut short = vec![good(0, 1)];
    short[0].qvec = Some(blob(&[1.0, 0.0, 0.0]));
    let e = read("short.db", SCHEMA, &short);
    assert!(
        e.contains("blob of 24 bytes") || e.contains("expected a blob of 32 bytes"),
        "{e}"
    );

    // an image the table images does not have
    let mut ghost = vec![good(0, 1)];
    ghost.push(row(s.ids[2], 999, &s.truth[2], &s.truth[3], 2));
    let e = read("ghost.db", SCHEMA, &ghost);
    assert!(
        e.contains("image_id 999 is not in the table `images`"),
        "{e}"
    );

    // not an SQLite file with --format colmap; a database given as text on stdin
    let txt = common::temp_file("plain.txt", "0 1 1 0 0 0 1 0 0 0 1\n");
    let e = err_of(&run(&[
        "multiple",
        txt.to_str().unwrap(),
        "--format",
        "colmap",
    ]));
    assert!(e.contains("plain.txt"), "{e}");
}

#[test]
fn malformed_sparse_models_are_clear_errors() {
    let s = scene(3, 9);
    let o = ReadOptions::default();
    let bin = images_bin(&s);
    // truncated in the middle of the second image
    let e = read_images_binary(&bin[..bin.len() - 30], "images.bin", &o)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("images.bin: byte ") && e.contains("truncated"),
        "{e}"
    );
    // a header claiming 10^12 images in a file of 100 bytes: refused before any allocation
    let mut huge = 1_000_000_000_000u64.to_le_bytes().to_vec();
    huge.extend([0u8; 92]);
    let e = read_images_binary(&huge, "images.bin", &o)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("claims 1000000000000 images") && e.contains("at most 1"),
        "{e}"
    );
    // a point count beyond the file
    let mut points = 1u64.to_le_bytes().to_vec();
    points.extend(&bin[8..8 + 4 + 56 + 4]);
    points.extend(b"x\0");
    points.extend(u64::MAX.to_le_bytes());
    let e = read_images_binary(&points, "images.bin", &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("2-D points") && e.contains("truncated"), "{e}");
    // the bytes they need, exactly (24 x 2^64 - 24, not saturated at 2^64 - 1)
    assert!(
        e.contains(&format!("need {} bytes", u128::from(u64::MAX) * 24)),
        "{e}"
    );
    // one line per image, no points lines: the second image line is not a points line
    let e = read_images_text(
        "1 1 0 0 0 0 0 0 1 a.jpg\n2 1 0 0 0 0 0 0 1 b.jpg\n",
        "images.txt",
        &o,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.starts_with("images.txt:2: ") && e.contains("points line of image 1"),
        "{e}"
    );
    // an image named twice, and an id used twice
    for (text, what) in [
        (
            "1 1 0 0 0 0 0 0 1 a.jpg\n\n2 1 0 0 0 0 0 0 1 a.jpg\n\n",
            "name `a.jpg`",
        ),
        (
            "1 1 0 0 0 0 0 0 1 a.jpg\n\n1 1 0 0 0 0 0 0 1 b.jpg\n\n",
            "image_id 1",
        ),
    ] {
        let e = read_images_text(text, "images.txt", &o)
            .unwrap_err()
            .to_string();
        assert!(e.contains(what) && e.contains("more than once"), "{e}");
    }
    // a zero quaternion (text and binary)
    let e = read_images_text("1 0 0 0 0 0 0 0 1 a.jpg\n\n", "images.txt", &o)
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("images.txt:1: image 1: quaternion") && e.contains("norm 0.000e0"),
        "{e}"
    );
    let mut zero = bin.clone();
    zero[12..44].fill(0);
    let e = read_images_binary(&zero, "images.bin", &o)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("byte 8: image 0") && e.contains("not a rotation"),
        "{e}"
    );
    // a short image line
    let e = read_images_text("1 1 0 0 0 0 0 0 1\n\n", "images.txt", &o)
        .unwrap_err()
        .to_string();
    assert!(e.contains("images.txt:1: expected IMAGE_ID"), "{e}");
    // the command line names the file of a bad --ground-truth / --init
    let db = db_path("for_models.db");
    let (rows, _) = rows(&s, 0.0, 1);
    write_db(&db, SCHEMA, &images_of(&s), &rows);
    let truncated = temp_dir().join("bad_images.bin");
    std::fs::write(&truncated, &bin[..20]).unwrap();
    let e = err_of(&run(&[
        "multiple",
        db.to_str().unwrap(),
        "--ground-truth",
        truncated.to_str().unwrap(),
    ]));
    assert!(e.contains("bad_images.bin: byte"), "{e}");
    // an --init model that lacks one of the graph's images
    let partial = temp_dir().join("partial_images.txt");
    let mut short_scene = scene(3, 9);
    short_scene.ids.pop();
    short_scene.names.pop();
    short_scene.truth.pop();
    std::fs::write(&partial, images_txt(&short_scene)).unwrap();
    let e = err_of(&run(&[
        "multiple",
        db.to_str().unwrap(),
        "--init",
        partial.to_str().unwrap(),
    ]));
    // the one estimate loader (issue 27): the file, the node, how it was matched
    assert!(
        e.contains(
            "1 of 3 nodes have no rotation in the file (COLMAP images.txt, matched by image name)"
        ),
        "{e}"
    );
}
