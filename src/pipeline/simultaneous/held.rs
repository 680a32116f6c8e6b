//! A rig whose other sensor's `sensor_from_rig` is known (`paper-notes/conjugate.md` `[H18]`):
//! with `S` held, the joint cost `J(R, S)` is exactly the chordal cost of the frames' view
//! graph ([`SimultaneousProblem::frame_graph`]: the right edges and every left edge turned
//! into `S^T L_ij S`), so the multiple-averaging pipeline solves it and its whole ladder
//! certifies it: no coupling to bound, at any size the view graph's certificate reaches.

use super::{SimultaneousProblem, SimultaneousSolution};
use crate::error::Result;
use crate::multiple::MultipleSettings;
use crate::pipeline::{AverageSettings, Averaged, average_multiple};
use crate::so3::{Rotation, nearest_rotation};

/// Average the frames of the rig `problem` with its other sensor's `sensor_from_rig` held at
/// `s` (projected to its nearest rotation): [`average_multiple`] on the frames' view graph, its
/// certificate about that graph's chordal L2 problem (the rig's with `S` held, `[H18]`). The
/// solution's `s` is the held rotation and its cost the joint cost `J(R, S)`, evaluated as the
/// frame graph's chordal cost (the certificate's upper bound).
///
/// ```
/// use rotavg::multiple::synthetic::SyntheticGraph;
/// use rotavg::pipeline::simultaneous::{SyntheticRig, average_with_sensor_held};
/// let graph = SyntheticGraph { num_rotations: 40, num_edges: 160, noise_sigma: 0.02, ..Default::default() };
/// let (p, _, s) = SyntheticRig { graph }.generate();
/// let held = average_with_sensor_held(&p, &s, &Default::default())?;
/// assert!(rotavg::so3::angle_between(&held.solution.s, &s) < 1e-12);
/// assert!(held.certificate.unwrap().is_certified());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn average_with_sensor_held(
    problem: &SimultaneousProblem,
    s: &Rotation,
    settings: &AverageSettings<MultipleSettings>,
) -> Result<Averaged<SimultaneousSolution>> {
    let s = nearest_rotation(s);
    let graph = problem.frame_graph(&s)?;
    let out = average_multiple(&graph, settings)?;
    let solution = SimultaneousSolution {
        cost: out.solution.cost,
        rotations: out.solution.rotations,
        s,
        report: out.solution.report,
    };
    Ok(Averaged {
        solution,
        certificate: out.certificate,
        details: out.details,
    })
}
