//! The conjugate-averaging pipeline: quaternion closed form -> chordal Gauss-Newton -> SDP
//! relaxation -> rank-one extraction and polish -> verified certificate `[H9]`.

use super::local::{
    ConjugateSettings, ConjugateSolution, Loss, solve_conjugate, solve_conjugate_from,
};
use super::problem::ConjugateProblem;
use super::sdp::{
    SdpSettings, SdpStatus, constraint_matrices, cost_matrix, extract_rotation, refine_multipliers,
    relax_conjugate, verify_lower_bound,
};
use crate::certificate::{BoundMethod, Certificate, GapTolerance};
use crate::certify::spectrum::{SpectrumEstimate, SpectrumMethod};
use crate::error::{Error, Result};
use crate::so3::{Metric, Rotation};
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Whether and how to certify.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum CertifyMode {
    /// SDP certificate when the cost is chordal L2 (the only certified objective), else none.
    #[default]
    Auto,
    /// SDP certificate (error if the cost is not chordal L2).
    Sdp,
    /// No certificate.
    None,
}

/// Settings of [`average_conjugate`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize, Default)]
#[serde(default)]
pub struct AverageSettings {
    /// The local solver (default: chordal L2).
    pub local: ConjugateSettings,
    /// Certification mode.
    pub certify: CertifyMode,
    /// Clarabel settings.
    pub sdp: SdpSettings,
    /// Gap tolerance of the verdict.
    pub tolerance: GapTolerance,
}

/// Statistics of the SDP step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SdpSummary {
    /// Clarabel's status.
    pub status: SdpStatus,
    /// Clarabel's iterations.
    pub iterations: u32,
    /// Time of the Clarabel solve (setup included), seconds.
    pub solve_seconds: f64,
    /// `lambda_2(Z) / lambda_1(Z)` (0 = rank one, relaxation tight).
    pub eigenvalue_ratio: f64,
    /// Chordal cost of the rotation extracted from `Z` after polishing, if extraction worked.
    pub extracted_cost: Option<f64>,
    /// `true` when the extracted rotation was better than the local solver's (the local solver
    /// had stopped at a non-global minimum).
    pub improved_local: bool,
}

/// The pipeline's result: the estimate (local solution, possibly improved by the SDP) and its
/// certificate.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ConjugateEstimate {
    /// The returned solution (`estimate = S`).
    pub solution: ConjugateSolution,
    /// Certificate of the chordal cost (`None` when not requested or not applicable).
    pub certificate: Option<Certificate>,
    /// SDP statistics, when the SDP ran.
    pub sdp: Option<SdpSummary>,
}

fn is_chordal_l2(s: &ConjugateSettings) -> bool {
    s.metric == Metric::Chordal && s.loss == Loss::Squared
}

/// Run the SDP and return the best verified bound for the rotation `s` (and the extracted
/// rotation). Both the raw Clarabel multipliers and the ones refined at `s` (and at the
/// extracted rotation, if any) are verified; the largest verified bound is kept (each is a valid
/// bound on the global minimum).
fn sdp_bound(
    problem: &ConjugateProblem,
    sdp: &SdpSettings,
    candidates: &[Rotation],
) -> Result<(Option<super::sdp::VerifiedBound>, super::sdp::SdpRelaxation)> {
    let relax = relax_conjugate(problem, sdp)?;
    let m = cost_matrix(problem);
    let cons = constraint_matrices();
    let mut best = verify_lower_bound(&m, &cons, &relax.multipliers);
    for s in candidates {
        if let Some(nu) = refine_multipliers(&m, &cons, &relax.multipliers, s)
            && let Some(b) = verify_lower_bound(&m, &cons, &nu)
            && best.is_none_or(|x| b.lower_bound > x.lower_bound)
        {
            best = Some(b);
        }
    }
    Ok((best, relax))
}

