//! Semidefinite relaxations solved with Clarabel (`paper-notes/sdp.md`).
//!
//! - [`multiple`]: the SDP relaxation of chordal L2 multiple rotation averaging, in dual form
//!   (fast, exploits graph sparsity through chordal decomposition) or primal form (cross-check),
//!   with the rounding of its solution `[P2]`-`[P5]`.
//! - [`conjugate`]: the 10x10 SDP relaxation of conjugate averaging and the rank-one extraction
//!   `[H2]`, `[H3]`.
//! - [`conv_so3`]: the same SDP with `conv(SO(3))` constraints on the Gram blocks of the edges
//!   (small graphs; what the `O(3)` relaxation misses with anisotropic costs, `[A6]`).
//! - [`lifted`]: the rank-`p` Burer-Monteiro factorisation of the multiple-averaging SDP,
//!   solved by a Riemannian trust-region method (the staircase `[D11]`).
//! - `spectral_bundle`: the model step of the proximal spectral bundles (the `conv(SO(3))`
//!   dual's node shifts `[A11]`, the rigs' couplings `[H21]`).
//! - [`svec`]: the vectorisation of symmetric matrices used by Clarabel's PSD cone `[P1]`.
//! - [`settings`]: one [`SdpSettings`] and one [`SdpStatus`] for both.
//!
//! Clarabel's types never appear in this public API (the glue is private). **The solver's
//! objective values are informational only and never a bound**: a rigorous lower bound is
//! recomputed from the returned multipliers with an independent eigenvalue computation in
//! [`crate::certify`] (contract section 3).

pub(crate) mod clarabel;
pub mod conjugate;
pub mod conv_so3;
pub mod lifted;
pub mod multiple;
pub mod settings;
pub mod simultaneous;
pub(crate) mod spectral_bundle;
pub mod svec;

pub use conjugate::{ConjugateRelaxation, relax_conjugate};
pub use multiple::{MultipleRelaxation, SdpPrediction, predict_relax_multiple, relax_multiple};
pub use settings::{ChordalMerge, SdpForm, SdpSettings, SdpStatus};
