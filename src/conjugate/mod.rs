//! Conjugate rotation averaging (hand-eye calibration's rotation part): find `S` with
//! `R_i ~ S^-1 L_i S` from weighted pairs `(L_i, R_i)` (SPEC sections 1-3).
//!
//! * [`ConjugateProblem`]: validated pairs, the chordal cost `g(S) = sum w_i ||S R_i - L_i S||_F^2`,
//!   diagnostics (angle mismatch, uninformative pairs, identifiability).
//! * [`quaternion_closed_form`], [`solve_conjugate`], [`solve_conjugate_from`]: local solvers.
//! * [`relax_conjugate`], [`certify_conjugate`]: the 10x10 SDP relaxation and its verified bound.
//! * [`average_conjugate`]: the pipeline closed form -> chordal -> SDP certificate.
//! * [`synthetic`]: seeded instances with a planted `S`.
//! * [`simultaneous`]: `S` jointly with absolute rotations from two view graphs (`[H12]`).
//!
//! Every equation is stated in `paper-notes/conjugate.md` with a label `[H1]`..`[H9]`.

mod average;
mod local;
mod problem;
pub mod sdp;
pub mod simultaneous;
pub mod synthetic;

pub use average::{
    AverageSettings, CertifyMode, ConjugateEstimate, SdpSummary, average_conjugate,
    average_conjugate_from, certify_conjugate,
};
pub use local::{
    ConjugateSettings, ConjugateSolution, Loss, conjugate_cost, quaternion_closed_form,
    solve_conjugate, solve_conjugate_from,
};
pub use problem::{
    ConjugatePair, ConjugateProblem, DiagnosticSettings, Diagnostics, Identifiability,
};
pub use sdp::{SdpRelaxation, SdpSettings, SdpStatus, relax_conjugate};
