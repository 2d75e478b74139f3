//! The state one run works in: the assembled system, the trial states,
//! the internal forces and tangent values of the current iterate, the kept
//! linear-solver state and the wall times of the current step.

use super::checkpoint::HierarchyWear;
use super::summary::WallTimes;
use crate::assembly::{
    AssemblyError, DofMap, ElementLaws, KeptBulkMatrix, LoadDerivatives, Outputs, States, System,
    Tangents, TetHistory,
};
use crate::linalg::amg::{AmgError, AmgParams};
use crate::linalg::multigrid::{FreeDofMultigrid, NodeBlockLayout};
use crate::linalg::{Cholesky, LinearError, Preconditioner};
use crate::spec::solver::{LinearSolverKind, Precision, PreconditionerKind, SolverSettings};
use std::time::Instant;

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
    /// The tets' element matrices kept within a step, under IMPL-EX
    /// concrete: there every concrete tangent is fixed for the step. Under
    /// the implicit integration the tets that start to damage in a step
    /// would each cost two matrices, and the changed order of the additions
    /// moves bifurcating runs onto another branch (the stress suite's
    /// splitting cube), so those runs assemble as before.
    pub(crate) kept_bulk: KeptBulkMatrix,
    /// Scratch for the constraint's gradient on the free DOFs.
    pub(crate) constraint_row: Vec<f64>,
    pub(crate) lin: LinearState,
    /// The smallest force scale of the residual criterion, N (a share of
    /// the largest load of the run so far).
    pub(crate) force_floor: f64,
    /// Wall times of the step being attempted.
    pub(crate) wall: WallTimes,
    /// Whether the step being attempted may hold interface points, so
    /// Newton counts their regime switches (`solver.expert.interface_holds`).
    pub(crate) holds_pairs: bool,
}

impl Workspace<'_> {
    /// Evaluates the iterate `u` from `start` with the tangent kinds
    /// `tangents` into `trial`, `f_int` and the tangent values; the trial
    /// states whose update is deferrable are completed by
    /// [`Workspace::update_history`].
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
                kept_bulk: Some(&mut self.kept_bulk),
                history: TetHistory::Deferred,
            },
        )?;
        self.wall.add_eval(&t);
        Ok(())
    }

    /// Completes the trial states the iterates' evaluations deferred (see
    /// [`TetHistory::Deferred`]) at the iterate `u`.
    pub(crate) fn update_history(
        &mut self,
        start: &States,
        u: &[f64],
    ) -> Result<(), AssemblyError> {
        let spent = self
            .system
            .update_history(self.laws, u, start, &mut self.trial)?;
        self.wall.constitutive += spent;
        Ok(())
    }

    /// r = −f_int on the free DOFs.
    pub(crate) fn residual(&self, r: &mut [f64]) {
        residual(self.system.dofs(), &self.f_int, r);
    }

    /// The residual criterion's force scale, N: the norm of the reactions
    /// of the current `f_int`, not below `force_floor` (once the specimen
    /// has unloaded, parts separated or the bar pulled free, the reactions
    /// are round-off and a share of the largest load stands in), 1 where
    /// both are zero.
    pub(crate) fn force_scale(&self) -> f64 {
        let reaction = reaction_norm(self.system, &self.f_int).max(self.force_floor);
        if reaction > 0.0 {
            reaction
        } else {
            1.0
        }
    }
}

/// r = −f_int on the free DOFs (no external loads besides the Dirichlet values).
pub(crate) fn residual(dofs: &DofMap, f_int: &[f64], r: &mut [f64]) {
    dofs.gather(f_int, r);
    r.iter_mut().for_each(|v| *v = -*v);
}

/// ‖f_int‖ over the constrained DOFs: the reactions, the force scale.
fn reaction_norm(system: &System, f_int: &[f64]) -> f64 {
    let dofs = system.dofs();
    (0..dofs.n_total())
        .filter(|&d| dofs.free_index(d).is_none())
        .map(|d| f_int[d] * f_int[d])
        .sum::<f64>()
        .sqrt()
}

/// The preconditioner kept across iterations and steps (PCG, GMRES) or the
/// factor of the current matrix (Cholesky mode).
pub(crate) enum Kept {
    Factor(Box<Cholesky>),
    Multigrid {
        layout: Box<NodeBlockLayout>,
        hierarchy: Option<Box<FreeDofMultigrid>>,
    },
}

impl Kept {
    /// Whether a preconditioner (a factor or a hierarchy) is available.
    pub(crate) fn is_ready(&self) -> bool {
        match self {
            Kept::Factor(c) => c.is_factored(),
            Kept::Multigrid { hierarchy, .. } => hierarchy.is_some(),
        }
    }

