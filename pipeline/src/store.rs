//! Content-addressed artifact store under the work directory.
//!
//! Layout:
//! ```text
//! WORK/.store/<stage>/<key>/           finished artifacts of one stage run
//! WORK/.store/<stage>/<key>/stage.json what was hashed (the key's inputs)
//! WORK/.store/<stage>/<key>.partial/   a run in progress (never read as done)
//! WORK/.store/<stage>/<key>.lock       held while a process works on <key>
//! WORK/<scene>/                        the scene's latest results, by name
//! WORK/<scene>/.ribbar-stages.json     which key each stage last published
//! ```
//! A key is the SHA-256 of the canonical JSON of exactly what the stage reads
//! (resolved spec sections, upstream keys, versions that change results);
//! never paths or times. A stage directory becomes visible under its key only
//! by one `rename` after `stage.json` is written, so an interrupted stage is
//! never taken as done. Two processes that need the same key serialise on its
//! lock file; the second then finds it done.

use serde::{Deserialize, Serialize};
use serde_json::Value;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::fs::{self, File};
use std::path::{Path, PathBuf};

/// Bumped when the store layout changes; part of every key.
pub const STORE_FORMAT: u32 = 1;

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
}

fn io_err(path: &Path) -> impl FnOnce(std::io::Error) -> StoreError + '_ {
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
pub fn changed_keys(old: &Value, new: &Value) -> Vec<String> {
    let (a, b) = (flatten(old), flatten(new));
    let mut keys: Vec<String> = a
        .keys()
        .chain(b.keys())
        .filter(|k| a.get(*k) != b.get(*k))
        .cloned()
        .collect();
    keys.dedup();
    keys.sort();
    keys.dedup();
    keys
}

/// The scene's record of what each stage last published.
pub type SceneRecord = BTreeMap<String, StageKey>;

pub struct Store {
    pub work: PathBuf,
}

/// An exclusive lock on one stage key, held by one thread of one process
/// on any host that shares the work directory; released on drop
/// (`crate::store_lock`).
pub struct KeyLock {
    lock: crate::store_lock::FileLock,
}

impl KeyLock {
    /// `Err` when another process took this lock while it was held (a file
    /// system whose locks do not hold across hosts).
    pub fn verify(&self) -> Result<(), StoreError> {
        Ok(self.lock.verify()?)
    }
}

impl Store {
    /// The work directory is made absolute once, so every stage and every
    /// tool it runs (gmsh runs in other directories) sees the same paths.
    pub fn new(work: impl Into<PathBuf>) -> Self {
        let work = work.into();
        Store {
            work: std::path::absolute(&work).unwrap_or(work),
        }
    }

    fn stage_root(&self, stage: &str) -> PathBuf {
        self.work.join(".store").join(stage)
    }

    pub fn artifact_dir(&self, key: &StageKey) -> PathBuf {
        self.stage_root(&key.stage).join(&key.key)
    }

    pub fn partial_dir(&self, key: &StageKey) -> PathBuf {
        self.stage_root(&key.stage)
            .join(format!("{}.partial", key.key))
    }

    pub fn scene_dir(&self, scene: &str) -> PathBuf {
        self.work.join(scene)
    }

    /// Wall time recorded when `key`'s artifacts were produced, s.
    pub fn wall_time(&self, key: &StageKey) -> Option<f64> {
        let bytes = fs::read(self.artifact_dir(key).join("stage.json")).ok()?;
        serde_json::from_slice::<StageKey>(&bytes).ok()?.wall_time_s
    }

    pub fn is_done(&self, key: &StageKey) -> bool {
        self.artifact_dir(key).join("stage.json").is_file()
    }

    /// Blocks until no other thread, process or host works on this key.
    pub fn lock(&self, key: &StageKey) -> Result<KeyLock, StoreError> {
        let root = self.stage_root(&key.stage);
        fs::create_dir_all(&root).map_err(io_err(&root))?;
        let path = root.join(format!("{}.lock", key.key));
        let lock = crate::store_lock::lock_exclusive(&path)?;
        // On NFS a name looked up before the lock may be cached: opening the
        // directory revalidates it (close-to-open), so the `is_done` that
        // follows sees a commit another host made while this one waited.
        let _ = File::open(&root);
        Ok(KeyLock { lock })
    }

    /// A fresh (emptied) in-progress directory for `key`. With `keep`, an
    /// existing one is reused (resumable stages keep their checkpoint there).
    pub fn begin(&self, key: &StageKey, keep: bool) -> Result<PathBuf, StoreError> {
        let dir = self.partial_dir(key);
        if dir.exists() && !keep {
            fs::remove_dir_all(&dir).map_err(io_err(&dir))?;
        }
        fs::create_dir_all(&dir).map_err(io_err(&dir))?;
        Ok(dir)
    }

    /// Marks the in-progress directory done: writes `stage.json` and renames
    /// the directory to its key in one step.
    pub fn commit(
        &self,
        key: &StageKey,
        partial: &Path,
        wall_time_s: f64,
    ) -> Result<PathBuf, StoreError> {
        let record = StageKey {
            wall_time_s: Some(wall_time_s),
            ..key.clone()
        };
        write_atomic(
            &partial.join("stage.json"),
            &serde_json::to_vec_pretty(&record).expect("serialisable"),
        )?;
        let done = self.artifact_dir(key);
        if done.exists() {
            // A concurrent process finished the same key first; ours is identical.
            fs::remove_dir_all(partial).map_err(io_err(partial))?;
        } else {
            fs::rename(partial, &done).map_err(io_err(&done))?;
        }
        sync_dir(&self.stage_root(&key.stage));
        Ok(done)
    }

