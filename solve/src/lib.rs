//! Material laws, element kernels, assembly and the nonlinear pull-out solver.
//!
//! Where things are: a law in `laws/` (one file each, dispatched by
//! `laws::AnyBulkLaw` / `AnyInterfaceLaw`); an element kernel in
//! `elements/`; sparse linear algebra in `linalg/`; the Newton solver and
//! path-following in `nonlinear/`, the concrete's gradient-enhanced
//! averaging in `nonlocal`; the problems built on them (pull-out,
//! linear perfect bond, material point) in `problems/`; spec sections in
//! `spec/`; what a run writes in `curve`, `fields` and `energy`.

pub mod assembly;
pub mod curve;
pub mod elements;
pub mod energy;
pub mod fields;
pub mod laws;
pub mod linalg;
pub mod nonlinear;
pub mod nonlocal;
pub mod problems;
pub mod spec;
