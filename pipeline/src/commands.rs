//! Command bodies shared by the binary and the study runner.

use crate::cli::{
    CleanArgs, CompareArgs, CompareAxis, EstimateArgs, MaterialArgs, SchemaArgs, SchemaKind,
};
use crate::progress::Printer;
use crate::scene::Scene;
use crate::stage::{Ctx, Keys, Stage};
use crate::store::Store;
use anyhow::{Context, Result};
use std::io::Write;
use std::path::Path;
use std::process::ExitCode;

/// Runs `stages` (in order, each only if stale) for one scene; a solve
/// that stopped before the end of the loading is an error.
pub fn run_scene(scene: &Scene, work: &Path, stages: &[Stage], printer: &Printer) -> Result<()> {
    match run_scene_stages(scene, work, stages, printer)? {
        None => Ok(()),
        Some(stopped) => Err(anyhow::anyhow!(stopped)),
    }
}

/// Runs `stages` (in order, each only if stale) for one scene; when the
/// solve stopped before the end of the loading, says so (the converged
/// steps are published like a whole curve).
pub fn run_scene_stages(
    scene: &Scene,
    work: &Path,
    stages: &[Stage],
    printer: &Printer,
) -> Result<Option<String>> {
    let gmsh = geom::gmsh::Gmsh::locate()?;
    let keys = Keys::of(scene, gmsh.version());
    let store = Store::new(work);
    let ctx = Ctx {
        store: &store,
        scene,
        keys: &keys,
        gmsh: &gmsh,
        printer,
    };
    for &stage in stages {
        crate::stage::ensure(&ctx, stage)?;
    }
    printer.finish();
    let dir = store.scene_dir(&scene.name);
    printer.line(&format!("results: {}", dir.display()));
    if stages.contains(&Stage::Solve) {
        if let Some(why) = incomplete_solve(&dir.join("solve.json")) {
            return Ok(Some(format!(
                "the solve of {} stopped before the end of the loading: {why}; \
                 the converged steps are kept in {}",
                scene.name,
                dir.join("curve.csv").display()
            )));
        }
    }
    Ok(None)
}

/// The reason recorded by a solve that stopped early, if it did.
pub fn incomplete_solve(solve_json: &Path) -> Option<String> {
    let v: serde_json::Value = serde_json::from_slice(&std::fs::read(solve_json).ok()?).ok()?;
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

/// Removes a scene's published results; with `--all`, the whole store.
pub fn clean(args: &CleanArgs, printer: &Printer) -> Result<ExitCode> {
    let store = Store::new(&args.work);
    if let Some(spec) = &args.spec {
        let scene = Scene::load(spec, &args.overrides)?;
        let dir = store.scene_dir(&scene.name);
        if dir.exists() {
            std::fs::remove_dir_all(&dir).with_context(|| format!("removing {}", dir.display()))?;
            printer.line(&format!("removed {}", dir.display()));
        }
    }
    if args.all {
        let dir = args.work.join(".store");
        if dir.exists() {
            std::fs::remove_dir_all(&dir).with_context(|| format!("removing {}", dir.display()))?;
            printer.line(&format!("removed {}", dir.display()));
        }
    } else if args.spec.is_none() {
        anyhow::bail!(
            "clean: give a SPEC (its results are removed) and/or --all (the whole store)"
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// The material-point driver.
/// `ribbar compare`: the relative L2 distance of the test run's σ_mb curve
/// from the reference's over their common range (`post::curve_distance`),
/// and both first peaks.
pub fn compare(args: &CompareArgs) -> Result<ExitCode> {
    let read = |path: &Path| {
        let file = if path.is_dir() {
            path.join("curve.csv")
        } else {
            path.to_path_buf()
        };
        crate::post::read_curve_csv(&file).with_context(|| format!("reading {}", file.display()))
    };
    let (test, reference) = (read(&args.test)?, read(&args.reference)?);
    let (axis, name) = match args.along {
        CompareAxis::Fed => (crate::post::CurveAxis::Fed, "FED"),
        CompareAxis::U => (crate::post::CurveAxis::ImposedDisplacement, "u"),
    };
    let distance = crate::post::curve_distance(&test, &reference, axis, None)?;
    let (peak_t, fed_t, _) = crate::post::first_peak_bond_stress(&test)?;
    let (peak_r, fed_r, _) = crate::post::first_peak_bond_stress(&reference)?;
    let mut out = std::io::stdout().lock();
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

pub fn material(args: &MaterialArgs) -> Result<ExitCode> {
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
