//! Quasi-static displacement-controlled solution (SPEC §2, §6): boundary
//! conditions and measurements of the pull-out test, adaptive load stepping
//! with Newton iterations, line search, cut-back, checkpoints and resume.
//!
//! The driver is written for any proportional Dirichlet loading
//! ([`Dirichlet`]: value = base + λ·rate) with a [`Measurement`] of force and
//! relative displacement; [`solve_pullout`] builds both from the pull-out
//! model's node sets:
//! * concrete bearing face (z = L): u_z = 0 on every node;
//! * lateral rigid-body modes of the concrete: of the bearing-face nodes
//!   nearest the line y = 0, the two extreme in x get u_y = 0; of those
//!   nearest x = 0, the one with the largest y gets u_x = 0 (removes x, y
//!   translation and rotation about z without opposing a mirror-symmetric
//!   deformation; the three other modes are held by u_z = 0 on the face);
//! * quarter models (`Symmetry::Quarter`): u_x = 0 on `symmetry_x`, u_y = 0
//!   on `symmetry_y` instead of the point constraints; forces × 4;
//! * bar loaded end: u_z = λ (the imposed displacement), u_x = u_y = 0 (the
//!   machine's grip; it also holds the bar's lateral modes once the
//!   interface has lost its shear stiffness);
//! * F = Σ of the internal forces f_z over the loaded-end nodes (the pull,
//!   N); FED = mean u_z of `bar_free_end` − mean u_z of `concrete_free_face`
//!   (the whole z = 0 concrete face as the mesh gives it, m);
//!   σ_mb = F / (π d l_adh) (paper eq. 14, Pa).

use crate::assembly::{AssemblyError, ElementLaws, EvalTimings, States, System};
use crate::interface_element::INTERFACE_POINTS;
use crate::laws::TangentKind;
use crate::linear::{dot, gmres, norm, pcg, Cholesky, LinearError, SplitMatrix, SymLower};
use crate::spec::solver::{
    ConcreteIntegration, Forcing, LinearSolverKind, Loading, Precision, Predictor, SolverSettings,
};
use mesh::{Model, Symmetry};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// Proportional Dirichlet conditions: u[dofs[i]] = base[i] + λ·rate[i].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Dirichlet {
    /// Global DOFs (3·node + component).
    pub dofs: Vec<usize>,
    /// Value at λ = 0, m.
    pub base: Vec<f64>,
    /// Value per unit λ (dimensionless: λ is a length, m).
    pub rate: Vec<f64>,
}

impl Dirichlet {
    /// Adds DOF `dof` with value `base + λ·rate`.
    pub fn push(&mut self, dof: usize, base: f64, rate: f64) {
        self.dofs.push(dof);
        self.base.push(base);
        self.rate.push(rate);
    }
    fn apply(&self, lambda: f64, u: &mut [f64]) {
        for i in 0..self.dofs.len() {
            u[self.dofs[i]] = self.base[i] + lambda * self.rate[i];
        }
    }
}

/// What is recorded per converged step.
#[derive(Debug, Clone, PartialEq)]
pub struct Measurement {
    /// Force = Σ f_int over these global DOFs, N.
    pub force_dofs: Vec<usize>,
    /// Relative displacement = mean u over `plus` − mean u over `minus`, m.
    pub plus_dofs: Vec<usize>,
    pub minus_dofs: Vec<usize>,
    /// Stress = force · this factor (1/m²), e.g. 1/(π d l_adh) (applied
    /// after `force_factor`).
    pub stress_per_force: f64,
    /// Whole-specimen force per force summed on the model (1, or 4 for a
    /// quarter model: `Symmetry::force_factor`), dimensionless.
    pub force_factor: f64,
}

impl Default for Measurement {
    fn default() -> Self {
        Self {
            force_dofs: Vec::new(),
            plus_dofs: Vec::new(),
            minus_dofs: Vec::new(),
            stress_per_force: 0.0,
            force_factor: 1.0,
        }
    }
}

impl Measurement {
    fn eval(&self, u: &[f64], f_int: &[f64]) -> (f64, f64, f64) {
        let force: f64 = self.force_factor * self.force_dofs.iter().map(|&d| f_int[d]).sum::<f64>();
        let mean = |ds: &[usize]| {
            if ds.is_empty() {
                0.0
            } else {
                ds.iter().map(|&d| u[d]).sum::<f64>() / ds.len() as f64
            }
        };
        let rel = mean(&self.plus_dofs) - mean(&self.minus_dofs);
        (force, rel, force * self.stress_per_force)
    }
}

/// One row of `curve.csv` (SI).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CurveRow {
    pub step: usize,
    /// Imposed displacement λ, m.
    pub u_imposed: f64,
    /// Reaction F, N.
    pub force: f64,
    /// Free-end displacement (relative displacement), m.
    pub fed: f64,
    /// Mean bond stress σ_mb, Pa.
    pub bond_stress: f64,
    /// Newton iterations of the converged attempt.
    pub iterations: usize,
}

/// Wall times by phase, s.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct WallTimes {
    pub total: f64,
    /// Scatter into the global matrix and force vector.
    pub assembly: f64,
    /// Constitutive updates and element kernels.
    pub constitutive: f64,
    /// Numeric Cholesky factorisations (and the symbolic analysis).
    pub factorisation: f64,
    /// Triangular solves and conjugate gradients.
    pub solve: f64,
}

impl WallTimes {
    fn add(&mut self, o: &WallTimes) {
        self.total += o.total;
        self.assembly += o.assembly;
        self.constitutive += o.constitutive;
        self.factorisation += o.factorisation;
        self.solve += o.solve;
    }
    fn add_eval(&mut self, e: &EvalTimings) {
        self.assembly += e.assembly;
        self.constitutive += e.constitutive;
    }
}

