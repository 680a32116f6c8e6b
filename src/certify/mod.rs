//! Certificates of global optimality and proven suboptimality gaps (contract section 3,
//! `paper-notes/certificates.md`), one verb for each problem:
//!
//! | problem | function | rungs |
//! |---|---|---|
//! | single | [`certify_single`] | theorems: closed forms, convexity `[S1]`-`[S7]` ([`single`]), branch and bound `[B1]`-`[B6]` ([`branch_and_bound`]) |
//! | multiple | [`certify_multiple`] | dual certificate, staircase, SDP, conv(SO(3)) dual and SDP `[D3]`-`[D16]`, `[A6]`, `[A11]` ([`multiple`]) |
//! | conjugate | [`certify_conjugate`] | SDP with verified multipliers `[H8]` ([`conjugate`]), branch and bound `[B1]`-`[B6]` |
//! | gravity priors | [`certify_gravity`] | SO(2) dual certificate `[G3]`, the tilted soft surrogate `[G12]`, the view graph's bound `[G7]`; soft priors: the view graph with a world node `[G10]` ([`gravity`]) |
//! | simultaneous | [`certify_simultaneous`] | dual certificate at the estimate `[H15]`, SDP `[H14]` ([`simultaneous`]) |
//!
//! Each takes the problem, the estimate and a [`CertifySettings`], never changes the estimate,
//! and returns a [`Certification`]: the [`Certificate`] (verdict, proven lower bound, gap), the
//! log of what ran, and a better solution if one was found while bounding.
//!
//! The layers, one way (checked by `tests/suite/layers.rs`):
//!
//! 1. the vocabulary: [`tolerance`], [`proof`] (the one enum naming proofs), [`budget`] (the
//!    budget, its prediction models and the one clock), [`log`], [`evidence`] (what proofs
//!    report beside a bound), [`certificate`], [`settings`], [`certification`], [`rung`] (what
//!    a proof is to a climb) and [`ladder`] (the one climb, generic over the rungs);
//! 2. the rungs and their kernels, one file a proof: [`single`], [`conjugate`],
//!    [`branch_and_bound`], [`simultaneous`], [`multiple`], [`gravity`] (each problem's folder; [`spectrum`]);
//! 3. the entry points (each problem folder's `mod.rs`), which choose the rungs and climb.
//!
//! Soundness rule: [`Verdict::Certified`] is only produced by [`Certificate::from_bounds`] from a
//! lower bound verified independently of any solver's own report.

pub mod branch_and_bound;
pub mod budget;
pub mod certificate;
pub mod certification;
pub mod conjugate;
pub mod evidence;
pub mod gravity;
pub mod ladder;
pub mod log;
pub mod multiple;
pub mod one_rotation;
pub mod proof;
pub mod rig;
pub mod rung;
pub mod settings;
pub mod simultaneous;
pub mod single;
pub mod spectrum;
pub(crate) mod tally;
pub mod tolerance;

pub use branch_and_bound::{BranchAndBoundStats, BranchAndBoundStop};
pub use budget::{Budget, Deadline};
pub use certificate::{
    Certificate, CertifiedProblem, CertifiedProblemKind, RandomizedLowerBound, Verdict,
};
pub use certification::{
    Certification, CertifyDetails, Improvement, ImprovementSource, MethodRun, SdpSummary,
};
pub use conjugate::certify_conjugate;
pub use gravity::{certify_gravity, gravity_problem_kind};
pub use log::{Attempt, Outcome, Point, Prediction, Refusal};
pub use multiple::certify_multiple;
pub use proof::{BoundMethod, Proof};
pub use rig::certify_rig;
pub use settings::{
    BranchAndBoundSettings, CertifyMode, CertifySettings, ConvDualSettings, DualSettings,
    RandomizedSettings, SpectrumSettings, StaircaseSettings,
};
pub use simultaneous::certify_simultaneous;
pub use single::certify_single;
pub use spectrum::SpectrumEstimate;
pub use tolerance::{GapTolerance, TolerancePart, ToleranceRule};
