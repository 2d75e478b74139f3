//! One attempt at a step: its start states (the explicit points'
//! extrapolated history), its first iterate and control, Newton, and the
//! remedies the policy allows (`policy::remedies`): retries with flipping
//! tets made explicit or flipping interface points held, and the damage
//! passes that settle them.

use super::setup::Driver;
use crate::assembly::LoadDerivatives;
use crate::elements::interface::INTERFACE_POINTS;
use crate::laws::{BulkLaw, InterfaceLaw};
use crate::nonlinear::checkpoint::RunState;
use crate::nonlinear::control::{Constraint, Control, ControlMode, Indirect, Quantity};
use crate::nonlinear::newton::Attempt;
use crate::nonlinear::policy::controls::Plan;
use crate::nonlinear::policy::remedies::{self, Remedy};
use crate::nonlinear::policy::{ConvergedPath, UNLOADED};
use crate::nonlinear::problem::Dirichlet;
use crate::nonlinear::report::{Cutback, Observer, WallTimes};
use crate::nonlinear::settle::{hold_pairs, settle, Iterate, Retried};
use crate::spec::solver::Predictor;
use std::time::Instant;

/// What an attempt at a step left: Newton's outcome (after the remedies),
/// the iterate's displacement and λ, and the step's wall times.
pub(crate) struct Tried {
    pub(crate) attempt: Attempt,
    pub(crate) u: Vec<f64>,
    pub(crate) lambda: f64,
    pub(crate) wall: WallTimes,
}

/// What the first iterate of a step is built from.
struct Predicting<'b> {
    fed: &'b Quantity,
    zone: Option<&'b Quantity>,
    rates: &'b [(usize, f64)],
    dirichlet: &'b Dirichlet,
    predictor: Predictor,
}

