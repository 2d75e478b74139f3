//! Material laws, element kernels, assembly and the nonlinear pull-out solver.

pub mod laws;
