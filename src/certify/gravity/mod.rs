//! Certificates for chordal L2 averaging with gravity priors (contract section 5, "Rigs and
//! gravity"; `paper-notes/gravity.md`): three rungs, climbed by the one ladder.
//!
//! | rung | when | bound |
//! |---|---|---|
//! | [`planar`]: the SO(2) dual certificate at the estimate `[G2]`, `[G3]` | every image has a prior | `K + sum lambda_i + n min(mu, 0)`, `mu` proven by the scalar comparison on large graphs (`scalar.rs`, `[G9]`), else (or when it does not certify) by a shifted sparse Cholesky; then `K + sum lambda_i - (rho^2 / c + h) / |x_g|^2` with the null space deflated (`grounded.rs`, `[G17]`) |
//! | `surrogate.rs`: the tilted soft surrogate `[G12]` | the mixed problem; a fallback of full gravity | the soft problem's certified bound (view graph and world node) less its constant on the held problem |
//! | `relaxed.rs`: the priors dropped `[G7]` | the last fallback | the view graph's own certified bound |
//!
//! Soft priors (`[G10]`, [`crate::multiple::gravity::GravityPriors::with_weight`]) are no
//! constraints: `certify_soft` certifies the view graph with a world node (one edge per prior)
//! by the multiple-averaging ladder: an ordinary anisotropic multiple-averaging problem with
//! the same minimum, so every rung of that ladder applies (the SDP included), at the estimate
//! with the world node at `I`.

mod grounded;
pub mod planar;
mod relaxed;
mod rung;
mod scalar;
mod state;
mod surrogate;
#[cfg(test)]
mod test_support;

pub use planar::{PlanarBound, PlanarForm, verify_planar};

use crate::certify::budget::Deadline;
use crate::certify::certificate::CertifiedProblemKind;
use crate::certify::certification::Certification;
use crate::certify::ladder::{Rungs, climb};
use crate::certify::multiple::{certify_multiple, graph_certificate};
use crate::certify::proof::{BoundMethod, Proof};
use crate::certify::rung::Handed;
use crate::certify::settings::CertifySettings;
use crate::certify::tally::Tally;
use crate::error::{Error, Result};
use crate::multiple::MultipleSolution;
use crate::multiple::gravity::GravityProblem;
use crate::so3::Rotation;
use state::GravityState;

/// The kind of problem a certificate of `problem` names: hard or soft priors, on all edges or
/// (`inliers`) on a robust solve's inlier graph.
pub fn gravity_problem_kind(problem: &GravityProblem, inliers: bool) -> CertifiedProblemKind {
    use CertifiedProblemKind as K;
    match (problem.priors().weight().is_some(), inliers) {
        (false, false) => K::ChordalL2Gravity,
        (false, true) => K::ChordalL2GravityInliers,
        (true, false) => K::ChordalL2GravitySoft,
        (true, true) => K::ChordalL2GravitySoftInliers,
    }
}

/// The largest angle (radians) between `R_i g_world` and `g_i` an estimate may have to be
/// certified as one of the gravity problem (its own solver's are within rounding).
pub const GRAVITY_FEASIBILITY_RAD: f64 = 1e-6;

/// Certify `rotations` (never changed) for the chordal L2 problem of `problem`'s view graph
/// with its gravity priors as hard constraints, or with soft priors (`[G10]`) plus their
/// terms. Held priors: full gravity by the SO(2) dual certificate `[G3]`, mixed by the tilted
/// soft surrogate `[G12]` (a fallback for full gravity too), and the view graph's own bound
/// `[G7]` last. Errors: a count of rotations that differs from the graph's, an estimate off
/// its held priors by more than [`GRAVITY_FEASIBILITY_RAD`].
///
/// ```
/// use rotavg::certify::{certify_gravity, CertifySettings};
/// use rotavg::multiple::gravity::GravityProblem;
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// let (graph, truth) = SyntheticGraph { num_rotations: 20, num_edges: 60, noise_sigma: 0.0, ..Default::default() }.generate();
/// let p = GravityProblem::from_truth(graph, &truth)?;
/// let c = certify_gravity(&p, &truth, &CertifySettings::default())?;
/// assert!(c.certificate.is_certified());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn certify_gravity(
    problem: &GravityProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
) -> Result<Certification<MultipleSolution>> {
    let deadline = Deadline::start(&settings.budget);
    settings.validate()?;
    let graph = problem.problem();
    graph.check_estimate(rotations)?;
    if problem.priors().weight().is_some() {
        return certify_soft(problem, rotations, settings);
    }
    let off = problem.max_prior_violation_deg(rotations);
    if off.is_nan() || off.to_radians() > GRAVITY_FEASIBILITY_RAD {
        return Err(Error::InvalidSettings {
            name: "estimate".into(),
            reason: format!(
                "the estimate is {off:.3e} degrees off its gravity priors (R_i g_world = g_i \
                 within {GRAVITY_FEASIBILITY_RAD:e} rad): it is not a point of the gravity \
                 problem; certify it without --gravity, or project it onto the priors"
            ),
        });
    }
    let cost = graph.chordal_cost(rotations);
    let mut state = GravityState {
        problem,
        rotations,
        tally: Tally::new(settings, deadline, cost, graph.min_weight()),
        relaxed_method: None,
    };
    let rungs: Rungs<'_, GravityState<'_>> = vec![
        Box::new(rung::PlanarRung::default()),
        Box::new(surrogate::SurrogateRung(Handed::new(soft_certificate))),
        Box::new(relaxed::RelaxedRung(Handed::new(graph_certificate))),
    ];
    climb(&mut state, rungs)?;
    let relaxed = state.relaxed_method.unwrap_or(BoundMethod::Dual);
    let (certificate, details) = state.tally.finish(BoundMethod::Dual, |proof| match proof {
        Proof::GravityRelaxed => relaxed,
        p => p.method(),
    });
    Ok(Certification {
        certificate,
        details,
        improvement: None,
    })
}

