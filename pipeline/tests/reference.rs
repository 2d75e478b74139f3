//! The generated reference of the user guide: the committed pages are what
//! the code says now, and every key says what it is.

use std::path::{Path, PathBuf};

fn reference_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .join("docs/src/reference")
}

/// The pages in docs/src/reference are what `pipeline::reference` writes
/// from the code now: a changed command-line option, scene key or unit
/// fails here until the pages are rewritten (`RIBBAR_WRITE_REFERENCE=1`).
#[test]
fn reference_pages_are_current() {
    let dir = reference_dir();
    let write = std::env::var_os("RIBBAR_WRITE_REFERENCE").is_some();
    let mut stale = Vec::new();
    for (name, text) in pipeline::reference::pages() {
        let path = dir.join(name);
        if write {
            std::fs::write(&path, &text).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            continue;
        }
        let committed = std::fs::read_to_string(&path).unwrap_or_default();
        if committed != text {
            let line = committed
                .lines()
                .zip(text.lines())
                .position(|(a, b)| a != b)
                .unwrap_or(committed.lines().count().min(text.lines().count()));
            stale.push(format!("{name} (first difference at line {})", line + 1));
        }
    }
    assert!(
        stale.is_empty(),
        "docs/src/reference is not what the code generates: {}; rewrite it with \
         `RIBBAR_WRITE_REFERENCE=1 cargo test -p pipeline --test suite reference::` and commit it",
        stale.join(", ")
    );
}

/// Every scene and study key has its doc text: a meaning and, for a key
/// that holds a value, `(unit; default …; bounds)` at the end of its
/// field's doc comment; a key added without it fails here.
#[test]
fn every_key_has_its_doc_text() {
    for schema in [
        pipeline::scene::RawScene::schema(),
        pipeline::study::RawStudy::schema(),
    ] {
        let missing = pipeline::reference::undocumented_keys(&schema);
        assert!(
            missing.is_empty(),
            "{}: keys without their doc text `Meaning (unit; default X; bounds).`: {missing:?}",
            schema["title"]
        );
    }
}

/// The check above can fail: a description without the unit and default
/// group is reported by the same function.
#[test]
fn a_key_without_its_unit_and_default_is_reported() {
    let mut schema = pipeline::scene::RawScene::schema();
    let description = schema
        .pointer_mut("/$defs/RawMeshSpec/properties/h_outer/description")
        .expect("mesh.h_outer has a description");
    *description = "Element size at the cube's outer faces.".into();
    assert_eq!(
        pipeline::reference::undocumented_keys(&schema),
        ["mesh.h_outer"]
    );
}
