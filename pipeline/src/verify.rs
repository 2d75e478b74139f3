//! `ribbar verify`: every stored result (or a scene's) checked against the
//! digests recorded when it was made; a folder that fails is moved to the
//! quarantine (the next run computes it again). Each interrupted solve's
//! checkpoint is checked too (header, checksum, key), and each results
//! folder's files against what ribbar wrote there (reported, not touched:
//! `ribbar run` puts the stored result back and keeps the changed file).
//! Exits non-zero when anything was found.

use crate::cli::VerifyArgs;
use crate::progress::Printer;
use crate::scene::Scene;
use crate::stage::{Keys, Stage, CHECKPOINT_FILE};
use crate::store::{Compare, Examined, FileState, Store, Thoroughness, RECORD_FILE};
use anyhow::Result;
use std::process::ExitCode;

/// What was checked and found.
#[derive(Default)]
struct Tally {
    results: usize,
    files: usize,
    bytes: u64,
    problems: usize,
}

/// The stage keys in the store: every finished-looking folder name.
fn stored_keys(store: &Store) -> Vec<(Stage, String)> {
    let mut out = Vec::new();
    for stage in Stage::ALL {
        let Ok(entries) = std::fs::read_dir(store.stage_root(stage.name())) else {
            continue;
        };
        let mut names: Vec<String> = entries
            .filter_map(|e| e.ok()?.file_name().into_string().ok())
            .filter(|n| !n.ends_with(".lock"))
            .collect();
        names.sort();
        out.extend(names.into_iter().map(|n| (stage, n)));
    }
    out
}

/// Checks one stored folder (or in-progress folder) and moves it aside if
/// it fails.
fn check_stored(
    store: &Store,
    stage: Stage,
    name: &str,
    tally: &mut Tally,
    printer: &Printer,
) -> Result<()> {
    if let Some(key) = name.strip_suffix(".partial") {
        return check_checkpoint(store, stage, key, tally, printer);
    }
    match store.examine_key(stage.name(), name, Thoroughness::Full) {
        Examined::Absent => {}
        Examined::Finished(record) => {
            tally.results += 1;
            tally.files += record.files.len();
            tally.bytes += record.bytes();
        }
        Examined::Damaged(why) => {
            tally.problems += 1;
            let dir = store.stage_root(stage.name()).join(name);
            match store.try_lock(stage.name(), name)? {
                None => printer.line(&format!(
                    "{stage}: damaged: {why} (in use by a running ribbar: not moved)"
                )),
                Some(_lock) => {
                    let moved = store.quarantine(&dir, &format!("{stage}-{name}"))?;
                    printer.line(&format!(
                        "{stage}: damaged: {why}; moved to {} (the next run computes it again)",
                        moved.display()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Checks an interrupted solve's checkpoint: the next run would resume
/// from it.
fn check_checkpoint(
    store: &Store,
    stage: Stage,
    key: &str,
    tally: &mut Tally,
    printer: &Printer,
) -> Result<()> {
    let path = store
        .partial_dir_of(stage.name(), key)
        .join(CHECKPOINT_FILE);
    if stage != Stage::Solve || !path.is_file() {
        return Ok(());
    }
    let Some(_lock) = store.try_lock(stage.name(), key)? else {
        return Ok(()); // being written by a running solve
    };
    if let Err(e) = solve::nonlinear::Checkpoint::load(&path, key) {
        tally.problems += 1;
        let moved = store.quarantine(&path, &format!("solve-{key}-checkpoint"))?;
        printer.line(&format!(
            "solve: {e}; moved to {} (the solve starts over)",
            moved.display()
        ));
    }
    Ok(())
}

/// Checks a results folder's files against its record.
fn check_folder(store: &Store, scene: &str, tally: &mut Tally, printer: &Printer) -> Result<()> {
    let record = match store.read_record(scene) {
        Ok(Some(record)) => record,
        Ok(None) => return Ok(()),
        Err(e) => {
            tally.problems += 1;
            printer.line(&format!("{e}"));
            return Ok(());
        }
    };
    for stage in Stage::ALL {
        let Some(published) = record.stages.get(stage.name()) else {
            continue;
        };
        let files = stage.published_files();
        for (path, state) in store.published_changes(scene, published, files, Compare::Digest) {
            tally.problems += 1;
            let what = if state == FileState::Absent {
                "missing"
            } else {
                "changed since ribbar wrote it"
            };
            printer.line(&format!(
                "{}: {what}; the stored result is intact and `ribbar run` publishes it again",
                path.display()
            ));
        }
    }
    Ok(())
}

pub fn run(args: &VerifyArgs, printer: &Printer) -> Result<ExitCode> {
    let store = Store::new(&args.work);
    let mut tally = Tally::default();
    let (targets, scenes): (Vec<(Stage, String)>, Vec<String>) = match &args.spec {
        Some(spec) => {
            let scene = Scene::load(spec, &args.overrides)?;
            let gmsh = crate::commands::locate_gmsh(printer)?;
            let keys = Keys::of(&scene, gmsh.version());
            let targets = Stage::ALL
                .iter()
                .flat_map(|s| {
                    let key = keys.get(*s).key.clone();
                    [(*s, key.clone()), (*s, format!("{key}.partial"))]
                })
                .collect();
            (targets, vec![scene.name])
        }
        None => {
            let scenes = std::fs::read_dir(&store.work)
                .map(|entries| {
                    entries
                        .filter_map(|e| e.ok()?.file_name().into_string().ok())
                        .filter(|n| store.scene_dir(n).join(RECORD_FILE).is_file())
                        .collect()
                })
                .unwrap_or_default();
            (stored_keys(&store), scenes)
        }
    };
    for (stage, name) in &targets {
        check_stored(&store, *stage, name, &mut tally, printer)?;
    }
    for scene in &scenes {
        check_folder(&store, scene, &mut tally, printer)?;
    }
    let (seconds, _) = crate::store::check_cost();
    println!(
        "verified {} stored results ({} files, {:.1} MB) and {} results folders in {seconds:.3} s: {}",
        tally.results,
        tally.files,
        tally.bytes as f64 * 1e-6,
        scenes.len(),
        match tally.problems {
            0 => "everything as recorded".to_string(),
            1 => "1 problem (named above)".to_string(),
            n => format!("{n} problems (named above)"),
        }
    );
    Ok(if tally.problems == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}
