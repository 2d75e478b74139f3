//! The driver's working state and how a run starts: from the unloaded
//! specimen, or from a checkpoint of the same model.

use crate::assembly::{ElementLaws, KeptBulkMatrix, States, System};
use crate::energy::{EnergyRow, EnergyStart, EnergyTracker};
use crate::laws::mazars::Mazars;
use crate::laws::{AnyBulkLaw, TangentKind};
use crate::nonlinear::checkpoint::{Checkpoint, RunState};
use crate::nonlinear::control::Quantity;
use crate::nonlinear::policy::{ConvergedPath, PathView, PolicyState, Rules};
use crate::nonlinear::problem::{Dirichlet, Measurement};
use crate::nonlinear::report::{SolveError, WallTimes};
use crate::nonlinear::summary::Summary;
use crate::nonlinear::workspace::{LinearState, Workspace};
use crate::nonlocal::{self, GradientAveraging};
use crate::spec::solver::{ConcreteIntegration, InterfaceIntegration, Loading, SolverSettings};
use mesh::Model;
use std::time::Instant;

/// The problem a run solves: the model with its laws, the Dirichlet
/// conditions that λ moves, and what is measured per step.
#[derive(Clone, Copy)]
pub struct Problem<'a> {
    pub model: &'a Model,
    pub laws: &'a ElementLaws,
    pub dirichlet: &'a Dirichlet,
    pub measurement: &'a Measurement,
    /// The measured force (whole specimen, N) at which the loaded member
    /// yields over its section, if its law has a yield limit: a run that
    /// stalls there ends at this limit load instead of failing.
    pub yield_force: Option<f64>,
}

/// What a step leaves: the run's state to go on with, or the end of the
/// run at a diagnosed limit.
pub(crate) enum Outcome {
    Continue(RunState),
    End(crate::nonlinear::summary::Ending, RunState),
}

/// Everything a run works with besides its state.
pub(crate) struct Driver<'a> {
    pub(crate) problem: Problem<'a>,
    pub(crate) loading: &'a Loading,
    pub(crate) settings: &'a SolverSettings,
    pub(crate) ws: Workspace<'a>,
    /// The free-end displacement as a linear quantity (indirect control).
    pub(crate) fed: Quantity,
    /// The DOFs that move with λ and their rates.
    pub(crate) rates: Vec<(usize, f64)>,
    /// The tets whose damage a step takes from an extrapolation of their
    /// history (IMPL-EX): every tet under `concrete_integration: impl_ex`,
    /// else the degenerate ones (quality below `expert.sliver_quality`).
    pub(crate) explicit: Vec<bool>,
    /// Whether the interface points take their damage from an
    /// extrapolation of their history (`interface_integration: impl_ex`).
    pub(crate) explicit_interface: bool,
    pub(crate) concrete_tets: usize,
    /// The committed states with the extrapolated damage of the explicit
    /// tets (and interface points) for the step being attempted; `None`
    /// when there are none.
    pub(crate) extrapolated: Option<States>,
    /// The trial states and internal forces of the IMPL-EX error
    /// indicator's evaluation (kept apart from the step's own, which the
    /// commit reads).
    pub(crate) indicator_trial: Option<(States, Vec<f64>)>,
    /// The concrete's gradient-enhanced averaging
    /// (`materials.concrete.nonlocal_length`), applied to each converged
    /// step's implicit history.
    pub(crate) averaging: Option<Averaging<'a>>,
    /// The energy balance of the converged steps, which the energy check
    /// reads; `Err` says why it is not available.
    pub(crate) energy: Result<EnergyTracker<'a>, String>,
    /// Wall times of this invocation, and of the run before a resume.
    pub(crate) wall: WallTimes,
    pub(crate) previous_wall: WallTimes,
    pub(crate) started: Instant,
}

