//! The `ribbar` pipeline: CLI types, scene specs and overrides, the
//! content-addressed store, the four stages, studies and post-processing.

pub mod app;
pub mod bench;
mod bench_petsc;
pub mod bench_series;
pub mod child;
pub mod cli;
pub mod commands;
mod measure;
pub mod outputs;
pub mod overrides;
pub mod post;
pub mod progress;
pub mod scene;
pub mod stage;
pub mod store;
pub mod study;
pub mod study_results;
pub mod study_run;
mod study_sensitivity;
