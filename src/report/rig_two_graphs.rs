//! Two view graphs whose edges carry information matrices, as the rig of two sensors they
//! describe (`paper-notes/conjugate.md` `[H24]`, "Two view graphs"): `rotavg rig RIGHT LEFT`,
//! `rotavg certify RIGHT --left LEFT` and Python's `average_rig` solve and certify them as
//! `rotavg rig FILE` does a rig file ([`super::RigFileReport`]); scalar weights keep the
//! simultaneous problem of [`super::RigReport`].

use crate::io::detect::LoadedGraph;
use crate::io::rig::{LoadedRig, TWO_GRAPHS_FORMAT};
use crate::multiple::Edge;
use crate::multiple::anisotropic::Information;
use crate::multiple::gravity::GravityPriors;
use crate::rig::{Image, RigProblem, Sensor};
use crate::so3::Rotation;
use crate::{Error, Result};

/// Whether `rotavg rig RIGHT LEFT` reads `right` and `left` as a rig of two sensors
/// ([`two_graph_rig`]): either graph's edges carry information matrices.
pub fn needs_rig_form(right: &LoadedGraph, left: &LoadedGraph) -> bool {
    right.problem.is_anisotropic() || left.problem.is_anisotropic()
}

/// The frames of two view graphs are their node ids, the same in both: otherwise the error
/// names how many are only in each.
pub(super) fn same_frames(right: &LoadedGraph, left: &LoadedGraph) -> Result<()> {
    if right.node_ids == left.node_ids {
        return Ok(());
    }
    let only = |a: &LoadedGraph, b: &LoadedGraph| {
        (a.node_ids.iter())
            .filter(|id| b.node_ids.binary_search(id).is_err())
            .count()
    };
    Err(Error::InvalidSettings {
        name: "rig".into(),
        reason: format!(
            "the two view graphs must have the same frames (node ids): {} only in the first, \
             {} only in the second",
            only(right, left),
            only(left, right)
        ),
    })
}

/// The rig of two sensors that `right` and `left` describe: frame `f` is node `f` of both
/// graphs; sensor 0 takes `right`'s images (images `0..n`, the rig's reference, known at the
/// identity: the frames are its rotations) and sensor 1 `left`'s (images `n..2n`), its
/// `sensor_from_rig` `S` estimated, or held at `held`; each graph's edges join its own
/// sensor's images with their information (a scalar graph's weight `w` as `w I`, the same
/// cost, when the other graph carries information; two scalar graphs keep their weights).
/// Image `f` and `n + f` have ids `f` and `n + f`. `gravity`: priors on the frames, one entry
/// per node of `right` (`rotavg rig RIGHT LEFT --gravity`, keyed as `multiple` keys `RIGHT`'s
/// nodes), and the reader's warnings: the priors of the reference sensor's images
/// (`paper-notes/gravity.md` `[G14]`, "Two view graphs"). Errors: different node ids, what
/// [`RigProblem::new`] refuses, priors not one per frame.
pub fn two_graph_rig(
    right: &LoadedGraph,
    left: &LoadedGraph,
    held: Option<Rotation>,
    gravity: Option<(GravityPriors, Vec<crate::warning::Warning>)>,
) -> Result<LoadedRig> {
    same_frames(right, left)?;
    let n = right.problem.num_rotations();
    let images: Vec<Image> = (0..2)
        .flat_map(|sensor| (0..n).map(move |frame| Image { frame, sensor }))
        .collect();
    // the reference known (not merely the gauge's choice): with `held`, both are
    let sensors = vec![
        Sensor {
            sensor_from_rig: Some(Rotation::identity()),
        },
        Sensor {
            sensor_from_rig: held,
        },
    ];
    let mut edges = Vec::with_capacity(right.problem.num_edges() + left.problem.num_edges());
    let mut information = Vec::with_capacity(edges.capacity());
    for (graph, offset) in [(right, 0), (left, n)] {
        let given = graph.problem.information();
        for (k, e) in graph.problem.edges().iter().enumerate() {
            information.push(match given {
                Some(h) => h[k],
                None => Information::new(nalgebra::Matrix3::identity() * e.weight)?,
            });
            edges.push(Edge {
                i: e.i + offset,
                j: e.j + offset,
                ..e.clone()
            });
        }
    }
    let problem = RigProblem::new(n, sensors, images, edges)?;
    let problem = match needs_rig_form(right, left) {
        true => problem.with_information(information)?,
        false => problem,
    };
    let warnings = [super::input_warnings(right), super::input_warnings(left)].concat();
    let rig = LoadedRig {
        problem,
        frame_ids: right.node_ids.clone(),
        sensor_ids: vec![0, 1],
        image_ids: (0..2 * n as u64).collect(),
        image_names: Vec::new(),
        format: TWO_GRAPHS_FORMAT.into(),
        pending_gravity: None,
        warnings,
    };
    with_frame_gravity(rig, gravity)
}

/// `rig` ([`two_graph_rig`]'s) with `priors` on its frames and the reader's `warnings`; `rig`
/// itself without them. By `[G14]` Claim 1 with `S_0 = I`, a frame's prior is its reference
/// image's; the other sensor's images have none. Errors: not one entry per frame, and what
/// [`LoadedRig::with_gravity`] refuses.
fn with_frame_gravity(
    rig: LoadedRig,
    gravity: Option<(GravityPriors, Vec<crate::warning::Warning>)>,
) -> Result<LoadedRig> {
    let Some((priors, warnings)) = gravity else {
        return Ok(rig);
    };
    let frames = rig.problem.num_frames();
    if priors.len() != frames {
        return Err(Error::InvalidSettings {
            name: "gravity".into(),
            reason: format!(
                "{} gravity entries for two view graphs of {frames} frames (one per node of the \
                 reference graph)",
                priors.len()
            ),
        });
    }
    // the reference sensor's images are `0..frames`; the other's `frames..2 frames` get none
    let images: Vec<usize> = (0..rig.problem.images().len()).collect();
    rig.with_gravity(priors.restricted(&images)?, warnings)
}

/// Certify an estimate of two view graphs' rig computed elsewhere (`rotations` of the frames,
/// `s` the other sensor's `sensor_from_rig`), never changed, as the rig of two sensors they
/// describe (`rig`, from [`two_graph_rig`] without a held sensor, perhaps with gravity priors): `rotavg certify RIGHT --left LEFT --estimate FILE` when either
/// graph carries information or gravity priors are given. `input` names the two files.
pub fn certify_two_graphs(
    input: String,
    rig: LoadedRig,
    rotations: Vec<Rotation>,
    s: Rotation,
    settings: &crate::certify::CertifySettings,
) -> Result<super::RigFileReport> {
    let estimate = crate::io::rig::RigEstimate {
        frames: rotations,
        sensors: vec![Rotation::identity(), s],
        projection: None,
    };
    super::RigFileReport::certify(input, rig, estimate, settings)
}
