//! The architecture, checked: every module imports only from its own layer or the layers below
//! (the table in `src/lib.rs`), the three problem modules do not import each other, and no file
//! of the repository holds a merge-conflict marker.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Layer of each top-level module of `src/` (higher may import lower, never the reverse).
/// Modules of one layer may import each other only where `PEERS_MAY_IMPORT` says so.
const LAYERS: &[(&str, u32)] = &[
    ("error", 0),
    ("warning", 0),
    ("so3", 1),
    ("termination", 1),
    ("progress", 1),
    ("objective", 2),
    ("validate", 2),
    ("deadline", 2),
    ("linalg", 3),
    ("single", 4),
    ("multiple", 4),
    ("conjugate", 4),
    ("relax", 5),
    ("rig", 5),
    ("certify", 6),
    ("pipeline", 7),
    ("io", 8),
    ("plot", 8),
    ("report", 9),
];

/// Same-layer imports that are allowed (importer, imported).
/// `multiple` may use `single` (the robust alignment of the accuracy report is a geodesic L1
/// single mean), never the reverse.
const PEERS_MAY_IMPORT: &[(&str, &str)] = &[
    ("objective", "so3"),
    ("validate", "so3"),
    ("multiple", "single"),
];

/// Names re-exported at the crate root, and the module they come from.
const ROOT_REEXPORTS: &[(&str, &str)] = &[
    ("Error", "error"),
    ("Result", "error"),
    ("Rotation", "so3"),
    ("Metric", "so3"),
    ("SolverReport", "termination"),
    ("Termination", "termination"),
    ("Objective", "objective"),
    ("Loss", "objective"),
    ("Certificate", "certify"),
    ("Verdict", "certify"),
    ("BoundMethod", "certify"),
    ("nalgebra", "external"),
];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable src directory") {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The first path segment after every `crate::` in a line of code (comments excluded), with
/// `crate::{a, b::c}` groups expanded.
fn crate_imports(line: &str) -> Vec<String> {
    let code = line.split("//").next().unwrap_or("");
    let mut out = Vec::new();
    let mut rest = code;
    while let Some(k) = rest.find("crate::") {
        // `rotavg_crate::` or `some_crate::` are not ours
        let before = rest[..k].chars().last();
        rest = &rest[k + "crate::".len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_') {
            continue;
        }
        if let Some(group) = rest.strip_prefix('{') {
            let inner = group.split('}').next().unwrap_or("");
            for item in inner.split(',') {
                let name: String = item
                    .trim()
                    .chars()
                    .take_while(|c| c.is_alphanumeric() || *c == '_')
                    .collect();
                if !name.is_empty() {
                    out.push(name);
                }
            }
        } else {
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            if !name.is_empty() {
                out.push(name);
            }
        }
    }
    out
}

#[test]
fn modules_import_only_downward() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let layer: BTreeMap<&str, u32> = LAYERS.iter().copied().collect();
    let reexport: BTreeMap<&str, &str> = ROOT_REEXPORTS.iter().copied().collect();
    let mut files = Vec::new();
    rust_files(&root, &mut files);
    let mut violations = Vec::new();
    let mut checked = 0;
    for file in &files {
        let rel = file.strip_prefix(&root).expect("under src");
        let first = rel
            .components()
            .next()
            .and_then(|c| c.as_os_str().to_str())
            .unwrap_or("");
        let module = first.trim_end_matches(".rs");
        if module == "lib" || module == "bin" || module == "main" {
            continue; // the crate root re-exports everything; the binary is the top layer
        }
        let Some(&own) = layer.get(module) else {
            violations.push(format!(
                "{}: module `{module}` is not in the layer table of tests/suite/layers.rs",
                rel.display()
            ));
            continue;
        };
        let text = std::fs::read_to_string(file).expect("readable source file");
        for (k, line) in text.lines().enumerate() {
            if line.trim_start().starts_with("//") {
                continue; // doc examples use `rotavg::`, and doc links are not imports
            }
            for target in crate_imports(line) {
                let target_module = reexport.get(target.as_str()).copied().unwrap_or(&target);
                if target_module == "external" || target_module == module {
                    continue;
                }
                checked += 1;
                let Some(&theirs) = layer.get(target_module) else {
                    violations.push(format!(
                        "{}:{}: imports `crate::{target}`, which is not in the layer table",
                        rel.display(),
                        k + 1
                    ));
                    continue;
                };
                let peer_ok = PEERS_MAY_IMPORT.contains(&(module, target_module));
                if theirs > own || (theirs == own && !peer_ok) {
                    violations.push(format!(
                        "{}:{}: `{module}` (layer {own}) imports `crate::{target}` (`{target_module}`, layer {theirs})",
                        rel.display(),
                        k + 1
                    ));
                }
            }
        }
    }
    assert!(
        checked > 100,
        "the scan found only {checked} crate imports: the parser is broken"
    );
    assert!(
        violations.is_empty(),
        "imports against the layering:\n{}",
        violations.join("\n")
    );
}

