//! The linear correction of a Newton iteration: the configured linear
//! solver on the current tangent, or on the tangent bordered by the
//! path-following constraint (see `control`), with the factor kept across
//! iterations and steps where it preconditions a Krylov method.
//!
//! The consistent tangent of Mazars (while damage grows) and of the FCZM
//! (sliding, damage growth) is unsymmetric, and during softening its
//! symmetric part is indefinite. Cholesky and PCG work on the symmetric part
//! (or the secant matrix when that is indefinite): a quasi-Newton method
//! with linear convergence. GMRES solves with the exact tangent (quadratic
//! convergence), preconditioned by a factor (or, `solver.expert.preconditioner:
//! multigrid`, a multigrid hierarchy) kept while GMRES needs few iterations
//! with it.

use super::control::{Border, BorderedPreconditioner, Indirect};
use super::workspace::{Kept, Workspace};
use crate::assembly::{Outputs, States, Tangents};
use crate::laws::TangentKind;
use crate::linalg::{
    dot, gmres, norm, pcg, KrylovInfo, LinearError, Preconditioner, SplitMatrix, SymLower,
};
use crate::spec::solver::{Forcing, LinearSolverKind, MultigridRebuild, SolverSettings};
use std::time::Instant;

/// A linear solve a Newton iteration asks for: the right-hand side, the
/// Krylov relative tolerance, and under indirect control the border (then
/// the right-hand side and the correction hold one more entry: the
/// constraint row, the load-factor increment).
#[derive(Clone, Copy)]
pub(crate) struct Request<'a> {
    pub(crate) rhs: &'a [f64],
    pub(crate) eta: f64,
    pub(crate) border: Option<&'a Border<'a>>,
}