/// The certificate of `rotations` for `problem` ([`certify_gravity`]): the rig's frames rung's
/// certifier (`[G14]`).
pub(crate) fn gravity_certificate(
    problem: &GravityProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
) -> Result<crate::certify::certificate::Certificate> {
    Ok(certify_gravity(problem, rotations, settings)?.certificate)
}

/// The certificate of `rotations` for the soft problem `problem` ([`certify_soft`]): the
/// surrogate rung's certifier.
fn soft_certificate(
    problem: &GravityProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
) -> Result<crate::certify::certificate::Certificate> {
    Ok(certify_soft(problem, rotations, settings)?.certificate)
}

/// An upper bound on `F_aug(R W~) - F(R)` over rotations `R` (`paper-notes/gravity.md` `[G10]`
/// "Two forms of the cost"): `F` the soft problem's cost as stated (the view graph's
/// `sum w ||R_j - R_ij R_i||^2` and the priors' `sum 2 w ||R_i d - g_i||^2`), `F_aug` the
/// augmented view graph's (`[A2]`'s trace form, the spokes' frames `F_i e_3 ~ g_i`) at the
/// standard point with `W~` the rotation nearest the computed world frame `W`: the view graph's
/// data defect `[D4]` and, per prior of weight `w`, `w (2 |2 - |d|^2 - |g|^2| + 4 (|g - F e_3|
/// |d| + |F e_3| (|d - W e_3| + ||W^T W - I||)))` with `8u` and `16u` added to the two
/// differences computed by cancellation, all doubled for the evaluation's own rounding.
fn soft_form_defect(problem: &GravityProblem) -> f64 {
    let u = crate::linalg::cholesky::UNIT_ROUNDOFF;
    let priors = problem.priors();
    let d = priors.world_down();
    let w = *priors.world_frame().matrix();
    let orthogonality = (w.transpose() * w - nalgebra::Matrix3::identity()).norm() + 16.0 * u;
    let down_gap = (d - w.column(2)).norm();
    let spokes: f64 = (0..priors.len())
        .filter_map(|i| {
            let (g, weight, frame) = (
                priors.direction(i)?,
                priors.prior_weight(i)?,
                problem.frame(i)?,
            );
            let gf: nalgebra::Vector3<f64> = frame.matrix().column(2).into_owned();
            let norms = (2.0 - d.norm_squared() - g.norm_squared()).abs() + 8.0 * u;
            let turn = (g - gf).norm() * d.norm() + gf.norm() * (down_gap + orthogonality);
            Some(weight * (2.0 * norms + 4.0 * turn))
        })
        .sum();
    let view = crate::certify::multiple::multipliers::data_defect(problem.problem()).max(0.0);
    2.0 * (view + spokes)
}

/// Certify `rotations` (file convention) for the soft problem of `problem`: the augmented
/// view graph's certification at the estimate, its improvement (if any) brought back to the
/// images (file convention, the world node at `I`, the gravity problem's gauge).
fn certify_soft(
    problem: &GravityProblem,
    rotations: &[Rotation],
    settings: &CertifySettings,
) -> Result<Certification<MultipleSolution>> {
    let augmented = problem.soft_augmented(problem.problem())?;
    let mut settings = settings.clone();
    // The world node's edges see only its third row (M = w e_3 e_3^T): its turns about e_3 are
    // a symmetry beyond the gauge, so S has two more null directions than the three the block
    // comparison's pencil lemma allows; it cannot prove here (at 10^4 cameras it failed in 19 s
    // before the shifted Cholesky proved in 7.5 s). The grounded bound leaves the world's two
    // unseen coordinates out (their rows of S exactly zero with their multipliers, [D15]).
    settings
        .dual
        .proofs
        .retain(|p| !matches!(p, Proof::BlockComparison));
    let mut c = certify_multiple(&augmented, &problem.soft_point(rotations), &settings)?;
    // the augmented graph's cost is the soft problem's in another form ([G10] "Two forms")
    c.certificate = c.certificate.lowered_by(soft_form_defect(problem));
    // the augmented graph's edges are the view graph's and the priors' (said so, [G10])
    let (m, k) = (problem.problem().num_edges(), problem.priors().num_known());
    c.certificate.explanation = c.certificate.explanation.replace(
        &format!("of its {} edges", m + k),
        &format!("of its {m} edges and {k} soft gravity priors (a world node's edges)"),
    );
    let improvement = c.improvement.map(|mut s| {
        s.rotations = problem.soft_estimate(s.rotations);
        s
    });
    Ok(Certification { improvement, ..c })
}