fn explain(cert_gap: Option<f64>, relax: &super::sdp::SdpRelaxation, lam: f64) -> String {
    match cert_gap {
        Some(_) => format!(
            "lower bound from Clarabel's multipliers ({:?}, {} iterations), verified with a dense eigenvalue check (lambda_min of the certificate matrix {:.3e}); Z eigenvalue ratio {:.1e}",
            relax.status, relax.iterations, lam, relax.eigenvalue_ratio
        ),
        None => "no usable multipliers from the SDP".into(),
    }
}

/// Certify a given rotation `s` (never changed) for the chordal cost `g` with the SDP `[H8]`.
///
/// ```
/// use rotavg::conjugate::{ConjugateProblem, certify_conjugate, SdpSettings};
/// use rotavg::so3::exp;
/// use nalgebra::Vector3;
/// let s = exp(&Vector3::new(0.4, -0.1, 0.7));
/// let rs = [exp(&Vector3::new(0.5, 0.0, 0.1)), exp(&Vector3::new(0.0, 0.8, -0.3))];
/// let ls: Vec<_> = rs.iter().map(|r| s * r * s.inverse()).collect();
/// let p = ConjugateProblem::from_rotations(&ls, &rs).unwrap();
/// let cert = certify_conjugate(&p, &s, &SdpSettings::default(), Default::default()).unwrap();
/// assert!(cert.is_certified());
/// ```
pub fn certify_conjugate(
    problem: &ConjugateProblem,
    s: &Rotation,
    sdp: &SdpSettings,
    tolerance: GapTolerance,
) -> Result<Certificate> {
    let start = Instant::now();
    let (bound, relax) = sdp_bound(problem, sdp, &[*s])?;
    let lam = bound.map(|b| b.min_eigenvalue);
    let mut certificate = Certificate::from_bounds(
        problem.chordal_cost(s),
        bound.map(|b| b.lower_bound),
        BoundMethod::Sdp,
        lam,
        tolerance,
        explain(
            bound.map(|b| b.lower_bound),
            &relax,
            lam.unwrap_or(f64::NAN),
        ),
        start.elapsed().as_secs_f64(),
    );
    attach_spectrum(&mut certificate, bound.as_ref());
    Ok(certificate)
}

/// The verified `lambda_min` bound and the 10 (dense, exact up to rounding) eigenvalues of the
/// certificate matrix `C(nu)` of the bound `[H8]`, `[D14]` (free: the verification computed them).
fn attach_spectrum(certificate: &mut Certificate, bound: Option<&super::sdp::VerifiedBound>) {
    if let Some(b) = bound {
        certificate.verified_min_eigenvalue = Some(b.verified_min_eigenvalue);
        certificate.smallest_eigenvalues = Some(SpectrumEstimate {
            values: b.eigenvalues.to_vec(),
            residuals: b.eigen_residuals.to_vec(),
            method: SpectrumMethod::Dense,
            shift: None,
            converged: true,
            subspace_dim: 10,
            seconds: 0.0,
        });
    }
}

/// The whole pipeline `[H9]`: local solve (closed-form initialiser, then the configured
/// solver), and for chordal L2 the SDP: extract `S` from `Z`, polish it with the chordal solver,
/// keep the better of the two, and certify it with the verified bound.
///
/// ```
/// use rotavg::conjugate::{ConjugateProblem, average_conjugate};
/// use rotavg::so3::{exp, angle_between};
/// use nalgebra::Vector3;
/// let s = exp(&Vector3::new(0.4, -0.1, 0.7));
/// let rs = [exp(&Vector3::new(0.5, 0.0, 0.1)), exp(&Vector3::new(0.0, 0.8, -0.3))];
/// let ls: Vec<_> = rs.iter().map(|r| s * r * s.inverse()).collect();
/// let p = ConjugateProblem::from_rotations(&ls, &rs).unwrap();
/// let est = average_conjugate(&p, &Default::default()).unwrap();
/// assert!(angle_between(&est.solution.estimate, &s) < 1e-9);
/// assert!(est.certificate.unwrap().is_certified());
/// ```
pub fn average_conjugate(
    problem: &ConjugateProblem,
    settings: &AverageSettings,
) -> Result<ConjugateEstimate> {
    average_conjugate_from(problem, settings, None)
}

