//! SVG figures for the CLI's `--plot FILE.svg`: the histogram of residual angles (degrees) and,
//! when a certificate was computed, a text panel with its facts.
//!
//! The SVG is written by hand (rectangles, lines, text): no plotting dependency, no fonts
//! needed at build time. Every number written is finite; non-finite inputs are dropped.

use crate::Certificate;
use std::fmt::Write;

/// Most bins a histogram gets.
pub const MAX_BINS: usize = 40;

const PANEL_WIDTH: f64 = 520.0;
const TEXT_WIDTH: f64 = 380.0;
const HEIGHT: f64 = 400.0;
const LEFT: f64 = 60.0;
const RIGHT: f64 = 500.0;
const TOP: f64 = 50.0;
const BOTTOM: f64 = 340.0;

/// An equal-width histogram: bin `k` covers `[lo + k width, lo + (k+1) width)` (the last bin
/// also holds `lo + bins * width`).
#[derive(Debug, Clone, PartialEq)]
pub struct Histogram {
    /// Left edge of the first bin.
    pub lo: f64,
    /// Width of every bin (> 0).
    pub width: f64,
    /// Number of values in each bin (at least one bin).
    pub counts: Vec<usize>,
}

/// Histogram of the finite values of `values`, with `ceil(log2 m) + 1` bins (Sturges' rule,
/// `m` = number of finite values) capped at [`MAX_BINS`]; the range is `[min, max]` (widened
/// to width 1 when all values are equal, and to `[0, 1]` when there are none).
///
/// ```
/// let h = rotavg::plot::histogram(&[0.0, 1.0, 2.0, 3.0, f64::NAN]);
/// assert_eq!(h.counts.len(), 3); // ceil(log2 4) + 1
/// assert_eq!(h.counts.iter().sum::<usize>(), 4);
/// ```
pub fn histogram(values: &[f64]) -> Histogram {
    let finite: Vec<f64> = values.iter().copied().filter(|v| v.is_finite()).collect();
    let m = finite.len();
    if m == 0 {
        return Histogram {
            lo: 0.0,
            width: 1.0,
            counts: vec![0],
        };
    }
    let min = finite.iter().copied().fold(f64::INFINITY, f64::min);
    let max = finite.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let bins = ((m as f64).log2().ceil() as usize + 1).clamp(1, MAX_BINS);
    let span = max - min;
    let (lo, width) = if span > 0.0 && span.is_finite() {
        (min, span / bins as f64)
    } else {
        (min - 0.5, 1.0 / bins as f64)
    };
    let mut counts = vec![0usize; bins];
    for v in finite {
        let k = ((v - lo) / width).floor();
        let k = if k.is_finite() && k > 0.0 {
            (k as usize).min(bins - 1)
        } else {
            0
        };
        counts[k] += 1;
    }
    Histogram { lo, width, counts }
}

/// Escape `&`, `<`, `>`, `"` for XML text and attributes.
fn escape(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            c if c.is_control() => out.push(' '),
            c => out.push(c),
        }
    }
    out
}

/// A tick label: short, finite.
fn tick(v: f64) -> String {
    if v == 0.0 || (v.abs() >= 0.01 && v.abs() < 1e4) {
        let s = format!("{v:.3}");
        let s = s.trim_end_matches('0').trim_end_matches('.');
        if s == "-0" { "0".into() } else { s.into() }
    } else {
        format!("{v:.2e}")
    }
}