impl<'a> Driver<'a> {
    pub(crate) fn new(
        problem: Problem<'a>,
        loading: &'a Loading,
        settings: &'a SolverSettings,
        system: &'a System,
        started: Instant,
    ) -> Result<Self, SolveError> {
        let mut wall = WallTimes::default();
        let lin = LinearState::new(
            system,
            settings,
            &problem.model.nodes,
            &problem.dirichlet.charts,
            &mut wall,
        )?;
        let length = problem.laws.nonlocal_length;
        if !nonlocal::admits(length, settings.concrete_integration) {
            return Err(SolveError::Model(format!(
                "materials.concrete.nonlocal_length {}",
                nonlocal::NEEDS_IMPL_EX
            )));
        }
        let averaging = match length {
            None => None,
            Some(length) => {
                let t = Instant::now();
                let averaging = Averaging::new(problem, system, length)?;
                wall.factorisation += t.elapsed().as_secs_f64();
                Some(averaging)
            }
        };
        let n_total = system.dofs().n_total();
        let ws = Workspace {
            system,
            laws: problem.laws,
            settings,
            trial: States::default(),
            f_int: vec![0.0; n_total],
            lower: vec![0.0; system.nnz()],
            upper: if settings.tangent == TangentKind::Consistent {
                vec![0.0; system.nnz()]
            } else {
                Vec::new()
            },
            load: None,
            kept_bulk: KeptBulkMatrix::default(),
            constraint_row: Vec::new(),
            lin,
            force_floor: 0.0,
            wall: WallTimes::default(),
            holds_pairs: false,
        };
        let model = problem.model;
        Ok(Self {
            rates: problem.dirichlet.load_rates(),
            fed: Quantity::new(
                problem.measurement.relative_weights(),
                system.dofs(),
                problem.dirichlet,
            ),
            problem,
            loading,
            settings,
            ws,
            explicit: explicit_tets(model, settings),
            explicit_interface: settings.interface_integration == InterfaceIntegration::ImplEx,
            concrete_tets: model
                .tet_region
                .iter()
                .filter(|r| **r == mesh::Region::Concrete)
                .count(),
            extrapolated: None,
            indicator_trial: None,
            averaging,
            energy: Err("not started".into()),
            wall,
            previous_wall: WallTimes::default(),
            started,
        })
    }

    /// The state of a run at the unloaded start.
    pub(crate) fn initial_state(&self) -> RunState {
        let dofs = self.ws.system.dofs();
        RunState {
            path: ConvergedPath::start(dofs.n_total(), States::initial(self.problem.model)),
            policy: PolicyState::start(self.loading),
            summary: Summary {
                dofs: dofs.n_free(),
                preconditioner: self.settings.preconditioner_for(dofs.n_free()),
                ..Summary::default()
            },
        }
    }

    /// The unloaded start of a run, with its energy record.
    pub(crate) fn start(&mut self) -> RunState {
        self.energy =
            EnergyTracker::new(self.problem.model, self.problem.laws).map_err(|e| e.to_string());
        self.initial_state()
    }

    /// The run's state from a checkpoint taken on the same model; restores
    /// the kept preconditioner so that the resumed iterates equal the
    /// uninterrupted run's.
    pub(crate) fn resume(&mut self, cp: Checkpoint) -> Result<RunState, SolveError> {
        let n_total = self.ws.system.dofs().n_total();
        cp.check_matches(self.problem.model, n_total)
            .map_err(SolveError::Checkpoint)?;
        let lin = &mut self.ws.lin;
        if let Some(p) = cp.preconditioner {
            // Rebuild the uninterrupted run's factor from its values (a
            // restore, not counted among the run's factorisations).
            if p.values.len() == lin.preconditioner.len() {
                let t = Instant::now();
                lin.kept.build(&p.values)?;
                self.wall.factorisation += t.elapsed().as_secs_f64();
                lin.preconditioner = p.values;
                lin.refactor = p.refactor;
                lin.wear = p.wear;
            }
        }
        let state = cp.state;
        lin.factorisations = state.summary.factorisations;
        lin.pcg_iterations = state.summary.pcg_iterations;
        lin.krylov_iterations = state.summary.krylov_iterations;
        let energy = cp.energy;
        self.energy = if energy.len() == state.path.rows.len() {
            EnergyTracker::resume(
                self.problem.model,
                self.problem.laws,
                energy_start(&state.path, energy),
            )
            .map_err(|e| e.to_string())
        } else {
            Err(format!(
                "the checkpoint's energy record holds {} steps, its curve {}",
                energy.len(),
                state.path.rows.len()
            ))
        };
        Ok(state)
    }

