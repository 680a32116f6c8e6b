//! A rig shaped like the simultaneous problem (`paper-notes/conjugate.md` `[H22]`): two sensors,
//! at least one estimated, and no edge between them. With `R_f = S_a F_f` (sensor `a`'s images)
//! and `S = S_b S_a^T`, the rig's cost is the joint cost of the two sensors' view graphs over
//! the frames, `f_R(R) + f_L(S R)`, and its minimum over rigs is at least the simultaneous
//! problem's (where `S` is free even when `S_a` is held); so the simultaneous certificates
//! (`[H14]`-`[H16]`: the trace-coupled dual at the estimate and its search, the SDP) bound it,
//! where the within-frame couplings `[H21]` have no edge between sensors to work with. Edges
//! with information matrices (`[H24]`) keep them in both graphs.

use super::state::RigState;
use crate::certify::log::{Prediction, Refusal};
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, Handed, JointCertifier, Plan, Rung};
use crate::error::Result;
use crate::multiple::{Edge, MultipleProblem};
use crate::rig::RigProblem;
use crate::so3::Rotation;

/// The simultaneous certificates of a two-sensor rig as a rung: the certification and the
/// prediction of its dense dual certificate on `n` frames, both handed in by the entry point.
pub(crate) struct TwoGraphsRung(pub(crate) Handed<(JointCertifier, JointPredictor)>);

/// The prediction of the simultaneous problem's dense dual certificate on `n` frames (in
/// practice [`crate::certify::simultaneous::predict_simultaneous`]) on `n` frames and graphs of
/// at most `edges` edges.
pub(crate) type JointPredictor = fn(usize, usize) -> Prediction;

impl<'a> Rung<RigState<'a>> for TwoGraphsRung {
    fn proof(&self) -> Proof {
        Proof::SimultaneousDual
    }

    fn plan(&mut self, cx: &RigState<'a>) -> Result<Plan> {
        if self.0.done {
            return Ok(Plan::Done);
        }
        if let Some(why) = not_two_graphs(cx.problem) {
            return Ok(Plan::Refuse(Refusal::NotApplicable { reason: why }, None));
        }
        // the dense dual certificate of [H15] and [H23] up to its DENSE_MAX_NODES, or the
        // low-rank one [H25], predicted from the larger sensor's graph
        let images = cx.problem.images();
        let mut per_sensor = [0usize; 2];
        for e in cx.problem.edges() {
            if let Some(count) = images.get(e.i).and_then(|a| per_sensor.get_mut(a.sensor)) {
                *count += 1;
            }
        }
        let edges = per_sensor[0].max(per_sensor[1]);
        Ok(Plan::Run((self.0.certify.1)(
            cx.problem.num_frames(),
            edges,
        )))
    }

    fn attempt(&mut self, cx: &mut RigState<'a>) -> Result<Found> {
        self.0.done = true;
        // a sensor without edges, or a graph the simultaneous certificate refuses: no bound
        let (right, left) = match two_graphs(cx.problem) {
            Ok(graphs) => graphs,
            Err(e) => return Ok(Found::failed(e.to_string())),
        };
        let (a, b) = (cx.sensors[0], cx.sensors[1]);
        let rotations: Vec<Rotation> = cx.frames.iter().map(|f| a * f).collect();
        let s = b * a.inverse();
        let mut settings = cx.tally.settings.clone();
        settings.budget.max_seconds = cx.tally.left();
        let c = match (self.0.certify.0)(&right, &left, &rotations, &s, &settings) {
            Ok(c) => c,
            Err(e) => return Ok(Found::failed(e.to_string())),
        };
        let Some(lb) = c.lower_bound else {
            return Ok(Found::failed(c.explanation));
        };
        let bound = cx.floor(lb);
        let note = format!(
            "the two sensors' view graphs as the simultaneous problem [H22]: {}",
            c.explanation.lines().last().unwrap_or("").trim()
        );
        // the family of the simultaneous certificate's bound (its note names the proof: the
        // dual certificate [H15] or the decoupled bound [H16] are both of the dual family)
        let proof = match c.method {
            crate::certify::proof::BoundMethod::Sdp => Proof::Sdp,
            _ => Proof::SimultaneousDual,
        };
        let bound = cx.offer(bound, proof, &note);
        Ok(Found::proved(bound, cx.tally.certifies(bound), note))
    }
}

