//! Meshing with gmsh, reading `.msh` 4.1, duplicating interface nodes and
//! building the solver's [`Model`].

pub mod model;
pub use model::*;