    /// Readies the workspace for the first step of this invocation.
    pub(crate) fn begin(&mut self, state: &mut RunState) {
        self.previous_wall = state.summary.wall_time_s;
        state.summary.wall_time_s = WallTimes::default();
        self.ws.trial = state.path.states.clone();
        state.summary.explicit_tets = self.explicit.iter().filter(|&&e| e).count();
        self.extrapolated = self
            .explicit
            .iter()
            .any(|&e| e)
            .then(|| state.path.states.clone());
    }

    /// The loading and solver settings the policy reads.
    pub(crate) fn rules(&self) -> Rules<'a> {
        Rules {
            loading: self.loading,
            settings: self.settings,
        }
    }

    /// What the policy reads of `path`.
    pub(crate) fn view<'p>(&self, path: &'p ConvergedPath) -> PathView<'p> {
        let factor = self.problem.measurement.force_factor;
        PathView {
            rows: &path.rows,
            lambda: path.lambda,
            lambda_increment: path.last_lambda_increment,
            fed: self.fed.value(&path.u),
            fed_increment: if path.last_increment.is_empty() {
                0.0
            } else {
                self.fed.value(&path.last_increment)
            },
            load: path.load,
            load_increment: path.last_load_increment,
            peak_load: path
                .rows
                .iter()
                .map(|r| (r.force / factor).abs())
                .fold(0.0, f64::max),
        }
    }

    /// The energy rows of the converged steps, or why there are none.
    pub(crate) fn energy_rows(&self) -> Result<Vec<EnergyRow>, String> {
        self.energy
            .as_ref()
            .map(|t| t.rows().to_vec())
            .map_err(Clone::clone)
    }
}

/// The converged state of `path` for the energy record to continue from,
/// with `rows` the energies of its steps.
pub(crate) fn energy_start(path: &ConvergedPath, rows: Vec<EnergyRow>) -> EnergyStart<'_> {
    EnergyStart {
        u: &path.u,
        states: &path.states,
        rows,
        lambda: path.lambda,
        force: path.rows.last().map_or(0.0, |r| r.force),
    }
}

/// The concrete's averaging operator over the Mazars tets, and their laws
/// in its order.
pub(crate) struct Averaging<'a> {
    pub(crate) operator: GradientAveraging,
    pub(crate) laws: Vec<&'a Mazars>,
}

impl<'a> Averaging<'a> {
    fn new(problem: Problem<'a>, system: &System, length: f64) -> Result<Self, SolveError> {
        let mazars = |law: &'a AnyBulkLaw| match law {
            AnyBulkLaw::Mazars(m) => Some(m),
            _ => None,
        };
        let tets = &problem.laws.tets;
        let operator = GradientAveraging::new(
            &problem.model.tets,
            system.tet_geometry(),
            |i| mazars(&tets[i]).is_some(),
            length,
        )?;
        let laws = operator
            .tets()
            .iter()
            .filter_map(|&i| mazars(&tets[i]))
            .collect();
        Ok(Self { operator, laws })
    }
}

/// The tets a step integrates explicitly (see `Driver::explicit`).
fn explicit_tets(model: &Model, settings: &SolverSettings) -> Vec<bool> {
    if settings.concrete_integration == ConcreteIntegration::ImplEx {
        return vec![true; model.tets.len()];
    }
    model
        .tets
        .iter()
        .map(|t| {
            mesh::build::tet_quality(t.map(|n| model.nodes[n as usize])) < settings.sliver_quality
        })
        .collect()
}
