//! The multiple-rotation-averaging pipeline `[D12]` (`paper-notes/certificates.md`):
//! initialise, solve locally, certify with the dual certificate `[D3]`-`[D9]`; when that fails,
//! bound the global minimum with the SDP relaxation (Clarabel, multipliers verified `[D4]`) for
//! small graphs or with the Riemannian staircase `[D11]` for large ones, and keep the better of
//! the local estimate and the polished SDP rounding.
//!
//! - [`average_multiple`]: estimate + certificate.
//! - [`certify_multiple_estimate`]: certify a given estimate **without changing it**.
//!
//! Every lower bound reported here is verified from multipliers by a sparse Cholesky
//! factorisation with a rigorous floating-point margin (or Gershgorin); the SDP solver's own
//! objective is never used. Any verified bound is a lower bound on the global minimum, so the
//! pipeline reports the largest of those it computed.

use crate::certificate::{BoundMethod, Certificate, GapTolerance};
use crate::certify::multiple::{
    CertifySettings, Verification, certify_multiple, lower_bound_from_multipliers, multipliers,
    stationarity_residual,
};
use crate::certify::spectrum::{SpectrumSettings, certificate_spectrum};
use crate::certify::staircase::{StaircaseSettings, staircase_bound};
use crate::error::{Error, Result};
use crate::multiple::{
    Initialisation, Loss, MultipleProblem, MultipleSettings, MultipleSolution, solve_multiple,
};
use crate::relax::{SdpSettings, SdpStatus, relax_multiple};
use crate::so3::Rotation;
use nalgebra::Matrix3;
use serde::{Deserialize, Serialize};
use std::fmt;
use std::time::Instant;

/// Absolute gap tolerance per unit of total edge weight used by the default
/// [`AverageMultipleSettings`]: the absolute tolerance is
/// `max(tolerance.absolute, ABSOLUTE_TOLERANCE_PER_WEIGHT * sum_e w_e)` (see
/// [`AverageMultipleSettings::effective_tolerance`]).
///
/// Why: at a noise-free optimum the certificate matrix `S = Q` is exactly singular, and the
/// provable gap is `3n (delta_0 + margin)` with a floating-point margin that grows with the
/// matrix norm (the weighted degrees) and the size, i.e. with the total weight `[D5]`, `[D6]`;
/// a fixed `1e-9` is not attainable beyond n ~ 100. `1e-11 sum_e w_e` means a gap equivalent
/// to a mean squared chordal residual of `1e-11` per unit weight (residual angles ~ `3e-6`
/// rad): far below any measurement noise, so no estimate with a materially higher cost can be
/// certified. For costs above `1e-5 sum_e w_e` (noise beyond ~ 0.1 degree) the relative
/// tolerance `1e-6` is larger anyway and this rule changes nothing.
pub const ABSOLUTE_TOLERANCE_PER_WEIGHT: f64 = 1e-11;

/// When the first dual certificate fails, the local solution is refined once with the gradient
/// tolerance multiplied by this factor before the dual certificate is retried.
pub const REFINE_FACTOR: f64 = 1e-6;

/// Refine before the first dual certificate when the stationarity residual `[D3]` exceeds this
/// times `|f| + absolute tolerance`.
pub const PRE_REFINE_RATIO: f64 = 1e-5;

const MARGIN_LIMITED: &str = "SDP / staircase skipped: the estimate is a critical point whose \
certificate matrix is PSD up to the floating-point margin of the verification; the gap is the \
verification's precision (3n x margin), which other multipliers cannot improve";

/// Which certificate the pipeline computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CertifyMode {
    /// Dual certificate; if it fails, the SDP when `n <= sdp_max_nodes`, else the staircase.
    #[default]
    Auto,
    /// Dual certificate only.
    Dual,
    /// Dual certificate, then the SDP (whatever the size) if it fails.
    Sdp,
    /// Dual certificate, then the Riemannian staircase if it fails.
    Staircase,
    /// No certificate.
    None,
}

