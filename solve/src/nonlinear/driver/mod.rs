//! The driver: runs the loading from the start or a checkpoint to its end,
//! one step at a time, each through the same four stages:
//!
//! 1. Plan: the control of the next step and its size (`policy::controls`);
//! 2. Attempt: Newton from the predicted iterate, with the retries the
//!    remedies allow (`attempt`);
//! 3. Review: Newton's outcome and the checks on the converged state
//!    (`review`, `policy::checks`);
//! 4. Commit (`commit`: the sizers and the endings after a step), or, for
//!    an attempt that was not committed, the action `policy::decide`
//!    chooses (`failed`).
//!
//! Everything the policy remembers between steps is the run's
//! `RunState`, which a checkpoint holds whole.

mod attempt;
mod commit;
mod failed;
mod record;
mod review;
mod setup;

pub use setup::Problem;

use crate::assembly::System;
use crate::nonlinear::checkpoint::{Checkpoint, RunState};
use crate::nonlinear::control::Quantity;
use crate::nonlinear::policy::controls::{self, process_zone, Plan, Zone};
use crate::nonlinear::report::{Observer, RunResult, SolveError};
use crate::spec::solver::{Loading, PathFollowing, SolverSettings};
use review::Verdict;
use setup::{Driver, Outcome};
use std::time::Instant;

/// Runs the loading from the checkpoint's state (or the start) to
/// `loading.u_final` or `loading.fed_stop`; under `solver.path_following`
/// steps may prescribe another quantity of the path than λ.
pub fn run(
    problem: &Problem<'_>,
    loading: &Loading,
    settings: &SolverSettings,
    checkpoint: Option<Checkpoint>,
    observer: &mut dyn Observer,
) -> Result<RunResult, SolveError> {
    let Problem {
        model,
        laws,
        dirichlet,
        ..
    } = *problem;
    if laws.tets.len() != model.tets.len() || laws.interfaces.len() != model.interfaces.len() {
        return Err(SolveError::Model(format!(
            "{} tet laws for {} tets, {} interface laws for {} interface elements",
            laws.tets.len(),
            model.tets.len(),
            laws.interfaces.len(),
            model.interfaces.len()
        )));
    }
    let started = Instant::now();
    let active: Vec<bool> = laws.interfaces.iter().map(|l| l.is_some()).collect();
    let system = System::with_ties(
        model,
        &dirichlet.dofs,
        &dirichlet.ties,
        &dirichlet.load_rates(),
        &active,
    )?;
    let mut driver = Driver::new(*problem, loading, settings, &system, started)?;
    let mut state = match checkpoint {
        Some(cp) => driver.resume(cp)?,
        None => driver.start(),
    };
    driver.begin(&mut state);
    loop {
        if let Some(ending) = state.policy.ended.clone() {
            let mut result = *driver.partial(state);
            result.ending = ending;
            return Ok(result);
        }
        if driver.done(&state) {
            return Ok(*driver.partial(state));
        }
        if let Some(max_steps) = loading.max_steps.filter(|&m| state.path.rows.len() >= m) {
            return Err(SolveError::StepLimit {
                max_steps,
                u_imposed: state.path.lambda,
                partial: driver.partial(state),
            });
        }
        state = match driver.step(state, observer)? {
            Outcome::Continue(state) => state,
            Outcome::End(ending, mut state) => {
                state.policy.ended = Some(ending);
                state
            }
        };
    }
}

impl Driver<'_> {
    /// One step: plan, attempt, review, then commit or the policy's
    /// decision.
    fn step(
        &mut self,
        mut state: RunState,
        observer: &mut dyn Observer,
    ) -> Result<Outcome, SolveError> {
        let zone = self.process_zone(&state);
        let plan = self.plan(&mut state, zone.as_ref());
        let zone = zone.as_ref().map(|(quantity, _)| quantity);
        let mut tried = self.attempt(&mut state, &plan, zone, observer);
        match self.review(&mut state, &plan, &mut tried)? {
            Verdict::Accepted(review) => Ok(self.commit(state, &plan, tried, review, observer)),
            Verdict::Failed(failure) => self.failed(state, &plan, tried, failure, observer),
        }
    }

    /// The next step's plan (`policy::controls::next`).
    fn plan(&self, state: &mut RunState, zone: Option<&(Quantity, f64)>) -> Plan {
        let view = self.view(&state.path);
        let zone = zone.map(|(quantity, moved)| Zone {
            value: quantity.value(&state.path.u),
            moved: *moved,
        });
        controls::next(&mut state.policy.steps, &view, zone, &self.rules())
    }

    /// The process zone of the last step, under `path_following:
    /// process_zone`.
    fn process_zone(&self, state: &RunState) -> Option<(Quantity, f64)> {
        if self.settings.path_following != PathFollowing::ProcessZone {
            return None;
        }
        process_zone::quantity(
            self.problem.model,
            self.problem.laws,
            &state.path.states,
            &state.path.last_increment,
            self.ws.system.dofs(),
            self.problem.dirichlet,
        )
    }

    /// The end of the loading: λ at `u_final`, or the FED at `fed_stop`.
    fn done(&self, state: &RunState) -> bool {
        let loading = self.loading;
        let path = &state.path;
        let fed_done = loading
            .fed_stop
            .is_some_and(|s| path.rows.last().is_some_and(|r| r.fed >= s * (1.0 - 1e-9)));
        path.lambda >= loading.u_final - 1e-9 * loading.u_final || fed_done
    }
}
