//! Certificates of the simultaneous problem (`paper-notes/conjugate.md` `[H14]`, `[H15]`): the
//! hand-eye rotation `S` and the absolutes `R_i` of two view graphs, jointly. Three rungs: the
//! dual certificate at the estimate in low-rank form (`low_rank.rs`, `sparse_side.rs`,
//! `low_rank_rung.rs`, `[H25]`: no dense matrix) and densely with a search over its couplings
//! ([`dual`], `[H15]`), then the SDP of [`crate::relax::simultaneous`] (`[H14]`, `sdp.rs`), each
//! predicted from its size and refused over the budget; their multipliers are verified
//! independently of how they were found ([`bound`], `sparse_side.rs`). When neither proves enough (or fits), the decoupled bound
//! (`decoupled.rs`, `[H16]`): the two graphs' own certified minima, summed, at any size.

pub mod bound;
mod conv;
mod decoupled;
pub mod dual;
mod grounded;
mod low_rank;
mod low_rank_rung;
pub mod multipliers;
mod sdp;
mod search;
mod sparse_side;
mod state;

pub use bound::{SimultaneousBound, verify_simultaneous_bound, verify_simultaneous_bound_at};
pub use dual::predict_multipliers_at_estimate;
pub use multipliers::multipliers_at_estimate;

use crate::certify::budget::Deadline;
use crate::certify::certification::{Certification, Improvement, ImprovementSource};
use crate::certify::ladder::{Rungs, climb};
use crate::certify::proof::{BoundMethod, Proof};
use crate::certify::rung::Handed;
use crate::certify::settings::CertifySettings;
use crate::certify::tally::Tally;
use crate::error::{Error, Result};
use crate::multiple::MultipleProblem;
use crate::relax::simultaneous::{JointRotations, joint_cost};
use crate::so3::Rotation;
use state::SimState;

/// Certify a joint estimate `(R, S)` of the simultaneous problem (right graph `right`, left
/// graph `left`, the same `n` nodes). Its rungs, each predicted and refused over the budget:
/// the dual certificate at the estimate `[H15]` (modes `auto` and `dual`; with low-rank
/// couplings and sparse factorisations `[H25]`, or dense `3n x 3n` with a search over the
/// couplings, the cheaper first), then, when it is not sufficient, the SDP `[H14]` (modes `auto`
/// and `sdp`), and the decoupled bound `[H16]`; any
/// other mode is refused as not applicable and the verdict is `inconclusive`. The verdict uses
/// the best verified bound. The estimate is never changed; a cheaper rounding of the SDP is
/// returned as the improvement (not polished: the joint local solver lives in
/// [`crate::pipeline::simultaneous`], which polishes it).
pub fn certify_simultaneous(
    right: &MultipleProblem,
    left: &MultipleProblem,
    rotations: &[Rotation],
    s: &Rotation,
    settings: &CertifySettings,
) -> Result<Certification<JointRotations>> {
    certify_with(right, left, (rotations, s), settings, true)
}

/// [`certify_simultaneous`]'s certificate with the dual certificate at the estimate alone (its
/// low-rank and dense rungs): the surrogate pair's inside the `conv(SO(3))` rung (`[H27]`).
pub(crate) fn dual_only_certificate(
    right: &MultipleProblem,
    left: &MultipleProblem,
    rotations: &[Rotation],
    s: &Rotation,
    settings: &CertifySettings,
) -> Result<crate::certify::certificate::Certificate> {
    Ok(certify_with(right, left, (rotations, s), settings, false)?.certificate)
}

/// The certification of `(rotations, s)`: every rung (`all`), or the dual certificate's.
fn certify_with(
    right: &MultipleProblem,
    left: &MultipleProblem,
    (rotations, s): (&[Rotation], &Rotation),
    settings: &CertifySettings,
    all: bool,
) -> Result<Certification<JointRotations>> {
    let deadline = Deadline::start(&settings.budget);
    settings.validate()?;
    let n = right.num_rotations();
    if rotations.len() != n || left.num_rotations() != n {
        return Err(Error::InvalidSettings {
            name: "estimate".into(),
            reason: format!(
                "{} rotations for two view graphs of {} and {} nodes",
                rotations.len(),
                n,
                left.num_rotations()
            ),
        });
    }
    let cost = joint_cost(right, left, rotations, s);
    let min_weight = right.min_weight().min(left.min_weight());
    let mut state = SimState {
        right,
        left,
        rotations,
        s,
        tally: Tally::new(settings, deadline, cost, min_weight),
        improvement: None,
        sdp: None,
        conv_ran: false,
    };
    let mut rungs: Rungs<'_, SimState<'_>> = vec![Box::new(low_rank_rung::LowRankRung::default())];
    if all {
        rungs.push(Box::new(conv::ConvRung(Handed::new((
            dual_only_certificate,
            predict_simultaneous,
        )))));
    }
    rungs.push(Box::new(dual::DualRung::default()));
    if all {
        rungs.push(Box::new(sdp::SdpRung::default()));
        rungs.push(Box::new(decoupled::DecoupledRung::new(
            crate::certify::multiple::graph_certificate,
        )));
    }
    climb(&mut state, rungs)?;
    let (certificate, mut details) = state.tally.finish(BoundMethod::Sdp, Proof::method);
    details.sdp = state.sdp;
    details.improvement = state.improvement.as_ref().map(|r| Improvement {
        source: ImprovementSource::SdpRounding,
        cost: r.cost,
    });
    Ok(Certification {
        certificate,
        details,
        improvement: state.improvement,
    })
}

/// The predicted cost of [`certify_simultaneous`]'s first proof on `n` nodes with view graphs
/// of at most `edges` edges each: the cheaper of the dense dual certificate (up to
/// [`dual::DENSE_MAX_NODES`]) and the low-rank one `[H25]` (isotropic graphs).
pub fn predict_simultaneous(n: usize, edges: usize) -> crate::certify::budget::Prediction {
    let sparse = low_rank_rung::predict(n, edges);
    if n > dual::DENSE_MAX_NODES {
        return sparse;
    }
    let dense = predict_multipliers_at_estimate(n);
    if dense.seconds < sparse.seconds {
        dense
    } else {
        sparse
    }
}

/// The certificate of [`certify_simultaneous`] alone (the rungs of other problems take it as a
/// [`crate::certify::rung::JointCertifier`]).
pub(crate) fn joint_certificate(
    right: &MultipleProblem,
    left: &MultipleProblem,
    rotations: &[Rotation],
    s: &Rotation,
    settings: &CertifySettings,
) -> Result<crate::certify::certificate::Certificate> {
    Ok(certify_simultaneous(right, left, rotations, s, settings)?.certificate)
}
