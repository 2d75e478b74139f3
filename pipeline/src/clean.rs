//! `ribbar clean`: removes only what ribbar made, and says what it kept.
//! A scene's results folder loses the files its record lists as ribbar
//! wrote them (edited ones and files of the user's stay); a folder without
//! a record is not ribbar's and is left alone. The scene's in-progress
//! stages (a solve's checkpoint) go too, unless a running ribbar holds
//! them. `--all` removes the store's own entries, and nothing else found
//! in `.store`.

use crate::progress::Printer;
use crate::scene::Scene;
use crate::stage::{Keys, Stage};
use crate::store::{Store, QUARANTINE, RECORD_FILE};
use anyhow::{Context, Result};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// At most this many kept paths are listed by name.
const LISTED: usize = 10;

fn listing(paths: &[PathBuf], root: &Path) -> String {
    let mut names: Vec<String> = paths
        .iter()
        .take(LISTED)
        .map(|p| p.strip_prefix(root).unwrap_or(p).display().to_string())
        .collect();
    if paths.len() > LISTED {
        names.push(format!("and {} more", paths.len() - LISTED));
    }
    names.join(", ")
}

/// The (stage, key) pairs of the scene's in-progress folders to look for:
/// those of its last run, and those of the spec now when gmsh (whose
/// version is in the keys) is found.
fn scene_keys(store: &Store, scene: &Scene) -> BTreeSet<(String, String)> {
    let mut keys: BTreeSet<(String, String)> = store
        .read_record(&scene.name)
        .ok()
        .flatten()
        .and_then(|r| r.run)
        .map(|run| run.keys.into_iter().collect())
        .unwrap_or_default();
    if let Ok(gmsh) = geom::gmsh::Gmsh::locate() {
        let now = Keys::of(scene, gmsh.version());
        keys.extend(
            Stage::ALL
                .iter()
                .map(|s| (s.name().to_string(), now.get(*s).key.clone())),
        );
    }
    keys
}

/// Removes the scene's in-progress folders that no running ribbar holds.
fn in_progress(store: &Store, scene: &Scene, printer: &Printer) -> Result<()> {
    for (stage, key) in scene_keys(store, scene) {
        let partial = store.partial_dir_of(&stage, &key);
        if !partial.exists() {
            continue;
        }
        match store.try_lock(&stage, &key)? {
            None => printer.line(&format!(
                "kept {}: a running ribbar is working on it",
                partial.display()
            )),
            Some(_lock) => {
                std::fs::remove_dir_all(&partial)
                    .with_context(|| format!("removing {}", partial.display()))?;
                let what = if stage == Stage::Solve.name() {
                    " (the interrupted solve and its checkpoint)"
                } else {
                    ""
                };
                printer.line(&format!("removed {}{what}", partial.display()));
            }
        }
    }
    Ok(())
}

/// `clean SPEC`.
pub fn scene(store: &Store, scene: &Scene, printer: &Printer) -> Result<()> {
    in_progress(store, scene, printer)?;
    let dir = store.scene_dir(&scene.name);
    let record = store.read_record(&scene.name).map_err(|e| {
        anyhow::anyhow!(
            "{e}; ribbar cannot tell its files in {} from others, so nothing there was removed \
             (`ribbar run` keeps the record aside and publishes the results again)",
            dir.display()
        )
    })?;
    if record.is_none() {
        if dir.exists() {
            printer.line(&format!(
                "kept {}: ribbar did not make it (it has no {RECORD_FILE}); nothing removed",
                dir.display()
            ));
        } else {
            printer.line(&format!(
                "nothing to remove: {} does not exist",
                dir.display()
            ));
        }
        return Ok(());
    }
    let (removed, kept) = store.remove_published(&scene.name, |name| {
        Stage::from_name(name).map_or(Vec::new(), |s| s.published_files().to_vec())
    })?;
    printer.line(&format!(
        "removed {} files ribbar wrote in {}",
        removed.len(),
        dir.display()
    ));
    if !kept.is_empty() {
        printer.line(&format!(
            "kept {} files there that ribbar did not write or that were changed since: {}",
            kept.len(),
            listing(&kept, &dir)
        ));
    }
    printer.line(&format!(
        "the stored results stay in {} (other scenes and study cases may share them; \
         `ribbar clean --all` removes the whole store)",
        store.work.join(".store").display()
    ));
    Ok(())
}

