//! The shape of `src/certify/` (issue 35), checked: its files import one way. Every file has a
//! layer (the vocabulary below the state of single and conjugate certifications, below the
//! proofs and their kernels, below the entry points), a file imports only from its own layer
//! or lower ones, and the import graph of the files has no circle (a circle through a
//! `mod.rs` is what a child importing an item its parent re-exports makes: children import
//! from the file that defines an item).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// Layer of the files of the vocabulary and of the entry points; every other file of a
/// problem folder (and `spectrum.rs`) is a proof or a kernel, [`PROOFS`].
const LAYERS: &[(&str, u32)] = &[
    ("certify::tolerance", 0),
    ("certify::proof", 0),
    ("certify::evidence", 0),
    ("certify::budget", 1),
    ("certify::log", 2),
    ("certify::certificate", 3),
    ("certify::settings", 3),
    ("certify::certification", 4),
    ("certify::rung", 4),
    ("certify::ladder", 5),
    ("certify::one_rotation", 6),
    ("certify::tally", 6),
    // the entry points: each problem folder's mod.rs
    ("certify::single", 8),
    ("certify::multiple", 8),
    ("certify::conjugate", 8),
    ("certify::simultaneous", 8),
    ("certify::gravity", 8),
    ("certify::rig", 8),
    ("certify", 9),
];

/// The layer of the proofs and their kernels.
const PROOFS: u32 = 7;

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("readable directory") {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// `certify::multiple::dual` for `src/certify/multiple/dual.rs` (`mod.rs`: its folder).
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).expect("under src");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| {
            c.as_os_str()
                .to_string_lossy()
                .trim_end_matches(".rs")
                .to_string()
        })
        .collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// The code of a file: comments and `#[cfg(test)]` modules left out (tests may import
