//! Quasi-static nonlinear solution (SPEC §6) for any proportional
//! Dirichlet loading ([`Dirichlet`]: value = base + λ·rate) with a
//! [`Measurement`] of force and relative displacement per converged step:
//! adaptive load stepping (`stepping`), Newton iterations with line search
//! and stagnation handling (`newton`), the linear correction of each
//! iteration (`correction`), checkpoints and resume (`checkpoint`).
//! `crate::problems::pullout` builds the pull-out test's conditions.

mod checkpoint;
mod control;
mod correction;
mod failure;
mod newton;
mod problem;
mod report;
mod stepping;
mod summary;
mod workspace;

pub use checkpoint::{
    Checkpoint, CheckpointError, HierarchyWear, ObserverRecord, PreconditionerState,
};
pub use control::ControlMode;
pub use failure::{RegimeChanges, StepFailure};
pub use problem::{Dirichlet, Measurement};
pub use report::{
    CommittedView, CurveRow, Cutback, Ending, Observer, RunResult, Silent, SolveError, StepReport,
    Summary, WallTimes,
};
pub use stepping::{run, Problem, CRACKED};
