//! Rigs of any number of sensors (`paper-notes/conjugate.md` `[H19]`; contract section 5's rig
//! convention): frames `F_f` and sensors `S_s` (`sensor_from_rig`, known or unknown), images
//! `X_a = S_{s_a} F_{f_a}`, and relative rotations between any two images, as COLMAP's rig
//! configurations produce.
//!
//! * [`RigProblem`]: the validated problem, its chordal cost `J(F, S)`, the frames' view graph
//!   at fixed sensors and the images' view graph.
//! * [`solve_rig`]: the local solver (from its start, joint Gauss-Newton steps in the frames
//!   and sensors, by preconditioned conjugate gradients or the frames' sparse Cholesky; with
//!   gravity priors, or
//!   where those stall, frames by the sparse chordal Newton-LM and sensors by a small dense
//!   Levenberg-Marquardt, alternated).
//! * The certificate is [`crate::certify::certify_rig`], the pipeline
//!   [`crate::pipeline::average_rig`].
//! * [`RigScene`]: seeded rigs with planted frames and sensors.
//!
//! The two-sensor problem whose sensors each see their own view graph over the same frames
//! (with its coupled certificates) is [`crate::pipeline::simultaneous`].

mod gravity;
mod joint;
mod problem;
mod robust;
mod solve;
pub(crate) use robust::solve_rig_robust_given;
pub(crate) use solve::polish_passes;
mod start;
mod synthetic;
mod world;

pub use gravity::FrameGravity;
pub use joint::{JOINT_CG_ITERATIONS, JOINT_DIRECT_VALUES, JOINT_MAX_STEPS, JOINT_TOLERANCE};
pub use problem::{Image, RigProblem, Sensor};
pub use robust::{
    FIRST_STAGE_REWEIGHTS, REWEIGHT_PASSES, REWEIGHT_TOLERANCE, RigRobust, RobustRig,
    residual_angles, rig_data_scale, solve_rig_robust, solve_rig_robust_from,
};
pub(crate) use solve::solve_rig_judged;
pub use solve::{
    MAX_ESTIMATED_SENSORS, RIG_DECREASE_TOLERANCE, RigSettings, RigSolution, solve_rig,
    solve_rig_from,
};
pub use synthetic::{RigScene, RigTruth};
pub use world::WorldRig;