/// anything).
fn code(text: &str) -> String {
    let text = text.split("#[cfg(test)]").next().unwrap_or("");
    text.lines()
        .map(|l| l.split("//").next().unwrap_or(""))
        // a visibility `pub(in path)` names a module, it imports nothing
        .map(|l| match (l.find("pub(in "), l.find(')')) {
            (Some(a), Some(b)) if b > a => format!("{}{}", &l[..a], &l[b + 1..]),
            _ => l.to_string(),
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The paths of a file's code that start at `crate::certify`, at `super`, or at one of the
/// file's own child modules (`mod child;`), as absolute segment lists.
fn paths(module: &[String], is_mod_rs: bool, code: &str) -> Vec<Vec<String>> {
    let children: BTreeSet<String> = code
        .lines()
        .filter_map(|l| {
            let l = l.trim();
            let l = l.strip_prefix("pub ").unwrap_or(l);
            let l = l.strip_prefix("pub(crate) ").unwrap_or(l);
            let l = l.strip_prefix("pub(super) ").unwrap_or(l);
            l.strip_prefix("mod ")?
                .strip_suffix(';')
                .map(str::to_string)
        })
        .collect();
    // a `mod.rs` names its children from its own module
    let own_dir: Vec<String> = module.to_vec();
    let mut out = Vec::new();
    let bytes: Vec<char> = code.chars().collect();
    let mut i = 0;
    while i < bytes.len() {
        let boundary = i == 0
            || !(bytes[i - 1].is_alphanumeric() || bytes[i - 1] == '_' || bytes[i - 1] == ':');
        if !boundary || !(bytes[i].is_alphabetic() || bytes[i] == '_') {
            i += 1;
            continue;
        }
        let mut j = i;
        while j < bytes.len() && (bytes[j].is_alphanumeric() || bytes[j] == '_' || bytes[j] == ':')
        {
            j += 1;
        }
        let word: String = bytes[i..j].iter().collect();
        i = j;
        let segs: Vec<String> = word
            .split("::")
            .filter(|s| !s.is_empty())
            .map(str::to_string)
            .collect();
        if segs.len() < 2 {
            continue;
        }
        let absolute = match segs[0].as_str() {
            "crate" => segs[1..].to_vec(),
            "super" => {
                let mut base = module.to_vec();
                let mut rest = &segs[..];
                while rest.first().is_some_and(|s| s == "super") {
                    base.pop();
                    rest = &rest[1..];
                }
                base.extend(rest.iter().cloned());
                base
            }
            s if is_mod_rs && children.contains(s) => {
                let mut base = own_dir.clone();
                base.extend(segs.iter().cloned());
                base
            }
            _ => continue,
        };
        if absolute.first().is_some_and(|s| s == "certify") {
            out.push(absolute);
        }
    }
    out
}

fn layer(module: &str) -> u32 {
    LAYERS
        .iter()
        .find(|(m, _)| *m == module)
        .map_or(PROOFS, |(_, l)| *l)
}

/// The import graph of the files of `src/certify/`: file module -> the modules it imports.
fn graph() -> BTreeMap<String, BTreeSet<String>> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src.join("certify"), &mut files);
    let modules: BTreeSet<String> = files
        .iter()
        .map(|f| module_of(&src, f).join("::"))
        .collect();
    let mut graph = BTreeMap::new();
    for file in &files {
        let module = module_of(&src, file);
        let name = module.join("::");
        let is_mod_rs = file.file_name().is_some_and(|f| f == "mod.rs");
        let text = std::fs::read_to_string(file).expect("readable source");
        let mut targets = BTreeSet::new();
        for path in paths(&module, is_mod_rs, &code(&text)) {
            // the longest prefix that is a file of the folder
            let target = (1..=path.len())
                .rev()
                .map(|k| path[..k].join("::"))
                .find(|m| modules.contains(m));
            if let Some(t) = target.filter(|t| *t != name) {
                targets.insert(t);
            }
        }
        graph.insert(name, targets);
    }
    graph
}

#[test]
fn certify_imports_go_one_way() {
    let graph = graph();
    assert!(graph.len() > 40, "only {} files found", graph.len());
    let mut violations = Vec::new();
    for (from, targets) in &graph {
        for to in targets {
            if layer(to) > layer(from) {
                violations.push(format!(
                    "{from} (layer {}) imports {to} (layer {})",
                    layer(from),
                    layer(to)
                ));
            }
        }
    }
    assert!(violations.is_empty(), "{}", violations.join("\n"));
}

#[test]
fn certify_has_no_import_circle() {
    let graph = graph();
    // depth-first search for a back edge
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(node.to_string(), 1);
        stack.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            match state.get(next.as_str()).copied().unwrap_or(0) {
                1 => {
                    let at = stack.iter().position(|s| s == next).unwrap_or(0);
                    let mut circle = stack[at..].to_vec();
                    circle.push(next.clone());
                    return Some(circle);
                }
                0 => {
                    if let Some(c) = visit(next, graph, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(node.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for node in graph.keys() {
        if state.get(node.as_str()).copied().unwrap_or(0) == 0
            && let Some(circle) = visit(node, &graph, &mut state, &mut Vec::new())
        {
            panic!("an import circle in src/certify: {}", circle.join(" -> "));
        }
    }
}

/// The scanner: `super` chains, child modules of a `mod.rs`, comments left out.
#[test]
fn paths_are_resolved() {
    let m: Vec<String> = ["certify", "multiple", "dual"].map(String::from).to_vec();
    let p = paths(
        &m,
        false,
        "use super::check::Scope;\nuse super::super::log::Point;",
    );
    assert_eq!(p[0].join("::"), "certify::multiple::check::Scope");
    assert_eq!(p[1].join("::"), "certify::log::Point");
    let m: Vec<String> = ["certify", "multiple"].map(String::from).to_vec();
    let p = paths(&m, true, "mod state;\nlet s = state::State::new();");
    assert_eq!(p[0].join("::"), "certify::multiple::state::State::new");
    assert!(paths(&m, true, &code("// crate::certify::ladder::climb")).is_empty());
}
