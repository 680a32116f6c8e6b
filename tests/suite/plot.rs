//! `rotavg::plot` (plotters, SVG backend) and the CLI's `--plot FILE.svg` for `multiple`,
//! `certify` and `conjugate`: the SVG is well formed (balanced tags, checked by a tiny tag
//! scanner), has one bar per histogram bin (bars are the only elements filled with
//! `BAR_COLOR` #4682B4), only finite numbers, escapes text, and, when a certificate with
//! eigenvalue estimates is given, has the eigenvalue panel with the values as text and the
//! proven-bound line.

use rotavg::io::handeye::write_conjugate_json;
use rotavg::io::json::write_problem_json;
use rotavg::multiple::synthetic::SyntheticGraph;
use rotavg::plot::{EigenvaluePanel, figure_svg, histogram, residual_histogram_svg};
use std::path::PathBuf;
use std::process::Command;

/// The histogram bars' fill (`rotavg::plot::BAR_COLOR`).
const BAR: &str = "fill=\"#4682B4\" stroke=\"none\"/>";

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
    assert_eq!(svg.matches(BAR).count(), bins);
    assert!(svg.contains("gap: 1.0e-9"));
    assert!(
        svg.contains("a&lt;b &amp; &quot;c&quot;: x &gt; y")
            || svg.contains("a&lt;b &amp; \"c\": x &gt; y")
    );
    assert!(svg.contains("&lt;with&gt; &amp; markup"));
    assert!(check_xml(&svg) > bins);
    check_numbers_finite(&svg);
    // no annotations: no certificate panel; empty and non-finite data still valid
    for data in [&v[..], &[][..], &[f64::NAN, 1.0, f64::NEG_INFINITY][..]] {
        let svg = residual_histogram_svg(data, "t", &[]);
        assert!(!svg.contains(">certificate<") && !svg.contains("\ncertificate\n"));
        assert_eq!(svg.matches(BAR).count(), histogram(data).counts.len());
        check_xml(&svg);
        check_numbers_finite(&svg);
    }
}

