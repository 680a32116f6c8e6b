//! A rig with every sensor held (`[H19]`): `J(F, S)` is the frames' view graph's chordal cost
//! plus the within-frame edges' cost, which `F` does not change; the view graph's certified
//! bound plus that constant bounds `J*`, less the rounding `rounding.rs` charges. With gravity
//! priors on the images (`[G14]`), the frames' gravity problem instead, plus its constant, less
//! the combination's rounding.

use super::state::RigState;
use crate::certify::certificate::Certificate;
use crate::certify::log::Prediction;
use crate::certify::proof::Proof;
use crate::certify::rung::{Found, GraphCertifier, GravityCertifier, Handed, Plan, Rung};
use crate::error::Result;
use crate::rig::FrameGravity;

/// The frames' bound as a rung: first, when every sensor is held.
pub(crate) struct FramesRung(pub(crate) Handed<(GraphCertifier, GravityCertifier)>);

impl<'a> Rung<RigState<'a>> for FramesRung {
    fn proof(&self) -> Proof {
        Proof::RigFrames
    }

    fn plan(&mut self, cx: &RigState<'a>) -> Result<Plan> {
        if self.0.done || !cx.problem.all_held() {
            return Ok(Plan::Done);
        }
        // the view graph's certification: a few sparse factorisations
        let size = (cx.problem.num_frames() + cx.problem.edges().len()) as f64;
        Ok(Plan::Run(Prediction::new(2e-6 * size, 2000.0 * size)))
    }

    fn attempt(&mut self, cx: &mut RigState<'a>) -> Result<Found> {
        self.0.done = true;
        let (graph_certify, gravity_certify) = self.0.certify;
        let mut settings = cx.tally.settings.clone();
        settings.budget.max_seconds = cx.tally.left();
        let (inner, constant, charge, edges, what) = match cx.problem.frame_gravity(cx.sensors)? {
            Some(fg) => {
                // a point the frames' problem refuses (off its held directions) fails the rung
                let inner = match gravity_certify(&fg.problem, cx.frames, &settings) {
                    Ok(c) => c,
                    Err(e) => {
                        return Ok(Found::failed(format!("the frames' gravity problem: {e}")));
                    }
                };
                let charge = combination_charge(&fg, cx);
                let edges = fg.problem.problem().num_edges();
                (inner, fg.constant, charge, edges, "gravity problem")
            }
            None => {
                let (graph, constant) = cx.problem.frame_graph(cx.sensors)?;
                let inner = graph_certify(&graph, cx.frames, &settings)?;
                // with information, the reformulation's rounding measured edge by edge
                // (`[H24]` "Measured rounding") in place of the floor's allowance
                let measured = match inner.lower_bound {
                    Some(_) => {
                        super::rounding::frames_information_charge(cx.problem, cx.sensors, &graph)
                    }
                    None => None, // nothing to charge
                };
                if let Some(measured) = measured {
                    let edges = graph.num_edges();
                    return found(
                        cx,
                        &inner,
                        (constant, measured),
                        (edges, "view graph"),
                        false,
                    );
                }
                (inner, constant, 0.0, graph.num_edges(), "view graph")
            }
        };
        found(cx, &inner, (constant, charge), (edges, what), true)
    }
}

/// The rung's bound from the frames' certificate `inner`: its bound plus `constant`, less
/// `charge` and, when `floored`, the rounding allowance of `rounding.rs` (not when `charge` is
/// the measured rounding itself, [`super::rounding::frames_information_charge`]).
fn found(
    cx: &mut RigState<'_>,
    inner: &Certificate,
    (constant, charge): (f64, f64),
    (edges, what): (usize, &str),
    floored: bool,
) -> Result<Found> {
    let Some(lb) = inner.lower_bound else {
        return Ok(Found::failed(format!(
            "the frames' {what} has no bound: {}",
            inner.explanation
        )));
    };
    let bound = match floored {
        true => cx.floor(lb + constant - charge),
        false => lb + constant - charge,
    };
    let rounding = match floored {
        true => "rounding".to_string(),
        false => format!("the rounding measured edge by edge, {charge:.3e} [H24]"),
    };
    let note = format!(
        "the frames' {what} ({edges} edges) bounded by {} at {lb:.9e}, plus the within-frame \
         edges'{} {constant:.9e}, less {rounding} [{}]",
        inner.method,
        if floored && charge > 0.0 {
            " and the priors' combination"
        } else {
            ""
        },
        if what == "view graph" { "H19" } else { "G14" }
    );
    let bound = cx.offer(bound, Proof::RigFrames, &note);
    Ok(Found::proved(bound, cx.tally.certifies(bound), note))
}

/// What `[G14]` charges for the frames' priors as computed: the soft combination's rounding, or
/// for held directions turned by at most `delta` from the exact ones, the change of the
/// minimum: `6 delta sqrt(W J) + 8 delta^2 W` (`W` the edges' weight, `J` the estimate's cost);
/// with information, whose edge weights are 1 and whose `M` may be indefinite, the Lipschitz
/// bound `20 delta sum tr(H)` (`[G14]` "Information": `8 delta ||M||_*` per edge).
fn combination_charge(fg: &FrameGravity, cx: &RigState<'_>) -> f64 {
    let delta = fg.held_angle;
    let held = match cx.problem.information() {
        Some(info) => 20.0 * delta * info.iter().map(|h| h.matrix().trace()).sum::<f64>(),
        None => {
            let w = cx.total_weight();
            6.0 * delta * (w * cx.tally.cost.max(0.0)).sqrt() + 8.0 * delta * delta * w
        }
    };
    (fg.soft_charge + held) * (1.0 + 1e-6)
}
