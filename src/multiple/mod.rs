//! Multiple rotation averaging: absolute rotations `R_0..R_{n-1}` from relative measurements
//! `R_ij` on a view graph, with the convention **`R_ij R_i = R_j`** (SPEC section 1).
//!
//! Chordal L2 cost `f(R) = sum_(i,j) w_ij ||R_j - R_ij R_i||_F^2` (`paper-notes/multiple.md`,
//! `[M1]`). Gauge: solutions are defined up to `R_i -> R_i G`; outputs fix `R_0 = I`.

pub mod accuracy;
pub mod average;
pub mod chordal;
pub mod geodesic;
pub mod init;
pub mod laplacian;
pub mod problem;
pub mod robust;
pub mod solve;
pub mod stats;
pub mod synthetic;

pub use average::{
    AverageMultipleSettings, CertifyMode, EstimateCertificate, MultipleEstimate, PipelineDetails,
    average_multiple, certify_multiple_estimate,
};
pub use chordal::chordal_gradient;
pub use init::{initialise, spanning_tree, spectral};
pub use problem::{Edge, MultipleProblem, fix_gauge};
pub use robust::{loss_cost_gradient, loss_terms};
pub use solve::{Initialisation, Loss, MultipleSettings, MultipleSolution, solve_multiple};
