//! A rig's constraints dropped (`[H19]`): the images' absolute rotations `X_a = S_{s_a} F_{f_a}`
//! are a tuple of rotations, so the images' view graph's minimum bounds `J*`. Each connected
//! component is solved from the estimate by the chordal Newton-LM and certified by the view
//! graph's ladder, with a share of the time left in proportion to its edges.

use super::state::RigState;
use crate::certify::log::Prediction;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, GraphCertifier, Plan, Rung};
use crate::error::Result;
use crate::multiple::chordal::solve_chordal;
use crate::multiple::{MultipleProblem, MultipleSettings, fix_gauge};
use crate::so3::Rotation;

/// The images' bound as a rung.
pub(crate) struct ImagesRung {
    done: bool,
    certify: GraphCertifier,
}

impl ImagesRung {
    /// The rung, certifying each component with `certify`.
    pub(crate) fn new(certify: GraphCertifier) -> Self {
        ImagesRung {
            done: false,
            certify,
        }
    }

    /// A proven lower bound on `graph`'s chordal minimum: its local minimum from `start`,
    /// certified within `seconds`; `Err` with the reason when none was proven.
    fn bound(
        &self,
        graph: &MultipleProblem,
        start: Vec<Rotation>,
        cx: &RigState<'_>,
        seconds: Option<f64>,
    ) -> Result<std::result::Result<f64, String>> {
        let local = MultipleSettings {
            max_seconds: seconds,
            ..Default::default()
        };
        let mut free = solve_chordal(graph, start, &local, None)?;
        fix_gauge(&mut free.rotations);
        let mut settings = cx.settings.clone();
        settings.budget.max_seconds = cx.left();
        let c = (self.certify)(graph, &free.rotations, &settings)?;
        Ok(c.lower_bound.ok_or(c.explanation))
    }
}

impl<'a> Rung<RigState<'a>> for ImagesRung {
    fn proof(&self) -> Proof {
        Proof::RigImages
    }

    fn plan(&mut self, cx: &RigState<'a>) -> Result<Plan> {
        if self.done {
            return Ok(Plan::Done);
        }
        // a local solve and a certification of sparse view graphs
        let size = (cx.problem.images().len() + cx.problem.edges().len()) as f64;
        Ok(Plan::Run(Prediction::new(4e-6 * size, 4000.0 * size)))
    }

    fn attempt(&mut self, cx: &mut RigState<'a>) -> Result<Found> {
        self.done = true;
        let x = cx.problem.image_rotations(cx.frames, cx.sensors);
        let images = cx.problem.image_graph()?;
        let parts: Vec<Vec<usize>> = images
            .components()
            .into_iter()
            .filter(|c| c.len() > 1)
            .collect();
        let mut sum = 0.0;
        for nodes in &parts {
            let graph = images.induced(nodes);
            let share = graph.num_edges() as f64 / images.num_edges() as f64;
            let seconds = cx.left().map(|l| l * share);
            let start = nodes.iter().map(|&a| x[a]).collect();
            match self.bound(&graph, start, cx, seconds)? {
                Ok(lb) => sum += lb,
                Err(why) => {
                    return Ok(Found::failed(format!(
                        "a component of the images' view graph ({} images) has no bound: {why}",
                        nodes.len()
                    )));
                }
            }
        }
        let bound = super::rounding::rounding_floor(sum, cx.total_weight());
        let note = format!(
            "the images' view graph without the rig's constraints: {} component(s), certified \
             minima summing to {sum:.9e} [H19]",
            parts.len()
        );
        let bound = cx.offer(bound, Proof::RigImages, &note);
        Ok(Found::proved(bound, cx.certifies(bound), note))
    }
}
