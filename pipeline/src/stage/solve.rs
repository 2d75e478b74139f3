//! The solve stage: loads the mesh stage's model, builds the per-element
//! laws, runs the pull-out (resuming from the in-progress checkpoint when
//! there is one), and writes `curve.csv`, `solve.json`, the requested VTU
//! fields and the interface traction profiles along the bar.
//!
//! The solver tracks the energy balance of every converged step
//! (`solve::energy`; it refuses states that create energy): `curve.csv`
//! carries the energy columns (J, whole specimen;
//! `solve::curve::ENERGY_COLUMNS`) after the curve's, and `solve.json` an
//! `energy_check` object. Everything a resumed run needs (the solver's
//! state with the energy rows, and in `Checkpoint::record` the interface
//! profiles so far) is in the one checkpoint file, so a resumed run
//! continues the sums and writes the same values as an uninterrupted one.

use super::ctx::Ctx;
use super::kinds::{Stage, CHECKPOINT_FILE};
use anyhow::Result;
use mesh::Model;
use solve::assembly::{ElementLaws, States};
use solve::curve::CurveRow;
use solve::energy::ENERGY_TOLERANCE;
use solve::fields::ProfileRow;
use solve::nonlinear::{
    Checkpoint, CommittedView, Cutback, Observer, ObserverRecord, RunResult, SolveError, StepReport,
};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// A checkpoint is written after a converged step once the time since the
/// last one is this many times what writing the last one took: writing
/// then costs at most ~5 % of the run whatever the model's size, and a
/// resumed run repeats little work (every step on small models).
const CHECKPOINT_COST_RATIO: u32 = 20;

struct StageObserver<'a> {
    ctx: &'a Ctx<'a>,
    laws: &'a ElementLaws,
    checkpoint_path: PathBuf,
    fields_dir: PathBuf,
    /// The whole specimen of a half or quarter model, when its fields are
    /// asked for on it (`outputs.fields.whole_specimen`).
    whole: Option<mesh::Unfolded>,
    /// Interface profiles of the field steps, and of the current peak (each
    /// new maximum replaces it); saved in the checkpoint.
    profile: Vec<ProfileRow>,
    peak_profile: Vec<ProfileRow>,
    last_checkpoint: Instant,
    checkpoint_cost: Duration,
    peak: f64,
    /// Set once σ_mb has dropped below the peak by more than
    /// `post::FIRST_PEAK_DROP`: the peak fields are then the adhesion peak's
    /// and a later frictional maximum does not replace them.
    peak_passed: bool,
    /// The state of the highest step so far, while the peak is not passed:
    /// written once (when the curve has dropped past it, before a
    /// checkpoint, and at the end), not at every rising step. On R1 the
    /// rising branch is 24 steps of 60 MB of fields each.
    pending_peak: Option<PeakState>,
    error: Option<anyhow::Error>,
    cutbacks: Vec<String>,
}

/// A converged state kept for the peak fields.
struct PeakState {
    row: CurveRow,
    u: Vec<f64>,
    states: States,
}

impl PeakState {
    /// Keeps (`row`, `u`, `states`) in `slot`, into the vectors already
    /// there: while the curve rises this copies tens of MB a step on R1.
    fn keep(slot: &mut Option<PeakState>, row: CurveRow, (u, states): (&[f64], &States)) {
        let p = slot.get_or_insert_with(|| PeakState {
            row,
            u: Vec::new(),
            states: States::default(),
        });
        p.row = row;
        p.u.clear();
        p.u.extend_from_slice(u);
        p.states.clone_from(states);
    }
}

