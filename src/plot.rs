//! SVG figures for the CLI's `--plot FILE.svg`: the histogram of residual angles (degrees),
//! and, when a certificate was computed, a text panel with its facts and a second chart with the
//! smallest eigenvalues of the certificate matrix (estimates) against the **proven** lower bound
//! on `lambda_min` (`paper-notes/certificates.md` `[D14]`).
//!
//! Drawn with [`plotters`] (a maintained plotting crate), SVG backend only, built with
//! `default-features = false`: no system library (fontconfig / freetype) and no embedded font
//! is needed, because the SVG backend writes text as `<text>` elements (the viewer picks the
//! font) and plotters' "naive" font module only *estimates* label sizes for the layout
//! (`plotters-0.3.7/src/style/font/naive.rs`, selected when neither `ttf` nor `ab_glyph` is
//! enabled). Every number drawn is finite; non-finite inputs are dropped.

use crate::Certificate;
use crate::certify::spectrum::SpectrumMethod;
use plotters::prelude::*;
use plotters::style::FontStyle;
use plotters::style::text_anchor::{HPos, Pos, VPos};

/// Most bins a histogram gets.
pub const MAX_BINS: usize = 40;

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

/// Width of the histogram (and eigenvalue) chart column, pixels.
const CHART_WIDTH: u32 = 520;
/// Width of the text column next to the charts, pixels.
const TEXT_WIDTH: u32 = 380;
/// Height of one row (histogram row, eigenvalue row), pixels.
const ROW_HEIGHT: u32 = 400;
/// Fill of the histogram bars (steelblue, `#4682B4`).
pub const BAR_COLOR: RGBColor = RGBColor(70, 130, 180);
/// Colour of the expected null-space eigenvalues (the gauge directions).
const NULL_COLOR: RGBColor = RGBColor(230, 120, 20);
/// Colour of the proven-bound line.
const BOUND_COLOR: RGBColor = RGBColor(200, 30, 30);

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

/// What the eigenvalue chart shows: the smallest eigenvalues of a certificate matrix
/// (estimates, ascending), the proven lower bound on `lambda_min`, and how many eigenvalues are
/// expected to be ~0 at a certified solution.
#[derive(Debug, Clone, PartialEq)]
pub struct EigenvaluePanel {
    /// Smallest eigenvalues (estimates), ascending.
    pub values: Vec<f64>,
    /// Residual of each value (`||S x - lambda x||`).
    pub residuals: Vec<f64>,
    /// Proven lower bound on `lambda_min`, if known.
    pub verified_lower_bound: Option<f64>,
    /// Dimension of the null space expected at a certified solution (3 gauge directions for
    /// multiple rotation averaging, 1 for the conjugate SDP: `z* = [vec S; 1]`).
    pub null_dimension: usize,
    /// How the values were computed, in words (shown in the figure).
    pub method: String,
}

/// The eigenvalue chart data of a certificate, when it carries
/// [`Certificate::smallest_eigenvalues`]; `null_dimension` as in [`EigenvaluePanel`].
///
/// ```
/// use rotavg::{BoundMethod, Certificate};
/// let c = Certificate::from_bounds(1.0, Some(1.0), BoundMethod::Dual, None, Default::default(), "", 0.0);
/// assert!(rotavg::plot::eigenvalue_panel(&c, 3).is_none());
/// ```
pub fn eigenvalue_panel(c: &Certificate, null_dimension: usize) -> Option<EigenvaluePanel> {
    let e = c.smallest_eigenvalues.as_ref()?;
    let method = match e.method {
        SpectrumMethod::Dense => "dense eigen-decomposition".to_string(),
        SpectrumMethod::ShiftInvertLanczos => format!(
            "shift-invert block Lanczos (shift {}){}",
            e.shift.map_or_else(|| "?".into(), |s| format!("{s:.2e}")),
            if e.converged() { "" } else { ", not converged" }
        ),
        SpectrumMethod::Lanczos => format!(
            "block Lanczos{}",
            if e.converged() { "" } else { ", not converged" }
        ),
    };
    Some(EigenvaluePanel {
        values: e.values.clone(),
        residuals: e.residuals.clone(),
        verified_lower_bound: c.verified_min_eigenvalue,
        null_dimension,
        method,
    })
}

