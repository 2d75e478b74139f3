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
//!
//! A sampled study draws its cases from a design space (`space`) with a
//! seeded sequence (`sequence`); a sensitivity study draws Saltelli's
//! design or Morris trajectories over the same space (`design`) and names
//! the responses it estimates indices of (`responses`):
//!
//! ```yaml
//! name: rib-design
//! base: ../r1-coarse.yaml
//! kind: sample                      # or sensitivity, with method: sobol | morris
//! sampler: {method: sobol, n: 32, seed: 7}
//! parameters:
//!   bar.ribs.height: {range: ["0.3 mm", "0.6 mm"]}
//!   bar.ribs.side_b: {choices: [rotated, mirrored]}
//! ```
//!
//! A case is the base spec with `--set key=value` overrides and the scene
//! name `<study>--<index>`; its stages share the store with every other case,
//! so cases that agree on a stage's inputs share that stage's artifacts.
//! Every kind expands to such a plain list of cases, which any runner (the
//! local one, an exported workflow) takes as it is.

mod design;
mod responses;
mod sequence;
mod space;

pub use design::{
    morris, saltelli, sample, Check, DesignPoint, Points, RejectedDraw, Role, Verdict,
};
pub use responses::{
    all_responses, parse_responses, stress_at_slip, Response, DEFAULT_RESPONSE_SLIP,
    SUMMARY_RESPONSES,
};
pub use sequence::{generator, Method, Stream};
pub use space::{display_unit, short_key, value_arg, Axis, AxisValue, Scale, Span};

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
    /// Cases drawn from a design space by a seeded sequence.
    Sample,
    /// Cases of a design for sensitivity indices (Sobol' or Morris).
    Sensitivity,
}

impl StudyKind {
    pub fn name(self) -> &'static str {
        match self {
            StudyKind::Sweep => "sweep",
            StudyKind::Convergence => "convergence",
            StudyKind::Sample => "sample",
            StudyKind::Sensitivity => "sensitivity",
        }
    }

    /// Whether the parameters are a design space (ranges and choices)
    /// rather than lists of values.
    pub fn is_sampled(self) -> bool {
        matches!(self, StudyKind::Sample | StudyKind::Sensitivity)
    }
}

/// The estimator of a sensitivity study.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum SensitivityMethod {
    /// Morris's elementary effects: μ*, σ per parameter.
    Morris,
    /// Sobol' first-order and total indices from Saltelli's design.
    Sobol,
}

/// `sampler:` as written.
#[derive(Debug, Clone, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawSampler {
    /// The sequence a sample study draws its designs from; a sensitivity
    /// study draws its own (choice; required for sample; sobol, halton,
    /// lhs or random).
    pub method: Option<Method>,
    /// Designs (sample), base rows (sobol) or trajectories (morris)
    /// (count; required; at least 1, 2 for sensitivity).
    pub n: usize,
    /// The seed of the sequence: the same seed draws the same designs
    /// (count; default 0).
    #[serde(default)]
    pub seed: u64,
    /// Morris's grid levels (count; default 4; even, at least 2).
    pub levels: Option<usize>,
}

/// How a sampled or sensitivity study's points were drawn.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Plan {
    Sample {
        method: Method,
        n: usize,
        seed: u64,
    },
    Sobol {
        n: usize,
        seed: u64,
    },
    Morris {
        trajectories: usize,
        levels: usize,
        seed: u64,
    },
}

impl Plan {
    /// The plan in words, as the study's outputs state it.
    pub fn describe(&self) -> String {
        match self {
            Plan::Sample { method, n, seed } => {
                format!("{n} designs, {} sequence, seed {seed}", method.name())
            }
            Plan::Sobol { n, seed } => format!(
                "Saltelli's design on {n} base rows of Owen-scrambled Sobol' points, seed {seed}"
            ),
            Plan::Morris {
                trajectories,
                levels,
                seed,
            } => {
                format!("{trajectories} Morris trajectories on a {levels}-level grid, seed {seed}")
            }
        }
    }
}