impl StageObserver<'_> {
    fn write_fields(
        &mut self,
        name: &str,
        row: &CurveRow,
        model: &Model,
        (u, states): (&[f64], &States),
    ) -> Result<()> {
        std::fs::create_dir_all(&self.fields_dir)?;
        solve::fields::write_bulk_vtu(
            &self.fields_dir.join(format!("{name}_bulk.vtu")),
            model,
            self.laws,
            u,
            states,
            self.whole.as_ref(),
        )?;
        solve::fields::write_interface_vtu(
            &self.fields_dir.join(format!("{name}_interface.vtu")),
            model,
            self.laws,
            u,
            states,
            self.whole.as_ref(),
        )?;
        let rows = solve::fields::profile_rows(model, self.laws, u, states, row.step, row.fed);
        if name == "peak" {
            self.peak_profile = rows;
        } else {
            self.profile.extend(rows);
        }
        Ok(())
    }

    /// Writes the solver's `checkpoint` of a converged state of `model`,
    /// with this observer's record, the peak's fields first: a resumed run
    /// never rewrites a peak it has already passed.
    fn save_checkpoint(
        &mut self,
        model: &Model,
        checkpoint: impl FnOnce() -> Checkpoint,
    ) -> Result<()> {
        // The peak's fields count in the cost: while the curve rises they
        // are written with every checkpoint.
        let started = Instant::now();
        self.write_pending_peak(model)?;
        let mut checkpoint = checkpoint();
        checkpoint.record = ObserverRecord {
            profile: self.profile.clone(),
            peak_profile: self.peak_profile.clone(),
        };
        checkpoint.save(&self.checkpoint_path, checkpoint_key(self.ctx))?;
        self.checkpoint_cost = started.elapsed();
        self.last_checkpoint = Instant::now();
        Ok(())
    }

    /// Ends the process after a SIGTERM (`crate::termination`), the
    /// checkpoint of step `row` written (`saved`): nothing is committed, so
    /// a rerun resumes from this step.
    fn exit_terminated(&self, row: &CurveRow, saved: Result<()>) -> ! {
        self.ctx.printer.finish();
        let checkpoint = self.checkpoint_path.display();
        match saved {
            Ok(()) => eprintln!(
                "{}solve of {} stopped by SIGTERM after step {} (u = {:.4} mm); its checkpoint \
                 {checkpoint} resumes it on the next run",
                crate::child::ERROR_PREFIX,
                self.ctx.scene.name,
                row.step,
                row.u_imposed * 1e3
            ),
            Err(e) => eprintln!(
                "{}solve of {} stopped by SIGTERM after step {}; writing its checkpoint \
                 {checkpoint} failed ({e:#}), the next run resumes from an earlier one or \
                 starts over",
                crate::child::ERROR_PREFIX,
                self.ctx.scene.name,
                row.step
            ),
        }
        std::process::exit(crate::termination::TERMINATED_EXIT)
    }

    /// Writes the kept peak state's fields, if one is waiting.
    fn write_pending_peak(&mut self, model: &Model) -> Result<()> {
        match self.pending_peak.take() {
            Some(p) => self.write_fields("peak", &p.row, model, (&p.u, &p.states)),
            None => Ok(()),
        }
    }
}

