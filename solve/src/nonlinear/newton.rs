//! Newton iterations at fixed Dirichlet values: line search, stagnation
//! handling and the convergence criteria of SPEC §6.
//!
//! Convergence needs both criteria after at least one correction:
//! ‖r‖ ≤ tol_r·‖reactions‖ and |Δu_k·r_{k−1}| ≤ tol_e·E_ref, where E_ref is
//! the largest |Δu·r| of the step's corrections, or the work scale
//! ‖reactions‖·h of the step (size h) when larger: after an exact predictor
//! every correction is round-off, relative to itself. A reference taken
//! from the first correction alone made tiny steps unconvergeable: after a
//! cut-back to a step of a few nm, the first correction carries only the
//! tiny imposed increment, and the leftover imbalance of the previous step
//! (converged to tol_r, not to zero) then looks like a large energy.

use super::failure::{RegimeChanges, StepFailure};
use super::workspace::Workspace;
use crate::assembly::{States, Tangents};
use crate::laws::TangentKind;
use crate::linear::{dot, norm};
use crate::spec::solver::{Forcing, SolverSettings};

/// Shortest line-search step kept; below it the full Newton step is taken.
const LINE_SEARCH_MIN_STEP: f64 = 0.25;

/// Outcome of one Newton attempt.
pub(crate) struct Attempt {
    pub(crate) iterations: usize,
    /// Relative residual of each iterate (the predictor first).
    pub(crate) history: Vec<f64>,
    pub(crate) failure: Option<StepFailure>,
    /// Converged on the force criterion only (see `Summary::force_only_steps`).
    pub(crate) force_only: bool,
}

impl Attempt {
    fn converged(iterations: usize, history: Vec<f64>, force_only: bool) -> Self {
        Self {
            iterations,
            history,
            failure: None,
            force_only,
        }
    }
    fn failed(iterations: usize, history: Vec<f64>, why: StepFailure) -> Self {
        Self {
            iterations,
            history,
            failure: Some(why),
            force_only: false,
        }
    }
}

fn constitutive(
    in_line_search: bool,
) -> impl FnOnce(crate::assembly::AssemblyError) -> StepFailure {
    move |source| StepFailure::Constitutive {
        in_line_search,
        source,
    }
}