impl Workspace<'_> {
    /// Solves for the Newton correction `du` of the `request` at iterate
    /// `u` (from `start`) with the configured linear solver.
    pub(crate) fn correction(
        &mut self,
        start: &States,
        u: &[f64],
        request: Request<'_>,
        du: &mut [f64],
    ) -> Result<(), LinearError> {
        if self.settings.linear_solver == LinearSolverKind::Gmres {
            return self.newton_krylov(start, u, request, du);
        }
        let Request { rhs, border, .. } = request;
        if !self.upper.is_empty() {
            // Unsymmetric consistent tangent: keep its symmetric part.
            for (v, w) in self.lower.iter_mut().zip(&self.upper) {
                *v = 0.5 * (*v + w);
            }
        }
        if let (LinearSolverKind::Pcg, Kept::Factor(chol), None) =
            (self.settings.linear_solver, &self.lin.kept, border)
        {
            if chol.is_factored() {
                let t = Instant::now();
                let mat = SymLower {
                    col_ptr: &self.system.col_ptr,
                    row_idx: &self.system.row_idx,
                    values: &self.lower,
                };
                let res = pcg(
                    mat,
                    chol,
                    rhs,
                    du,
                    self.settings.pcg_tolerance,
                    self.settings.pcg_max_iterations,
                );
                self.wall.solve += t.elapsed().as_secs_f64();
                if let Ok(info) = res {
                    self.lin.pcg_iterations += info.iterations;
                    return Ok(());
                }
            }
        }
        let mut values = std::mem::take(&mut self.lower);
        let res = if self.settings.tangent == TangentKind::Consistent {
            self.factorize_spd(start, u, &mut values)
        } else {
            self.factorize(&values)
        };
        self.lower = values;
        res?;
        if self.settings.linear_solver == LinearSolverKind::Pcg {
            // The factor preconditions later steps: keep what it was built from.
            self.lin.preconditioner.copy_from_slice(&self.lower);
        }
        self.factor_solve(rhs, du, border)
    }

    /// Factorises `values` or builds the multigrid hierarchy of them.
    fn factorize(&mut self, values: &[f64]) -> Result<(), LinearError> {
        let t = Instant::now();
        let res = self.lin.kept.build(values);
        self.wall.factorisation += t.elapsed().as_secs_f64();
        self.lin.factorisations += 1;
        self.lin.wear = self.lin.wear.rebuilt();
        res
    }

    /// du = (kept factor, bordered when asked)⁻¹ rhs.
    fn factor_solve(
        &mut self,
        rhs: &[f64],
        du: &mut [f64],
        border: Option<&Border<'_>>,
    ) -> Result<(), LinearError> {
        let t = Instant::now();
        du.copy_from_slice(rhs);
        let out = match (border, &self.lin.kept) {
            (None, Kept::Factor(chol)) => chol.solve_in_place(du),
            (None, kept) => kept.apply(du),
            (Some(b), kept) => BorderedPreconditioner::new(kept, b).and_then(|p| p.apply(du)),
        };
        self.wall.solve += t.elapsed().as_secs_f64();
        out
    }

    /// Factorises `values` (lower triangle); if that matrix is not positive
    /// definite, evaluates the secant matrix at the same iterate into
    /// `values` and factorises that (same internal forces and trial states).
    fn factorize_spd(
        &mut self,
        start: &States,
        u: &[f64],
        values: &mut [f64],
    ) -> Result<(), LinearError> {
        let mut res = self.factorize(values);
        if matches!(res, Err(LinearError::NotPositiveDefinite { .. })) {
            self.secant_matrix(start, u, values)?;
            res = self.factorize(values);
        }
        res
    }

    /// GMRES on the full tangent (bordered when asked), preconditioned by
    /// the kept factor; refactorises (symmetric part, else secant) when
    /// there is none, when the last solve needed more than half of
    /// `krylov_max_iterations`, or when GMRES fails with the old factor. If
    /// GMRES fails even with a fresh factor, the correction of the
    /// factorised matrix itself is used (a quasi-Newton step; the line
    /// search and the iteration limit guard it).
    fn newton_krylov(
        &mut self,
        start: &States,
        u: &[f64],
        request: Request<'_>,
        du: &mut [f64],
    ) -> Result<(), LinearError> {
        let lower = std::mem::take(&mut self.lower);
        let upper = std::mem::take(&mut self.upper);
        let system = self.system;
        let a = SplitMatrix {
            col_ptr: &system.col_ptr,
            row_idx: &system.row_idx,
            lower: &lower,
            // A symmetric tangent kind has no separate upper values.
            upper: if upper.is_empty() { &lower } else { &upper },
        };
        let out = (|| {
            if self.lin.kept.is_ready()
                && !self.lin.refactor
                && self.try_gmres(a, request, du).is_ok()
            {
                return Ok(());
            }
            let mut pvals = std::mem::take(&mut self.lin.preconditioner);
            a.symmetric_part(&mut pvals);
            let res = self.factorize_spd(start, u, &mut pvals);
            self.lin.preconditioner = pvals;
            res?;
            self.lin.refactor = false;
            if self.try_gmres(a, request, du).is_ok() {
                return Ok(());
            }
            self.lin.refactor = true;
            if matches!(self.lin.kept, Kept::Multigrid { .. }) {
                return self.multigrid_fallback(start, u, a, request, du);
            }
            self.factor_solve(request.rhs, du, request.border)
        })();
        self.lower = lower;
        self.upper = upper;
        out
    }

    /// One GMRES solve with the kept factor; why it did not converge.
    fn try_gmres(
        &mut self,
        a: SplitMatrix<'_>,
        request: Request<'_>,
        du: &mut [f64],
    ) -> Result<(), LinearError> {
        let Request { rhs, eta, border } = request;
        let max = self.settings.krylov_max_iterations;
        let t = Instant::now();
        let res = match border {
            None => gmres(&a, &self.lin.kept, rhs, du, eta, max),
            Some(b) => BorderedPreconditioner::new(&self.lin.kept, b)
                .and_then(|p| gmres(&b.operator(&a), &p, rhs, du, eta, max)),
        };
        self.wall.solve += t.elapsed().as_secs_f64();
        match res {
            Ok(info) => {
                self.lin.krylov_iterations += info.iterations;
                self.lin.refactor = info.iterations > max / 2 || self.worn(&info);
                Ok(())
            }
            Err(e) => {
                if let LinearError::KrylovNotConverged { iterations, .. } = e {
                    self.lin.krylov_iterations += iterations;
                }
                Err(e)
            }
        }
    }

    /// Under `solver.expert.multigrid_rebuild: amortised`, counts a solve with
    /// the kept hierarchy and says whether its wear has passed what a
    /// build costs ([`super::HierarchyWear`]).
    fn worn(&mut self, info: &KrylovInfo) -> bool {
        self.settings.multigrid_rebuild == MultigridRebuild::Amortised
            && matches!(self.lin.kept, Kept::Multigrid { .. })
            && self
                .lin
                .wear
                .after_solve(info.iterations, info.relative_residual)
    }

    /// GMRES failed with a fresh hierarchy of the symmetric part (which may
    /// be indefinite while points soften, where the multigrid's smoother
    /// assumes a positive spectrum): rebuild it from the secant matrix
    /// (positive definite) and retry; failing that, solve the secant system
    /// itself, a quasi-Newton correction like the Cholesky route's.
    fn multigrid_fallback(
        &mut self,
        start: &States,
        u: &[f64],
        a: SplitMatrix<'_>,
        request: Request<'_>,
        du: &mut [f64],
    ) -> Result<(), LinearError> {
        let mut values = std::mem::take(&mut self.lin.preconditioner);
        let res = self
            .secant_matrix(start, u, &mut values)
            .and_then(|()| self.factorize(&values));
        self.lin.preconditioner = values;
        res?;
        if self.try_gmres(a, request, du).is_ok() {
            return Ok(());
        }
        let values = std::mem::take(&mut self.lin.preconditioner);
        let secant = SplitMatrix {
            col_ptr: a.col_ptr,
            row_idx: a.row_idx,
            lower: &values,
            upper: &values,
        };
        // The secant system's own error: what the last fallback reached.
        let res = self.try_gmres(secant, request, du);
        self.lin.preconditioner = values;
        res
    }

    /// The secant matrix of the iterate `u` (from `start`) into `values`
    /// (same internal forces and trial states as the tangent's evaluation).
    fn secant_matrix(
        &mut self,
        start: &States,
        u: &[f64],
        values: &mut [f64],
    ) -> Result<(), LinearError> {
        let e = self
            .system
            .evaluate(
                self.laws,
                u,
                start,
                &mut self.trial,
                Tangents::all(TangentKind::Secant),
                Outputs::with_matrix(&mut self.f_int, values),
            )
            .map_err(|_| LinearError::NonFinite)?;
        self.wall.add_eval(&e);
        Ok(())
    }
}