impl Observer for StageObserver<'_> {
    fn step_converged(&mut self, report: &StepReport, view: &CommittedView<'_>) {
        let r = &report.row;
        self.ctx.printer.progress(&format!(
            "solve: step {:>4}  u = {:.4} mm  FED = {:.4} mm  σ_mb = {:.3} MPa  iterations {}",
            r.step,
            r.u_imposed * 1e3,
            r.fed * 1e3,
            r.bond_stress / 1e6,
            r.iterations
        ));
        let t = &report.times;
        self.ctx.printer.detail(&format!(
            "solve:   step size {:.3e} {}; relative residuals [{}]{}{}; assembly {:.2} s, constitutive {:.2} s, factorisation {:.2} s, linear solve {:.2} s",
            report.step_size,
            report.mode.step_unit(),
            residual_list(&report.residual_history),
            if report.force_only {
                " (stagnating: ended on the best iterate)"
            } else {
                ""
            },
            report
                .impl_ex_residual
                .map(|e| format!("; IMPL-EX residual under the implicit damage {e:.2e}"))
                .unwrap_or_default(),
            t.assembly,
            t.constitutive,
            t.factorisation,
            t.solve
        ));
        if self.error.is_some() {
            // Outputs failed before: no checkpoint is written any more, but
            // a SIGTERM still ends the run here rather than at SIGKILL.
            if crate::termination::requested() {
                self.exit_terminated(r, Err(anyhow::anyhow!("an earlier output failed")));
            }
            return;
        }
        let request = &self.ctx.scene.outputs.fields;
        let mut result = Ok(());
        let state = (view.u, view.states);
        if request.steps.contains(&r.step) {
            result = self.write_fields(&format!("step{:04}", r.step), r, view.model, state);
        }
        if r.bond_stress < (1.0 - crate::post::FIRST_PEAK_DROP) * self.peak && !self.peak_passed {
            self.peak_passed = true;
            result = result.and_then(|()| self.write_pending_peak(view.model));
        }
        if request.at_peak && !self.peak_passed && r.bond_stress > self.peak && result.is_ok() {
            self.peak = r.bond_stress;
            PeakState::keep(&mut self.pending_peak, *r, state);
        }
        let terminated = crate::termination::requested();
        if result.is_ok()
            && (terminated
                || self.last_checkpoint.elapsed() >= self.checkpoint_cost * CHECKPOINT_COST_RATIO)
        {
            result = self.save_checkpoint(view.model, view.checkpoint);
        }
        if terminated {
            self.exit_terminated(r, result);
        }
        if let Err(e) = result {
            self.error = Some(e);
        }
    }

    fn rewound(&mut self, stalled: usize, view: &CommittedView<'_>) {
        // Built once: the state to go back to is also what is saved.
        let checkpoint = (view.checkpoint)();
        let kept = &checkpoint.state.path.rows;
        self.ctx.printer.line(&if kept.is_empty() {
            format!(
                "solve: step {stalled} stalled with interface points held; starting again \
                 with them held from step 1 (solver.expert.interface_holds: on_stall)"
            )
        } else {
            format!(
                "solve: step {stalled} stalled; going back to step {} (u = {:.4} mm), from where \
                 interface points that chatter may be held (solver.expert.interface_holds: on_stall)",
                kept.len(),
                checkpoint.state.path.lambda * 1e3
            )
        });
        let discarded = |step: usize| step > kept.len();
        self.profile.retain(|r| !discarded(r.step));
        // Fields of discarded steps: rewritten if the run reaches those
        // steps again, and must not outlive it if it does not.
        for &step in self
            .ctx
            .scene
            .outputs
            .fields
            .steps
            .iter()
            .filter(|&&s| discarded(s))
        {
            for part in ["bulk", "interface"] {
                let _ =
                    std::fs::remove_file(self.fields_dir.join(format!("step{step:04}_{part}.vtu")));
            }
        }
        let peak_discarded = self
            .pending_peak
            .as_ref()
            .is_some_and(|p| discarded(p.row.step))
            || self.peak_profile.first().is_some_and(|r| discarded(r.step));
        if peak_discarded {
            // The peak so far was a discarded step's: the kept steps' own
            // maximum is waiting again if it is the last kept step (a
            // rising curve), else the next higher step takes its place.
            self.pending_peak = None;
            self.peak_profile.clear();
            self.peak_passed = false;
            self.peak = kept.iter().map(|r| r.bond_stress).fold(0.0, f64::max);
            if let Some(last) = kept.last().filter(|r| r.bond_stress >= self.peak) {
                if self.ctx.scene.outputs.fields.at_peak {
                    PeakState::keep(&mut self.pending_peak, *last, (view.u, view.states));
                }
            }
        }
        // A resume from here must not find a checkpoint of a discarded step.
        if self.error.is_none() {
            if let Err(e) = self.save_checkpoint(view.model, || checkpoint) {
                self.error = Some(e);
            }
        }
    }

    fn cutback(&mut self, event: &Cutback) {
        let text = format!(
            "step {} at u = {:.4e} m: {}; step {:.3e} {} → {:.3e} {}",
            event.step,
            event.u_imposed,
            event.reason,
            event.failed_step_size,
            event.failed_mode.step_unit(),
            event.next_step_size,
            event.next_mode.step_unit(),
        );
        self.ctx.printer.detail(&format!(
            "solve: cut back: {text}; relative residuals [{}]",
            residual_list(&event.residual_history)
        ));
        self.cutbacks.push(text);
    }
}

/// Relative residuals as `-v` prints them: three digits each.
fn residual_list(history: &[f64]) -> String {
    history
        .iter()
        .map(|v| format!("{v:.2e}"))
        .collect::<Vec<_>>()
        .join(", ")
}

