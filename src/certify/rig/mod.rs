//! Certificates of a rig of any number of sensors (`paper-notes/conjugate.md` `[H19]`). Two
//! rungs, each a sum of view-graph certifications (handed in by the entry point:
//! `certify_multiple`), so they reach any size the view-graph ladder does:
//!
//! * [`Proof::RigFrames`] (every sensor held): `J(F, S)` is the frames' view graph's cost plus
//!   the within-frame edges' constant, exactly up to rounding that `rounding.rs` charges.
//! * [`Proof::RigImages`]: every rig point is a point of the images' view graph without the
//!   rig's constraints (`X_a = S_{s_a} F_{f_a}` is a tuple of rotations), so the sum of its
//!   components' certified minima bounds `J*`. Tight when the images' optimum is a rig
//!   (noise-free data); a gap otherwise (the constraints' cost).

mod bundle;
mod coupled;
mod couplings;
mod frames;
mod images;
mod rounding;
mod search;
mod state;
mod traces;
pub(crate) mod two_graphs;
mod wide;
mod world;

use crate::certify::budget::Deadline;
use crate::certify::certification::{Certification, Improvement, ImprovementSource};
use crate::certify::ladder::{Rungs, climb};
use crate::certify::proof::{BoundMethod, Proof};
use crate::certify::rung::{GraphCertifier, Handed};
use crate::certify::settings::CertifySettings;
use crate::certify::tally::Tally;
use crate::error::{Error, Result};
use crate::rig::{RigProblem, RigSolution};
use crate::so3::Rotation;
use state::RigState;

/// Certify a rig estimate (`frames` `F_f`, `sensors` `S_s`, never changed; `[H19]`): when
/// every sensor is held, the frames' view graph; always, the images' view graph without the
/// rig's constraints; each certified by `certify` (the view graph's ladder) within the
/// budget. The verdict uses the best bound, and is about the estimate with its held sensors at
/// their held rotations; a point of lower cost met on the way (the coupled bound's polish,
/// `[H21]`) is the certification's `improvement`, which the bound covers as well. With gravity
/// priors (`[G14]`) the frames' bound is the frames' gravity problem's; soft priors on a rig
/// with a sensor to estimate are certified jointly through the world rig (`[G16]`). Errors:
/// estimates of the wrong length, a held sensor farther than 1e-9 rad from its held rotation,
/// frames off their held gravity directions.
///
/// ```
/// use rotavg::certify::certify_rig;
/// use rotavg::rig::{RigScene, RigSettings, solve_rig};
/// let (p, _) = RigScene { frames: 30, sensors: 3, noise_sigma: 0.0, ..Default::default() }.generate();
/// let s = solve_rig(&p, &RigSettings::default())?;
/// let c = certify_rig(&p, &s.frames, &s.sensors, &Default::default())?;
/// assert!(c.certificate.is_certified()); // noise-free: the images' optimum is a rig
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn certify_rig(
    problem: &RigProblem,
    frames: &[Rotation],
    sensors: &[Rotation],
    settings: &CertifySettings,
) -> Result<Certification<RigSolution>> {
    certify_rig_with(problem, (frames, sensors), settings, true)
}

/// [`certify_rig`] without the images' bound (`[H19]` item 2), for an attempt that only a
/// certificate serves: the joint problem of `[G16]`, whose gap is not the run's (the held rig's
/// certificate is). At 10^4 frames and 2 sensors that bound took 10-15 s of a 20 s attempt
/// for a 16 % gap (2026-12-02).
pub(crate) fn certify_rig_without_images_bound(
    problem: &RigProblem,
    frames: &[Rotation],
    sensors: &[Rotation],
    settings: &CertifySettings,
) -> Result<Certification<RigSolution>> {
    certify_rig_with(problem, (frames, sensors), settings, false)
}

/// Whether `problem` has the simultaneous problem's shape (`[H22]`: two sensors, one or both
/// estimated, no edge between them), where the within-frame couplings `[H21]` have no edge
/// between sensors to work with.
pub(crate) fn is_two_graphs(problem: &RigProblem) -> bool {
    two_graphs::not_two_graphs(problem).is_none()
}

