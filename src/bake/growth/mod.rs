//! The growth generator (`--generator growth`).

pub mod decimate;
pub mod seed;
pub mod svg;
pub mod umbra;
