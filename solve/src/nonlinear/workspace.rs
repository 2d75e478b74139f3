//! The state one run works in: the assembled system, the trial states,
//! the internal forces and tangent values of the current iterate, the kept
//! linear-solver state and the wall times of the current step.

use super::correction::LinearState;
use super::report::WallTimes;
use crate::assembly::{
    AssemblyError, DofMap, ElementLaws, LoadDerivatives, Outputs, States, System, Tangents,
};
use crate::spec::solver::SolverSettings;

pub(crate) struct Workspace<'a> {
    pub(crate) system: &'a System,
    pub(crate) laws: &'a ElementLaws,
    pub(crate) settings: &'a SolverSettings,
    /// States of the current iterate (from the step's start states).
    pub(crate) trial: States,
    /// Internal forces of the current iterate (global), N.
    pub(crate) f_int: Vec<f64>,
    /// Lower-triangle tangent values of the current iterate, N/m.
    pub(crate) lower: Vec<f64>,
    /// Transposed entries of the consistent tangent (see
    /// `assembly::Outputs::upper`); empty for symmetric tangent kinds.
    pub(crate) upper: Vec<f64>,
    /// Derivatives in λ of the current iterate, under path-following
    /// control; `None` otherwise.
    pub(crate) load: Option<LoadDerivatives>,
    /// Scratch for the constraint's gradient on the free DOFs.
    pub(crate) constraint_row: Vec<f64>,
    pub(crate) lin: LinearState,
    /// The smallest force scale of the residual criterion, N (a share of
    /// the largest load of the run so far).
    pub(crate) force_floor: f64,
    /// Wall times of the step being attempted.
    pub(crate) wall: WallTimes,
}

impl Workspace<'_> {
    /// Evaluates the iterate `u` from `start` with the tangent kinds
    /// `tangents` into `trial`, `f_int` and the tangent values.
    pub(crate) fn evaluate(
        &mut self,
        start: &States,
        u: &[f64],
        tangents: Tangents,
    ) -> Result<(), AssemblyError> {
        let upper = (!self.upper.is_empty()).then_some(self.upper.as_mut_slice());
        let t = self.system.evaluate(
            self.laws,
            u,
            start,
            &mut self.trial,
            tangents,
            Outputs {
                f_int: &mut self.f_int,
                lower: Some(&mut self.lower),
                upper,
                load: self.load.as_mut(),
            },
        )?;
        self.wall.add_eval(&t);
        Ok(())
    }

    /// r = −f_int on the free DOFs.
    pub(crate) fn residual(&self, r: &mut [f64]) {
        residual(self.system.dofs(), &self.f_int, r);
    }

    /// ‖f_int‖ over the constrained DOFs: the reactions, the force scale.
    pub(crate) fn reaction_norm(&self) -> f64 {
        reaction_norm(self.system, &self.f_int)
    }
}

/// r = −f_int on the free DOFs (no external loads besides the Dirichlet values).
pub(crate) fn residual(dofs: &DofMap, f_int: &[f64], r: &mut [f64]) {
    dofs.gather(f_int, r);
    r.iter_mut().for_each(|v| *v = -*v);
}

/// ‖f_int‖ over the constrained DOFs: the reactions, the force scale.
pub(crate) fn reaction_norm(system: &System, f_int: &[f64]) -> f64 {
    let dofs = system.dofs();
    (0..dofs.n_total())
        .filter(|&d| dofs.free_index(d).is_none())
        .map(|d| f_int[d] * f_int[d])
        .sum::<f64>()
        .sqrt()
}