fn certify_rig_with(
    problem: &RigProblem,
    (frames, sensors): (&[Rotation], &[Rotation]),
    settings: &CertifySettings,
    images_bound: bool,
) -> Result<Certification<RigSolution>> {
    if let Some(world) = problem.soft_priors_as_world_frame()? {
        check_estimate(problem, frames, sensors)?;
        let posed = (problem, &world);
        let inner: world::RigCertifier = if images_bound {
            certify_rig
        } else {
            certify_rig_without_images_bound
        };
        return world::certify_through_world(posed, frames, sensors, settings, inner);
    }
    let certify: GraphCertifier = crate::certify::multiple::graph_certificate;
    let deadline = Deadline::start(&settings.budget);
    settings.validate()?;
    check_estimate(problem, frames, sensors)?;
    // the same J of the same unknowns without the images no edge measures ([H19])
    let measured = problem.without_unmeasured_images();
    let problem = measured.as_ref().unwrap_or(problem);
    // the held sensors at their held rotations (the estimate's are within 1e-9 rad of them):
    // the bounds and the cost are of the problem as posed
    let sensors = &problem.at_held(sensors)[..];
    check_held_priors(problem, frames, sensors)?;
    let cost = problem.cost(frames, sensors);
    let mut state = RigState {
        problem,
        frames,
        sensors,
        tally: Tally::new(settings, deadline, cost, problem.min_weight()),
        improvement: None,
    };
    let mut rungs: Rungs<'_, RigState<'_>> = vec![
        Box::new(frames::FramesRung(Handed::new((
            certify,
            crate::certify::gravity::gravity_certificate,
        )))),
        Box::new(coupled::CoupledRung(Handed::new(certify), None)),
        Box::new(two_graphs::TwoGraphsRung(Handed::new((
            crate::certify::simultaneous::joint_certificate,
            crate::certify::simultaneous::predict_simultaneous,
        )))),
    ];
    if images_bound {
        rungs.push(Box::new(images::ImagesRung(Handed::new(certify))));
    }
    climb(&mut state, rungs)?;
    let (certificate, mut details) = state.tally.finish(BoundMethod::Dual, Proof::method);
    details.improvement = state.improvement.as_ref().map(|s| Improvement {
        source: ImprovementSource::RigPolish,
        cost: s.cost,
    });
    Ok(Certification {
        certificate,
        details,
        improvement: state.improvement,
    })
}

/// The augmented graph of `[H21]` of a generated rig at its solution polished by 20
/// alternation passes, its image rotations and each image's sensor (for the certificates'
/// tests).
#[cfg(test)]
pub(crate) fn coupled_graph_for_tests(
    scene: &crate::rig::RigScene,
) -> (crate::multiple::MultipleProblem, Vec<Rotation>, Vec<usize>) {
    let (problem, _) = scene.generate();
    let s = crate::rig::solve_rig(&problem, &Default::default()).expect("solves");
    let polished = crate::rig::polish_passes(&problem, (s.frames, s.sensors), 20, (None, u64::MAX));
    let (frames, sensors, _) = polished.expect("polishes");
    let coupled = couplings::couple(&problem, &frames, &sensors, u64::MAX)
        .expect("couples")
        .expect("couplings");
    let x = problem.image_rotations(&frames, &sensors);
    let sensor = problem.images().iter().map(|im| im.sensor).collect();
    (coupled.graph, x, sensor)
}

/// Held gravity priors (`[G14]`): the frames on their directions (within
/// [`crate::certify::gravity::GRAVITY_FEASIBILITY_RAD`]), else the estimate is no point of the
/// problem and no bound may certify it.
fn check_held_priors(p: &RigProblem, frames: &[Rotation], sensors: &[Rotation]) -> Result<()> {
    let Some(fg) = p.frame_gravity(sensors)? else {
        return Ok(());
    };
    if fg.problem.priors().weight().is_some() {
        return Ok(());
    }
    let off = fg.problem.max_prior_violation_deg(frames);
    if off.is_nan() || off.to_radians() > crate::certify::gravity::GRAVITY_FEASIBILITY_RAD {
        return Err(Error::InvalidSettings {
            name: "estimate".into(),
            reason: format!(
                "the estimate is {off:.3e} degrees off its frames' held gravity directions (each \
                 frame's priors brought to it by sensor_from_rig, [G14]): it is not a point of \
                 the problem; certify it without --gravity, or with --gravity-weight"
            ),
        });
    }
    Ok(())
}

/// One rotation per frame and per sensor; the held sensors at their held rotations.
fn check_estimate(p: &RigProblem, frames: &[Rotation], sensors: &[Rotation]) -> Result<()> {
    let invalid = |reason: String| Error::InvalidSettings {
        name: "estimate".into(),
        reason,
    };
    if frames.len() != p.num_frames() || sensors.len() != p.sensors().len() {
        return Err(invalid(format!(
            "{} frames and {} sensors for a rig of {} frames and {} sensors",
            frames.len(),
            sensors.len(),
            p.num_frames(),
            p.sensors().len()
        )));
    }
    for (s, (held, given)) in p.held().iter().zip(sensors).enumerate() {
        if let Some(h) = held
            && crate::so3::angle_between(h, given) > 1e-9
        {
            return Err(invalid(format!(
                "sensor {s} is held at a rotation {:.3e} rad from the estimate's",
                crate::so3::angle_between(h, given)
            )));
        }
    }
    Ok(())
}