impl CertifyMode {
    /// Short name: `auto`, `dual`, `sdp`, `staircase`, `none`.
    pub fn name(self) -> &'static str {
        match self {
            CertifyMode::Auto => "auto",
            CertifyMode::Dual => "dual",
            CertifyMode::Sdp => "sdp",
            CertifyMode::Staircase => "staircase",
            CertifyMode::None => "none",
        }
    }
}

/// Settings of [`average_multiple`] and [`certify_multiple_estimate`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AverageMultipleSettings {
    /// Local solver (loss, initialisation, tolerances).
    pub local: MultipleSettings,
    /// Which certificate to compute (only for the chordal loss: other losses get none).
    pub certify_mode: CertifyMode,
    /// Dual-certificate verification settings (tolerances, shifts, Lanczos, factor cap).
    pub certify: CertifySettings,
    /// Raise the absolute gap tolerance to `absolute_tolerance_per_weight * sum_e w_e` when that
    /// is larger than `certify.tolerance.absolute` (default `1e-11`,
    /// [`ABSOLUTE_TOLERANCE_PER_WEIGHT`]); `0` disables the rule.
    pub absolute_tolerance_per_weight: f64,
    /// SDP settings (Clarabel).
    pub sdp: SdpSettings,
    /// `Auto` runs the SDP only when the graph has at most this many nodes (default 150; the
    /// SDP takes ~7 s at n = 150 on sparse graphs on a 2-core machine).
    pub sdp_max_nodes: usize,
    /// Staircase settings (its `certify` field is replaced by [`Self::certify`] with the
    /// effective tolerance).
    pub staircase: StaircaseSettings,
    /// When set, also estimate the smallest eigenvalues of the certificate matrix whose
    /// multipliers gave the reported bound ([`Certificate::smallest_eigenvalues`], `[D14]`;
    /// estimates for figures, not bounds). Default `None`: no extra work. Not computed when the
    /// bound came from the staircase (its multipliers are not kept).
    pub spectrum: Option<SpectrumSettings>,
}

impl Default for AverageMultipleSettings {
    fn default() -> Self {
        AverageMultipleSettings {
            local: MultipleSettings::default(),
            certify_mode: CertifyMode::Auto,
            certify: CertifySettings::default(),
            absolute_tolerance_per_weight: ABSOLUTE_TOLERANCE_PER_WEIGHT,
            sdp: SdpSettings::default(),
            sdp_max_nodes: 150,
            staircase: StaircaseSettings::default(),
            spectrum: None,
        }
    }
}

impl AverageMultipleSettings {
    /// The gap tolerance applied to `problem`: `certify.tolerance` with the absolute part raised
    /// to `absolute_tolerance_per_weight * sum_e w_e` if that is larger.
    pub fn effective_tolerance(&self, problem: &MultipleProblem) -> GapTolerance {
        let total: f64 = problem.edges().iter().map(|e| e.weight).sum();
        let mut t = self.certify.tolerance;
        t.absolute = t.absolute.max(self.absolute_tolerance_per_weight * total);
        t
    }

    fn certify_for(&self, problem: &MultipleProblem) -> CertifySettings {
        CertifySettings {
            tolerance: self.effective_tolerance(problem),
            ..self.certify
        }
    }

    fn validate(&self) -> Result<()> {
        let v = self.absolute_tolerance_per_weight;
        if !(v.is_finite() && v >= 0.0) {
            return Err(Error::InvalidSettings {
                name: "absolute_tolerance_per_weight".into(),
                reason: format!("must be finite and >= 0, got {v}"),
            });
        }
        if let Some(sp) = &self.spectrum {
            sp.validate()?;
        }
        Ok(())
    }
}

/// One bounding method that ran.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MethodRun {
    /// Which method.
    pub method: BoundMethod,
    /// The verified lower bound it produced (on the global minimum), if any.
    pub lower_bound: Option<f64>,
    /// Wall time, seconds.
    pub seconds: f64,
    /// What happened, in words.
    pub note: String,
}

