//! Adaptive load stepping: λ (the imposed displacement) from the start or
//! a checkpoint to the end of the loading, one Newton attempt per try,
//! cut-back on failure, growth after easy steps, IMPL-EX step control, and
//! the committed state offered to the observer after every converged step.

use super::checkpoint::{Checkpoint, PreconditionerState};
use super::correction::LinearState;
use super::failure::SolveError;
use super::problem::{Dirichlet, Measurement};
use super::report::{
    CommittedView, CurveRow, Cutback, Observer, RunResult, StepReport, Summary, WallTimes,
};
use super::workspace::{reaction_norm, residual, Workspace};
use crate::assembly::{AssemblyError, ElementLaws, Outputs, States, System, Tangents};
use crate::laws::TangentKind;
use crate::linear::norm;
use crate::spec::solver::{
    ConcreteIntegration, LinearSolverKind, Loading, Predictor, SolverSettings,
};
use mesh::Model;
use std::time::Instant;

/// The converged state of a run between steps.
struct Path {
    /// Global displacement, m.
    u: Vec<f64>,
    committed: States,
    rows: Vec<CurveRow>,
    summary: Summary,
    /// λ of the last converged step, m.
    lambda: f64,
    /// Size of the next step to try, m.
    next_step: f64,
    /// Increment and size of the last converged step (the predictor's).
    last_increment: Vec<f64>,
    last_step: f64,
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
    let system = System::new(model, &dirichlet.dofs, &dirichlet.load_rates(), &active)?;
    let n_total = system.dofs().n_total();
    let n_free = system.dofs().n_free();
    let lin = LinearState::new(&system, settings, &mut wall)?;
    let mut ws = Workspace {
        system: &system,
        laws,
        settings,
        trial: States::default(),
        f_int: vec![0.0; n_total],
        lower: vec![0.0; system.nnz()],
        upper: if settings.tangent == TangentKind::Consistent {
            vec![0.0; system.nnz()]
        } else {
            Vec::new()
        },
        lin,
        wall: WallTimes::default(),
    };
    let mut path = match checkpoint {
        Some(cp) => resume(&mut ws, model, cp, n_total, &mut wall)?,
        None => Path {
            u: vec![0.0; n_total],
            committed: States::initial(model),
            rows: Vec::new(),
            summary: Summary {
                dofs: n_free,
                ..Summary::default()
            },
            lambda: 0.0,
            next_step: loading.initial_step,
            last_increment: Vec::new(),
            last_step: 0.0,
        },
    };
    let previous_wall = path.summary.wall_time_s;
    path.summary.wall_time_s = WallTimes::default();
    ws.trial = path.committed.clone();
    let done_eps = 1e-9 * loading.u_final;

    let make_cp = |path: &Path, h: f64, lin: &LinearState| Checkpoint {
        n_nodes: model.nodes.len(),
        n_tets: model.tets.len(),
        n_interfaces: model.interfaces.len(),
        u_imposed: path.lambda,
        next_step: h,
        u: path.u.clone(),
        states: path.committed.clone(),
        rows: path.rows.clone(),
        summary: path.summary.clone(),
        preconditioner: (settings.linear_solver != LinearSolverKind::Cholesky
            && lin.chol.is_factored())
        .then(|| PreconditionerState {
            values: lin.preconditioner.clone(),
            refactor: lin.refactor,
        }),
        last_increment: path.last_increment.clone(),
        last_step: path.last_step,
    };
    let finish = |summary: &mut Summary, wall: &WallTimes| {
        let mut w = previous_wall;
        let mut now = *wall;
        now.total = t_start.elapsed().as_secs_f64();
        w.add(&now);
        summary.wall_time_s = w;
    };
    let partial = |mut path: Path, h: f64, lin: &LinearState, wall: &WallTimes| {
        finish(&mut path.summary, wall);
        let last = make_cp(&path, h, lin);
        Box::new(RunResult {
            rows: path.rows,
            summary: path.summary,
            last,
        })
    };

    // IMPL-EX: the committed states with the extrapolated damage of the
    // step being attempted.
    let mut extrapolated = (settings.concrete_integration == ConcreteIntegration::ImplEx)
        .then(|| path.committed.clone());

