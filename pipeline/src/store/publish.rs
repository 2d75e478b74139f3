//! Publishing a stage's artifacts into its results folder as copies, and
//! taking them out again, without ever overwriting or deleting a file that
//! ribbar did not write there as it is: a published file that was edited
//! (or a file of the user's in its place) is moved aside under a name that
//! says so, and the caller is told.
//!
//! Copies, not hard links: a hard link is the stored file itself, so an
//! editor that saves in place would change the artifact of every scene and
//! study case that shares it. `std::fs::copy` lets the file system make a
//! reflink where it can (`copy_file_range`); elsewhere the bytes are copied
//! once per publish, and an unchanged published file is never copied again.

use super::base::{io_err, Store, StoreError, RECORD_FILE};
use super::digest::{mtime_ns, sha256_file};
use super::record::{PublishedFile, PublishedStage, SceneRecord};
use super::stages::StageRecord;
use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

/// Nanoseconds spent publishing in this process, and bytes copied.
static PUBLISH_NANOS: AtomicU64 = AtomicU64::new(0);
static COPIED_BYTES: AtomicU64 = AtomicU64::new(0);

/// Time spent publishing results folders so far in this process, s, and
/// the bytes copied.
pub fn publish_cost() -> (f64, u64) {
    (
        PUBLISH_NANOS.load(Ordering::Relaxed) as f64 * 1e-9,
        COPIED_BYTES.load(Ordering::Relaxed),
    )
}

/// What is at a published path, against what ribbar wrote there.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FileState {
    Absent,
    /// The file ribbar wrote there, unchanged.
    Ours,
    /// A file with exactly the content about to be published.
    Same,
    /// Anything else: edited since ribbar wrote it, or not ribbar's.
    Changed,
}

/// What a publish or an unpublish did beyond the expected.
#[derive(Debug, Default)]
pub struct Published {
    /// Files moved aside (each a sentence naming both paths).
    pub notes: Vec<String>,
    /// Bytes copied.
    pub copied_bytes: u64,
}

/// Whether `rel` is one of `entries` or inside one of them.
pub fn under(rel: &str, entries: &[&str]) -> bool {
    entries
        .iter()
        .any(|e| rel == *e || rel.strip_prefix(e).is_some_and(|r| r.starts_with('/')))
}

/// The name a changed file is kept under beside `path`: `curve.csv` →
/// `curve.edited.csv` (`curve.edited-2.csv`, … when taken), so that it
/// still opens with the same program.
pub fn edited_name(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    (1..)
        .map(|n| {
            let suffix = if n == 1 {
                String::new()
            } else {
                format!("-{n}")
            };
            path.with_file_name(format!("{stem}.edited{suffix}{ext}"))
        })
        .find(|p| fs::symlink_metadata(p).is_err())
        .expect("an unused name")
}

/// Why a path is taken to be ribbar's.
#[derive(Clone, Copy)]
enum Claim<'a> {
    /// The record of what ribbar wrote there.
    Recorded(&'a PublishedFile),
    /// Published by a ribbar that kept no file records.
    Legacy,
    None,
}

/// How a published file is compared with its record.
#[derive(Clone, Copy, PartialEq, Eq)]
pub enum Compare {
    /// Size and time first; the digest only when they moved.
    Quick,
    /// Always the digest (`ribbar verify`).
    Digest,
}

/// The state of `path` against `claim` and the content about to go there.
fn state(path: &Path, claim: Claim, new_sha: Option<&str>) -> Result<FileState, StoreError> {
    state_by(path, claim, new_sha, Compare::Quick)
}

fn state_by(
    path: &Path,
    claim: Claim,
    new_sha: Option<&str>,
    compare: Compare,
) -> Result<FileState, StoreError> {
    let meta = match fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(FileState::Absent),
        Err(e) => return Err(io_err(path)(e)),
    };
    if !meta.is_file() {
        return Ok(FileState::Changed);
    }
    if let (Claim::Recorded(r), Compare::Quick) = (claim, compare) {
        if meta.len() == r.size && mtime_ns(&meta) == r.mtime_ns {
            return Ok(if new_sha == Some(r.sha256.as_str()) {
                FileState::Same
            } else {
                FileState::Ours
            });
        }
    }
    let sha = sha256_file(path)?;
    Ok(match claim {
        _ if new_sha == Some(sha.as_str()) => FileState::Same,
        Claim::Recorded(r) if r.sha256 == sha => FileState::Ours,
        Claim::Legacy => FileState::Ours,
        _ => FileState::Changed,
    })
}