/// Summary of a run (`summary.json`).
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Summary {
    /// Largest σ_mb, Pa.
    pub peak_bond_stress: f64,
    /// FED at the peak, m.
    pub fed_at_peak: f64,
    /// FED at the last converged step, m.
    pub final_fed: f64,
    pub steps: usize,
    pub cutbacks: usize,
    /// Free DOFs.
    pub dofs: usize,
    pub total_iterations: usize,
    pub factorisations: usize,
    pub pcg_iterations: usize,
    /// GMRES iterations of the Newton–Krylov solver.
    #[serde(default)]
    pub krylov_iterations: usize,
    /// Steps accepted on the force criterion alone: Newton stagnated with
    /// the residual already below `residual_tolerance` (points switching
    /// between loading and unloading, or stick and slip, kept the energy
    /// criterion out of reach).
    #[serde(default)]
    pub force_only_steps: usize,
    /// IMPL-EX: the largest relative residual of a converged step's
    /// displacement under the implicit damage (see
    /// `SolverSettings::impl_ex_tolerance`); 0 for implicit integration.
    #[serde(default)]
    pub impl_ex_max_residual: f64,
    pub wall_time_s: WallTimes,
}

/// Everything needed to restart from a converged step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    pub n_nodes: usize,
    pub n_tets: usize,
    pub n_interfaces: usize,
    /// λ of the last converged step, m.
    pub u_imposed: f64,
    /// Size of the next step to try, m.
    pub next_step: f64,
    /// Global displacement, m.
    pub u: Vec<f64>,
    pub states: States,
    pub rows: Vec<CurveRow>,
    pub summary: Summary,
    /// The matrix whose factor preconditions the next linear solves (PCG
    /// and GMRES keep one across steps); a resumed run factorises exactly
    /// these values, so its iterates equal the uninterrupted run's bit for
    /// bit. `None` when no factor is kept (Cholesky mode, or none yet).
    pub preconditioner: Option<PreconditionerState>,
    /// Global displacement increment of the last converged step (m; empty
    /// before the first), for the extrapolating predictor.
    pub last_increment: Vec<f64>,
    /// Size of the last converged step, m (0 before the first).
    pub last_step: f64,
}

/// The kept preconditioner of a run: the lower-triangle values (N/m) that
/// were factorised, and whether the solver had decided to refactorise at
/// its next correction.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PreconditionerState {
    pub values: Vec<f64>,
    pub refactor: bool,
}

/// A checkpoint file that cannot be written or read.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    #[error("checkpoint {path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    #[error("checkpoint {path}: corrupt or of another version ({detail})")]
    Corrupt { path: String, detail: String },
}

impl Checkpoint {
    /// Writes atomically (temporary file then rename), bincode.
    pub fn save(&self, path: &Path) -> Result<(), CheckpointError> {
        let io = |source| CheckpointError::Io {
            path: path.display().to_string(),
            source,
        };
        let bytes = bincode::serialize(&(CHECKPOINT_MAGIC, self)).map_err(|e| {
            CheckpointError::Corrupt {
                path: path.display().to_string(),
                detail: e.to_string(),
            }
        })?;
        geom::fsutil::write_atomic(path, &bytes).map_err(io)
    }

    pub fn load(path: &Path) -> Result<Self, CheckpointError> {
        let bytes = std::fs::read(path).map_err(|source| CheckpointError::Io {
            path: path.display().to_string(),
            source,
        })?;
        let (magic, cp): (u64, Checkpoint) =
            bincode::deserialize(&bytes).map_err(|e| CheckpointError::Corrupt {
                path: path.display().to_string(),
                detail: e.to_string(),
            })?;
        if magic != CHECKPOINT_MAGIC {
            return Err(CheckpointError::Corrupt {
                path: path.display().to_string(),
                detail: format!("format tag {magic:#x}"),
            });
        }
        Ok(cp)
    }
}

const CHECKPOINT_MAGIC: u64 = 0x7269_6262_6172_0005;

/// A finished (or partial) run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunResult {
    pub rows: Vec<CurveRow>,
    pub summary: Summary,
    /// The last converged state (for fields and restarts).
    pub last: Checkpoint,
}

/// Per converged step, for progress output.
#[derive(Debug, Clone, PartialEq)]
pub struct StepReport {
    pub row: CurveRow,
    /// Step size of the converged attempt, m.
    pub step_size: f64,
    /// Wall times of this step (all attempts).
    pub times: WallTimes,
    /// Relative residual ‖r‖/F_scale at each iterate of the converged
    /// attempt (the predictor first).
    pub residual_history: Vec<f64>,
    /// The attempt ended on its best iterate of a stagnating iteration
    /// (counted in `Summary::force_only_steps`).
    pub force_only: bool,
    /// IMPL-EX: relative residual of the converged displacement under the
    /// implicit damage (the extrapolation error of the step); `None` for
    /// implicit integration.
    pub impl_ex_residual: Option<f64>,
}

/// A failed attempt that led to a smaller step.
#[derive(Debug, Clone, PartialEq)]
pub struct Cutback {
    /// Step number being attempted.
    pub step: usize,
    /// Imposed displacement of the failed attempt, m.
    pub u_imposed: f64,
    pub failed_step_size: f64,
    pub next_step_size: f64,
    pub reason: String,
    /// ‖r‖/‖reaction‖ per iteration.
    pub residual_history: Vec<f64>,
}

/// The converged state offered to observers.
pub struct CommittedView<'a> {
    pub model: &'a Model,
    pub laws: &'a ElementLaws,
    pub checkpoint: &'a dyn Fn() -> Checkpoint,
    pub u: &'a [f64],
    pub states: &'a States,
}

/// Receives progress; every method has a no-op default.
pub trait Observer {
    fn step_converged(&mut self, _report: &StepReport, _state: &CommittedView<'_>) {}
    fn cutback(&mut self, _event: &Cutback) {}
}

/// An observer that ignores everything.
pub struct Silent;
impl Observer for Silent {}

/// Why a run stopped early.
#[derive(Debug, thiserror::Error)]
pub enum SolveError {
    #[error("model: {0}")]
    Model(String),
    #[error(transparent)]
    Assembly(#[from] AssemblyError),
    #[error("linear solver set-up: {0}")]
    Linear(#[from] LinearError),
    #[error("checkpoint does not match the model: {0}")]
    Checkpoint(String),
    #[error(
        "step {step} did not converge at the minimum step size: imposed displacement {u_imposed:e} m \
         (step {step_size:e} m); residual history {residual_history:?}; likely cause: {cause}; \
         {} converged steps kept", partial.rows.len()
    )]
    Stalled {
        step: usize,
        u_imposed: f64,
        step_size: f64,
        residual_history: Vec<f64>,
        cause: String,
        partial: Box<RunResult>,
    },
    #[error(
        "loading.max_steps = {max_steps} converged steps reached at imposed displacement \
         {u_imposed:e} m before the end of the loading"
    )]
    StepLimit {
        max_steps: usize,
        u_imposed: f64,
        partial: Box<RunResult>,
    },
}

