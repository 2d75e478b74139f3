//! The mesh crate's integration tests on real gmsh meshes, a module per
//! file (each says what it covers).

mod common;

mod bad_input;
mod bar_core;
mod diagnosis;
mod envelope;
mod read_msh;
mod ribbed;
mod symmetry;
mod topology;
mod unbonded;
