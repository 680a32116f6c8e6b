//! Errors speak the user's words (issue 27, item 5): a JSON input of the wrong shape is
//! described by the shape expected (`a JSON object {"rotations": [R, ...], ...}`), never by
//! the name of a Rust type (`expected struct RawSingle`, `ConjugateJson`), and a folder given
//! to a verb says which folders that verb reads instead of "Is a directory (os error 21)".

use rotavg::io::detect::ReadOptions;
use rotavg::io::handeye::read_conjugate_json;
use rotavg::io::json::{read_estimate, read_problem_json};
use rotavg::io::single_json::{parse_single_estimate, parse_single_json};
use std::path::Path;
use std::process::Command;

/// The words of `message` that look like Rust type names: CamelCase (an upper-case letter
/// after a lower-case one, e.g. `RawSingle`, `ConjugateJson`) or after the word `struct`.
fn type_names(message: &str) -> Vec<String> {
    let words: Vec<&str> = message
        .split(|c: char| !c.is_ascii_alphanumeric() && c != '_')
        .filter(|w| !w.is_empty())
        .collect();
    let mut found = Vec::new();
    for (k, w) in words.iter().enumerate() {
        let camel = w.starts_with(|c: char| c.is_ascii_uppercase())
            && w.as_bytes()
                .windows(2)
                .any(|p| p[0].is_ascii_lowercase() && p[1].is_ascii_uppercase());
        if camel || (k > 0 && words[k - 1] == "struct") {
            found.push(w.to_string());
        }
    }
    if message.contains("struct ") {
        found.push("struct".into());
    }
    found
}

/// JSON texts of the wrong shape for every reader.
const WRONG_SHAPES: [&str; 9] = [
    "[]",
    "5",
    "\"rotations\"",
    "null",
    "{\"rotations\": 3}",
    "{\"edges\": {}}",
    "{\"num_rotations\": 2, \"edges\": [5]}",
    "{\"pairs\": [1]}",
    "{\"pairs\": {}}",
];

#[test]
fn wrong_json_shapes_are_described_without_type_names() {
    let options = ReadOptions::default();
    let mut checked = 0;
    for text in WRONG_SHAPES {
        let messages = [
            ("single problem", parse_single_json(text, "x.json").err()),
            (
                "single estimate",
                parse_single_estimate(text, "x.json").err(),
            ),
            (
                "multiple problem",
                read_problem_json(text, "x.json", &options).err(),
            ),
            ("estimate", read_estimate(text, "x.json", &options).err()),
            (
                "conjugate problem",
                read_conjugate_json(text, "x.json").err(),
            ),
        ];
        for (reader, error) in messages {
            let Some(error) = error else { continue };
            let message = error.to_string();
            let names = type_names(&message);
            assert!(
                names.is_empty(),
                "the {reader} reader on `{text}` names Rust types {names:?}: {message}"
            );
            checked += 1;
        }
    }
    assert!(checked >= 40, "only {checked} errors checked");
}

#[test]
fn the_type_name_check_finds_type_names() {
    let serde = "invalid type: sequence, expected struct RawSingle at line 1 column 0";
    assert!(!type_names(serde).is_empty());
    assert!(!type_names("missing field in ConjugateJson").is_empty());
    let ours = "x.json:1: invalid type: integer `5`, expected a JSON object {\"rotations\": [R, ...]} \
                (EGs.txt, JSON, COLMAP, SO(3), R_ij)";
    assert_eq!(type_names(ours), Vec::<String>::new());
}

/// `rotavg ARGS` in the repository root: (exit status, stderr).
fn rotavg(args: &[&str]) -> (Option<i32>, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_rotavg"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("rotavg runs");
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn wrong_json_shapes_on_the_command_line() {
    let dir =
        crate::common::scratch_root().join(format!("rotavg-error-words-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("wrong.json");
    let path = file.to_str().unwrap();
    let estimate = Path::new("examples/data/slam.g2o");
    assert!(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join(estimate)
            .exists()
    );
    for text in WRONG_SHAPES {
        std::fs::write(&file, text).unwrap();
        for args in [
            vec!["single", path],
            vec!["multiple", path, "--format", "json"],
            vec!["conjugate", path, "--format", "json"],
            vec!["certify", "examples/data/slam.g2o", "--estimate", path],
            vec!["certify", path, "--estimate", path],
        ] {
            let (status, stderr) = rotavg(&args);
            assert_eq!(status, Some(1), "{args:?} on `{text}`: {stderr}");
            let names = type_names(&stderr);
            assert!(
                names.is_empty(),
                "{args:?} on `{text}` names Rust types {names:?}: {stderr}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_folder_given_to_the_wrong_verb_says_which_folders_it_reads() {
    let cases: [(&[&str], &str); 5] = [
        (&["single", "examples/data/handeye"], "single"),
        (&["multiple", "examples/data/handeye"], "COLMAP"),
        (&["info", "examples/data/handeye"], "COLMAP"),
        (
            &["certify", "examples/data", "--estimate", "x.json"],
            "certify",
        ),
        (&["conjugate", "examples/data"], "hand"),
    ];
    for (args, expected) in cases {
        let (status, stderr) = rotavg(args);
        assert_eq!(status, Some(1), "{args:?}: {stderr}");
        assert!(
            !stderr.contains("os error") && !stderr.contains("Is a directory"),
            "{args:?}: {stderr}"
        );
        // `conjugate` on a folder without pose streams says which streams it looked for
        let folder = stderr.contains("folder") || args[0] == "conjugate";
        assert!(
            folder && stderr.contains(expected),
            "{args:?} does not say which folders it reads: {stderr}"
        );
    }
}

#[test]
fn a_view_graph_given_to_single_or_conjugate_names_the_verb_that_reads_it() {
    for file in ["examples/data/slam.g2o", "examples/data/sfm_outliers.txt"] {
        for verb in ["single", "conjugate"] {
            let (status, stderr) = rotavg(&[verb, file]);
            assert_eq!(status, Some(1), "{verb} {file}: {stderr}");
            assert!(
                stderr.contains(&format!("`rotavg multiple {file}` reads it"))
                    && stderr.contains(&format!("`rotavg {verb}` reads JSON")),
                "{verb} {file}: {stderr}"
            );
            assert!(!stderr.contains("expected value"), "{stderr}");
        }
    }
}