/// Moves a changed file aside; the sentence that says so.
fn move_aside(path: &Path, why: &str) -> Result<String, StoreError> {
    let kept = edited_name(path);
    fs::rename(path, &kept).map_err(io_err(path))?;
    Ok(format!(
        "{} {why}: kept as {}",
        path.display(),
        kept.file_name().unwrap_or_default().to_string_lossy()
    ))
}

/// Moves aside anything that is not a folder where `rel` needs one (a file
/// named `fields`, say); the sentences that say so.
fn clear_the_way(root: &Path, rel: &str) -> Result<Vec<String>, StoreError> {
    let mut notes = Vec::new();
    let mut dir = root.to_path_buf();
    let parts: Vec<&str> = rel.split('/').collect();
    for part in &parts[..parts.len().saturating_sub(1)] {
        dir.push(part);
        if fs::symlink_metadata(&dir).is_ok_and(|m| !m.is_dir()) {
            notes.push(move_aside(
                &dir,
                "is where ribbar puts a folder of results",
            )?);
        }
    }
    Ok(notes)
}

/// The record of a file as it now is at `path`, with `sha256`.
fn fingerprint(path: &Path, sha256: &str) -> Result<PublishedFile, StoreError> {
    let meta = fs::metadata(path).map_err(io_err(path))?;
    Ok(PublishedFile {
        size: meta.len(),
        sha256: sha256.to_string(),
        mtime_ns: mtime_ns(&meta),
    })
}

/// Copies `src` over `dst` through a temporary sibling; the copy is
/// writable (the stored file is not).
fn copy_atomic(src: &Path, dst: &Path) -> Result<u64, StoreError> {
    if let Some(parent) = dst.parent() {
        fs::create_dir_all(parent).map_err(io_err(parent))?;
    }
    let tmp = geom::fsutil::temp_sibling(dst);
    let _ = fs::remove_file(&tmp);
    let copied = fs::copy(src, &tmp).map_err(|e| {
        // A disk that filled up leaves no half copy behind.
        let _ = fs::remove_file(&tmp);
        io_err(&tmp)(e)
    })?;
    let mut perms = fs::metadata(&tmp).map_err(io_err(&tmp))?.permissions();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        perms.set_mode(0o644);
    }
    #[cfg(not(unix))]
    #[allow(clippy::permissions_set_readonly_false)]
    perms.set_readonly(false);
    fs::set_permissions(&tmp, perms).map_err(io_err(&tmp))?;
    fs::rename(&tmp, dst).map_err(io_err(dst))?;
    Ok(copied)
}

/// The files a published stage holds in `dir`, each with its claim.
fn files_of<'a>(
    dir: &Path,
    stage: &'a PublishedStage,
    entries: &[&str],
) -> Vec<(String, Claim<'a>)> {
    match &stage.files {
        Some(files) => files
            .iter()
            .map(|(rel, f)| (rel.clone(), Claim::Recorded(f)))
            .collect(),
        // Files kept aside as changed are never taken for results.
        None => super::digest::list_files(dir, &[])
            .unwrap_or_default()
            .into_iter()
            .filter(|rel| under(rel, entries) && super::record::unedited(rel) == *rel)
            .map(|rel| (rel, Claim::Legacy))
            .collect(),
    }
}

/// The claim ribbar has on `rel` in a folder with `record` (`entries`:
/// the stage being published's names, for a record without file lists).
fn claim_of<'a>(record: &'a SceneRecord, stage: &str, rel: &str, entries: &[&str]) -> Claim<'a> {
    let own = record.stages.get(stage);
    if own.is_some_and(|s| s.files.is_none()) && under(rel, entries) {
        return Claim::Legacy;
    }
    record
        .stages
        .values()
        .find_map(|s| s.files.as_ref()?.get(rel))
        .map_or(Claim::None, Claim::Recorded)
}