/// What the pipeline did.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PipelineDetails {
    /// The certify mode requested.
    pub certify_mode: CertifyMode,
    /// The bounding methods that ran, in order.
    pub methods: Vec<MethodRun>,
    /// Time of the local solve (initialisation included), seconds.
    pub solve_seconds: f64,
    /// Time spent refining the local solution to a tighter gradient tolerance before the dual
    /// certificate (included in `certify_seconds`), seconds.
    pub refine_seconds: f64,
    /// Time of all certification work (dual, SDP, staircase, polishing of the SDP rounding),
    /// seconds.
    pub certify_seconds: f64,
    /// Total time, seconds.
    pub total_seconds: f64,
    /// SDP outcome, when it ran.
    pub sdp_status: Option<SdpStatus>,
    /// Chordal cost of the polished SDP rounding, when the SDP ran.
    pub sdp_polished_cost: Option<f64>,
    /// `true` when the polished SDP rounding replaced the local estimate (lower cost).
    pub improved_by_sdp: bool,
    /// Stationarity residual of the certified estimate `[D3]` (0 at a critical point).
    pub stationarity_residual: Option<f64>,
    /// Why no certificate was computed (certificate `None`), or why the SDP / staircase was
    /// skipped after a failed dual certificate.
    pub skipped_reason: Option<String>,
}

/// The result of [`average_multiple`]: the estimate and its certificate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MultipleEstimate {
    /// The estimate (gauge `R_0 = I`), cost, solver report. When the SDP rounding won,
    /// `solution` is its polished version.
    pub solution: MultipleSolution,
    /// Certificate of `solution.rotations` for the chordal cost (`None` for other losses or
    /// `CertifyMode::None`).
    pub certificate: Option<Certificate>,
    /// Which methods ran, times, SDP status.
    pub details: PipelineDetails,
}

impl fmt::Display for MultipleEstimate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        writeln!(f, "{}", self.solution)?;
        match &self.certificate {
            Some(c) => write!(f, "certificate: {c}")?,
            None => write!(
                f,
                "certificate: none ({})",
                self.details
                    .skipped_reason
                    .as_deref()
                    .unwrap_or("not requested")
            )?,
        }
        write!(
            f,
            "\ntimes: solve {:.3} s, certify {:.3} s, total {:.3} s",
            self.details.solve_seconds, self.details.certify_seconds, self.details.total_seconds
        )
    }
}

/// The result of [`certify_multiple_estimate`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimateCertificate {
    /// The certificate of the given rotations (upper bound = their chordal cost).
    pub certificate: Certificate,
    /// Methods run, times, and the cost of the SDP's polished rounding if it ran (a better
    /// estimate exists when that is lower than the given cost).
    pub details: PipelineDetails,
}

impl fmt::Display for EstimateCertificate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.certificate)?;
        if let Some(c) = self.details.sdp_polished_cost {
            write!(f, "; SDP rounding + polish reaches cost {c:.9e}")?;
        }
        Ok(())
    }
}

/// The best verified bound seen so far.
struct Best {
    lower_bound: f64,
    method: BoundMethod,
    min_eigenvalue: Option<f64>,
    explanation: String,
    /// Verified lower bound on `lambda_min` of this bound's certificate matrix.
    verified_min_eigenvalue: f64,
    /// The Cholesky shift that verified it, if any (a shift-invert hint for the spectrum).
    shift: Option<f64>,
    /// The multipliers of this bound's certificate matrix (`None` for the staircase).
    lambdas: Option<Vec<Matrix3<f64>>>,
}

impl Best {
    fn offer(slot: &mut Option<Best>, cand: Best) {
        if slot
            .as_ref()
            .is_none_or(|b| cand.lower_bound > b.lower_bound)
        {
            *slot = Some(cand);
        }
    }
}