/// The design of a sampled or sensitivity study: its space, how its
/// points were drawn, the points (one per case, in case order) and the
/// draws that were outside the design bounds, and its responses.
#[derive(Debug, Clone)]
pub struct Design {
    pub axes: Vec<Axis>,
    pub plan: Plan,
    pub points: Points,
    pub responses: Vec<Response>,
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
    /// How the parameter lists of a sweep or a convergence study make
    /// cases (choice; default product).
    pub combine: Option<Combine>,
    /// Dotted scene key → list of values (sweep, convergence), e.g.
    /// `bar.ribs.angle: [40 deg, 55 deg]`, in the order written; a
    /// convergence study's first key is its size, with at least 3 values,
    /// and further keys need `combine: zip`. A sample or sensitivity study
    /// gives each key a `{range: [low, high]}` (with `scale: log` for a
    /// logarithmic axis) or `{choices: [...]}` instead (mapping; required;
    /// at least one key, no empty list).
    #[schemars(schema_with = "crate::schema::parameter_lists")]
    pub parameters: serde_yaml::Mapping,
    /// Dotted scene key → one value applied to every case (mapping; default
    /// {}).
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, serde_json::Value>")]
    pub set: BTreeMap<String, serde_yaml::Value>,
    /// The most cases the study may expand to; a larger study is refused
    /// before it is expanded (count; default 1000; at least 1).
    #[serde(default)]
    pub max_cases: Option<usize>,
    /// How a sample or sensitivity study draws its points: `{method:
    /// sobol | halton | lhs | random, n, seed}` for a sample, `{n, seed}`
    /// (Sobol' base rows) or `{n, seed, levels}` (Morris trajectories) for a
    /// sensitivity study (mapping; required for sample and sensitivity).
    pub sampler: Option<RawSampler>,
    /// A sensitivity study's estimator: `sobol` (first-order and total
    /// indices) or `morris` (elementary effects) (choice; required for
    /// sensitivity).
    pub method: Option<SensitivityMethod>,
    /// The responses a sample or sensitivity study tabulates and a
    /// sensitivity study estimates indices of: summary names, or
    /// `{stress_at_slip: "0.5 mm"}` (list of responses; default all).
    #[schemars(with = "Option<Vec<serde_json::Value>>")]
    pub responses: Option<Vec<serde_yaml::Value>>,
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
    /// A sampled or sensitivity study's design (its points are the cases').
    pub design: Option<Design>,
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
        let shared: Vec<String> = raw
            .set
            .iter()
            .map(|(k, v)| format!("{k}={}", value_arg(v)))
            .collect();
        let max_cases = raw.max_cases.unwrap_or(DEFAULT_MAX_CASES);
        let (keys, rows, design) = if raw.kind.is_sampled() {
            let design = sampled_design(&raw, &base, &shared).map_err(invalid)?;
            let how = design.plan.describe();
            check_case_count(Some(design.points.points.len()), &how, max_cases).map_err(invalid)?;
            let keys = design.axes.iter().map(|a| a.key.clone()).collect();
            let rows = design
                .points
                .points
                .iter()
                .map(|p| {
                    p.values
                        .iter()
                        .map(|v| (v.table.clone(), v.arg.clone()))
                        .collect()
                })
                .collect();
            (keys, rows, Some(design))
        } else {
            refuse_sampled_keys(&raw).map_err(invalid)?;
            let (keys, lists) = parameter_lists(&raw, &invalid)?;
            let combine = raw.combine.unwrap_or_default();
            let (count, how) = case_count(combine, &lists);
            check_case_count(count, &how, max_cases).map_err(invalid)?;
            let combos = combinations(combine, &keys, &lists, &invalid)?;
            let rows = combos
                .into_iter()
                .map(|values| {
                    values
                        .into_iter()
                        .map(|v| (v.clone(), value_arg(&v)))
                        .collect()
                })
                .collect();
            (keys, rows, None)
        };
        let cases = cases(&raw.name, &keys, &shared, rows);
        Ok(Study {
            name: raw.name,
            kind: raw.kind,
            base,
            keys,
            shared,
            cases,
            design,
        })
    }
}