/// Whether `name` is one of the entries ribbar makes in the store folder
/// `folder` (a stage's: keys, in-progress folders, locks; the
/// quarantine's: `<stage>-<key>-…`).
fn is_store_entry(folder: &str, name: &str) -> bool {
    let is_key = |k: &str| k.len() == 32 && k.bytes().all(|b| b.is_ascii_hexdigit());
    if folder == QUARANTINE {
        return Stage::ALL.iter().any(|s| {
            name.strip_prefix(s.name())
                .and_then(|r| r.strip_prefix('-'))
                .is_some_and(|r| r.len() > 33 && is_key(&r[..32]) && r.as_bytes()[32] == b'-')
        });
    }
    let key = name
        .strip_suffix(".partial")
        .or_else(|| name.strip_suffix(".lock"))
        .unwrap_or(name);
    is_key(key)
}

/// `clean --all`.
pub fn store(store: &Store, printer: &Printer) -> Result<()> {
    let root = store.work.join(".store");
    let Ok(folders) = std::fs::read_dir(&root) else {
        printer.line(&format!(
            "nothing to remove: {} does not exist",
            root.display()
        ));
        return Ok(());
    };
    let mut kept = Vec::new();
    let mut removed = 0usize;
    let known: Vec<&str> = Stage::ALL
        .iter()
        .map(|s| s.name())
        .chain([QUARANTINE])
        .collect();
    for folder in folders {
        let folder = folder.with_context(|| format!("reading {}", root.display()))?;
        let name = folder.file_name().to_string_lossy().into_owned();
        if !known.contains(&name.as_str()) || !folder.path().is_dir() {
            kept.push(folder.path());
            continue;
        }
        for entry in std::fs::read_dir(folder.path())
            .with_context(|| format!("reading {}", folder.path().display()))?
        {
            let entry = entry?;
            let path = entry.path();
            if !is_store_entry(&name, &entry.file_name().to_string_lossy()) {
                kept.push(path);
                continue;
            }
            let gone = if path.is_dir() {
                std::fs::remove_dir_all(&path)
            } else {
                std::fs::remove_file(&path)
            };
            gone.with_context(|| format!("removing {}", path.display()))?;
            removed += 1;
        }
        let _ = std::fs::remove_dir(folder.path());
    }
    let _ = std::fs::remove_dir(&root);
    printer.line(&format!(
        "removed {removed} entries of the store {}",
        root.display()
    ));
    if !kept.is_empty() {
        printer.line(&format!(
            "kept {} entries there that ribbar did not make: {}",
            kept.len(),
            listing(&kept, &root)
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Only the names ribbar gives store entries are taken as its own.
    #[test]
    fn store_entries_are_recognised_by_their_names() {
        let key = "0123456789abcdef0123456789abcdef";
        for name in [
            key.to_string(),
            format!("{key}.partial"),
            format!("{key}.lock"),
        ] {
            assert!(is_store_entry("solve", &name), "{name}");
        }
        assert!(is_store_entry(QUARANTINE, &format!("solve-{key}-1")));
        assert!(is_store_entry(
            QUARANTINE,
            &format!("mesh-{key}-checkpoint-2")
        ));
        for name in [
            "thesis.tex",
            "0123",
            &format!("{key}x"),
            &format!("{key}.bak"),
        ] {
            assert!(!is_store_entry("solve", name), "{name}");
        }
        assert!(!is_store_entry(QUARANTINE, "notes.txt"));
    }
}