/// SVG text of the histogram of `residuals_deg` (one `<rect class="bar">` per bin of
/// [`histogram`], zero-count bins included) under `title`; when `annotations` is not empty, a
/// text panel to the right lists them as `key: value` lines.
///
/// ```
/// let svg = rotavg::plot::residual_histogram_svg(
///     &[0.5, 1.0, 1.5, 4.0],
///     "residuals",
///     &[("gap".to_string(), "1e-9".to_string())],
/// );
/// assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
/// assert_eq!(svg.matches("class=\"bar\"").count(), 3);
/// ```
pub fn residual_histogram_svg(
    residuals_deg: &[f64],
    title: &str,
    annotations: &[(String, String)],
) -> String {
    let h = histogram(residuals_deg);
    let width = if annotations.is_empty() {
        PANEL_WIDTH
    } else {
        PANEL_WIDTH + TEXT_WIDTH
    };
    let mut s = String::new();
    // `write!` into a String cannot fail.
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{HEIGHT}\" \
         viewBox=\"0 0 {width} {HEIGHT}\" font-family=\"sans-serif\" font-size=\"12\">"
    );
    let _ = writeln!(
        s,
        "<rect x=\"0\" y=\"0\" width=\"{width}\" height=\"{HEIGHT}\" fill=\"white\"/>"
    );
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"28\" text-anchor=\"middle\" font-size=\"15\">{}</text>",
        (LEFT + RIGHT) / 2.0,
        escape(title)
    );
    let bins = h.counts.len();
    let max_count = h.counts.iter().copied().max().unwrap_or(0).max(1);
    let bar_w = (RIGHT - LEFT) / bins as f64;
    let y_of = |c: f64| BOTTOM - (BOTTOM - TOP) * c / max_count as f64;
    for (k, &c) in h.counts.iter().enumerate() {
        let x = LEFT + bar_w * k as f64;
        let y = y_of(c as f64);
        let _ = writeln!(
            s,
            "<rect class=\"bar\" x=\"{x:.2}\" y=\"{y:.2}\" width=\"{bw:.2}\" height=\"{bh:.2}\" \
             fill=\"steelblue\" stroke=\"white\" stroke-width=\"0.5\"><title>{a} to {b} deg: \
             {c}</title></rect>",
            bw = bar_w,
            bh = BOTTOM - y,
            a = tick(h.lo + h.width * k as f64),
            b = tick(h.lo + h.width * (k + 1) as f64),
        );
    }
    // axes
    let _ = writeln!(
        s,
        "<line x1=\"{LEFT}\" y1=\"{BOTTOM}\" x2=\"{RIGHT}\" y2=\"{BOTTOM}\" stroke=\"black\"/>"
    );
    let _ = writeln!(
        s,
        "<line x1=\"{LEFT}\" y1=\"{TOP}\" x2=\"{LEFT}\" y2=\"{BOTTOM}\" stroke=\"black\"/>"
    );
    const TICKS: usize = 5;
    for t in 0..=TICKS {
        let f = t as f64 / TICKS as f64;
        let x = LEFT + (RIGHT - LEFT) * f;
        let v = h.lo + h.width * bins as f64 * f;
        let _ = writeln!(
            s,
            "<line x1=\"{x:.2}\" y1=\"{BOTTOM}\" x2=\"{x:.2}\" y2=\"{y2}\" stroke=\"black\"/>\
             <text x=\"{x:.2}\" y=\"{ty}\" text-anchor=\"middle\">{l}</text>",
            y2 = BOTTOM + 5.0,
            ty = BOTTOM + 18.0,
            l = tick(v),
        );
        let c = (max_count as f64 * f).round();
        let y = y_of(c);
        let _ = writeln!(
            s,
            "<line x1=\"{x2}\" y1=\"{y:.2}\" x2=\"{LEFT}\" y2=\"{y:.2}\" stroke=\"black\"/>\
             <text x=\"{tx}\" y=\"{ty:.2}\" text-anchor=\"end\">{c}</text>",
            x2 = LEFT - 5.0,
            tx = LEFT - 8.0,
            ty = y + 4.0,
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">residual angle (degrees)</text>",
        (LEFT + RIGHT) / 2.0,
        BOTTOM + 40.0
    );
    let _ = writeln!(
        s,
        "<text x=\"16\" y=\"{y}\" text-anchor=\"middle\" transform=\"rotate(-90 16 {y})\">\
         number of edges</text>",
        y = (TOP + BOTTOM) / 2.0
    );
    if !annotations.is_empty() {
        let x = PANEL_WIDTH + 10.0;
        let _ = writeln!(
            s,
            "<text x=\"{x}\" y=\"{TOP}\" font-size=\"14\" font-weight=\"bold\">certificate</text>"
        );
        for (k, (key, value)) in annotations.iter().enumerate() {
            let y = TOP + 24.0 * (k + 1) as f64;
            let _ = writeln!(
                s,
                "<text class=\"annotation\" x=\"{x}\" y=\"{y}\"><tspan font-weight=\"bold\">{}\
                 </tspan>: {}</text>",
                escape(key),
                escape(value)
            );
        }
    }
    s.push_str("</svg>\n");
    s
}

/// The certificate facts shown next to the histogram: verdict, method, cost (upper bound),
/// proven lower bound, gap, relative gap and the smallest eigenvalue of the certificate
/// matrix (as [`Certificate::min_eigenvalue`] reports it: the Lanczos estimate when one was
/// computed, else the verified bound).
///
/// ```
/// use rotavg::{BoundMethod, Certificate};
/// let c = Certificate::from_bounds(
///     1.0, Some(1.0), BoundMethod::Dual, Some(0.5), Default::default(), "", 0.0,
/// );
/// let facts = rotavg::plot::certificate_annotations(&c);
/// assert!(facts.iter().any(|(k, _)| k == "gap"));
/// ```
pub fn certificate_annotations(c: &Certificate) -> Vec<(String, String)> {
    let opt = |v: Option<f64>| v.map_or_else(|| "none".to_string(), |v| format!("{v:.6e}"));
    vec![
        ("verdict".into(), c.verdict.to_string()),
        ("method".into(), c.method.to_string()),
        (
            "cost (upper bound)".into(),
            format!("{:.6e}", c.upper_bound),
        ),
        ("proven lower bound".into(), opt(c.lower_bound)),
        ("gap".into(), opt(c.gap)),
        ("relative gap".into(), opt(c.relative_gap)),
        (
            "lambda_min (certificate matrix)".into(),
            opt(c.min_eigenvalue),
        ),
    ]
}

/// Write [`residual_histogram_svg`] to `path` ([`crate::Error::Io`] on failure).
pub fn write_svg(path: &str, svg: &str) -> crate::Result<()> {
    std::fs::write(path, svg).map_err(|e| crate::Error::Io {
        path: path.into(),
        message: e.to_string(),
    })
}
