//! Single rotation averaging: the L1 and L2 means `argmin_R sum_i w_i d(R_i, R)^p` of many
//! estimates `R_i` of one rotation, under the angle (geodesic), chordal and quaternion
//! distances (contract sections 1 and 2; `paper-notes/single.md`, labels `[S1]`..`[S8]`).
//!
//! The problem ([`SingleProblem`]) carries its [`Objective`](crate::objective::Objective)
//! (metric and loss); [`solve_single`] picks the method:
//!
//! | metric     | loss | method                                                        | certificate ([`crate::certify::certify_single`]) |
//! |------------|------|---------------------------------------------------------------|-------------|
//! | chordal    | L2 | closed form: det-corrected SVD projection of `sum w_i R_i` `[S1]` | always      |
//! | quaternion | L2 | sign-aligned normalised quaternion sum `[S2]`                 | when all samples lie within pi/2 of the estimate (else a proven bound) |
//! | geodesic   | L2 | Karcher mean, from the chordal L2 mean `[S3]`                 | pi/2 ball `[S4]` |
//! | geodesic   | L1 | Weiszfeld on SO(3) with the sample case handled `[S5]`        | pi/2 ball `[S4]` |
//! | chordal    | L1 | IRLS / majorise-minimise on SO(3) from the projected Euclidean geometric median `[S6]` | Euclidean bound `[S7]`, then branch and bound |
//! | quaternion | L1 | sign-aligned Weiszfeld on unit quaternions `[S10]`                | branch and bound `[B1]`-`[B6]` |
//!
//! ```
//! use rotavg::single::{solve_single, SingleProblem, SingleSettings};
//! use rotavg::objective::{Loss, Objective};
//! use rotavg::so3::{exp, perturb_gaussian, Metric};
//! use rand::SeedableRng;
//!
//! let mut rng = rand::rngs::StdRng::seed_from_u64(1);
//! let truth = exp(&nalgebra::Vector3::new(0.3, -0.1, 0.7));
//! let samples: Vec<_> = (0..100).map(|_| perturb_gaussian(&truth, 0.05, &mut rng)).collect();
//! let problem = SingleProblem::new(samples, None)?
//!     .with_objective(Objective::new(Metric::Geodesic, Loss::L2))?;
//! let solution = solve_single(&problem, &SingleSettings::default())?;
//! assert!(solution.report.termination.is_converged());
//! assert!(rotavg::so3::angle_between(&solution.estimate, &truth) < 0.05);
//! println!("{solution}");
//! # Ok::<(), rotavg::Error>(())
//! ```

pub mod closed_form;
pub mod iterative;
pub mod problem;
pub mod solve;

pub use problem::SingleProblem;
pub use solve::{SingleSettings, SingleSolution, solve_single};