/// The cases of a study from one row of (table value, `--set` value) per
/// case.
fn cases(
    study: &str,
    keys: &[String],
    shared: &[String],
    rows: Vec<Vec<(serde_yaml::Value, String)>>,
) -> Vec<Case> {
    rows.into_iter()
        .enumerate()
        .map(|(index, row)| {
            let name = format!("{study}--{index}");
            let mut overrides = shared.to_vec();
            overrides.extend(
                keys.iter()
                    .zip(&row)
                    .map(|(k, (_, arg))| format!("{k}={arg}")),
            );
            overrides.push(format!("name={name}"));
            Case {
                index,
                name,
                parameters: keys
                    .iter()
                    .cloned()
                    .zip(row.into_iter().map(|(v, _)| v))
                    .collect(),
                overrides,
            }
        })
        .collect()
}

/// The keys a sweep or convergence study does not read, named when given.
fn refuse_sampled_keys(raw: &RawStudy) -> Result<(), String> {
    let given = [
        ("sampler", raw.sampler.is_some()),
        ("method", raw.method.is_some()),
        ("responses", raw.responses.is_some()),
    ];
    match given.iter().find(|(_, g)| *g) {
        Some((key, _)) => Err(format!(
            "{key}: only for kind: sample or kind: sensitivity (this study is a {})",
            raw.kind.name()
        )),
        None => Ok(()),
    }
}

/// The design of a sample or sensitivity study: its axes, its points drawn
/// and checked as scenes (the base spec with `shared` and the point's
/// values), and its responses.
fn sampled_design(raw: &RawStudy, base: &Path, shared: &[String]) -> Result<Design, String> {
    if raw.combine.is_some() {
        return Err(format!("combine: not for a {} study", raw.kind.name()));
    }
    let axes: Vec<Axis> = raw
        .parameters
        .iter()
        .map(|(k, v)| {
            let key = k
                .as_str()
                .ok_or_else(|| format!("parameters: key {k:?} is not a dotted spec key"))?;
            Axis::parse(key, v)
        })
        .collect::<Result<_, _>>()?;
    if axes.is_empty() {
        return Err("parameters: at least one key with a range or choices".into());
    }
    let plan = plan(raw)?;
    let responses = parse_responses(raw.responses.as_deref())?;
    let text =
        std::fs::read_to_string(base).map_err(|e| format!("base: {}: {e}", base.display()))?;
    let check = |values: &[AxisValue]| -> Result<design::Verdict, String> {
        let mut overrides = shared.to_vec();
        overrides.extend(
            axes.iter()
                .zip(values)
                .map(|(a, v)| format!("{}={}", a.key, v.arg)),
        );
        match crate::scene::Scene::from_yaml(&text, base, &overrides) {
            Ok(_) => Ok(design::Verdict::Valid),
            Err(crate::scene::SceneError::Invalid { source, .. }) => {
                Ok(design::Verdict::OutOfBounds(source.to_string()))
            }
            Err(e) => Err(format!("a case is not a scene: {e}")),
        }
    };
    let points = match plan {
        Plan::Sample { method, n, seed } => design::sample(&axes, method, n, seed, &check)?,
        Plan::Sobol { n, seed } => design::saltelli(&axes, n, seed, &check)?,
        Plan::Morris {
            trajectories,
            levels,
            seed,
        } => design::morris(&axes, trajectories, levels, seed, &check)?,
    };
    Ok(Design {
        axes,
        plan,
        points,
        responses,
    })
}

