//! Adaptive load stepping from the start or a checkpoint to the end of the
//! loading: one Newton attempt per try, cut-back on failure, growth after
//! easy steps, IMPL-EX step control, the choice of what a step prescribes
//! (the imposed displacement λ, or under path-following the free-end
//! displacement, the energy a step releases or the jumps of the
//! interface's process zone, see `control`), and the committed state
//! offered to the observer after every converged step. What a converged
//! attempt must pass before its commit is in `review`; how a run ends
//! where it has no quasi-static continuation, in `ending`.

use super::checkpoint::{Checkpoint, PreconditionerState};
use super::control::{generalised_load, Constraint, Control, ControlMode, Indirect, Quantity};
use super::failure::{RegimeChanges, StepFailure};
use super::newton::Attempt;
use super::problem::{Dirichlet, Measurement};
use super::report::{
    CommittedView, CurveRow, Cutback, Ending, Observer, RunResult, SolveError, StepReport, Summary,
    WallTimes,
};
use super::workspace::{LinearState, Workspace};
use crate::assembly::{
    AssemblyError, ElementLaws, KeptBulkMatrix, LoadDerivatives, Outputs, States, System, Tangents,
};
use crate::elements::interface::INTERFACE_POINTS;
use crate::energy::{EnergyRow, EnergyStart, EnergyTracker};
use crate::laws::mazars::Mazars;
use crate::laws::{AnyBulkLaw, BulkLaw, HeldHistory, InterfaceLaw, TangentKind};
use crate::linalg::norm;
use crate::nonlocal::{self, GradientAveraging};
use crate::spec::solver::{
    ConcreteIntegration, InterfaceHolds, InterfaceIntegration, LinearSolverKind, Loading,
    PathFollowing, Predictor, SolverSettings,
};
use mesh::Model;
use std::time::Instant;

mod ending;
mod review;

pub use ending::CRACKED;
use ending::UNLOADED;
use review::Review;

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

/// A step dissipates when the energy it releases exceeds this fraction of
/// the external work it takes; dissipation control starts there.
const DISSIPATIVE: f64 = 0.1;
/// Dissipation control hands back to displacement control when a step
/// releases less than this fraction of its external work.
const ELASTIC: f64 = 0.05;
/// After a failed displacement-controlled step, dissipation control takes
/// over if the last converged step released at least this fraction of its
/// work.
const STARTS_DISSIPATING: f64 = 1e-3;
/// How often a step is retried with its flip-flopping tets made explicit
/// before it is cut back, without interface holds ...
const RETRIES: usize = 2;
/// ... and with its flip-flopping interface points held too
/// (`solver.expert.interface_holds`).
const RETRIES_WITH_HOLDS: usize = 3;
/// Most damage passes of a retried step (`settle_explicit_damage`).
const DAMAGE_PASSES: usize = 20;
/// A retried tet's damage is settled when the implicit one exceeds the one
/// its stress used by no more than this.
const DAMAGE_SETTLED: f64 = 1e-3;

/// The converged state of a run between steps.
#[derive(Clone)]
struct Path {
    /// Global displacement, m.
    u: Vec<f64>,
    committed: States,
    rows: Vec<CurveRow>,
    summary: Summary,
    /// λ of the last converged step, m.
    lambda: f64,
    /// What the next step prescribes, and its size (m).
    mode: ControlMode,
    next_step: f64,
    /// The largest next displacement-controlled step the curve's bend
    /// allows (`loading.curve_tolerance`), m; infinite when it sets none.
    /// Kept apart from `next_step`, which Newton's effort sets, so that a
    /// step shortened for the curve's sake does not slow the steps after
    /// the bend.
    curve_step: f64,
    /// Global displacement increment and Δλ of the last converged step
    /// (the predictor's; empty and 0 before the first).
    last_increment: Vec<f64>,
    last_lambda_increment: f64,
    /// The generalised load F = Σ rate_a f_int,a of the last converged
    /// step (N) and its increment in that step.
    load: f64,
    last_load_increment: f64,
    /// Whether the steel's plastic strain grew in the last converged step.
    steel_yielding: bool,
    /// Concrete tets whose damage grew in the last converged step.
    damaging_tets: usize,
    /// The next step is taken under displacement control after a
    /// process-zone attempt moved λ too far ([`StepFailure::LoadJump`]);
    /// cleared when a step converges.
    zone_paused: bool,
}

impl Path {
    /// Energy released ½(F_0 λ − F λ_0) and external work ½(F_0 + F)Δλ of
    /// the last converged step (J).
    fn last_energies(&self) -> (f64, f64) {
        let (l, f) = (self.lambda, self.load);
        let (l0, f0) = (l - self.last_lambda_increment, f - self.last_load_increment);
        (0.5 * (f0 * l - f * l0), 0.5 * (f0 + f) * (l - l0))
    }
}

/// One step's plan: what it prescribes, how far, and the predictor's
/// scale of the last increment.
struct Plan {
    mode: ControlMode,
    size: f64,
    /// λ (displacement control) or FED (indirect) at the end of the step, m.
    target: f64,
    /// The predictor's multiple of the last increment (0: none).
    scale: f64,
    /// The process zone's jump quantity a `ProcessZone` step prescribes.
    zone: Option<Quantity>,
}

/// Everything a run works with besides its path.
struct Driver<'a> {
    problem: Problem<'a>,
    loading: &'a Loading,
    settings: &'a SolverSettings,
    ws: Workspace<'a>,
    /// The free-end displacement as a linear quantity (indirect control).
    fed: Quantity,
    /// The DOFs that move with λ and their rates.
    rates: Vec<(usize, f64)>,
    /// The tets whose damage a step takes from an extrapolation of their
    /// history (IMPL-EX): every tet under `concrete_integration: impl_ex`,
    /// else the degenerate ones (quality below `solver.expert.sliver_quality`).
    explicit: Vec<bool>,
    /// Whether the interface points take their damage from an
    /// extrapolation of their history (`interface_integration: impl_ex`).
    explicit_interface: bool,
    /// The committed states with the extrapolated damage of the explicit
    /// tets (and interface points) for the step being attempted; `None`
    /// when there are none.
    extrapolated: Option<States>,
    /// The trial states and internal forces of the IMPL-EX error
    /// indicator's evaluation (kept apart from the step's own, which the
    /// commit reads).
    indicator_trial: Option<(States, Vec<f64>)>,
    /// The concrete's gradient-enhanced averaging
    /// (`materials.concrete.nonlocal_length`), applied to each converged
    /// step's implicit history.
    averaging: Option<Averaging<'a>>,
    /// Under `solver.expert.interface_holds: on_stall`, before the holds: the
    /// path before the first cut-back since the last easy step, which a
    /// stall goes back to.
    rewind: Option<Path>,
    /// The energy balance of the converged steps, which also refuses a
    /// state that creates energy (`solver.expert.dissipation_tolerance`); `Err`
    /// says why it is not available.
    energy: Result<EnergyTracker<'a>, String>,
    /// Wall times of this invocation, and of the run before a resume.
    wall: WallTimes,
    previous_wall: WallTimes,
    started: Instant,
}