/// SVG of the histogram of `residuals_deg` (one bar per bin of [`histogram`], filled with
/// [`BAR_COLOR`], zero-count bins included) under `title`; when `annotations` is not empty, a
/// text panel to the right lists them as `key: value` lines.
///
/// ```
/// let svg = rotavg::plot::residual_histogram_svg(
///     &[0.5, 1.0, 1.5, 4.0],
///     "residuals",
///     &[("gap".to_string(), "1e-9".to_string())],
/// );
/// assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
/// assert_eq!(svg.matches("fill=\"#4682B4\"").count(), 3);
/// ```
pub fn residual_histogram_svg(
    residuals_deg: &[f64],
    title: &str,
    annotations: &[(String, String)],
) -> String {
    figure_svg(residuals_deg, title, annotations, None)
}

/// The whole `--plot` figure: [`residual_histogram_svg`] and, when `eigen` is given, a second
/// row with the eigenvalue chart (index on x, value on y, linear, zero line; the expected
/// null-space values in orange; a red line at the proven lower bound labelled
/// `proven lambda_min >= ...`) and the values as text to its right.
///
/// ```
/// use rotavg::plot::{figure_svg, EigenvaluePanel};
/// let e = EigenvaluePanel {
///     values: vec![0.0, 1e-12, 2e-12, 0.8, 0.8, 0.8],
///     residuals: vec![1e-14; 6],
///     verified_lower_bound: Some(-1e-10),
///     null_dimension: 3,
///     method: "dense".into(),
/// };
/// let svg = figure_svg(&[1.0, 2.0], "t", &[("a".into(), "b".into())], Some(&e));
/// assert!(svg.contains("proven lambda_min &gt;= -1.000e-10"));
/// ```
pub fn figure_svg(
    residuals_deg: &[f64],
    title: &str,
    annotations: &[(String, String)],
    eigen: Option<&EigenvaluePanel>,
) -> String {
    let with_text = !annotations.is_empty() || eigen.is_some();
    let width = if with_text {
        CHART_WIDTH + TEXT_WIDTH
    } else {
        CHART_WIDTH
    };
    let height = if eigen.is_some() {
        2 * ROW_HEIGHT
    } else {
        ROW_HEIGHT
    };
    let mut out = String::new();
    {
        let root = SVGBackend::with_string(&mut out, (width, height)).into_drawing_area();
        // Drawing into a String cannot fail with the SVG backend and the naive font module;
        // should it, the partial figure is still a closed, well-formed SVG document.
        let _ = draw(&root, residuals_deg, title, annotations, eigen);
        let _ = root.present();
    }
    out
}

type Area<'a> = DrawingArea<SVGBackend<'a>, plotters::coord::Shift>;
type DrawResult = std::result::Result<(), Box<dyn std::error::Error + 'static>>;

fn font(size: f64) -> TextStyle<'static> {
    ("sans-serif", size).into_font().color(&BLACK)
}

fn bold(size: f64) -> TextStyle<'static> {
    ("sans-serif", size)
        .into_font()
        .style(FontStyle::Bold)
        .color(&BLACK)
}

fn draw(
    root: &Area<'_>,
    residuals_deg: &[f64],
    title: &str,
    annotations: &[(String, String)],
    eigen: Option<&EigenvaluePanel>,
) -> DrawResult {
    root.fill(&WHITE)?;
    let (top, bottom) = if eigen.is_some() {
        let (a, b) = root.split_vertically(ROW_HEIGHT);
        (a, Some(b))
    } else {
        (root.clone(), None)
    };
    let (hist_area, text_area) = top.split_horizontally(CHART_WIDTH);
    draw_histogram(&hist_area, residuals_deg, title)?;
    if !annotations.is_empty() {
        text_area.draw(&Text::new("certificate", (10, 40), bold(17.0)))?;
        for (k, (key, value)) in annotations.iter().enumerate() {
            let y = 40 + 24 * (k as i32 + 1);
            text_area.draw(&Text::new(format!("{key}: {value}"), (10, y), font(14.0)))?;
        }
    }
    if let (Some(area), Some(e)) = (bottom, eigen) {
        let (chart_area, text_area) = area.split_horizontally(CHART_WIDTH);
        draw_eigenvalues(&chart_area, e)?;
        draw_eigen_text(&text_area, e)?;
    }
    Ok(())
}

