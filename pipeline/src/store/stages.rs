//! A stage's folder under its key: what finished means, the lock, begin,
//! commit and the quarantine.

use super::base::{
    io_err, sync_dir, write_atomic, StageKey, Store, StoreError, QUARANTINE, STAGE_FILE,
};
use super::digest::{self, Depth, FileDigest};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fs::{self, File};
use std::path::{Path, PathBuf};

/// Below this many bytes a stage's files are always checked by digest.
const ALWAYS_DIGEST_BYTES: u64 = 1 << 20;
/// Beyond that, by digest when hashing them costs under about 1 % of the
/// stage's own time: bytes per second of the stage's recorded wall time
/// (1 % of 300 MB/s, a SHA-256 rate without hardware help).
const DIGEST_BYTES_PER_STAGE_SECOND: f64 = 3e6;

/// A stage's `stage.json`: its key and what was hashed, the run's wall
/// time, and the record of every file it made.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StageRecord {
    #[serde(flatten)]
    pub key: StageKey,
    /// Every artifact file, by its path relative to the folder.
    pub files: BTreeMap<String, FileDigest>,
}

impl StageRecord {
    /// Total size of the recorded files, bytes.
    pub fn bytes(&self) -> u64 {
        self.files.values().map(|f| f.size).sum()
    }

    /// How a lookup checks this record's folder: by digest when that is
    /// cheap against what the stage cost to make, by sizes otherwise.
    pub fn lookup_depth(&self) -> Depth {
        let bytes = self.bytes();
        let budget = self.key.wall_time_s.unwrap_or(0.0) * DIGEST_BYTES_PER_STAGE_SECOND;
        if bytes <= ALWAYS_DIGEST_BYTES || (bytes as f64) <= budget {
            Depth::Digests
        } else {
            Depth::Sizes
        }
    }
}

/// What [`Store::examine`] found under a key.
#[derive(Debug, Clone, PartialEq)]
pub enum Examined {
    /// Nothing under the key.
    Absent,
    /// A finished folder: its record agrees with its files.
    Finished(StageRecord),
    /// Something under the key that is not finished: why, naming the file.
    Damaged(String),
}