/// Run the SDP and verify its multipliers; returns the verified bound (if the multipliers were
/// usable) and the SDP's polished rounding.
fn run_sdp(
    problem: &MultipleProblem,
    settings: &AverageMultipleSettings,
    certify: &CertifySettings,
    details: &mut PipelineDetails,
    best: &mut Option<Best>,
) -> Result<Option<MultipleSolution>> {
    let t = Instant::now();
    let sdp = relax_multiple(problem, &settings.sdp)?;
    details.sdp_status = Some(sdp.status);
    let bound = if sdp.multipliers.len() == problem.num_rotations()
        && sdp
            .multipliers
            .iter()
            .all(|l| l.iter().all(|x| x.is_finite()))
    {
        Some(lower_bound_from_multipliers(
            problem,
            &sdp.multipliers,
            certify,
        )?)
    } else {
        None
    };
    // round + polish with the chordal local solver
    let polished = if sdp.rounded.len() == problem.num_rotations() {
        let local = MultipleSettings {
            loss: Loss::Chordal,
            init: Initialisation::Given(sdp.rounded.clone()),
            ..settings.local.clone()
        };
        solve_multiple(problem, &local).ok()
    } else {
        None
    };
    details.sdp_polished_cost = polished.as_ref().map(|p| p.chordal_cost);
    let note = format!(
        "Clarabel SDP ({:?}, {} iterations, {:.3} s); multipliers verified{}; rounding cost {:.9e}{}",
        sdp.status,
        sdp.iterations,
        sdp.solver_seconds,
        bound
            .as_ref()
            .map(|b| format!(
                ": lambda_min(Q - blkdiag(Lambda)) >= {:.3e}",
                b.verified_min_eigenvalue
            ))
            .unwrap_or_else(|| " (unusable multipliers)".into()),
        sdp.rounded_cost,
        polished
            .as_ref()
            .map(|p| format!(", polished {:.9e}", p.chordal_cost))
            .unwrap_or_default()
    );
    if let Some(b) = &bound {
        Best::offer(
            best,
            Best {
                lower_bound: b.lower_bound,
                method: BoundMethod::Sdp,
                min_eigenvalue: b
                    .min_eigenvalue_estimate
                    .or(Some(b.verified_min_eigenvalue)),
                explanation: format!(
                    "bound from the SDP relaxation's multipliers (Clarabel {:?}), verified \
                     independently: lambda_min(Q - blkdiag(Lambda)) >= {:.3e}",
                    sdp.status, b.verified_min_eigenvalue
                ),
                verified_min_eigenvalue: b.verified_min_eigenvalue,
                shift: b.shift,
                lambdas: Some(sdp.multipliers.clone()),
            },
        );
    }
    details.methods.push(MethodRun {
        method: BoundMethod::Sdp,
        lower_bound: bound.map(|b| b.lower_bound),
        seconds: t.elapsed().as_secs_f64(),
        note,
    });
    Ok(polished)
}

fn run_staircase(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &AverageMultipleSettings,
    certify: &CertifySettings,
    details: &mut PipelineDetails,
    best: &mut Option<Best>,
) -> Result<()> {
    let t = Instant::now();
    let st = StaircaseSettings {
        certify: *certify,
        ..settings.staircase
    };
    let r = staircase_bound(problem, rotations, &st)?;
    Best::offer(
        best,
        Best {
            lower_bound: r.bound.lower_bound,
            method: BoundMethod::Staircase,
            min_eigenvalue: r
                .bound
                .min_eigenvalue_estimate
                .or(Some(r.bound.verified_min_eigenvalue)),
            explanation: r.certificate.explanation.clone(),
            verified_min_eigenvalue: r.bound.verified_min_eigenvalue,
            shift: r.bound.shift,
            lambdas: None,
        },
    );
    details.methods.push(MethodRun {
        method: BoundMethod::Staircase,
        lower_bound: Some(r.bound.lower_bound),
        seconds: t.elapsed().as_secs_f64(),
        note: format!(
            "Riemannian staircase: rank {}, {} iterations, lifted cost {:.9e}; {}",
            r.rank, r.iterations, r.lifted_cost, r.stop_reason
        ),
    });
    Ok(())
}