/// Boundary conditions and measurement of the pull-out test (see module doc).
pub fn pullout_conditions(model: &Model) -> Result<(Dirichlet, Measurement), SolveError> {
    let sets = &model.node_sets;
    let need = |name: &str, v: &Vec<u32>| {
        if v.is_empty() {
            Err(SolveError::Model(format!("node set {name} is empty")))
        } else if v.iter().any(|&n| n as usize >= model.nodes.len()) {
            Err(SolveError::Model(format!(
                "node set {name} references a missing node"
            )))
        } else {
            Ok(())
        }
    };
    need("bar_loaded_end", &sets.bar_loaded_end)?;
    need("bar_free_end", &sets.bar_free_end)?;
    need("concrete_bearing_face", &sets.concrete_bearing_face)?;
    need("concrete_free_face", &sets.concrete_free_face)?;
    if !(model.bar_diameter > 0.0 && model.adhesive_length > 0.0) {
        return Err(SolveError::Model(format!(
            "bar_diameter {} m and adhesive_length {} m must be > 0",
            model.bar_diameter, model.adhesive_length
        )));
    }
    let mut dir = Dirichlet::default();
    let mut seen = vec![false; 3 * model.nodes.len()];
    let mut fix = |dir: &mut Dirichlet, dof: usize, rate: f64| {
        if !seen[dof] {
            seen[dof] = true;
            dir.push(dof, 0.0, rate);
        }
    };
    for &n in &sets.bar_loaded_end {
        let n = n as usize;
        fix(&mut dir, 3 * n, 0.0);
        fix(&mut dir, 3 * n + 1, 0.0);
        fix(&mut dir, 3 * n + 2, 1.0);
    }
    for &n in &sets.concrete_bearing_face {
        fix(&mut dir, 3 * n as usize + 2, 0.0);
    }
    if model.symmetry == Symmetry::Quarter {
        // The mirror planes hold the normal displacement; with the bearing
        // face's u_z = 0 they remove every rigid mode, so no point
        // constraints are added (they would over-constrain the quarter).
        need("symmetry_x", &sets.symmetry_x)?;
        need("symmetry_y", &sets.symmetry_y)?;
        for &n in &sets.symmetry_x {
            fix(&mut dir, 3 * n as usize, 0.0);
        }
        for &n in &sets.symmetry_y {
            fix(&mut dir, 3 * n as usize + 1, 0.0);
        }
        return Ok((dir, measurement(model)));
    }
    // Lateral rigid modes: points on (or nearest to) the mirror lines of
    // the bearing face, where a symmetric deformation has no displacement
    // across the line. Corner points (the earlier choice) pin the Poisson
    // expansion of the face and changed the elastic force by 0.45 % on a
    // mirrored test specimen.
    let x = |n: &u32| model.nodes[*n as usize];
    let face = &sets.concrete_bearing_face;
    let nearest = |c: usize| {
        let d = face
            .iter()
            .map(|n| x(n)[c].abs())
            .fold(f64::INFINITY, f64::min);
        let span = face
            .iter()
            .map(|n| x(n)[1 - c].abs())
            .fold(0.0f64, f64::max);
        let line: Vec<u32> = face
            .iter()
            .copied()
            .filter(|n| x(n)[c].abs() <= d + 1e-9 * span)
            .collect();
        let lo = line
            .iter()
            .copied()
            .min_by(|p, q| x(p)[1 - c].total_cmp(&x(q)[1 - c]))
            .expect("checked non-empty");
        let hi = line
            .iter()
            .copied()
            .max_by(|p, q| x(p)[1 - c].total_cmp(&x(q)[1 - c]))
            .expect("checked non-empty");
        (lo, hi)
    };
    // Nearest the line y = 0: two points at both ends hold u_y (y
    // translation and rotation about z); nearest x = 0: one holds u_x.
    let (a, b) = nearest(1);
    let (_, c) = nearest(0);
    if x(&b)[0] - x(&a)[0] <= 0.0 {
        return Err(SolveError::Model(
            "concrete_bearing_face has no extent in x: cannot remove the rotation about z".into(),
        ));
    }
    fix(&mut dir, 3 * a as usize + 1, 0.0);
    fix(&mut dir, 3 * b as usize + 1, 0.0);
    fix(&mut dir, 3 * c as usize, 0.0);
    Ok((dir, measurement(model)))
}

/// Force on the loaded end (times the symmetry factor), FED and σ_mb.
fn measurement(model: &Model) -> Measurement {
    let sets = &model.node_sets;
    Measurement {
        force_dofs: sets
            .bar_loaded_end
            .iter()
            .map(|&n| 3 * n as usize + 2)
            .collect(),
        plus_dofs: sets
            .bar_free_end
            .iter()
            .map(|&n| 3 * n as usize + 2)
            .collect(),
        minus_dofs: sets
            .concrete_free_face
            .iter()
            .map(|&n| 3 * n as usize + 2)
            .collect(),
        stress_per_force: 1.0 / (std::f64::consts::PI * model.bar_diameter * model.adhesive_length),
        force_factor: model.symmetry.force_factor(),
    }
}

/// Runs the pull-out test of SPEC §2 (see [`run`]).
pub fn solve_pullout(
    model: &Model,
    laws: &ElementLaws,
    loading: &Loading,
    settings: &SolverSettings,
    checkpoint: Option<Checkpoint>,
    observer: &mut dyn Observer,
) -> Result<RunResult, SolveError> {
    let (dir, meas) = pullout_conditions(model)?;
    run(
        model, laws, &dir, &meas, loading, settings, checkpoint, observer,
    )
}

