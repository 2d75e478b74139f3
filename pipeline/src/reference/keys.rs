//! The scene, study and units reference pages, from the JSON Schemas of
//! the raw spec types and from `geom::units::Dim`.

use super::markdown::{cell, GENERATED};
use serde_json::Value;
use std::collections::HashMap;

/// A key's doc text, read from its field's doc comment: the meaning, then
/// `(unit; default …; bounds)` as the comment's last parenthesis. The unit
/// is a dimension of `geom::units::Dim` (`length`, `stress`, …), or
/// `choice`, `bool`, `count`, `text`, `path`, `list of …`, `mapping …`;
/// the default starts with `default` or is `required`; what follows is the
/// bounds, if any.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct KeyDoc {
    pub meaning: String,
    pub unit: String,
    pub default: String,
    pub bounds: String,
}

impl KeyDoc {
    /// Reads `description`; `None` when it has no final group with a unit
    /// and a default.
    pub fn parse(description: &str) -> Option<KeyDoc> {
        let text = description.trim().trim_end_matches('.').trim_end();
        let inner_end = text.strip_suffix(')')?.len();
        let mut depth = 0usize;
        let mut open = None;
        // Brackets of either kind pair with each other, so that intervals
        // such as (0, 90] or [0, c) nest like parentheses.
        for (i, c) in text[..inner_end].char_indices().rev() {
            match c {
                ')' | ']' => depth += 1,
                '(' | '[' if depth == 0 => {
                    open = Some(i);
                    break;
                }
                '(' | '[' => depth -= 1,
                _ => {}
            }
        }
        let open = open?;
        let parts = split_top_level(&text[open + 1..inner_end]);
        let (unit, rest) = parts.split_first()?;
        let (default, bounds) = rest.split_first()?;
        let default = if let Some(d) = default.strip_prefix("default") {
            d.trim_start_matches(':').trim().to_string()
        } else if default.starts_with("required") {
            default.clone()
        } else {
            return None;
        };
        let meaning = text[..open].trim().to_string();
        if meaning.is_empty() || unit.is_empty() || default.is_empty() {
            return None;
        }
        Some(KeyDoc {
            meaning: format!("{meaning}."),
            unit: unit.clone(),
            default,
            bounds: bounds.join("; "),
        })
    }
}

/// `text` split at the `;` outside parentheses and brackets (of either
/// kind, which pair with each other in intervals), trimmed.
fn split_top_level(text: &str) -> Vec<String> {
    let mut parts = vec![String::new()];
    let mut depth = 0i32;
    for c in text.chars() {
        match c {
            '(' | '[' | '{' => depth += 1,
            ')' | ']' | '}' => depth -= 1,
            ';' if depth == 0 => {
                parts.push(String::new());
                continue;
            }
            _ => {}
        }
        parts.last_mut().expect("never empty").push(c);
    }
    parts.into_iter().map(|p| p.trim().to_string()).collect()
}

/// One key of a file, as the walk over its schema finds it.
struct Key<'s> {
    path: String,
    description: Option<String>,
    /// The key's schema with references and the optional null followed.
    target: &'s Value,
    /// A mapping of further keys, listed after it.
    section: bool,
}

/// The field order of each raw type, as its `Deserialize` declares it
/// (the schema's own properties are sorted by name).
fn field_orders() -> HashMap<&'static str, &'static [&'static str]> {
    use crate::schema::struct_fields as f;
    HashMap::from([
        ("RawScene", f::<crate::scene::RawScene>()),
        ("RawBar", f::<geom::spec::RawBar>()),
        ("RawRibs", f::<geom::spec::RawRibs>()),
        (
            "RawLongitudinalRibs",
            f::<geom::spec::RawLongitudinalRibs>(),
        ),
        ("RawSpecimen", f::<geom::spec::RawSpecimen>()),
        ("RawMeshSpec", f::<mesh::spec::RawMeshSpec>()),
        ("RawMaterials", f::<solve::spec::materials::RawMaterials>()),
        ("RawConcrete", f::<solve::spec::materials::RawConcrete>()),
        ("RawSteel", f::<solve::spec::materials::RawSteel>()),
        ("RawInterface", f::<solve::spec::materials::RawInterface>()),
        ("RawLoading", f::<solve::spec::solver::RawLoading>()),
        ("RawSolver", f::<solve::spec::solver::RawSolver>()),
        ("RawExpert", f::<solve::spec::solver::RawExpert>()),
        ("RawOutputs", f::<crate::outputs::RawOutputs>()),
        ("RawFields", f::<crate::outputs::RawFields>()),
        ("RawStudy", f::<crate::study::RawStudy>()),
        ("RawSampler", f::<crate::study::RawSampler>()),
    ])
}

