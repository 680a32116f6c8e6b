//! The two library examples of the docs (`docs/library.md`) are exactly
//! `examples/readme_quickstart.rs` and `examples/readme_conjugate.rs`, and every Rust block of
//! the README and of `docs/library.md` is a complete program (`fn main` visible, no hidden
//! lines), so what a reader pastes into a `main.rs` is what `cargo run --example` and the
//! downstream fixture (`fixtures/downstream/`) build and run. (The blocks are compiled and run
//! as doc tests: `src/lib.rs`, `doc_markdown`; the shell commands: `tests/suite/docs_examples.rs`.)

fn rust_blocks(text: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in text.lines() {
        match (&mut current, line) {
            (None, "```rust") => current = Some(String::new()),
            (Some(block), "```") => {
                blocks.push(std::mem::take(block));
                current = None;
            }
            (Some(block), _) => {
                block.push_str(line);
                block.push('\n');
            }
            (None, _) => {}
        }
    }
    blocks
}

#[test]
fn readme_examples_are_the_example_programs() {
    let root = env!("CARGO_MANIFEST_DIR");
    let read = |path: &str| std::fs::read_to_string(format!("{root}/{path}")).expect(path);
    let library = rust_blocks(&read("docs/library.md"));
    for name in ["readme_quickstart", "readme_conjugate"] {
        let example =
            std::fs::read_to_string(format!("{root}/examples/{name}.rs")).expect("example file");
        assert!(
            library.contains(&example),
            "docs/library.md has no ```rust block equal to examples/{name}.rs"
        );
    }
    let readme = rust_blocks(&read("README.md"));
    assert!(!readme.is_empty(), "README.md has no Rust example");
    for block in readme.iter().chain(&library) {
        // `# ` hides a line from the reader; attributes (`#[...]`) are code
        let hidden = |l: &str| l.starts_with('#') && !l.starts_with("#[") && !l.starts_with("#!");
        assert!(
            block.contains("fn main()") && !block.lines().any(hidden),
            "a README example is not a complete program:\n{block}"
        );
    }
}
