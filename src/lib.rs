//! # rotavg — certifiably optimal rotation averaging
//!
//! Three problems (Hartley, Trumpf, Dai & Li, "Rotation Averaging", IJCV 2013):
//!
//! 1. **Single** rotation averaging ([`single`]): L1/L2 means of many estimates of one rotation
//!    under the angle (geodesic), chordal and quaternion distances.
//! 2. **Multiple** rotation averaging ([`multiple`]): absolute rotations `R_1..R_n` from relative
//!    measurements `R_ij` on a view graph, with `R_ij R_i = R_j`.
//! 3. **Conjugate** rotation averaging (hand-eye): `S` with `R_i ~ S^-1 L_i S`.
//!
//! Every solver returns a report (estimate, cost, iterations, why it stopped, wall time) and a
//! [`Certificate`]: a proven lower bound on the global minimum and the gap to it.
//!
//! Conventions (see `paper-notes/conventions.md`): a rotation is a 3x3 matrix with `R^T R = I`
//! and `det R = +1` ([`Rotation`] = `nalgebra::Rotation3<f64>`); `theta(R, S)` is the angle of
//! `R^T S` in `[0, pi]`; chordal distance `||R - S||_F = 2 sqrt(2) sin(theta/2)`; quaternion
//! distance `2 sin(theta/4)`.
//!
//! # Where to start
//!
//! | problem | validated data | local solve | certify | whole pipeline |
//! |---|---|---|---|---|
//! | single | [`single::SingleProblem::new`] | [`single::average_single`] | [`single::certify_single`] | [`single::average_single`] |
//! | multiple | [`multiple::MultipleProblem::new`] | [`multiple::solve_multiple`] | [`certify::certify_multiple`], [`multiple::certify_multiple_estimate`] | [`multiple::average_multiple`] |
//! | conjugate | [`conjugate::ConjugateProblem::new`] | [`conjugate::solve_conjugate`] | [`conjugate::certify_conjugate`] | [`conjugate::average_conjugate`] |
//!
//! SDP relaxations: [`relax::relax_multiple`], [`conjugate::relax_conjugate`]. Files:
//! [`io`] (g2o, TORO, 1DSfM, Bundler, hand-eye, JSON). SO(3) tools: [`so3`]. Results carry a
//! [`SolverReport`] (with its [`Termination`]) and a [`Certificate`]; errors are one [`Error`].
//! The README (also compiled as doc tests) shows the command-line tool and longer examples.
//!
//! ```
//! use rotavg::multiple::synthetic::SyntheticGraph;
//! use rotavg::multiple::{average_multiple, AverageMultipleSettings};
//! // A seeded random view graph: 50 nodes, 150 edges, 0.05 rad noise; solve and certify.
//! let (problem, _truth) = SyntheticGraph { num_rotations: 50, num_edges: 150, ..Default::default() }.generate();
//! let estimate = average_multiple(&problem, &AverageMultipleSettings::default())?;
//! assert!(estimate.certificate.as_ref().is_some_and(|c| c.is_certified()));
//! assert!(rotavg::so3::angle(&estimate.solution.rotations[0]) < 1e-12); // gauge R_0 = I
//! # Ok::<(), rotavg::Error>(())
//! ```
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod certificate;
pub mod certify;
pub mod conjugate;
pub mod error;
pub mod io;
pub mod multiple;
pub mod plot;
pub mod relax;
pub mod report;
pub mod serde_rot;
pub mod single;
pub mod so3;

pub use certificate::{BoundMethod, Certificate, Verdict};
pub use error::{Error, Result};
pub use report::{SolverReport, Termination};
pub use so3::{Metric, Rotation};

/// The README's code blocks are compiled and run as doc tests.
#[doc = include_str!("../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;
