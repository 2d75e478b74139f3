//! Studies: a base scene spec plus lists of values for any keys, expanded
//! into cases (cartesian product or zipped lists), or a convergence series
//! over one size key (a mesh size, or a step size with the keys that scale
//! with it zipped after it).
//!
//! ```yaml
//! name: r1-delta-s
//! base: ../r1-coarse.yaml           # relative to this file
//! kind: sweep                       # sweep (default) | convergence
//! combine: product                  # product (default) | zip
//! parameters:
//!   materials.interface.delta_s: [0.02, 0.16, 0.5, 1.0]
//! ```
//! A case is the base spec with `--set key=value` overrides and the scene
//! name `<study>--<index>`; its stages share the store with every other case,
//! so cases that agree on a stage's inputs share that stage's artifacts.

use schemars::JsonSchema;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// What a study computes from its cases.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum StudyKind {
    /// One case per combination of the values; a table and a plot of all
    /// curves.
    #[default]
    Sweep,
    /// A series over one size key (a mesh size or a step size): observed
    /// order, Richardson extrapolation, GCI, the least-squares uncertainty
    /// and the curve distance of each size to the next finer one.
    Convergence,
}

/// How the parameter lists make cases.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Combine {
    /// Every combination of the lists' values.
    #[default]
    Product,
    /// The lists side by side, of equal lengths: case i takes the i-th value
    /// of each.
    Zip,
}

/// A study file as written. Every field's doc comment is its text in the
/// study reference and the JSON Schema (`ribbar schema study`).
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawStudy {
    /// The study's name: its tables and plots go to `WORK/<name>/`, its
    /// cases are named `<name>--<i>` (text; required; letters, digits, `-`,
    /// `_` or `.`).
    pub name: String,
    /// The base scene, relative to the study file (path; required; an
    /// existing file).
    pub base: PathBuf,
    /// A sweep, or a convergence series whose first parameter is the size
    /// (choice; default sweep).
    #[serde(default)]
    pub kind: StudyKind,
    /// How the parameter lists make cases (choice; default product).
    #[serde(default)]
    pub combine: Combine,
    /// Dotted scene key → list of values, e.g. `bar.ribs.angle: [40 deg,
    /// 55 deg]`, in the order written; a convergence study's first key is
    /// its size, with at least 3 values, and further keys need
    /// `combine: zip` (mapping of lists; required; at least one key, no
    /// empty list).
    #[schemars(schema_with = "crate::schema::parameter_lists")]
    pub parameters: serde_yaml::Mapping,
    /// Dotted scene key → one value applied to every case (mapping; default
    /// {}).
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, serde_json::Value>")]
    pub set: BTreeMap<String, serde_yaml::Value>,
    /// The most cases the study may expand to (default
    /// [`DEFAULT_MAX_CASES`]); a larger product is refused before it is
    /// expanded.
    #[serde(default)]
    pub max_cases: Option<usize>,
}

/// The most cases a study expands to unless its `max_cases` says more:
/// each case is a whole pull-out run, and a product of a few long lists
/// quickly reaches millions.
pub const DEFAULT_MAX_CASES: usize = 1000;

/// Refuses a study of `cases` cases (`None`: more than a `usize` holds)
/// above its limit, with the count and how it arose, before any case is
/// built.
pub fn check_case_count(cases: Option<usize>, how: &str, max_cases: usize) -> Result<(), String> {
    match cases {
        Some(n) if n <= max_cases => Ok(()),
        _ => Err(format!(
            "parameters: the study expands to {} cases ({how}), more than max_cases = \
             {max_cases}; raise max_cases in the study file if that many runs are meant",
            cases.map_or("more than 2^64".to_string(), |n| n.to_string())
        )),
    }
}

/// One case of a study.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    pub index: usize,
    pub name: String,
    /// (key, value as given) of the swept parameters.
    pub parameters: Vec<(String, serde_yaml::Value)>,
    /// All `--set` arguments of the case, name included.
    pub overrides: Vec<String>,
}

