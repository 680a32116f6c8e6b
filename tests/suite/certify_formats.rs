//! `rotavg certify --estimate` in every estimate format rotavg reads or writes (issue 27,
//! item 1), and the library's `load_estimate_for`: planted rotations written here in g2o,
//! COLMAP `images.txt` / `images.bin` / a sparse model folder, JSON with node ids, Bundler,
//! rotation lists, in shuffled order and with ids (or names) that differ from the problem's node
//! indices; the estimate certify reports is compared with the planted rotations node by node.
//! Errors: a node missing, names that match nothing, a non-rotation, a database without poses,
//! a folder of models.

use crate::common;

use common::{json_of, run, temp_dir};
use rotavg::Rotation;
use rotavg::io::colmap::image_pair_to_pair_id;
use rotavg::io::detect::{GraphFormat, ReadOptions, load_graph};
use rotavg::io::input::{EstimateFormat, MatchedBy, load_estimate_for};
use rotavg::rand::{SeedableRng, rngs::StdRng};
use rotavg::so3::{angle_between, perturb, random_rotation, to_quaternion};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// A planted scene: sparse file ids, image names, world-to-camera rotations `R_k`, translations,
/// and the edges of a connected graph (a chain plus chords).
struct Scene {
    ids: Vec<u32>,
    names: Vec<String>,
    truth: Vec<Rotation>,
    translations: Vec<[f64; 3]>,
    edges: Vec<(usize, usize)>,
}

fn scene(n: usize, seed: u64) -> Scene {
    let mut rng = StdRng::seed_from_u64(seed);
    let ids: Vec<u32> = (0..n as u32).map(|k| 5 + 7 * k).collect();
    let mut edges: Vec<(usize, usize)> = (0..n - 1).map(|k| (k, k + 1)).collect();
    edges.extend((0..n).filter(|k| k + 3 < n).map(|k| (k, k + 3)));
    Scene {
        names: (0..n).map(|k| format!("cam/img_{k:03}.jpg")).collect(),
        truth: (0..n).map(|_| random_rotation(&mut rng)).collect(),
        translations: (0..n)
            .map(|k| [k as f64, 0.5 * k as f64, -(k as f64)])
            .collect(),
        ids,
        edges,
    }
}

/// A permutation of `0..n` (a fixed shuffle).
fn shuffled(n: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).collect();
    let mut rng = StdRng::seed_from_u64(99);
    use rotavg::rand::seq::SliceRandom;
    order.shuffle(&mut rng);
    assert_ne!(order, (0..n).collect::<Vec<_>>());
    order
}

/// g2o quaternion `qx qy qz qw` of a rotation.
fn g2o_quat(r: &Rotation) -> String {
    let q = to_quaternion(r);
    format!("{} {} {} {}", q.i, q.j, q.k, q.w)
}

/// The problem as g2o: node `k` is vertex id `ids[k]`; the edge `(a, b)` measures
/// `Z = W_a^T W_b` with `W = R^T` (g2o's convention, paper-notes [F1]), exactly.
fn g2o_problem(s: &Scene) -> String {
    let mut text = String::new();
    for &(a, b) in &s.edges {
        let z = s.truth[a] * s.truth[b].inverse();
        let _ = writeln!(
            text,
            "EDGE_SE3:QUAT {} {} 1 0 0 {} 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1",
            s.ids[a],
            s.ids[b],
            g2o_quat(&z)
        );
    }
    text
}

/// The estimate `est` as COLMAP images lines in the order `order` (world-to-camera `qvec`).
fn images_txt(s: &Scene, est: &[Rotation], order: &[usize], ids: &[u32]) -> String {
    let mut t = String::from(
        "# Image list with two lines of data per image:\n#   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n",
    );
    for &k in order {
        let q = to_quaternion(&est[k]);
        let [x, y, z] = s.translations[k];
        let _ = writeln!(
            t,
            "{} {} {} {} {} {x} {y} {z} 1 {}\n",
            ids[k], q.w, q.i, q.j, q.k, s.names[k]
        );
    }
    t
}

/// The same as COLMAP's `images.bin`.
fn images_bin(s: &Scene, est: &[Rotation], order: &[usize], ids: &[u32]) -> Vec<u8> {
    let mut b = (order.len() as u64).to_le_bytes().to_vec();
    for &k in order {
        b.extend(ids[k].to_le_bytes());
        let q = to_quaternion(&est[k]);
        let t = s.translations[k];
        for v in [q.w, q.i, q.j, q.k, t[0], t[1], t[2]] {
            b.extend(v.to_le_bytes());
        }
        b.extend(1u32.to_le_bytes());
        b.extend(s.names[k].as_bytes());
        b.push(0);
        b.extend(1u64.to_le_bytes()); // one 2-D point
        b.extend(1.5f64.to_le_bytes());
        b.extend(2.5f64.to_le_bytes());
        b.extend(u64::MAX.to_le_bytes());
    }
    b
}

