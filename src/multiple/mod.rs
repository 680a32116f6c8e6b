//! Multiple rotation averaging: absolute rotations `R_0..R_{n-1}` from relative measurements
//! `R_ij` on a view graph, with the convention **`R_ij R_i = R_j`** (contract section 1).
//!
//! Chordal L2 cost `f(R) = sum_(i,j) w_ij ||R_j - R_ij R_i||_F^2` (`paper-notes/multiple.md`,
//! `[M1]`). Gauge: solutions are defined up to `R_i -> R_i G`; outputs fix `R_0 = I`.
//!
//! - Data: [`MultipleProblem::new`] from [`Edge`]s; files through [`crate::io`]; seeded
//!   instances from [`synthetic::SyntheticGraph`].
//! - Local solvers: [`solve_multiple`] with [`MultipleSettings`] for the problem's objective
//!   (chordal Newton-LM, geodesic, L1 / Huber / Cauchy IRLS; [`Initialisation`] spanning tree
//!   or spectral, see [`initialise`]).
//! - Certificate: [`crate::certify::certify_multiple`]; whole pipeline:
//!   [`crate::pipeline::average_multiple`].
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
pub mod anisotropic;
pub mod chordal;
pub mod geodesic;
pub mod gravity;
pub mod init;
pub mod laplacian;
pub mod problem;
pub mod robust;
pub mod robust_scale;
pub mod solve;
pub mod stats;
pub mod synthetic;
pub(crate) mod two_stage;
pub(crate) mod union_find;

pub use chordal::chordal_gradient;
pub use init::{initialise, spanning_tree, spectral};
pub use problem::{Edge, MultipleProblem, fix_gauge};
pub use robust::{objective_cost_gradient, objective_terms};
pub use solve::{
    Initialisation, LinearAlgebraCounts, MultipleSettings, MultipleSolution, solve_multiple,
};
