//! Certificates of global optimality and proven suboptimality gaps (SPEC section 3,
//! `paper-notes/certificates.md`).
//!
//! - [`multiple`]: the dual certificate of chordal L2 multiple rotation averaging, and the
//!   verified lower bound from any multipliers (used for SDP multipliers too).
//! - [`eigen`]: sparse extreme-eigenvalue machinery: verified lower bounds on `lambda_min` by
//!   sparse Cholesky with a rigorous floating-point margin, and Lanczos estimates.
//! - [`scalar`]: the scalar comparison `[D13]`: a proof that `S` is positive semidefinite from one
//!   factorisation of an `n x n` scalar matrix (fast on graphs whose `3n x 3n` factor fills).
//! - [`spectrum`]: the `k` smallest eigenvalues of a certificate matrix (estimates, for
//!   figures; never bounds).
//! - [`staircase`]: a Riemannian staircase (rank-lifted Burer-Monteiro descent) whose verified
//!   multipliers bound the SDP optimum when the estimate's own certificate fails.

pub mod eigen;
pub mod multiple;
pub mod scalar;
pub mod spectrum;
pub mod staircase;

pub use multiple::{
    CertifySettings, MultipleCertificate, Verification, VerifiedBound, certificate_matrix,
    certify_multiple, certify_with_multipliers, lower_bound_from_multipliers, multipliers,
};
