//! A rig with soft gravity priors and sensors to estimate, certified through its world rig
//! (`paper-notes/gravity.md` `[G16]`, [`crate::rig::WorldRig`]): the rig's ladder climbs the
//! world rig, whose minimum is the joint problem's, and its bound is brought back with the
//! data's defect.

use crate::certify::certificate::Certificate;
use crate::certify::certification::Certification;
use crate::certify::proof::Proof;
use crate::certify::settings::CertifySettings;
use crate::error::Result;
use crate::rig::{RigProblem, RigSolution, WorldRig};
use crate::so3::Rotation;

/// The rig's certificate, handed in by the entry point (which this file sits below).
pub(super) type RigCertifier = fn(
    &RigProblem,
    &[Rotation],
    &[Rotation],
    &CertifySettings,
) -> Result<Certification<RigSolution>>;

/// `certify` of `problem` (soft priors, a sensor to estimate, the estimate checked) at
/// `(frames, sensors)` through `world`: the verdict is about the posed cost (edges and
/// priors) under the posed problem's tolerance.
pub(super) fn certify_through_world(
    (problem, world): (&RigProblem, &WorldRig),
    frames: &[Rotation],
    sensors: &[Rotation],
    settings: &CertifySettings,
    certify: RigCertifier,
) -> Result<Certification<RigSolution>> {
    let sensors = problem.at_held(sensors);
    let (world_frames, world_sensors) = world.point(frames, &sensors);
    // the world's turns about e_3 are two null directions of every certificate matrix of the
    // world rig beyond the gauge's three: the grounded bound and the block comparison cannot
    // prove there (`[G10]` item 4), so they are not tried
    let mut inner_settings = settings.clone();
    (inner_settings.dual.proofs).retain(|p| !matches!(p, Proof::Grounded | Proof::BlockComparison));
    let inner = certify(
        &world.problem,
        &world_frames,
        &world_sensors,
        &inner_settings,
    )?;
    let cost = problem.cost(frames, &sensors);
    let tolerance = settings.tolerance.resolve(problem.min_weight());
    let c = &inner.certificate;
    let lower = c.lower_bound.map(|l| world.posed_bound(l));
    let note = match (c.lower_bound, lower) {
        (Some(l), Some(posed)) => format!(
            "{}; through the world rig [G16]: its bound {l:.9e}, {posed:.9e} for the rig \
             with its soft priors after the data's defect",
            c.explanation
        ),
        _ => format!("{}; through the world rig [G16]", c.explanation),
    };
    let mut certificate = Certificate::from_bounds(
        cost,
        lower,
        c.method,
        c.min_eigenvalue,
        tolerance,
        note,
        inner.details.seconds,
    );
    certificate.verified_min_eigenvalue = c.verified_min_eigenvalue;
    let mut details = inner.details;
    let improvement = (inner.improvement)
        .map(|s| {
            let (frames, sensors) = world.posed_point(&s.frames, &s.sensors);
            let cost = problem.cost(&frames, &sensors);
            RigSolution {
                frames,
                sensors,
                cost,
                report: s.report,
            }
        })
        .filter(|s| s.cost < cost);
    if let Some(i) = details.improvement.as_mut() {
        match &improvement {
            Some(s) => i.cost = s.cost,
            None => details.improvement = None,
        }
    }
    Ok(Certification {
        certificate,
        details,
        improvement,
    })
}
