//! The `ribbar` pipeline: CLI types, scene specs and overrides, the
//! content-addressed store, the four stages, studies and post-processing.

pub mod app;
pub mod bench;
mod bench_petsc;
pub mod bench_series;
pub mod child;
mod clean;
pub mod cli;
pub mod commands;
pub mod estimate;
pub mod export;
pub mod inputs;
mod measure;
pub mod outputs;
pub mod overrides;
mod plausibility;
pub mod post;
pub mod progress;
pub mod reference;
pub mod scene;
pub mod schema;
pub mod stage;
pub mod store;
pub mod store_lock;
pub mod study;
pub mod study_outcome;
pub mod study_results;
pub mod study_run;
mod study_sensitivity;
pub mod termination;
mod verify;
