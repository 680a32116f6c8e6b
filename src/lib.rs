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
//! Every local solver returns a solution with a report (estimate, cost, iterations, why it
//! stopped, wall time); every certifier a [`Certificate`]: a proven lower bound on the global
//! minimum and the gap to it.
//!
//! Conventions (see `paper-notes/conventions.md`): a rotation is a 3x3 matrix with `R^T R = I`
//! and `det R = +1` ([`Rotation`] = `nalgebra::Rotation3<f64>`); `theta(R, S)` is the angle of
//! `R^T S` in `[0, pi]`; chordal distance `||R - S||_F = 2 sqrt(2) sin(theta/2)`; quaternion
//! distance `2 sin(theta/4)`. Every problem minimises `sum_k w_k rho(d_k)` for its
//! [`Objective`] (a [`Metric`] and a [`Loss`]; default chordal L2).
//!
//! # Where to start: one verb, one signature, three problems
//!
//! | verb | single | multiple | conjugate |
//! |---|---|---|---|
//! | data | [`single::SingleProblem`] | [`multiple::MultipleProblem`] | [`conjugate::ConjugateProblem`] |
//! | `solve_*(&problem, &settings)` | [`single::solve_single`] | [`multiple::solve_multiple`] | [`conjugate::solve_conjugate`] |
//! | `relax_*(&problem, &SdpSettings)` | — | [`relax::relax_multiple`] | [`relax::relax_conjugate`] |
//! | `certify_*(&problem, &estimate, &CertifySettings)` | [`certify::certify_single`] | [`certify::certify_multiple`] | [`certify::certify_conjugate`] |
//! | `average_*(&problem, &AverageSettings)` | [`pipeline::average_single`] | [`pipeline::average_multiple`] | [`pipeline::average_conjugate`] |
//!
//! Files: [`io`] (g2o, TORO, 1DSfM, Bundler, hand-eye, JSON; [`io::input`] loads what the
//! command line loads). Reports: [`report`] (the `--json` objects and texts of the command
//! line, as types). Errors are one [`Error`].
//! The README (also compiled as doc tests) shows the command-line tool and longer examples.
//!
//! # Layers
//!
//! Each layer is a folder (or a file) of `src/`, and a module imports only from its own layer
//! or the layers below (checked by `tests/suite/layers.rs`):
//!
//! ```text
//!  bin/rotavg          the command line: parse arguments, print reports
//!  report              typed reports: Serialize = the --json object, Display = the text
//!  io, plot            file formats, input loading, figures
//!  pipeline            average_*: solve -> certify -> adopt an improvement
//!  certify             certify_*: theory, dual certificate, SDP bounds, staircase (verified)
//!  relax               relax_*: the SDP relaxations (Clarabel glue, svec, rounding)
//!  single multiple conjugate   problem data + objective + cost + local solvers (solve_*)
//!  linalg              verified factorisations, Lanczos, block-sparse systems
//!  objective validate deadline   metric x loss; input checks; the local solvers' time limit
//!  so3 termination     rotations, distances, serde; why a solver stopped
//!  error               the one Error enum
//! ```
//!
//! Data flow of every pipeline (one shape for the three problems):
//!
//! ```text
//! file --io--> Problem --solve_*--> Solution --certify_*--> Certification { certificate, improvement }
//!                                       ^                                        |
//!                                       +---- better solution (refined, SDP) ----+
//!                          --> Averaged { solution, certificate, details } --report--> JSON / text
//! ```
//!
//! ```
//! use rotavg::multiple::synthetic::SyntheticGraph;
//! use rotavg::pipeline::{average_multiple, AverageSettings};
//! // A seeded random view graph: 50 nodes, 150 edges, 0.05 rad noise; solve and certify.
//! let (problem, _truth) = SyntheticGraph { num_rotations: 50, num_edges: 150, ..Default::default() }.generate();
//! let estimate = average_multiple(&problem, &AverageSettings::default())?;
//! assert!(estimate.certificate.as_ref().is_some_and(|c| c.is_certified()));
//! assert!(rotavg::so3::angle(&estimate.solution.rotations[0]) < 1e-12); // gauge R_0 = I
//! # Ok::<(), rotavg::Error>(())
//! ```
#![forbid(unsafe_code)]
#![deny(missing_docs)]

pub mod certify;
pub mod conjugate;
mod deadline;
pub mod error;
pub mod io;
pub mod linalg;
pub mod multiple;
pub mod objective;
pub mod pipeline;
#[cfg(feature = "plot")]
pub mod plot;
pub mod progress;
pub mod relax;
pub mod report;
pub mod rig;
pub mod single;
pub mod so3;
pub mod termination;
pub mod validate;
pub mod warning;

pub use certify::{BoundMethod, Certificate, Verdict};
pub use error::{Error, Result};
pub use objective::{Loss, Objective};
pub use so3::{Metric, Rotation};
pub use termination::{SolverReport, Termination};

/// The linear-algebra crate of the public API ([`Rotation`] is `nalgebra::Rotation3<f64>`):
/// use `rotavg::nalgebra` to get the very version rotavg was built with.
pub use nalgebra;

/// The random-number crate of the seeded generators (`so3::random_rotation`,
/// `conjugate::synthetic::random_instance`, ...): `rotavg::rand::SeedableRng` and so on.
pub use rand;

/// The sparse and dense matrix crate of the public API (connection Laplacians, certificate
/// matrices, `svec`), re-exported for the same reason as [`nalgebra`].
pub use faer;

// The BLAS/LAPACK routines of Clarabel's SDP cone (`rotavg-lapack/`): naming the crate links it
// into every binary that uses rotavg, and `relax::clarabel` takes the routines' addresses next
// to its Clarabel call, so that order-sensitive linkers (GNU ld.bfd) load them too.
use rotavg_lapack as _;

/// The README and the docs book: every ```` ```rust ```` block is compiled and run as a doc
/// test (one item per Markdown file; the shell commands run in `tests/suite/docs_examples.rs`).
#[cfg(doctest)]
pub mod doc_markdown {
    #[doc = include_str!("../README.md")]
    pub struct Readme;
    #[doc = include_str!("../docs/introduction.md")]
    pub struct Introduction;
    #[doc = include_str!("../docs/library.md")]
    pub struct Library;
    #[doc = include_str!("../docs/certificates.md")]
    pub struct Certificates;
    #[doc = include_str!("../docs/benchmarks.md")]
    pub struct Benchmarks;
    #[doc = include_str!("../docs/status.md")]
    pub struct Status;
    #[doc = include_str!("../docs/development.md")]
    pub struct Development;
    #[doc = include_str!("../docs/reference/contract.md")]
    pub struct ReferenceContract;
    #[doc = include_str!("../docs/reference/cli.md")]
    pub struct ReferenceCli;
    #[doc = include_str!("../docs/reference/conventions.md")]
    pub struct ReferenceConventions;
    #[doc = include_str!("../docs/guides/sfm-colmap.md")]
    pub struct GuideSfmColmap;
    #[doc = include_str!("../docs/guides/slam-g2o.md")]
    pub struct GuideSlamG2o;
    #[doc = include_str!("../docs/guides/hand-eye.md")]
    pub struct GuideHandEye;
    #[doc = include_str!("../docs/guides/python.md")]
    pub struct GuidePython;
    #[doc = include_str!("../docs/guides/certify-other-tools.md")]
    pub struct GuideCertifyOtherTools;
    #[doc = include_str!("../docs/guides/anisotropic.md")]
    pub struct GuideAnisotropic;
}
