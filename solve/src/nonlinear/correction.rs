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

use super::control::{Border, BorderedPreconditioner};
use super::workspace::{Kept, Workspace};
use crate::assembly::{Outputs, States, Tangents};
use crate::laws::TangentKind;
use crate::linalg::{gmres, pcg, KrylovInfo, LinearError, Preconditioner, SplitMatrix, SymLower};
use crate::spec::solver::{LinearSolverKind, MultigridRebuild};
use std::time::Instant;

impl Workspace<'_> {
    /// Solves for the Newton correction `du` of the right-hand side `rhs`
    /// at iterate `u` (from `start`) with the configured linear solver;
    /// `eta` is the Krylov relative tolerance. With a `border`, `rhs` and
    /// `du` hold one more entry (the constraint row, the load-factor
    /// increment).
    pub(crate) fn correction(
        &mut self,
        start: &States,
        u: &[f64],
        (rhs, du): (&[f64], &mut [f64]),
        eta: f64,
        border: Option<&Border<'_>>,
    ) -> Result<(), LinearError> {
        if self.settings.linear_solver == LinearSolverKind::Gmres {
            return self.newton_krylov(start, u, (rhs, du), eta, border);
        }
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
        (rhs, du): (&[f64], &mut [f64]),
        eta: f64,
        border: Option<&Border<'_>>,
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
                && self.try_gmres(a, border, rhs, du, eta).is_ok()
            {
                return Ok(());
            }
            let mut pvals = std::mem::take(&mut self.lin.preconditioner);
            a.symmetric_part(&mut pvals);
            let res = self.factorize_spd(start, u, &mut pvals);
            self.lin.preconditioner = pvals;
            res?;
            self.lin.refactor = false;
            if self.try_gmres(a, border, rhs, du, eta).is_ok() {
                return Ok(());
            }
            self.lin.refactor = true;
            if matches!(self.lin.kept, Kept::Multigrid { .. }) {
                return self.multigrid_fallback(start, u, a, (rhs, du), eta, border);
            }
            self.factor_solve(rhs, du, border)
        })();
        self.lower = lower;
        self.upper = upper;
        out
    }

    /// One GMRES solve with the kept factor; why it did not converge.
    fn try_gmres(
        &mut self,
        a: SplitMatrix<'_>,
        border: Option<&Border<'_>>,
        rhs: &[f64],
        du: &mut [f64],
        eta: f64,
    ) -> Result<(), LinearError> {
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
        (rhs, du): (&[f64], &mut [f64]),
        eta: f64,
        border: Option<&Border<'_>>,
    ) -> Result<(), LinearError> {
        let mut values = std::mem::take(&mut self.lin.preconditioner);
        let res = self
            .secant_matrix(start, u, &mut values)
            .and_then(|()| self.factorize(&values));
        self.lin.preconditioner = values;
        res?;
        if self.try_gmres(a, border, rhs, du, eta).is_ok() {
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
        let res = self.try_gmres(secant, border, rhs, du, eta);
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