/// The schema `s` stands for: a `$ref` followed, an optional value's null
/// branch left out. Returns the target and the name of the definition it
/// came from, if any.
fn target<'s>(root: &'s Value, s: &'s Value) -> (&'s Value, Option<&'s str>) {
    if let Some(reference) = s.get("$ref").and_then(Value::as_str) {
        let name = reference.rsplit('/').next();
        let found = root.pointer(reference.trim_start_matches('#')).unwrap_or(s);
        return (target(root, found).0, name);
    }
    for combinator in ["anyOf", "oneOf"] {
        if let Some(branches) = s.get(combinator).and_then(Value::as_array) {
            let real: Vec<&Value> = branches
                .iter()
                .filter(|b| b.get("type").and_then(Value::as_str) != Some("null"))
                .collect();
            if real.len() == 1 && real.len() < branches.len() {
                return target(root, real[0]);
            }
        }
    }
    (s, None)
}

/// Every key under `schema` (an object), depth first, in field order.
fn walk<'s>(
    root: &'s Value,
    schema: &'s Value,
    name: Option<&str>,
    prefix: &str,
    orders: &HashMap<&str, &[&str]>,
    out: &mut Vec<Key<'s>>,
) {
    let Some(properties) = schema.get("properties").and_then(Value::as_object) else {
        return;
    };
    let order = name.and_then(|n| orders.get(n)).copied().unwrap_or(&[]);
    let mut names: Vec<&String> = properties.keys().collect();
    names.sort_by_key(|k| (order.iter().position(|o| o == k).unwrap_or(usize::MAX), *k));
    for key in names {
        let field = &properties[key];
        let (t, def) = target(root, field);
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        let section = t.get("properties").is_some();
        out.push(Key {
            path: path.clone(),
            description: field
                .get("description")
                .or_else(|| t.get("description"))
                .and_then(Value::as_str)
                .map(String::from),
            target: t,
            section,
        });
        if section {
            walk(root, t, def, &path, orders, out);
        }
    }
}

fn keys<'s>(root: &'s Value, name: &str) -> Vec<Key<'s>> {
    let mut out = Vec::new();
    walk(root, root, Some(name), "", &field_orders(), &mut out);
    out
}

/// The keys of `schema` (a scene's or a study's) whose doc text is missing
/// or, for a key that holds a value, has no `(unit; default …)` group.
pub fn undocumented_keys(schema: &Value) -> Vec<String> {
    let name = match schema.get("title").and_then(Value::as_str) {
        Some("ribbar study") => "RawStudy",
        _ => "RawScene",
    };
    keys(schema, name)
        .into_iter()
        .filter(|k| match &k.description {
            None => true,
            Some(d) => !k.section && KeyDoc::parse(d).is_none(),
        })
        .map(|k| k.path)
        .collect()
}

/// The values a key takes, from its schema: the names of a choice, or
/// `true` / `false`, joined as Markdown.
fn choices(root: &Value, s: &Value) -> Vec<(String, Option<String>)> {
    let (s, _) = target(root, s);
    let mut out = Vec::new();
    if let Some(values) = s.get("enum").and_then(Value::as_array) {
        out.extend(
            values
                .iter()
                .filter_map(Value::as_str)
                .map(|v| (v.to_string(), None)),
        );
    }
    if let Some(c) = s.get("const").and_then(Value::as_str) {
        let doc = s
            .get("description")
            .and_then(Value::as_str)
            .map(String::from);
        out.push((c.to_string(), doc));
    }
    if s.get("type").and_then(Value::as_str) == Some("boolean") {
        out.push(("true".into(), None));
        out.push(("false".into(), None));
    }
    for combinator in ["anyOf", "oneOf"] {
        for branch in s
            .get(combinator)
            .and_then(Value::as_array)
            .into_iter()
            .flatten()
        {
            out.extend(choices(root, branch));
        }
    }
    out
}

/// The Markdown of one top-level section: its text, its keys' table and
/// the meaning of each named choice.
fn section_markdown(root: &Value, section: &Key, keys: &[&Key]) -> String {
    let mut out = format!("\n## {}\n\n", section.path);
    if let Some(d) = &section.description {
        out.push_str(&format!("{d}\n\n"));
    }
    out.push_str("| key | value | default | bounds | meaning |\n|---|---|---|---|---|\n");
    let mut choice_notes = String::new();
    for key in keys {
        let doc = key.description.as_deref().and_then(KeyDoc::parse);
        let named = choices(root, key.target);
        let value = if key.section {
            "section".to_string()
        } else if doc.as_ref().is_some_and(|d| d.unit == "choice") && !named.is_empty() {
            named
                .iter()
                .map(|(v, _)| format!("`{v}`"))
                .collect::<Vec<_>>()
                .join(", ")
        } else {
            doc.as_ref().map(|d| d.unit.clone()).unwrap_or_default()
        };
        let (default, bounds, meaning) = match &doc {
            Some(d) => (d.default.clone(), d.bounds.clone(), d.meaning.clone()),
            None => (
                String::new(),
                String::new(),
                key.description.clone().unwrap_or_default(),
            ),
        };
        out.push_str(&format!(
            "| `{}` | {} | {} | {} | {} |\n",
            key.path,
            cell(&value),
            cell(&default),
            cell(&bounds),
            cell(&meaning)
        ));
        let documented: Vec<String> = named
            .iter()
            .filter_map(|(v, d)| {
                d.as_ref()
                    .map(|d| format!("`{v}`: {}", cell(d).trim_end_matches('.')))
            })
            .collect();
        if !documented.is_empty() {
            choice_notes.push_str(&format!("- `{}`: {}.\n", key.path, documented.join("; ")));
        }
    }
    if !choice_notes.is_empty() {
        out.push_str(&format!("\nThe choices:\n\n{choice_notes}"));
    }
    out
}

