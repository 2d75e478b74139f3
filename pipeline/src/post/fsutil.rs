//! Writing result files so that a reader never sees a half-written one.

use super::error::PostError;
use std::path::{Path, PathBuf};

/// A temporary sibling of `path` that keeps its extension (the PNG encoder
/// picks its format from it), unique per process.
pub(crate) fn temp_sibling(path: &Path) -> PathBuf {
    geom::fsutil::temp_sibling(path)
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
    geom::fsutil::write_atomic(path, bytes).map_err(|source| PostError::Io {
        action: "writing",
        path: path.to_path_buf(),
        source,
    })
}
