//! The review of a converged attempt before it is committed: its IMPL-EX
//! error, the curve's bend within it, the energy it creates or leaves
//! out of balance, and the jump of λ under process-zone control; each
//! may send the step back shorter.

use super::{release_retried, Averaging, Driver, Path, Plan};
use crate::assembly::{AssemblyError, Outputs, States, System, Tangents};
use crate::energy::ENERGY_TOLERANCE;
use crate::laws::TangentKind;
use crate::linalg::norm;
use crate::nonlinear::control::ControlMode;
use crate::nonlinear::failure::{RegimeChanges, StepFailure};
use crate::nonlinear::newton::Attempt;
use crate::nonlinear::report::{SolveError, WallTimes};
use crate::nonlinear::workspace::{residual, Workspace};
use crate::spec::solver::CurveError;
use rayon::prelude::*;
use std::time::Instant;

/// A converged state may give back up to this fraction of W_ext from the
/// dissipated energy whatever its step's work: the scale of the residual
/// work the force criterion leaves in a step (`crate::energy`), so that a
/// step of a few nanometres is not refused for it.
const DISSIPATION_FLOOR: f64 = 2e-3;

/// A displacement-controlled step whose curve bends by more than this
/// multiple of `loading.curve_tolerance` is redone shorter.
const CURVE_REJECT: f64 = 2.0;

/// Steps sized by the curve's bend aim this much below the size that
/// would meet the tolerance exactly.
const CURVE_SAFETY: f64 = 0.9;

/// What the review of a converged attempt found.
#[derive(Default)]
pub(super) struct Review {
    /// The IMPL-EX error indicator (`None` without explicit points).
    pub(super) impl_ex_residual: Option<f64>,
    /// The curve's bend at its last point and the next step it asks for
    /// (m), see [`Driver::curve_bend`].
    pub(super) curve: Option<(f64, f64)>,
    /// The regime changes from the committed state to the accepted one,
    /// counted before the retried points are released.
    pub(super) changes: RegimeChanges,
    /// The step's force (N), FED (m) and σ_mb (Pa), measured once for the
    /// curve's bend, the energy and the curve row.
    pub(super) measured: (f64, f64, f64),
}

