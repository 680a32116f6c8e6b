//! Certificates of global optimality and proven suboptimality gaps (SPEC section 3,
//! `paper-notes/certificates.md`), one verb for the three problems:
//!
//! | problem | function | methods |
//! |---|---|---|
//! | single | [`certify_single`] | theorems: closed forms, convexity `[S1]`-`[S7]` ([`single`]), then branch and bound `[B1]`-`[B6]` ([`branch_and_bound`]) |
//! | multiple | [`certify_multiple`] | dual certificate, SDP, staircase `[D3]`-`[D14]` ([`multiple`]) |
//! | conjugate | [`certify_conjugate`] | SDP with verified multipliers `[H8]` ([`conjugate`]), branch and bound `[B1]`-`[B6]` |
//!
//! Each takes `(&problem, &estimate, &CertifySettings)`, never changes the estimate, and returns
//! a [`Certification`]: the [`Certificate`] (verdict, proven lower bound, gap), what ran, and a
//! better solution if one was found while bounding.
//!
//! Every proof is a rung of one ladder ([`ladder`]): a predicted cost, an attempt, and a verified
//! bound or a typed refusal; the report lists each rung tried ([`CertifyDetails::ladder`]).
//!
//! Soundness rule: [`Verdict::Certified`] is only produced by [`Certificate::from_bounds`] from a
//! lower bound verified independently of any solver's own report.

pub mod branch_and_bound;
pub mod certificate;
pub mod certification;
pub mod conjugate;
pub mod ladder;
pub mod multiple;
pub mod settings;
pub mod simultaneous;
pub mod single;
pub mod spectrum;

pub use branch_and_bound::{BranchAndBoundSettings, BranchAndBoundStats, BranchAndBoundStop};
pub use certificate::{
    BoundMethod, Certificate, CertifiedProblem, CertifiedProblemKind, GapTolerance,
    RandomizedLowerBound, TolerancePart, ToleranceRule, Verdict,
};
pub use certification::{
    Certification, CertifyDetails, Improvement, ImprovementSource, MethodRun, SdpSummary,
};
pub use conjugate::certify_conjugate;
pub use ladder::{Attempt, Outcome, Point, Prediction, Refusal, Rung};
pub use multiple::certify_multiple;
pub use settings::{
    Budget, CertifyMode, CertifySettings, DualProof, DualSettings, RandomizedSettings,
};
pub use single::certify_single;
pub use spectrum::{SpectrumEstimate, SpectrumSettings};