/// Dual certificate at `rotations`: records the run, offers its bound, returns
/// `(certified, margin_limited)`. `margin_limited`: not certified, but the estimate is a critical
/// point and `S + shift I` factorised with most of the verified deficit being the floating-point
/// margin `[D6]` (not a negative eigenvalue): the gap is the verification's precision, and the
/// SDP / staircase multipliers (verified the same way, at the same optimum) cannot do better.
fn run_dual(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    certify: &CertifySettings,
    details: &mut PipelineDetails,
    best: &mut Option<Best>,
) -> Result<(bool, bool)> {
    let c = certify_multiple(problem, rotations, certify)?;
    Best::offer(
        best,
        Best {
            lower_bound: c.bound.lower_bound,
            method: BoundMethod::Dual,
            min_eigenvalue: c.certificate.min_eigenvalue,
            explanation: c.certificate.explanation.clone(),
            verified_min_eigenvalue: c.bound.verified_min_eigenvalue,
            shift: c.bound.shift,
            // O(m), negligible next to the verification
            lambdas: Some(multipliers(problem, rotations)?),
        },
    );
    details.stationarity_residual = Some(c.stationarity_residual);
    details.methods.push(MethodRun {
        method: BoundMethod::Dual,
        lower_bound: Some(c.bound.lower_bound),
        seconds: c.certificate.seconds,
        note: format!(
            "dual certificate: {} (stationarity residual {:.3e})",
            c.certificate.verdict, c.stationarity_residual
        ),
    });
    let certified = c.certificate.is_certified();
    let b = &c.bound;
    let margin_limited = !certified
        && b.verification == Verification::Cholesky
        && b.fp_margin >= 0.5 * (-b.verified_min_eigenvalue)
        && c.stationarity_residual <= 1e-6 * (c.certificate.upper_bound.abs() + 1.0);
    Ok((certified, margin_limited))
}

/// Re-solve (chordal) from the current estimate with the gradient tolerance times
/// [`REFINE_FACTOR`]; replaces `solution` when the cost does not increase. Returns whether it
/// replaced it.
fn refine(
    problem: &MultipleProblem,
    settings: &AverageMultipleSettings,
    solution: &mut MultipleSolution,
    details: &mut PipelineDetails,
) -> bool {
    let t = Instant::now();
    let local = MultipleSettings {
        loss: Loss::Chordal,
        init: Initialisation::Given(solution.rotations.clone()),
        gradient_tolerance: settings.local.gradient_tolerance * REFINE_FACTOR,
        ..settings.local.clone()
    };
    let replaced = match solve_multiple(problem, &local) {
        Ok(r) if r.chordal_cost <= solution.chordal_cost => {
            let before = solution.report.clone();
            *solution = MultipleSolution {
                report: crate::report::SolverReport {
                    iterations: before.iterations + r.report.iterations,
                    seconds: before.seconds + r.report.seconds,
                    ..r.report.clone()
                },
                init_cost: solution.init_cost,
                ..r
            };
            true
        }
        _ => false,
    };
    details.refine_seconds += t.elapsed().as_secs_f64();
    replaced
}

/// The certificate from the best bound; with `spectrum` set, also the smallest-eigenvalue
/// estimates of that bound's certificate matrix `[D14]`.
fn final_certificate(
    problem: &MultipleProblem,
    cost: f64,
    mut best: Option<Best>,
    note: Option<&str>,
    tolerance: GapTolerance,
    seconds: f64,
    spectrum: Option<&SpectrumSettings>,
) -> Certificate {
    if let (Some(b), Some(n)) = (best.as_mut(), note) {
        b.explanation = format!("{}; {n}", b.explanation);
    }
    match best {
        Some(b) => {
            let mut c = Certificate::from_bounds(
                cost,
                Some(b.lower_bound),
                b.method,
                b.min_eigenvalue,
                tolerance,
                b.explanation,
                seconds,
            );
            c.verified_min_eigenvalue = Some(b.verified_min_eigenvalue);
            if let (Some(sp), Some(l)) = (spectrum, &b.lambdas) {
                // an estimate for a figure: its failure never fails the certification
                c.smallest_eigenvalues = certificate_spectrum(problem, l, sp, b.shift).ok();
            }
            c
        }
        None => Certificate::from_bounds(
            cost,
            None,
            BoundMethod::Dual,
            None,
            tolerance,
            "no lower bound could be computed",
            seconds,
        ),
    }
}

