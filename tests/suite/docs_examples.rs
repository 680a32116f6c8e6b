//! The shell commands of the README and of the docs book (`docs/**/*.md`) run as printed.
//!
//! Every line of a ```` ```sh ```` block is a command (a trailing `\` continues it; `#` starts a
//! comment). The blocks of one file run in order in one fresh folder that holds a link to the
//! repository's `examples/` (so `examples/data/...` resolves, and files a command writes, e.g.
//! `--output estimate.json`, are there for the next command), with this build's `rotavg` first
//! on `PATH`. Each must exit with status 0, print no error, and its standard output lines must
//! be at most 100 characters (the default text output; `--verbose` is exempt).
//!
//! Commands that build or install (`cargo`, `pip`, `bash benches/...`, `python`, `mdbook`,
//! `git`) are not run here (a notice is printed): `.ci/run` runs the README's two commands
//! itself. Commands on the public benchmarks (`../shared/data`, not in a clone) must be in
//! ```` ```text ```` blocks, with their recorded output: this test fails on any in a `sh` block.

use std::path::Path;
use std::process::Command;

/// The programs whose commands are shown but not run by this test.
const NOT_RUN: [&str; 7] = ["cargo", "pip", "bash", "python", "python3", "mdbook", "git"];

/// The commands of the ```sh blocks of a Markdown text, continuation lines joined.
fn sh_commands(text: &str) -> Vec<String> {
    let mut commands = Vec::new();
    let mut in_block = false;
    let mut pending = String::new();
    for line in text.lines() {
        let trimmed = line.trim();
        if !in_block {
            in_block = trimmed == "```sh";
            continue;
        }
        if trimmed == "```" {
            in_block = false;
            continue;
        }
        // a comment: the whole line, or after a command (`cmd   # note`)
        let code = match line.find(" #") {
            Some(k) if !line[..k].contains('\'') => &line[..k],
            _ if trimmed.starts_with('#') => "",
            _ => line,
        };
        let code = code.trim_end();
        // a continuation line starts where the previous one left off, after one space
        let code = if pending.is_empty() {
            code
        } else {
            code.trim_start()
        };
        if let Some(start) = code.strip_suffix('\\') {
            pending.push_str(start.trim_end());
            pending.push(' ');
            continue;
        }
        pending.push_str(code);
        let command = std::mem::take(&mut pending).trim().to_string();
        if !command.is_empty() {
            commands.push(command);
        }
    }
    commands
}

/// The Markdown files checked: README.md and every `.md` file under `docs/`, as `(path relative
/// to the repository, text)`.
fn markdown_files(root: &Path) -> Vec<(String, String)> {
    let mut files = vec![root.join("README.md")];
    let mut folders = vec![root.join("docs")];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).expect("docs/ is readable") {
            let path = entry.expect("a docs entry").path();
            if path.is_dir() {
                folders.push(path);
            } else if path.extension().is_some_and(|e| e == "md") {
                files.push(path);
            }
        }
    }
    files.sort();
    files
        .into_iter()
        .map(|file| {
            let text = std::fs::read_to_string(&file).expect("a Markdown file");
            let name = file
                .strip_prefix(root)
                .unwrap_or(&file)
                .display()
                .to_string();
            (name, text)
        })
        .collect()
}

#[test]
fn shell_commands_of_the_docs_run() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let binary = Path::new(env!("CARGO_BIN_EXE_rotavg"));
    let path = format!(
        "{}:{}",
        binary.parent().expect("the binary's folder").display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let mut ran = 0;
    for (name, text) in markdown_files(root) {
        let commands = sh_commands(&text);
        if commands.is_empty() {
            continue;
        }
        let folder = crate::common::scratch_root().join(format!(
            "rotavg-docs-{}-{}",
            std::process::id(),
            name.replace('/', "_")
        ));
        let _ = std::fs::remove_dir_all(&folder);
        std::fs::create_dir_all(&folder).expect("a scratch folder");
        std::os::unix::fs::symlink(root.join("examples"), folder.join("examples"))
            .expect("a link to examples/");
        for command in commands {
            assert!(
                !command.contains("../shared/data"),
                "{name}: `{command}` needs the public benchmarks: show it in a ```text block"
            );
            let program = command.split_whitespace().next().unwrap_or("");
            if NOT_RUN.contains(&program) {
                println!("{name}: not run here: {command}");
                continue;
            }
            let out = Command::new("sh")
                .arg("-c")
                .arg(&command)
                .current_dir(&folder)
                .env("PATH", &path)
                .output()
                .expect("sh runs");
            let stdout = String::from_utf8_lossy(&out.stdout);
            let stderr = String::from_utf8_lossy(&out.stderr);
            assert!(
                out.status.success(),
                "{name}: `{command}` failed ({}):\n{stdout}\n{stderr}",
                out.status
            );
            assert!(
                !stderr.contains("error"),
                "{name}: `{command}` printed an error:\n{stderr}"
            );
            if !command.contains("--verbose") {
                for line in stdout.lines() {
                    assert!(
                        line.chars().count() <= 100,
                        "{name}: `{command}` printed a line of {} characters:\n{line}",
                        line.chars().count()
                    );
                }
            }
            ran += 1;
        }
        let _ = std::fs::remove_dir_all(&folder);
    }
    assert!(ran >= 6, "only {ran} documented commands ran");
    println!("{ran} documented commands ran");
}

#[test]
fn commands_are_parsed_as_a_shell_reads_them() {
    let text = "```sh\nrotavg a \\\n  --b c   # note\n# comment\n\necho 'x # y' | rotavg d\n```\n\
                ```text\nrotavg not-run\n```\n";
    assert_eq!(
        sh_commands(text),
        ["rotavg a --b c", "echo 'x # y' | rotavg d"]
    );
}

#[test]
fn every_rust_block_of_the_docs_is_a_doc_test() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let lib = std::fs::read_to_string(root.join("src/lib.rs")).expect("src/lib.rs");
    for (name, text) in markdown_files(root) {
        if !text.lines().any(|l| l.trim() == "```rust") {
            continue;
        }
        assert!(
            lib.contains(&format!("include_str!(\"../{name}\")")),
            "{name} has Rust code blocks but src/lib.rs (doc_markdown) does not include it"
        );
    }
}