/// Runs the loading from the checkpoint's state (or the start) to
/// `loading.u_final` or `loading.fed_stop`, adaptive steps, Newton with
/// line search; under `solver.path_following` steps may prescribe another
/// quantity of the path than λ (see `Driver::plan`).
pub fn run(
    problem: &Problem<'_>,
    loading: &Loading,
    settings: &SolverSettings,
    checkpoint: Option<Checkpoint>,
    observer: &mut dyn Observer,
) -> Result<RunResult, SolveError> {
    let Problem {
        model,
        laws,
        dirichlet,
        ..
    } = *problem;
    if laws.tets.len() != model.tets.len() || laws.interfaces.len() != model.interfaces.len() {
        return Err(SolveError::Model(format!(
            "{} tet laws for {} tets, {} interface laws for {} interface elements",
            laws.tets.len(),
            model.tets.len(),
            laws.interfaces.len(),
            model.interfaces.len()
        )));
    }
    let started = Instant::now();
    let active: Vec<bool> = laws.interfaces.iter().map(|l| l.is_some()).collect();
    let system = System::with_ties(
        model,
        &dirichlet.dofs,
        &dirichlet.ties,
        &dirichlet.load_rates(),
        &active,
    )?;
    let mut driver = Driver::new(*problem, loading, settings, &system, started)?;
    let mut path = match checkpoint {
        Some(cp) => driver.resume(cp)?,
        None => {
            let path = driver.start();
            driver.energy = EnergyTracker::new(model, laws).map_err(|e| e.to_string());
            path
        }
    };
    driver.previous_wall = path.summary.wall_time_s;
    path.summary.wall_time_s = WallTimes::default();
    driver.ws.trial = path.committed.clone();
    path.summary.explicit_tets = driver.explicit.iter().filter(|&&e| e).count();
    driver.extrapolated = driver
        .explicit
        .iter()
        .any(|&e| e)
        .then(|| path.committed.clone());
    while !driver.done(&path) {
        if let Some(max_steps) = loading.max_steps.filter(|&m| path.rows.len() >= m) {
            let u_imposed = path.lambda;
            let h = path.next_step;
            return Err(SolveError::StepLimit {
                max_steps,
                u_imposed,
                partial: driver.partial(path, h),
            });
        }
        path = match driver.step(path, observer)? {
            Outcome::Continue(path) => path,
            Outcome::End(ending, path) => {
                let h = path.next_step;
                let mut result = *driver.partial(path, h);
                result.ending = ending;
                return Ok(result);
            }
        };
    }
    let h = path.next_step;
    Ok(*driver.partial(path, h))
}

/// What a step leaves: the path to go on with, or the end of the run at a
/// diagnosed limit.
enum Outcome {
    Continue(Path),
    End(Ending, Path),
}