pub fn run(ctx: &Ctx, out: &Path) -> Result<()> {
    let mesh_dir = ctx.done_dir(Stage::Mesh);
    let mesh_dir = mesh_dir.as_path();
    let model = Model::load(&mesh_dir.join(mesh::MODEL_FILE))?;
    let laws = ctx
        .scene
        .materials
        .element_laws(&model, ctx.scene.specimen.non_adhesive)?;
    let checkpoint_path = out.join(CHECKPOINT_FILE);
    let mut checkpoint = load_checkpoint(ctx, out)?;
    // A scheduler's SIGTERM stops the solve at its next converged step.
    let sigterm = crate::termination::catch_sigterm();
    let (outcome, mut observer) = loop {
        let resumed = checkpoint.is_some();
        let mut observer = new_observer(ctx, &laws, &model, out, checkpoint.as_ref())?;
        let outcome = solve::problems::pullout::solve_pullout(
            &model,
            &laws,
            &ctx.scene.loading,
            &ctx.scene.solver,
            checkpoint.take(),
            &mut observer,
        );
        match outcome {
            // A whole checkpoint of this key taken on another model: not
            // one to resume from either.
            Err(SolveError::Checkpoint(why)) if resumed => set_aside(ctx, out, &why)?,
            outcome => break (outcome, observer),
        }
    };
    drop(sigterm);
    ctx.printer.finish();
    if let Some(e) = observer.error.take() {
        return Err(e.context("writing solve outputs"));
    }
    // The peak's fields go to disk whatever the outcome.
    let peak_written = observer.write_pending_peak(&model);
    let (result, stopped) = split_outcome(outcome)?;
    peak_written?;
    if ctx.scene.outputs.fields.at_end {
        write_end_fields(&mut observer, &model, &result)?;
    }
    write_collection(&observer.fields_dir, &result.rows, observer.peak)?;
    let profile = [observer.profile.as_slice(), &observer.peak_profile].concat();
    crate::store::write_atomic(
        &out.join("interface_profile.csv"),
        solve::fields::write_profile_csv(&profile).as_bytes(),
    )?;
    let energy_rows = result.energy.as_deref().ok();
    let energy_check = energy_check_json(ctx, &result)?;
    crate::store::write_atomic(
        &out.join("curve.csv"),
        solve::curve::write_curve_csv(&result.rows, energy_rows).as_bytes(),
    )?;
    report_ending(ctx, &result.ending);
    let solve_json = serde_json::json!({
        "summary": result.summary,
        "completed": stopped.is_none(),
        // A run stopped for a numerical reason has not ended in any of
        // the ways `ending` names.
        "ending": stopped.is_none().then_some(&result.ending),
        "stopped": stopped,
        "cutbacks": observer.cutbacks,
        "energy_check": energy_check,
    });
    crate::store::write_atomic(
        &out.join("solve.json"),
        &serde_json::to_vec_pretty(&solve_json)?,
    )?;
    let _ = std::fs::remove_file(&checkpoint_path);
    if let Some(why) = &stopped {
        // The converged part is a result like any other (a rerun with the
        // same inputs would stop at the same step): it is committed, post
        // runs on it, and `run` exits non-zero while it stands.
        ctx.printer.line(&format!("solve: stopped early: {why}"));
    }
    Ok(())
}

/// The observer of a run from `checkpoint` (or from the start).
fn new_observer<'a>(
    ctx: &'a Ctx<'a>,
    laws: &'a ElementLaws,
    model: &Model,
    out: &Path,
    checkpoint: Option<&Checkpoint>,
) -> Result<StageObserver<'a>> {
    let (peak_so_far, peak_passed) = peak_before(checkpoint)?;
    let record = checkpoint.map(|cp| cp.record.clone()).unwrap_or_default();
    Ok(StageObserver {
        ctx,
        laws,
        checkpoint_path: out.join(CHECKPOINT_FILE),
        fields_dir: out.join("fields"),
        whole: (ctx.scene.outputs.fields.whole_specimen && model.symmetry != mesh::Symmetry::Full)
            .then(|| model.unfold()),
        profile: record.profile,
        peak_profile: record.peak_profile,
        last_checkpoint: Instant::now(),
        checkpoint_cost: Duration::ZERO,
        peak: peak_so_far,
        peak_passed,
        pending_peak: None,
        error: None,
        cutbacks: Vec::new(),
    })
}

/// The key a checkpoint of this stage carries: the solve stage's own.
fn checkpoint_key<'k>(ctx: &'k Ctx) -> &'k str {
    &ctx.keys.get(Stage::Solve).key
}