#[derive(Debug, Clone)]
pub struct Study {
    pub name: String,
    pub kind: StudyKind,
    /// The base spec, resolved against the study file's directory.
    pub base: PathBuf,
    pub keys: Vec<String>,
    /// The `set:` overrides, as `key=value`, that every case starts with.
    pub shared: Vec<String>,
    pub cases: Vec<Case>,
}

#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error("{path}: cannot read the study: {source}")]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: {message}")]
    Invalid { path: PathBuf, message: String },
}

/// A value as it goes on the command line after `key=`: YAML flow form.
pub fn value_arg(v: &serde_yaml::Value) -> String {
    match v {
        serde_yaml::Value::String(s) => format!("{s:?}"),
        other => serde_yaml::to_string(other)
            .unwrap_or_default()
            .trim()
            .to_string(),
    }
}

impl RawStudy {
    /// The JSON Schema of a study file (`ribbar schema study`).
    pub fn schema() -> serde_json::Value {
        crate::schema::root::<RawStudy>(
            "ribbar study",
            "A ribbar study: a base scene and the values of the keys it varies.",
        )
    }
}

impl Study {
    pub fn load(path: &Path) -> Result<Study, StudyError> {
        let text =
            geom::fsutil::read_capped(path, geom::fsutil::MAX_SPEC_BYTES).map_err(|source| {
                StudyError::Read {
                    path: path.to_path_buf(),
                    source,
                }
            })?;
        let invalid = |message: String| StudyError::Invalid {
            path: path.to_path_buf(),
            message,
        };
        let raw: RawStudy = serde_yaml::from_str(&text).map_err(|e| invalid(e.to_string()))?;
        if raw.name.is_empty()
            || !raw
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.'))
        {
            return Err(invalid(format!(
                "name: {:?} must be letters, digits, '-', '_' or '.'",
                raw.name
            )));
        }
        let base = path.parent().unwrap_or(Path::new(".")).join(&raw.base);
        if !base.is_file() {
            return Err(invalid(format!("base: {} is not a file", base.display())));
        }
        let (keys, lists) = parameter_lists(&raw, &invalid)?;
        let (count, how) = case_count(raw.combine, &lists);
        check_case_count(count, &how, raw.max_cases.unwrap_or(DEFAULT_MAX_CASES))
            .map_err(invalid)?;
        let combos = combinations(raw.combine, &keys, &lists, &invalid)?;
        let shared: Vec<String> = raw
            .set
            .iter()
            .map(|(k, v)| format!("{k}={}", value_arg(v)))
            .collect();
        let cases = combos
            .into_iter()
            .enumerate()
            .map(|(index, values)| {
                let name = format!("{}--{index}", raw.name);
                let parameters: Vec<(String, serde_yaml::Value)> =
                    keys.iter().cloned().zip(values).collect();
                let mut overrides = shared.clone();
                overrides.extend(
                    parameters
                        .iter()
                        .map(|(k, v)| format!("{k}={}", value_arg(v))),
                );
                overrides.push(format!("name={name}"));
                Case {
                    index,
                    name,
                    parameters,
                    overrides,
                }
            })
            .collect();
        Ok(Study {
            name: raw.name,
            kind: raw.kind,
            base,
            keys,
            shared,
            cases,
        })
    }
}

/// The study's varied keys and their value lists, checked against its kind.
fn parameter_lists(
    raw: &RawStudy,
    invalid: &dyn Fn(String) -> StudyError,
) -> Result<(Vec<String>, Vec<Vec<serde_yaml::Value>>), StudyError> {
    let mut keys = Vec::new();
    let mut lists = Vec::new();
    for (k, v) in &raw.parameters {
        let key = k
            .as_str()
            .ok_or_else(|| invalid(format!("parameters: key {k:?} is not a dotted spec key")))?
            .to_string();
        let values = v
            .as_sequence()
            .filter(|s| !s.is_empty())
            .ok_or_else(|| {
                invalid(format!(
                    "parameters.{key}: expected a non-empty list of values"
                ))
            })?
            .clone();
        keys.push(key);
        lists.push(values);
    }
    if keys.is_empty() {
        return Err(invalid(
            "parameters: at least one key with a list of values".into(),
        ));
    }
    if raw.kind == StudyKind::Convergence && keys.len() > 1 && raw.combine != Combine::Zip {
        return Err(invalid(format!(
            "parameters: a convergence study varies one size key (e.g. mesh.h_interface or \
             loading.max_step), or several with combine: zip (the first is the size), found {}",
            keys.len()
        )));
    }
    if raw.kind == StudyKind::Convergence && lists[0].len() < 3 {
        return Err(invalid(format!(
            "parameters.{}: a convergence study needs at least 3 grids, found {}",
            keys[0],
            lists[0].len()
        )));
    }
    if raw.kind == StudyKind::Convergence {
        for value in &lists[0] {
            size_of(&keys[0], value).map_err(invalid)?;
        }
    }
    Ok((keys, lists))
}

