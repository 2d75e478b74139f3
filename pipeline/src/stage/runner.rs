//! Running a stage: skip it when its key is finished, otherwise run it
//! into the store's in-progress directory and commit it by one rename;
//! publish its files either way. A folder under the key that is not
//! finished (damaged, partly removed, made by another version) is moved to
//! the quarantine and the stage runs again: it is never served.

use super::ctx::Ctx;
use super::kinds::Stage;
use crate::store::{Examined, KeyLock, StageRecord, Thoroughness};
use anyhow::{Context, Result};
use std::path::Path;
use std::time::Instant;

/// Runs `stage` unless its key is finished; publishes either way.
/// Returns whether it ran.
pub fn ensure(ctx: &Ctx, stage: Stage) -> Result<bool> {
    let key = ctx.keys.get(stage);
    let (record, ran) = match ctx.store.examine(key, Thoroughness::Lookup) {
        Examined::Finished(record) => (record, false),
        _ => {
            let lock = ctx.store.lock(key)?;
            // Another process may have finished it while we waited.
            match ctx.store.examine(key, Thoroughness::Lookup) {
                Examined::Finished(record) => (record, false),
                found => {
                    if let Examined::Damaged(why) = found {
                        set_aside(ctx, stage, &why)?;
                    }
                    (run_and_commit(ctx, stage, &lock)?, true)
                }
            }
        }
    };
    if !ran {
        ctx.printer.line(&format!("{stage}: up to date"));
    }
    super::folder::publish(ctx.store, &ctx.scene.name, stage, &record, ctx.printer)?;
    Ok(ran)
}

/// Moves the unfinished folder under `stage`'s key to the quarantine,
/// saying why and where.
fn set_aside(ctx: &Ctx, stage: Stage, why: &str) -> Result<()> {
    let key = ctx.keys.get(stage);
    let moved = ctx.store.quarantine(
        &ctx.store.artifact_dir(key),
        &format!("{stage}-{}", key.key),
    )?;
    ctx.printer.line(&format!(
        "{stage}: the stored result is not usable ({why}); moved to {} and computed again",
        moved.display()
    ));
    Ok(())
}

/// Runs `stage` and commits it under `lock`, checked first: a lock that
/// another host took meanwhile commits nothing.
fn run_and_commit(ctx: &Ctx, stage: Stage, lock: &KeyLock) -> Result<StageRecord> {
    let key = ctx.keys.get(stage);
    let started = Instant::now();
    let partial = ctx.store.begin(key, stage.resumable())?;
    run_stage(ctx, stage, &partial)
        .with_context(|| format!("stage {stage} of scene {}", ctx.scene.name))?;
    let seconds = started.elapsed().as_secs_f64();
    lock.verify()?;
    let committed = ctx.store.commit(key, &partial, seconds)?;
    if let Some((why, moved)) = &committed.replaced {
        ctx.printer.line(&format!(
            "{stage}: a folder under its key was not usable ({why}); moved to {}",
            moved.display()
        ));
    }
    ctx.printer
        .line(&format!("{stage}: done in {seconds:.1} s"));
    Ok(committed.record)
}

fn run_stage(ctx: &Ctx, stage: Stage, out: &Path) -> Result<()> {
    match stage {
        Stage::Geometry => super::geometry::run(ctx, out),
        Stage::Mesh => super::mesh::run(ctx, out),
        Stage::Solve => super::solve::run(ctx, out),
        Stage::Post => super::post::run(ctx, out),
    }
}
