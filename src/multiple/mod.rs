//! Multiple rotation averaging: absolute rotations `R_0..R_{n-1}` from relative measurements
//! `R_ij` on a view graph, with the convention **`R_ij R_i = R_j`** (SPEC section 1).
//!
//! Chordal L2 cost `f(R) = sum_(i,j) w_ij ||R_j - R_ij R_i||_F^2` (`paper-notes/multiple.md`,
//! `[M1]`). Gauge: solutions are defined up to `R_i -> R_i G`; outputs fix `R_0 = I`.

pub mod accuracy;
pub mod laplacian;
pub mod problem;
pub mod stats;
pub mod synthetic;

pub use problem::{Edge, MultipleProblem, fix_gauge};