fn draw_histogram(area: &Area<'_>, residuals_deg: &[f64], title: &str) -> DrawResult {
    let h = histogram(residuals_deg);
    let bins = h.counts.len();
    let max_count = h.counts.iter().copied().max().unwrap_or(0).max(1) as f64;
    let hi = h.lo + h.width * bins as f64;
    let mut chart = ChartBuilder::on(area)
        .caption(title, ("sans-serif", 18.0))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(h.lo..hi, 0.0..max_count * 1.05)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_desc("residual angle (degrees)")
        .y_desc("count")
        .x_labels(6)
        .x_label_formatter(&|v| tick(*v))
        .y_label_formatter(&|v| tick(*v))
        .label_style(font(13.0))
        .axis_desc_style(font(14.0))
        .draw()?;
    chart.draw_series(h.counts.iter().enumerate().map(|(k, &c)| {
        let x0 = h.lo + h.width * k as f64;
        let mut bar = Rectangle::new([(x0, 0.0), (x0 + h.width, c as f64)], BAR_COLOR.filled());
        bar.set_margin(0, 0, 1, 1);
        bar
    }))?;
    Ok(())
}

/// Y range of the eigenvalue chart: the values, 0 and the proven bound, padded by 8%.
fn eigen_range(e: &EigenvaluePanel) -> (f64, f64) {
    let mut lo: f64 = 0.0;
    let mut hi: f64 = 0.0;
    for v in e.values.iter().chain(e.verified_lower_bound.iter()) {
        if v.is_finite() {
            lo = lo.min(*v);
            hi = hi.max(*v);
        }
    }
    let span = hi - lo;
    if !(span > 0.0 && span.is_finite()) {
        return (-1.0, 1.0);
    }
    (lo - 0.08 * span, hi + 0.08 * span)
}

