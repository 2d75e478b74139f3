//! The review of an attempt before its commit: Newton's outcome, then the
//! checks of `policy::checks` in order (load jump; the IMPL-EX error,
//! after the implicit history; the curve's bend; the energy), each of
//! which may refuse the converged state.

use super::attempt::Tried;
use super::setup::{Averaging, Driver};
use crate::assembly::{AssemblyError, Outputs, States, System, Tangents};
use crate::laws::TangentKind;
use crate::linalg::norm;
use crate::nonlinear::checkpoint::RunState;
use crate::nonlinear::failure::{Refusal, RegimeChanges, StepFailure};
use crate::nonlinear::policy::checks::{curve_bend, energy, impl_ex, load_jump};
use crate::nonlinear::policy::controls::{at_min_step, Plan};
use crate::nonlinear::report::{SolveError, WallTimes};
use crate::nonlinear::settle::release_retried;
use crate::nonlinear::workspace::{residual, Workspace};
use rayon::prelude::*;
use std::time::Instant;

/// What the review of a converged attempt found.
#[derive(Default)]
pub(crate) struct Review {
    /// The IMPL-EX error indicator (`None` without explicit points).
    pub(crate) impl_ex_residual: Option<f64>,
    /// The curve's bend at its last point and the next step it asks for
    /// (m), see `curve_bend::bend`.
    pub(crate) curve: Option<(f64, f64)>,
    /// The regime changes from the committed state to the accepted one,
    /// counted before the retried points are released.
    pub(crate) changes: RegimeChanges,
    /// The step's force (N), FED (m) and σ_mb (Pa), measured once for the
    /// curve's bend, the energy and the curve row.
    pub(crate) measured: (f64, f64, f64),
}

/// The review's outcome.
pub(crate) enum Verdict {
    Accepted(Review),
    /// Newton did not converge, or a check refused the state.
    Failed(StepFailure),
}

