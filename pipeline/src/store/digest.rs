//! What the store records of each artifact file at commit (size,
//! modification time, SHA-256) and how a folder is checked against that
//! record: sizes and times always, digests when asked or when a file's time
//! has moved.

use super::base::{io_err, StoreError};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::fs;
use std::io::Read;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Instant, UNIX_EPOCH};

/// The record of one artifact file.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct FileDigest {
    pub size: u64,
    /// SHA-256 of the content, hex.
    pub sha256: String,
    /// Modification time when it was recorded, ns since the Unix epoch: a
    /// file whose time has moved is hashed again even where sizes suffice.
    pub mtime_ns: u64,
}

/// How thoroughly a folder is checked against its record.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Depth {
    /// Each file's presence, kind and size; the digest of each file whose
    /// modification time has moved.
    Sizes,
    /// Every file's digest as well.
    Digests,
}

/// Nanoseconds spent hashing and checking artifacts in this process (the
/// cost `-v` reports against the run).
static CHECK_NANOS: AtomicU64 = AtomicU64::new(0);
/// Bytes hashed in this process.
static HASHED_BYTES: AtomicU64 = AtomicU64::new(0);

/// Time spent on the store's digests and checks so far in this process, s,
/// and the bytes hashed.
pub fn check_cost() -> (f64, u64) {
    (
        CHECK_NANOS.load(Ordering::Relaxed) as f64 * 1e-9,
        HASHED_BYTES.load(Ordering::Relaxed),
    )
}

/// Runs `f`, adding its wall time to the check cost.
pub(super) fn timed<T>(f: impl FnOnce() -> T) -> T {
    let started = Instant::now();
    let out = f();
    CHECK_NANOS.fetch_add(started.elapsed().as_nanos() as u64, Ordering::Relaxed);
    out
}

/// SHA-256 of a file's content, hex.
pub fn sha256_file(path: &Path) -> Result<String, StoreError> {
    let mut file = fs::File::open(path).map_err(io_err(path))?;
    let mut hasher = Sha256::new();
    let mut buf = vec![0u8; 1 << 20];
    loop {
        let n = file.read(&mut buf).map_err(io_err(path))?;
        if n == 0 {
            break;
        }
        HASHED_BYTES.fetch_add(n as u64, Ordering::Relaxed);
        hasher.update(&buf[..n]);
    }
    Ok(hex(&hasher.finalize()))
}

pub(super) fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

