//! Command bodies shared by the binary and the study runner.

use crate::cli::{CleanArgs, MaterialArgs};
use crate::progress::Printer;
use crate::scene::Scene;
use crate::stage::{Ctx, Keys, Stage};
use crate::store::Store;
use anyhow::{Context, Result};
use std::path::Path;
use std::process::ExitCode;

/// Runs `stages` (in order, each only if stale) for one scene.
pub fn run_scene(scene: &Scene, work: &Path, stages: &[Stage], printer: &Printer) -> Result<()> {
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
            anyhow::bail!(
                "the solve of {} stopped before the end of the loading: {why}; \
                 the converged steps are kept in {}",
                scene.name,
                dir.join("curve.csv").display()
            );
        }
    }
    Ok(())
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
