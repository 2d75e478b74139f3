//! Writing result files so that a reader never sees a half-written one.

use super::PostError;
use std::path::{Path, PathBuf};

/// A temporary sibling of `path` that keeps its extension (the PNG encoder
/// picks its format from it), unique per process.
pub(crate) fn temp_sibling(path: &Path) -> PathBuf {
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

pub(crate) fn create_parent(path: &Path) -> Result<(), PostError> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => {
            std::fs::create_dir_all(dir).map_err(|source| PostError::Io {
                action: "creating directory",
                path: dir.to_path_buf(),
                source,
            })
        }
        _ => Ok(()),
    }
}

/// Moves a finished temporary file onto its final name.
pub(crate) fn commit(tmp: &Path, path: &Path) -> Result<(), PostError> {
    std::fs::rename(tmp, path).map_err(|source| {
        let _ = std::fs::remove_file(tmp);
        PostError::Io {
            action: "renaming into place",
            path: path.to_path_buf(),
            source,
        }
    })
}

/// Writes `bytes` to `path` through a temporary file and a rename.
pub(crate) fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), PostError> {
    create_parent(path)?;
    let tmp = temp_sibling(path);
    std::fs::write(&tmp, bytes).map_err(|source| PostError::Io {
        action: "writing",
        path: tmp.clone(),
        source,
    })?;
    commit(&tmp, path)
}