/// A file's modification time, ns since the Unix epoch (0 where the file
/// system does not keep one).
pub fn mtime_ns(meta: &fs::Metadata) -> u64 {
    meta.modified()
        .ok()
        .and_then(|t| t.duration_since(UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos() as u64)
}

/// Every regular file under `dir`, as paths relative to it with `/`
/// separators, sorted; `skip` names top-level entries left out.
pub(super) fn list_files(dir: &Path, skip: &[&str]) -> Result<Vec<String>, StoreError> {
    fn walk(root: &Path, rel: &str, out: &mut Vec<String>) -> Result<(), StoreError> {
        let here = if rel.is_empty() {
            root.to_path_buf()
        } else {
            root.join(rel)
        };
        for entry in fs::read_dir(&here).map_err(io_err(&here))? {
            let entry = entry.map_err(io_err(&here))?;
            let name = entry.file_name().to_string_lossy().into_owned();
            let child = if rel.is_empty() {
                name
            } else {
                format!("{rel}/{name}")
            };
            let kind = entry.file_type().map_err(io_err(&entry.path()))?;
            if kind.is_dir() {
                walk(root, &child, out)?;
            } else {
                out.push(child);
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(dir, "", &mut out)?;
    out.retain(|rel| !skip.contains(&rel.as_str()));
    out.sort();
    Ok(out)
}

/// Records every file of a finished in-progress folder and makes each one
/// read-only, so that only a deliberate change of mode lets it be written.
/// Hidden files (the temporaries of a run that was killed while writing)
/// are removed first: no artifact's name starts with a dot.
pub(super) fn seal(dir: &Path, skip: &[&str]) -> Result<BTreeMap<String, FileDigest>, StoreError> {
    timed(|| {
        let mut files = BTreeMap::new();
        for rel in list_files(dir, skip)? {
            let path = dir.join(&rel);
            let hidden = rel.split('/').any(|part| part.starts_with('.'));
            if hidden {
                fs::remove_file(&path).map_err(io_err(&path))?;
                continue;
            }
            make_read_only(&path)?;
            let meta = fs::symlink_metadata(&path).map_err(io_err(&path))?;
            files.insert(
                rel,
                FileDigest {
                    size: meta.len(),
                    sha256: sha256_file(&path)?,
                    mtime_ns: mtime_ns(&meta),
                },
            );
        }
        Ok(files)
    })
}

pub(super) fn make_read_only(path: &Path) -> Result<(), StoreError> {
    let mut perms = fs::metadata(path).map_err(io_err(path))?.permissions();
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        perms.set_mode(perms.mode() & 0o444);
    }
    #[cfg(not(unix))]
    perms.set_readonly(true);
    fs::set_permissions(path, perms).map_err(io_err(path))
}

/// Whether `rel` is a relative path that stays inside its folder.
fn is_inner(rel: &str) -> bool {
    !rel.is_empty()
        && !rel.starts_with('/')
        && rel
            .split('/')
            .all(|part| !part.is_empty() && part != "." && part != "..")
}

/// The first difference between the files under `dir` and their record,
/// as a sentence naming the file; `None` when they agree.
pub(super) fn first_difference(
    dir: &Path,
    files: &BTreeMap<String, FileDigest>,
    depth: Depth,
) -> Option<String> {
    timed(|| {
        files
            .iter()
            .find_map(|(rel, digest)| file_difference(dir, rel, digest, depth))
    })
}

/// How `dir/rel` differs from `digest`, if it does.
pub(super) fn file_difference(
    dir: &Path,
    rel: &str,
    digest: &FileDigest,
    depth: Depth,
) -> Option<String> {
    if !is_inner(rel) {
        return Some(format!(
            "{}: its record names the file {rel:?}, outside the folder",
            dir.join("stage.json").display()
        ));
    }
    let path: PathBuf = dir.join(rel);
    let shown = path.display();
    let meta = match fs::symlink_metadata(&path) {
        Ok(m) => m,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            return Some(format!("{shown}: missing"))
        }
        Err(e) => return Some(format!("{shown}: {e}")),
    };
    if !meta.is_file() {
        return Some(format!("{shown}: not a regular file"));
    }
    if meta.len() != digest.size {
        return Some(format!(
            "{shown}: {} bytes where {} were recorded",
            meta.len(),
            digest.size
        ));
    }
    if depth == Depth::Sizes && mtime_ns(&meta) == digest.mtime_ns {
        return None;
    }
    match sha256_file(&path) {
        Ok(sha) if sha == digest.sha256 => None,
        Ok(_) => Some(format!(
            "{shown}: its content differs from the one recorded (SHA-256)"
        )),
        Err(e) => Some(e.to_string()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sealed folder agrees with its record; a same-size edit, a
    /// truncation, a deletion and a file turned into a directory are each
    /// found and named, the edit even by the size check (its time moved).
    #[test]
    fn each_change_of_a_sealed_file_is_found_and_named() {
        let dir = std::env::temp_dir().join(format!("ribbar-digest-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(dir.join("fields")).unwrap();
        fs::write(dir.join("curve.csv"), "step,u\n1,2.0675e6\n").unwrap();
        fs::write(dir.join("fields/a.vtu"), "<VTKFile/>").unwrap();
        fs::write(dir.join(".curve.csv.tmp-1"), "half").unwrap();
        let files = seal(&dir, &[]).unwrap();
        assert_eq!(
            files.keys().collect::<Vec<_>>(),
            ["curve.csv", "fields/a.vtu"]
        );
        assert!(!dir.join(".curve.csv.tmp-1").exists());
        for depth in [Depth::Sizes, Depth::Digests] {
            assert_eq!(first_difference(&dir, &files, depth), None);
        }
        let edit = |f: &dyn Fn(&Path)| {
            let path = dir.join("curve.csv");
            let mut perms = fs::metadata(&path).unwrap().permissions();
            #[allow(clippy::permissions_set_readonly_false)]
            perms.set_readonly(false);
            fs::set_permissions(&path, perms).unwrap();
            f(&path);
        };
        // The time of the edit is later than the seal's (ns resolution,
        // or a coarse clock: make sure it moved).
        std::thread::sleep(std::time::Duration::from_millis(20));
        edit(&|p| fs::write(p, "step,u\n1,2.0675e7\n").unwrap());
        let why = first_difference(&dir, &files, Depth::Sizes).unwrap();
        assert!(
            why.contains("curve.csv") && why.contains("SHA-256"),
            "{why}"
        );
        edit(&|p| fs::write(p, "step").unwrap());
        let why = first_difference(&dir, &files, Depth::Sizes).unwrap();
        assert!(why.contains("4 bytes where 18"), "{why}");
        edit(&|p| fs::remove_file(p).unwrap());
        let why = first_difference(&dir, &files, Depth::Sizes).unwrap();
        assert!(why.ends_with("curve.csv: missing"), "{why}");
        fs::create_dir(dir.join("curve.csv")).unwrap();
        let why = first_difference(&dir, &files, Depth::Sizes).unwrap();
        assert!(why.contains("not a regular file"), "{why}");
        let mut outside = files.clone();
        outside.insert("../x".into(), files["fields/a.vtu"].clone());
        let why = first_difference(&dir.join("fields"), &outside, Depth::Sizes).unwrap();
        assert!(why.contains("outside the folder"), "{why}");
        fs::remove_dir_all(&dir).unwrap();
    }
}