/// The page of a file's keys: `intro`, then one section per top-level
/// key that is a section, the plain top-level keys first.
fn keys_page(schema: &Value, name: &str, title: &str, intro: &str) -> String {
    let all = keys(schema, name);
    let mut out = format!("{GENERATED}\n\n# {title}\n\n{intro}\n");
    let top: Vec<&Key> = all.iter().filter(|k| !k.path.contains('.')).collect();
    let plain: Vec<&Key> = top.iter().copied().filter(|k| !k.section).collect();
    if !plain.is_empty() {
        let head = Key {
            path: "Top-level keys".into(),
            description: None,
            target: schema,
            section: true,
        };
        out.push_str(&section_markdown(schema, &head, &plain));
    }
    for section in top.iter().filter(|k| k.section) {
        let prefix = format!("{}.", section.path);
        let inner: Vec<&Key> = all.iter().filter(|k| k.path.starts_with(&prefix)).collect();
        out.push_str(&section_markdown(schema, section, &inner));
    }
    out
}

/// `reference/scene.md`.
pub fn scene_page() -> String {
    keys_page(
        &crate::scene::RawScene::schema(),
        "RawScene",
        "Scene file",
        "A scene file is YAML. Every key is listed here with what it holds, its \
         default and its bounds; a key that is not listed is refused, naming it. A \
         quantity is a plain number in SI units or a string of a number and a unit \
         (`8 mm`, `\"30 GPa\"`, `\"55 deg\"`: [Units](units.md)). Any key can be set \
         for one run with `--set key.path=value`, e.g. `--set bar.ribs.angle=\"60 deg\"`. \
         Editors validate and complete scene files with the schema `ribbar schema scene` \
         prints ([scene.schema.json](scene.schema.json)): the shipped scenes start with \
         the line `# yaml-language-server: $schema=…` that points to it.",
    )
}

/// `reference/study.md`.
pub fn study_page() -> String {
    keys_page(
        &crate::study::RawStudy::schema(),
        "RawStudy",
        "Study file",
        "A study file (`ribbar study STUDY`) is YAML naming a base scene and the values \
         of the scene keys it varies. Each case is the base scene with `--set` \
         overrides and the name `<study>--<i>`; cases that agree on a stage's inputs \
         share that stage's results. The schema: `ribbar schema study` \
         ([study.schema.json](study.schema.json)).",
    )
}

/// `reference/units.md`: the units each dimension accepts.
pub fn units_page() -> String {
    use geom::units::Dim;
    let mut out = format!(
        "{GENERATED}\n\n# Units\n\nA quantity in a scene is a plain number, read in \
         the SI unit of its key's dimension, or a string of a number and one of the \
         units below (a space between them is optional). A unit of another dimension \
         is refused, naming the key. Inside ribbar, and in every file it writes, \
         values are SI.\n\n| dimension | SI unit | accepted units |\n|---|---|---|\n"
    );
    for dim in Dim::ALL {
        let units: Vec<String> = dim
            .units()
            .iter()
            .map(|(name, _)| {
                if name.is_empty() {
                    "a plain number".to_string()
                } else {
                    format!("`{name}`")
                }
            })
            .collect();
        out.push_str(&format!(
            "| {dim} | `{}` | {} |\n",
            dim.si_unit(),
            units.join(", ")
        ));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A doc comment's last parenthesis gives the unit, the default and the
    /// bounds, nested parentheses included; one without a default is not
    /// read.
    #[test]
    fn key_doc_reads_the_last_group() {
        let interval = KeyDoc::parse("An angle (angle; default 55 deg; in (0, 90] deg).").unwrap();
        assert_eq!(interval.bounds, "in (0, 90] deg");
        let d = KeyDoc::parse(
            "Largest size (in the core) of the bar (length; default none: the whole \
             bar at h_interface (no core size); ≥ h_interface).",
        )
        .unwrap();
        assert_eq!(d.meaning, "Largest size (in the core) of the bar.");
        assert_eq!(d.unit, "length");
        assert_eq!(
            d.default,
            "none: the whole bar at h_interface (no core size)"
        );
        assert_eq!(d.bounds, "≥ h_interface");
        let required = KeyDoc::parse("Core diameter d (length; required; > 0)").unwrap();
        assert_eq!(required.default, "required");
        assert!(KeyDoc::parse("Core diameter d (length; > 0).").is_none());
        assert!(KeyDoc::parse("Core diameter d.").is_none());
    }
}