    loop {
        let fed_done = loading
            .fed_stop
            .is_some_and(|s| path.rows.last().is_some_and(|r: &CurveRow| r.fed >= s));
        if path.lambda >= loading.u_final - done_eps || fed_done {
            break;
        }
        if let Some(max_steps) = loading.max_steps.filter(|&m| path.rows.len() >= m) {
            let u_imposed = path.lambda;
            let h = path.next_step;
            return Err(SolveError::StepLimit {
                max_steps,
                u_imposed,
                partial: partial(path, h, &ws.lin, &wall),
            });
        }
        let step = path.rows.len() + 1;
        let h_try = path.next_step.min(loading.u_final - path.lambda);
        let target = path.lambda + h_try;
        ws.wall = WallTimes::default();
        let t_step = Instant::now();
        let mut u_trial = path.u.clone();
        if settings.predictor == Predictor::Extrapolate && path.last_step > 0.0 {
            let s = h_try / path.last_step;
            u_trial
                .iter_mut()
                .zip(&path.last_increment)
                .for_each(|(v, d)| *v += s * d);
        }
        dirichlet.apply(target, &mut u_trial);
        if let Some(ex) = extrapolated.as_mut() {
            ex.clone_from(&path.committed);
            let ratio = if path.last_step > 0.0 {
                h_try / path.last_step
            } else {
                0.0
            };
            for (state, law) in ex.bulk.iter_mut().zip(&laws.tets) {
                *state = law.extrapolate(state, ratio);
            }
        }
        let step_start = extrapolated.as_ref().unwrap_or(&path.committed);
        let attempt = ws.newton(step_start, &mut u_trial, h_try);
        let mut step_wall = ws.wall;
        step_wall.total = t_step.elapsed().as_secs_f64();
        wall.add(&step_wall);
        let summary = &mut path.summary;
        summary.total_iterations += attempt.iterations;
        summary.factorisations = ws.lin.factorisations;
        summary.pcg_iterations = ws.lin.pcg_iterations;
        summary.krylov_iterations = ws.lin.krylov_iterations;
        match attempt.failure {
            None => {
                summary.force_only_steps += usize::from(attempt.force_only);
                path.last_increment.clear();
                path.last_increment
                    .extend(u_trial.iter().zip(&path.u).map(|(a, b)| a - b));
                path.last_step = h_try;
                path.u = u_trial;
                std::mem::swap(&mut path.committed, &mut ws.trial);
                path.lambda = target;
                let (force, fed, bond) = measurement.eval(&path.u, &ws.f_int);
                let row = CurveRow {
                    step,
                    u_imposed: path.lambda,
                    force,
                    fed,
                    bond_stress: bond,
                    iterations: attempt.iterations,
                };
                path.rows.push(row);
                let summary = &mut path.summary;
                summary.steps = path.rows.len();
                if bond > summary.peak_bond_stress || path.rows.len() == 1 {
                    summary.peak_bond_stress = bond;
                    summary.fed_at_peak = fed;
                }
                summary.final_fed = fed;
                let mut h = if attempt.iterations <= loading.easy_iterations {
                    (h_try * loading.growth)
                        .min(loading.max_step)
                        .max(path.next_step)
                } else {
                    h_try
                };
                let impl_ex_residual = match extrapolated.as_mut() {
                    Some(scratch) => {
                        let t = Instant::now();
                        let e = implicit_residual(
                            &system,
                            laws,
                            &path.committed,
                            &path.u,
                            scratch,
                            &mut ws.trial,
                            &mut ws.f_int,
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
                path.next_step = h;
                finish(&mut path.summary, &wall);
                let cp = || make_cp(&path, h, &ws.lin);
                let view = CommittedView {
                    model,
                    laws,
                    checkpoint: &cp,
                    u: &path.u,
                    states: &path.committed,
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
                ws.trial.clone_from(&path.committed);
            }
            Some(reason) => {
                summary.cutbacks += 1;
                let next = h_try * loading.cutback;
                ws.trial.clone_from(&path.committed);
                observer.cutback(&Cutback {
                    step,
                    u_imposed: target,
                    failed_step_size: h_try,
                    next_step_size: next,
                    reason: reason.clone(),
                    residual_history: attempt.history.clone(),
                });
                if h_try <= loading.min_step * (1.0 + 1e-12) {
                    return Err(SolveError::Stalled {
                        step,
                        u_imposed: target,
                        step_size: h_try,
                        residual_history: attempt.history,
                        cause: Box::new(reason),
                        partial: partial(path, h_try, &ws.lin, &wall),
                    });
                }
                path.next_step = next.max(loading.min_step);
            }
        }
    }
    let h = path.next_step;
    let result = partial(path, h, &ws.lin, &wall);
    Ok(*result)
}

/// The run's state from a checkpoint taken on the same model; restores the
/// kept preconditioner so that the resumed iterates equal the
/// uninterrupted run's.
fn resume(
    ws: &mut Workspace<'_>,
    model: &Model,
    cp: Checkpoint,
    n_total: usize,
    wall: &mut WallTimes,
) -> Result<Path, SolveError> {
    cp.check_matches(model, n_total)
        .map_err(SolveError::Checkpoint)?;
    let lin = &mut ws.lin;
    if let Some(p) = cp.preconditioner {
        // Rebuild the uninterrupted run's factor from its values (a
        // restore, not counted among the run's factorisations).
        if p.values.len() == lin.preconditioner.len() {
            let t = Instant::now();
            lin.chol.factorize(&p.values)?;
            wall.factorisation += t.elapsed().as_secs_f64();
            lin.preconditioner = p.values;
            lin.refactor = p.refactor;
        }
    }
    let (last_increment, last_step) = if cp.last_increment.len() == n_total {
        (cp.last_increment, cp.last_step)
    } else {
        (Vec::new(), 0.0)
    };
    lin.factorisations = cp.summary.factorisations;
    lin.pcg_iterations = cp.summary.pcg_iterations;
    lin.krylov_iterations = cp.summary.krylov_iterations;
    Ok(Path {
        u: cp.u,
        committed: cp.states,
        rows: cp.rows,
        summary: cp.summary,
        lambda: cp.u_imposed,
        next_step: cp.next_step,
        last_increment,
        last_step,
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
    system.evaluate(
        laws,
        u,
        scratch,
        trial,
        Tangents::all(TangentKind::Secant),
        Outputs::forces(f_int),
    )?;
    let mut r = vec![0.0; system.dofs().n_free()];
    residual(system.dofs(), f_int, &mut r);
    let reaction = reaction_norm(system, f_int);
    Ok(norm(&r) / if reaction > 0.0 { reaction } else { 1.0 })
}
