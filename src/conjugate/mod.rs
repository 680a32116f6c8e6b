//! Conjugate rotation averaging (hand-eye calibration's rotation part): find `S` with
//! `R_i ~ S^-1 L_i S` from weighted pairs `(L_i, R_i)` (contract sections 1-3).
//!
//! * [`ConjugateProblem`]: validated pairs with their [`Objective`](crate::objective::Objective)
//!   (default the chordal cost `g(S) = sum w_i ||S R_i - L_i S||_F^2`), diagnostics (angle
//!   mismatch, uninformative pairs, identifiability).
//! * [`solve_conjugate`] (and the [`quaternion_closed_form`] it starts from): local solvers.
//! * The 10x10 SDP relaxation is [`crate::relax::relax_conjugate`], its verified bound
//!   [`crate::certify::certify_conjugate`], the whole pipeline
//!   [`crate::pipeline::average_conjugate`] and the simultaneous problem
//!   [`crate::pipeline::simultaneous`].
//! * [`synthetic`]: seeded instances with a planted `S`.
//!
//! Every equation is stated in `paper-notes/conjugate.md` with a label `[H1]`..`[H15]`.

pub mod problem;
pub mod solve;
pub mod synthetic;

pub use problem::{
    ConjugatePair, ConjugateProblem, DiagnosticSettings, Diagnostics, Identifiability,
};
pub use solve::{ConjugateSettings, ConjugateSolution, quaternion_closed_form, solve_conjugate};