/// A COLMAP database of the scene (images `ids` named `names`, exact relative rotations).
fn database(path: &Path, s: &Scene) {
    let _ = std::fs::remove_file(path);
    let db = rusqlite::Connection::open(path).unwrap();
    db.execute_batch(
        "CREATE TABLE cameras (camera_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, model INTEGER NOT NULL, width INTEGER NOT NULL, height INTEGER NOT NULL, params BLOB, prior_focal_length INTEGER NOT NULL);
         CREATE TABLE images (image_id INTEGER PRIMARY KEY AUTOINCREMENT NOT NULL, name TEXT NOT NULL UNIQUE, camera_id INTEGER NOT NULL);
         CREATE TABLE two_view_geometries (pair_id INTEGER PRIMARY KEY NOT NULL, rows INTEGER NOT NULL, cols INTEGER NOT NULL, data BLOB, config INTEGER NOT NULL, F BLOB, E BLOB, H BLOB, qvec BLOB, tvec BLOB);",
    )
    .unwrap();
    let blob = |v: &[f64]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
    db.execute(
        "INSERT INTO cameras VALUES (1, 1, 640, 480, ?1, 0)",
        [blob(&[500.0, 510.0, 320.0, 240.0])],
    )
    .unwrap();
    for k in 0..s.ids.len() {
        db.execute(
            "INSERT INTO images VALUES (?1, ?2, 1)",
            rusqlite::params![s.ids[k], s.names[k]],
        )
        .unwrap();
    }
    for &(a, b) in &s.edges {
        let (a, b) = if s.ids[a] < s.ids[b] { (a, b) } else { (b, a) };
        let rel = s.truth[b] * s.truth[a].inverse(); // cam2_from_cam1
        let q = to_quaternion(&rel);
        db.execute(
            "INSERT INTO two_view_geometries VALUES (?1, 0, 2, NULL, 2, NULL, NULL, NULL, ?2, ?3)",
            rusqlite::params![
                image_pair_to_pair_id(s.ids[a], s.ids[b]) as i64,
                blob(&[q.w, q.i, q.j, q.k]),
                blob(&[0.0, 0.0, 1.0])
            ],
        )
        .unwrap();
    }
}