fn wants_sdp(mode: CertifyMode, n: usize, max_nodes: usize) -> Option<bool> {
    match mode {
        CertifyMode::Auto => Some(n <= max_nodes),
        CertifyMode::Sdp => Some(true),
        CertifyMode::Staircase => Some(false),
        CertifyMode::Dual | CertifyMode::None => None,
    }
}

/// Multiple rotation averaging with a certificate: initialise and solve locally
/// ([`solve_multiple`] with `settings.local`), then, for the chordal loss, certify:
///
/// 1. the dual certificate of the local solution `[D3]`-`[D9]`;
/// 2. if it does not certify and the mode allows: the SDP (when `n <= sdp_max_nodes` in
///    `Auto`, always in `Sdp`): its multipliers are verified independently `[D4]`, its rounding
///    is polished by the local solver and replaces the estimate when its chordal cost is lower
///    (the dual certificate is then recomputed at the new estimate); or the Riemannian
///    staircase `[D11]` (large graphs in `Auto`, always in `Staircase`).
///
/// The certificate's lower bound is the **largest** verified bound computed (each is a lower
/// bound on the global minimum, whatever estimate produced it) and its `method` names the
/// method that produced it. The absolute gap tolerance follows
/// [`AverageMultipleSettings::effective_tolerance`]. Other losses get no certificate.
///
/// ```
/// use rotavg::multiple::average::{average_multiple, AverageMultipleSettings};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, _) = SyntheticGraph { num_rotations: 30, num_edges: 90, noise_sigma: 0.05, ..Default::default() }.generate();
/// let est = average_multiple(&p, &AverageMultipleSettings::default()).unwrap();
/// assert!(est.certificate.unwrap().is_certified());
/// ```
pub fn average_multiple(
    problem: &MultipleProblem,
    settings: &AverageMultipleSettings,
) -> Result<MultipleEstimate> {
    let start = Instant::now();
    settings.validate()?;
    let mut solution = solve_multiple(problem, &settings.local)?;
    let mut details = PipelineDetails {
        certify_mode: settings.certify_mode,
        solve_seconds: solution.report.seconds,
        ..Default::default()
    };
    if settings.certify_mode == CertifyMode::None || solution.loss != Loss::Chordal {
        details.skipped_reason = Some(if settings.certify_mode == CertifyMode::None {
            "certify mode none".into()
        } else {
            format!(
                "the {} loss has no certificate (only chordal L2 is certifiable)",
                solution.loss.name()
            )
        });
        details.total_seconds = start.elapsed().as_secs_f64();
        return Ok(MultipleEstimate {
            solution,
            certificate: None,
            details,
        });
    }
    let t_cert = Instant::now();
    let certify = settings.certify_for(problem);
    let mut best = None;
    // The dual certificate needs an accurate critical point: the local solver's relative
    // gradient test (`||grad|| / sum w`) can leave a stationarity residual that is large
    // against a small cost (parking-garage: residual 3.5e-6 at cost 1.7e-3). Refine with a much
    // tighter tolerance (Newton converges quadratically: a few iterations) before the dual
    // certificate when the residual is large against the cost, and otherwise once after a
    // failed dual certificate.
    let residual = stationarity_residual(problem, &solution.rotations)?;
    let mut refined = false;
    if residual > PRE_REFINE_RATIO * (solution.chordal_cost.abs() + certify.tolerance.absolute) {
        refined = refine(problem, settings, &mut solution, &mut details);
    }
    let (mut certified, mut margin_limited) = run_dual(
        problem,
        &solution.rotations,
        &certify,
        &mut details,
        &mut best,
    )?;
    if !certified
        && !refined
        && !margin_limited
        && refine(problem, settings, &mut solution, &mut details)
    {
        (certified, margin_limited) = run_dual(
            problem,
            &solution.rotations,
            &certify,
            &mut details,
            &mut best,
        )?;
    }
    if margin_limited {
        details.skipped_reason = Some(MARGIN_LIMITED.into());
    }
    if !certified && !margin_limited {
        match wants_sdp(
            settings.certify_mode,
            problem.num_rotations(),
            settings.sdp_max_nodes,
        ) {
            Some(true) => {
                let polished = run_sdp(problem, settings, &certify, &mut details, &mut best)?;
                if let Some(p) = polished
                    && p.chordal_cost < solution.chordal_cost
                {
                    solution = p;
                    details.improved_by_sdp = true;
                    run_dual(
                        problem,
                        &solution.rotations,
                        &certify,
                        &mut details,
                        &mut best,
                    )?;
                }
            }
            Some(false) => run_staircase(
                problem,
                &solution.rotations,
                settings,
                &certify,
                &mut details,
                &mut best,
            )?,
            None => {}
        }
    }
    let certificate = final_certificate(
        problem,
        solution.chordal_cost,
        best,
        margin_limited.then_some(MARGIN_LIMITED),
        certify.tolerance,
        t_cert.elapsed().as_secs_f64(),
        settings.spectrum.as_ref(),
    );
    details.certify_seconds = t_cert.elapsed().as_secs_f64();
    details.total_seconds = start.elapsed().as_secs_f64();
    Ok(MultipleEstimate {
        solution,
        certificate: Some(certificate),
        details,
    })
}

