//! Writing files so that a reader sees either the old content or the whole
//! new one, never a half-written file: every crate's artifacts go through
//! [`write_atomic`], each wrapping the I/O error in its own typed error.
//! Reading the files a user names ([`read_capped`]): only regular files,
//! and never more than a cap, so that `/dev/zero` or a stray huge file is
//! refused instead of read until memory runs out.

use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// The largest spec, study or material-point test file read, bytes: the
/// largest shipped one is a few kB.
pub const MAX_SPEC_BYTES: u64 = 1 << 20;
/// The largest table (a `curve.csv` given to `compare`) read, bytes.
pub const MAX_TABLE_BYTES: u64 = 1 << 30;
/// The largest record of ribbar's own read (`stage.json`, a results
/// folder's record), bytes: a solve with fields at every step lists a few
/// thousand files in a few hundred kB.
pub const MAX_RECORD_BYTES: u64 = 64 << 20;

/// The text of the regular file `path`, refused (an `InvalidInput` error
/// that says why) when it is not a regular file (a device, a FIFO, a
/// directory) or is larger than `cap` bytes.
pub fn read_capped(path: &Path, cap: u64) -> std::io::Result<String> {
    let invalid = |why: String| std::io::Error::new(std::io::ErrorKind::InvalidInput, why);
    let not_regular = || invalid("not a regular file (a device, a pipe or a directory)".into());
    // Looked at before it is opened: opening a FIFO waits for a writer.
    if !std::fs::metadata(path)?.is_file() {
        return Err(not_regular());
    }
    let file = std::fs::File::open(path)?;
    let meta = file.metadata()?;
    if !meta.is_file() {
        return Err(not_regular());
    }
    if meta.len() > cap {
        return Err(invalid(format!(
            "{} bytes, more than the {cap} a file of this kind may have",
            meta.len()
        )));
    }
    let mut text = String::new();
    // The file may grow while it is read: never past the cap.
    file.take(cap + 1).read_to_string(&mut text)?;
    if text.len() as u64 > cap {
        return Err(invalid(format!(
            "grew past the {cap} bytes a file of this kind may have while it was read"
        )));
    }
    Ok(text)
}

/// A scratch file name `.{stem}-{pid}-{n}.{ext}` in `dir`, distinct for
/// every call in this process (threads may share a directory).
pub fn scratch_name(dir: &Path, stem: &str, ext: &str) -> PathBuf {
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    dir.join(format!(".{stem}-{}-{n}.{ext}", std::process::id()))
}

/// A temporary sibling of `path`, unique per process, keeping the extension
/// (tools that pick a format from the name still see it).
pub fn temp_sibling(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.tmp-{}{ext}", std::process::id()))
}

/// Writes `bytes` to `path` (parent directories created) through a synced
/// temporary sibling and one rename; the temporary is removed on failure.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let tmp = temp_sibling(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn replaces_the_file_whole_and_leaves_no_temporary() {
        let dir = std::env::temp_dir().join(format!("ribbar-fsutil-{}", std::process::id()));
        let path = dir.join("sub/a.json");
        write_atomic(&path, b"old").unwrap();
        write_atomic(&path, b"new").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"new");
        assert_eq!(std::fs::read_dir(dir.join("sub")).unwrap().count(), 1);
        // A target that cannot be replaced by a file: an error, no leftover.
        std::fs::create_dir_all(dir.join("sub/d")).unwrap();
        std::fs::write(dir.join("sub/d/x"), b"").unwrap();
        assert!(write_atomic(&dir.join("sub/d"), b"x").is_err());
        assert_eq!(std::fs::read_dir(dir.join("sub")).unwrap().count(), 2);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Only regular files under the cap are read; a device or an oversized
    /// file is refused saying why.
    #[test]
    fn read_capped_refuses_devices_and_large_files() {
        let err = read_capped(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert!(err.to_string().contains("not a regular file"), "{err}");
        let dir = std::env::temp_dir().join(format!("ribbar-capped-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("spec.yaml");
        std::fs::write(&path, "name: x\n").unwrap();
        assert_eq!(read_capped(&path, 8).unwrap(), "name: x\n");
        let err = read_capped(&path, 7).unwrap_err();
        assert!(
            err.to_string().contains("8 bytes, more than the 7"),
            "{err}"
        );
        assert!(read_capped(&dir, 7).is_err());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