/// Outcome of one Newton attempt.
struct Attempt {
    iterations: usize,
    history: Vec<f64>,
    failure: Option<String>,
    /// Converged on the force criterion only (see `Summary::force_only_steps`).
    force_only: bool,
}

/// Linear-algebra state reused across iterations and steps.
struct LinearState {
    /// Factor of the current matrix (Cholesky mode) or of an older one
    /// (PCG, GMRES: the preconditioner).
    chol: Cholesky,
    factorisations: usize,
    pcg_iterations: usize,
    krylov_iterations: usize,
    /// Transposed entries of the consistent tangent (see
    /// `System::evaluate_full`); empty for symmetric tangent kinds.
    upper: Vec<f64>,
    /// Lower values of the matrix held in `chol` when it is kept across
    /// iterations (PCG, GMRES preconditioner); saved in checkpoints.
    preconditioner: Vec<f64>,
    /// The preconditioner is missing or has become poor: factorise anew.
    refactor: bool,
}

/// Displacement-controlled run: λ from the checkpoint's value (or 0) to
/// `loading.u_final` (or until the measured relative displacement reaches
/// `loading.fed_stop`), adaptive steps, Newton with line search.
#[allow(clippy::too_many_arguments)]
pub fn run(
    model: &Model,
    laws: &ElementLaws,
    dirichlet: &Dirichlet,
    measurement: &Measurement,
    loading: &Loading,
    settings: &SolverSettings,
    checkpoint: Option<Checkpoint>,
    observer: &mut dyn Observer,
) -> Result<RunResult, SolveError> {
    let t_start = Instant::now();
    if laws.tets.len() != model.tets.len() || laws.interfaces.len() != model.interfaces.len() {
        return Err(SolveError::Model(format!(
            "{} tet laws for {} tets, {} interface laws for {} interface elements",
            laws.tets.len(),
            model.tets.len(),
            laws.interfaces.len(),
            model.interfaces.len()
        )));
    }
    let active: Vec<bool> = laws.interfaces.iter().map(|l| l.is_some()).collect();
    let mut wall = WallTimes::default();
    let system = System::new(model, &dirichlet.dofs, &active)?;
    let dofs = system.dofs();
    let n_total = dofs.n_total();
    let n_free = dofs.n_free();
    let mut dof_node = vec![0usize; n_free];
    for d in 0..n_total {
        if let Some(f) = dofs.free_index(d) {
            dof_node[f] = d / 3;
        }
    }
    let t = Instant::now();
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
    wall.factorisation += t.elapsed().as_secs_f64();
    let mut lin = LinearState {
        chol,
        factorisations: 0,
        pcg_iterations: 0,
        krylov_iterations: 0,
        upper: if settings.tangent == TangentKind::Consistent {
            vec![0.0; system.nnz()]
        } else {
            Vec::new()
        },
        preconditioner: if settings.linear_solver == LinearSolverKind::Cholesky {
            Vec::new()
        } else {
            vec![0.0; system.nnz()]
        },
        refactor: true,
    };

    let mut last_inc: Vec<f64> = Vec::new();
    let mut last_h = 0.0;
    let (mut u, mut committed, mut rows, mut summary, mut lambda, mut h) = match checkpoint {
        Some(cp) => {
            if cp.n_nodes != model.nodes.len()
                || cp.n_tets != model.tets.len()
                || cp.n_interfaces != model.interfaces.len()
                || cp.u.len() != n_total
                || cp.states.bulk.len() != model.tets.len()
                || cp.states.interface.len() != INTERFACE_POINTS * model.interfaces.len()
            {
                return Err(SolveError::Checkpoint(format!(
                    "checkpoint has {} nodes, {} tets, {} interface elements; model has {}, {}, {}",
                    cp.n_nodes,
                    cp.n_tets,
                    cp.n_interfaces,
                    model.nodes.len(),
                    model.tets.len(),
                    model.interfaces.len()
                )));
            }
            if let Some(p) = cp.preconditioner {
                // Rebuild the uninterrupted run's factor from its values
                // (a restore, not counted among the run's factorisations).
                if p.values.len() == lin.preconditioner.len() {
                    let t = Instant::now();
                    lin.chol.factorize(&p.values)?;
                    wall.factorisation += t.elapsed().as_secs_f64();
                    lin.preconditioner = p.values;
                    lin.refactor = p.refactor;
                }
            }
            if cp.last_increment.len() == n_total {
                last_inc = cp.last_increment;
                last_h = cp.last_step;
            }
            lin.factorisations = cp.summary.factorisations;
            lin.pcg_iterations = cp.summary.pcg_iterations;
            lin.krylov_iterations = cp.summary.krylov_iterations;
            (
                cp.u,
                cp.states,
                cp.rows,
                cp.summary,
                cp.u_imposed,
                cp.next_step,
            )
        }
        None => (
            vec![0.0; n_total],
            States::initial(model),
            Vec::new(),
            Summary {
                dofs: n_free,
                ..Summary::default()
            },
            0.0,
            loading.initial_step,
        ),
    };
    let previous_wall = summary.wall_time_s;
    summary.wall_time_s = WallTimes::default();
    let mut trial = committed.clone();
    let mut f_int = vec![0.0; n_total];
    let mut values = vec![0.0; system.nnz()];
    let done_eps = 1e-9 * loading.u_final;

    let make_cp = |u: &[f64],
                   states: &States,
                   rows: &[CurveRow],
                   summary: &Summary,
                   lambda: f64,
                   h: f64,
                   lin: &LinearState,
                   last_inc: &[f64],
                   last_h: f64| {
        Checkpoint {
            n_nodes: model.nodes.len(),
            n_tets: model.tets.len(),
            n_interfaces: model.interfaces.len(),
            u_imposed: lambda,
            next_step: h,
            u: u.to_vec(),
            states: states.clone(),
            rows: rows.to_vec(),
            summary: summary.clone(),
            preconditioner: (settings.linear_solver != LinearSolverKind::Cholesky
                && lin.chol.is_factored())
            .then(|| PreconditionerState {
                values: lin.preconditioner.clone(),
                refactor: lin.refactor,
            }),
            last_increment: last_inc.to_vec(),
            last_step: last_h,
        }
    };
    let finish = |summary: &mut Summary, wall: &WallTimes, lin: &LinearState| {
        let mut w = previous_wall;
        let mut now = *wall;
        now.total = t_start.elapsed().as_secs_f64();
        w.add(&now);
        summary.wall_time_s = w;
        let _ = lin;
    };

    // IMPL-EX: the committed states with the extrapolated damage of the
    // step being attempted.
    let mut extrapolated =
        (settings.concrete_integration == ConcreteIntegration::ImplEx).then(|| committed.clone());

    loop {
        let fed_done = loading
            .fed_stop
            .is_some_and(|s| rows.last().is_some_and(|r: &CurveRow| r.fed >= s));
        if lambda >= loading.u_final - done_eps || fed_done {
            break;
        }
        if let Some(max_steps) = loading.max_steps.filter(|&m| rows.len() >= m) {
            finish(&mut summary, &wall, &lin);
            let last = make_cp(
                &u, &committed, &rows, &summary, lambda, h, &lin, &last_inc, last_h,
            );
            return Err(SolveError::StepLimit {
                max_steps,
                u_imposed: lambda,
                partial: Box::new(RunResult {
                    rows,
                    summary,
                    last,
                }),
            });
        }
        let step = rows.len() + 1;
        let h_try = h.min(loading.u_final - lambda);
        let target = lambda + h_try;
        let mut step_wall = WallTimes::default();
        let t_step = Instant::now();
        let mut u_trial = u.clone();
        if settings.predictor == Predictor::Extrapolate && last_h > 0.0 {
            let s = h_try / last_h;
            u_trial
                .iter_mut()
                .zip(&last_inc)
                .for_each(|(v, d)| *v += s * d);
        }
        dirichlet.apply(target, &mut u_trial);
        if let Some(ex) = extrapolated.as_mut() {
            ex.clone_from(&committed);
            let ratio = if last_h > 0.0 { h_try / last_h } else { 0.0 };
            for (state, law) in ex.bulk.iter_mut().zip(&laws.tets) {
                *state = law.extrapolate(state, ratio);
            }
        }
        let step_start = extrapolated.as_ref().unwrap_or(&committed);
        let attempt = newton(
            &system,
            laws,
            settings,
            step_start,
            &mut trial,
            &mut u_trial,
            &mut f_int,
            &mut values,
            h_try,
            &mut lin,
            &mut step_wall,
        );
        step_wall.total = t_step.elapsed().as_secs_f64();
        wall.add(&step_wall);
        summary.total_iterations += attempt.iterations;
        summary.factorisations = lin.factorisations;
        summary.pcg_iterations = lin.pcg_iterations;
        summary.krylov_iterations = lin.krylov_iterations;
        match attempt.failure {
            None => {
                summary.force_only_steps += usize::from(attempt.force_only);
                last_inc.clear();
                last_inc.extend(u_trial.iter().zip(&u).map(|(a, b)| a - b));
                last_h = h_try;
                u = u_trial;
                std::mem::swap(&mut committed, &mut trial);
                lambda = target;
                let (force, fed, bond) = measurement.eval(&u, &f_int);
                let row = CurveRow {
                    step,
                    u_imposed: lambda,
                    force,
                    fed,
                    bond_stress: bond,
                    iterations: attempt.iterations,
                };
                rows.push(row);
                summary.steps = rows.len();
                if bond > summary.peak_bond_stress || rows.len() == 1 {
                    summary.peak_bond_stress = bond;
                    summary.fed_at_peak = fed;
                }
                summary.final_fed = fed;
                if attempt.iterations <= loading.easy_iterations {
                    h = (h_try * loading.growth).min(loading.max_step).max(h);
                } else {
                    h = h_try;
                }
                let impl_ex_residual = match extrapolated.as_mut() {
                    Some(scratch) => {
                        let t = Instant::now();
                        let e = implicit_residual(
                            &system, laws, &committed, &u, scratch, &mut trial, &mut f_int,
                        )?;
                        let spent = t.elapsed().as_secs_f64();
                        step_wall.constitutive += spent;
                        wall.constitutive += spent;
                        summary.impl_ex_max_residual = summary.impl_ex_max_residual.max(e);
                        // A linear extrapolation's error grows like h² on a
                        // smooth history; near R1's adhesion peak it was
                        // closer to h (docs/solver.md), and the steps then
                        // shrink over several steps instead of one.
                        if e > settings.impl_ex_tolerance {
                            let shrink = (settings.impl_ex_tolerance / e).sqrt() * 0.9;
                            h = (h_try * shrink.max(loading.cutback))
                                .max(loading.min_step)
                                .min(h);
                        }
                        Some(e)
                    }
                    None => None,
                };
                finish(&mut summary, &wall, &lin);
                let cp = || {
                    make_cp(
                        &u, &committed, &rows, &summary, lambda, h, &lin, &last_inc, last_h,
                    )
                };
                let view = CommittedView {
                    model,
                    laws,
                    checkpoint: &cp,
                    u: &u,
                    states: &committed,
                };
                observer.step_converged(
                    &StepReport {
                        row,
                        step_size: h_try,
                        times: step_wall,
                        residual_history: attempt.history.clone(),
                        force_only: attempt.force_only,
                        impl_ex_residual,
                    },
                    &view,
                );
                trial.clone_from(&committed);
            }
            Some(reason) => {
                summary.cutbacks += 1;
                let next = h_try * loading.cutback;
                trial.clone_from(&committed);
                observer.cutback(&Cutback {
                    step,
                    u_imposed: target,
                    failed_step_size: h_try,
                    next_step_size: next,
                    reason: reason.clone(),
                    residual_history: attempt.history.clone(),
                });
                if h_try <= loading.min_step * (1.0 + 1e-12) {
                    finish(&mut summary, &wall, &lin);
                    let last = make_cp(
                        &u, &committed, &rows, &summary, lambda, h_try, &lin, &last_inc, last_h,
                    );
                    return Err(SolveError::Stalled {
                        step,
                        u_imposed: target,
                        step_size: h_try,
                        residual_history: attempt.history,
                        cause: reason,
                        partial: Box::new(RunResult {
                            rows,
                            summary,
                            last,
                        }),
                    });
                }
                h = next.max(loading.min_step);
            }
        }
    }
    finish(&mut summary, &wall, &lin);
    let last = make_cp(
        &u, &committed, &rows, &summary, lambda, h, &lin, &last_inc, last_h,
    );
    Ok(RunResult {
        rows,
        summary,
        last,
    })
}

