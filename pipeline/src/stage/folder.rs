//! The results folder `WORK/<scene>/` as one consistent view: it holds,
//! for each stage, the files of one key, and only stages whose upstream
//! files are the ones they were made from. A stage published with a new
//! key takes out the downstream stages made from its old files; a failed
//! run takes out the failed stage's and the later stages' files of earlier
//! specs (they stay in the store) and records how it ended, so that no
//! file of an earlier run sits beside the failed run's without saying so.

use super::keys::Keys;
use super::kinds::Stage;
use crate::progress::Printer;
use crate::store::{RunOutcome, RunRecord, SceneRecord, StageRecord, Store};
use anyhow::Result;
use serde_json::Value;

/// Publishes `record` as `stage`'s files of `scene`, saying what was moved
/// aside, then takes out the stages downstream made from other files.
pub fn publish(
    store: &Store,
    scene: &str,
    stage: Stage,
    record: &StageRecord,
    printer: &Printer,
) -> Result<u64> {
    let done = store.publish(scene, record, stage.published_files())?;
    for note in &done.notes {
        printer.line(&format!("{stage}: {note}"));
    }
    drop_broken_chain(store, scene, printer)?;
    Ok(done.copied_bytes)
}

/// The stages of `record` whose upstream stage is not published with the
/// key they were made from, in run order.
fn broken_chain(record: &SceneRecord) -> Vec<Stage> {
    let mut kept: Vec<Stage> = Vec::new();
    let mut broken = Vec::new();
    for stage in Stage::ALL {
        let Some(published) = record.stages.get(stage.name()) else {
            continue;
        };
        let intact = match stage.upstream() {
            None => true,
            Some(up) => {
                let made_from = published.key.inputs.get(up.name()).and_then(Value::as_str);
                let up_now = kept
                    .contains(&up)
                    .then(|| record.stages.get(up.name()).map(|s| s.key.key.as_str()))
                    .flatten();
                made_from.is_some() && made_from == up_now
            }
        };
        if intact {
            kept.push(stage);
        } else {
            broken.push(stage);
        }
    }
    broken
}

fn drop_broken_chain(store: &Store, scene: &str, printer: &Printer) -> Result<()> {
    let Some(record) = store.read_record(scene)? else {
        return Ok(());
    };
    for stage in broken_chain(&record) {
        unpublish(store, scene, stage, printer)?;
        printer.detail(&format!(
            "{stage}: its files in the results folder were made from another {} and were taken out",
            stage.upstream().map_or("input", Stage::name)
        ));
    }
    Ok(())
}

fn unpublish(store: &Store, scene: &str, stage: Stage, printer: &Printer) -> Result<()> {
    let done = store.unpublish(scene, stage.name(), stage.published_files())?;
    for note in &done.notes {
        printer.line(&format!("{stage}: {note}"));
    }
    Ok(())
}

/// What a results folder held when a run began: each stage's key.
pub type Held = Vec<(Stage, String)>;

fn held(record: &SceneRecord) -> Held {
    Stage::ALL
        .iter()
        .filter_map(|s| Some((*s, record.stages.get(s.name())?.key.key.clone())))
        .collect()
}

/// Records that `command` starts on `scene` with `keys`, after checking
/// that the results folder is ribbar's (or new, or empty); returns what
/// the folder held.
pub fn begin_run(
    store: &Store,
    scene: &str,
    command: &str,
    keys: &Keys,
    printer: &Printer,
) -> Result<Held> {
    let names: Vec<&str> = Stage::ALL
        .iter()
        .flat_map(|s| s.published_files().iter().copied())
        .collect();
    if let Some(note) = store.claim_scene_dir(scene, &names)? {
        printer.line(&format!("results: {note}"));
    }
    let before = held(&store.read_record(scene)?.unwrap_or_default());
    store.update_record(scene, |r| {
        r.run = Some(RunRecord {
            command: command.to_string(),
            started_unix_s: crate::store::unix_now(),
            finished_unix_s: None,
            outcome: RunOutcome::Running,
            keys: Stage::ALL
                .iter()
                .map(|s| (s.name().to_string(), keys.get(*s).key.clone()))
                .collect(),
        });
    })?;
    Ok(before)
}