/// The in-progress checkpoint in `out`, if there is a usable one. One that
/// is damaged, of another version or of another run is moved to the
/// quarantine (the message names both paths) and the solve starts over;
/// so does a solve without a checkpoint, from an emptied folder.
fn load_checkpoint(ctx: &Ctx, out: &Path) -> Result<Option<Checkpoint>> {
    let checkpoint_path = out.join(CHECKPOINT_FILE);
    if !checkpoint_path.is_file() {
        clear(out)?;
        return Ok(None);
    }
    match Checkpoint::load(&checkpoint_path, checkpoint_key(ctx)) {
        Ok(cp) => {
            ctx.printer.line(&format!(
                "solve: resuming after step {} (u = {:.4} mm)",
                cp.state.path.rows.len(),
                cp.state.path.lambda * 1e3
            ));
            Ok(Some(cp))
        }
        Err(e) => {
            set_aside(ctx, out, &e.to_string())?;
            Ok(None)
        }
    }
}

/// Moves the unusable checkpoint in `out` to the quarantine, saying why,
/// and empties `out` for a run from the start.
fn set_aside(ctx: &Ctx, out: &Path, why: &str) -> Result<()> {
    let path = out.join(CHECKPOINT_FILE);
    let moved = ctx
        .store
        .quarantine(&path, &format!("solve-{}-checkpoint", checkpoint_key(ctx)))?;
    ctx.printer.line(&format!(
        "solve: not resuming from {}: {why}; moved to {}; starting over",
        path.display(),
        moved.display()
    ));
    clear(out)
}

/// Empties the in-progress folder `out` (files of a run that is not
/// continued).
fn clear(out: &Path) -> Result<()> {
    for entry in std::fs::read_dir(out)? {
        let path = entry?.path();
        if path.is_dir() {
            std::fs::remove_dir_all(&path)?;
        } else {
            std::fs::remove_file(&path)?;
        }
    }
    Ok(())
}

/// The first peak of a resumed run's converged steps and whether the
/// curve has already dropped past it (the peak fields are then written).
fn peak_before(checkpoint: Option<&Checkpoint>) -> Result<(f64, bool)> {
    Ok(
        match checkpoint.filter(|cp| !cp.state.path.rows.is_empty()) {
            Some(cp) => {
                let (first, _, step) = crate::post::first_peak_bond_stress(&cp.state.path.rows)?;
                (
                    first,
                    step < cp.state.path.rows.len()
                        && cp
                            .state
                            .path
                            .rows
                            .iter()
                            .any(|r| r.bond_stress < (1.0 - crate::post::FIRST_PEAK_DROP) * first),
                )
            }
            None => (f64::NEG_INFINITY, false),
        },
    )
}

/// The converged steps of a run and, when it stopped early, why: a stall
/// or the step limit keep their converged part as a result.
fn split_outcome(
    outcome: std::result::Result<RunResult, SolveError>,
) -> Result<(RunResult, Option<String>)> {
    Ok(match outcome {
        Ok(result) => (result, None),
        Err(SolveError::Stalled {
            partial,
            step,
            u_imposed,
            residual_history,
            cause,
            step_size,
            step_unit,
        }) => {
            let why = format!(
                "step {step} did not converge at the minimum step size {step_size:e} {step_unit} \
                 (imposed u = {u_imposed:e} m); residual history {residual_history:?}; likely \
                 cause: {cause}; {}",
                cause.stall_advice()
            );
            (*partial, Some(why))
        }
        Err(SolveError::StepLimit {
            max_steps,
            u_imposed,
            partial,
        }) => {
            let why = step_limit_text(max_steps, u_imposed);
            (*partial, Some(why))
        }
        Err(e) => return Err(e.into()),
    })
}

/// Why a run stopped at its step limit, and the key that moves it.
fn step_limit_text(max_steps: usize, u_imposed: f64) -> String {
    format!(
        "solver.expert.max_steps = {max_steps} converged steps reached at imposed u = \
         {u_imposed:e} m; raise solver.expert.max_steps, or remove it, to go further"
    )
}

/// How a run ended at the bar's limit load, and what lets the bond carry
/// more.
fn limit_load_text(force: f64, yield_force: f64) -> String {
    format!(
        "solve: ended at a limit load: the bar yields over its section at F = {force:.1} N \
         ({:.0} % of σ_y A = {yield_force:.1} N); the bond sees no more load. A stronger bar \
         (materials.steel.sigma_y, bar.diameter) or a shorter bond \
         (specimen.adhesive_length) moves the bond's failure below the yield force",
        100.0 * force / yield_force,
    )
}