/// IMPL-EX error indicator of a converged step: the residual of the
/// converged displacement `u` when every concrete point takes the damage
/// its implicit history reached in the step instead of the extrapolated
/// one (what an implicit Newton iteration would see there), relative to
/// the reaction like the force criterion. Overwrites `scratch`, `trial` and
/// `f_int` (`f_int` is left with the implicit internal forces).
fn implicit_residual(
    system: &System,
    laws: &ElementLaws,
    committed: &States,
    u: &[f64],
    scratch: &mut States,
    trial: &mut States,
    f_int: &mut [f64],
) -> Result<f64, AssemblyError> {
    scratch.clone_from(committed);
    for s in &mut scratch.bulk {
        s.explicit_damage = Some(s.damage);
    }
    system.evaluate(laws, u, scratch, trial, TangentKind::Secant, f_int, None)?;
    let mut r = vec![0.0; system.dofs().n_free()];
    residual(system.dofs(), f_int, &mut r);
    let reaction = reaction_norm(system, f_int);
    Ok(norm(&r) / if reaction > 0.0 { reaction } else { 1.0 })
}

/// How many points changed by `changed` from their committed state.
fn count_changed<T>(committed: &[T], trial: &[T], changed: impl Fn(&T, &T) -> bool) -> usize {
    committed
        .iter()
        .zip(trial)
        .filter(|(c, t)| changed(c, t))
        .count()
}

