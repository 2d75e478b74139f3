//! Command bodies shared by the binary and the study runner.

use crate::cli::{
    CleanArgs, CompareArgs, CompareAxis, EstimateArgs, MaterialArgs, SchemaArgs, SchemaKind,
};
use crate::progress::Printer;
use crate::scene::Scene;
use crate::stage::{folder, Ctx, Keys, Stage};
use crate::store::{RunOutcome, Store};
use anyhow::{Context, Result};
use std::io::Write;
use std::path::Path;
use std::process::ExitCode;

/// Finds gmsh, saying so while `gmsh --version` keeps it waiting.
pub fn locate_gmsh(printer: &Printer) -> Result<geom::gmsh::Gmsh> {
    Ok(printer.while_running(
        |t| {
            format!(
                "gmsh: waiting for `gmsh --version` ({:.0} s; given up after 60 s)",
                t.as_secs_f64()
            )
        },
        geom::gmsh::Gmsh::locate,
    )?)
}

/// Runs `stages` (in order, each only if stale) for one scene; a solve
/// that stopped before the end of the loading is an error.
pub fn run_scene(scene: &Scene, work: &Path, stages: &[Stage], printer: &Printer) -> Result<()> {
    match run_scene_stages(scene, work, stages, printer)? {
        None => Ok(()),
        Some(stopped) => Err(anyhow::anyhow!(stopped)),
    }
}

/// Runs `stages` (in order, each only if stale) for one scene, recording
/// in its results folder how the run ended; when the solve stopped before
/// the end of the loading, says so (the converged steps are published like
/// a whole curve).
pub fn run_scene_stages(
    scene: &Scene,
    work: &Path,
    stages: &[Stage],
    printer: &Printer,
) -> Result<Option<String>> {
    for warning in crate::plausibility::warnings(scene) {
        printer.line(&format!("warning: {warning}"));
    }
    let gmsh = locate_gmsh(printer)?;
    let keys = Keys::of(scene, gmsh.version());
    let store = Store::new(work);
    let ctx = Ctx {
        store: &store,
        scene,
        keys: &keys,
        gmsh: &gmsh,
        printer,
    };
    let command = match stages {
        [.., last] if stages.len() < Stage::ALL.len() => last.name(),
        _ => "run",
    };
    let before = folder::begin_run(&store, &scene.name, command, &keys, printer)?;
    for &stage in stages {
        if let Err(e) = crate::stage::ensure(&ctx, stage) {
            printer.finish();
            let failure = (stage, &e);
            if let Err(record) =
                folder::failed(&store, &scene.name, &keys, failure, &before, printer)
            {
                printer.line(&format!(
                    "results: the failure could not be recorded: {record:#}"
                ));
            }
            return Err(e);
        }
    }
    printer.finish();
    let dir = store.scene_dir(&scene.name);
    printer.line(&format!("results: {}", dir.display()));
    report_check_cost(printer);
    let stopped = stages
        .contains(&Stage::Solve)
        .then(|| incomplete_solve(&dir.join("solve.json")))
        .flatten();
    let outcome = match &stopped {
        Some(reason) => RunOutcome::Stopped {
            reason: reason.clone(),
        },
        None => RunOutcome::Complete,
    };
    folder::end_run(&store, &scene.name, outcome)?;
    if let Some(why) = stopped {
        return Ok(Some(format!(
            "the solve of {} stopped before the end of the loading: {why}; \
             the converged steps are kept in {}",
            scene.name,
            dir.join("curve.csv").display()
        )));
    }
    Ok(None)
}

/// With `-v`: what the store's digests and checks cost in this process.
fn report_check_cost(printer: &Printer) {
    let (check_s, hashed) = crate::store::check_cost();
    let (publish_s, copied) = crate::store::publish_cost();
    printer.detail(&format!(
        "store: digests and checks {check_s:.3} s ({:.1} MB hashed); published copies {publish_s:.3} s ({:.1} MB copied)",
        hashed as f64 * 1e-6,
        copied as f64 * 1e-6
    ));
}

/// The reason recorded by a solve that stopped early, if it did.
pub fn incomplete_solve(solve_json: &Path) -> Option<String> {
    let text = geom::fsutil::read_capped(solve_json, geom::fsutil::MAX_RECORD_BYTES).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    if v.get("completed")?.as_bool()? {
        None
    } else {
        Some(v.get("stopped")?.as_str().unwrap_or("unknown").to_string())
    }
}

/// `ribbar estimate`: the solve's estimate from the scene's meshed model
/// (the mesh stage of exactly these inputs must be done).
pub fn estimate(args: &EstimateArgs) -> Result<ExitCode> {
    let a = &args.scene;
    let scene = Scene::load(&a.spec, &a.overrides)?;
    let gmsh = geom::gmsh::Gmsh::locate().context("estimate needs gmsh's version for the keys")?;
    let keys = Keys::of(&scene, gmsh.version());
    let store = Store::new(&a.work);
    let key = keys.get(Stage::Mesh);
    if !store.is_done(key) {
        anyhow::bail!(
            "estimate: the mesh of {} is not in {} yet; run `ribbar mesh` with the same spec and --set first",
            scene.name,
            a.work.display()
        );
    }
    let nodes = crate::estimate::mesh_nodes(&store.artifact_dir(key).join("mesh.json"))?;
    let estimate = crate::estimate::SolveEstimate::new(&scene, nodes);
    let mut json = serde_json::to_vec_pretty(&estimate)?;
    json.push(b'\n');
    match &args.output {
        Some(path) => crate::store::write_atomic(path, &json)?,
        None => std::io::stdout().lock().write_all(&json)?,
    }
    Ok(ExitCode::SUCCESS)
}

