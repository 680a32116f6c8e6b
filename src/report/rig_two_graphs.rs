//! Two view graphs whose edges carry information matrices, as the rig of two sensors they
//! describe (`paper-notes/conjugate.md` `[H24]`, "Two view graphs"): `rotavg rig RIGHT LEFT`,
//! `rotavg certify RIGHT --left LEFT` and Python's `average_rig` solve and certify them as
//! `rotavg rig FILE` does a rig file ([`super::RigFileReport`]); scalar weights keep the
//! simultaneous problem of [`super::RigReport`].

use crate::io::detect::LoadedGraph;
use crate::io::rig::{LoadedRig, TWO_GRAPHS_FORMAT};
use crate::multiple::Edge;
use crate::multiple::anisotropic::Information;
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
/// cost). Image `f` and `n + f` have ids `f` and `n + f`. Errors: different node ids, and
/// what [`RigProblem::new`] refuses.
pub fn two_graph_rig(
    right: &LoadedGraph,
    left: &LoadedGraph,
    held: Option<Rotation>,
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
    let problem = RigProblem::new(n, sensors, images, edges)?.with_information(information)?;
    let warnings = [super::input_warnings(right), super::input_warnings(left)].concat();
    Ok(LoadedRig {
        problem,
        frame_ids: right.node_ids.clone(),
        sensor_ids: vec![0, 1],
        image_ids: (0..2 * n as u64).collect(),
        image_names: Vec::new(),
        format: TWO_GRAPHS_FORMAT.into(),
        pending_gravity: None,
        warnings,
    })
}

/// Certify an estimate of two view graphs' rig computed elsewhere (`rotations` of the frames,
/// `s` the other sensor's `sensor_from_rig`), never changed, as the rig of two sensors they
/// describe ([`two_graph_rig`]): `rotavg certify RIGHT --left LEFT --estimate FILE` when either
/// graph carries information. `input` names the two files.
pub fn certify_two_graphs(
    input: String,
    (right, left): (&LoadedGraph, &LoadedGraph),
    rotations: Vec<Rotation>,
    s: Rotation,
    settings: &crate::certify::CertifySettings,
) -> Result<super::RigFileReport> {
    let rig = two_graph_rig(right, left, None)?;
    let estimate = crate::io::rig::RigEstimate {
        frames: rotations,
        sensors: vec![Rotation::identity(), s],
        projection: None,
    };
    super::RigFileReport::certify(input, rig, estimate, settings)
}