/// Records how the run ended.
pub fn end_run(store: &Store, scene: &str, outcome: RunOutcome) -> Result<()> {
    store.update_record(scene, |r| {
        if let Some(run) = &mut r.run {
            run.finished_unix_s = Some(crate::store::unix_now());
            run.outcome = outcome;
        }
    })?;
    Ok(())
}

/// After `stage` failed: takes out of the results folder the files of that
/// stage and the later ones that are not this spec's, records the failure
/// and says what the folder now holds, and which of the files it held
/// when the run began (`before`) were taken out.
pub fn failed(
    store: &Store,
    scene: &str,
    keys: &Keys,
    (stage, error): (Stage, &anyhow::Error),
    before: &Held,
    printer: &Printer,
) -> Result<()> {
    let record = store.read_record(scene)?.unwrap_or_default();
    for &later in &Stage::ALL[stage as usize..] {
        let stale = record
            .stages
            .get(later.name())
            .is_some_and(|p| p.key.key != keys.get(later).key);
        if stale {
            unpublish(store, scene, later, printer)?;
        }
    }
    end_run(
        store,
        scene,
        RunOutcome::Failed {
            stage: stage.name().to_string(),
            error: crate::child::error_lines(error).join(": "),
        },
    )?;
    let now = held(&store.read_record(scene)?.unwrap_or_default());
    let holds: Vec<&str> = now.iter().map(|(s, _)| s.name()).collect();
    let taken_out: Vec<&str> = before
        .iter()
        .filter(|held| !now.contains(held))
        .map(|(s, _)| s.name())
        .collect();
    let holds = if holds.is_empty() {
        "no stage's files".to_string()
    } else {
        format!("this spec's {} files", holds.join(", "))
    };
    let earlier = if taken_out.is_empty() {
        String::new()
    } else {
        format!(
            "; the {} files of an earlier run were taken out (they stay in the store)",
            taken_out.join(", ")
        )
    };
    printer.line(&format!(
        "results: {} holds {holds} after {stage} failed{earlier}",
        store.scene_dir(scene).display()
    ));
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::{PublishedStage, StageKey};
    use serde_json::json;

    fn published(stage: Stage, up_key: Option<&str>) -> PublishedStage {
        let mut inputs = json!({"x": stage.name()});
        if let (Some(up), Some(k)) = (stage.upstream(), up_key) {
            inputs[up.name()] = json!(k);
        }
        PublishedStage {
            key: StageKey::new(stage.name(), inputs),
            files: None,
        }
    }

    /// A stage made from another upstream key, and everything after it,
    /// is out of the chain; an intact chain keeps every stage.
    #[test]
    fn a_stage_made_from_other_upstream_files_breaks_the_chain() {
        let mut record = SceneRecord::default();
        let geometry = published(Stage::Geometry, None);
        let mesh = published(Stage::Mesh, Some(&geometry.key.key));
        let solve = published(Stage::Solve, Some(&mesh.key.key));
        let post = published(Stage::Post, Some(&solve.key.key));
        for (s, p) in [
            (Stage::Geometry, geometry),
            (Stage::Mesh, mesh),
            (Stage::Solve, solve),
            (Stage::Post, post.clone()),
        ] {
            record.stages.insert(s.name().into(), p);
        }
        assert!(broken_chain(&record).is_empty());
        record
            .stages
            .insert("mesh".into(), published(Stage::Mesh, Some("another")));
        assert_eq!(
            broken_chain(&record),
            [Stage::Mesh, Stage::Solve, Stage::Post]
        );
        record.stages.remove("mesh");
        record.stages.remove("solve");
        assert_eq!(broken_chain(&record), [Stage::Post]);
    }
}