/// How a sampled or sensitivity study's `sampler` and `method` draw.
fn plan(raw: &RawStudy) -> Result<Plan, String> {
    let sampler = raw.sampler.as_ref().ok_or_else(|| {
        format!(
            "sampler: required for a {} study, e.g. {{method: sobol, n: 32, seed: 7}}",
            raw.kind.name()
        )
    })?;
    let (n, seed) = (sampler.n, sampler.seed);
    if raw.kind == StudyKind::Sample {
        if raw.method.is_some() {
            return Err(
                "method: for kind: sensitivity; a sample's sequence is sampler.method".into(),
            );
        }
        if sampler.levels.is_some() {
            return Err(
                "sampler.levels: for Morris trajectories (kind: sensitivity, method: morris)"
                    .into(),
            );
        }
        let method = sampler
            .method
            .ok_or("sampler.method: required: sobol, halton, lhs or random")?;
        if n == 0 {
            return Err("sampler.n: at least 1 design".into());
        }
        return Ok(Plan::Sample { method, n, seed });
    }
    if sampler.method.is_some() {
        return Err(
            "sampler.method: a sensitivity study draws its own design (Saltelli's from Sobol' \
             points, or Morris trajectories): give n and seed"
                .into(),
        );
    }
    let method = raw
        .method
        .ok_or("method: required for a sensitivity study: sobol or morris")?;
    if n < 2 {
        return Err(format!(
            "sampler.n: at least 2 ({} of a sensitivity study)",
            match method {
                SensitivityMethod::Sobol => "base rows",
                SensitivityMethod::Morris => "trajectories",
            }
        ));
    }
    match method {
        SensitivityMethod::Sobol => {
            if sampler.levels.is_some() {
                return Err("sampler.levels: for method: morris".into());
            }
            Ok(Plan::Sobol { n, seed })
        }
        SensitivityMethod::Morris => {
            let levels = sampler.levels.unwrap_or(4);
            if levels < 2 || levels % 2 != 0 {
                return Err(format!(
                    "sampler.levels: {levels}: an even number, at least 2"
                ));
            }
            Ok(Plan::Morris {
                trajectories: n,
                levels,
                seed,
            })
        }
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
    if raw.kind == StudyKind::Convergence && keys.len() > 1 && raw.combine != Some(Combine::Zip) {
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

    fn sampled(dir: &Path, name: &str, head: &str) -> Result<Study, StudyError> {
        let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/tiny-ribbed.yaml");
        let text = format!(
            "name: {name}\nbase: {}\n{head}\nparameters:\n  bar.ribs.height: {{range: [0.3 mm, 0.7 mm]}}\n  \
             bar.ribs.angle: {{range: [45 deg, 90 deg]}}\n  bar.ribs.top_width: {{range: [0.5 mm, 3 mm]}}\n  \
             bar.ribs.side_b: {{choices: [rotated, mirrored]}}\n",
            base.display()
        );
        Study::load(&write(dir, &format!("{name}.yaml"), &text))
    }

    fn designs(s: &Study) -> Vec<Vec<String>> {
        s.cases.iter().map(|c| c.overrides.clone()).collect()
    }

    /// A sampled study gives the same designs from the same seed and other
    /// designs from another, for every sequence; its table values are SI.
    #[test]
    fn the_seed_fixes_a_sampled_studys_designs() {
        let dir = std::env::temp_dir().join(format!("ribbar-sampled-{}", std::process::id()));
        for method in ["sobol", "halton", "lhs", "random"] {
            let head = |seed: u64| {
                format!("kind: sample\nsampler: {{method: {method}, n: 6, seed: {seed}}}")
            };
            let a = sampled(&dir, "a", &head(7)).unwrap();
            let again = sampled(&dir, "a", &head(7)).unwrap();
            let other = sampled(&dir, "a", &head(8)).unwrap();
            assert_eq!(a.cases.len(), 6, "{method}");
            assert_eq!(designs(&a), designs(&again), "{method}");
            assert_ne!(designs(&a), designs(&other), "{method}");
            let (key, height) = &a.cases[0].parameters[0];
            assert_eq!(key, "bar.ribs.height");
            let h = height.as_f64().unwrap();
            assert!((0.3e-3..=0.7e-3).contains(&h), "{method}: {h}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Draws outside the design bounds (ribs so wide at so low an angle
    /// that they overlap, or too wide for the longitudinal ribs) are kept
    /// with the spec's reason and replaced, so the study has its n cases,
    /// each a valid scene.
    #[test]
    fn draws_outside_the_bounds_are_reported_and_replaced() {
        let dir = std::env::temp_dir().join(format!("ribbar-rejected-{}", std::process::id()));
        let s = sampled(
            &dir,
            "r",
            "kind: sample\nsampler: {method: lhs, n: 12, seed: 1}",
        )
        .unwrap();
        let design = s.design.as_ref().unwrap();
        assert_eq!(s.cases.len(), 12);
        assert!(!design.points.rejected.is_empty());
        for r in &design.points.rejected {
            assert!(r.reason.contains("must be"), "{r:?}");
        }
        for case in &s.cases {
            crate::scene::Scene::load(&s.base, &case.overrides).unwrap();
        }
        // Sensitivity designs keep their structure: Sobol' rows of d + 2
        // cases, Morris trajectories of d + 1.
        let sobol = sampled(
            &dir,
            "s",
            "kind: sensitivity\nmethod: sobol\nsampler: {n: 3, seed: 2}",
        )
        .unwrap();
        assert_eq!(sobol.cases.len(), 3 * 6);
        let morris = sampled(
            &dir,
            "m",
            "kind: sensitivity\nmethod: morris\nsampler: {n: 2, seed: 2}",
        )
        .unwrap();
        assert_eq!(morris.cases.len(), 2 * 5);
        std::fs::remove_dir_all(&dir).ok();
    }

    /// Keys of the wrong kind, a missing sampler and an unknown spec key
    /// are refused with the key named, before anything runs.
    #[test]
    fn sampled_studies_refuse_what_they_cannot_run() {
        let dir = std::env::temp_dir().join(format!("ribbar-sampled-bad-{}", std::process::id()));
        for (head, words) in [
            ("kind: sample", "sampler: required"),
            ("kind: sample\nsampler: {n: 4}", "sampler.method"),
            (
                "kind: sample\ncombine: zip\nsampler: {method: sobol, n: 4}",
                "combine",
            ),
            ("kind: sensitivity\nsampler: {n: 4}", "method: required"),
            (
                "kind: sensitivity\nmethod: sobol\nsampler: {method: lhs, n: 4}",
                "sampler.method",
            ),
            (
                "kind: sensitivity\nmethod: morris\nsampler: {n: 4, levels: 3}",
                "levels",
            ),
            (
                "kind: sample\nsampler: {method: sobol, n: 4}\nresponses: [peak]",
                "unknown response",
            ),
        ] {
            let err = sampled(&dir, "b", head).unwrap_err().to_string();
            assert!(err.contains(words), "{head}: {err}");
        }
        let base = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/data/tiny-ribbed.yaml");
        let typo = write(
            &dir,
            "t.yaml",
            &format!(
                "name: t\nbase: {}\nkind: sample\nsampler: {{method: sobol, n: 2}}\nparameters:\n  \
                 bar.ribs.hieght: {{range: [0.3 mm, 0.7 mm]}}\n",
                base.display()
            ),
        );
        let err = Study::load(&typo).unwrap_err().to_string();
        assert!(
            err.contains("hieght") && err.contains("not a scene"),
            "{err}"
        );
        let p = write(
            &dir,
            "sweep.yaml",
            &format!(
                "name: w\nbase: {}\nsampler: {{n: 2}}\nparameters:\n  a: [1]\n",
                base.display()
            ),
        );
        assert!(Study::load(&p)
            .unwrap_err()
            .to_string()
            .contains("only for kind: sample"));
        std::fs::remove_dir_all(&dir).ok();
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
