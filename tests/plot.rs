//! `rotavg::plot` (hand-written SVG) and the CLI's `--plot FILE.svg` for `multiple` and
//! `certify`: the SVG is well formed (balanced tags, checked by a tiny tag scanner), has one bar
//! per histogram bin, only finite numbers, and escapes text.

use rotavg::io::json::write_problem_json;
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::plot::{histogram, residual_histogram_svg};
use std::path::PathBuf;
use std::process::Command;

/// Check the tags of `svg` are balanced (a stack of open element names; `<?...?>`, comments,
/// self-closing tags handled) and the root is `svg`. Returns the number of elements.
fn check_xml(svg: &str) -> usize {
    let t = svg.trim_start();
    let t = if t.starts_with("<?xml") {
        &t[t.find("?>").expect("unterminated XML header") + 2..]
    } else {
        t
    };
    assert!(t.trim_start().starts_with("<svg"), "root is not <svg");
    let mut stack: Vec<String> = Vec::new();
    let mut elements = 0;
    let mut rest = t;
    let mut closed_root = false;
    while let Some(i) = rest.find('<') {
        assert!(
            !closed_root || rest[..i].trim().is_empty(),
            "content after </svg>"
        );
        let j = rest[i..].find('>').expect("unterminated tag") + i;
        let tag = &rest[i + 1..j];
        assert!(!tag.contains('<'), "'<' inside a tag: {tag}");
        if let Some(name) = tag.strip_prefix('/') {
            let open = stack.pop().expect("closing tag without opening");
            assert_eq!(open, name.trim(), "mismatched tags");
            if stack.is_empty() {
                closed_root = true;
            }
        } else {
            assert!(!closed_root, "second root element");
            elements += 1;
            let name: String = tag
                .chars()
                .take_while(|c| !c.is_whitespace() && *c != '/')
                .collect();
            assert!(!name.is_empty(), "empty tag name");
            // quotes balanced inside the tag
            assert_eq!(tag.matches('"').count() % 2, 0, "unbalanced quotes: {tag}");
            if !tag.ends_with('/') {
                stack.push(name);
            }
        }
        rest = &rest[j + 1..];
    }
    assert!(stack.is_empty(), "unclosed tags: {stack:?}");
    assert!(closed_root, "no </svg>");
    elements
}

/// Every numeric attribute value parses as a finite f64.
fn check_numbers_finite(svg: &str) {
    for attr in [
        "x",
        "y",
        "width",
        "height",
        "x1",
        "x2",
        "y1",
        "y2",
        "font-size",
    ] {
        let pat = format!(" {attr}=\"");
        let mut rest = svg;
        while let Some(i) = rest.find(&pat) {
            let v = &rest[i + pat.len()..];
            let end = v.find('"').unwrap();
            let num: f64 = v[..end]
                .parse()
                .unwrap_or_else(|_| panic!("{attr}={} is not a number", &v[..end]));
            assert!(num.is_finite(), "{attr}={num}");
            rest = &v[end..];
        }
    }
    let lower = svg.to_ascii_lowercase();
    assert!(!lower.contains("nan") && !lower.contains("inf"));
}

#[test]
fn histogram_counts_every_finite_value_once() {
    // 100 values 0..99: Sturges ceil(log2 100) + 1 = 8 bins over [0, 99].
    let v: Vec<f64> = (0..100).map(f64::from).collect();
    let h = histogram(&v);
    assert_eq!(h.counts.len(), 8);
    assert_eq!(h.counts.iter().sum::<usize>(), 100);
    assert_eq!(h.lo, 0.0);
    assert!((h.width - 99.0 / 8.0).abs() < 1e-12);
    // equal values and empty input still give valid bins
    assert_eq!(histogram(&[2.0; 5]).counts.iter().sum::<usize>(), 5);
    assert_eq!(histogram(&[f64::NAN, f64::INFINITY]).counts, vec![0]);
    // cap
    let many: Vec<f64> = (0..1_000_000).map(|k| f64::from(k) * 1e-3).collect();
    assert!(histogram(&many).counts.len() <= rotavg::plot::MAX_BINS);
}

#[test]
fn svg_is_well_formed_with_one_bar_per_bin() {
    let v: Vec<f64> = (0..37)
        .map(|k| (f64::from(k) * 0.37).sin().abs() * 3.0)
        .collect();
    let notes = vec![
        ("gap".to_string(), "1.0e-9".to_string()),
        ("a<b & \"c\"".to_string(), "x > y".to_string()),
    ];
    let svg = residual_histogram_svg(&v, "title <with> & markup", &notes);
    let bins = histogram(&v).counts.len();
    assert_eq!(svg.matches("class=\"bar\"").count(), bins);
    assert_eq!(svg.matches("class=\"annotation\"").count(), notes.len());
    assert!(svg.contains("&lt;with&gt; &amp; markup"));
    assert!(check_xml(&svg) > bins);
    check_numbers_finite(&svg);
    // no annotations: no certificate panel; empty and non-finite data still valid
    for data in [&v[..], &[][..], &[f64::NAN, 1.0, f64::NEG_INFINITY][..]] {
        let svg = residual_histogram_svg(data, "t", &[]);
        assert!(!svg.contains("class=\"annotation\""));
        assert_eq!(
            svg.matches("class=\"bar\"").count(),
            histogram(data).counts.len()
        );
        check_xml(&svg);
        check_numbers_finite(&svg);
    }
}

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("rotavg-plot-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn cli_multiple_and_certify_write_svg() {
    // n = 12, 30 edges, sigma = 0.05 rad: certified by the dual (as in tests/cli_multiple.rs).
    let (p, _) = SyntheticGraph {
        num_rotations: 12,
        num_edges: 30,
        noise_sigma: 0.05,
        seed: 5,
        ..Default::default()
    }
    .generate();
    let d = dir();
    let g = d.join("g.json");
    std::fs::write(&g, write_problem_json(&p)).unwrap();
    let svg = d.join("out.svg");
    let est = d.join("est.json");
    let out = Command::new(env!("CARGO_BIN_EXE_rotavg"))
        .args(["multiple", g.to_str().unwrap(), "--quiet", "--plot"])
        .arg(&svg)
        .arg("--output")
        .arg(&est)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg).unwrap();
    check_xml(&text);
    check_numbers_finite(&text);
    assert!(
        text.contains("class=\"annotation\""),
        "certificate panel missing"
    );
    // 30 residuals: ceil(log2 30) + 1 = 6 bins
    assert_eq!(text.matches("class=\"bar\"").count(), 6);

    let svg2 = d.join("cert.svg");
    let out = Command::new(env!("CARGO_BIN_EXE_rotavg"))
        .args(["certify", g.to_str().unwrap(), "--quiet", "--estimate"])
        .arg(&est)
        .arg("--plot")
        .arg(&svg2)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(&svg2).unwrap();
    check_xml(&text);
    check_numbers_finite(&text);
    assert!(text.contains("class=\"annotation\""));

    // unwritable path: an I/O error, non-zero exit
    let out = Command::new(env!("CARGO_BIN_EXE_rotavg"))
        .args(["multiple", g.to_str().unwrap(), "--quiet", "--plot"])
        .arg(d.join("no-such-dir").join("x.svg"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let _ = std::fs::remove_dir_all(&d);
}