/// The scanner itself: grouped imports, doc links and foreign crates.
#[test]
fn import_scanner_reads_groups_and_skips_comments() {
    assert_eq!(
        crate_imports("use crate::{error::Result, so3::Rotation};"),
        vec!["error", "so3"]
    );
    assert_eq!(
        crate_imports("let x = crate::linalg::gamma(3) + crate::so3::angle(&r);"),
        vec!["linalg", "so3"]
    );
    assert!(crate_imports("// see crate::pipeline").is_empty());
    assert!(crate_imports("use other_crate::pipeline;").is_empty());
}

/// A committed merge conflict once reached README.md on main; no file may hold one.
#[test]
fn no_conflict_markers_in_the_repository() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let listed = std::process::Command::new("git")
        .args(["ls-files", "-z"])
        .current_dir(root)
        .output()
        .ok()
        .filter(|o| o.status.success());
    let files: Vec<PathBuf> = match listed {
        Some(o) => o
            .stdout
            .split(|b| *b == 0)
            .filter(|s| !s.is_empty())
            .map(|s| root.join(String::from_utf8_lossy(s).as_ref()))
            .collect(),
        None => {
            eprintln!("git ls-files unavailable: scanning src/, tests/ and the top-level files");
            let mut v = Vec::new();
            rust_files(&root.join("src"), &mut v);
            rust_files(&root.join("tests"), &mut v);
            v.push(root.join("README.md"));
            v
        }
    };
    let mut found = Vec::new();
    for file in &files {
        let Ok(text) = std::fs::read_to_string(file) else {
            continue; // binary or unreadable
        };
        for (k, line) in text.lines().enumerate() {
            if line.starts_with("<<<<<<< ") || line.starts_with(">>>>>>> ") || line == "<<<<<<<" {
                found.push(format!("{}:{}: {line}", file.display(), k + 1));
            }
        }
    }
    assert!(files.len() > 10, "only {} files listed", files.len());
    assert!(
        found.is_empty(),
        "merge-conflict markers:\n{}",
        found.join("\n")
    );
}

/// The command line stays a thin layer of option groups over the library (issue 35): the
/// non-blank, non-comment lines of `src/bin` at most 1,000 (991 on 2026-11-30, after the value
/// parsers, the error text, certify's problem loading and the report writers moved into the
/// library).
#[test]
fn the_command_line_stays_under_a_thousand_lines() {
    let mut files = Vec::new();
    rust_files(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("src/bin"),
        &mut files,
    );
    let lines: usize = files
        .iter()
        .map(|f| {
            std::fs::read_to_string(f)
                .expect("readable source")
                .lines()
                .filter(|l| !l.trim().is_empty() && !l.trim().starts_with("//"))
                .count()
        })
        .sum();
    assert!(lines <= 1000, "src/bin holds {lines} code lines");
}