/// Removes what ribbar made of a scene's results (and its in-progress
/// stages); with `--all`, the whole store. Says what it kept.
pub fn clean(args: &CleanArgs, printer: &Printer) -> Result<ExitCode> {
    let store = Store::new(&args.work);
    if let Some(spec) = &args.spec {
        let scene = Scene::load(spec, &args.overrides)?;
        crate::clean::scene(&store, &scene, printer)?;
    }
    if args.all {
        crate::clean::store(&store, printer)?;
    } else if args.spec.is_none() {
        anyhow::bail!(
            "clean: give a SPEC (its results are removed) and/or --all (the whole store)"
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Curves whose ranges differ more than this (the shorter over the longer)
/// are refused by `compare` unless `--common-range` says to compare them
/// over their common range.
pub const COMPARED_RANGE_SHARE: f64 = 0.9;

/// `ribbar compare`: the relative L2 distance of the test run's σ_mb curve
/// from the reference's (`post::curve_distance`), the range it was taken
/// over, and both first peaks. Curves that end far apart are refused
/// unless told: over their common range a stalled run looks like its
/// reference.
pub fn compare(args: &CompareArgs) -> Result<ExitCode> {
    let read = |path: &Path| {
        let file = if path.is_dir() {
            path.join("curve.csv")
        } else {
            path.to_path_buf()
        };
        let text = geom::fsutil::read_capped(&file, geom::fsutil::MAX_TABLE_BYTES)
            .with_context(|| format!("reading {}", file.display()))?;
        crate::post::parse_curve_csv(&text, &file)
            .with_context(|| format!("reading {}", file.display()))
    };
    let (test, reference) = (read(&args.test)?, read(&args.reference)?);
    let (axis, name) = match args.along {
        CompareAxis::Fed => (crate::post::CurveAxis::Fed, "FED"),
        CompareAxis::U => (crate::post::CurveAxis::ImposedDisplacement, "u"),
    };
    let end = |rows: &[crate::post::CurveRow]| {
        rows.iter()
            .map(|r| match args.along {
                CompareAxis::Fed => r.fed,
                CompareAxis::U => r.u_imposed,
            })
            .fold(0.0, f64::max)
    };
    let (end_t, end_r) = (end(&test), end(&reference));
    let share = end_t.min(end_r) / end_t.max(end_r);
    let ends = format!(
        "the test ends at {name} = {:.4} mm, the reference at {:.4} mm",
        end_t * 1e3,
        end_r * 1e3
    );
    if (share.is_nan() || share < COMPARED_RANGE_SHARE) && !args.common_range {
        anyhow::bail!(
            "the curves end far apart: {ends} ({:.0} % of the longer range); over their \
             common range a run that stopped early looks like its reference. Compare them \
             over 0 – {:.4} mm anyway with --common-range",
            100.0 * share,
            end_t.min(end_r) * 1e3
        );
    }
    let distance = crate::post::curve_distance(&test, &reference, axis, None)?;
    let (peak_t, fed_t, _) = crate::post::first_peak_bond_stress(&test)?;
    let (peak_r, fed_r, _) = crate::post::first_peak_bond_stress(&reference)?;
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "compared over {name} = 0 – {:.4} mm ({:.0} % of the longer curve's range; {ends})",
        end_t.min(end_r) * 1e3,
        100.0 * share
    )?;
    writeln!(
        out,
        "relative L2 distance of sigma_mb along {name}: {:.4} %",
        100.0 * distance
    )?;
    writeln!(
        out,
        "first peak: {:.4} MPa at FED {:.4} mm (test), {:.4} MPa at FED {:.4} mm (reference), {:+.3} %",
        peak_t / 1e6,
        fed_t * 1e3,
        peak_r / 1e6,
        fed_r * 1e3,
        100.0 * (peak_t / peak_r - 1.0)
    )?;
    Ok(ExitCode::SUCCESS)
}

/// The material-point driver.
pub fn material(args: &MaterialArgs) -> Result<ExitCode> {
    if let Some(output) = &args.output {
        crate::inputs::refuse_overwriting(output, &[("the test file", &args.test)])?;
    }
    let table = solve::problems::material_point::run_file(&args.test)?;
    match &args.output {
        Some(path) => {
            let mut bytes = Vec::new();
            table.write_csv(&mut bytes)?;
            crate::store::write_atomic(path, &bytes)?;
        }
        None => table.write_csv(std::io::stdout().lock())?,
    }
    Ok(ExitCode::SUCCESS)
}

/// Prints the JSON Schema of a scene or study file.
pub fn schema(args: &SchemaArgs) -> Result<ExitCode> {
    let schema = match args.kind {
        SchemaKind::Scene => crate::scene::RawScene::schema(),
        SchemaKind::Study => crate::study::RawStudy::schema(),
    };
    let mut out = std::io::stdout().lock();
    writeln!(out, "{}", serde_json::to_string_pretty(&schema)?)?;
    Ok(ExitCode::SUCCESS)
}