impl Driver<'_> {
    /// Attempts the step `plan` (under process-zone control, `zone` its
    /// quantity) with the retries its remedies allow; the failure is the
    /// last attempt's.
    pub(crate) fn attempt(
        &mut self,
        state: &mut RunState,
        plan: &Plan,
        zone: Option<&Quantity>,
        observer: &mut dyn Observer,
    ) -> Tried {
        self.ws.wall = WallTimes::default();
        let t_step = Instant::now();
        let peak_load = self.view(&state.path).peak_load;
        self.ws.force_floor = UNLOADED * peak_load;
        let mut retried = Retried::default();
        let mut retries = 0;
        self.ws.holds_pairs = state.policy.holds_points(self.settings);
        let budget = remedies::retry_budget(self.ws.holds_pairs);
        let path = &state.path;
        let (attempt, u, lambda) = loop {
            self.prepare_start(path, plan, &retried);
            let predicting = Predicting {
                fed: &self.fed,
                zone,
                rates: &self.rates,
                dirichlet: self.problem.dirichlet,
                predictor: self.settings.predictor,
            };
            let mut iterate = predict(&predicting, path, plan);
            let step_start = self.extrapolated.as_ref().unwrap_or(&path.states);
            if plan.mode == ControlMode::Displacement && path.last_increment.is_empty() {
                let mut u = path.u.clone();
                if self.ws.tangent_predictor(step_start, &mut u, plan.size) {
                    self.problem.dirichlet.apply(plan.target, &mut u);
                    iterate.u = u;
                }
            }
            let mut attempt =
                self.ws
                    .newton(step_start, &mut iterate.u, plan.size, &mut iterate.control);
            state.summary.total_iterations += attempt.iterations;
            let flipping = !(attempt.flipping.is_empty() && attempt.flipping_pairs.is_empty());
            if attempt.failure.is_none()
                && remedies::needs_settling(!retried.is_empty(), attempt.force_only, flipping)
            {
                let start = self.extrapolated.get_or_insert_with(|| path.states.clone());
                attempt = settle(
                    &mut self.ws,
                    start,
                    &mut retried,
                    &mut iterate,
                    attempt,
                    &mut state.summary,
                );
            }
            let lambda = iterate.control.lambda().unwrap_or(plan.target);
            let Some(failure) = attempt.failure.clone() else {
                break (attempt, iterate.u, lambda);
            };
            let new_tets = retried.new_tets(&attempt.flipping, &self.explicit);
            let new_points = retried.new_points(&attempt.flipping_pairs);
            match remedies::next_remedy(retries, budget, new_tets, new_points) {
                Some(Remedy::ExplicitTets) => retried.add_tets(&attempt.flipping, &self.explicit),
                Some(Remedy::HoldPoints) => {
                    state.summary.held_interface_points +=
                        hold_pairs(&mut retried.held, &attempt.flipping_pairs, &self.ws.trial);
                }
                None => break (attempt, iterate.u, lambda),
            }
            retries += 1;
            state.summary.explicit_retries += 1;
            self.ws.trial.clone_from(&path.states);
            observer.cutback(&Cutback {
                step: path.rows.len() + 1,
                u_imposed: lambda,
                failed_mode: plan.mode,
                failed_step_size: plan.size,
                next_mode: plan.mode,
                next_step_size: plan.size,
                reason: failure.into(),
                residual_history: attempt.history.clone(),
            });
        };
        let mut wall = self.ws.wall;
        wall.total = t_step.elapsed().as_secs_f64();
        self.wall.add(&wall);
        let summary = &mut state.summary;
        summary.factorisations = self.ws.lin.factorisations;
        summary.pcg_iterations = self.ws.lin.pcg_iterations;
        summary.krylov_iterations = self.ws.lin.krylov_iterations;
        Tried {
            attempt,
            u,
            lambda,
            wall,
        }
    }

    /// The states a step starts from: the committed ones, with the damage
    /// of the explicit tets (and of the retried ones) extrapolated over the
    /// step, the held points held; and the load derivatives' buffer under
    /// indirect control.
    fn prepare_start(&mut self, path: &ConvergedPath, plan: &Plan, retried: &Retried) {
        self.ws.load = (plan.mode != ControlMode::Displacement)
            .then(|| LoadDerivatives::new(self.ws.system.dofs().n_free()));
        let any =
            !retried.is_empty() || self.explicit_interface || self.explicit.iter().any(|&e| e);
        match (any, self.extrapolated.is_some()) {
            (true, false) => self.extrapolated = Some(path.states.clone()),
            (false, true) => self.extrapolated = None,
            _ => {}
        }
        if let Some(ex) = self.extrapolated.as_mut() {
            ex.clone_from(&path.states);
            let laws = &self.problem.laws.tets;
            let explicit = &self.explicit;
            let chosen = (0..ex.bulk.len())
                .filter(|&i| explicit[i])
                .chain(retried.tets.iter().copied());
            for i in chosen {
                ex.bulk[i] = laws[i].extrapolate(&ex.bulk[i], plan.scale);
            }
            if self.explicit_interface {
                let laws = &self.problem.laws.interfaces;
                for (points, law) in ex.interface.chunks_mut(INTERFACE_POINTS).zip(laws) {
                    if let Some(law) = law {
                        for s in points {
                            *s = law.extrapolate(s, plan.scale);
                        }
                    }
                }
            }
            for &(i, h) in &retried.held {
                ex.interface[i].held = Some(h);
            }
        }
    }
}

/// The first iterate of a step and the control that holds it: the last
/// converged state plus the planned multiple of the last increment, with
/// the Dirichlet values of the predicted λ.
fn predict<'b>(from: &Predicting<'b>, path: &ConvergedPath, plan: &Plan) -> Iterate<'b> {
    let mut u = path.u.clone();
    if from.predictor == Predictor::Extrapolate && plan.scale > 0.0 {
        u.iter_mut()
            .zip(&path.last_increment)
            .for_each(|(v, d)| *v += plan.scale * d);
    }
    let dirichlet = from.dirichlet;
    if plan.mode == ControlMode::Displacement {
        dirichlet.apply(plan.target, &mut u);
        return Iterate {
            u,
            size: plan.size,
            control: Control::Displacement,
        };
    }
    let lambda = path.lambda + plan.scale * path.last_lambda_increment;
    dirichlet.apply(lambda, &mut u);
    let constraint = match plan.mode {
        ControlMode::FreeEnd => Constraint::Quantity {
            quantity: from.fed,
            target: plan.target,
        },
        ControlMode::ProcessZone => Constraint::Quantity {
            quantity: from.zone.expect("a process zone's quantity"),
            target: plan.target,
        },
        _ => Constraint::Energy {
            rates: from.rates,
            force0: path.load,
            lambda0: path.lambda,
            target: plan.target,
        },
    };
    Iterate {
        u,
        size: plan.size,
        control: Control::Indirect(Indirect {
            constraint,
            dirichlet,
            lambda,
            increment: 0.0,
        }),
    }
}
