//! Material laws, element kernels, assembly and the nonlinear pull-out solver.

pub mod amg;
pub mod assembly;
pub mod curve;
pub mod element;
pub mod energy;
pub mod fields;
pub mod interface_element;
pub mod laws;
pub mod linear;
pub mod linear_elastic;
pub mod material_point;
pub mod nonlinear;
pub mod problems;
pub mod spec;
