//! Certificates for single rotation averaging (`paper-notes/single.md`): a proven lower bound on
//! the global minimum of `sum_i w_i d(R_i, R)^p`, computed from the data and the estimate only
//! (never from a solver's own claims), and the verdict of [`crate::Certificate::from_bounds`].
//! The rungs: the theorems ([`theory`]) and the branch and bound over SO(3)
//! ([`crate::certify::branch_and_bound`]).

pub mod theory;

pub use theory::PAIRWISE_TEST_LIMIT;

use crate::certify::branch_and_bound::BranchAndBoundRung;
use crate::certify::branch_and_bound::terms::SingleTerms;
use crate::certify::budget::Deadline;
use crate::certify::certification::Certification;
use crate::certify::ladder::{Rungs, climb};
use crate::certify::one_rotation::RotationState;
use crate::certify::proof::Proof;
use crate::certify::settings::{CertifyMode, CertifySettings};
use crate::error::Result;
use crate::single::{SingleProblem, SingleSolution};
use crate::so3::Rotation;
use theory::TheoryRung;

/// Certify `estimate` for `problem` under its objective, without changing it. The upper bound
/// is the cost of `estimate`; the lower bound is proven (see the module docs); the verdict
/// compares the gap with `settings.tolerance`. Modes: `theory` (the theorems only),
/// `branch_and_bound` (the branch and bound over SO(3) only, `[B1]`-`[B6]`), `auto` (the
/// theorems, then the branch and bound when they do not certify; the larger bound is
/// reported). When the branch and bound finds a solution of lower cost it is returned as the
/// [`Certification::improvement`] (the estimate's verdict is then `gap_reported`).
///
/// ```
/// use rotavg::certify::{certify_single, CertifySettings};
/// use rotavg::single::SingleProblem;
/// use rotavg::{Rotation, Verdict};
/// let p = SingleProblem::new(vec![Rotation::identity(); 4], None)?;
/// let c = certify_single(&p, &Rotation::identity(), &CertifySettings::default())?;
/// assert_eq!(c.certificate.verdict, Verdict::Certified);
/// # Ok::<(), rotavg::Error>(())
/// ```
pub fn certify_single(
    problem: &SingleProblem,
    estimate: &Rotation,
    settings: &CertifySettings,
) -> Result<Certification<SingleSolution>> {
    settings.check_one_rotation("single", CertifyMode::Theory, estimate)?;
    let deadline = Deadline::start(&settings.budget);
    let cost = problem.cost(estimate);
    let mut state = RotationState::new(settings, deadline, *estimate, cost, problem.min_weight());
    let terms = SingleTerms::new(problem);
    let rungs: Rungs<'_, RotationState<'_, SingleSolution>> = vec![
        Box::new(TheoryRung::new(problem)),
        Box::new(BranchAndBoundRung::new(&terms, problem.len())),
    ];
    climb(&mut state, rungs)?;
    let objective = problem.objective();
    Ok(state.finish(|details| {
        let why = details
            .skipped_reason
            .clone()
            .or_else(|| details.methods().last().map(|m| m.note.clone()))
            .unwrap_or_else(|| format!("no lower bound for the {objective} cost"));
        (Proof::Theory, why)
    }))
}
