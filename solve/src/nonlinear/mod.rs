//! Quasi-static nonlinear solution (SPEC §6) for any proportional
//! Dirichlet loading ([`Dirichlet`]: value = base + λ·rate) with a
//! [`Measurement`] of force and relative displacement per converged step.
//!
//! - `driver`: the loop over the steps (plan, attempt, review, commit);
//! - `policy`: the stepping policy's state and its named rules (controls,
//!   checks, sizers, remedies, endings, `decide`), pure functions of plain
//!   data (docs/architecture.md, "The stepping policy");
//! - `newton` (iterations with line search and stagnation handling),
//!   `correction` (the linear solve of an iteration), `control` (the
//!   constraints of indirect control), `settle` (the damage passes);
//! - `checkpoint` (resume), `report` and `summary` (what a run returns).
//!
//! `crate::problems::pullout` builds the pull-out test's conditions.

mod checkpoint;
mod control;
mod correction;
mod driver;
mod failure;
mod newton;
pub(crate) mod policy;
mod problem;
mod report;
mod settle;
mod summary;
mod workspace;

pub use checkpoint::{
    Checkpoint, CheckpointError, HierarchyWear, ObserverRecord, PreconditionerState, RunState,
};
pub use control::ControlMode;
pub use driver::{run, Problem};
pub use failure::{NotConverged, Refusal, RegimeChanges, StepFailure};
pub use policy::endings::CRACKED;
pub use policy::{ConvergedPath, PolicyState, RewindPoint, Steps};
pub use problem::{Dirichlet, Measurement};
pub use report::{
    CommittedView, CurveRow, Cutback, Ending, Observer, RunResult, Silent, SolveError, StepReport,
    Summary, WallTimes,
};
pub use summary::CheckOff;
