//! A rig's constraints dropped (`[H19]`): the images' absolute rotations `X_a = S_{s_a} F_{f_a}`
//! are a tuple of rotations, so the images' view graph's minimum bounds `J*`. Each connected
//! component is solved from the estimate by the chordal Newton-LM and certified by the view
//! graph's ladder, with a share of the time left in proportion to its edges. A component
//! whose graph the ladder cannot bound (weakly joined sensors: its factor over the budget, the
//! comparisons' condition failing on the few edges between sensors) is split by the sensor
//! pair of its edges (`[H19]`, the split): `min sum_g J_g >= sum_g min J_g`.

use super::state::RigState;
use crate::certify::log::Prediction;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, GraphCertifier, Handed, Plan, Rung};
use crate::certify::settings::CertifySettings;
use crate::error::Result;
use crate::multiple::chordal::solve_chordal;
use crate::multiple::{MultipleProblem, MultipleSettings, fix_gauge};
use crate::so3::Rotation;

/// The images' bound as a rung.
pub(crate) struct ImagesRung(pub(crate) Handed<GraphCertifier>);

impl<'a> Rung<RigState<'a>> for ImagesRung {
    fn proof(&self) -> Proof {
        Proof::RigImages
    }

    fn plan(&mut self, cx: &RigState<'a>) -> Result<Plan> {
        if self.0.done {
            return Ok(Plan::Done);
        }
        // a local solve and a certification of sparse view graphs; a fallback after the coupled
        // bound `[H21]`, which certifies the noisy rigs this bound leaves a gap on
        let size = (cx.problem.images().len() + cx.problem.edges().len()) as f64;
        Ok(Plan::Fallback(Prediction::new(4e-6 * size, 4000.0 * size)))
    }

    fn attempt(&mut self, cx: &mut RigState<'a>) -> Result<Found> {
        self.0.done = true;
        let x = cx.problem.image_rotations(cx.frames, cx.sensors);
        let images = cx.problem.image_graph()?;
        // a labelled estimate is no bound of the rig's: not run
        let mut settings = cx.tally.settings.clone();
        settings.dual.randomized.enabled = false;
        let whole = components_minimum(
            self.0.certify,
            (&images, &x, Start::Solved),
            cx,
            &settings,
            cx.tally.left(),
        )?;
        let (sum, note) = match whole {
            Ok((parts, sum)) => (
                sum,
                format!(
                    "the images' view graph without the rig's constraints: {parts} component(s), \
                     certified minima summing to {sum:.9e} [H19]"
                ),
            ),
            Err(why) => {
                let (sum, split) =
                    sensor_pairs_minimum(self.0.certify, &images, &x, cx, &settings)?;
                (
                    sum,
                    format!(
                        "the images' view graph without the rig's constraints, split by the \
                         sensor pairs of its edges: {split}, certified minima summing to \
                         {sum:.9e} [H19]; the whole graph was not bounded ({why})"
                    ),
                )
            }
        };
        // the same data and cost as the rig's: no reformulation to charge with information
        // (`[H24]`); scalar weights keep `[H19]`'s rounding floor
        let bound = if cx.problem.is_anisotropic() {
            sum
        } else {
            cx.floor(sum)
        };
        let bound = cx.offer(bound, Proof::RigImages, &note);
        Ok(Found::proved(bound, cx.tally.certifies(bound), note))
    }
}

/// `[H19]`'s split: the images' edges grouped by the (unordered) sensor pair of their images,
/// each group's graph bounded by the sum of its components' certified minima, or by 0 (a
/// sum of squares) where the ladder finds none; `sum_g min J_g <= min sum_g J_g`. The sum and a
/// note of what bounded each group.
fn sensor_pairs_minimum(
    certify: GraphCertifier,
    images: &MultipleProblem,
    x: &[Rotation],
    cx: &RigState<'_>,
    settings: &CertifySettings,
) -> Result<(f64, String)> {
    let sensor = |a: usize| cx.problem.images()[a].sensor;
    let pair = |e: &crate::multiple::Edge| {
        let (s, t) = (sensor(e.i), sensor(e.j));
        (s.min(t), s.max(t))
    };
    let groups: std::collections::BTreeSet<(usize, usize)> =
        images.edges().iter().map(pair).collect();
    let (mut sum, mut zero) = (0.0, Vec::new());
    let total = images.num_edges() as f64;
    for (s, t) in groups {
        let keep: Vec<bool> = images.edges().iter().map(|e| pair(e) == (s, t)).collect();
        let graph = images.edge_subset(&keep)?;
        let share = graph.num_edges() as f64 / total;
        let seconds = cx.tally.left().map(|l| l * share);
        match components_minimum(certify, (&graph, x, Start::Solved), cx, settings, seconds)? {
            Ok((_, min)) => sum += min,
            Err(_) => zero.push(format!("{s}-{t}")),
        }
    }
    let split = if zero.is_empty() {
        "every group bounded".to_string()
    } else {
        format!("sensor pairs {} bounded by 0", zero.join(", "))
    };
    Ok((sum, split))
}

/// Whether [`components_minimum`] solves each component from the estimate before certifying
/// it.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(super) enum Start {
    /// Solved from the estimate by the chordal Newton-LM (the images' graph, where the rig's
    /// estimate is not critical).
    Solved,
    /// Certified at the estimate itself: a critical point by construction (the augmented graph
    /// of couplings built at it for its multipliers, `[H21]`; `[D15]` charges the residual
    /// left). The Newton step that only confirmed convergence took 8 s of a 10^4-frame,
    /// 6-sensor rig's certificate.
    Given,
}

/// The sum of the certified minima of `graph`'s components (of more than one node), each
/// started from `x` as `start` says and certified by `certify` with `settings`, with a share of
/// `seconds` in proportion to its edges; the number of components, or why one has no bound.
pub(super) fn components_minimum(
    certify: GraphCertifier,
    (graph, x, start): (&MultipleProblem, &[Rotation], Start),
    cx: &RigState<'_>,
    settings: &CertifySettings,
    seconds: Option<f64>,
) -> Result<std::result::Result<(usize, f64), String>> {
    let parts: Vec<Vec<usize>> = graph
        .components()
        .into_iter()
        .filter(|c| c.len() > 1)
        .collect();
    let mut sum = 0.0;
    for nodes in &parts {
        let part = graph.induced(nodes)?;
        if part.num_edges() + 1 == nodes.len() {
            continue; // a tree: its measurements are met exactly, minimum 0
        }
        let share = part.num_edges() as f64 / graph.num_edges() as f64;
        let local = MultipleSettings {
            max_seconds: seconds.map(|l| l * share),
            ..Default::default()
        };
        let given: Vec<Rotation> = nodes.iter().map(|&a| x[a]).collect();
        let rotations = match start {
            Start::Given => given,
            Start::Solved => {
                let mut free = solve_chordal(&part, given, &local, None)?;
                fix_gauge(&mut free.rotations);
                free.rotations
            }
        };
        let mut settings = settings.clone();
        settings.budget.max_seconds = cx.tally.left().map(|l| seconds.map_or(l, |s| l.min(s)));
        let c = certify(&part, &rotations, &settings)?;
        match c.lower_bound {
            Some(lb) => sum += lb,
            None => {
                return Ok(Err(format!(
                    "a component of {} images has no bound: {}",
                    nodes.len(),
                    c.explanation
                )));
            }
        }
    }
    Ok(Ok((parts.len(), sum)))
}