fn draw_eigenvalues(area: &Area<'_>, e: &EigenvaluePanel) -> DrawResult {
    let k = e.values.len().max(1);
    let (lo, hi) = eigen_range(e);
    let xr = 0.5..k as f64 + 0.5;
    let mut chart = ChartBuilder::on(area)
        .caption(
            "smallest eigenvalues of the certificate matrix (estimates)",
            ("sans-serif", 16.0),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d(xr.clone(), lo..hi)?;
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_desc("index k (ascending)")
        .y_desc("lambda_k")
        .x_labels(k.min(12))
        .x_label_formatter(&|v| {
            if (v - v.round()).abs() < 1e-9 {
                format!("{}", v.round())
            } else {
                String::new()
            }
        })
        .y_label_formatter(&|v| tick(*v))
        .label_style(font(13.0))
        .axis_desc_style(font(14.0))
        .draw()?;
    // zero line
    chart.draw_series(LineSeries::new(
        [(xr.start, 0.0), (xr.end, 0.0)],
        BLACK.stroke_width(1),
    ))?;
    // proven lower bound on lambda_min
    if let Some(mu) = e.verified_lower_bound.filter(|m| m.is_finite()) {
        chart.draw_series(DashedLineSeries::new(
            [(xr.start, mu), (xr.end, mu)],
            6,
            4,
            BOUND_COLOR.stroke_width(2),
        ))?;
        // label just under the line (above it when the line is near the bottom)
        // backend_coord is in root pixels; area.draw takes area-relative pixels
        // (right-aligned at the right end, where the ascending values are highest)
        let (ox, oy) = area.get_base_pixel();
        let (px, py) = chart.backend_coord(&(xr.end, mu));
        let (_, pbottom) = chart.backend_coord(&(xr.end, lo));
        let y = if pbottom - py > 24 { py + 6 } else { py - 20 };
        area.draw(&Text::new(
            format!("proven lambda_min >= {mu:.3e}"),
            (px - ox - 8, y - oy),
            font(13.0)
                .color(&BOUND_COLOR)
                .pos(Pos::new(HPos::Right, VPos::Top)),
        ))?;
    }
    // the values: expected null space (orange), the rest (blue)
    chart.draw_series(
        e.values
            .iter()
            .enumerate()
            .filter(|(_, v)| v.is_finite())
            .map(|(i, &v)| {
                let color = if i < e.null_dimension {
                    NULL_COLOR
                } else {
                    BAR_COLOR
                };
                Circle::new(((i + 1) as f64, v), 5, color.filled())
            }),
    )?;
    Ok(())
}

fn draw_eigen_text(area: &Area<'_>, e: &EigenvaluePanel) -> DrawResult {
    let mut y = 40;
    let mut line = |text: String, style: TextStyle<'static>, dy: i32| -> DrawResult {
        area.draw(&Text::new(text, (10, y), style))?;
        y += dy;
        Ok(())
    };
    line("eigenvalue estimates".into(), bold(17.0), 22)?;
    line(format!("method: {}", e.method), font(12.0), 18)?;
    line(
        "estimates, not proofs; the proof is the".into(),
        font(12.0),
        16,
    )?;
    match e.verified_lower_bound.filter(|m| m.is_finite()) {
        Some(mu) => line(
            format!("verified bound lambda_min >= {mu:.3e}"),
            font(12.0).color(&BOUND_COLOR),
            18,
        )?,
        None => line("verified bound (not available here)".into(), font(12.0), 18)?,
    }
    line(
        format!(
            "expected at a certified solution: {} eigenvalue{} ~ 0",
            e.null_dimension,
            if e.null_dimension == 1 { "" } else { "s" }
        ),
        font(12.0).color(&NULL_COLOR),
        16,
    )?;
    line(
        if e.null_dimension == 3 {
            "(the 3 gauge directions: S Y = 0), the rest > 0".into()
        } else {
            "(z* = [vec S; 1] with C z* = 0), the rest > 0".into()
        },
        font(12.0).color(&NULL_COLOR),
        22,
    )?;
    for (i, v) in e.values.iter().enumerate() {
        let r = e.residuals.get(i).copied().unwrap_or(f64::NAN);
        let text = if r.is_finite() {
            format!("lambda_{} = {v:.6e}  (residual {r:.1e})", i + 1)
        } else {
            format!("lambda_{} = {v:.6e}", i + 1)
        };
        if v.is_finite() {
            line(text, font(12.0), 17)?;
        }
    }
    Ok(())
}

/// The certificate facts shown next to the histogram: verdict, method, cost (upper bound),
/// proven lower bound, gap, relative gap, the proven lower bound on the smallest eigenvalue of
/// the certificate matrix ([`Certificate::verified_min_eigenvalue`]) and its estimate
/// ([`Certificate::min_eigenvalue`]: the Lanczos estimate when one was computed, else the
/// verified bound).
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
            "verified bound on lambda_min".into(),
            opt(c.verified_min_eigenvalue),
        ),
        ("lambda_min estimate".into(), opt(c.min_eigenvalue)),
    ]
}

/// Write an SVG ([`figure_svg`], [`residual_histogram_svg`]) to `path` ([`crate::Error::Io`] on failure).
pub fn write_svg(path: &str, svg: &str) -> crate::Result<()> {
    std::fs::write(path, svg).map_err(|e| crate::Error::Io {
        path: path.into(),
        message: e.to_string(),
    })
}