/// Certify a given estimate (e.g. computed by another solver) **without changing it**: upper
/// bound = its chordal cost; lower bound = the largest verified bound among the dual
/// certificate at the estimate `[D3]`-`[D9]` and, if that does not certify, the SDP's verified
/// multipliers (`n <= sdp_max_nodes` in `Auto`, or mode `Sdp`) or the staircase (large graphs
/// in `Auto`, or mode `Staircase`). Certified only when the verified gap is within the
/// tolerance ([`AverageMultipleSettings::effective_tolerance`]); an estimate that is not a
/// critical point gets a (valid) bound. `certify_mode` `None` is treated as `Dual`;
/// `settings.local` is used only to polish the SDP rounding (reported in
/// [`PipelineDetails::sdp_polished_cost`], never substituted).
///
/// ```
/// use rotavg::multiple::average::{certify_multiple_estimate, AverageMultipleSettings};
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (p, gt) = SyntheticGraph { num_rotations: 20, num_edges: 40, noise_sigma: 0.0, ..Default::default() }.generate();
/// let c = certify_multiple_estimate(&p, &gt, &AverageMultipleSettings::default()).unwrap();
/// assert!(c.certificate.is_certified());
/// ```
pub fn certify_multiple_estimate(
    problem: &MultipleProblem,
    rotations: &[Rotation],
    settings: &AverageMultipleSettings,
) -> Result<EstimateCertificate> {
    let start = Instant::now();
    settings.validate()?;
    problem.check_estimate(rotations)?;
    let certify = settings.certify_for(problem);
    let mode = match settings.certify_mode {
        CertifyMode::None => CertifyMode::Dual,
        m => m,
    };
    let mut details = PipelineDetails {
        certify_mode: mode,
        ..Default::default()
    };
    let mut best = None;
    let (certified, margin_limited) =
        run_dual(problem, rotations, &certify, &mut details, &mut best)?;
    if margin_limited {
        details.skipped_reason = Some(MARGIN_LIMITED.into());
    }
    if !certified && !margin_limited {
        match wants_sdp(mode, problem.num_rotations(), settings.sdp_max_nodes) {
            Some(true) => {
                run_sdp(problem, settings, &certify, &mut details, &mut best)?;
            }
            Some(false) => run_staircase(
                problem,
                rotations,
                settings,
                &certify,
                &mut details,
                &mut best,
            )?,
            None => {}
        }
    }
    details.stationarity_residual = Some(stationarity_residual(problem, rotations)?);
    let certificate = final_certificate(
        problem,
        problem.chordal_cost(rotations),
        best,
        margin_limited.then_some(MARGIN_LIMITED),
        certify.tolerance,
        start.elapsed().as_secs_f64(),
        settings.spectrum.as_ref(),
    );
    details.certify_seconds = start.elapsed().as_secs_f64();
    details.total_seconds = details.certify_seconds;
    Ok(EstimateCertificate {
        certificate,
        details,
    })
}
