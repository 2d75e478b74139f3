//! The store's vocabulary: its names and format, its error, a stage's key,
//! and the atomic write every part of it uses.

use serde::{Deserialize, Serialize};
use serde_json::Value;
use sha2::{Digest as _, Sha256};
use std::collections::BTreeMap;
use std::fs::File;
use std::path::{Path, PathBuf};

/// Bumped when the store layout changes; part of every key. Format 2: each
/// artifact's digests in `stage.json`, copies in the results folders.
pub const STORE_FORMAT: u32 = 2;

/// Where folders and files that failed their checks are moved.
pub const QUARANTINE: &str = "quarantine";
/// A stage's folder of recorded artifacts: the record itself.
pub const STAGE_FILE: &str = "stage.json";
/// The record's file name in a results folder.
pub const RECORD_FILE: &str = ".ribbar-stages.json";

#[derive(Debug, thiserror::Error)]
pub enum StoreError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: corrupt store record ({reason}); remove it or run `ribbar clean`")]
    Corrupt { path: PathBuf, reason: String },
    #[error(transparent)]
    Lock(#[from] crate::store_lock::LockError),
    #[error(
        "{path} exists and was not made by ribbar (it has no {RECORD_FILE}): ribbar would mix \
         its results with the files there; move them away or choose another --work"
    )]
    NotOurs { path: PathBuf },
}

pub(crate) fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> StoreError + '_ {
    move |source| StoreError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// The identity of one stage run: its name and what it reads.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageKey {
    pub stage: String,
    pub key: String,
    /// The exact document that was hashed.
    pub inputs: Value,
    /// The spec keys as written that this stage reads (not hashed): lets
    /// `status` name what the user changed.
    #[serde(default)]
    pub written: Value,
    /// Wall time of the run that produced the artifacts, s (not hashed).
    #[serde(default)]
    pub wall_time_s: Option<f64>,
}

impl StageKey {
    pub fn new(stage: &str, inputs: Value) -> Self {
        let document =
            serde_json::json!({ "stage": stage, "store_format": STORE_FORMAT, "inputs": inputs });
        // serde_json's Map is ordered by key (no preserve_order feature), so
        // this serialisation is canonical.
        let bytes = serde_json::to_vec(&document).expect("JSON values always serialise");
        let digest = Sha256::digest(&bytes);
        let key = digest.iter().take(16).map(|b| format!("{b:02x}")).collect();
        StageKey {
            stage: stage.to_string(),
            key,
            inputs,
            written: Value::Null,
            wall_time_s: None,
        }
    }

    pub fn with_written(mut self, written: Value) -> Self {
        self.written = written;
        self
    }
}

/// Flattens a JSON tree into dotted keys, for "which key changed" messages.
pub fn flatten(value: &Value) -> BTreeMap<String, String> {
    fn walk(prefix: &str, v: &Value, out: &mut BTreeMap<String, String>) {
        match v {
            Value::Object(map) if !map.is_empty() => {
                for (k, child) in map {
                    let p = if prefix.is_empty() {
                        k.clone()
                    } else {
                        format!("{prefix}.{k}")
                    };
                    walk(&p, child, out);
                }
            }
            other => {
                out.insert(prefix.to_string(), other.to_string());
            }
        }
    }
    let mut out = BTreeMap::new();
    walk("", value, &mut out);
    out
}

/// Dotted keys whose values differ between two input documents.
/// A section absent on one side (a null leaf) and written on the other is
/// named by its keys, not by the section itself; an absent section and an
/// empty one are the same.
pub fn changed_keys(old: &Value, new: &Value) -> Vec<String> {
    let (a, b) = (flatten(old), flatten(new));
    let written = |v: Option<&String>| v.filter(|v| *v != "null" && *v != "{}").cloned();
    let section_of_the_other = |k: &str, other: &BTreeMap<String, String>| {
        let prefix = format!("{k}.");
        other
            .range(prefix.clone()..)
            .next()
            .is_some_and(|(o, _)| o.starts_with(&prefix))
    };
    let mut keys: Vec<String> = a
        .keys()
        .chain(b.keys())
        .filter(|k| written(a.get(*k)) != written(b.get(*k)))
        .filter(|k| !section_of_the_other(k, &a) && !section_of_the_other(k, &b))
        .cloned()
        .collect();
    keys.dedup();
    keys.sort();
    keys.dedup();
    keys
}

/// The store under one work directory.
pub struct Store {
    pub work: PathBuf,
}

/// Writes a file so that readers see either the old or the whole new content.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), StoreError> {
    geom::fsutil::write_atomic(path, bytes).map_err(io_err(path))
}

pub(super) fn sync_dir(dir: &Path) {
    // Durability of the rename; failure here only weakens crash safety.
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
}