/// Why the rig is not the simultaneous problem's shape, or `None` when it is.
pub(crate) fn not_two_graphs(p: &RigProblem) -> Option<String> {
    let images = p.images();
    if p.sensors().len() != 2 {
        return Some(format!("{} sensors, not 2", p.sensors().len()));
    }
    if p.held().iter().all(Option::is_some) {
        return Some("both sensors held (the frames' bound is exact)".into());
    }
    if p.edges()
        .iter()
        .any(|e| images[e.i].sensor != images[e.j].sensor)
    {
        return Some("an edge joins the two sensors".into());
    }
    None
}

/// The two sensors' view graphs over the frames (sensor 0's: the right graph), each edge with
/// its information matrix when the rig's carry them (`[H24]`: the simultaneous relaxation and
/// its dual bound hold for any connection Laplacians `Q`, `[H22]` "Information").
pub(crate) fn two_graphs(p: &RigProblem) -> Result<(MultipleProblem, MultipleProblem)> {
    let images = p.images();
    let mut graphs = [Vec::new(), Vec::new()];
    let mut information = [Vec::new(), Vec::new()];
    for (k, e) in p.edges().iter().enumerate() {
        let sensor = images[e.i].sensor;
        graphs[sensor].push(Edge {
            i: images[e.i].frame,
            j: images[e.j].frame,
            ..e.clone()
        });
        if let Some(h) = p.information() {
            information[sensor].push(h[k]);
        }
    }
    let n = p.num_frames();
    let [right, left] = graphs;
    let graph = |edges, info: Vec<_>| {
        let g = MultipleProblem::new(n, edges)?;
        match p.is_anisotropic() {
            true => g.with_information(info),
            false => Ok(g),
        }
    };
    let [right_info, left_info] = information;
    Ok((graph(right, right_info)?, graph(left, left_info)?))
}

#[cfg(test)]
mod tests {
    use super::two_graphs;
    use crate::rig::RigScene;

    /// A two-sensor rig with information and no edge between its sensors: its two graphs carry
    /// the information, and their joint cost at `(S_a F, S_b F)` is the rig's cost at `(F, S)`
    /// (the rig's own `cost`), at the truth and at a point turned from it; with scalar
    /// weights too.
    #[test]
    fn the_two_graphs_carry_the_rig_s_cost() {
        for anisotropy in [1.0, 3.0] {
            let scene = RigScene {
                cross_fraction: 0.0,
                anisotropy,
                ..RigScene::sized(12, 2, 0.02, false, 3)
            };
            let (p, truth) = scene.generate();
            assert_eq!(p.is_anisotropic(), anisotropy > 1.0);
            let (right, left) = two_graphs(&p).unwrap();
            assert_eq!(right.is_anisotropic(), p.is_anisotropic());
            assert_eq!(left.is_anisotropic(), p.is_anisotropic());
            let turned: Vec<_> = (truth.frames.iter())
                .map(|f| crate::so3::exp(&nalgebra::Vector3::new(0.1, -0.2, 0.05)) * f)
                .collect();
            for frames in [&truth.frames, &turned] {
                let (a, b) = (truth.sensors[0], truth.sensors[1]);
                let r: Vec<_> = frames.iter().map(|f| a * f).collect();
                let l: Vec<_> = frames.iter().map(|f| b * f).collect();
                let joint = right.chordal_cost(&r) + left.chordal_cost(&l);
                let rig = p.cost(frames, &truth.sensors);
                assert!((joint - rig).abs() <= 1e-9 * rig, "{joint} against {rig}");
            }
        }
    }
}