/// The fields of the last converged step (`fields/end_*`).
fn write_end_fields(
    observer: &mut StageObserver<'_>,
    model: &Model,
    result: &RunResult,
) -> Result<()> {
    if let Some(row) = result.rows.last() {
        let cp = &result.last;
        observer.write_fields("end", row, model, (&cp.state.path.u, &cp.state.path.states))?;
    }
    Ok(())
}

/// `fields/fields.pvd`: every written field step as one ParaView time
/// series over the imposed displacement. The peak and end files join it
/// under their own step unless a requested step already holds that state.
fn write_collection(fields_dir: &Path, rows: &[solve::curve::CurveRow], peak: f64) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(fields_dir) else {
        return Ok(());
    };
    let mut names: Vec<String> = entries
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter_map(|n| n.strip_suffix("_bulk.vtu").map(str::to_string))
        .collect();
    // Requested steps first, so that they win over peak/end at the same step.
    names.sort_by_key(|n| (!n.starts_with("step"), n.clone()));
    let step_of = |name: &str| -> Option<usize> {
        match name {
            "peak" => rows.iter().find(|r| r.bond_stress == peak).map(|r| r.step),
            "end" => rows.last().map(|r| r.step),
            _ => name.strip_prefix("step")?.parse().ok(),
        }
    };
    let mut steps: Vec<(usize, solve::fields::CollectionStep)> = Vec::new();
    for name in names {
        let Some(step) = step_of(&name) else { continue };
        let Some(row) = rows.iter().find(|r| r.step == step) else {
            continue;
        };
        if steps.iter().any(|(s, _)| *s == step) {
            continue;
        }
        let mut files = vec![format!("{name}_bulk.vtu")];
        if fields_dir.join(format!("{name}_interface.vtu")).is_file() {
            files.push(format!("{name}_interface.vtu"));
        }
        steps.push((
            step,
            solve::fields::CollectionStep {
                u_imposed: row.u_imposed,
                files,
            },
        ));
    }
    steps.sort_by_key(|(s, _)| *s);
    let steps: Vec<_> = steps.into_iter().map(|(_, c)| c).collect();
    crate::store::write_atomic(
        &fields_dir.join("fields.pvd"),
        solve::fields::collection_pvd(&steps).as_bytes(),
    )?;
    Ok(())
}

/// `solve.json`'s `energy_check`: the balance check of the tracked rows,
/// or why there is none.
fn energy_check_json(ctx: &Ctx, result: &RunResult) -> Result<serde_json::Value> {
    Ok(match &result.energy {
        Ok(rows) if rows.len() == result.rows.len() => {
            let check = solve::energy::check(rows, ENERGY_TOLERANCE);
            if !check.passed {
                ctx.printer.line(&format!(
                "solve: energy check failed: imbalance {:.3e} (step {}), smallest dissipation increment {:.3e} (tolerance {:.0e} of W_ext)",
                check.max_relative_imbalance, check.step_of_max_imbalance, check.min_dissipation_increment, check.tolerance
            ));
            }
            let mut v = serde_json::to_value(&check)?;
            v["available"] = true.into();
            v["final"] = serde_json::to_value(rows.last())?;
            v
        }
        Err(why) => serde_json::json!({"available": false, "reason": why}),
        _ => {
            serde_json::json!({"available": false, "reason": "energy rows do not match the curve"})
        }
    })
}