/// Removes the directories on the way from `rel`'s parent up to `root`
/// that are empty.
fn remove_empty_parents(root: &Path, rel: &str) {
    let mut dir = root.join(rel);
    while dir.pop() && dir.starts_with(root) && dir != root {
        if fs::remove_dir(&dir).is_err() {
            break;
        }
    }
}

impl Store {
    /// Copies the files of `record` under `entries` (names or folders of
    /// the stage's published files) into `WORK/<scene>/` and records them.
    /// Files the stage published before and no longer has go; either way a
    /// changed file is moved aside, never overwritten or deleted.
    pub fn publish(
        &self,
        scene: &str,
        record: &StageRecord,
        entries: &[&str],
    ) -> Result<Published, StoreError> {
        let started = Instant::now();
        let done = self.publish_copies(scene, record, entries)?;
        PUBLISH_NANOS.fetch_add(started.elapsed().as_nanos() as u64, Ordering::Relaxed);
        COPIED_BYTES.fetch_add(done.copied_bytes, Ordering::Relaxed);
        Ok(done)
    }

    fn publish_copies(
        &self,
        scene: &str,
        record: &StageRecord,
        entries: &[&str],
    ) -> Result<Published, StoreError> {
        let src_root = self.artifact_dir(&record.key);
        let dst_root = self.scene_dir(scene);
        fs::create_dir_all(&dst_root).map_err(io_err(&dst_root))?;
        let scene_record = self.read_record(scene)?.unwrap_or_default();
        let stage = record.key.stage.as_str();
        let mut done = Published::default();
        let mut files = BTreeMap::new();
        for (rel, digest) in record.files.iter().filter(|(r, _)| under(r, entries)) {
            let dst = dst_root.join(rel);
            done.notes.extend(clear_the_way(&dst_root, rel)?);
            let claim = claim_of(&scene_record, stage, rel, entries);
            let now = state(&dst, claim, Some(&digest.sha256))?;
            if now == FileState::Changed {
                done.notes.push(move_aside(
                    &dst,
                    "was changed after ribbar wrote it (or is not ribbar's)",
                )?);
            }
            if now != FileState::Same {
                done.copied_bytes += copy_atomic(&src_root.join(rel), &dst)?;
            }
            files.insert(rel.clone(), fingerprint(&dst, &digest.sha256)?);
        }
        if let Some(old) = scene_record.stages.get(stage) {
            for (rel, claim) in files_of(&dst_root, old, entries) {
                if !files.contains_key(&rel) {
                    done.notes.extend(self.take_out(&dst_root, &rel, claim)?);
                }
            }
        }
        self.update_record(scene, |r| {
            r.stages.insert(
                stage.to_string(),
                PublishedStage {
                    key: record.key.clone(),
                    files: Some(files),
                },
            );
        })?;
        Ok(done)
    }

    /// Takes `stage`'s published files out of `WORK/<scene>/` (those
    /// changed since ribbar wrote them are moved aside) and drops it from
    /// the record.
    pub fn unpublish(
        &self,
        scene: &str,
        stage: &str,
        entries: &[&str],
    ) -> Result<Published, StoreError> {
        let dst_root = self.scene_dir(scene);
        let Some(record) = self.read_record(scene)? else {
            return Ok(Published::default());
        };
        let mut done = Published::default();
        if let Some(old) = record.stages.get(stage) {
            for (rel, claim) in files_of(&dst_root, old, entries) {
                done.notes.extend(self.take_out(&dst_root, &rel, claim)?);
            }
        }
        self.update_record(scene, |r| {
            r.stages.remove(stage);
        })?;
        Ok(done)
    }

    /// Removes one published file if it is ribbar's as written; moves it
    /// aside if it changed; the sentence saying so in that case.
    fn take_out(&self, root: &Path, rel: &str, claim: Claim) -> Result<Option<String>, StoreError> {
        let path = root.join(rel);
        let note = match state(&path, claim, None)? {
            FileState::Absent => None,
            FileState::Ours | FileState::Same => {
                fs::remove_file(&path).map_err(io_err(&path))?;
                None
            }
            FileState::Changed => Some(move_aside(
                &path,
                "was changed after ribbar wrote it and is no longer a result of this scene",
            )?),
        };
        remove_empty_parents(root, rel);
        Ok(note)
    }