/// A convergence study's grid size, m: the value of its first key as a
/// length (a mesh size, or a step size); the message names the key.
pub fn size_of(key: &str, value: &serde_yaml::Value) -> Result<f64, String> {
    let field = format!("parameters.{key}");
    let bad = |why: String| {
        format!("{field}: a convergence study's size must be a positive length: {why}")
    };
    let raw: geom::units::RawQuantity =
        serde_yaml::from_value(value.clone()).map_err(|e| bad(e.to_string()))?;
    let h = raw
        .to_si(geom::units::Dim::Length, &field)
        .map_err(|e| bad(e.to_string()))?;
    if h > 0.0 {
        Ok(h)
    } else {
        Err(bad(format!("{h} m")))
    }
}

/// How many cases the lists make, and how (`10 × 10 × …`); `None` when
/// the product overflows.
fn case_count(combine: Combine, lists: &[Vec<serde_yaml::Value>]) -> (Option<usize>, String) {
    let lengths: Vec<String> = lists.iter().map(|l| l.len().to_string()).collect();
    match combine {
        Combine::Zip => (
            Some(lists[0].len()),
            format!("{} zipped values", lists[0].len()),
        ),
        Combine::Product => (
            lists.iter().try_fold(1usize, |n, l| n.checked_mul(l.len())),
            format!("the product {} of the lists' lengths", lengths.join(" × ")),
        ),
    }
}