/// Says how a run that returned a result ended, when it was not by
/// reaching the end of the loading.
fn report_ending(ctx: &Ctx, ending: &solve::nonlinear::Ending) {
    match *ending {
        solve::nonlinear::Ending::Completed => {}
        solve::nonlinear::Ending::LimitLoad { force, yield_force } => {
            ctx.printer.line(&limit_load_text(force, yield_force));
        }
        solve::nonlinear::Ending::BrittleFailure {
            force,
            u_imposed,
            snap_back_to,
            unsettled_points,
            cracked_through_tets,
            damaging_concrete_tets,
            concrete_tets,
        } => {
            let mut beyond = if unsettled_points > 0 {
                format!(
                    "beyond it no state at dissipation control's smallest step is in balance \
                     ({unsettled_points} held interface points do not settle)"
                )
            } else if snap_back_to < u_imposed {
                format!(
                    "beyond it the path snaps back to u = {:.4} mm",
                    snap_back_to * 1e3
                )
            } else {
                format!(
                    "beyond it no state at dissipation control's smallest step is in balance \
                     (its attempt reached u = {:.4} mm)",
                    snap_back_to * 1e3
                )
            };
            if cracked_through_tets > 0 {
                beyond = format!(
                    "its concrete is cracked through the cover ({cracked_through_tets} tets \
                     with D ≥ {} from the bar to the cube's faces); {beyond}",
                    solve::nonlinear::CRACKED
                );
            }
            // Without a crack band through the cover the evidence is the
            // path's, not the cube's: the bond may be what lets go (R2's
            // 80 mm interface unzipping at once, smooth bars).
            let what = if cracked_through_tets > 0 {
                "the cube splits"
            } else {
                "no crack band crosses the cover: the bond or the cube fails unstably"
            };
            ctx.printer.line(&format!(
                "solve: ended at a brittle failure: F = {force:.1} N at u = {:.4} mm is the \
                 failure load; {beyond} with concrete damage spreading in \
                 {damaging_concrete_tets} of {concrete_tets} concrete tets ({what}; \
                 no quasi-static continuation under a growing pull)",
                u_imposed * 1e3,
            ));
        }
        solve::nonlinear::Ending::Unloaded {
            force,
            peak_force,
            broken_concrete_tets,
        } => {
            ctx.printer.line(&format!(
                "solve: ended unloaded: F = {force:.3e} N after a peak of {peak_force:.1} N \
             (the cube split through or the bar pulled free; {broken_concrete_tets} \
             concrete tets with D > 0.99)"
            ));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use solve::assembly::AssemblyError;
    use solve::linalg::LinearError;
    use solve::nonlinear::{NotConverged, Refusal, RegimeChanges, StepFailure};

    /// Every way a step can fail, as a stall at the minimum step reports it.
    fn every_failure() -> Vec<StepFailure> {
        let regimes = RegimeChanges::default();
        let not_converged = [
            NotConverged::Constitutive {
                in_line_search: true,
                source: AssemblyError::Model("x".into()),
            },
            NotConverged::Constitutive {
                in_line_search: false,
                source: AssemblyError::Model("x".into()),
            },
            NotConverged::NonFiniteResidual,
            NotConverged::NonFiniteCorrection,
            NotConverged::Stagnating {
                relative_residual: 1e-3,
                regimes,
            },
            NotConverged::Diverging {
                residual: 1e9,
                regimes,
            },
            NotConverged::LinearSolve {
                source: LinearError::NotPositiveDefinite { index: 0 },
                regimes,
            },
            NotConverged::Unsettled {
                points: 3,
                passes: 20,
                relative_residual: 1e-2,
                regimes,
            },
            NotConverged::IterationLimit {
                iterations: 25,
                relative_residual: 1e-2,
                regimes,
            },
        ];
        let refused = [
            Refusal::LoadJump {
                increment: 1e-4,
                limit: 2e-5,
            },
            Refusal::ExtrapolationError {
                indicator: 0.1,
                limit: 0.02,
            },
            Refusal::CurveResolution {
                deviation: 1e-2,
                limit: 6e-3,
                next_step: 1e-6,
            },
            Refusal::CreatesEnergy {
                of_step_work: 0.5,
                of_total_work: 0.01,
                limit: 0.15,
                regimes,
            },
            Refusal::OutOfBalance {
                of_step_work: 0.5,
                of_total_work: 0.01,
                limit: 0.15,
                regimes,
            },
            Refusal::FailsEnergyCheck {
                imbalance: 0.02,
                dissipation_increment: -0.01,
                limit: 0.01,
                regimes,
            },
        ];
        let mut all: Vec<StepFailure> = not_converged.into_iter().map(Into::into).collect();
        all.extend(refused.into_iter().map(StepFailure::from));
        all
    }

    /// The dotted scene keys a message names (`loading.min_step`, …).
    fn keys_in(text: &str) -> Vec<String> {
        const SECTIONS: [&str; 6] = [
            "loading.",
            "solver.",
            "materials.",
            "specimen.",
            "bar.",
            "mesh.",
        ];
        let word = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '.';
        text.split(|c: char| !word(c))
            .filter(|w| SECTIONS.iter().any(|s| w.starts_with(s)))
            // File names (`solver.md`) are not keys.
            .filter(|w| ![".md", ".json", ".yaml"].iter().any(|e| w.ends_with(e)))
            .map(|w| w.trim_end_matches('.').to_string())
            .collect()
    }

    /// Whether the scene's schema has the dotted `key`.
    fn scene_has(schema: &serde_json::Value, key: &str) -> bool {
        use serde_json::Value;
        // What a schema stands for: references followed, an optional
        // value's null branch left out.
        const NULL: Value = Value::Null;
        fn resolve<'s>(schema: &'s Value, mut node: &'s Value) -> &'s Value {
            loop {
                if let Some(r) = node.get("$ref").and_then(Value::as_str) {
                    node = schema.pointer(r.trim_start_matches('#')).unwrap_or(&NULL);
                } else if let Some(branches) = node.get("anyOf").and_then(Value::as_array) {
                    let real = branches
                        .iter()
                        .find(|b| b.get("type").and_then(Value::as_str) != Some("null"));
                    node = real.unwrap_or(&NULL);
                } else {
                    return node;
                }
            }
        }
        let mut node = schema;
        for part in key.split('.') {
            match resolve(schema, node)
                .get("properties")
                .and_then(|p| p.get(part))
            {
                Some(next) => node = next,
                None => return false,
            }
        }
        true
    }

    /// Every message of a run that stops early or ends short of its
    /// loading names at least one scene key a user would change, and every
    /// key it names exists in the scene's schema (so a renamed key fails
    /// here, not in a user's hands).
    #[test]
    fn stop_messages_name_keys_that_exist() {
        let schema = crate::scene::RawScene::schema();
        let mut messages: Vec<(String, String)> = every_failure()
            .iter()
            .map(|f| (format!("stall: {f}"), f.stall_advice()))
            .collect();
        messages.push(("step limit".into(), step_limit_text(3, 1e-5)));
        messages.push(("limit load".into(), limit_load_text(9e3, 1e4)));
        for (what, text) in &messages {
            let keys = keys_in(text);
            assert!(!keys.is_empty(), "{what}: names no key: {text}");
            for key in keys {
                assert!(
                    scene_has(&schema, &key),
                    "{what}: {key} is not a scene key: {text}"
                );
            }
        }
        let checkpoint = SolveError::Checkpoint("3 nodes, not 4".into()).to_string();
        assert!(checkpoint.contains("`ribbar clean`"), "{checkpoint}");
        // The check itself can fail: a key of an earlier layout is not found.
        assert!(!scene_has(&schema, "solver.max_iterations"));
        assert!(scene_has(&schema, "solver.expert.max_iterations"));
    }

    /// The user pages on stopping runs and on the solver name only scene
    /// keys that exist.
    #[test]
    fn the_solver_pages_name_keys_that_exist() {
        let schema = crate::scene::RawScene::schema();
        let docs = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/src");
        for page in ["howto/when-a-run-stops.md", "explanation/solver.md"] {
            let text = std::fs::read_to_string(docs.join(page)).expect(page);
            let keys = keys_in(&text);
            assert!(keys.len() > 10, "{page}: {keys:?}");
            for key in keys {
                assert!(scene_has(&schema, &key), "{page}: {key} is not a scene key");
            }
        }
    }

    /// Each cause of a stall names its own keys: the iteration limit
    /// `solver.expert.max_iterations`, the stagnating residual the
    /// acceptance and the holds, the linear solve its solver and
    /// preconditioner, unsettled points the holds, the IMPL-EX refusal its
    /// tolerance and rejection, the curve's bend its tolerance; each after
    /// `loading.min_step`.
    #[test]
    fn each_stall_names_the_keys_of_its_cause() {
        let advice = |i: usize| every_failure()[i].stall_advice();
        let expect = [
            (8, vec!["solver.expert.max_iterations"]),
            (
                4,
                vec![
                    "solver.expert.stagnation_acceptance",
                    "solver.expert.interface_holds",
                ],
            ),
            (
                6,
                vec![
                    "solver.expert.linear_solver",
                    "solver.expert.preconditioner",
                ],
            ),
            (7, vec!["solver.expert.interface_holds"]),
            (
                10,
                vec!["solver.impl_ex_tolerance", "solver.expert.impl_ex_reject"],
            ),
            (11, vec!["loading.curve_tolerance"]),
        ];
        for (i, keys) in expect {
            let text = advice(i);
            let mut want = vec!["loading.min_step".to_string()];
            want.extend(keys.iter().map(|k| k.to_string()));
            assert_eq!(keys_in(&text), want, "{text}");
        }
    }
}
