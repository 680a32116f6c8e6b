//! Readers and writers for the file formats: JSON (SPEC section 5), g2o (3-D and 2-D), TORO
//! `EDGE3`, 1DSfM `EGs.txt`, Bundler ground truth, hand-eye pose files. Each reader documents,
//! where it reads, how the format maps onto this crate's conventions.

pub mod detect;
pub mod g2o;
pub mod handeye;
pub mod json;
pub mod sfm;
pub mod single_json;