impl<'a> Driver<'a> {
    fn new(
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
            explicit: explicit_tets(problem.model, settings),
            explicit_interface: settings.interface_integration == InterfaceIntegration::ImplEx,
            extrapolated: None,
            indicator_trial: None,
            averaging,
            rewind: None,
            energy: Err("not started".into()),
            wall,
            previous_wall: WallTimes::default(),
            started,
        })
    }

    fn start(&self) -> Path {
        Path {
            u: vec![0.0; self.ws.system.dofs().n_total()],
            committed: States::initial(self.problem.model),
            rows: Vec::new(),
            summary: Summary {
                dofs: self.ws.system.dofs().n_free(),
                preconditioner: self
                    .settings
                    .preconditioner_for(self.ws.system.dofs().n_free()),
                ..Summary::default()
            },
            lambda: 0.0,
            mode: ControlMode::Displacement,
            next_step: self.loading.initial_step,
            curve_step: f64::INFINITY,
            last_increment: Vec::new(),
            last_lambda_increment: 0.0,
            load: 0.0,
            last_load_increment: 0.0,
            steel_yielding: false,
            damaging_tets: 0,
            zone_paused: false,
        }
    }

    /// The run's state from a checkpoint taken on the same model; restores
    /// the kept preconditioner so that the resumed iterates equal the
    /// uninterrupted run's.
    fn resume(&mut self, cp: Checkpoint) -> Result<Path, SolveError> {
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
        let (last_increment, last_lambda_increment) = if cp.last_increment.len() == n_total {
            (cp.last_increment, cp.last_step)
        } else {
            (Vec::new(), 0.0)
        };
        lin.factorisations = cp.summary.factorisations;
        lin.pcg_iterations = cp.summary.pcg_iterations;
        lin.krylov_iterations = cp.summary.krylov_iterations;
        let energy = cp.energy;
        let path = Path {
            u: cp.u,
            committed: cp.states,
            rows: cp.rows,
            summary: cp.summary,
            lambda: cp.u_imposed,
            mode: cp.control_mode,
            next_step: cp.next_step,
            curve_step: cp.curve_step,
            last_increment,
            last_lambda_increment,
            load: cp.generalised_load,
            last_load_increment: cp.last_load_increment,
            steel_yielding: false,
            damaging_tets: 0,
            zone_paused: false,
        };
        self.energy = if energy.len() == path.rows.len() {
            EnergyTracker::resume(
                self.problem.model,
                self.problem.laws,
                energy_start(&path, energy),
            )
            .map_err(|e| e.to_string())
        } else {
            Err(format!(
                "the checkpoint's energy record holds {} steps, its curve {}",
                energy.len(),
                path.rows.len()
            ))
        };
        Ok(path)
    }

    /// The end of the loading: λ at `u_final`, or the FED at `fed_stop`.
    fn done(&self, path: &Path) -> bool {
        let loading = self.loading;
        let fed_done = loading
            .fed_stop
            .is_some_and(|s| path.rows.last().is_some_and(|r| r.fed >= s * (1.0 - 1e-9)));
        path.lambda >= loading.u_final - 1e-9 * loading.u_final || fed_done
    }

    /// FED increment of the last converged step, m.
    fn last_fed_increment(&self, path: &Path) -> f64 {
        if path.last_increment.is_empty() {
            0.0
        } else {
            self.fed.value(&path.last_increment)
        }
    }

    /// What the next step prescribes and how far. FED control starts
    /// after the first converged step, when both λ and the FED grew in it
    /// (their ratio converts the step size); process-zone control after a
    /// step in which λ grew and interface points softened, until a step in
    /// which none did. Indirect control hands the step to displacement
    /// control where the extrapolated λ would pass `u_final`.
    fn plan(&self, path: &mut Path) -> Plan {
        let loading = self.loading;
        let dl = path.last_lambda_increment;
        let df = self.last_fed_increment(path);
        if path.mode == ControlMode::Displacement
            && self.settings.path_following == PathFollowing::Fed
            && dl > 0.0
            && df > 0.0
        {
            path.mode = ControlMode::FreeEnd;
            path.next_step *= df / dl;
        }
        let zone = (self.settings.path_following == PathFollowing::ProcessZone)
            .then(|| self.process_zone(path))
            .flatten();
        match (&zone, path.mode) {
            (Some((_, moved)), ControlMode::Displacement) if dl > 0.0 && !path.zone_paused => {
                path.mode = ControlMode::ProcessZone;
                path.next_step *= moved / dl;
            }
            (None, ControlMode::ProcessZone) => {
                // No point softened in the last step: nothing for the
                // zone's constraint to hold; λ takes the steps again, as
                // long as the last one moved it.
                path.mode = ControlMode::Displacement;
                path.next_step = self.lambda_step(path);
            }
            _ => {}
        }
        match path.mode {
            ControlMode::ProcessZone => {
                let (quantity, moved) = zone.expect("a process zone");
                let size = path.next_step;
                let scale = size / moved;
                self.landing(path, scale).unwrap_or_else(|| Plan {
                    mode: ControlMode::ProcessZone,
                    size,
                    target: quantity.value(&path.u) + size,
                    scale,
                    zone: Some(quantity),
                })
            }
            ControlMode::Displacement => self.by_lambda(path, path.next_step.min(path.curve_step)),
            ControlMode::Energy => {
                let (released, _) = path.last_energies();
                let size = path.next_step;
                let scale = if released > 0.0 { size / released } else { 0.0 };
                self.landing(path, scale).unwrap_or(Plan {
                    mode: ControlMode::Energy,
                    size,
                    target: size,
                    scale,
                    zone: None,
                })
            }
            ControlMode::FreeEnd => {
                let plan = self.by_fed(path, path.next_step, df);
                if path.lambda + plan.scale * dl >= loading.u_final {
                    return self.by_lambda(path, loading.u_final - path.lambda);
                }
                plan
            }
        }
    }

    /// The size of a displacement-controlled step that takes over from
    /// the process zone's control: the last step's |Δλ| within the
    /// loading's bounds.
    fn lambda_step(&self, path: &Path) -> f64 {
        path.last_lambda_increment
            .abs()
            .clamp(self.loading.min_step, self.loading.max_step)
    }

    /// A step prescribing λ `h` further (at most to `u_final`).
    fn by_lambda(&self, path: &Path, h: f64) -> Plan {
        let dl = path.last_lambda_increment;
        let size = h.min(self.loading.u_final - path.lambda);
        Plan {
            mode: ControlMode::Displacement,
            size,
            target: path.lambda + size,
            scale: if dl > 0.0 { size / dl } else { 0.0 },
            zone: None,
        }
    }

    /// The last step of an indirectly controlled run: where a step
    /// repeating `scale` times the last increment would pass `fed_stop`, a
    /// step to it under FED control; where it would pass `u_final`, a
    /// step to it under displacement control.
    fn landing(&self, path: &Path, scale: f64) -> Option<Plan> {
        let df = self.last_fed_increment(path);
        if let Some(stop) = self.loading.fed_stop {
            let fed = self.fed.value(&path.u);
            if fed + scale * df >= stop {
                return Some(self.by_fed(path, stop - fed, df));
            }
        }
        let u_final = self.loading.u_final;
        (path.lambda + scale * path.last_lambda_increment >= u_final)
            .then(|| self.by_lambda(path, u_final - path.lambda))
    }

    /// The process zone's jump quantity and its value for the last
    /// increment (m), `None` when no interface point softened in the last
    /// step. The zone is the node pairs whose λ̃ grew in it; each pair's
    /// jump counts along its last increment Δ[u]_p, scaled so that the
    /// quantity moves by the r.m.s. of |Δ[u]_p| over the zone (pairs
    /// weighted by their area) in a step that repeats the last one:
    /// q(u) = Σ_p w_p Δ[u]_p·[u]_p / (W · rms). The pairs moving fastest
    /// weigh most; pairs outside the zone are free, and so is λ.
    fn process_zone(&self, path: &Path) -> Option<(Quantity, f64)> {
        let du = &path.last_increment;
        if du.is_empty() {
            return None;
        }
        let model = self.problem.model;
        let laws = &self.problem.laws.interfaces;
        let states = &path.committed.interface;
        let mut dense = vec![0.0; du.len()];
        let (mut area, mut squares) = (0.0, 0.0);
        for (e, (element, law)) in model.interfaces.iter().zip(laws).enumerate() {
            if law.is_none() {
                continue;
            }
            let weight = element.area / INTERFACE_POINTS as f64;
            for a in 0..INTERFACE_POINTS {
                if states[e * INTERFACE_POINTS + a].lambda_increment <= 0.0 {
                    continue;
                }
                let (s, c) = (
                    3 * element.nodes[a] as usize,
                    3 * element.nodes[a + INTERFACE_POINTS] as usize,
                );
                area += weight;
                for k in 0..3 {
                    let jump = du[c + k] - du[s + k];
                    squares += weight * jump * jump;
                    dense[c + k] += weight * jump;
                    dense[s + k] -= weight * jump;
                }
            }
        }
        if squares <= 0.0 || !squares.is_finite() {
            return None;
        }
        let rms = (squares / area).sqrt();
        let norm = area * rms;
        dense.iter_mut().for_each(|w| *w /= norm);
        let quantity = Quantity::from_dense(&dense, self.ws.system.dofs(), self.problem.dirichlet);
        Some((quantity, rms))
    }

    /// A step prescribing the FED `size` further (at most to `fed_stop`).
    fn by_fed(&self, path: &Path, size: f64, last_fed_increment: f64) -> Plan {
        let fed = self.fed.value(&path.u);
        let mut size = size;
        if let Some(stop) = self.loading.fed_stop {
            size = size.min(stop - fed).max(self.loading.min_step);
        }
        Plan {
            mode: ControlMode::FreeEnd,
            size,
            target: fed + size,
            scale: if last_fed_increment > 0.0 {
                size / last_fed_increment
            } else {
                0.0
            },
            zone: None,
        }
    }

    /// Attempts one step; on convergence commits it and reports it, on
    /// failure cuts the next step back. Ends the run at the minimum step.
    fn step(&mut self, mut path: Path, observer: &mut dyn Observer) -> Result<Outcome, SolveError> {
        let plan = self.plan(&mut path);
        self.ws.wall = WallTimes::default();
        let t_step = Instant::now();
        self.ws.force_floor = UNLOADED * self.peak_load(&path);
        // Tets made explicit for this step after an attempt in which they
        // switched between damage growing and not (see `retry_explicit`).
        let mut flipped: Vec<usize> = Vec::new();
        // Interface points held at a history for this step after an
        // attempt in which their regime kept switching.
        let mut held: Vec<(usize, HeldHistory)> = Vec::new();
        let mut retries = 0;
        self.ws.holds_pairs = self.holds_pairs(&path);
        let (mut attempt, u_trial, lambda) = loop {
            self.prepare_start(&path, &plan, &flipped, &held);
            let (mut u_trial, mut control) = Self::predict(
                (&self.fed, &self.rates),
                &self.problem,
                self.settings,
                (&path, &plan),
            );
            let step_start = self.extrapolated.as_ref().unwrap_or(&path.committed);
            if plan.mode == ControlMode::Displacement && path.last_increment.is_empty() {
                let mut u = path.u.clone();
                if self.ws.tangent_predictor(step_start, &mut u, plan.size) {
                    self.problem.dirichlet.apply(plan.target, &mut u);
                    u_trial = u;
                }
            }
            let mut attempt = self
                .ws
                .newton(step_start, &mut u_trial, plan.size, &mut control);
            path.summary.total_iterations += attempt.iterations;
            let chattered = attempt.force_only
                && !(attempt.flipping.is_empty() && attempt.flipping_pairs.is_empty());
            let retried = !(flipped.is_empty() && held.is_empty());
            if attempt.failure.is_none() && (chattered || retried) {
                let start = self
                    .extrapolated
                    .get_or_insert_with(|| path.committed.clone());
                attempt = settle_explicit_damage(
                    &mut self.ws,
                    start,
                    (&mut flipped, &mut held),
                    (&mut u_trial, plan.size, &mut control),
                    attempt,
                    &mut path.summary,
                );
            }
            let lambda = control.lambda().unwrap_or(plan.target);
            let most = if self.ws.holds_pairs {
                RETRIES_WITH_HOLDS
            } else {
                RETRIES
            };
            if attempt.failure.is_some() && retries < most {
                let before = flipped.len();
                flipped.extend(attempt.flipping.iter().filter(|&&i| !self.explicit[i]));
                flipped.sort_unstable();
                flipped.dedup();
                // Tets first: their retry settles monotonically. Interface
                // points are held only when no new tet chattered (holding
                // both at once turned retries that the tets alone settle
                // into unsettled ones: docs/solver.md, "Law switches").
                let mut more = flipped.len() > before;
                if !more {
                    let added = hold_pairs(&mut held, &attempt.flipping_pairs, &self.ws.trial);
                    path.summary.held_interface_points += added;
                    more = added > 0;
                }
                if more {
                    retries += 1;
                    path.summary.explicit_retries += 1;
                    self.ws.trial.clone_from(&path.committed);
                    observer.cutback(&Cutback {
                        step: path.rows.len() + 1,
                        u_imposed: lambda,
                        failed_mode: plan.mode,
                        failed_step_size: plan.size,
                        next_mode: plan.mode,
                        next_step_size: plan.size,
                        reason: attempt.failure.clone().expect("a failed attempt"),
                        residual_history: attempt.history.clone(),
                    });
                    continue;
                }
            }
            break (attempt, u_trial, lambda);
        };
        let mut step_wall = self.ws.wall;
        step_wall.total = t_step.elapsed().as_secs_f64();
        self.wall.add(&step_wall);
        let summary = &mut path.summary;
        summary.factorisations = self.ws.lin.factorisations;
        summary.pcg_iterations = self.ws.lin.pcg_iterations;
        summary.krylov_iterations = self.ws.lin.krylov_iterations;
        let review = self.review(
            &mut path,
            &plan,
            (&u_trial, lambda),
            &mut attempt,
            &mut step_wall,
        )?;
        if attempt.failure.is_none() {
            let path = self.commit(
                path,
                &plan,
                (u_trial, lambda),
                (attempt, review),
                step_wall,
                observer,
            )?;
            Ok(match self.ending_after_step(&path) {
                Some(ending) => Outcome::End(ending, path),
                None => Outcome::Continue(path),
            })
        } else {
            self.cut_back(path, &plan, lambda, attempt, observer)
        }
    }

    /// The first iterate of a step and the control that holds it: the
    /// last converged state plus the planned multiple of the last
    /// increment, with the Dirichlet values of the predicted λ.
    fn predict<'b>(
        (fed, rates): (&'b Quantity, &'b [(usize, f64)]),
        problem: &Problem<'b>,
        settings: &SolverSettings,
        (path, plan): (&Path, &'b Plan),
    ) -> (Vec<f64>, Control<'b>) {
        let mut u = path.u.clone();
        if settings.predictor == Predictor::Extrapolate && plan.scale > 0.0 {
            u.iter_mut()
                .zip(&path.last_increment)
                .for_each(|(v, d)| *v += plan.scale * d);
        }
        let dirichlet = problem.dirichlet;
        if plan.mode == ControlMode::Displacement {
            dirichlet.apply(plan.target, &mut u);
            return (u, Control::Displacement);
        }
        let lambda = path.lambda + plan.scale * path.last_lambda_increment;
        dirichlet.apply(lambda, &mut u);
        let constraint = match plan.mode {
            ControlMode::FreeEnd => Constraint::Quantity {
                quantity: fed,
                target: plan.target,
            },
            ControlMode::ProcessZone => Constraint::Quantity {
                quantity: plan.zone.as_ref().expect("a process zone's quantity"),
                target: plan.target,
            },
            _ => Constraint::Energy {
                rates,
                force0: path.load,
                lambda0: path.lambda,
                target: plan.target,
            },
        };
        let control = Control::Indirect(Indirect {
            constraint,
            dirichlet,
            lambda,
            increment: 0.0,
        });
        (u, control)
    }

    /// The states a step starts from: the committed ones, with the damage
    /// of the explicit tets (and of `flipped`) extrapolated over the step;
    /// and the load derivatives' buffer under indirect control.
    fn prepare_start(
        &mut self,
        path: &Path,
        plan: &Plan,
        flipped: &[usize],
        held: &[(usize, HeldHistory)],
    ) {
        self.ws.load = (plan.mode != ControlMode::Displacement)
            .then(|| LoadDerivatives::new(self.ws.system.dofs().n_free()));
        let any = !(flipped.is_empty() && held.is_empty())
            || self.explicit_interface
            || self.explicit.iter().any(|&e| e);
        match (any, self.extrapolated.is_some()) {
            (true, false) => self.extrapolated = Some(path.committed.clone()),
            (false, true) => self.extrapolated = None,
            _ => {}
        }
        if let Some(ex) = self.extrapolated.as_mut() {
            ex.clone_from(&path.committed);
            let laws = &self.problem.laws.tets;
            let explicit = &self.explicit;
            let chosen = (0..ex.bulk.len())
                .filter(|&i| explicit[i])
                .chain(flipped.iter().copied());
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
            for &(i, h) in held {
                ex.interface[i].held = Some(h);
            }
        }
    }

    /// Makes the converged attempt the path's new state, chooses the next
    /// step size and reports the step.
    fn commit(
        &mut self,
        mut path: Path,
        plan: &Plan,
        (u, lambda): (Vec<f64>, f64),
        (attempt, review): (Attempt, Review),
        step_wall: WallTimes,
        observer: &mut dyn Observer,
    ) -> Result<Path, SolveError> {
        path.summary.force_only_steps += usize::from(attempt.force_only);
        path.last_increment.clear();
        path.last_increment
            .extend(u.iter().zip(&path.u).map(|(a, b)| a - b));
        // The planned size itself under displacement control: the sum and
        // difference of λ values would round it.
        path.last_lambda_increment = match plan.mode {
            ControlMode::Displacement => plan.size,
            _ => lambda - path.lambda,
        };
        let load = generalised_load(&self.rates, &self.ws.f_int);
        path.last_load_increment = load - path.load;
        path.load = load;
        path.zone_paused = false;
        path.u = u;
        std::mem::swap(&mut path.committed, &mut self.ws.trial);
        path.steel_yielding = review.changes.steel_yield > 0;
        path.damaging_tets = review.changes.concrete_damage;
        if let Ok(tracker) = &mut self.energy {
            tracker.accept();
        }
        path.lambda = lambda;
        let (force, fed, bond) = review.measured;
        let row = CurveRow {
            step: path.rows.len() + 1,
            u_imposed: path.lambda,
            force,
            fed,
            bond_stress: bond,
            iterations: attempt.iterations,
            impl_ex_error: review.impl_ex_residual,
        };
        path.rows.push(row);
        let summary = &mut path.summary;
        summary.steps = path.rows.len();
        if bond > summary.peak_bond_stress || path.rows.len() == 1 {
            summary.peak_bond_stress = bond;
            summary.fed_at_peak = fed;
        }
        summary.final_fed = fed;
        self.size_next(&mut path, plan, &attempt, &review);
        self.finish(&mut path.summary);
        let h = path.next_step;
        let cp = || self.checkpoint(&path, h);
        let view = CommittedView {
            model: self.problem.model,
            laws: self.problem.laws,
            checkpoint: &cp,
            u: &path.u,
            states: &path.committed,
        };
        observer.step_converged(
            &StepReport {
                row,
                mode: plan.mode,
                step_size: plan.size,
                times: step_wall,
                residual_history: attempt.history,
                force_only: attempt.force_only,
                impl_ex_residual: review.impl_ex_residual,
            },
            &view,
        );
        self.ws.trial.clone_from(&path.committed);
        Ok(path)
    }

    /// The next step's size after a converged one: grown after an easy
    /// step, kept after a hard one, bounded by the IMPL-EX error and,
    /// apart, by the curve's bend; and the switch of control mode.
    fn size_next(&mut self, path: &mut Path, plan: &Plan, attempt: &Attempt, review: &Review) {
        let loading = self.loading;
        // A step the curve's bend shortened says nothing of the size
        // Newton could take: that one stays as it was.
        let for_curve = plan.mode == ControlMode::Displacement && path.curve_step < path.next_step;
        if plan.mode != path.mode || for_curve {
            // A displacement-controlled last step of an indirect run: the
            // next one (if any) keeps the run's mode and size.
        } else if attempt.iterations <= loading.easy_iterations {
            self.rewind = None;
            path.next_step = (plan.size * loading.growth)
                .min(self.max_step(path, plan))
                .max(path.next_step);
        } else if attempt.force_only && self.explicit_interface {
            // Ended on its best iterate (friction points chattering; the
            // interface's damage is explicit): the chatter, not the step,
            // sets the residual (R2's floors did not shrink from 20 nm to
            // 1 nm), so keeping the size would crawl; the next step grows
            // as after an easy one, and a failure cuts it back. Not for
            // the implicit interface, whose runs keep their curves
            // (docs/solver.md, "IMPL-EX interface").
            path.next_step = (plan.size * loading.growth).min(self.max_step(path, plan));
        } else {
            path.next_step = plan.size;
        }
        if self.settings.path_following == PathFollowing::Energy
            || (self.settings.path_following == PathFollowing::Auto
                && path.mode == ControlMode::Energy)
        {
            self.switch_after(path, plan);
        }
        path.curve_step = f64::INFINITY;
        if let Some((deviation, next)) = review.curve {
            let summary = &mut path.summary;
            summary.curve_max_deviation = summary.curve_max_deviation.max(deviation);
            if plan.mode == path.mode {
                path.curve_step = next.max(loading.initial_step);
            }
        }
        if let Some(e) = review.impl_ex_residual {
            let summary = &mut path.summary;
            summary.impl_ex_max_residual = summary.impl_ex_max_residual.max(e);
            // A linear extrapolation's error grows like h² on a
            // smooth history; near R1's adhesion peak it was closer to
            // h (docs/solver.md), and the steps then shrink over
            // several steps instead of one.
            if e > self.settings.impl_ex_tolerance {
                let shrink = (self.settings.impl_ex_tolerance / e).sqrt() * 0.9;
                path.next_step = (plan.size * shrink.max(loading.cutback))
                    .max(loading.min_step)
                    .min(path.next_step);
            }
        }
    }

    /// Whether `plan` is a step of the smallest size of its kind (which
    /// cannot be shortened).
    fn at_min_step(&self, path: &Path, plan: &Plan) -> bool {
        plan.size <= self.min_step(path, plan) * (1.0 + 1e-12)
    }

    /// The smallest step of `plan`'s kind.
    fn min_step(&self, path: &Path, plan: &Plan) -> f64 {
        match plan.mode {
            ControlMode::Energy => self.energy_floor(path),
            _ => self.loading.min_step,
        }
    }

    /// The largest step of `plan`'s kind: under dissipation control the
    /// work of the load over `loading.max_step` (as the floor is over
    /// `min_step`), not the length itself read as joules.
    fn max_step(&self, path: &Path, plan: &Plan) -> f64 {
        match plan.mode {
            ControlMode::Energy => Self::load_work(path, self.loading.max_step),
            _ => self.loading.max_step,
        }
    }

    /// Reports the failed attempt and halves (by `solver.expert.cutback`) the
    /// next try; a failure at the minimum step ends the run.
    fn cut_back(
        &mut self,
        mut path: Path,
        plan: &Plan,
        lambda: f64,
        attempt: Attempt,
        observer: &mut dyn Observer,
    ) -> Result<Outcome, SolveError> {
        let loading = self.loading;
        let converged = matches!(attempt.failure, Some(StepFailure::CurveResolution { .. }));
        if self.rewind.is_none()
            && !converged
            && self.settings.interface_holds == InterfaceHolds::OnStall
            && path.summary.interface_holds_from_step.is_none()
        {
            self.rewind = Some(path.clone());
        }
        let reason = attempt.failure.expect("a failed attempt");
        if !converged {
            path.summary.cutbacks += 1;
        }
        let load_jump = matches!(reason, StepFailure::LoadJump { .. });
        let next = match reason {
            StepFailure::LoadJump { .. } => self.lambda_step(&path),
            StepFailure::CurveResolution { next_step, .. } => next_step,
            _ => plan.size * loading.cutback,
        };
        let energy_step = if load_jump || converged {
            None
        } else {
            self.hand_over(&path, plan)
        };
        self.ws.trial.clone_from(&path.committed);
        let step = path.rows.len() + 1;
        let (next_mode, next_step_size) = match energy_step {
            Some(energy) => (ControlMode::Energy, energy),
            None if load_jump => (ControlMode::Displacement, next),
            None => (plan.mode, next),
        };
        observer.cutback(&Cutback {
            step,
            u_imposed: lambda,
            failed_mode: plan.mode,
            failed_step_size: plan.size,
            next_mode,
            next_step_size,
            reason: reason.clone(),
            residual_history: attempt.history.clone(),
        });
        if load_jump {
            path.mode = ControlMode::Displacement;
            path.zone_paused = true;
            path.next_step = next;
            return Ok(Outcome::Continue(path));
        }
        if converged {
            path.curve_step = next;
            return Ok(Outcome::Continue(path));
        }
        if let Some(energy) = energy_step {
            path.mode = ControlMode::Energy;
            path.next_step = energy;
            return Ok(Outcome::Continue(path));
        }
        let min_step = self.min_step(&path, plan);
        if self.at_min_step(&path, plan) {
            if let Some(limit) = self.limit_load(&path, &reason) {
                return Ok(Outcome::End(limit, path));
            }
            // The held points first: a stalled attempt's iterates can
            // wander to λ < 0 with damage everywhere without a split
            // (the stress sweep's case 21, which the holds carry to its
            // end), so a split is diagnosed only once they were tried.
            if let Some(back) = self.rewind.take() {
                return Ok(Outcome::Continue(self.go_back(back, &path, observer)));
            }
            if let Some(failure) = self.brittle_failure(&path, plan, lambda, &reason) {
                return Ok(Outcome::End(failure, path));
            }
            if self.may_hold_from_start(&path) {
                // Held from the step before the stall, the points did not
                // settle either: the run starts again with them held from
                // step 1, as under `always` (docs/solver.md, "Holds after a
                // stall"). Decided by the summary alone, which checkpoints
                // keep, so a resumed run goes the same way.
                let start = self.start();
                // As at the start: the kept preconditioner of the stalled
                // state would steer the inexact Newton iterates elsewhere
                // (measured: across the snap-back in one step).
                self.ws.lin.refactor = true;
                return Ok(Outcome::Continue(self.go_back(start, &path, observer)));
            }
            return Err(SolveError::Stalled {
                step,
                u_imposed: lambda,
                step_size: plan.size,
                step_unit: plan.mode.step_unit(),
                residual_history: attempt.history,
                cause: Box::new(reason),
                partial: self.partial(path, plan.size),
            });
        }
        if plan.mode == path.mode {
            path.next_step = next.max(min_step);
        }
        Ok(Outcome::Continue(path))
    }

    /// The size (J) of the dissipation-controlled step that follows a
    /// failed displacement-controlled one, if dissipation control takes
    /// over there. Displacement control found no equilibrium just after a
    /// step that dissipated: a snap-back, which dissipation control
    /// follows, its step releasing what the last one did. (After an
    /// elastic step the energy constraint would not respond to λ: the
    /// step is cut back first, nearer to where dissipation starts.)
    fn hand_over(&self, path: &Path, plan: &Plan) -> Option<f64> {
        // `auto` hands over only where displacement control would stop (at
        // the minimum step), so that every run it carries to the end keeps
        // its curve; `energy` at the first failure.
        let allowed = match self.settings.path_following {
            PathFollowing::Energy => true,
            PathFollowing::Auto => self.at_min_step(path, plan),
            _ => false,
        };
        let (released, work) = path.last_energies();
        (allowed
            && plan.mode == ControlMode::Displacement
            && path.mode == ControlMode::Displacement
            && released > STARTS_DISSIPATING * work.abs()
            && !self.unloaded(path))
        .then(|| released.max(self.energy_floor(path)))
    }

    /// The path `back` from before the cut-backs that led to the stall of
    /// `stalled`, from where every step may hold interface points. Holding
    /// them in the stalled state itself does not help: its last steps
    /// ended at the residual tolerance, so even a nanometre step starts
    /// out of balance (docs/solver.md, "Law switches"). The effort spent
    /// since is kept in the counters.
    fn go_back(&mut self, mut back: Path, stalled: &Path, observer: &mut dyn Observer) -> Path {
        let (now, then) = (&stalled.summary, &mut back.summary);
        then.total_iterations = now.total_iterations;
        then.cutbacks = now.cutbacks;
        then.explicit_retries = now.explicit_retries;
        then.damage_passes = now.damage_passes;
        then.held_interface_points = now.held_interface_points;
        then.interface_holds_from_step = Some(back.rows.len() + 1);
        then.dissipation_rejections = now.dissipation_rejections;
        self.ws.trial.clone_from(&back.committed);
        if let Ok(tracker) = &mut self.energy {
            let mut rows = tracker.rows().to_vec();
            rows.truncate(back.rows.len());
            if let Err(e) = tracker.rewind(energy_start(&back, rows)) {
                self.energy = Err(format!("going back to step {}: {e}", back.rows.len()));
            }
        }
        let h = back.next_step;
        let cp = || self.checkpoint(&back, h);
        observer.rewound(
            stalled.rows.len() + 1,
            &CommittedView {
                model: self.problem.model,
                laws: self.problem.laws,
                checkpoint: &cp,
                u: &back.u,
                states: &back.committed,
            },
        );
        back
    }

    /// Whether the next step may hold interface points
    /// (`solver.expert.interface_holds`).
    fn holds_pairs(&self, path: &Path) -> bool {
        match self.settings.interface_holds {
            InterfaceHolds::Off => false,
            InterfaceHolds::OnStall => path.summary.interface_holds_from_step.is_some(),
            InterfaceHolds::Always => true,
        }
    }

    /// The load has fallen to a negligible share of its largest value: the
    /// parts slide freely, nothing is left to release, and displacement
    /// control takes over again.
    fn unloaded(&self, path: &Path) -> bool {
        path.load.abs() <= UNLOADED * self.peak_load(path)
    }

    /// The largest |F| of the converged steps (the model's load, N).
    fn peak_load(&self, path: &Path) -> f64 {
        let factor = self.problem.measurement.force_factor;
        path.rows
            .iter()
            .map(|r| (r.force / factor).abs())
            .fold(0.0, f64::max)
    }

    /// The smallest energy step: the work of the load over `min_step`, J.
    fn energy_floor(&self, path: &Path) -> f64 {
        Self::load_work(path, self.loading.min_step)
    }

    /// The energy a dissipation-controlled step of `length` of λ stands
    /// for: ½ |F| × length, J.
    fn load_work(path: &Path, length: f64) -> f64 {
        0.5 * path.load.abs() * length
    }

    /// Under dissipation control's policy: a dissipative displacement-
    /// controlled step hands over to dissipation control (its released
    /// energy sizes the next step), an elastic dissipation-controlled step
    /// hands back (its Δλ sizes the next step).
    fn switch_after(&self, path: &mut Path, plan: &Plan) {
        let (released, work) = path.last_energies();
        // The size the next step would have (the curve may bound it)
        // over this one's.
        let ratio = path.next_step.min(path.curve_step) / plan.size;
        match plan.mode {
            ControlMode::Displacement
                if path.mode == ControlMode::Displacement
                    && released > DISSIPATIVE * work.abs()
                    && !self.unloaded(path) =>
            {
                path.mode = ControlMode::Energy;
                path.next_step = released * ratio;
            }
            ControlMode::Energy
                if path.last_lambda_increment > 0.0
                    && (released < ELASTIC * work || self.unloaded(path)) =>
            {
                path.mode = ControlMode::Displacement;
                path.next_step = (path.last_lambda_increment * ratio)
                    .clamp(self.loading.min_step, self.loading.max_step);
            }
            _ => {}
        }
    }

    /// Adds this invocation's wall times to the run's so far.
    fn finish(&self, summary: &mut Summary) {
        let mut w = self.previous_wall;
        let mut now = self.wall;
        now.total = self.started.elapsed().as_secs_f64();
        w.add(&now);
        summary.wall_time_s = w;
        // A resumed run reports the larger of its invocations' peaks.
        if let Some(rss) = peak_resident_mib() {
            summary.peak_rss_mib = summary.peak_rss_mib.max(rss);
        }
    }

    fn checkpoint(&self, path: &Path, next_step: f64) -> Checkpoint {
        let model = self.problem.model;
        let lin = &self.ws.lin;
        Checkpoint {
            n_nodes: model.nodes.len(),
            n_tets: model.tets.len(),
            n_interfaces: model.interfaces.len(),
            u_imposed: path.lambda,
            next_step,
            curve_step: path.curve_step,
            control_mode: path.mode,
            u: path.u.clone(),
            states: path.committed.clone(),
            rows: path.rows.clone(),
            summary: path.summary.clone(),
            preconditioner: (self.settings.linear_solver != LinearSolverKind::Cholesky
                && lin.kept.is_ready())
            .then(|| PreconditionerState {
                values: lin.preconditioner.clone(),
                refactor: lin.refactor,
                wear: lin.wear,
            }),
            last_increment: path.last_increment.clone(),
            last_step: path.last_lambda_increment,
            generalised_load: path.load,
            last_load_increment: path.last_load_increment,
            energy: self.energy_rows().unwrap_or_default(),
            record: Default::default(),
        }
    }

    /// The run's result so far, with the state to resume from.
    fn partial(&self, mut path: Path, next_step: f64) -> Box<RunResult> {
        self.finish(&mut path.summary);
        let last = self.checkpoint(&path, next_step);
        Box::new(RunResult {
            rows: path.rows,
            summary: path.summary,
            last,
            ending: Ending::Completed,
            energy: self.energy_rows(),
        })
    }

    /// The energy rows of the converged steps, or why there are none.
    fn energy_rows(&self) -> Result<Vec<EnergyRow>, String> {
        self.energy
            .as_ref()
            .map(|t| t.rows().to_vec())
            .map_err(Clone::clone)
    }
}

