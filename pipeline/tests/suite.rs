//! The pipeline's integration tests, a module per file (each says what it
//! covers). Real gmsh, real files, the `ribbar` binary.

mod common;

mod bench_linear;
mod bench_series;
mod bond_law;
mod cli;
mod cluster;
mod faults;
mod post_convergence;
mod post_plots;
mod post_summary;
mod post_tables;
mod post_uncertainty;
mod reference;
mod sensitivity;
mod stress;
mod study;
mod study_sampled;
