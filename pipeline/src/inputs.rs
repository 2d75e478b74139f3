//! No output of a command may be one of its inputs: `material T -o T`, a
//! spec kept where its own results are published, or a study file inside
//! the store would be overwritten or deleted by the command that reads it.

use anyhow::{bail, Result};
use std::path::{Path, PathBuf};

/// The path with symbolic links and `..` resolved as far as it exists
/// (the rest appended), so that two names of one place compare equal.
fn resolved(path: &Path) -> PathBuf {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let mut existing = absolute.clone();
    let mut rest = Vec::new();
    while !existing.exists() {
        match (
            existing.file_name().map(|n| n.to_owned()),
            existing.parent(),
        ) {
            (Some(name), Some(parent)) => {
                rest.push(name);
                existing = parent.to_path_buf();
            }
            _ => return absolute,
        }
    }
    let mut out = existing.canonicalize().unwrap_or(existing);
    out.extend(rest.iter().rev());
    out
}

/// Whether `a` and `b` name one file: the same place, or (hard links) the
/// same device and inode.
pub fn same_file(a: &Path, b: &Path) -> bool {
    if resolved(a) == resolved(b) {
        return true;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
    }
    false
}

/// Whether `path` is `dir` or inside it.
pub fn is_inside(path: &Path, dir: &Path) -> bool {
    resolved(path).starts_with(resolved(dir))
}

/// Refuses `output` when it is one of `inputs` (each named by what it is).
pub fn refuse_overwriting(output: &Path, inputs: &[(&str, &Path)]) -> Result<()> {
    for (what, input) in inputs {
        if same_file(output, input) {
            bail!(
                "{}: the output is {what} itself ({}), which the command reads; \
                 write the output to another file",
                output.display(),
                input.display()
            );
        }
    }
    Ok(())
}

/// Refuses an input that the command would write: inside one of
/// `output_dirs` (the store) or one of `output_files` (folders included).
pub fn refuse_input_among_outputs(
    what: &str,
    input: &Path,
    output_dirs: &[PathBuf],
    output_files: &[PathBuf],
) -> Result<()> {
    let inside = output_dirs.iter().find(|d| is_inside(input, d));
    let named = output_files
        .iter()
        .find(|f| same_file(input, f) || is_inside(input, f));
    if let Some(place) = inside.or(named) {
        bail!(
            "{}: {what} is where the command writes its results ({}): ribbar would \
             overwrite or remove it; keep it outside the work directory's results",
            input.display(),
            place.display()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A file and a hard link to it, and two spellings of one path, are the
    /// same file; the refusal names both.
    #[test]
    fn the_same_file_under_two_names_is_refused() {
        let dir = std::env::temp_dir().join(format!("ribbar-inputs-{}", std::process::id()));
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let test = dir.join("t.yaml");
        std::fs::write(&test, "law: j2").unwrap();
        std::fs::hard_link(&test, dir.join("link.yaml")).unwrap();
        assert!(same_file(&test, &dir.join("sub/../t.yaml")));
        assert!(same_file(&test, &dir.join("link.yaml")));
        assert!(!same_file(&test, &dir.join("new.csv")));
        let err = refuse_overwriting(&dir.join("link.yaml"), &[("the test file", &test)])
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("link.yaml") && err.contains("the test file"),
            "{err}"
        );
        let err = refuse_input_among_outputs(
            "the spec",
            &dir.join("sub/x.yaml"),
            &[dir.join("sub")],
            &[],
        )
        .unwrap_err()
        .to_string();
        assert!(err.contains("x.yaml") && err.contains("the spec"), "{err}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