/// How thoroughly [`Store::examine`] checks a folder's files.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Thoroughness {
    /// The record's own choice ([`StageRecord::lookup_depth`]).
    Lookup,
    /// Every file's digest (`ribbar verify`, commit).
    Full,
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

    pub fn stage_root(&self, stage: &str) -> PathBuf {
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

    pub fn quarantine_dir(&self) -> PathBuf {
        self.work.join(".store").join(QUARANTINE)
    }

    /// Wall time recorded when `key`'s artifacts were produced, s.
    pub fn wall_time(&self, key: &StageKey) -> Option<f64> {
        let path = self.artifact_dir(key).join(STAGE_FILE);
        let text = geom::fsutil::read_capped(&path, geom::fsutil::MAX_RECORD_BYTES).ok()?;
        serde_json::from_str::<StageRecord>(&text)
            .ok()?
            .key
            .wall_time_s
    }

    /// Whether `key` is finished (checked as a lookup checks it).
    pub fn is_done(&self, key: &StageKey) -> bool {
        matches!(
            self.examine(key, Thoroughness::Lookup),
            Examined::Finished(_)
        )
    }

    /// The one definition of a finished stage folder (module doc).
    pub fn examine(&self, key: &StageKey, thoroughness: Thoroughness) -> Examined {
        self.examine_key(&key.stage, &key.key, thoroughness)
    }

    /// [`Store::examine`] of `stage`'s folder `key`.
    pub fn examine_key(&self, stage: &str, key: &str, thoroughness: Thoroughness) -> Examined {
        let dir = self.stage_root(stage).join(key);
        examine_dir(&dir, stage, key, thoroughness)
    }

    /// Moves `path` (a folder or a file of the store) into the quarantine
    /// as `<label>-<n>`; returns where it went.
    pub fn quarantine(&self, path: &Path, label: &str) -> Result<PathBuf, StoreError> {
        let root = self.quarantine_dir();
        fs::create_dir_all(&root).map_err(io_err(&root))?;
        let target = (1..)
            .map(|n| root.join(format!("{label}-{n}")))
            .find(|p| fs::symlink_metadata(p).is_err())
            .expect("an unused name");
        fs::rename(path, &target).map_err(io_err(path))?;
        sync_dir(&root);
        Ok(target)
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

    /// The lock on `stage`'s `key` if no other process holds it (`None`
    /// if one does).
    pub fn try_lock(&self, stage: &str, key: &str) -> Result<Option<KeyLock>, StoreError> {
        let root = self.stage_root(stage);
        fs::create_dir_all(&root).map_err(io_err(&root))?;
        let path = root.join(format!("{key}.lock"));
        Ok(crate::store_lock::try_lock_exclusive(&path)?.map(|lock| KeyLock { lock }))
    }

    /// The in-progress directory of `stage`'s `key`.
    pub fn partial_dir_of(&self, stage: &str, key: &str) -> PathBuf {
        self.stage_root(stage).join(format!("{key}.partial"))
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

    /// Marks the in-progress directory done: records every file (size,
    /// time, digest), makes them read-only, writes `stage.json` and renames
    /// the directory to its key in one step. A folder already under the key
    /// is kept when it is finished (a concurrent process made the same
    /// result) and moved to the quarantine when it is not.
    pub fn commit(
        &self,
        key: &StageKey,
        partial: &Path,
        wall_time_s: f64,
    ) -> Result<Committed, StoreError> {
        let files = digest::seal(partial, &[STAGE_FILE])?;
        let record = StageRecord {
            key: StageKey {
                wall_time_s: Some(wall_time_s),
                ..key.clone()
            },
            files,
        };
        let stage_json = partial.join(STAGE_FILE);
        write_atomic(
            &stage_json,
            &serde_json::to_vec_pretty(&record).expect("serialisable"),
        )?;
        digest::make_read_only(&stage_json)?;
        let done = self.artifact_dir(key);
        let mut replaced = None;
        match self.examine(key, Thoroughness::Full) {
            Examined::Finished(theirs) => {
                fs::remove_dir_all(partial).map_err(io_err(partial))?;
                return Ok(Committed {
                    record: theirs,
                    replaced,
                });
            }
            Examined::Damaged(why) => {
                let to = self.quarantine(&done, &format!("{}-{}", key.stage, key.key))?;
                replaced = Some((why, to));
            }
            Examined::Absent => {}
        }
        fs::rename(partial, &done).map_err(io_err(&done))?;
        sync_dir(&self.stage_root(&key.stage));
        Ok(Committed { record, replaced })
    }
}

/// What [`Store::commit`] did.
#[derive(Debug)]
pub struct Committed {
    /// The record now under the key.
    pub record: StageRecord,
    /// A folder found under the key that was not finished: why, and where
    /// it was moved.
    pub replaced: Option<(String, PathBuf)>,
}

/// [`Store::examine`] of the folder `dir` expected to hold `key`.
fn examine_dir(dir: &Path, stage: &str, key: &str, thoroughness: Thoroughness) -> Examined {
    match fs::symlink_metadata(dir) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Examined::Absent,
        Err(e) => return Examined::Damaged(format!("{}: {e}", dir.display())),
        Ok(m) if !m.is_dir() => {
            return Examined::Damaged(format!("{}: not a directory", dir.display()))
        }
        Ok(_) => {}
    }
    let stage_json = dir.join(STAGE_FILE);
    let bytes = match geom::fsutil::read_capped(&stage_json, geom::fsutil::MAX_RECORD_BYTES) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Examined::Damaged(format!(
                "{}: missing (the folder was never finished, or was partly removed)",
                stage_json.display()
            ))
        }
        Err(e) => return Examined::Damaged(format!("{}: {e}", stage_json.display())),
    };
    let record: StageRecord = match serde_json::from_str(&bytes) {
        Ok(r) => r,
        Err(e) => {
            return Examined::Damaged(format!(
                "{}: not a record of this ribbar ({e})",
                stage_json.display()
            ))
        }
    };
    if record.key.stage != stage || record.key.key != key {
        return Examined::Damaged(format!(
            "{}: the record of {} {}, not of this key",
            stage_json.display(),
            record.key.stage,
            record.key.key
        ));
    }
    let depth = match thoroughness {
        Thoroughness::Lookup => record.lookup_depth(),
        Thoroughness::Full => Depth::Digests,
    };
    match digest::first_difference(dir, &record.files, depth) {
        Some(why) => Examined::Damaged(why),
        None => Examined::Finished(record),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::store::changed_keys;
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

    fn scratch(name: &str) -> PathBuf {
        let work = std::env::temp_dir().join(format!("ribbar-store-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&work);
        work
    }

    /// A partial stage is never done; a committed one is, with its files
    /// recorded and read-only, and the published copy is not the stored file.
    #[test]
    fn a_partial_stage_is_never_done_and_commit_publishes() {
        let work = scratch("commit");
        let store = Store::new(&work);
        let key = StageKey::new("geometry", json!({"bar": 1}));
        let _lock = store.lock(&key).unwrap();
        let partial = store.begin(&key, false).unwrap();
        fs::write(partial.join("geometry.json"), "{}").unwrap();
        assert!(!store.is_done(&key));
        let committed = store.commit(&key, &partial, 0.5).unwrap();
        assert!(store.is_done(&key));
        assert_eq!(committed.record.files["geometry.json"].size, 2);
        let stored = store.artifact_dir(&key).join("geometry.json");
        assert!(fs::metadata(&stored).unwrap().permissions().readonly());
        store
            .publish("r1", &committed.record, &["geometry.json"])
            .unwrap();
        let published = work.join("r1/geometry.json");
        assert!(published.is_file());
        assert!(!fs::metadata(&published).unwrap().permissions().readonly());
        fs::write(&published, "{\"edited\": 1}").unwrap();
        assert_eq!(fs::read_to_string(&stored).unwrap(), "{}");
        let record = store.read_record("r1").unwrap().unwrap();
        assert_eq!(record.stages["geometry"].key.key, key.key);
        fs::remove_dir_all(&work).unwrap();
    }

    /// One definition of finished for lookup and commit: a folder under the
    /// key without `stage.json` is not finished, and a commit moves it to the
    /// quarantine instead of keeping it and dropping the fresh result.
    #[test]
    fn commit_replaces_an_unfinished_folder_and_keeps_it_aside() {
        let work = scratch("unfinished");
        let store = Store::new(&work);
        let key = StageKey::new("solve", json!({"mu": 0.3}));
        let stale = store.artifact_dir(&key);
        fs::create_dir_all(&stale).unwrap();
        fs::write(stale.join("curve.csv"), "stale").unwrap();
        let Examined::Damaged(why) = store.examine(&key, Thoroughness::Lookup) else {
            panic!("an unfinished folder is not finished");
        };
        assert!(why.contains("stage.json: missing"), "{why}");
        let partial = store.begin(&key, false).unwrap();
        fs::write(partial.join("curve.csv"), "fresh").unwrap();
        let committed = store.commit(&key, &partial, 0.1).unwrap();
        let (_, moved) = committed.replaced.expect("the stale folder was moved");
        assert_eq!(
            fs::read_to_string(moved.join("curve.csv")).unwrap(),
            "stale"
        );
        assert_eq!(
            fs::read_to_string(stale.join("curve.csv")).unwrap(),
            "fresh"
        );
        assert!(store.is_done(&key));
        // A second commit of the same key finds the first finished and
        // keeps it (a concurrent process made the same result).
        let partial = store.begin(&key, false).unwrap();
        fs::write(partial.join("curve.csv"), "fresh").unwrap();
        assert!(store
            .commit(&key, &partial, 0.1)
            .unwrap()
            .replaced
            .is_none());
        assert!(!partial.exists());
        // The record of another key in the folder is not this key's.
        let other = StageKey::new("solve", json!({"mu": 0.4}));
        let other_dir = store.artifact_dir(&other);
        fs::create_dir_all(store.stage_root("solve")).unwrap();
        copy_dir(&stale, &other_dir);
        let Examined::Damaged(why) = store.examine(&other, Thoroughness::Lookup) else {
            panic!("a copied folder is not the other key's");
        };
        assert!(why.contains("not of this key"), "{why}");
        fs::remove_dir_all(&work).unwrap();
    }

    fn copy_dir(from: &Path, to: &Path) {
        fs::create_dir_all(to).unwrap();
        for e in fs::read_dir(from).unwrap() {
            let e = e.unwrap();
            fs::copy(e.path(), to.join(e.file_name())).unwrap();
        }
    }

    /// Lookups check by digest when the files are small or cheap to hash
    /// against the stage's time, by sizes (and moved times) otherwise.
    #[test]
    fn lookups_check_digests_when_cheap() {
        let record = |bytes: u64, wall: f64| StageRecord {
            key: StageKey {
                wall_time_s: Some(wall),
                ..StageKey::new("solve", json!({}))
            },
            files: [(
                "curve.csv".to_string(),
                FileDigest {
                    size: bytes,
                    sha256: String::new(),
                    mtime_ns: 0,
                },
            )]
            .into(),
        };
        assert_eq!(record(1000, 0.0).lookup_depth(), Depth::Digests);
        assert_eq!(record(300_000_000, 100.0).lookup_depth(), Depth::Digests);
        assert_eq!(record(300_000_000, 10.0).lookup_depth(), Depth::Sizes);
    }
}
