//! The commit of an accepted attempt: the path's new converged state, the
//! curve row, the sizers' next step (`policy::sizers`), the report to the
//! observer, and the endings that a committed step can reach
//! (`policy::endings::after_step`).

use super::attempt::Tried;
use super::review::Review;
use super::setup::{Driver, Outcome};
use crate::curve::CurveRow;
use crate::nonlinear::checkpoint::RunState;
use crate::nonlinear::control::{generalised_load, ControlMode};
use crate::nonlinear::policy::controls::Plan;
use crate::nonlinear::policy::endings::{self, StepChanges};
use crate::nonlinear::policy::sizers::{self, Committed};
use crate::nonlinear::report::{CommittedView, Observer, StepReport};

impl Driver<'_> {
    /// Makes the accepted attempt the path's new state, sizes the next
    /// step, reports the step, and ends the run if the step ends it.
    pub(crate) fn commit(
        &mut self,
        mut state: RunState,
        plan: &Plan,
        tried: Tried,
        review: Review,
        observer: &mut dyn Observer,
    ) -> Outcome {
        let Tried {
            attempt, u, lambda, ..
        } = tried;
        let path = &mut state.path;
        state.summary.force_only_steps += usize::from(attempt.force_only);
        path.last_increment.clear();
        path.last_increment
            .extend(u.iter().zip(&path.u).map(|(a, b)| a - b));
        // The planned size itself under displacement control: the sum and
        // difference of λ values would round it.
        path.last_lambda_increment = match plan.mode {
            ControlMode::Displacement => plan.size,
            _ => lambda - path.lambda,
        };
        let load = generalised_load(&self.rates, &self.ws.f_int);
        path.last_load_increment = load - path.load;
        path.load = load;
        state.policy.steps.zone_paused = false;
        path.u = u;
        std::mem::swap(&mut path.states, &mut self.ws.trial);
        let changes = StepChanges {
            steel_yielding: review.changes.steel_yield > 0,
            damaging_tets: review.changes.concrete_damage,
        };
        if let Ok(tracker) = &mut self.energy {
            tracker.accept();
        }
        path.lambda = lambda;
        let (force, fed, bond) = review.measured;
        let row = CurveRow {
            step: path.rows.len() + 1,
            u_imposed: path.lambda,
            force,
            fed,
            bond_stress: bond,
            iterations: attempt.iterations,
            impl_ex_error: review.impl_ex_residual,
        };
        path.rows.push(row);
        let summary = &mut state.summary;
        summary.steps = path.rows.len();
        if bond > summary.peak_bond_stress || path.rows.len() == 1 {
            summary.peak_bond_stress = bond;
            summary.fed_at_peak = fed;
        }
        summary.final_fed = fed;
        self.size_next(&mut state, plan, &attempt, &review);
        let view = self.view(&state.path);
        let cracked = || self.cracked_through(&state.path.states);
        let broken = || self.broken(&state.path.states);
        let specimen = self.specimen(&cracked, &broken);
        let ended = endings::after_step(&view, changes, &specimen);
        state.policy.ended = ended;
        self.finish(&mut state);
        let cp = || self.checkpoint(&state);
        let view = CommittedView {
            model: self.problem.model,
            laws: self.problem.laws,
            checkpoint: &cp,
            u: &state.path.u,
            states: &state.path.states,
        };
        observer.step_converged(
            &StepReport {
                row,
                mode: plan.mode,
                step_size: plan.size,
                times: tried.wall,
                residual_history: attempt.history,
                force_only: attempt.force_only,
                impl_ex_residual: review.impl_ex_residual,
            },
            &view,
        );
        self.ws.trial.clone_from(&state.path.states);
        match state.policy.ended.clone() {
            Some(ending) => Outcome::End(ending, state),
            None => Outcome::Continue(state),
        }
    }

    /// The sizers' next step after the committed step `plan` (the path
    /// already holds it), and what it leaves in the summary.
    fn size_next(
        &mut self,
        state: &mut RunState,
        plan: &Plan,
        attempt: &crate::nonlinear::newton::Attempt,
        review: &Review,
    ) {
        let step = Committed {
            iterations: attempt.iterations,
            force_only: attempt.force_only,
            explicit_interface: self.explicit_interface,
            curve: review.curve,
            impl_ex_error: review.impl_ex_residual,
        };
        let view = self.view(&state.path);
        let policy = &mut state.policy;
        if sizers::after_commit(&mut policy.steps, plan, &step, &view, &self.rules()) {
            // An easy step: a later stall no longer goes back before it.
            policy.rewind = None;
        }
        let summary = &mut state.summary;
        if let Some((deviation, _)) = review.curve {
            summary.curve_max_deviation = summary.curve_max_deviation.max(deviation);
        }
        if let Some(e) = review.impl_ex_residual {
            summary.impl_ex_max_residual = summary.impl_ex_max_residual.max(e);
        }
    }
}
