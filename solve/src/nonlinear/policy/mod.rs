//! The stepping policy: what a run remembers across steps
//! ([`PolicyState`]), what it reads of the converged path ([`PathView`]),
//! and the named pieces that decide each step (docs/architecture.md, "The
//! stepping policy"):
//!
//! - `controls`: what a step prescribes (displacement, free end,
//!   dissipation, process zone), when a control takes over, and the plan;
//! - `checks`: the verdicts on a converged attempt (load jump, IMPL-EX
//!   error, curve bend, energy);
//! - `sizers`: the next step after a committed one;
//! - `remedies`: the retries within a step (explicit tets, interface holds)
//!   and their budgets;
//! - `endings`: the ways a run ends without a continuation;
//! - `decide`: what follows an attempt that was not committed.
//!
//! Every function here is a pure function of plain data, so each rule is
//! tested on hand-built histories; the driver (`crate::nonlinear::driver`)
//! does the work they decide.

pub(crate) mod checks;
pub(crate) mod controls;
mod decide;
pub(crate) mod endings;
pub(crate) mod remedies;
pub(crate) mod sizers;

mod state;
#[cfg(test)]
pub(crate) mod test_support;

pub(crate) use decide::{counts_as_cutback, decide, keeps_rewind_point, Action, StallEndings};
pub use state::{ConvergedPath, PathView, PolicyState, RewindPoint, Rules, Steps, UNLOADED};