/// [`average_conjugate`] with an optional user initialisation (replaces the closed form).
///
/// ```
/// use rand::SeedableRng;
/// use rotavg::conjugate::{average_conjugate_from, synthetic::random_instance, AverageSettings};
/// use rotavg::so3::Rotation;
/// let mut rng = rand::rngs::StdRng::seed_from_u64(8);
/// let (problem, _s) = random_instance(10, 0.02, 0.0, &mut rng);
/// // Even from a poor start the SDP step finds and certifies the global minimum.
/// let est = average_conjugate_from(&problem, &AverageSettings::default(), Some(&Rotation::identity()))?;
/// let cert = est.certificate.unwrap();
/// assert!(cert.is_certified());
/// assert!((cert.upper_bound - est.solution.chordal_cost).abs() <= 1e-12 * cert.upper_bound);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_conjugate_from(
    problem: &ConjugateProblem,
    settings: &AverageSettings,
    init: Option<&Rotation>,
) -> Result<ConjugateEstimate> {
    let mut solution = match init {
        Some(s0) => solve_conjugate_from(problem, &settings.local, s0)?,
        None => solve_conjugate(problem, &settings.local)?,
    };
    let certify = match settings.certify {
        CertifyMode::None => false,
        CertifyMode::Auto => is_chordal_l2(&settings.local),
        CertifyMode::Sdp => {
            if !is_chordal_l2(&settings.local) {
                return Err(Error::InvalidSettings {
                    name: "certify".into(),
                    reason: "the SDP certificate is for the chordal L2 cost only".into(),
                });
            }
            true
        }
    };
    if !certify {
        return Ok(ConjugateEstimate {
            solution,
            certificate: None,
            sdp: None,
        });
    }
    let start = Instant::now();
    let relax = relax_conjugate(problem, &settings.sdp)?;
    let mut extracted_cost = None;
    let mut improved = false;
    if let Some(s0) = extract_rotation(&relax.z)
        && let Ok(pol) = solve_conjugate_from(problem, &settings.local, &s0)
    {
        extracted_cost = Some(pol.cost);
        if pol.cost < solution.cost {
            improved = solution.cost - pol.cost > 1e-12 * solution.cost.abs().max(1e-300);
            let seconds = solution.report.seconds + pol.report.seconds;
            solution = pol;
            solution.report.seconds = seconds;
        }
    }
    let m = cost_matrix(problem);
    let cons = constraint_matrices();
    let mut bound = verify_lower_bound(&m, &cons, &relax.multipliers);
    if let Some(nu) = refine_multipliers(&m, &cons, &relax.multipliers, &solution.estimate)
        && let Some(b) = verify_lower_bound(&m, &cons, &nu)
        && bound.is_none_or(|x| b.lower_bound > x.lower_bound)
    {
        bound = Some(b);
    }
    let lam = bound.map(|b| b.min_eigenvalue);
    let mut certificate = Certificate::from_bounds(
        solution.chordal_cost,
        bound.map(|b| b.lower_bound),
        BoundMethod::Sdp,
        lam,
        settings.tolerance,
        explain(
            bound.map(|b| b.lower_bound),
            &relax,
            lam.unwrap_or(f64::NAN),
        ),
        start.elapsed().as_secs_f64(),
    );
    attach_spectrum(&mut certificate, bound.as_ref());
    Ok(ConjugateEstimate {
        solution,
        certificate: Some(certificate),
        sdp: Some(SdpSummary {
            status: relax.status,
            iterations: relax.iterations,
            solve_seconds: relax.seconds,
            eigenvalue_ratio: relax.eigenvalue_ratio,
            extracted_cost,
            improved_local: improved,
        }),
    })
}