impl Workspace<'_> {
    /// Newton iterations from the iterate `u` (Dirichlet values already
    /// set) and the step's start states `start`, for a step of size
    /// `step_size` (m). On return `u`, `trial` and `f_int` hold the last
    /// (or the accepted) iterate.
    pub(crate) fn newton(&mut self, start: &States, u: &mut [f64], step_size: f64) -> Attempt {
        let settings = self.settings;
        let dofs = self.system.dofs();
        let n_free = dofs.n_free();
        let mut history = Vec::new();
        let mut r = vec![0.0; n_free];
        let mut du = vec![0.0; n_free];
        let mut energy_ref = 0.0f64;
        let mut last_energy = f64::INFINITY;
        // Correction of the previous iteration (for the line search).
        let mut prev: Option<(Vec<f64>, f64)> = None;
        let mut first_norm = 0.0;
        // Forcing term of the last correction and the residual it started from.
        let mut eta_prev = 0.0f64;
        let mut r_prev = 0.0f64;
        // Tangent kinds of the tets and of the interface elements: a stagnating
        // consistent-tangent Newton continues with the secant matrix (see
        // below), from iteration `window`.
        let mut kinds = Tangents::all(settings.tangent);
        let mut window = 0;
        // The iterate with the smallest relative residual (a stagnating
        // attempt may end on it, see below).
        let mut best_rel = f64::INFINITY;
        let mut best_u = vec![0.0; u.len()];
        for k in 0..=settings.max_iterations {
            if let Err(e) = self.evaluate(start, u, kinds) {
                return Attempt::failed(k, history, constitutive(false)(e));
            }
            self.residual(&mut r);
            if let (true, Some((d, g0))) = (settings.line_search, prev.as_ref()) {
                match self.line_search(start, u, kinds, d, *g0, r_prev, &mut r) {
                    Ok(s) => last_energy *= s,
                    Err(e) => return Attempt::failed(k, history, e),
                }
            }
            let reaction = self.reaction_norm();
            let rnorm = norm(&r);
            if !rnorm.is_finite() {
                return Attempt::failed(k, history, StepFailure::NonFiniteResidual);
            }
            let scale = if reaction > 0.0 { reaction } else { 1.0 };
            history.push(rnorm / scale);
            // The predictor (k = 0) counts: at a threshold the first correction
            // can cross to the worse side of the cycle (R1 with δ_s = 0.02 and
            // 1: predictor 1.8e-4, best later iterate 2.2e-4).
            if rnorm / scale < best_rel {
                best_rel = rnorm / scale;
                best_u.copy_from_slice(u);
            }
            if k == 0 {
                first_norm = rnorm;
            }
            if k > 0
                && rnorm <= settings.residual_tolerance * scale
                && last_energy <= settings.energy_tolerance * energy_ref.max(scale * step_size)
            {
                return Attempt::converged(k, history, false);
            }
            if k == settings.max_iterations {
                break;
            }
            // Stagnation (switching stick/slip or loading/unloading points that
            // Newton cannot settle): the last 4 residuals all above half the
            // best before them. A cut-back now is cheaper than more iterations.
            if k >= window + 8 {
                let best_before = history[window..k - 3]
                    .iter()
                    .copied()
                    .fold(f64::INFINITY, f64::min);
                let stagnating = history[k - 3..].iter().all(|&v| v > 0.5 * best_before);
                if stagnating
                    && best_rel <= settings.stagnation_acceptance * settings.residual_tolerance
                {
                    // Points flipping between law branches hold Newton in a
                    // cycle whose best iterate is (nearly) in equilibrium; more
                    // iterations only flip them back and forth, and the energy
                    // criterion measures the flips. End on the best iterate.
                    // Checked before the secant switch (docs/solver.md,
                    // Stagnation).
                    if rnorm / scale > best_rel {
                        u.copy_from_slice(&best_u);
                        if let Err(e) = self.evaluate(start, u, kinds) {
                            return Attempt::failed(k, history, constitutive(false)(e));
                        }
                    }
                    return Attempt::converged(k, history, true);
                }
                if stagnating && kinds != Tangents::all(TangentKind::Secant) {
                    // Points switching between branches (damage growing or not,
                    // stick or slip) make the consistent tangent jump from one
                    // iterate to the next; the secant matrix does not
                    // (docs/solver.md, Stagnation).
                    kinds = Tangents::all(TangentKind::Secant);
                    window = k;
                } else if stagnating {
                    return Attempt::failed(
                        k,
                        history,
                        StepFailure::Stagnating {
                            relative_residual: rnorm / scale,
                            regimes: RegimeChanges::between(start, &self.trial),
                        },
                    );
                }
            }
            if rnorm > 1e8 * first_norm.max(scale) {
                return Attempt::failed(
                    k,
                    history,
                    StepFailure::Diverging {
                        residual: rnorm,
                        regimes: RegimeChanges::between(start, &self.trial),
                    },
                );
            }
            let eta = forcing_term(settings, k, rnorm, r_prev, eta_prev, scale);
            eta_prev = eta;
            r_prev = rnorm;
            if let Err(source) = self.correction(start, u, &r, &mut du, eta) {
                let regimes = RegimeChanges::between(start, &self.trial);
                return Attempt::failed(k, history, StepFailure::LinearSolve { source, regimes });
            }
            let g0 = dot(&du, &r);
            if !g0.is_finite() {
                return Attempt::failed(k, history, StepFailure::NonFiniteCorrection);
            }
            if k == 0 && g0 == 0.0 {
                return Attempt::converged(1, history, false);
            }
            energy_ref = energy_ref.max(g0.abs());
            last_energy = g0.abs();
            dofs.scatter_add(&du, 1.0, u);
            prev = Some((du.clone(), g0));
        }
        let why = StepFailure::IterationLimit {
            iterations: settings.max_iterations,
            relative_residual: history.last().copied().unwrap_or(f64::NAN),
            regimes: RegimeChanges::between(start, &self.trial),
        };
        Attempt::failed(settings.max_iterations, history, why)
    }

    /// After a full correction `d` (with g0 = d·r before it): if it
    /// overshot the energy minimum along its direction and did not reduce
    /// the residual (‖r‖ above `r_prev`), tries the secant root. The
    /// unsymmetric tangent has no potential, so a shorter step is kept only
    /// if its residual is smaller than the full step's; and a step shorter
    /// than [`LINE_SEARCH_MIN_STEP`] is never kept (docs/solver.md, "The
    /// softening-branch stall"). Returns the step length kept; `u`, the
    /// workspace's iterate and `r` are left at it.
    #[allow(clippy::too_many_arguments)]
    fn line_search(
        &mut self,
        start: &States,
        u: &mut [f64],
        kinds: Tangents,
        d: &[f64],
        g0: f64,
        r_prev: f64,
        r: &mut [f64],
    ) -> Result<f64, StepFailure> {
        let dofs = self.system.dofs();
        let mut s = 1.0;
        let mut g = dot(d, r);
        let full_norm = norm(r);
        let mut best = (1.0, full_norm);
        let mut tries = 0;
        while g < 0.0 && g.abs() > 0.5 * g0 && full_norm > r_prev && tries < 4 {
            let s_new = (s * g0 / (g0 - g)).clamp(0.1 * s, 0.9 * s);
            dofs.scatter_add(d, s_new - s, u);
            s = s_new;
            self.evaluate(start, u, kinds).map_err(constitutive(true))?;
            self.residual(r);
            let n = norm(r);
            if n < best.1 {
                best = (s, n);
            }
            g = dot(d, r);
            tries += 1;
        }
        if best.0 < LINE_SEARCH_MIN_STEP {
            best = (1.0, full_norm);
        }
        if s != best.0 {
            dofs.scatter_add(d, best.0 - s, u);
            s = best.0;
            self.evaluate(start, u, kinds).map_err(constitutive(true))?;
            self.residual(r);
        }
        Ok(s)
    }
}

