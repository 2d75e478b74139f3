//! What `ribbar status` says of each stage of a scene.

use super::keys::Keys;
use super::kinds::{Stage, CHECKPOINT_FILE};
use crate::scene::Scene;
use crate::store::{changed_keys, StageKey, Store};
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
}

pub fn status(store: &Store, scene: &Scene, keys: &Keys) -> Result<Vec<(Stage, StageStatus)>> {
    let record = store.read_record(&scene.name)?;
    Ok(Stage::ALL
        .into_iter()
        .map(|stage| {
            let key = keys.get(stage);
            let st = if store.is_done(key) {
                StageStatus::UpToDate
            } else if store.partial_dir(key).join(CHECKPOINT_FILE).is_file() {
                StageStatus::Interrupted
            } else if let Some(old) = record.get(stage.name()) {
                StageStatus::Stale(stale_reasons(old, key))
            } else {
                StageStatus::Missing
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
    reasons
}