impl Workspace<'_> {
    /// The correction of the bordered system (see `control`): right-hand
    /// side (r, −s g) with the constraint row scaled by s = ‖k_λ‖/‖(gᵤ, g_λ)‖,
    /// so that GMRES weighs both alike; `du` receives (Δu, Δλ).
    pub(crate) fn bordered_correction(
        &mut self,
        start: &States,
        u: &[f64],
        c: &Indirect<'_>,
        r: &[f64],
        du: &mut [f64],
        eta: f64,
    ) -> Result<(), LinearError> {
        let load = self.load.take().unwrap_or_default();
        let n = r.len();
        let mut rhs = vec![0.0; n + 1];
        let mut row = std::mem::take(&mut self.constraint_row);
        row.resize(n, 0.0);
        let row_lambda = c.constraint.gradient(&load, &mut row);
        let g_norm = (dot(&row, &row) + row_lambda * row_lambda).sqrt();
        let scale = match norm(&load.column) / g_norm {
            s if s.is_finite() && s > 0.0 => s,
            _ => 1.0,
        };
        rhs[..n].copy_from_slice(r);
        rhs[n] = -scale * c.constraint.residual(u, c.lambda, &self.f_int);
        let border = Border {
            column: &load.column,
            row: &row,
            row_lambda,
            scale,
        };
        let request = Request {
            rhs: &rhs,
            eta,
            border: Some(&border),
        };
        let out = self.correction(start, u, request, du);
        self.load = Some(load);
        self.constraint_row = row;
        out
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
            eta.min(ETA_MAX).max(floor)
        }
        Forcing::Tolerance => {
            let aim = 0.5 * settings.residual_tolerance * scale / rnorm;
            if aim.is_finite() {
                aim.min(ETA_MAX).max(floor)
            } else {
                floor
            }
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

    /// `tolerance` forcing aims each correction at half the force
    /// criterion (tol_r · scale / ‖r‖ / 2) within [`krylov_tolerance`, 0.1],
    /// whatever the previous corrections did.
    #[test]
    fn forcing_term_aims_at_the_force_criterion() {
        let aim = SolverSettings {
            forcing: Forcing::Tolerance,
            residual_tolerance: 1e-4,
            ..SolverSettings::default()
        };
        let f = |k, r, scale| forcing_term(&aim, k, r, 1.0, 0.1, scale);
        // ‖r‖ = 7e-3 of a 2 kN reaction: 0.5e-4 / 7e-3.
        assert!((f(0, 14.0, 2e3) - 0.5e-4 / 7e-3).abs() < 1e-15);
        assert_eq!(f(1, 14.0, 2e3), f(0, 14.0, 2e3));
        // Near the criterion at most 0.1, far from it at least 1e-3.
        assert_eq!(f(1, 1.2e-4, 1.0), 0.1);
        assert_eq!(f(0, 1.0, 1.0), aim.krylov_tolerance);
        assert_eq!(f(0, 0.0, 1.0), aim.krylov_tolerance);
    }
}
