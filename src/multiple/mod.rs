//! Multiple rotation averaging: absolute rotations `R_0..R_{n-1}` from relative measurements
//! `R_ij` on a view graph, with the convention **`R_ij R_i = R_j`** (SPEC section 1).
//!
//! Chordal L2 cost `f(R) = sum_(i,j) w_ij ||R_j - R_ij R_i||_F^2` (`paper-notes/multiple.md`,
//! `[M1]`). Gauge: solutions are defined up to `R_i -> R_i G`; outputs fix `R_0 = I`.
//!
//! - Data: [`MultipleProblem::new`] from [`Edge`]s; files through [`crate::io`]; seeded
//!   instances from [`synthetic::SyntheticGraph`].
//! - Local solvers: [`solve_multiple`] with [`MultipleSettings`] (chordal Newton-LM, geodesic,
//!   L1 / Huber / Cauchy IRLS; [`Initialisation`] spanning tree or spectral, see [`initialise`]).
//! - Whole pipeline: [`average_multiple`] (solve, then the dual certificate, then the SDP or the
//!   staircase when needed) and [`certify_multiple_estimate`] for an estimate computed elsewhere.
//! - Diagnostics: [`stats::graph_stats`], [`accuracy::align_and_compare`] against ground truth,
//!   the connection Laplacian [`laplacian::connection_laplacian`].
//!
//! ```
//! use rotavg::multiple::{solve_multiple, MultipleSettings, synthetic::SyntheticGraph};
//! use rotavg::multiple::accuracy::align_and_compare;
//! let (problem, truth) = SyntheticGraph { num_rotations: 40, num_edges: 120, noise_sigma: 0.01, ..Default::default() }.generate();
//! let solution = solve_multiple(&problem, &MultipleSettings::default())?;
//! assert!(solution.report.termination.is_converged());
//! let truth: Vec<_> = truth.into_iter().map(Some).collect();
//! let accuracy = align_and_compare(&solution.rotations, &truth).unwrap();
//! assert!(accuracy.max_deg < 2.0); // 0.01 rad of noise per edge: errors of a fraction of a degree
//! # Ok::<(), rotavg::Error>(())
//! ```

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