impl Driver<'_> {
    /// Reviews the attempt `tried` at the step `plan`: the workspace's
    /// trial states are the attempt's, its retried points released once
    /// accepted, and the energy tracker holds its trial row.
    pub(crate) fn review(
        &mut self,
        state: &mut RunState,
        plan: &Plan,
        tried: &mut Tried,
    ) -> Result<Verdict, SolveError> {
        if let Some(failure) = &tried.attempt.failure {
            return Ok(Verdict::Failed(failure.clone().into()));
        }
        let (path, loading) = (&state.path, self.loading);
        if let Some(jump) = load_jump::check(plan, path.lambda, tried.lambda, loading) {
            return Ok(Verdict::Failed(jump.into()));
        }
        let u = &tried.u;
        let measured = self.problem.measurement.eval(u, &self.ws.f_int);
        self.average_history(&path.states, u, &mut tried.wall)?;
        let impl_ex_residual = self.extrapolation_error(u, &mut tried.wall)?;
        let summary = &mut state.summary;
        if let Some(e) = impl_ex_residual {
            let at_min = at_min_step(plan, &self.view(path), &self.rules());
            if let Some(refusal) = impl_ex::check(e, at_min, self.settings) {
                summary.impl_ex_rejections += 1;
                summary.impl_ex_max_residual = summary.impl_ex_max_residual.max(e);
                return Ok(Verdict::Failed(refusal.into()));
            }
        }
        let view = self.view(path);
        let mode = state.policy.steps.mode;
        let curve = curve_bend::bend(&view, plan, mode, measured.1, measured.2, loading);
        if let Some((deviation, _)) = curve {
            if let Some(refusal) = curve_bend::check(deviation, plan, loading) {
                summary.curve_rejections += 1;
                return Ok(Verdict::Failed(refusal.into()));
            }
        }
        let changes = RegimeChanges::between(&path.states, &self.ws.trial);
        release_retried(&mut self.ws.trial, &self.explicit);
        let step = path.rows.len() + 1;
        if let Some(refusal) = self.energy_refusal(step, u, tried.lambda, measured.0, changes) {
            state.summary.dissipation_rejections += 1;
            return Ok(Verdict::Failed(refusal.into()));
        }
        Ok(Verdict::Accepted(Review {
            impl_ex_residual,
            curve,
            changes,
            measured,
        }))
    }

    /// The energy check's verdict on the workspace's trial state at (`u`,
    /// `lambda`, `force`), which becomes the tracker's trial row. Off
    /// (`Summary::checks_off` says why) where points are integrated
    /// explicitly for the whole run: their stress comes from an
    /// extrapolated history and their state from the implicit one, so
    /// their energy record carries IMPL-EX's error, not a sign of a state
    /// off the path.
    fn energy_refusal(
        &mut self,
        step: usize,
        u: &[f64],
        lambda: f64,
        force: f64,
        regimes: RegimeChanges,
    ) -> Option<Refusal> {
        let limit = if self.has_explicit_points() {
            0.0
        } else {
            self.settings.dissipation_tolerance
        };
        let tracker = self.energy.as_mut().ok()?;
        let row = match tracker.trial(lambda, force, u, &self.ws.trial) {
            Ok(row) => row,
            Err(e) => {
                self.energy = Err(format!("step {step}: {e}"));
                return None;
            }
        };
        let last = tracker.rows().last().copied().unwrap_or_default();
        energy::check(&row, &last, limit, regimes)
    }

    /// Whether points are integrated explicitly for the whole run (IMPL-EX
    /// concrete or interface, or slivers).
    pub(crate) fn has_explicit_points(&self) -> bool {
        self.explicit_interface || self.explicit.iter().any(|&e| e)
    }

    /// Under a gradient-enhanced damage, the implicit history of the
    /// converged iterate `u`: each Mazars tet's κ from the averaged
    /// equivalent strain of `u` (see [`crate::nonlocal`]), in the
    /// workspace's trial states. Its time is the constitutive phase's.
    fn average_history(
        &mut self,
        committed: &States,
        u: &[f64],
        step_wall: &mut WallTimes,
    ) -> Result<(), SolveError> {
        let Some(Averaging { operator, laws }) = &self.averaging else {
            return Ok(());
        };
        let t = Instant::now();
        let system: &System = self.ws.system;
        let measures: Vec<(f64, f64)> = operator
            .tets()
            .par_iter()
            .zip(laws)
            .map(|(&i, law)| law.local_measures(&system.tet_strain(i, u)))
            .collect();
        let local: Vec<f64> = measures.iter().map(|m| m.0).collect();
        let averaged = operator.average(&local)?;
        let trial = &mut self.ws.trial.bulk;
        for (((&i, law), &eps_bar), &(_, alpha_t)) in operator
            .tets()
            .iter()
            .zip(laws)
            .zip(&averaged)
            .zip(&measures)
        {
            trial[i] = law.averaged_state(&committed.bulk[i], &trial[i], eps_bar, alpha_t);
        }
        let spent = t.elapsed().as_secs_f64();
        step_wall.constitutive += spent;
        self.wall.constitutive += spent;
        Ok(())
    }

    /// The IMPL-EX error indicator of the converged iterate `u` (see
    /// [`implicit_residual`]), `None` without explicit points; its time is
    /// the constitutive phase's. Leaves the workspace's trial states and
    /// internal forces (the step's answer) as they are.
    fn extrapolation_error(
        &mut self,
        u: &[f64],
        step_wall: &mut WallTimes,
    ) -> Result<Option<f64>, SolveError> {
        let Some(scratch) = self.extrapolated.as_mut() else {
            return Ok(None);
        };
        let t = Instant::now();
        let (trial, forces) = self
            .indicator_trial
            .get_or_insert_with(|| (self.ws.trial.clone(), self.ws.f_int.clone()));
        std::mem::swap(&mut self.ws.trial, trial);
        std::mem::swap(&mut self.ws.f_int, forces);
        let e = implicit_residual(&mut self.ws, trial, &self.explicit, u, scratch);
        std::mem::swap(&mut self.ws.trial, trial);
        std::mem::swap(&mut self.ws.f_int, forces);
        let e = e?;
        let spent = t.elapsed().as_secs_f64();
        step_wall.constitutive += spent;
        self.wall.constitutive += spent;
        Ok(Some(e))
    }
}

/// IMPL-EX error indicator of a converged step: the residual of the
/// converged displacement `u` when every concrete point (and IMPL-EX
/// interface point) takes the damage its implicit history reached in the
/// step (`converged`) instead of the extrapolated one (what an implicit
/// Newton iteration would see there), over the force criterion's scale
/// ([`Workspace::force_scale`]). `explicit`: the tets integrated
/// explicitly for the whole run (see `release_retried`). Overwrites
/// `scratch` and the workspace's trial states and internal forces (see
/// `Driver::extrapolation_error`, which keeps the step's).
fn implicit_residual(
    ws: &mut Workspace<'_>,
    converged: &States,
    explicit: &[bool],
    u: &[f64],
    scratch: &mut States,
) -> Result<f64, AssemblyError> {
    // The states as the commit leaves them (retried tets and held points
    // released to the larger damage).
    scratch.clone_from(converged);
    release_retried(scratch, explicit);
    for s in &mut scratch.bulk {
        s.explicit_damage = Some(s.damage);
    }
    for s in &mut scratch.interface {
        s.explicit_lambda = s.explicit_lambda.map(|_| s.lambda_max);
    }
    let system: &System = ws.system;
    system.evaluate(
        ws.laws,
        u,
        scratch,
        &mut ws.trial,
        Tangents::all(TangentKind::Secant),
        Outputs::forces_of_stresses(&mut ws.f_int),
    )?;
    let mut r = vec![0.0; system.dofs().n_free()];
    residual(system.dofs(), &ws.f_int, &mut r);
    Ok(norm(&r) / ws.force_scale())
}
