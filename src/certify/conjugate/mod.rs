//! Certificates for conjugate averaging (hand-eye; contract section 3, `paper-notes/conjugate.md`):
//! the rungs are the SDP relaxation with verified multipliers `[H8]` ([`sdp`]) and the branch
//! and bound over SO(3) `[B1]`-`[B6]` ([`crate::certify::branch_and_bound`]).

pub mod sdp;

pub use sdp::{ConjugateBound, certificate_matrix, refine_multipliers, verify_lower_bound};

use crate::certify::branch_and_bound::BranchAndBoundRung;
use crate::certify::branch_and_bound::terms::ConjugateTerms;
use crate::certify::budget::Deadline;
use crate::certify::certification::Certification;
use crate::certify::ladder::{Rungs, climb};
use crate::certify::one_rotation::RotationState;
use crate::certify::proof::Proof;
use crate::certify::settings::{CertifyMode, CertifySettings};
use crate::conjugate::{ConjugateProblem, ConjugateSolution};
use crate::error::Result;
use crate::so3::Rotation;

/// Certify a rotation `s` (never changed) for conjugate averaging. For the chordal L2 objective
/// (modes `auto` and `sdp`): solve the SDP relaxation `[H3]`, verify lower bounds from Clarabel's
/// multipliers and from the multipliers refined at `s` and at the polished extraction `[H8]`
/// (each is a bound on the global minimum; the largest is kept), and polish the rank-one
/// extraction with the local solver: when that has a lower cost than `s` it is returned as the
/// [`Certification::improvement`]. In mode `auto`, when the SDP does not certify, and for every
/// other objective, the branch and bound over SO(3) `[B1]`-`[B6]` bounds the global minimum
/// (mode `branch_and_bound`: only it; mode `auto` only up to
/// `branch_and_bound.auto_max_terms` pairs); a better solution it finds is the improvement.
/// Mode `sdp` with another objective than chordal L2 gives an `inconclusive` certificate.
///
/// ```
/// use rotavg::certify::{certify_conjugate, CertifySettings};
/// use rotavg::conjugate::ConjugateProblem;
/// use rotavg::so3::exp;
/// use nalgebra::Vector3;
/// let s = exp(&Vector3::new(0.4, -0.1, 0.7));
/// let rs = [exp(&Vector3::new(0.5, 0.0, 0.1)), exp(&Vector3::new(0.0, 0.8, -0.3))];
/// let ls: Vec<_> = rs.iter().map(|r| s * r * s.inverse()).collect();
/// let p = ConjugateProblem::from_rotations(&ls, &rs)?;
/// let c = certify_conjugate(&p, &s, &CertifySettings::default())?;
/// assert!(c.certificate.is_certified());
/// assert!(c.improvement.is_none());
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn certify_conjugate(
    problem: &ConjugateProblem,
    s: &Rotation,
    settings: &CertifySettings,
) -> Result<Certification<ConjugateSolution>> {
    settings.check_one_rotation("conjugate", CertifyMode::Sdp, s)?;
    let deadline = Deadline::start(&settings.budget);
    let cost = problem.cost(s);
    let mut state = RotationState::new(settings, deadline, *s, cost, problem.min_weight());
    let terms = ConjugateTerms::new(problem);
    let rungs: Rungs<'_, RotationState<'_, ConjugateSolution>> = vec![
        Box::new(sdp::SdpRung::new(problem)),
        Box::new(BranchAndBoundRung::new(&terms, problem.num_pairs())),
    ];
    climb(&mut state, rungs)?;
    let objective = problem.objective();
    Ok(state.finish(|details| {
        let why = match &details.skipped_reason {
            Some(r) => format!("no lower bound for the {objective} cost: {r}"),
            None => "no usable multipliers from the SDP".into(),
        };
        (Proof::Sdp, why)
    }))
}