fn write(name: &str, bytes: impl AsRef<[u8]>) -> PathBuf {
    let p = temp_dir().join(name);
    if let Some(d) = p.parent() {
        std::fs::create_dir_all(d).unwrap();
    }
    std::fs::write(&p, bytes).unwrap();
    p
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The estimate of a `--json` report, node by node.
fn estimate_of(v: &serde_json::Value) -> Vec<Rotation> {
    v["estimate"]
        .as_array()
        .expect("estimate")
        .iter()
        .map(|m| {
            let rows: [[f64; 3]; 3] = serde_json::from_value(m.clone()).unwrap();
            Rotation::from_matrix_unchecked(rotavg::nalgebra::Matrix3::from_fn(|a, b| rows[a][b]))
        })
        .collect()
}

/// `rotavg certify PROBLEM --estimate EST --json`: the report, after checking that the
/// estimate certify used is `expected` node by node and its cost the problem's cost there.
fn certify_matches(problem: &Path, estimate: &Path, expected: &[Rotation]) -> serde_json::Value {
    let out = run(&["certify", s(problem), "--estimate", s(estimate), "--json"]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = json_of(&out);
    let got = estimate_of(&v);
    assert_eq!(got.len(), expected.len());
    for (k, (a, b)) in got.iter().zip(expected).enumerate() {
        assert!(
            angle_between(a, b) < 1e-9,
            "node {k}: {}",
            angle_between(a, b)
        );
    }
    let graph = load_graph(problem, GraphFormat::Auto, &ReadOptions::default()).unwrap();
    let cost = graph.problem.chordal_cost(expected);
    let reported = v["cost"].as_f64().unwrap();
    assert!(
        (reported - cost).abs() <= 1e-9 * (1.0 + cost),
        "{reported} vs {cost}"
    );
    v
}

/// The planted rotations with node 2 turned by 0.3 rad: not optimal, cost > 0.
fn perturbed(s: &Scene) -> Vec<Rotation> {
    let mut est = s.truth.clone();
    let mut rng = StdRng::seed_from_u64(3);
    est[2] = perturb(&est[2], 0.3, &mut rng);
    est
}

#[test]
fn certifies_g2o_vertices_matched_by_id_in_any_order() {
    let sc = scene(12, 1);
    let problem = write("g/problem.g2o", g2o_problem(&sc));
    // the exact rotations: certified at cost 0
    let order = shuffled(12);
    let mut est = String::from("# an estimate from another tool: vertices in another order\n");
    for &k in &order {
        let [x, y, z] = sc.translations[k];
        let _ = writeln!(
            est,
            "VERTEX_SE3:QUAT {} {x} {y} {z} {}",
            sc.ids[k],
            g2o_quat(&sc.truth[k].inverse())
        );
    }
    let exact = write("g/exact.g2o", &est);
    let v = certify_matches(&problem, &exact, &sc.truth);
    assert_eq!(v["certificate"]["verdict"], "certified");
    assert!(v["cost"].as_f64().unwrap() < 1e-12);
    // a perturbed estimate with the problem's edges after it (GTSAM writes both): node 2 moved
    let bad = perturbed(&sc);
    let mut est = String::new();
    for &k in order.iter().rev() {
        let _ = writeln!(
            est,
            "VERTEX_SE3:QUAT {} 0 0 0 {}",
            sc.ids[k],
            g2o_quat(&bad[k].inverse())
        );
    }
    est.push_str(&g2o_problem(&sc));
    let perturbed_file = write("g/perturbed.g2o", &est);
    let v = certify_matches(&problem, &perturbed_file, &bad);
    assert!(v["cost"].as_f64().unwrap() > 0.01);
    assert_ne!(v["certificate"]["verdict"], "certified");
    // the library function says what it read
    let graph = load_graph(&problem, GraphFormat::Auto, &ReadOptions::default()).unwrap();
    let e = load_estimate_for(s(&perturbed_file), &graph, &ReadOptions::default()).unwrap();
    assert_eq!(
        (e.format, e.matched_by, e.unmatched.len()),
        (EstimateFormat::G2o, MatchedBy::Id, 0)
    );
}

#[test]
fn certifies_colmap_text_binary_and_model_folders() {
    let sc = scene(10, 2);
    // a g2o problem whose vertex ids are the COLMAP image ids
    let problem = write("c/problem.g2o", g2o_problem(&sc));
    let order = shuffled(10);
    let est = perturbed(&sc);
    let txt = write("c/images.txt", images_txt(&sc, &est, &order, &sc.ids));
    certify_matches(&problem, &txt, &est);
    let bin = write("c/bin/images.bin", images_bin(&sc, &est, &order, &sc.ids));
    certify_matches(&problem, &bin, &est);
    // a text model folder (cameras, images, points3D) and a binary one (binary wins)
    let folder = temp_dir().join("c/model_txt");
    write(
        "c/model_txt/images.txt",
        images_txt(&sc, &est, &order, &sc.ids),
    );
    write(
        "c/model_txt/cameras.txt",
        "1 PINHOLE 640 480 500 500 320 240\n",
    );
    write("c/model_txt/points3D.txt", "");
    certify_matches(&problem, &folder, &est);
    // the header names the estimate's file (its own line when the text is wrapped at 100
    // characters; after `; ` in the --verbose one-line form)
    let text = run(&["certify", s(&problem), "--estimate", s(&folder)]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(text.contains(&format!("estimate {}", s(&folder))), "{text}");
    let text = run(&[
        "certify",
        s(&problem),
        "--estimate",
        s(&folder),
        "--verbose",
    ]);
    let text = String::from_utf8_lossy(&text.stdout);
    assert!(
        text.contains(&format!("; estimate {}", s(&folder))),
        "{text}"
    );
    let bin_folder = temp_dir().join("c/model_bin");
    write(
        "c/model_bin/images.bin",
        images_bin(&sc, &sc.truth, &order, &sc.ids),
    );
    write(
        "c/model_bin/images.txt",
        images_txt(&sc, &est, &order, &sc.ids),
    );
    let v = certify_matches(&problem, &bin_folder, &sc.truth);
    assert_eq!(v["certificate"]["verdict"], "certified");
    // a folder of models: which one?
    write(
        "c2/sparse/0/images.txt",
        images_txt(&sc, &est, &order, &sc.ids),
    );
    write(
        "c2/sparse/1/images.bin",
        images_bin(&sc, &est, &order, &sc.ids),
    );
    let out = run(&[
        "certify",
        s(&problem),
        "--estimate",
        s(&temp_dir().join("c2/sparse")),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("holds the sparse models 0, 1: give one of them"),
        "{err}"
    );
    // cameras.txt holds no poses
    let out = run(&[
        "certify",
        s(&problem),
        "--estimate",
        s(&folder.join("cameras.txt")),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("holds no image poses"), "{err}");
}

#[test]
fn certifies_a_database_problem_against_a_model_matched_by_name() {
    let sc = scene(9, 4);
    let db = temp_dir().join("d/database.db");
    std::fs::create_dir_all(db.parent().unwrap()).unwrap();
    database(&db, &sc);
    // the model numbers its images differently (as a new reconstruction does) and lists
    // them shuffled: only the names match
    let order = shuffled(9);
    let other_ids: Vec<u32> = (0..9).map(|k| 1000 - 10 * k as u32).collect();
    let est = perturbed(&sc);
    let model = temp_dir().join("d/sparse/0");
    write(
        "d/sparse/0/images.bin",
        images_bin(&sc, &est, &order, &other_ids),
    );
    // the node order of the database graph: images sorted by id, as the planted scene
    let v = certify_matches(&db, &model, &est);
    assert_eq!(v["node_ids"][3], sc.ids[3]);
    // the folder holding database.db is the problem too
    certify_matches(db.parent().unwrap(), &model, &est);
    // the library: matched by name
    let graph = load_graph(&db, GraphFormat::Auto, &ReadOptions::default()).unwrap();
    let e = load_estimate_for(s(&model), &graph, &ReadOptions::default()).unwrap();
    assert_eq!(
        (e.format, e.matched_by),
        (EstimateFormat::ColmapBinary, MatchedBy::Name)
    );
    // an extra image in the model: used nowhere, reported on a `warning:` line (and in the
    // JSON's warnings)
    let mut extra = images_txt(&sc, &est, &order, &other_ids);
    extra.push_str("77 1 0 0 0 0 0 0 1 cam/unknown.jpg\n\n");
    let extra = write("d/extra/images.txt", extra);
    let out = run(&["certify", s(&db), "--estimate", s(&extra)]);
    let text = String::from_utf8_lossy(&out.stdout)
        .split_whitespace()
        .collect::<Vec<_>>()
        .join(" ");
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.contains("warning:")
            && text.contains("1 entries (COLMAP images.txt) match no node")
            && text.contains("cam/unknown.jpg"),
        "{text}"
    );
    // names that match nothing: an error naming the file, the nodes, and a name of the file
    let renamed = images_txt(&sc, &est, &order, &other_ids).replace("cam/", "other/");
    let renamed = write("d/renamed/images.txt", renamed);
    let out = run(&["certify", s(&db), "--estimate", s(&renamed)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(s(&renamed))
            && err.contains("9 of 9 nodes have no rotation")
            && err.contains("matched by image name")
            && err.contains("name other/img_"),
        "{err}"
    );
    // the database itself holds no estimated poses: a clear refusal
    let out = run(&["certify", s(&db), "--estimate", s(&db)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("holds no estimated camera poses"), "{err}");
}

/// pycolmap's rotation averaging writes a model whose translations are NaN: its rotations are
/// certified in one line, the translations reported (issue 38) and never used.
#[test]
fn models_with_nan_translations_are_certified_with_a_warning() {
    let mut sc = scene(9, 6);
    let db = temp_dir().join("nan/database.db");
    std::fs::create_dir_all(db.parent().unwrap()).unwrap();
    database(&db, &sc);
    sc.translations = vec![[f64::NAN; 3]; 9];
    let order = shuffled(9);
    let est = perturbed(&sc);
    let bin = write(
        "nan/sparse/0/images.bin",
        images_bin(&sc, &est, &order, &sc.ids),
    );
    // C++ streams write `nan`, Rust `NaN`: both are read
    let txt = write(
        "nan/sparse/1/images.txt",
        images_txt(&sc, &est, &order, &sc.ids).replace("NaN", "nan"),
    );
    for model in [bin, txt] {
        let v = certify_matches(&db, &model, &est);
        // `certify` reads a database with weights 1 unless `--information full`: no warning
        let w = v["warnings"].as_array().unwrap();
        assert_eq!(w.len(), 1, "{w:?}");
        assert_eq!(w[0]["code"], "translations_not_finite");
        assert_eq!(w[0]["count"], 9);
        assert!(v["certificate"]["lower_bound"].is_number());
    }
    // a NaN rotation is still an error naming the file
    let text = images_txt(&sc, &est, &order, &sc.ids);
    let first = text
        .lines()
        .find(|l| !l.starts_with('#') && !l.is_empty())
        .unwrap();
    let mut toks: Vec<&str> = first.split(' ').collect();
    toks[1] = "nan"; // QW
    let bad = write(
        "nan/sparse/2/images.txt",
        text.replace(first, &toks.join(" ")),
    );
    let out = run(&["certify", s(&db), "--estimate", s(&bad)]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("images.txt"));
}

#[test]
fn certifies_json_with_ids_bundler_and_rotation_lists() {
    let sc = scene(8, 5);
    let problem = write("j/problem.g2o", g2o_problem(&sc));
    let est = perturbed(&sc);
    let rows = |r: &Rotation| {
        let m = r.matrix();
        format!(
            "[[{},{},{}],[{},{},{}],[{},{},{}]]",
            m[(0, 0)],
            m[(0, 1)],
            m[(0, 2)],
            m[(1, 0)],
            m[(1, 1)],
            m[(1, 2)],
            m[(2, 0)],
            m[(2, 1)],
            m[(2, 2)]
        )
    };
    // rotavg's own --output: node ids, here shuffled
    let order = shuffled(8);
    let ids: Vec<String> = order.iter().map(|&k| sc.ids[k].to_string()).collect();
    let rs: Vec<String> = order.iter().map(|&k| rows(&est[k])).collect();
    let json = write(
        "j/est.json",
        format!(
            "{{\"node_ids\": [{}], \"rotations\": [{}]}}",
            ids.join(","),
            rs.join(",")
        ),
    );
    certify_matches(&problem, &json, &est);
    // a rotation list `id R11 .. R33`, shuffled
    let mut list = String::new();
    for &k in &order {
        let m = est[k].matrix();
        let _ = writeln!(
            list,
            "{} {}",
            sc.ids[k],
            (0..9)
                .map(|e| m[(e / 3, e % 3)].to_string())
                .collect::<Vec<_>>()
                .join(" ")
        );
    }
    let list_file = write("j/rotations.txt", &list);
    certify_matches(&problem, &list_file, &est);
    // Bundler: camera index = id; cameras the problem does not have are zero (unknown)
    let max = *sc.ids.iter().max().unwrap() as usize;
    let mut out = format!("# Bundle file v0.3\n{} 0\n", max + 1);
    for id in 0..=max {
        let r = sc
            .ids
            .iter()
            .position(|&i| i as usize == id)
            .map(|k| *est[k].matrix())
            .unwrap_or_else(rotavg::nalgebra::Matrix3::zeros);
        let _ = writeln!(out, "500 0 0");
        for a in 0..3 {
            let _ = writeln!(out, "{} {} {}", r[(a, 0)], r[(a, 1)], r[(a, 2)]);
        }
        let _ = writeln!(out, "0 0 0");
    }
    let bundler = write("j/bundle.out", &out);
    certify_matches(&problem, &bundler, &est);
}

#[test]
fn estimate_errors_name_the_file_the_line_and_the_nodes() {
    let sc = scene(6, 6);
    let problem = write("e/problem.g2o", g2o_problem(&sc));
    let order: Vec<usize> = (0..6).collect();
    // a node missing: the file and the node (index, id)
    let mut est = String::new();
    for k in 0..5 {
        let _ = writeln!(
            est,
            "VERTEX_SE3:QUAT {} 0 0 0 {}",
            sc.ids[k],
            g2o_quat(&sc.truth[k].inverse())
        );
    }
    let missing = write("e/missing.g2o", &est);
    let out = run(&["certify", s(&problem), "--estimate", s(&missing)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!(
            "{}: estimate: 1 of 6 nodes have no rotation in the file (g2o vertex lines, matched by id): node 5 (id {})",
            s(&missing),
            sc.ids[5]
        )),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    // a quaternion that is not a unit one: file and line
    let text = images_txt(&sc, &sc.truth, &order, &sc.ids);
    let line_of_third = text
        .lines()
        .position(|l| l.starts_with(&format!("{} ", sc.ids[2])))
        .unwrap()
        + 1;
    let broken: Vec<String> = text
        .lines()
        .map(|l| {
            if l.starts_with(&format!("{} ", sc.ids[2])) {
                let mut t: Vec<&str> = l.split(' ').collect();
                t[1] = "3";
                t.join(" ")
            } else {
                l.to_string()
            }
        })
        .collect();
    let broken = write("e/images.txt", broken.join("\n") + "\n");
    let out = run(&["certify", s(&problem), "--estimate", s(&broken)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(&format!("{}:{line_of_third}:", s(&broken))) && err.contains("not a rotation"),
        "{err}"
    );
    // a JSON list of the wrong length
    let short = write(
        "e/short.json",
        r#"{"rotations": [[[1,0,0],[0,1,0],[0,0,1]]]}"#,
    );
    let out = run(&["certify", s(&problem), "--estimate", s(&short)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("the file has 1 rotations, the problem has 6 nodes"),
        "{err}"
    );
    // images.bin whose header claims more images than the file holds: refused, no allocation
    let mut bin = images_bin(&sc, &sc.truth, &order, &sc.ids);
    bin[..8].copy_from_slice(&(1u64 << 60).to_le_bytes());
    let bin = write("e/images.bin", bin);
    let out = run(&["certify", s(&problem), "--estimate", s(&bin)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("claims 1152921504606846976 images"), "{err}");
}

#[test]
fn init_and_ground_truth_read_the_same_formats() {
    let sc = scene(10, 7);
    let problem = write("i/problem.g2o", g2o_problem(&sc));
    let order = shuffled(10);
    let model = temp_dir().join("i/model");
    write(
        "i/model/images.bin",
        images_bin(&sc, &sc.truth, &order, &sc.ids),
    );
    let mut gt = String::new();
    for &k in &order {
        let _ = writeln!(
            gt,
            "VERTEX_SE3:QUAT {} 0 0 0 {}",
            sc.ids[k],
            g2o_quat(&sc.truth[k].inverse())
        );
    }
    let gt = write("i/truth.g2o", &gt);
    let out = run(&[
        "multiple",
        s(&problem),
        "--json",
        "--init",
        s(&model),
        "--ground-truth",
        s(&gt),
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = json_of(&out);
    assert_eq!(v["accuracy"]["num_compared"], 10);
    assert!(v["accuracy"]["max_deg"].as_f64().unwrap() < 1e-6);
    assert!(v["solver"]["iterations"].as_u64().unwrap() <= 1);
}

// ---- outputs that round-trip (issue 27, item 3) ----

/// The repository's example SLAM graph.
fn slam_g2o() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("examples/data/slam.g2o")
}

#[test]
fn g2o_output_keeps_the_input_translations_and_edges() {
    use rotavg::io::g2o::{read_g2o, read_g2o_vertices};
    let input = slam_g2o();
    let out_file = temp_dir().join("rt/new/folder/slam_out.g2o"); // folders created
    let out = run(&["multiple", s(&input), "--json", "--output", s(&out_file)]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = json_of(&out);
    let est = estimate_of(&v);
    let (text_in, text_out) = (
        std::fs::read_to_string(&input).unwrap(),
        std::fs::read_to_string(&out_file).unwrap(),
    );
    let o = ReadOptions::default();
    let (vin, vout) = (
        read_g2o_vertices(&text_in, "in", &o).unwrap(),
        read_g2o_vertices(&text_out, "out", &o).unwrap(),
    );
    assert_eq!(vin.len(), 400);
    assert_eq!(vout.len(), 400);
    // every vertex keeps its id and its translation, as written in the input
    let tokens = |text: &str| -> Vec<Vec<String>> {
        text.lines()
            .filter(|l| l.starts_with("VERTEX"))
            .map(|l| l.split_whitespace().take(5).map(str::to_string).collect())
            .collect()
    };
    assert_eq!(tokens(&text_in), tokens(&text_out));
    // every other line (edges, comments) as read, in order
    let others = |text: &str| -> Vec<String> {
        text.lines()
            .filter(|l| !l.starts_with("VERTEX"))
            .map(str::to_string)
            .collect()
    };
    assert_eq!(others(&text_in), others(&text_out));
    // read back as a problem: the same edges
    let (gin, gout) = (
        read_g2o(&text_in, "in", &o).unwrap(),
        read_g2o(&text_out, "out", &o).unwrap(),
    );
    assert_eq!(gin.problem, gout.problem);
    assert_eq!(gin.node_ids, gout.node_ids);
    // the vertex rotations are the estimate (up to one global rotation), at the same cost
    let written = gout.initial.unwrap();
    let g = est[0].inverse() * written[0];
    for k in 0..400 {
        assert!(angle_between(&(est[k] * g), &written[k]) < 1e-9, "node {k}");
    }
    let cost = v["cost"].as_f64().unwrap();
    assert!((gout.problem.chordal_cost(&written) - cost).abs() < 1e-9 * (1.0 + cost));
    // and turned into the input's frame: closer to the input's vertex rotations (least
    // squares) than the estimate with R_0 = I or anchored at the input's node 0
    let misfit = |rs: &[Rotation]| -> f64 {
        rs.iter()
            .zip(&vin)
            .map(|(r, v)| (r.matrix() - v.rotation.matrix()).norm_squared())
            .sum()
    };
    let anchor = est[0].inverse() * vin[0].rotation;
    let anchored: Vec<Rotation> = est.iter().map(|r| r * anchor).collect();
    let best = misfit(&written);
    assert!(
        best <= misfit(&est) && best <= misfit(&anchored) + 1e-9,
        "{best}"
    );
    assert!(best < misfit(&est) - 1.0, "{best} vs {}", misfit(&est));
    // rotavg certify reads its own output back
    let c = run(&["certify", s(&input), "--estimate", s(&out_file), "--json"]);
    assert_eq!(json_of(&c)["certificate"]["verdict"], "certified");
}

#[test]
fn planar_and_toro_g2o_outputs_keep_their_vertex_types() {
    use rotavg::io::g2o::read_g2o;
    // a planar square with a diagonal (VERTEX_SE2 / EDGE_SE2), headings with noise
    let se2 = "VERTEX_SE2 0 0 0 0\nVERTEX_SE2 1 1 0 1.5\nVERTEX_SE2 2 1 1 3.2\nVERTEX_SE2 3 0 1 -1.6\n\
               EDGE_SE2 0 1 1 0 1.55 1 0 0 1 0 10\nEDGE_SE2 1 2 1 0 1.6 1 0 0 1 0 10\n\
               EDGE_SE2 2 3 1 0 1.5 1 0 0 1 0 10\nEDGE_SE2 3 0 1 0 1.62 1 0 0 1 0 10\n\
               EDGE_SE2 0 2 1 1 3.1 1 0 0 1 0 10\n";
    // TORO: VERTEX3 for nodes 0, 1; node 2 has no vertex line
    let toro = "VERTEX3 0 0 0 0 0 0 0\nVERTEX3 1 5 6 7 0.1 0.2 0.3\n\
                EDGE3 0 1 1 0 0 0.1 0.2 0.3\nEDGE3 1 2 1 0 0 0 0 0.2\nEDGE3 2 0 1 0 0 -0.1 -0.2 -0.5\n";
    for (name, text, vertex, lines) in [
        ("rt/square.g2o", se2, "VERTEX_SE2", 4),
        ("rt/toro.g2o", toro, "VERTEX3", 3),
    ] {
        let input = write(name, text);
        let out_file = temp_dir().join(format!("{name}.out.g2o"));
        let out = run(&["multiple", s(&input), "--json", "--output", s(&out_file)]);
        assert_eq!(
            out.status.code(),
            Some(0),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let est = estimate_of(&json_of(&out));
        let written = std::fs::read_to_string(&out_file).unwrap();
        assert_eq!(
            written.lines().filter(|l| l.starts_with(vertex)).count(),
            lines,
            "{written}"
        );
        let o = ReadOptions::default();
        let back = read_g2o(&written, "out", &o).unwrap();
        assert_eq!(back.problem, read_g2o(text, "in", &o).unwrap().problem);
        let w = back.initial.unwrap();
        let g = est[0].inverse() * w[0];
        for k in 0..est.len() {
            assert!(
                angle_between(&(est[k] * g), &w[k]) < 1e-9,
                "{name}: node {k}"
            );
        }
    }
    let toro_out = std::fs::read_to_string(temp_dir().join("rt/toro.g2o.out.g2o")).unwrap();
    assert!(toro_out.contains("VERTEX3 1 5 6 7 "), "{toro_out}");
    // the vertex the input lacked comes first (g2o needs vertices before edges), at 0
    assert!(toro_out.starts_with("VERTEX3 2 0 0 0 "), "{toro_out}");
}

#[test]
fn colmap_output_is_a_loadable_sparse_model_with_the_database_cameras() {
    use rotavg::io::colmap::load_images;
    let sc = scene(9, 8);
    let db = temp_dir().join("m/database.db");
    std::fs::create_dir_all(db.parent().unwrap()).unwrap();
    database(&db, &sc);
    let model = temp_dir().join("m/not/yet/sparse/0");
    let model_arg = format!("{}/", s(&model));
    let out = run(&["multiple", s(&db), "--json", "--output", &model_arg]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let est = estimate_of(&json_of(&out));
    let images = load_images(s(&model.join("images.txt")), &ReadOptions::default()).unwrap();
    assert_eq!(images.len(), 9);
    for (k, im) in images.iter().enumerate() {
        assert_eq!(
            (im.image_id, im.name.as_str(), im.camera_id),
            (sc.ids[k], sc.names[k].as_str(), 1)
        );
        assert!(angle_between(&im.rotation, &est[k]) < 1e-12);
    }
    let cameras = std::fs::read_to_string(model.join("cameras.txt")).unwrap();
    assert!(
        cameras
            .lines()
            .any(|l| l == "1 PINHOLE 640 480 500 510 320 240"),
        "{cameras}"
    );
    let points = std::fs::read_to_string(model.join("points3D.txt")).unwrap();
    assert!(points.lines().all(|l| l.starts_with('#')), "{points}");
    // certify reads the model back: the database problem, matched by name
    let c = run(&["certify", s(&db), "--estimate", s(&model), "--json"]);
    assert_eq!(json_of(&c)["certificate"]["verdict"], "certified");
    // an input without cameras: a documented placeholder camera; `images.txt` as the path
    let graph = write("m/p.g2o", g2o_problem(&sc));
    let images_path = temp_dir().join("m/other/images.txt");
    let out = run(&["multiple", s(&graph), "--output", s(&images_path)]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let cameras = std::fs::read_to_string(temp_dir().join("m/other/cameras.txt")).unwrap();
    assert!(
        cameras.contains("placeholder camera")
            && cameras.contains("\n1 SIMPLE_PINHOLE 1 1 1 0.5 0.5\n"),
        "{cameras}"
    );
    assert!(temp_dir().join("m/other/points3D.txt").is_file());
}

#[test]
fn output_problems_are_refused_before_the_input_is_read() {
    // the input does not exist: an output error shows the output was checked first
    let blocker = write("o/a_file", "x");
    let under_file = format!("{}/sub/est.json", s(&blocker));
    let out = run(&["multiple", "no/such/input.g2o", "--output", &under_file]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("cannot create the output folder"), "{err}");
    assert!(!err.contains("no/such/input"), "{err}");
    let folder = format!("{}/", s(&temp_dir().join("o/model")));
    let out = run(&[
        "multiple",
        "no/such/input.g2o",
        "--output",
        &folder,
        "--output-format",
        "g2o",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("give a file name"), "{err}");
    // g2o from standard input cannot be re-read for a g2o output: refused
    let text = std::fs::read_to_string(slam_g2o()).unwrap();
    let g2o_out = temp_dir().join("o/stdin.g2o");
    let out = common::run_with_stdin(
        &["multiple", "-", "--format", "g2o", "--output", s(&g2o_out)],
        &text,
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("cannot be read again from standard input"),
        "{err}"
    );
    assert!(!g2o_out.exists());
}

/// A `.npy` file as NumPy's format 1.0 defines it (written here, not by the reader under
/// test): magic, version, a little-endian header length, the header dict padded with spaces
/// to a multiple of 64 bytes and ended by a newline, then the data.
fn npy(descr: &str, fortran: bool, shape: &str, data: &[u8]) -> Vec<u8> {
    let dict = format!(
        "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
        if fortran { "True" } else { "False" }
    );
    let total = (10 + dict.len() + 1).div_ceil(64) * 64;
    let header = format!("{dict:<width$}\n", width = total - 10 - 1);
    let mut out = b"\x93NUMPY\x01\x00".to_vec();
    out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

/// A zip archive of stored members, each local header with a zip64 extra field, as NumPy's
/// `np.savez` writes them (its central directory is not read, so it is left out here).
fn npz(members: &[(&str, &[u8], u16)]) -> Vec<u8> {
    let mut out = Vec::new();
    for (name, data, method) in members {
        out.extend_from_slice(b"PK\x03\x04");
        out.extend_from_slice(&45u16.to_le_bytes()); // version needed
        out.extend_from_slice(&0u16.to_le_bytes()); // flags
        out.extend_from_slice(&method.to_le_bytes());
        out.extend_from_slice(&[0; 8]); // time, date, crc (not checked)
        out.extend_from_slice(&u32::MAX.to_le_bytes()); // sizes in the zip64 field
        out.extend_from_slice(&u32::MAX.to_le_bytes());
        out.extend_from_slice(&(name.len() as u16).to_le_bytes());
        out.extend_from_slice(&20u16.to_le_bytes()); // extra field length
        out.extend_from_slice(name.as_bytes());
        out.extend_from_slice(&1u16.to_le_bytes());
        out.extend_from_slice(&16u16.to_le_bytes());
        out.extend_from_slice(&(data.len() as u64).to_le_bytes());
        out.extend_from_slice(&(data.len() as u64).to_le_bytes());
        out.extend_from_slice(data);
    }
    out
}

#[test]
fn certifies_numpy_arrays_in_every_layout() {
    let sc = scene(6, 8);
    let problem = write("np/problem.g2o", g2o_problem(&sc));
    let est = perturbed(&sc);
    let n = est.len();
    // element (k, r, c) in C order, then in Fortran order
    let c_order: Vec<f64> = (0..n * 9)
        .map(|x| est[x / 9].matrix()[((x % 9) / 3, x % 3)])
        .collect();
    let f_order: Vec<f64> = (0..n * 9)
        .map(|x| est[x % n].matrix()[((x / n) % 3, x / (3 * n))])
        .collect();
    let le = |v: &[f64]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
    let be: Vec<u8> = c_order.iter().flat_map(|x| x.to_be_bytes()).collect();
    let shape3 = format!("({n}, 3, 3)");
    let cases = [
        ("c.npy", npy("<f8", false, &shape3, &le(&c_order))),
        ("f.npy", npy("<f8", true, &shape3, &le(&f_order))),
        (
            "nine.npy",
            npy("<f8", false, &format!("({n}, 9)"), &le(&c_order)),
        ),
        ("big.npy", npy(">f8", false, &shape3, &be)),
        (
            "named.npz",
            npz(&[
                ("other.npy", &npy("<f8", false, "(1,)", &le(&[0.0])), 0),
                (
                    "rotations.npy",
                    &npy("<f8", false, &shape3, &le(&c_order)),
                    0,
                ),
            ]),
        ),
        (
            "one.npz",
            npz(&[("arr_0.npy", &npy("<f8", false, &shape3, &le(&c_order)), 0)]),
        ),
    ];
    for (name, bytes) in cases {
        certify_matches(&problem, &write(&format!("np/{name}"), bytes), &est);
    }
    // float32: the same rotations to single precision, brought onto SO(3)
    let single: Vec<u8> = c_order
        .iter()
        .flat_map(|&x| (x as f32).to_le_bytes())
        .collect();
    let f4 = write("np/f4.npy", npy("<f4", false, &shape3, &single));
    let out = json_of(&run(&[
        "certify",
        s(&problem),
        "--estimate",
        s(&f4),
        "--json",
    ]));
    for (a, b) in estimate_of(&out).iter().zip(&est) {
        assert!(angle_between(a, b) < 1e-6);
    }
}

#[test]
fn numpy_files_it_cannot_read_are_refused_by_name() {
    let sc = scene(6, 8);
    let problem = write("npx/problem.g2o", g2o_problem(&sc));
    let data = vec![0u8; 6 * 9 * 8];
    // a header announcing 4 GB, and a shape whose product overflows: refused before npyz
    // allocates or multiplies
    let mut long = b"\x93NUMPY\x02\x00".to_vec();
    long.extend_from_slice(&u32::MAX.to_le_bytes());
    long.extend_from_slice(b"{'descr'");
    let cases: [(&str, Vec<u8>, &str); 8] = [
        ("long.npy", long, "longer than the file"),
        (
            "overflow.npy",
            npy("<f8", false, "(4294967296, 4294967296, 9)", &data),
            "not a product of sizes",
        ),
        (
            "shape.npy",
            npy("<f8", false, "(6, 3)", &data[..144]),
            "shape [6, 3]",
        ),
        (
            "int.npy",
            npy("<i8", false, "(6, 3, 3)", &data),
            "dtype <i8",
        ),
        (
            "huge.npy",
            npy("<f8", false, "(1000000000000, 3, 3)", &data),
            "more than the file holds",
        ),
        (
            "compressed.npz",
            npz(&[("arr_0.npy", &data, 8)]),
            "np.savez_compressed",
        ),
        (
            "two.npz",
            npz(&[("a.npy", &data, 0), ("b.npy", &data, 0)]),
            "2 arrays (a.npy, b.npy)",
        ),
        ("text.npy", b"1 0 0 0 1 0 0 0 1\n".to_vec(), "not one"),
    ];
    for (name, bytes, words) in cases {
        let est = write(&format!("npx/{name}"), bytes);
        let out = run(&["certify", s(&problem), "--estimate", s(&est)]);
        assert_eq!(out.status.code(), Some(1), "{name}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(words) && err.contains(name), "{name}: {err}");
    }
    // the zero matrices of a well-formed array are not rotations
    let zeros = write("npx/zeros.npy", npy("<f8", false, "(6, 3, 3)", &data));
    let out = run(&["certify", s(&problem), "--estimate", s(&zeros)]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("rotation 0"), "{err}");
}
