//! The rig solver's start (`paper-notes/conjugate.md` `[H19]`): the frames seen by the held
//! sensors, then every unknown sensor from the edges that link it to sensors already placed.

use super::problem::RigProblem;
use crate::conjugate::{ConjugatePair, ConjugateProblem, ConjugateSettings, solve_conjugate};
use crate::error::{Error, Result};
use crate::multiple::{Edge, MultipleProblem, MultipleSettings, solve_multiple};
use crate::so3::{Rotation, nearest_rotation};
use nalgebra::Matrix3;

/// The start's sensors: the held ones as held; each unknown one from the edges linking it to an
/// image of a placed sensor (the chordal mean of the rotations they imply), else from its own
/// edges between two frames of the held sensors' view graph (the conjugate problem of the pairs
/// `(R_ab, F_b F_a^T)`). Also the held sensors' frames, when they place every frame (the first
/// frame step starts from them). Errors: a sensor that no edge links to the placed ones.
pub(crate) fn start_sensors(
    p: &RigProblem,
    max_seconds: Option<f64>,
) -> Result<(Vec<Rotation>, Option<Vec<Rotation>>)> {
    let frames = reference_frames(p, max_seconds)?;
    let mut placed: Vec<Option<Rotation>> = p.held().to_vec();
    loop {
        let mut progress = false;
        for s in 0..placed.len() {
            if placed[s].is_some() {
                continue;
            }
            placed[s] = match linked_mean(p, s, &placed, &frames) {
                Some(r) => Some(r),
                None => own_motions(p, s, &frames, max_seconds)?,
            };
            progress |= placed[s].is_some();
        }
        if !progress {
            break;
        }
    }
    let sensors = placed
        .iter()
        .enumerate()
        .map(|(s, r)| {
            r.ok_or_else(|| Error::InvalidSettings {
                name: "rig".into(),
                reason: format!(
                    "sensor {s} cannot be placed: no edge links its images to a held sensor's \
                     (or to another placed sensor's), and it has no two images of frames the \
                     held sensors see"
                ),
            })
        })
        .collect::<Result<_>>()?;
    Ok((sensors, frames.into_iter().collect()))
}

/// The frames of the held sensors' view graph (edges between images of held sensors at two
/// frames, turned into frame edges), on its largest component; `None` elsewhere.
fn reference_frames(p: &RigProblem, max_seconds: Option<f64>) -> Result<Vec<Option<Rotation>>> {
    let held = p.held();
    let mut edges = Vec::new();
    for e in p.edges() {
        let (a, b) = (p.images()[e.i], p.images()[e.j]);
        if let (Some(sa), Some(sb)) = (held[a.sensor], held[b.sensor])
            && a.frame != b.frame
        {
            edges.push(Edge {
                i: a.frame,
                j: b.frame,
                rotation: sb.inverse() * e.rotation * sa,
                weight: e.weight,
            });
        }
    }
    let mut frames = vec![None; p.num_frames()];
    if edges.is_empty() {
        return Ok(frames);
    }
    let (graph, nodes) = MultipleProblem::new(p.num_frames(), edges)?.largest_component();
    let settings = MultipleSettings {
        max_seconds,
        ..Default::default()
    };
    let solved = solve_multiple(&graph, &settings)?;
    for (k, f) in nodes.into_iter().enumerate() {
        frames[f] = Some(solved.rotations[k]);
    }
    Ok(frames)
}

/// Sensor `s` from its edges to images of placed sensors: each implies
/// `S_s = R T F_a F_b^T` (edge into `s`) or `R^T T F_b F_a^T` (edge out of `s`), frames
/// needed only when the two images are of different frames; their weighted chordal mean.
fn linked_mean(
    p: &RigProblem,
    s: usize,
    placed: &[Option<Rotation>],
    frames: &[Option<Rotation>],
) -> Option<Rotation> {
    let mut sum = Matrix3::zeros();
    let mut any = false;
    for e in p.edges() {
        let (a, b) = (p.images()[e.i], p.images()[e.j]);
        let (toward, other, from_frame, to_frame) = if b.sensor == s && a.sensor != s {
            (true, a.sensor, a.frame, b.frame)
        } else if a.sensor == s && b.sensor != s {
            (false, b.sensor, b.frame, a.frame)
        } else {
            continue;
        };
        let Some(t) = placed[other] else { continue };
        // F_other F_s^T: the identity within one frame
        let relative = if from_frame == to_frame {
            Rotation::identity()
        } else {
            match (frames[from_frame], frames[to_frame]) {
                (Some(fo), Some(fs)) => fo * fs.inverse(),
                _ => continue,
            }
        };
        let implied = if toward {
            e.rotation * t * relative
        } else {
            e.rotation.inverse() * t * relative
        };
        sum += e.weight * implied.matrix();
        any = true;
    }
    any.then(|| crate::so3::project_to_so3(&sum).map(|r| nearest_rotation(&r)))
        .flatten()
}

/// Sensor `s` from its own edges between two frames the held sensors place: the conjugate
/// problem of the pairs `(R_ab, F_b F_a^T)` (`||S F_b F_a^T - R_ab S||`); `None` without any.
fn own_motions(
    p: &RigProblem,
    s: usize,
    frames: &[Option<Rotation>],
    max_seconds: Option<f64>,
) -> Result<Option<Rotation>> {
    let mut pairs = Vec::new();
    for e in p.edges() {
        let (a, b) = (p.images()[e.i], p.images()[e.j]);
        if a.sensor != s || b.sensor != s {
            continue;
        }
        if let (Some(fa), Some(fb)) = (frames[a.frame], frames[b.frame]) {
            pairs.push(ConjugatePair {
                weight: e.weight,
                ..ConjugatePair::new(e.rotation, fb * fa.inverse())
            });
        }
    }
    if pairs.is_empty() {
        return Ok(None);
    }
    let settings = ConjugateSettings {
        max_seconds,
        ..Default::default()
    };
    let solved = solve_conjugate(&ConjugateProblem::new(pairs)?, &settings)?;
    Ok(Some(solved.estimate))
}