/// Write the `--plot` figure to `path`: the histogram of `residuals_rad` (radians, drawn in
/// degrees) of `what` (e.g. `edges`, `pairs`) under the title `NAME: residual angles of m
/// WHAT` (`NAME` the file name of `input`), the certificate's facts, and, when the certificate
/// carries them, the smallest eigenvalues of its certificate matrix with `null_dimension`
/// values expected at ~0 (3 gauge directions for multiple averaging, 1 for the conjugate SDP).
///
/// ```
/// let path = std::env::temp_dir().join(format!("rotavg-doc-fig-{}.svg", std::process::id()));
/// let path = path.to_str().unwrap();
/// rotavg::plot::write_figure(path, &[0.01, 0.02, 0.03], "edges", None, 3, "data/graph.g2o")?;
/// let svg = std::fs::read_to_string(path).unwrap();
/// std::fs::remove_file(path).unwrap();
/// assert!(svg.contains("graph.g2o: residual angles of 3 edges"));
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn write_figure(
    path: &str,
    residuals_rad: &[f64],
    what: &str,
    certificate: Option<&Certificate>,
    null_dimension: usize,
    input: &str,
) -> crate::Result<()> {
    let deg: Vec<f64> = residuals_rad.iter().map(|a| a.to_degrees()).collect();
    let notes = certificate.map(certificate_annotations).unwrap_or_default();
    let eigen = certificate.and_then(|c| eigenvalue_panel(c, null_dimension));
    // the file name only: a long path would not fit above the histogram
    let name = std::path::Path::new(input)
        .file_name()
        .map_or_else(|| input.to_string(), |f| f.to_string_lossy().into_owned());
    let title = format!("{name}: residual angles of {} {what}", deg.len());
    write_svg(path, &figure_svg(&deg, &title, &notes, eigen.as_ref()))
}

/// [`write_figure`] for multiple averaging: the residual angles of the edges of `problem` at
/// `rotations`, 3 gauge directions.
///
/// ```
/// use rotavg::multiple::{Edge, MultipleProblem};
/// use rotavg::Rotation;
/// let p = MultipleProblem::new(2, vec![Edge { i: 0, j: 1, rotation: Rotation::identity(), weight: 1.0 }])?;
/// let path = std::env::temp_dir().join(format!("rotavg-doc-mfig-{}.svg", std::process::id()));
/// let path = path.to_str().unwrap();
/// rotavg::plot::write_multiple_figure(path, &p, &[Rotation::identity(); 2], None, "g.json")?;
/// assert!(std::fs::read_to_string(path).unwrap().contains("residual angles of 1 edges"));
/// std::fs::remove_file(path).unwrap();
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn write_multiple_figure(
    path: &str,
    problem: &crate::multiple::MultipleProblem,
    rotations: &[crate::Rotation],
    certificate: Option<&Certificate>,
    input: &str,
) -> crate::Result<()> {
    problem.check_estimate(rotations)?;
    write_figure(
        path,
        &problem.residual_angles(rotations),
        "edges",
        certificate,
        3,
        input,
    )
}

/// [`write_figure`] for conjugate averaging: the residual angles of the pairs of `problem` at
/// `s`, one null direction.
///
/// ```
/// use rotavg::conjugate::ConjugateProblem;
/// use rotavg::Rotation;
/// let p = ConjugateProblem::from_rotations(&[Rotation::identity()], &[Rotation::identity()])?;
/// let path = std::env::temp_dir().join(format!("rotavg-doc-cfig-{}.svg", std::process::id()));
/// let path = path.to_str().unwrap();
/// rotavg::plot::write_conjugate_figure(path, &p, &Rotation::identity(), None, "pairs.json")?;
/// assert!(std::fs::read_to_string(path).unwrap().contains("residual angles of 1 pairs"));
/// std::fs::remove_file(path).unwrap();
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn write_conjugate_figure(
    path: &str,
    problem: &crate::conjugate::ConjugateProblem,
    s: &crate::Rotation,
    certificate: Option<&Certificate>,
    input: &str,
) -> crate::Result<()> {
    write_figure(
        path,
        &problem.residual_angles(s),
        "pairs",
        certificate,
        1,
        input,
    )
}