/// One list of values per case: the lists side by side (`zip`) or every
/// combination (`product`).
fn combinations(
    combine: Combine,
    keys: &[String],
    lists: &[Vec<serde_yaml::Value>],
    invalid: &dyn Fn(String) -> StudyError,
) -> Result<Vec<Vec<serde_yaml::Value>>, StudyError> {
    Ok(match combine {
        Combine::Zip => {
            let n = lists[0].len();
            if let Some((k, l)) = keys.iter().zip(lists).find(|(_, l)| l.len() != n) {
                return Err(invalid(format!(
                    "parameters.{k}: zipped lists must have equal lengths ({} vs {n})",
                    l.len()
                )));
            }
            (0..n)
                .map(|i| lists.iter().map(|l| l[i].clone()).collect())
                .collect()
        }
        Combine::Product => lists.iter().fold(vec![Vec::new()], |acc, list| {
            acc.iter()
                .flat_map(|prefix| {
                    list.iter().map(move |v| {
                        let mut c = prefix.clone();
                        c.push(v.clone());
                        c
                    })
                })
                .collect()
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
        std::fs::create_dir_all(dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn product_and_zip_expand_cases_with_names_and_overrides() {
        let dir = std::env::temp_dir().join(format!("ribbar-study-test-{}", std::process::id()));
        write(&dir, "base.yaml", "name: b\n");
        let p = write(
            &dir,
            "s.yaml",
            "name: s\nbase: base.yaml\nparameters:\n  a.b: [1, 2]\n  c: [\"60 deg\", x, y]\n",
        );
        let s = Study::load(&p).unwrap();
        assert_eq!(s.cases.len(), 6);
        assert_eq!(s.cases[1].overrides, vec!["a.b=1", "c=\"x\"", "name=s--1"]);
        let p = write(
            &dir,
            "z.yaml",
            "name: z\nbase: base.yaml\ncombine: zip\nparameters:\n  a: [1, 2]\n  c: [3, 4, 5]\n",
        );
        let err = Study::load(&p).unwrap_err().to_string();
        assert!(
            err.contains("parameters.c") && err.contains("equal lengths"),
            "{err}"
        );
        let p = write(&dir, "c.yaml", "name: c\nbase: base.yaml\nkind: convergence\nparameters:\n  mesh.h_interface: [1, 2]\n");
        assert!(Study::load(&p)
            .unwrap_err()
            .to_string()
            .contains("at least 3 grids"));
        // A step-size series: the size first, the keys that scale with it
        // zipped after it.
        let p = write(
            &dir,
            "steps.yaml",
            "name: t\nbase: base.yaml\nkind: convergence\ncombine: zip\nparameters:\n  \
             loading.max_step: [20 um, 10 um, 5 um]\n  loading.initial_step: [5 um, 2.5 um, 1.25 um]\n",
        );
        let s = Study::load(&p).unwrap();
        let sizes: Vec<f64> = s
            .cases
            .iter()
            .map(|c| size_of(&c.parameters[0].0, &c.parameters[0].1).unwrap())
            .collect();
        for (h, expected) in sizes.iter().zip([20e-6, 10e-6, 5e-6]) {
            assert!((h / expected - 1.0).abs() < 1e-12, "{sizes:?}");
        }
        let p = write(
            &dir,
            "product.yaml",
            "name: t\nbase: base.yaml\nkind: convergence\nparameters:\n  \
             loading.max_step: [20 um, 10 um, 5 um]\n  loading.initial_step: [5 um, 2 um, 1 um]\n",
        );
        let err = Study::load(&p).unwrap_err().to_string();
        assert!(err.contains("combine: zip"), "{err}");
        let p = write(
            &dir,
            "tol.yaml",
            "name: t\nbase: base.yaml\nkind: convergence\nparameters:\n  \
             solver.impl_ex_tolerance: [3e-2, 1.5e-2, \"x\"]\n",
        );
        let err = Study::load(&p).unwrap_err().to_string();
        assert!(
            err.contains("parameters.solver.impl_ex_tolerance") && err.contains("length"),
            "{err}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// A product of six 10-value lists (10^6 cases) is refused with its
    /// count before it is expanded; `max_cases` raises the limit.
    #[test]
    fn a_study_too_large_is_refused_before_it_is_expanded() {
        let dir = std::env::temp_dir().join(format!("ribbar-study-big-{}", std::process::id()));
        write(&dir, "base.yaml", "name: b\n");
        let list = "[0.11, 0.12, 0.13, 0.14, 0.15, 0.16, 0.17, 0.18, 0.19, 0.2]";
        let params: String = ["a", "b", "c", "d", "e", "f"]
            .iter()
            .map(|k| format!("  {k}: {list}\n"))
            .collect();
        let p = write(
            &dir,
            "big.yaml",
            &format!("name: big\nbase: base.yaml\nparameters:\n{params}"),
        );
        let err = Study::load(&p).unwrap_err().to_string();
        assert!(
            err.contains("1000000 cases")
                && err.contains("10 × 10 × 10 × 10 × 10 × 10")
                && err.contains("max_cases = 1000"),
            "{err}"
        );
        let p = write(
            &dir,
            "raised.yaml",
            "name: r\nbase: base.yaml\nmax_cases: 2000\nparameters:\n  a: [1, 2]\n  b: [1, 2]\n",
        );
        assert_eq!(Study::load(&p).unwrap().cases.len(), 4);
        assert!(check_case_count(None, "x", 10)
            .unwrap_err()
            .contains("2^64"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// Every shipped study's every case is a valid scene: a `set:` or a
    /// parameter value its base's laws reject fails here, not hours into
    /// the study.
    #[test]
    fn every_shipped_study_case_is_a_valid_scene() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../specs/studies");
        let mut studies = 0;
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_none_or(|e| e != "yaml") {
                continue;
            }
            let study = Study::load(&path).unwrap_or_else(|e| panic!("{e}"));
            for case in &study.cases {
                crate::scene::Scene::load(&study.base, &case.overrides)
                    .unwrap_or_else(|e| panic!("{}: case {}: {e}", path.display(), case.name));
            }
            studies += 1;
        }
        assert!(studies >= 10, "{studies} studies in {}", dir.display());
    }
}
