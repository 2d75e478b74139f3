//! What `ribbar status` says of each stage of a scene, and of the results
//! folder: which run it shows, and which of its files are not as ribbar
//! wrote them.

use super::keys::Keys;
use super::kinds::{Stage, CHECKPOINT_FILE};
use crate::scene::Scene;
use crate::store::{changed_keys, utc_text, Examined, FileState, RunOutcome, StageKey, Store};
use crate::store::{Compare, Thoroughness};
use anyhow::Result;

/// What `status` says of one stage.
#[derive(Debug, Clone, PartialEq)]
pub enum StageStatus {
    UpToDate,
    /// Never run for this scene.
    Missing,
    /// Run before with other inputs: the dotted keys that changed.
    Stale(Vec<String>),
    /// An interrupted run that can be resumed.
    Interrupted,
    /// A folder under the key that is not finished: why, naming the file.
    Damaged(String),
}

pub fn status(store: &Store, scene: &Scene, keys: &Keys) -> Result<Vec<(Stage, StageStatus)>> {
    // A damaged record is `folder_report`'s to name.
    let record = store
        .read_record(&scene.name)
        .ok()
        .flatten()
        .unwrap_or_default();
    Ok(Stage::ALL
        .into_iter()
        .map(|stage| {
            let key = keys.get(stage);
            let st = match store.examine(key, Thoroughness::Lookup) {
                Examined::Finished(_) => StageStatus::UpToDate,
                Examined::Damaged(why) => StageStatus::Damaged(why),
                Examined::Absent if store.partial_dir(key).join(CHECKPOINT_FILE).is_file() => {
                    StageStatus::Interrupted
                }
                Examined::Absent => match record.stages.get(stage.name()) {
                    Some(old) => StageStatus::Stale(stale_reasons(&old.key, key)),
                    None => StageStatus::Missing,
                },
            };
            (stage, st)
        })
        .collect())
}

/// What made a stage stale, in the user's words where possible: the spec
/// keys as written, then upstream stages, then (when the written spec did
/// not change, e.g. a program version) the resolved inputs.
fn stale_reasons(old: &StageKey, new: &StageKey) -> Vec<String> {
    let mut reasons = if old.written.is_null() {
        Vec::new()
    } else {
        changed_keys(&old.written, &new.written)
    };
    let resolved = changed_keys(&old.inputs, &new.inputs);
    reasons.extend(
        resolved
            .iter()
            .filter(|k| Stage::from_name(k).is_some())
            .cloned(),
    );
    if reasons.is_empty() {
        reasons = resolved;
    }
    if reasons.is_empty() && old.key != new.key {
        // Same inputs, another key: the store's own format changed.
        reasons.push("the store format of this ribbar".to_string());
    }
    reasons
}

/// Lines on the results folder: which run it shows and how that run
/// ended, which stages it holds (this spec's or another's), and each
/// published file that is not as ribbar wrote it.
pub fn folder_report(store: &Store, scene: &Scene, keys: &Keys) -> Result<Vec<String>> {
    let dir = store.scene_dir(&scene.name);
    let record = match store.read_record(&scene.name) {
        Ok(Some(record)) => record,
        Ok(None) => return Ok(vec![format!("{}: no results yet", dir.display())]),
        Err(e) => {
            return Ok(vec![format!(
                "{e}: `ribbar run` keeps it aside and publishes the results again"
            )])
        }
    };
    let mut lines = Vec::new();
    if let Some(run) = &record.run {
        let when = utc_text(run.finished_unix_s.unwrap_or(run.started_unix_s));
        let how = match &run.outcome {
            RunOutcome::Running => {
                "has not ended (still running, or killed): its files are those of the stages it finished".to_string()
            }
            RunOutcome::Complete => "completed".to_string(),
            RunOutcome::Stopped { reason } => format!("stopped early in the solve: {reason}"),
            RunOutcome::Failed { stage, error } => format!(
                "failed in stage {stage}: {}",
                error.lines().next().unwrap_or_default()
            ),
        };
        lines.push(format!(
            "{} shows the `ribbar {}` of {when}, which {how}",
            dir.display(),
            run.command
        ));
    }
    let held: Vec<String> = Stage::ALL
        .iter()
        .filter_map(|s| {
            let p = record.stages.get(s.name())?;
            Some(if p.key.key == keys.get(*s).key {
                format!("{s} (this spec)")
            } else {
                format!("{s} (other inputs)")
            })
        })
        .collect();
    lines.push(if held.is_empty() {
        "it holds no stage's files".to_string()
    } else {
        format!("it holds the files of {}", held.join(", "))
    });
    for stage in Stage::ALL {
        let Some(p) = record.stages.get(stage.name()) else {
            continue;
        };
        let files = stage.published_files();
        for (path, state) in store.published_changes(&scene.name, p, files, Compare::Quick) {
            let what = match state {
                FileState::Absent => "missing",
                _ => "changed since ribbar wrote it",
            };
            lines.push(format!(
                "{}: {what} (the stored result is intact; `ribbar run` publishes it again{})",
                path.display(),
                if state == FileState::Absent {
                    ""
                } else {
                    " and keeps this file beside it"
                }
            ));
        }
    }
    Ok(lines)
}
