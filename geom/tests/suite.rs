//! The geometry crate's integration tests, a module per file (each says
//! what it covers).

mod common;

mod shipped_specs;
mod sweep;
mod symmetry;
