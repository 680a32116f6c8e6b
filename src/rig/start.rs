//! The rig solver's start (`paper-notes/conjugate.md` `[H19]`): the frames seen by the held
//! sensors, then every unknown sensor from the edges that link it to sensors already placed.

use super::problem::RigProblem;
use crate::conjugate::{ConjugatePair, ConjugateProblem, ConjugateSettings, solve_conjugate};
use crate::error::{Error, Result};
use crate::multiple::{Edge, MultipleProblem, MultipleSettings, solve_multiple};
use crate::so3::{Rotation, nearest_rotation};
use nalgebra::Matrix3;

/// The start's sensors: the held ones as held; each unknown one from the edges linking it to an
/// image of a placed sensor ([`linked_mean`]: first by the links within one frame where there
/// are enough of them, without any frame; the held sensors' frames are solved only for the
/// sensors those do not place), else from its own edges between two of those frames (the
/// conjugate problem of the pairs `(R_ab, F_b F_a^T)`). The frames' start is the frame step's
/// own (`[H19]` "Starts"). Errors: a sensor that no edge links to the placed ones.
pub(crate) fn start_sensors(p: &RigProblem, max_seconds: Option<f64>) -> Result<Vec<Rotation>> {
    let mut placed: Vec<Option<Rotation>> = p.held().to_vec();
    place(p, &mut placed, None, max_seconds)?;
    if placed.iter().any(Option::is_none) {
        let frames = reference_frames(p, max_seconds)?;
        place(p, &mut placed, Some(&frames), max_seconds)?;
    }
    placed
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
        .collect()
}

/// Places unknown sensors until no more can be: by [`linked_mean`], then (with `frames`) by
/// [`own_motions`].
fn place(
    p: &RigProblem,
    placed: &mut [Option<Rotation>],
    frames: Option<&[Option<Rotation>]>,
    max_seconds: Option<f64>,
) -> Result<()> {
    loop {
        let mut progress = false;
        for s in 0..placed.len() {
            if placed[s].is_some() {
                continue;
            }
            placed[s] = match (linked_mean(p, s, placed, frames), frames) {
                (Some(r), _) => Some(r),
                (None, Some(frames)) => own_motions(p, s, frames, max_seconds)?,
                (None, None) => None,
            };
            progress |= placed[s].is_some();
        }
        if !progress {
            return Ok(());
        }
    }
}

/// The frames of the held sensors' view graph (edges between images of held sensors at two
/// frames, turned into frame edges, with their information), on its largest component; `None`
/// elsewhere.
fn reference_frames(p: &RigProblem, max_seconds: Option<f64>) -> Result<Vec<Option<Rotation>>> {
    let held = p.held();
    let (mut edges, mut info) = (Vec::new(), Vec::new());
    for (k, e) in p.edges().iter().enumerate() {
        let (a, b) = (p.images()[e.i], p.images()[e.j]);
        if let (Some(sa), Some(sb)) = (held[a.sensor], held[b.sensor])
            && a.frame != b.frame
        {
            if let Some(h) = p.information() {
                info.push(h[k].turned_for_solve(&sa));
            }
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
    let mut graph = MultipleProblem::new(p.num_frames(), edges)?;
    if p.information().is_some() {
        graph = graph.with_information(info)?;
    }
    let (graph, nodes) = graph.largest_component();
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
/// needed only when the two images are of different frames; their weighted chordal mean (with
/// information, weighted by [`crate::multiple::anisotropic::Information::start_weight`]), of
/// the links within one frame alone when there are [`WITHIN_LINKS_ALONE`] of them; without
/// `frames`, `None` unless there are (links across frames count only with `frames`).
fn linked_mean(
    p: &RigProblem,
    s: usize,
    placed: &[Option<Rotation>],
    frames: Option<&[Option<Rotation>]>,
) -> Option<Rotation> {
    // [within one frame, across frames]: the weighted sums and the counts of the links
    let mut sum = [Matrix3::zeros(); 2];
    let mut count = [0usize; 2];
    for (k, e) in p.edges().iter().enumerate() {
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
            match frames.map(|f| (f[from_frame], f[to_frame])) {
                Some((Some(fo), Some(fs))) => fo * fs.inverse(),
                _ => continue,
            }
        };
        let implied = if toward {
            e.rotation * t * relative
        } else {
            e.rotation.inverse() * t * relative
        };
        // with information, the start's weight ([A17])
        let weight = p.information().map_or(e.weight, |h| h[k].start_weight());
        let across = usize::from(from_frame != to_frame);
        sum[across] += weight * implied.matrix();
        count[across] += 1;
    }
    let sum = match count {
        [within, _] if within >= WITHIN_LINKS_ALONE => sum[0],
        // without frames, only enough links within one frame place a sensor
        _ if frames.is_none() || count == [0, 0] => return None,
        _ => sum[0] + sum[1],
    };
    crate::so3::project_to_so3(&sum).map(|r| nearest_rotation(&r))
}

/// The links within one frame that place a sensor alone ([`linked_mean`]): each implies `S_s`
/// up to its noise, while a link across frames carries the held sensors' frames' drift between
/// its two frames (on a 10^4-frame path rig with information, sensors started from both kinds
/// left the joint steps to stall into passes: 7.5 s against 1.0 s; and placed by them, no
/// frame is needed: the held sensors' frames, a solve of about 2 s on that rig and 13 s at
/// 3x10^4 frames, are not computed); fewer are averaged with
/// the links across frames (on rigs of 4-9 frames with 20 % outliers, one wrong link of two
/// led 4 of 200 campaign rigs to a higher local minimum).
const WITHIN_LINKS_ALONE: usize = 8;

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
