//! Material laws, element kernels, assembly and the nonlinear pull-out solver.

pub mod laws;
pub mod material_point;
pub mod assembly;
pub mod element;
pub mod fields;
pub mod interface_element;
pub mod linear;
pub mod pullout;
pub mod spec;
