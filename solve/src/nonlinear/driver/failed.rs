//! An attempt that was not committed: the rewind point is kept if the
//! policy says so, `policy::decide` chooses the action, and the driver
//! carries it out: a new size or control, a rewind, a restart with holds,
//! an ending, or the stall that stops the run.

use super::attempt::Tried;
use super::setup::{energy_start, Driver, Outcome};
use crate::assembly::States;
use crate::nonlinear::checkpoint::RunState;
use crate::nonlinear::control::ControlMode;
use crate::nonlinear::failure::StepFailure;
use crate::nonlinear::policy::controls::Plan;
use crate::nonlinear::policy::endings::{self, Specimen, Stall, CRACKED};
use crate::nonlinear::policy::{
    counts_as_cutback, decide, keeps_rewind_point, Action, PathView, PolicyState, RewindPoint,
    StallEndings,
};
use crate::nonlinear::report::{CommittedView, Cutback, Observer, SolveError};
use crate::nonlinear::summary::{Ending, Summary};

impl Driver<'_> {
    /// Carries out what the policy decides after `failure` of the attempt
    /// `tried` at the step `plan`.
    pub(crate) fn failed(
        &mut self,
        mut state: RunState,
        plan: &Plan,
        tried: Tried,
        failure: StepFailure,
        observer: &mut dyn Observer,
    ) -> Result<Outcome, SolveError> {
        let rules = self.rules();
        if keeps_rewind_point(&state.policy, &failure, &rules) {
            state.policy.rewind = Some(Box::new(RewindPoint {
                path: state.path.clone(),
                steps: state.policy.steps,
                summary: state.summary.clone(),
            }));
        }
        if counts_as_cutback(&failure) {
            state.summary.cutbacks += 1;
        }
        let view = self.view(&state.path);
        let cracked = || self.cracked_through(&state.path.states);
        let broken = || self.broken(&state.path.states);
        let evidence = StallEvidence {
            view: &view,
            stall: Stall {
                plan,
                lambda: tried.lambda,
                failure: &failure,
                held_from_start: state.policy.holds_from_step == Some(1),
                may_hold_from_start: state.policy.may_hold_from_start(self.settings),
            },
            specimen: self.specimen(&cracked, &broken),
        };
        let action = decide(&state.policy, &failure, plan, &view, &rules, &evidence);
        self.ws.trial.clone_from(&state.path.states);
        let (next_mode, next_step_size) = action.next_attempt(plan, self.loading.cutback);
        observer.cutback(&Cutback {
            step: state.path.rows.len() + 1,
            u_imposed: tried.lambda,
            failed_mode: plan.mode,
            failed_step_size: plan.size,
            next_mode,
            next_step_size,
            reason: failure.clone(),
            residual_history: tried.attempt.history.clone(),
        });
        let steps = &mut state.policy.steps;
        match action {
            Action::Displacement { size } => {
                steps.mode = ControlMode::Displacement;
                steps.zone_paused = true;
                steps.next = size;
            }
            Action::ForCurve { size } => steps.curve_limit = size,
            Action::HandOver { energy } => {
                steps.mode = ControlMode::Energy;
                steps.next = energy;
            }
            Action::CutBack { size } => {
                if plan.mode == steps.mode {
                    steps.next = size;
                }
            }
            Action::End(ending) => return Ok(Outcome::End(ending, state)),
            Action::Rewind => {
                let back = *state.policy.rewind.take().expect("a rewind point");
                return Ok(Outcome::Continue(self.go_back(back, state, observer)));
            }
            Action::RestartWithHolds => {
                let start = self.initial_state();
                let back = RewindPoint {
                    path: start.path,
                    steps: start.policy.steps,
                    summary: start.summary,
                };
                // As at the start: the kept preconditioner of the stalled
                // state would steer the inexact Newton iterates elsewhere.
                self.ws.lin.refactor = true;
                return Ok(Outcome::Continue(self.go_back(back, state, observer)));
            }
            Action::Stall => {
                return Err(SolveError::Stalled {
                    step: state.path.rows.len() + 1,
                    u_imposed: tried.lambda,
                    step_size: plan.size,
                    step_unit: plan.mode.step_unit(),
                    residual_history: tried.attempt.history,
                    cause: Box::new(failure),
                    partial: self.partial(state),
                })
            }
        }
        Ok(Outcome::Continue(state))
    }

    /// The run's state at `back`, from where every step may hold interface
    /// points, after the stall of `stalled`. Holding them in the stalled
    /// state itself does not help: its last steps ended at the residual
    /// tolerance, so even a nanometre step starts out of balance. The
    /// effort spent since is kept in the counters.
    fn go_back(
        &mut self,
        back: RewindPoint,
        stalled: RunState,
        observer: &mut dyn Observer,
    ) -> RunState {
        let RewindPoint {
            path,
            steps,
            mut summary,
        } = back;
        keep_effort(&mut summary, &stalled.summary);
        let state = RunState {
            policy: PolicyState {
                steps,
                holds_from_step: Some(path.rows.len() + 1),
                rewind: None,
                ended: None,
            },
            path,
            summary,
        };
        self.ws.trial.clone_from(&state.path.states);
        if let Ok(tracker) = &mut self.energy {
            let mut rows = tracker.rows().to_vec();
            rows.truncate(state.path.rows.len());
            if let Err(e) = tracker.rewind(energy_start(&state.path, rows)) {
                self.energy = Err(format!("going back to step {}: {e}", state.path.rows.len()));
            }
        }
        let cp = || self.checkpoint(&state);
        observer.rewound(
            stalled.path.rows.len() + 1,
            &CommittedView {
                model: self.problem.model,
                laws: self.problem.laws,
                checkpoint: &cp,
                u: &state.path.u,
                states: &state.path.states,
            },
        );
        state
    }

    /// What the endings read of the specimen, its counts taken from the
    /// closures when a rule asks.
    pub(crate) fn specimen<'c>(
        &self,
        cracked_through: &'c dyn Fn() -> usize,
        broken: &'c dyn Fn() -> usize,
    ) -> Specimen<'c> {
        Specimen {
            yield_force: self.problem.yield_force,
            concrete_tets: self.concrete_tets,
            cracked_through,
            broken,
        }
    }

    /// Concrete tets of `states` with damage of at least [`CRACKED`] in
    /// bands from the bar to the cube's faces.
    pub(crate) fn cracked_through(&self, states: &States) -> usize {
        let cracked: Vec<bool> = states.bulk.iter().map(|s| s.damage >= CRACKED).collect();
        self.problem.model.cover_crossing_tets(&cracked)
    }

    /// Concrete tets of `states` with D > 0.99 (a crack through the cube
    /// shows as a layer of them).
    pub(crate) fn broken(&self, states: &States) -> usize {
        states
            .bulk
            .iter()
            .zip(&self.problem.model.tet_region)
            .filter(|(s, r)| **r == mesh::Region::Concrete && s.damage > 0.99)
            .count()
    }
}

/// The effort counters of `now` carried into a rewound summary: the work
/// spent on the discarded steps stays counted.
fn keep_effort(then: &mut Summary, now: &Summary) {
    then.total_iterations = now.total_iterations;
    then.cutbacks = now.cutbacks;
    then.explicit_retries = now.explicit_retries;
    then.damage_passes = now.damage_passes;
    then.held_interface_points = now.held_interface_points;
    then.dissipation_rejections = now.dissipation_rejections;
    then.impl_ex_rejections = now.impl_ex_rejections;
    then.curve_rejections = now.curve_rejections;
    then.explicit_tets = now.explicit_tets;
}

/// The stall endings of one failed attempt.
struct StallEvidence<'a> {
    view: &'a PathView<'a>,
    stall: Stall<'a>,
    specimen: Specimen<'a>,
}

impl StallEndings for StallEvidence<'_> {
    fn limit_load(&self) -> Option<Ending> {
        endings::limit_load(self.view.rows, self.stall.failure, &self.specimen)
    }

    fn brittle_failure(&self) -> Option<Ending> {
        endings::brittle_failure(self.view, &self.stall, &self.specimen)
    }
}
