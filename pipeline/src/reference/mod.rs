//! The generated reference pages of the user guide (`docs/src/reference/`):
//! the command line from clap's own description of it, the scene and study
//! keys from the JSON Schemas of their raw types (`crate::schema`), the
//! units from `geom::units::Dim`. A test compares the committed pages with
//! what [`pages`] writes now, so they cannot drift from the code.
//!
//! A key's text is its field's doc comment: the meaning, then
//! `(unit; default …; bounds)` as its last parenthesis ([`KeyDoc`]).

mod cli;
mod keys;
mod markdown;

pub use keys::{undocumented_keys, KeyDoc};

/// Every generated file of `docs/src/reference/`: its name and its text.
pub fn pages() -> Vec<(&'static str, String)> {
    let json =
        |v: serde_json::Value| serde_json::to_string_pretty(&v).expect("schemas serialise") + "\n";
    vec![
        ("cli.md", cli::page()),
        ("scene.md", keys::scene_page()),
        ("study.md", keys::study_page()),
        ("units.md", keys::units_page()),
        ("scene.schema.json", json(crate::scene::RawScene::schema())),
        ("study.schema.json", json(crate::study::RawStudy::schema())),
    ]
}