    pub fn read_record(&self, scene: &str) -> Result<SceneRecord, StoreError> {
        let path = self.scene_dir(scene).join(".ribbar-stages.json");
        match fs::read(&path) {
            Ok(bytes) => serde_json::from_slice(&bytes).map_err(|e| StoreError::Corrupt {
                path: path.clone(),
                reason: e.to_string(),
            }),
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(SceneRecord::new()),
            Err(e) => Err(StoreError::Io { path, source: e }),
        }
    }

    /// Makes `files` (relative paths inside the artifact directory) visible
    /// under `WORK/<scene>/` and records the key. Each file is replaced
    /// atomically; directories are mirrored.
    pub fn publish(&self, scene: &str, key: &StageKey, files: &[&str]) -> Result<(), StoreError> {
        let src_root = self.artifact_dir(key);
        let dst_root = self.scene_dir(scene);
        fs::create_dir_all(&dst_root).map_err(io_err(&dst_root))?;
        for rel in files {
            let src = src_root.join(rel);
            if src.is_dir() {
                let dst = dst_root.join(rel);
                if dst.exists() {
                    fs::remove_dir_all(&dst).map_err(io_err(&dst))?;
                }
                copy_tree(&src, &dst)?;
            } else if src.is_file() {
                link_or_copy_atomic(&src, &dst_root.join(rel))?;
            }
        }
        let mut record = self.read_record(scene).unwrap_or_default();
        record.insert(key.stage.clone(), key.clone());
        write_atomic(
            &dst_root.join(".ribbar-stages.json"),
            &serde_json::to_vec_pretty(&record).expect("serialisable"),
        )
    }
}

fn copy_tree(src: &Path, dst: &Path) -> Result<(), StoreError> {
    fs::create_dir_all(dst).map_err(io_err(dst))?;
    for entry in fs::read_dir(src).map_err(io_err(src))? {
        let entry = entry.map_err(io_err(src))?;
        let path = entry.path();
        let target = dst.join(entry.file_name());
        if path.is_dir() {
            copy_tree(&path, &target)?;
        } else {
            link_or_copy_atomic(&path, &target)?;
        }
    }
    Ok(())
}

/// Hard-links (same file system, no copy of large meshes) or copies `src`
/// to a temporary name beside `dst`, then renames it over `dst`.
fn link_or_copy_atomic(src: &Path, dst: &Path) -> Result<(), StoreError> {
    if let Some(parent) = dst.parent() {
        fs::create_dir_all(parent).map_err(io_err(parent))?;
    }
    if same_file(src, dst) {
        return Ok(());
    }
    let tmp = geom::fsutil::temp_sibling(dst);
    let _ = fs::remove_file(&tmp);
    if fs::hard_link(src, &tmp).is_err() {
        fs::copy(src, &tmp).map_err(io_err(&tmp))?;
    }
    let renamed = fs::rename(&tmp, dst).map_err(io_err(dst));
    // rename() between two links of one file succeeds without removing the
    // source name (POSIX), which a concurrent publish can make happen.
    let _ = fs::remove_file(&tmp);
    renamed
}

#[cfg(unix)]
fn same_file(a: &Path, b: &Path) -> bool {
    use std::os::unix::fs::MetadataExt;
    match (fs::metadata(a), fs::metadata(b)) {
        (Ok(x), Ok(y)) => x.dev() == y.dev() && x.ino() == y.ino(),
        _ => false,
    }
}

#[cfg(not(unix))]
fn same_file(_: &Path, _: &Path) -> bool {
    false
}

/// Writes a file so that readers see either the old or the whole new content.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), StoreError> {
    geom::fsutil::write_atomic(path, bytes).map_err(io_err(path))
}

fn sync_dir(dir: &Path) {
    // Durability of the rename; failure here only weakens crash safety.
    if let Ok(d) = File::open(dir) {
        let _ = d.sync_all();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    #[test]
    fn keys_depend_on_content_only_and_name_changed_keys() {
        let a = StageKey::new(
            "solve",
            json!({"materials": {"interface": {"mu": 0.3}}, "mesh": "k1"}),
        );
        let b = StageKey::new(
            "solve",
            json!({"mesh": "k1", "materials": {"interface": {"mu": 0.3}}}),
        );
        let c = StageKey::new(
            "solve",
            json!({"mesh": "k1", "materials": {"interface": {"mu": 0.001}}}),
        );
        assert_eq!(a.key, b.key);
        assert_ne!(a.key, c.key);
        assert_eq!(
            changed_keys(&a.inputs, &c.inputs),
            vec!["materials.interface.mu".to_string()]
        );
    }

    #[test]
    fn a_partial_stage_is_never_done_and_commit_publishes() {
        let work = std::env::temp_dir().join(format!("ribbar-store-test-{}", std::process::id()));
        let _ = fs::remove_dir_all(&work);
        let store = Store::new(&work);
        let key = StageKey::new("geometry", json!({"bar": 1}));
        let _lock = store.lock(&key).unwrap();
        let partial = store.begin(&key, false).unwrap();
        fs::write(partial.join("geometry.json"), "{}").unwrap();
        assert!(!store.is_done(&key));
        store.commit(&key, &partial, 0.5).unwrap();
        assert!(store.is_done(&key));
        store.publish("r1", &key, &["geometry.json"]).unwrap();
        assert!(work.join("r1/geometry.json").is_file());
        assert_eq!(store.read_record("r1").unwrap()["geometry"].key, key.key);
        fs::remove_dir_all(&work).unwrap();
    }
}
