//! Format auto-detection and reading (`rotavg::io::detect`): the first byte's bits 3-5 choose
//! the file name handed to `detect_format` / `read_graph` (extension-based or content-based
//! detection, or a forced format), its low bits the reader options. Whatever `detect_format`
//! decides must be what `read_graph` reads, and accepted graphs go through
//! `common::check_graph`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use rotavg::io::detect::{GraphFormat, detect_format, read_graph};

mod common;

const NAMES: [&str; 8] = [
    "-",
    "EGs.txt",
    "graph.g2o",
    "problem.json",
    "x.JSON",
    "sphere.G2O",
    "data",
    ".json.txt",
];

fuzz_target!(|data: &[u8]| {
    let Some((selector, text)) = common::split(data) else {
        return;
    };
    let options = common::options(selector);
    let name = NAMES[usize::from((selector >> 3) & 7)];
    let detected = detect_format(name, &text);
    if let Ok(f) = detected {
        assert_ne!(f, GraphFormat::Auto, "detect_format never answers Auto");
    }
    let forced = match selector >> 6 {
        0 | 1 => GraphFormat::Auto,
        2 => GraphFormat::G2o,
        _ => GraphFormat::OneDsfm,
    };
    if let Ok(g) = read_graph(&text, name, forced, &options) {
        common::check_graph(&g);
        let expected = if forced == GraphFormat::Auto {
            detected.expect("read_graph(Auto) succeeded, so detection did")
        } else {
            forced
        };
        assert_eq!(g.format, expected);
    }
});