/// Damage growth during a failed attempt, as a hint of the likely cause.
fn diagnose(committed: &States, trial: &States) -> String {
    let grew = |a: f64, b: f64| b > a + 1e-12;
    let iface = count_changed(&committed.interface, &trial.interface, |c, t| {
        grew(c.damage, t.damage)
    });
    let bulk = count_changed(&committed.bulk, &trial.bulk, |c, t| {
        grew(c.damage, t.damage)
    });
    let plastic = count_changed(&committed.bulk, &trial.bulk, |c, t| {
        c.plastic_strain != t.plastic_strain
    });
    let slip = count_changed(&committed.interface, &trial.interface, |c, t| {
        c.slip != t.slip
    });
    format!(
        "in the last iterate, interface damage grew at {iface} node pairs and frictional slip changed at {slip}; \
         concrete damage grew in {bulk} tets; steel yielded in {plastic} tets (softening or sticking/sliding switches)"
    )
}

/// Shortest line-search step kept; below it the full Newton step is taken.
const LINE_SEARCH_MIN_STEP: f64 = 0.25;

/// Newton iterations at fixed Dirichlet values (already in `u`).
///
/// Convergence needs both criteria of SPEC §6 after at least one
/// correction: ‖r‖ ≤ tol_r·‖reactions‖ and |Δu_k·r_{k−1}| ≤ tol_e·E_ref,
/// where E_ref is the largest |Δu·r| of the step's corrections, or the work
/// scale ‖reactions‖·h of the step (size h) when larger: after an exact
/// predictor every correction is round-off, relative to itself. A reference
/// taken from the first correction alone made tiny steps unconvergeable:
/// after a cut-back to a step of a few nm, the first correction carries only
/// the tiny imposed increment, and the leftover imbalance of the previous
/// step (converged to tol_r, not to zero) then looks like a large energy.
#[allow(clippy::too_many_arguments)]
fn newton(
    system: &System,
    laws: &ElementLaws,
    settings: &SolverSettings,
    committed: &States,
    trial: &mut States,
    u: &mut [f64],
    f_int: &mut [f64],
    values: &mut [f64],
    step_size: f64,
    lin: &mut LinearState,
    wall: &mut WallTimes,
) -> Attempt {
    let dofs = system.dofs();
    let n_free = dofs.n_free();
    let mut history = Vec::new();
    let mut r = vec![0.0; n_free];
    let mut du = vec![0.0; n_free];
    let mut energy_ref = 0.0f64;
    let mut last_energy = f64::INFINITY;
    let fail = |history: Vec<f64>, iterations, why: String| Attempt {
        iterations,
        history,
        failure: Some(why),
        force_only: false,
    };
    // Correction of the previous iteration (for the line search).
    let mut prev: Option<(Vec<f64>, f64)> = None;
    let mut first_norm = 0.0;
    // Forcing term of the last correction and the residual it started from.
    let mut eta_prev = 0.0f64;
    let mut r_prev = 0.0f64;
    // Tangent kinds of the tets and of the interface elements: a stagnating
    // consistent-tangent Newton continues with the secant matrix (see
    // below), from iteration `window`.
    let mut kinds = [settings.tangent; 2];
    let mut window = 0;
    // The iterate with the smallest relative residual (a stagnating
    // attempt may end on it, see below).
    let mut best_rel = f64::INFINITY;
    let mut best_u = vec![0.0; u.len()];
    for k in 0..=settings.max_iterations {
        let mut eval = |u: &[f64],
                        trial: &mut States,
                        f_int: &mut [f64],
                        values: &mut [f64],
                        upper: &mut Vec<f64>| {
            let upper = (!upper.is_empty()).then_some(upper.as_mut_slice());
            let res =
                system.evaluate_kinds(laws, u, committed, trial, kinds, f_int, Some(values), upper);
            match res {
                Ok(t) => {
                    wall.add_eval(&t);
                    Ok(())
                }
                Err(e) => Err(e.to_string()),
            }
        };
        if let Err(why) = eval(u, trial, f_int, values, &mut lin.upper) {
            return fail(history, k, format!("constitutive failure: {why}"));
        }
        residual(dofs, f_int, &mut r);
        // Line search: if the full correction overshot the energy minimum
        // along its direction and did not reduce the residual, go back to
        // the secant root. The tangent is unsymmetric (no potential), so a
        // shorter step is kept only if its residual is smaller than the full
        // step's; otherwise the full step stands (short steps that reduce
        // nothing stalled Newton at a constant residual).
        if let (true, Some((d, g0))) = (settings.line_search, prev.as_ref()) {
            let mut s = 1.0;
            let mut g = dot(d, &r);
            let full_norm = norm(&r);
            let mut best = (1.0, full_norm);
            let mut tries = 0;
            while g < 0.0 && g.abs() > 0.5 * g0 && full_norm > r_prev && tries < 4 {
                let s_new = (s * g0 / (g0 - g)).clamp(0.1 * s, 0.9 * s);
                dofs.scatter_add(d, s_new - s, u);
                s = s_new;
                if let Err(why) = eval(u, trial, f_int, values, &mut lin.upper) {
                    return fail(
                        history,
                        k,
                        format!("constitutive failure in line search: {why}"),
                    );
                }
                residual(dofs, f_int, &mut r);
                let n = norm(&r);
                if n < best.1 {
                    best = (s, n);
                }
                g = dot(d, &r);
                tries += 1;
            }
            // A very short step is worth nothing: Newton starts again from
            // (almost) the same point with (almost) the same direction. On
            // r1-coarse's softening branch the tries ended at s = 0.001–0.03
            // for 5–10 iterations in a row at a constant residual (1.6e-4)
            // while the full steps converged quadratically (7 iterations to
            // 6e-9) once taken: they cross kinks of the laws (contact
            // opening/closing, damage starting/stopping) that a short step
            // stops in front of.
            if best.0 < LINE_SEARCH_MIN_STEP {
                best = (1.0, full_norm);
            }
            if s != best.0 {
                dofs.scatter_add(d, best.0 - s, u);
                s = best.0;
                if let Err(why) = eval(u, trial, f_int, values, &mut lin.upper) {
                    return fail(
                        history,
                        k,
                        format!("constitutive failure in line search: {why}"),
                    );
                }
                residual(dofs, f_int, &mut r);
            }
            last_energy *= s;
        }
        let reaction = reaction_norm(system, f_int);
        let rnorm = norm(&r);
        if !rnorm.is_finite() {
            return fail(history, k, "non-finite residual".into());
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
            return Attempt {
                iterations: k,
                history,
                failure: None,
                force_only: false,
            };
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
                // Checked before the secant switch: on r1-coarse with
                // μ = 0.001 the consistent tangent alternated 1.04e-4 /
                // 6.6e-4 (tolerance 1e-4), the secant iterations then
                // drifted upwards, and the step was cut down to the minimum
                // size; δ_s = 0.02 and 1 likewise (1.07e-4 and 1.29e-4).
                if rnorm / scale > best_rel {
                    u.copy_from_slice(&best_u);
                    if let Err(why) = eval(u, trial, f_int, values, &mut lin.upper) {
                        return fail(history, k, format!("constitutive failure: {why}"));
                    }
                }
                return Attempt {
                    iterations: k,
                    history,
                    failure: None,
                    force_only: true,
                };
            }
            if stagnating && kinds != [TangentKind::Secant; 2] {
                // Points switching between branches (damage growing or not,
                // stick or slip) make the consistent tangent jump from one
                // iterate to the next; the secant matrix does not. Measured
                // on r1-coarse: switching both families got furthest
                // (FED 0.43 mm in 242 s); the interfaces alone stalled at
                // u = 0.218 mm; Mazars' secant matrix from the start
                // stagnated from the first concrete damage on.
                kinds = [TangentKind::Secant; 2];
                window = k;
            } else if stagnating {
                return fail(
                    history,
                    k,
                    format!(
                        "stagnating at relative residual {:e}. {}",
                        rnorm / scale,
                        diagnose(committed, trial)
                    ),
                );
            }
        }
        if rnorm > 1e8 * first_norm.max(scale) {
            return fail(
                history,
                k,
                format!(
                    "diverging: residual {rnorm:e} N. {}",
                    diagnose(committed, trial)
                ),
            );
        }
        let eta = forcing_term(settings, k, rnorm, r_prev, eta_prev, scale);
        eta_prev = eta;
        r_prev = rnorm;
        if let Err(e) = solve_correction(
            system, laws, settings, committed, trial, u, f_int, values, &r, &mut du, eta, lin, wall,
        ) {
            return fail(
                history,
                k,
                format!("linear solve: {e}. {}", diagnose(committed, trial)),
            );
        }
        let g0 = dot(&du, &r);
        if !g0.is_finite() {
            return fail(history, k, "non-finite correction".into());
        }
        if k == 0 && g0 == 0.0 {
            return Attempt {
                iterations: 1,
                history,
                failure: None,
                force_only: false,
            };
        }
        energy_ref = energy_ref.max(g0.abs());
        last_energy = g0.abs();
        dofs.scatter_add(&du, 1.0, u);
        prev = Some((du.clone(), g0));
    }
    let why = format!(
        "no convergence in {} iterations (last relative residual {:e}). {}",
        settings.max_iterations,
        history.last().copied().unwrap_or(f64::NAN),
        diagnose(committed, trial)
    );
    fail(history, settings.max_iterations, why)
}