    /// Each published file of `stage` in `WORK/<scene>/` that is not as
    /// ribbar wrote it: (path, Absent or Changed).
    pub fn published_changes(
        &self,
        scene: &str,
        stage: &PublishedStage,
        entries: &[&str],
        compare: Compare,
    ) -> Vec<(PathBuf, FileState)> {
        let root = self.scene_dir(scene);
        files_of(&root, stage, entries)
            .into_iter()
            .filter_map(|(rel, claim)| {
                let path = root.join(&rel);
                match state_by(&path, claim, None, compare) {
                    Ok(FileState::Ours | FileState::Same) => None,
                    Ok(s) => Some((path, s)),
                    Err(_) => Some((path, FileState::Changed)),
                }
            })
            .collect()
    }

    /// Removes every file of `WORK/<scene>/` that ribbar wrote there as it
    /// wrote it and the folders left empty; the record too when nothing else
    /// is left (else it stays, listing no results). Returns the paths
    /// removed and the paths kept (changed since, or not ribbar's).
    pub fn remove_published(
        &self,
        scene: &str,
        entries_of: impl Fn(&str) -> Vec<&'static str>,
    ) -> Result<(Vec<PathBuf>, Vec<PathBuf>), StoreError> {
        let root = self.scene_dir(scene);
        let Some(record) = self.read_record(scene)? else {
            return Ok((Vec::new(), Vec::new()));
        };
        let mut removed = Vec::new();
        for (name, stage) in &record.stages {
            let entries = entries_of(name);
            for (rel, claim) in files_of(&root, stage, &entries) {
                let path = root.join(&rel);
                if matches!(
                    state(&path, claim, None)?,
                    FileState::Ours | FileState::Same
                ) {
                    fs::remove_file(&path).map_err(io_err(&path))?;
                    remove_empty_parents(&root, &rel);
                    removed.push(path);
                }
            }
        }
        let record_path = root.join(RECORD_FILE);
        let others = |root: &Path| -> Vec<PathBuf> {
            fs::read_dir(root)
                .map(|entries| {
                    entries
                        .filter_map(|e| Some(e.ok()?.path()))
                        .filter(|p| *p != record_path)
                        .collect()
                })
                .unwrap_or_default()
        };
        let kept: Vec<PathBuf> = super::digest::list_files(&root, &[RECORD_FILE])
            .unwrap_or_default()
            .into_iter()
            .map(|rel| root.join(rel))
            .collect();
        if others(&root).is_empty() {
            fs::remove_file(&record_path).map_err(io_err(&record_path))?;
            let _ = fs::remove_dir(&root);
        } else {
            // What is left is not ribbar's; the folder stays a results
            // folder (its record lists no results), so that a later run
            // publishes beside those files instead of refusing the folder.
            self.write_record(scene, &SceneRecord::default())?;
        }
        let kept = if kept.is_empty() { others(&root) } else { kept };
        Ok((removed, kept))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Changed files keep their extension and never take an existing name.
    #[test]
    fn edited_names_keep_the_extension_and_are_new() {
        let dir = std::env::temp_dir().join(format!("ribbar-edited-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let p = dir.join("curve.csv");
        assert_eq!(edited_name(&p), dir.join("curve.edited.csv"));
        fs::write(dir.join("curve.edited.csv"), "").unwrap();
        assert_eq!(edited_name(&p), dir.join("curve.edited-2.csv"));
        assert_eq!(edited_name(&dir.join("fields")), dir.join("fields.edited"));
        fs::remove_dir_all(&dir).unwrap();
        assert!(under("fields/a.vtu", &["fields"]) && under("curve.csv", &["curve.csv"]));
        assert!(!under("fieldsx/a.vtu", &["fields"]) && !under("curve.csv.x", &["curve.csv"]));
    }
}
