//! The `ribbar` pipeline: CLI types, scene specs and overrides, the
//! content-addressed store, the four stages, studies and post-processing.

pub mod app;
pub mod bench;
mod bench_petsc;
pub mod bench_series;
pub mod child;
pub mod cli;
pub mod commands;
pub mod estimate;
pub mod export;
mod measure;
pub mod outputs;
pub mod overrides;
pub mod post;
pub mod progress;
pub mod reference;
pub mod scene;
pub mod schema;
pub mod stage;
pub mod store;
pub mod store_lock;
pub mod study;
pub mod study_run;
pub mod termination;