/// A fresh temporary directory per call (tests run in parallel and each removes its own).
fn dir() -> PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    let d = crate::common::scratch_root().join(format!(
        "rotavg-plot-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::SeqCst)
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn cli_multiple_and_certify_write_svg() {
    // n = 12, 30 edges, sigma = 0.05 rad: certified by the dual (as in
    // tests/suite/cli_multiple.rs).
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
        text.contains("verdict: certified"),
        "certificate panel missing"
    );
    // 30 residuals: ceil(log2 30) + 1 = 6 bins
    assert_eq!(text.matches(BAR).count(), 6);
    assert_eigen_panel(&text, 10, 3);

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
    assert!(text.contains("verdict: certified"));
    assert_eigen_panel(&text, 10, 3);

    // unwritable path: an I/O error, non-zero exit
    let out = Command::new(env!("CARGO_BIN_EXE_rotavg"))
        .args(["multiple", g.to_str().unwrap(), "--quiet", "--plot"])
        .arg(d.join("no-such-dir").join("x.svg"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let _ = std::fs::remove_dir_all(&d);
}

/// The eigenvalue panel is present: title, `count` values as text, the proven-bound line's
/// label, and the expected null-space note.
fn assert_eigen_panel(svg: &str, count: usize, null_dimension: usize) {
    assert!(
        svg.contains("smallest eigenvalues of the certificate matrix (estimates)"),
        "eigenvalue panel missing"
    );
    for k in 1..=count {
        assert!(
            svg.contains(&format!("lambda_{k} = ")),
            "lambda_{k} missing"
        );
    }
    assert!(!svg.contains(&format!("lambda_{} = ", count + 1)));
    assert!(
        svg.contains("proven lambda_min &gt;= "),
        "bound line label missing"
    );
    assert!(svg.contains(&format!(
        "expected at a certified solution: {null_dimension} eigenvalue"
    )));
}

#[test]
fn eigenvalue_panel_is_drawn_with_values_and_bound() {
    let e = EigenvaluePanel {
        values: vec![-1e-13, 2e-13, 5e-13, 0.7, 0.71, 1.3, f64::NAN],
        residuals: vec![1e-14; 7],
        verified_lower_bound: Some(-2.5e-9),
        null_dimension: 3,
        method: "dense eigen-decomposition".into(),
    };
    let svg = figure_svg(&[1.0, 2.0, 2.5], "t", &[], Some(&e));
    check_xml(&svg);
    check_numbers_finite(&svg);
    // the 6 finite values, as text and as points
    assert_eigen_panel(&svg, 6, 3);
    assert!(svg.contains("lambda_4 = 7.000000e-1"));
    assert!(svg.contains("proven lambda_min &gt;= -2.500e-9"));
    assert_eq!(svg.matches("<circle").count(), 6);
    // the histogram is still there
    assert_eq!(
        svg.matches(BAR).count(),
        histogram(&[1.0, 2.0, 2.5]).counts.len()
    );
    // no verified bound: no line label, still well formed
    let e2 = EigenvaluePanel {
        verified_lower_bound: None,
        ..e
    };
    let svg = figure_svg(&[], "t", &[], Some(&e2));
    check_xml(&svg);
    check_numbers_finite(&svg);
    assert!(!svg.contains("proven lambda_min"));
}

/// `rotavg multiple --json`: `verified_min_eigenvalue` always (with a certificate),
/// `smallest_eigenvalues` only with `--plot` (10 ascending values; first 3 ~ 0 at a certified
/// solution, the verified bound below the smallest estimate minus its residual).
#[test]
fn cli_json_has_verified_bound_and_eigenvalues_with_plot() {
    let (p, _) = SyntheticGraph {
        num_rotations: 15,
        num_edges: 40,
        noise_sigma: 0.05,
        seed: 9,
        ..Default::default()
    }
    .generate();
    let d = dir().join("json");
    std::fs::create_dir_all(&d).unwrap();
    let g = d.join("g.json");
    std::fs::write(&g, write_problem_json(&p)).unwrap();
    let run = |plot: bool| -> serde_json::Value {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_rotavg"));
        cmd.args([
            "multiple",
            g.to_str().unwrap(),
            "--json",
            "--certify",
            "auto",
        ]);
        if plot {
            cmd.arg("--plot").arg(d.join("f.svg"));
        }
        let out = cmd.output().unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let plain = run(false);
    let c = &plain["certificate"];
    assert_eq!(c["verdict"], "certified");
    assert!(c["verified_min_eigenvalue"].as_f64().is_some());
    assert!(c.get("smallest_eigenvalues").is_none());
    let with = run(true);
    let c = &with["certificate"];
    let mu = c["verified_min_eigenvalue"].as_f64().unwrap();
    let e = &c["smallest_eigenvalues"];
    assert_eq!(e["method"], "dense");
    let v: Vec<f64> = e["values"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert_eq!(v.len(), 10);
    assert!(v.windows(2).all(|w| w[0] <= w[1]));
    assert!(v[..3].iter().all(|x| x.abs() < 1e-8), "{v:?}");
    assert!(v[3] > 1e-3);
    assert!(mu <= v[0] + 1e-9);
    let _ = std::fs::remove_dir_all(&d);
}

/// Conjugate: `rotavg conjugate --plot` and `rotavg certify --plot` draw the 10 eigenvalues of
/// the 10x10 certificate matrix (one expected ~ 0).
#[test]
fn cli_conjugate_and_certify_conjugate_write_eigen_panel() {
    use rand::SeedableRng;
    let mut rng = rand::rngs::StdRng::seed_from_u64(3);
    let (p, s) = rotavg::conjugate::synthetic::random_instance(12, 0.01, 0.0, &mut rng);
    let d = dir().join("conj");
    std::fs::create_dir_all(&d).unwrap();
    let g = d.join("pairs.json");
    std::fs::write(&g, write_conjugate_json(&p)).unwrap();
    let svg = d.join("c.svg");
    let out = Command::new(env!("CARGO_BIN_EXE_rotavg"))
        .args(["conjugate", g.to_str().unwrap(), "--quiet", "--plot"])
        .arg(&svg)
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
    assert!(text.contains("verdict: certified"));
    assert!(text.contains("residual angles of 12 pairs"));
    assert_eigen_panel(&text, 10, 1);

    let est = d.join("s.json");
    std::fs::write(
        &est,
        format!(
            "{{\"rotation\": {}}}",
            serde_json::to_string(&rotavg::so3::rotation_to_rows(&s)).unwrap()
        ),
    )
    .unwrap();
    let svg2 = d.join("c2.svg");
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
    assert_eigen_panel(&text, 10, 1);
    let _ = std::fs::remove_dir_all(&d);
}
