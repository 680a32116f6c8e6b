//! The integration tests, one test binary: each file here was its own `tests/*.rs` target and is
//! now a module (compiling and linking 43 binaries against rotavg and its dependencies took most
//! of `cargo test`'s build time). Run one file's tests with a name filter, e.g.
//! `cargo test --release --test suite cli_json_contract::` (test names are `module::test`).
//!
//! Modules that run the `rotavg` command line need the `cli` feature (the binary is built only
//! with it); those that write COLMAP databases (rusqlite) or draw figures need `colmap` / `plot`.
//! The opt-in soundness campaign stays a target of its own (`tests/soundness_campaign.rs`).

mod common;

#[cfg(feature = "cli")]
mod anisotropic;
mod block_comparison;
mod branch_and_bound;
mod budget_monotone;
mod certify_families;
#[cfg(all(feature = "cli", feature = "colmap"))]
mod certify_formats;
mod certify_layers;
mod certify_loss;
mod certify_multiple;
mod certify_randomized;
mod clarabel_sdp;
#[cfg(feature = "cli")]
mod cli_info;
#[cfg(feature = "cli")]
mod cli_json_contract;
#[cfg(feature = "cli")]
mod cli_multiple;
#[cfg(feature = "cli")]
mod cli_single;
#[cfg(feature = "cli")]
mod cli_text_width;
#[cfg(all(feature = "cli", feature = "colmap"))]
mod colmap;
#[cfg(all(feature = "cli", feature = "colmap"))]
mod colmap_scene;
mod conjugate;
#[cfg(feature = "cli")]
mod conjugate_cli;
mod conjugate_io;
mod conjugate_sdp;
mod conjugate_simultaneous;
mod conv_dual;
#[cfg(feature = "cli")]
mod data_as_given;
mod deadline;
#[cfg(feature = "cli")]
mod docs_examples;
#[cfg(feature = "cli")]
mod error_words;
mod estimates_in_so3;
mod example_data;
mod fuzz_regressions;
mod gravity;
mod gravity_cli;
mod gravity_soft;
#[cfg(feature = "cli")]
mod handeye_streams;
mod io_formats;
mod io_shared_data;
#[cfg(feature = "cli")]
mod io_streaming;
mod layers;
mod loss_auto;
mod multiple_solvers;
mod nearest_rotations;
mod pipeline_multiple;
#[cfg(all(feature = "cli", feature = "plot"))]
mod plot;
mod properties_conjugate;
mod properties_multiple;
mod properties_single;
mod properties_so3;
mod readme_examples;
mod relax_multiple;
mod rig_cli;
mod rig_gravity;
mod rig_information;
mod rig_robust_scale;
mod rig_sensors;
#[cfg(feature = "cli")]
mod robust_inliers;
mod scalar_weights;
mod single;
mod soundness_multiple;
mod soundness_rig;
mod spectrum;
mod tolerance_invariance;
mod tolerance_spectrum;
mod two_stage;
mod warnings_json;
