//! The README's two library examples are exactly `examples/readme_quickstart.rs` and
//! `examples/readme_conjugate.rs` (complete programs: `fn main` visible, no hidden lines), so
//! what a reader pastes into a `main.rs` is what `cargo run --example` and the downstream
//! fixture (`fixtures/downstream/`) build and run.

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
    let readme = std::fs::read_to_string(format!("{root}/README.md")).expect("README.md");
    let blocks = rust_blocks(&readme);
    for name in ["readme_quickstart", "readme_conjugate"] {
        let example =
            std::fs::read_to_string(format!("{root}/examples/{name}.rs")).expect("example file");
        assert!(
            blocks.contains(&example),
            "README.md has no ```rust block equal to examples/{name}.rs"
        );
    }
    for block in &blocks {
        assert!(
            block.contains("fn main()") && !block.lines().any(|l| l.starts_with('#')),
            "a README example is not a complete program:\n{block}"
        );
    }
}