impl Driver<'_> {
    /// After a converged attempt at `u`: the averaged history (under a
    /// gradient-enhanced damage), then the IMPL-EX error indicator against
    /// it.
    fn implicit_history(
        &mut self,
        committed: &States,
        u: &[f64],
        step_wall: &mut WallTimes,
    ) -> Result<Option<f64>, SolveError> {
        self.average_history(committed, u, step_wall)?;
        self.extrapolation_error(u, step_wall)
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
        let e = implicit_residual(&mut self.ws, (trial, &self.explicit), u, scratch);
        std::mem::swap(&mut self.ws.trial, trial);
        std::mem::swap(&mut self.ws.f_int, forces);
        let e = e?;
        let spent = t.elapsed().as_secs_f64();
        step_wall.constitutive += spent;
        self.wall.constitutive += spent;
        Ok(Some(e))
    }

    /// The failure that sends a converged step back when its IMPL-EX
    /// error `e` passes `impl_ex_reject` × the tolerance (never at the
    /// minimum step, which cannot be shortened), counted in the summary.
    fn rejection(&self, path: &mut Path, plan: &Plan, e: f64) -> Option<StepFailure> {
        let limit = self.settings.impl_ex_reject? * self.settings.impl_ex_tolerance;
        if e <= limit || self.at_min_step(path, plan) {
            return None;
        }
        path.summary.impl_ex_rejections += 1;
        path.summary.impl_ex_max_residual = path.summary.impl_ex_max_residual.max(e);
        Some(StepFailure::ExtrapolationError {
            indicator: e,
            limit,
        })
    }

    /// Whether a converged attempt ending at (`u`, `lambda`) is kept: not
    /// when a process-zone step moved λ too far, nor when its IMPL-EX
    /// error passes the rejection limit, nor when the curve bent too much
    /// within it (the failure is set in `attempt`). Returns the IMPL-EX
    /// error, evaluated after the implicit history, and the curve's bend.
    pub(super) fn review(
        &mut self,
        path: &mut Path,
        plan: &Plan,
        (u, lambda): (&[f64], f64),
        attempt: &mut Attempt,
        step_wall: &mut WallTimes,
    ) -> Result<Review, SolveError> {
        let mut review = Review::default();
        if attempt.failure.is_none() {
            attempt.failure = self.load_jump(path, plan, lambda);
        }
        if attempt.failure.is_some() {
            return Ok(review);
        }
        review.measured = self.problem.measurement.eval(u, &self.ws.f_int);
        review.impl_ex_residual = self.implicit_history(&path.committed, u, step_wall)?;
        if let Some(e) = review.impl_ex_residual {
            attempt.failure = self.rejection(path, plan, e);
        }
        if attempt.failure.is_none() {
            review.curve = self.curve_bend(path, plan, review.measured);
            if let Some((deviation, _)) = review.curve {
                attempt.failure = self.curve_rejection(path, plan, deviation);
            }
        }
        if attempt.failure.is_none() {
            review.changes = RegimeChanges::between(&path.committed, &self.ws.trial);
            release_retried(&mut self.ws.trial, &self.explicit);
            attempt.failure =
                self.energy_rejection(path, (u, lambda, review.measured.0), review.changes);
        }
        Ok(review)
    }

    /// The energies of the state the step reached at (`u`, `lambda`) (the
    /// workspace's trial, its retried points released), and the failure
    /// that refuses it when it gives back from the dissipated energy, or
    /// leaves forces out of balance whose work is, more than
    /// `solver.expert.dissipation_tolerance` of the work the step received plus
    /// [`DISSIPATION_FLOOR`] of W_ext, or when it would take the run's
    /// record outside the energy check of solve.json. The state is the
    /// tracker's trial until the commit accepts it.
    fn energy_rejection(
        &mut self,
        path: &mut Path,
        (u, lambda, force): (&[f64], f64, f64),
        regimes: RegimeChanges,
    ) -> Option<StepFailure> {
        // Points integrated explicitly for the whole run take their stress
        // from an extrapolated history and their state from the implicit
        // one: their energy record carries IMPL-EX's error (bounded by
        // `impl_ex_tolerance`), not a sign of a state off the path.
        let explicit = self.explicit_interface || self.explicit.iter().any(|&e| e);
        let limit = if explicit {
            0.0
        } else {
            self.settings.dissipation_tolerance
        };
        let tracker = self.energy.as_mut().ok()?;
        let row = match tracker.trial(lambda, force, u, &self.ws.trial) {
            Ok(row) => row,
            Err(e) => {
                self.energy = Err(format!("step {}: {e}", path.rows.len() + 1));
                return None;
            }
        };
        let last = tracker.rows().last().copied().unwrap_or_default();
        // The work the step received: a step back along a snap-back
        // receives none, and gives back nothing but the floor.
        if limit == 0.0 || row.w_ext <= 0.0 {
            return None;
        }
        let step_work = (row.w_ext - last.w_ext).max(0.0);
        let allowed = limit * step_work + DISSIPATION_FLOOR * row.w_ext;
        let given_back = last.dissipated - row.dissipated;
        // The work of the forces left out of balance in the step: a
        // retried step whose tets' damage passes did not settle.
        let unbalanced = ((row.w_ext - row.w_int) - (last.w_ext - last.w_int)).abs();
        let failure = if given_back > allowed {
            StepFailure::CreatesEnergy {
                of_step_work: given_back / step_work,
                of_total_work: given_back / row.w_ext,
                limit,
                regimes,
            }
        } else if unbalanced > allowed {
            StepFailure::OutOfBalance {
                of_step_work: unbalanced / step_work,
                of_total_work: unbalanced / row.w_ext,
                limit,
                regimes,
            }
        } else if !row.keeps_check(&last, ENERGY_TOLERANCE) {
            // Each step within the rules above may still leave a part of
            // its work unbalanced; summed over a snap-back they can take
            // the record past the check that solve.json reports, so the
            // check itself bounds the path.
            StepFailure::FailsEnergyCheck {
                imbalance: row.relative_imbalance(),
                dissipation_increment: row.relative_dissipation_increment(&last),
                limit: ENERGY_TOLERANCE,
                regimes,
            }
        } else {
            return None;
        };
        path.summary.dissipation_rejections += 1;
        Some(failure)
    }

    /// How far the curve bends at its last point once a displacement-
    /// controlled step ends at `u`: the distance of that point from the
    /// chord between the one before it (or the origin) and the new one,
    /// on axes scaled to the FED's range and to the largest |σ_mb| so far
    /// (`loading.curve_tolerance`; see [`chord_deviation`]), and the step
    /// size that would bring it to the tolerance. The distance grows with
    /// the product of the two steps' lengths, whence the geometric mean in
    /// the next size. `None` when the control is off, under path-following
    /// or before the first step.
    fn curve_bend(
        &self,
        path: &Path,
        plan: &Plan,
        (_, fed, bond): (f64, f64, f64),
    ) -> Option<(f64, f64)> {
        let loading = self.loading;
        let tolerance = loading.curve_tolerance;
        if tolerance <= 0.0
            || plan.mode != ControlMode::Displacement
            || path.mode != ControlMode::Displacement
        {
            return None;
        }
        let rows = &path.rows;
        let last = rows.last()?;
        let before = rows.len().checked_sub(2).map(|i| &rows[i]);
        let fed_range = loading.fed_stop.unwrap_or(loading.u_final);
        let stress_range = rows
            .iter()
            .map(|r| r.bond_stress.abs())
            .fold(bond.abs(), f64::max);
        if !(stress_range > 0.0 && fed.is_finite()) {
            return None;
        }
        let scaled = |fed: f64, bond: f64| [fed / fed_range, bond / stress_range];
        let deviation = chord_deviation(
            loading.curve_error,
            scaled(last.fed, last.bond_stress),
            before.map_or([0.0, 0.0], |r| scaled(r.fed, r.bond_stress)),
            scaled(fed, bond),
        );
        if !deviation.is_finite() {
            return None;
        }
        let previous = match path.last_lambda_increment {
            d if d > 0.0 => d,
            _ => plan.size,
        };
        let next = if deviation > 0.0 {
            CURVE_SAFETY * (previous * plan.size * tolerance / deviation).sqrt()
        } else {
            f64::INFINITY
        };
        Some((deviation, next))
    }

    /// The failure that sends a converged step back when the curve's bend
    /// `deviation` passes `CURVE_REJECT` × `loading.curve_tolerance`, with
    /// the size of the shorter step (the bend shrinks in proportion to
    /// it); never for a step at or below `initial_step`.
    fn curve_rejection(&self, path: &mut Path, plan: &Plan, deviation: f64) -> Option<StepFailure> {
        let loading = self.loading;
        let limit = CURVE_REJECT * loading.curve_tolerance;
        let floor = loading.initial_step;
        if deviation <= limit || plan.size <= floor * (1.0 + 1e-12) {
            return None;
        }
        path.summary.curve_rejections += 1;
        let next_step = (CURVE_SAFETY * plan.size * loading.curve_tolerance / deviation).max(floor);
        Some(StepFailure::CurveResolution {
            deviation,
            limit,
            next_step,
        })
    }

    /// The failure of a converged process-zone step that moved λ to
    /// `lambda`, further than `loading.max_step` from the last one; or of
    /// a converged dissipation-controlled step that carried λ forward by
    /// more than that, or past `u_final`. Where the path turns forward
    /// again after a snap-back, a step's released energy ½(F₀λ − Fλ₀)
    /// nearly vanishes along the secant through the origin, so a step of
    /// a few millijoules may land anywhere on it: stress-holdout-8's case
    /// 5 went from λ = 0.191 to 2.145 mm in one step (u_final 0.3 mm), its
    /// force rising along that secant. Displacement control takes such a
    /// step; backward jumps (a split's snap-back) stay dissipation
    /// control's.
    fn load_jump(&self, path: &Path, plan: &Plan, lambda: f64) -> Option<StepFailure> {
        let increment = lambda - path.lambda;
        let (max_step, u_final) = (self.loading.max_step, self.loading.u_final);
        let (jumped, limit) = match plan.mode {
            ControlMode::ProcessZone => (increment.abs() > max_step, max_step),
            ControlMode::Energy => (
                increment > max_step || lambda > u_final * (1.0 + 1e-12),
                max_step.min(u_final - path.lambda),
            ),
            _ => return None,
        };
        jumped.then_some(StepFailure::LoadJump { increment, limit })
    }
}

