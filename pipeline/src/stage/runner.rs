//! Running a stage: skip it when its key is done, otherwise run it into
//! the store's in-progress directory and commit it by one rename; publish
//! its files either way.

use super::ctx::Ctx;
use super::kinds::Stage;
use anyhow::{Context, Result};
use std::path::Path;
use std::time::Instant;

/// Runs `stage` unless its key is done; publishes either way.
/// Returns whether it ran.
pub fn ensure(ctx: &Ctx, stage: Stage) -> Result<bool> {
    let key = ctx.keys.get(stage);
    let ran = if ctx.store.is_done(key) {
        false
    } else {
        let lock = ctx.store.lock(key)?;
        if ctx.store.is_done(key) {
            false
        } else {
            let started = Instant::now();
            let partial = ctx.store.begin(key, stage.resumable())?;
            run_stage(ctx, stage, &partial)
                .with_context(|| format!("stage {stage} of scene {}", ctx.scene.name))?;
            let seconds = started.elapsed().as_secs_f64();
            lock.verify()?;
            ctx.store.commit(key, &partial, seconds)?;
            ctx.printer
                .line(&format!("{stage}: done in {seconds:.1} s"));
            true
        }
    };
    if !ran {
        ctx.printer.line(&format!("{stage}: up to date"));
    }
    ctx.store
        .publish(&ctx.scene.name, key, stage.published_files())?;
    Ok(ran)
}

fn run_stage(ctx: &Ctx, stage: Stage, out: &Path) -> Result<()> {
    match stage {
        Stage::Geometry => super::geometry::run(ctx, out),
        Stage::Mesh => super::mesh::run(ctx, out),
        Stage::Solve => super::solve::run(ctx, out),
        Stage::Post => super::post::run(ctx, out),
    }
}
