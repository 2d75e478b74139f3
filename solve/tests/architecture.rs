//! docs/architecture.md's section "The stepping policy" names the rules of
//! `solve/src/nonlinear/` as they are in the code: every name it lists
//! exists there, and every constant it gives has that value.

use std::path::{Path, PathBuf};

/// The module prefixes of `solve::nonlinear` whose names the section
/// checks (`policy::endings::after_step`, `failure::Refusal`, …).
const MODULES: [&str; 6] = [
    "policy",
    "driver",
    "failure",
    "checkpoint",
    "summary",
    "settle",
];

fn nonlinear_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src/nonlinear")
}

/// The section's text, up to the next section of the same level.
fn section() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/architecture.md");
    let text = std::fs::read_to_string(&path).expect("docs/architecture.md");
    let start = text
        .find("\n## The stepping policy\n")
        .expect("the section \"The stepping policy\"");
    let rest = &text[start + 1..];
    let end = rest[3..].find("\n## ").map_or(rest.len(), |i| i + 3);
    rest[..end].to_string()
}

/// The code names in backticks that start with one of [`MODULES`], with
/// the value written after them (`` `policy::x::NAME` = 0.5 ``), if any.
fn names(section: &str) -> Vec<(String, Option<String>)> {
    let mut out = Vec::new();
    let mut parts = section.split('`');
    // Text before the first backtick, then name and text in turn.
    parts.next();
    while let (Some(name), Some(after)) = (parts.next(), parts.next()) {
        let name = name.split_whitespace().collect::<String>();
        if MODULES.iter().any(|m| name.starts_with(&format!("{m}::"))) {
            let value = after
                .trim_start()
                .strip_prefix('=')
                .and_then(|v| v.split_whitespace().next())
                .map(String::from);
            out.push((name, value));
        }
    }
    out
}

/// The source of module `segments` under `dir` (`a/b.rs` or `a/b/mod.rs`),
/// and how many segments named modules.
fn module_source(dir: &Path, segments: &[&str]) -> (String, usize) {
    let mut dir = dir.to_path_buf();
    let mut source = std::fs::read_to_string(dir.join("mod.rs")).unwrap_or_default();
    let mut depth = 0;
    for segment in segments {
        let file = dir.join(format!("{segment}.rs"));
        let nested = dir.join(segment).join("mod.rs");
        let found = std::fs::read_to_string(&file).or_else(|_| std::fs::read_to_string(&nested));
        match found {
            Ok(text) => {
                source = text;
                dir = dir.join(segment);
                depth += 1;
            }
            Err(_) => break,
        }
    }
    (source, depth)
}

/// Whether `word` occurs in `text` as a whole identifier.
fn has_word(text: &str, word: &str) -> bool {
    text.match_indices(word).any(|(i, _)| {
        let ident = |c: char| c.is_alphanumeric() || c == '_';
        let before = text[..i].chars().next_back().is_none_or(|c| !ident(c));
        let after = text[i + word.len()..]
            .chars()
            .next()
            .is_none_or(|c| !ident(c));
        before && after
    })
}

/// Why `name` (`policy::a::b::Item::member`) does not resolve, if it does
/// not: its modules are files, its item is declared in the last of them,
/// and a member after it occurs there.
fn unresolved(name: &str) -> Option<String> {
    let segments: Vec<&str> = name.split("::").collect();
    let (source, depth) = module_source(&nonlinear_dir(), &segments);
    let Some((item, members)) = segments[depth..].split_first() else {
        return None; // a module
    };
    let declared = ["fn", "const", "struct", "enum", "trait", "type", "mod"]
        .iter()
        .any(|kind| has_word(&source, &format!("{kind} {item}")));
    if !declared {
        return Some(format!(
            "{item} is not declared in {}",
            segments[..depth].join("::")
        ));
    }
    members
        .iter()
        .find(|m| !has_word(&source, m))
        .map(|m| format!("{m} does not occur beside {item}"))
}

/// The value of the constant `item` as its declaration writes it.
fn constant_value(name: &str) -> Option<f64> {
    let segments: Vec<&str> = name.split("::").collect();
    let (source, depth) = module_source(&nonlinear_dir(), &segments);
    let item = segments.get(depth)?;
    let start = source.find(&format!("const {item}:"))?;
    let value = source[start..].split('=').nth(1)?.split(';').next()?.trim();
    value.replace('_', "").parse().ok()
}

/// Every `policy::…` (and driver, failure, checkpoint, summary, settle)
/// name the section lists exists in `solve/src/nonlinear/`, and every
/// constant it gives a value has that value in the code, so the section
/// cannot drift from the code unnoticed.
#[test]
fn the_stepping_policy_section_names_what_the_code_has() {
    let names = names(&section());
    assert!(names.len() > 60, "too few names found: {names:?}");
    let mut wrong = Vec::new();
    for (name, value) in &names {
        if let Some(why) = unresolved(name) {
            wrong.push(format!("{name}: {why}"));
        }
        if let Some(value) = value {
            let written: f64 = value.parse().unwrap_or(f64::NAN);
            match constant_value(name) {
                Some(v) if v == written => {}
                found => wrong.push(format!(
                    "{name} = {value} in the docs, {found:?} in the code"
                )),
            }
        }
    }
    assert!(wrong.is_empty(), "docs/architecture.md: {wrong:#?}");
    let constants = names.iter().filter(|(_, v)| v.is_some()).count();
    assert!(constants >= 16, "{constants} constants with values");
}

/// The resolution above can fail: a made-up rule, a rule in the wrong
/// file, a misnamed variant and a wrong value are each found.
#[test]
fn a_name_the_code_lacks_is_found() {
    assert!(unresolved("policy::endings::no_such_rule").is_some());
    assert!(unresolved("policy::sizers::limit_load").is_some());
    assert!(unresolved("policy::decide::Action::NoSuchArm").is_some());
    assert!(unresolved("policy::decide::Action::Rewind").is_none());
    assert!(unresolved("policy::controls::next").is_none());
    assert_eq!(constant_value("policy::endings::LIMIT_SHARE"), Some(0.9));
    assert_ne!(constant_value("policy::endings::SNAP_BACK"), Some(0.25));
}
