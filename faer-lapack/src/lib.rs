//! placeholder; see README