/// The converged state of `path` for the energy record to continue from,
/// with `rows` the energies of its steps.
fn energy_start(path: &Path, rows: Vec<EnergyRow>) -> EnergyStart<'_> {
    EnergyStart {
        u: &path.u,
        states: &path.committed,
        rows,
        lambda: path.lambda,
        force: path.rows.last().map_or(0.0, |r| r.force),
    }
}

/// The concrete's averaging operator over the Mazars tets, and their laws
/// in its order.
struct Averaging<'a> {
    operator: GradientAveraging,
    laws: Vec<&'a Mazars>,
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

/// Fixed-point passes on the damage of the tets Newton could not settle:
/// those a retry made explicit, and those that kept switching between
/// damage growing and not in an attempt that ended on its best iterate.
/// Each pass gives them the damage their implicit history reached at the
/// converged displacement (never less than the damage already used) and
/// solves again, until no such tet's damage grows by more than
/// `DAMAGE_SETTLED` and no other tet chatters. The damage used only
/// grows, so the passes cannot cycle as Newton's consistent iterates did;
/// once settled, the stress of every such tet is the one its committed
/// state gives, and the converged state is in equilibrium under the
/// implicit law on the stated criteria. Without the passes the
/// extrapolated damage of a tet passing its threshold lagged the implicit
/// one by so much that committed states were out of balance by up to 95 %
/// of the reaction (docs/solver.md, "Law switches: the explicit retry").
/// The interface points held for the step (or that chattered in an
/// attempt ending on its best iterate) are settled by the same passes: each
/// pass holds them at the history their law reached at the converged jump,
/// and the passes end once the displacement is in balance with that,
/// where a held point's traction is its law's (`InterfaceLaw::held_step`).
/// Their history need not grow monotonically; the passes are bounded by
/// `DAMAGE_PASSES` all the same.
/// Returns the last attempt: a failed pass fails the step; a step whose
/// damage has not settled after `DAMAGE_PASSES` is kept, its residual
/// under the implicit damage reported like IMPL-EX's.
fn settle_explicit_damage(
    ws: &mut Workspace<'_>,
    start: &mut States,
    (flipped, held): (&mut Vec<usize>, &mut Vec<(usize, HeldHistory)>),
    (u, step_size, control): (&mut [f64], f64, &mut Control<'_>),
    mut attempt: Attempt,
    summary: &mut Summary,
) -> Attempt {
    let mut settled = false;
    for _ in 0..DAMAGE_PASSES {
        let mut changed = false;
        if attempt.force_only {
            for &i in &attempt.flipping {
                if start.bulk[i].explicit_damage.is_none() {
                    let state = &mut start.bulk[i];
                    state.explicit_damage = Some(state.damage.max(ws.trial.bulk[i].damage));
                    flipped.push(i);
                    changed = true;
                }
            }
        }
        for &i in flipped.iter() {
            let implicit = ws.trial.bulk[i].damage;
            let state = &mut start.bulk[i];
            let used = state.explicit_damage.unwrap_or(state.damage);
            if implicit > used + DAMAGE_SETTLED {
                state.explicit_damage = Some(implicit);
                changed = true;
            }
        }
        if attempt.force_only {
            let added = hold_pairs(held, &attempt.flipping_pairs, &ws.trial);
            summary.held_interface_points += added;
            changed |= added > 0;
        }
        // A held point takes the history its law reached at the converged
        // jump; the balance check below then decides whether that moved
        // the equilibrium.
        changed |= rehold(held, start, &ws.trial);
        if !changed {
            settled = true;
            break;
        }
        // Often the converged displacement is already in balance under the
        // updated damage (it grew by little): one force evaluation then
        // spares a Newton solve. An attempt that ended on its best iterate
        // has not met the energy criterion: it gets the solve.
        let balanced = if attempt.force_only {
            Ok((false, f64::INFINITY))
        } else {
            in_balance(ws, start, u, step_size, control)
        };
        match balanced {
            Ok((true, _)) => {
                settled = true;
                break;
            }
            Ok((false, _)) => {}
            Err(source) => {
                let why = StepFailure::Constitutive {
                    in_line_search: false,
                    source,
                };
                attempt.failure = Some(why);
                break;
            }
        }
        let pass = ws.newton(start, u, step_size, control);
        summary.total_iterations += pass.iterations;
        summary.damage_passes += 1;
        let iterations = attempt.iterations + pass.iterations;
        attempt = Attempt { iterations, ..pass };
        if attempt.failure.is_some() {
            break;
        }
    }
    // Damage only grows, so unsettled tets leave a bounded residual, which
    // is reported; held points can wander, so theirs fails the attempt.
    if !settled && attempt.failure.is_none() && !held.is_empty() {
        rehold(held, start, &ws.trial);
        match in_balance(ws, start, u, step_size, control) {
            Ok((true, _)) => {}
            Ok((false, relative_residual)) => {
                attempt.failure = Some(StepFailure::Unsettled {
                    points: held.len(),
                    passes: DAMAGE_PASSES,
                    relative_residual,
                    regimes: RegimeChanges::between(start, &ws.trial),
                })
            }
            Err(source) => {
                attempt.failure = Some(StepFailure::Constitutive {
                    in_line_search: false,
                    source,
                })
            }
        }
    }
    flipped.sort_unstable();
    flipped.dedup();
    attempt
}

/// Holds each held point at the history its law reached in `trial` (at
/// the converged jump), in `held` and in `start`; whether any moved.
fn rehold(held: &mut [(usize, HeldHistory)], start: &mut States, trial: &States) -> bool {
    let mut moved = false;
    for (i, h) in held.iter_mut() {
        let implicit = HeldHistory::of(&trial.interface[*i]);
        if implicit != *h {
            *h = implicit;
            moved = true;
        }
        start.interface[*i].held = Some(*h);
    }
    moved
}

/// Hands the points a retry treated apart back to their laws. A tet made
/// explicit for this step only goes back to the implicit integration,
/// keeping the damage its stress used where that is the larger: the state
/// then matches the equilibrium just found, and the energy it released
/// stays dissipated. A held interface point likewise keeps the history its
/// implicit update reached (the hold's, once settled).
fn release_retried(committed: &mut States, explicit: &[bool]) {
    for (s, &always) in committed.bulk.iter_mut().zip(explicit) {
        if !always {
            if let Some(used) = s.explicit_damage.take() {
                s.damage = s.damage.max(used);
            }
        }
    }
    for s in &mut committed.interface {
        if let Some(h) = s.held.take() {
            s.damage = s.damage.max(h.damage);
        }
    }
}

/// Adds the interface points `flipping` not held yet to `held`, each held
/// at the history of its last iterate in `trial`; returns how many.
fn hold_pairs(held: &mut Vec<(usize, HeldHistory)>, flipping: &[usize], trial: &States) -> usize {
    let before = held.len();
    // At the paper's mesh tens of thousands of points flip in one iterate:
    // a scan of `held` per point would be quadratic.
    let mut known: std::collections::HashSet<usize> = held.iter().map(|&(j, _)| j).collect();
    for &i in flipping {
        if known.insert(i) {
            held.push((i, HeldHistory::of(&trial.interface[i])));
        }
    }
    held.len() - before
}

/// Whether `u` meets the force criterion (and the control's constraint)
/// from the start states `start`, and its relative residual; leaves the
/// trial states and internal forces of `u` in the workspace.
fn in_balance(
    ws: &mut Workspace<'_>,
    start: &States,
    u: &[f64],
    step_size: f64,
    control: &Control<'_>,
) -> Result<(bool, f64), AssemblyError> {
    let system: &System = ws.system;
    system.evaluate(
        ws.laws,
        u,
        start,
        &mut ws.trial,
        Tangents::all(TangentKind::Secant),
        Outputs::forces_of_stresses(&mut ws.f_int),
    )?;
    let mut r = vec![0.0; system.dofs().n_free()];
    ws.residual(&mut r);
    let scale = ws.force_scale();
    let tolerance = ws.settings.residual_tolerance;
    let held = match control {
        Control::Displacement => true,
        Control::Indirect(c) => {
            c.constraint.residual(u, c.lambda, &ws.f_int).abs()
                <= c.constraint.tolerance(tolerance, step_size)
        }
    };
    let relative = norm(&r) / scale;
    Ok((held && relative <= tolerance, relative))
}

/// The process's peak resident memory so far, MiB (Linux `VmHWM`); `None`
/// where /proc is not available.
fn peak_resident_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}