/// GMRES relative tolerance of correction `k` (see [`Forcing`]); `rnorm`
/// is the current residual norm, `r_prev` the one the previous correction
/// started from (N), `scale` the force scale of the residual criterion.
pub(crate) fn forcing_term(
    settings: &SolverSettings,
    k: usize,
    rnorm: f64,
    r_prev: f64,
    eta_prev: f64,
    scale: f64,
) -> f64 {
    const ETA_MAX: f64 = 0.1;
    let floor = settings.krylov_tolerance;
    match settings.forcing {
        Forcing::Fixed => floor,
        Forcing::EisenstatWalker => {
            let eta = if k == 0 || r_prev <= 0.0 {
                ETA_MAX
            } else {
                let ratio = rnorm / r_prev;
                let mut e = 0.9 * ratio * ratio;
                // Safeguard against a sudden drop after a lucky iterate.
                let carried = 0.9 * eta_prev * eta_prev;
                if carried > 0.1 {
                    e = e.max(carried);
                }
                e
            };
            let _ = scale;
            eta.min(ETA_MAX).max(floor)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The Eisenstat–Walker forcing term (choice 2) stays within
    /// [`krylov_tolerance`, 0.1], starts a step at 0.1, follows
    /// 0.9 (‖r_k‖/‖r_{k−1}‖)² in between, and `fixed` forcing is constant
    /// (SPEC §6: inexact Newton corrections; Eisenstat & Walker 1996).
    #[test]
    fn forcing_term_follows_eisenstat_walker_within_bounds() {
        let ew = SolverSettings::default();
        assert_eq!(ew.forcing, Forcing::EisenstatWalker);
        let f = |k, r, rp, ep| forcing_term(&ew, k, r, rp, ep, 1.0);
        assert_eq!(f(0, 1.0, 0.0, 0.0), 0.1);
        // Ratio 0.2: 0.9·0.04 = 0.036.
        assert!((f(1, 0.2, 1.0, 0.1) - 0.036).abs() < 1e-15);
        // A slow decrease is capped at 0.1, a fast one floored at 1e-3.
        assert_eq!(f(2, 0.9, 1.0, 0.1), 0.1);
        assert_eq!(f(3, 1e-3, 1.0, 0.01), ew.krylov_tolerance);
        // Safeguard: a previous η of 0.4 keeps η ≥ 0.9·0.16 = 0.144 → cap.
        assert_eq!(f(4, 1e-2, 1.0, 0.4), 0.1);
        let fixed = SolverSettings {
            forcing: Forcing::Fixed,
            ..ew
        };
        assert_eq!(forcing_term(&fixed, 3, 0.5, 1.0, 0.1, 1.0), 1e-3);
    }
}