/// GMRES relative tolerance of correction `k` (see [`Forcing`]); `rnorm`
/// is the current residual norm, `r_prev` the one the previous correction
/// started from (N), `scale` the force scale of the residual criterion.
fn forcing_term(
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

/// r = −f_int on the free DOFs (no external loads besides the Dirichlet values).
fn residual(dofs: &crate::assembly::DofMap, f_int: &[f64], r: &mut [f64]) {
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

/// Factorises `values` (lower triangle); if that matrix is not positive
/// definite, evaluates the secant matrix at the same iterate into `values`
/// and factorises that (same internal forces and trial states).
#[allow(clippy::too_many_arguments)]
fn factorize_spd(
    system: &System,
    laws: &ElementLaws,
    committed: &States,
    trial: &mut States,
    u: &[f64],
    f_int: &mut [f64],
    values: &mut [f64],
    lin: &mut LinearState,
    wall: &mut WallTimes,
) -> Result<(), LinearError> {
    let t = Instant::now();
    let mut res = lin.chol.factorize(values);
    wall.factorisation += t.elapsed().as_secs_f64();
    lin.factorisations += 1;
    if matches!(res, Err(LinearError::NotPositiveDefinite { .. })) {
        let e = system
            .evaluate(
                laws,
                u,
                committed,
                trial,
                TangentKind::Secant,
                f_int,
                Some(values),
            )
            .map_err(|_| LinearError::NonFinite)?;
        wall.add_eval(&e);
        let t = Instant::now();
        res = lin.chol.factorize(values);
        wall.factorisation += t.elapsed().as_secs_f64();
        lin.factorisations += 1;
    }
    res
}

/// Solves for the Newton correction with the configured linear solver.
///
/// The consistent tangent of Mazars (while damage grows) and of the FCZM
/// (sliding, damage growth) is unsymmetric, and during softening its
/// symmetric part is indefinite. Cholesky and PCG work on the symmetric part
/// (or the secant matrix when that is indefinite): a quasi-Newton method
/// with linear convergence. GMRES solves with the exact tangent (quadratic
/// convergence), preconditioned by a factor kept while GMRES needs few
/// iterations with it.
#[allow(clippy::too_many_arguments)]
fn solve_correction(
    system: &System,
    laws: &ElementLaws,
    settings: &SolverSettings,
    committed: &States,
    trial: &mut States,
    u: &[f64],
    f_int: &mut [f64],
    values: &mut [f64],
    r: &[f64],
    du: &mut [f64],
    eta: f64,
    lin: &mut LinearState,
    wall: &mut WallTimes,
) -> Result<(), LinearError> {
    if settings.linear_solver == LinearSolverKind::Gmres {
        // A symmetric tangent kind has no separate upper values.
        let upper = std::mem::take(&mut lin.upper);
        let lower: &[f64] = values;
        let up: &[f64] = if upper.is_empty() { lower } else { &upper };
        let out = newton_krylov(
            system, laws, settings, committed, trial, u, f_int, lower, up, r, du, eta, lin, wall,
        );
        lin.upper = upper;
        return out;
    }
    if !lin.upper.is_empty() {
        // Unsymmetric consistent tangent: keep its symmetric part.
        for (v, w) in values.iter_mut().zip(&lin.upper) {
            *v = 0.5 * (*v + w);
        }
    }
    if settings.linear_solver == LinearSolverKind::Pcg && lin.chol.is_factored() {
        let t = Instant::now();
        let mat = SymLower {
            col_ptr: &system.col_ptr,
            row_idx: &system.row_idx,
            values,
        };
        let res = pcg(
            mat,
            &lin.chol,
            r,
            du,
            settings.pcg_tolerance,
            settings.pcg_max_iterations,
        );
        wall.solve += t.elapsed().as_secs_f64();
        if let Ok(info) = res {
            lin.pcg_iterations += info.iterations;
            return Ok(());
        }
    }
    let fallback = settings.tangent == TangentKind::Consistent;
    if fallback {
        factorize_spd(system, laws, committed, trial, u, f_int, values, lin, wall)?;
    } else {
        let t = Instant::now();
        let res = lin.chol.factorize(values);
        wall.factorisation += t.elapsed().as_secs_f64();
        lin.factorisations += 1;
        res?;
    }
    if settings.linear_solver == LinearSolverKind::Pcg {
        // The factor preconditions later steps: keep what it was built from.
        lin.preconditioner.copy_from_slice(values);
    }
    let t = Instant::now();
    du.copy_from_slice(r);
    let out = lin.chol.solve_in_place(du);
    wall.solve += t.elapsed().as_secs_f64();
    out
}

/// GMRES on the full tangent (`values`, `upper`), preconditioned by the kept
/// factor; refactorises (symmetric part, else secant) when there is none,
/// when the last solve needed more than half of `krylov_max_iterations`, or
/// when GMRES fails with the old factor. If GMRES fails even with a fresh
/// factor, the correction of the factorised matrix itself is used (a
/// quasi-Newton step; the line search and the iteration limit guard it).
#[allow(clippy::too_many_arguments)]
fn newton_krylov(
    system: &System,
    laws: &ElementLaws,
    settings: &SolverSettings,
    committed: &States,
    trial: &mut States,
    u: &[f64],
    f_int: &mut [f64],
    values: &[f64],
    upper: &[f64],
    r: &[f64],
    du: &mut [f64],
    eta: f64,
    lin: &mut LinearState,
    wall: &mut WallTimes,
) -> Result<(), LinearError> {
    let a = SplitMatrix {
        col_ptr: &system.col_ptr,
        row_idx: &system.row_idx,
        lower: values,
        upper,
    };
    let half = settings.krylov_max_iterations / 2;
    let try_gmres = |lin: &mut LinearState, wall: &mut WallTimes, du: &mut [f64]| {
        let t = Instant::now();
        let res = gmres(a, &lin.chol, r, du, eta, settings.krylov_max_iterations);
        wall.solve += t.elapsed().as_secs_f64();
        match res {
            Ok(info) => {
                lin.krylov_iterations += info.iterations;
                lin.refactor = info.iterations > half;
                true
            }
            Err(LinearError::KrylovNotConverged { iterations, .. }) => {
                lin.krylov_iterations += iterations;
                false
            }
            Err(_) => false,
        }
    };
    if lin.chol.is_factored() && !lin.refactor && try_gmres(lin, wall, du) {
        return Ok(());
    }
    let mut pvals = std::mem::take(&mut lin.preconditioner);
    a.symmetric_part(&mut pvals);
    let res = factorize_spd(
        system, laws, committed, trial, u, f_int, &mut pvals, lin, wall,
    );
    lin.preconditioner = pvals;
    res?;
    lin.refactor = false;
    if try_gmres(lin, wall, du) {
        return Ok(());
    }
    lin.refactor = true;
    let t = Instant::now();
    du.copy_from_slice(r);
    let out = lin.chol.solve_in_place(du);
    wall.solve += t.elapsed().as_secs_f64();
    out
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