/// IMPL-EX error indicator of a converged step: the residual of the
/// converged displacement `u` when every concrete point (and IMPL-EX
/// interface point) takes the damage its implicit history reached in the
/// step instead of the extrapolated one (what an implicit Newton
/// iteration would see there), over the force criterion's scale
/// ([`Workspace::force_scale`]). `explicit`: the tets integrated
/// explicitly for the whole run (see `release_retried`). Overwrites
/// `scratch` and the workspace's trial states and internal forces (see
/// `Driver::extrapolation_error`, which keeps the step's).
fn implicit_residual(
    ws: &mut Workspace<'_>,
    (converged, explicit): (&States, &[bool]),
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

/// How far `p` lies from the chord `a`–`b` (scaled axes: FED, σ_mb), as
/// `measure` asks. `Stress` takes, where the FED grows through the three
/// points, the σ_mb distance at `p`'s FED: the error a curve read along
/// FED gets from the chord there. On r1-coarse's steep rise to the
/// adhesion peak (scaled slope 10–20) the shortest distance is that many
/// times smaller, and that rise carried most of its curve error
/// (docs/solver.md, "Resolving the curve"). Elsewhere (a snap-back, a FED
/// at a standstill) both take the shortest distance.
fn chord_deviation(measure: CurveError, p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    if measure == CurveError::Stress && a[0] < p[0] && p[0] < b[0] {
        let t = (p[0] - a[0]) / (b[0] - a[0]);
        (p[1] - (a[1] + t * (b[1] - a[1]))).abs()
    } else {
        distance_to_segment(p, a, b)
    }
}

/// Distance of `p` from the segment from `a` to `b` (a point when they
/// coincide).
fn distance_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (ab, ap) = ([b[0] - a[0], b[1] - a[1]], [p[0] - a[0], p[1] - a[1]]);
    let length2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if length2 > 0.0 {
        ((ap[0] * ab[0] + ap[1] * ab[1]) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (ap[0] - t * ab[0]).hypot(ap[1] - t * ab[1])
}