    /// Builds the preconditioner of the symmetric matrix with lower values
    /// `values`.
    pub(crate) fn build(&mut self, values: &[f64]) -> Result<(), LinearError> {
        match self {
            Kept::Factor(c) => c.factorize(values),
            Kept::Multigrid { layout, hierarchy } => {
                *hierarchy = None;
                let h =
                    layout
                        .build(values, nonlinear_multigrid_params())
                        .map_err(|e| match e {
                            AmgError::Coarse(e) => e,
                            _ => LinearError::NonFinite,
                        })?;
                *hierarchy = Some(Box::new(h));
                Ok(())
            }
        }
    }
}

impl Preconditioner for Kept {
    fn apply(&self, r: &mut [f64]) -> Result<(), LinearError> {
        match self {
            Kept::Factor(c) => c.precondition(r),
            Kept::Multigrid {
                hierarchy: Some(h), ..
            } => h.apply(r),
            Kept::Multigrid {
                hierarchy: None, ..
            } => Err(LinearError::NonFinite),
        }
    }
}

/// Multigrid set-up of the tangent. Interface elements couple the twin
/// nodes of the steel and concrete sides far more weakly than the bulk
/// couples neighbours (K_s A_node against E h: ~4e-3 on R1), so with every
/// coupling strong, aggregates span the interface and the coarse spaces
/// cannot move the bar against the concrete: R1's first step did not
/// converge in 40 GMRES iterations. A strength threshold of 0.02 keeps
/// aggregates on one side (tiny-ribbed: 373 GMRES iterations to 0.05 mm
/// against 1 256 with none; 0.08: 375, 0.2: 1 756).
fn nonlinear_multigrid_params() -> AmgParams {
    AmgParams {
        strength: 0.02,
        ..AmgParams::default()
    }
}

/// Linear-algebra state reused across iterations and steps.
pub(crate) struct LinearState {
    pub(crate) kept: Kept,
    pub(crate) factorisations: usize,
    pub(crate) pcg_iterations: usize,
    pub(crate) krylov_iterations: usize,
    /// Lower values of the matrix the kept preconditioner was built from
    /// (PCG, GMRES); saved in checkpoints.
    pub(crate) preconditioner: Vec<f64>,
    /// The preconditioner is missing or has become poor: build it anew.
    pub(crate) refactor: bool,
    /// The kept hierarchy's wear since its build
    /// (`solver.expert.multigrid_rebuild: amortised`).
    pub(crate) wear: HierarchyWear,
}

impl LinearState {
    /// The symbolic analysis (Cholesky) or the node-block layout (multigrid)
    /// of `system`'s pattern, timed into `wall`; `nodes` are the model's
    /// node coordinates (m), the multigrid's rigid-body modes, and `charts`
    /// the nodes' sides of a tied cut ([`super::problem::Dirichlet::charts`]).
    pub(crate) fn new(
        system: &System,
        settings: &SolverSettings,
        nodes: &[[f64; 3]],
        charts: &[i8],
        wall: &mut WallTimes,
    ) -> Result<Self, LinearError> {
        let dofs = system.dofs();
        let t = Instant::now();
        let kept = if settings.preconditioner_for(dofs.n_free()) == PreconditionerKind::Multigrid {
            let layout = NodeBlockLayout::new(
                &system.col_ptr,
                &system.row_idx,
                |d| dofs.owned_index(d),
                nodes,
                charts,
            )?;
            Kept::Multigrid {
                layout: Box::new(layout),
                hierarchy: None,
            }
        } else {
            let mut dof_node = vec![0usize; dofs.n_free()];
            for d in 0..dofs.n_total() {
                if let Some(f) = dofs.owned_index(d) {
                    dof_node[f] = d / 3;
                }
            }
            let mut chol = Cholesky::new(
                &system.col_ptr,
                &system.row_idx,
                settings.ordering,
                &dof_node,
            )?;
            if settings.linear_solver == LinearSolverKind::Gmres {
                chol.set_single_precision_preconditioner(
                    settings.preconditioner_precision == Precision::Single,
                );
            }
            Kept::Factor(Box::new(chol))
        };
        wall.factorisation += t.elapsed().as_secs_f64();
        Ok(Self {
            kept,
            factorisations: 0,
            pcg_iterations: 0,
            krylov_iterations: 0,
            preconditioner: if settings.linear_solver == LinearSolverKind::Cholesky {
                Vec::new()
            } else {
                vec![0.0; system.nnz()]
            },
            refactor: true,
            wear: HierarchyWear::default(),
        })
    }
}
