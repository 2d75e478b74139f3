//! `ribbar study --export snakemake`: a study as a Snakemake workflow laid
//! out as the Snakemake workflow catalogue lays them out, to run where the
//! study runs (this machine, a Slurm cluster) with only its config changed:
//!
//! ```text
//! DIR/workflow/Snakefile          wildcard rules, one per stage (the same for every study)
//! DIR/workflow/rules/common.smk   the case table, the ribbar commands, the resources
//! DIR/config/config.yaml          the ribbar command, the work directory, resource margins
//! DIR/config/cases.tsv            one row per case: its name, its values, its --set overrides
//! DIR/config/study.yaml           the study, its base the scene beside it
//! DIR/config/scene.yaml           the study's base scene, byte for byte
//! DIR/profiles/slurm/config.yaml  a profile for snakemake-executor-plugin-slurm
//! ```
//! The cases are the study's expansion (any kind), so the workflow's stages
//! have the same keys as `ribbar study`'s and share its store.

use crate::study::{value_arg, Case, Study};
use anyhow::{bail, Context, Result};
use std::path::{Path, PathBuf};

const SNAKEFILE: &str = include_str!("../templates/snakemake/Snakefile");
const COMMON: &str = include_str!("../templates/snakemake/common.smk");
const SLURM_PROFILE: &str = include_str!("../templates/snakemake/slurm-profile.yaml");

/// Memory and time of a mesh job: gmsh's are not estimated (a mesh of
/// R2's 2.3 M tets takes about 14 s and 2 GB), so a bound that holds them.
const MESH_MEM_MB: u64 = 4000;
const MESH_RUNTIME_MIN: u64 = 30;
/// Threads of a solve job (its parallel assembly and linear solves).
const SOLVE_THREADS: u64 = 2;
/// The factor on the estimated peak memory of a solve: the largest
/// measured / estimated ratio of the calibration runs is below it
/// (docs/src/validation/cluster-resources.md).
pub const MEMORY_MARGIN: f64 = 1.5;
/// The factor on the estimated one-thread time of a solve: the largest
/// measured / estimated ratio of the calibration runs is below it.
pub const RUNTIME_MARGIN: f64 = 3.0;
/// A floor under every solve's memory (MB) and time (min): the process
/// and gmsh's libraries, the scheduler's start-up.
const SOLVE_MIN_MEM_MB: u64 = 1000;
const SOLVE_MIN_RUNTIME: u64 = 10;

/// What an export wrote.
pub struct Exported {
    pub dir: PathBuf,
    pub cases: usize,
}

/// Writes the workflow of `study` (read from `study_file`) into `dir`, its
/// config pointing at the work directory `work` and the `ribbar` program.
pub fn export_snakemake(
    study: &Study,
    study_file: &Path,
    work: &Path,
    ribbar: &Path,
    dir: &Path,
) -> Result<Exported> {
    let write = |rel: &str, bytes: &[u8]| -> Result<()> {
        crate::store::write_atomic(&dir.join(rel), bytes)
            .with_context(|| format!("writing the workflow's {rel}"))
    };
    write("workflow/Snakefile", SNAKEFILE.as_bytes())?;
    write("workflow/rules/common.smk", COMMON.as_bytes())?;
    write("profiles/slurm/config.yaml", SLURM_PROFILE.as_bytes())?;
    let scene = std::fs::read(&study.base)
        .with_context(|| format!("reading the study's base {}", study.base.display()))?;
    write("config/scene.yaml", &scene)?;
    write(
        "config/study.yaml",
        study_copy(study_file, "scene.yaml")?.as_bytes(),
    )?;
    write("config/cases.tsv", case_table(study)?.as_bytes())?;
    let work = std::path::absolute(work).unwrap_or_else(|_| work.to_path_buf());
    write(
        "config/config.yaml",
        config_yaml(&study.name, &work, ribbar).as_bytes(),
    )?;
    Ok(Exported {
        dir: dir.to_path_buf(),
        cases: study.cases.len(),
    })
}

/// The study file with its `base` replaced by `base` (the copy of the
/// scene beside it); everything else as written.
fn study_copy(study_file: &Path, base: &str) -> Result<String> {
    let text = std::fs::read_to_string(study_file)
        .with_context(|| format!("reading {}", study_file.display()))?;
    let mut doc: serde_yaml::Value = serde_yaml::from_str(&text)
        .with_context(|| format!("{}: not YAML", study_file.display()))?;
    let Some(map) = doc.as_mapping_mut() else {
        bail!("{}: not a mapping", study_file.display());
    };
    map.insert("base".into(), base.into());
    Ok(format!(
        "# {}, exported with the workflow: its base is the scene beside it.\n{}",
        study_file.display(),
        serde_yaml::to_string(&doc)?
    ))
}

/// The case table: `case`, the varied keys' values as the study gives them,
/// and `set`, the case's `--set` overrides (name included) as one
/// shell-quoted line, which is what the workflow runs.
pub fn case_table(study: &Study) -> Result<String> {
    let keys: Vec<&str> = study
        .cases
        .first()
        .map(|c| c.parameters.iter().map(|(k, _)| k.as_str()).collect())
        .unwrap_or_default();
    if let Some(k) = keys.iter().find(|k| matches!(**k, "case" | "set")) {
        bail!("parameters.{k}: the case table names its own columns so; no spec key is called so");
    }
    let mut rows = vec![[vec!["case"], keys.clone(), vec!["set"]]
        .concat()
        .iter()
        .map(|s| tsv_field(s))
        .collect::<Vec<_>>()
        .join("\t")];
    for case in &study.cases {
        rows.push(case_row(case)?);
    }
    Ok(rows.join("\n") + "\n")
}

fn case_row(case: &Case) -> Result<String> {
    let mut fields = vec![tsv_field(&case.name)];
    fields.extend(
        case.parameters
            .iter()
            .map(|(_, v)| tsv_field(&value_arg(v))),
    );
    let sets: Vec<String> = case.overrides.iter().map(|o| shell_quote(o)).collect();
    fields.push(tsv_field(&sets.join(" ")));
    Ok(fields.join("\t"))
}

/// A field of a tab-separated table as Python's csv module reads it: in
/// double quotes (doubled inside) when it holds a tab, a newline or a quote.
fn tsv_field(s: &str) -> String {
    if s.contains(['\t', '\n', '\r', '"']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// `s` as one word of a POSIX shell (and of Python's shlex.split).
pub fn shell_quote(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_.=/:+,@%".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}

/// A YAML scalar for a path or a command: JSON's string form, which YAML reads.
fn yaml_string(s: &str) -> String {
    serde_json::to_string(s).expect("strings serialise")
}

fn config_yaml(study: &str, work: &Path, ribbar: &Path) -> String {
    format!(
        r#"# Config of the workflow of ribbar study {study} (`ribbar study --export snakemake`).
# Relative paths are relative to the directory snakemake runs in (the one
# holding workflow/ and config/). Moving the workflow to a cluster, or
# anywhere else, changes only `ribbar` and `work`.

# The command that runs ribbar on every host that runs a job: a path, a name
# on the PATH ("ribbar"), or a wrapper ("apptainer exec ribbar.sif ribbar").
ribbar: {ribbar}
# The work directory: ribbar's store and each case's results. On a cluster,
# a file system every node mounts at the same path, with record locks that
# hold across hosts (docs/src/explanation/cluster-store.md).
work: {work}
study: config/study.yaml
scene: config/scene.yaml
cases: config/cases.tsv
study_name: {name}

# What each job asks the scheduler for. A solve's memory and time come from
# ribbar's estimate of it once its mesh is made (results/estimates/), times
# the margin below, times the attempt (2, 3 on the profile's retries); the
# models and their measured error: docs/src/validation/cluster-resources.md.
resources:
  mesh:
    threads: 1
    mem_mb: {mesh_mem}
    runtime: {mesh_runtime}
  solve:
    threads: {solve_threads}
    memory_margin: {memory_margin}
    min_mem_mb: {solve_min_mem}
    runtime_margin: {runtime_margin}
    min_runtime: {solve_min_runtime}
"#,
        ribbar = yaml_string(&ribbar.display().to_string()),
        work = yaml_string(&work.display().to_string()),
        name = yaml_string(study),
        mesh_mem = MESH_MEM_MB,
        mesh_runtime = MESH_RUNTIME_MIN,
        solve_threads = SOLVE_THREADS,
        memory_margin = MEMORY_MARGIN,
        solve_min_mem = SOLVE_MIN_MEM_MB,
        runtime_margin = RUNTIME_MARGIN,
        solve_min_runtime = SOLVE_MIN_RUNTIME,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A value with a tab, a quote or a newline stays one field, and an
    /// override with spaces or quotes stays one shell word.
    #[test]
    fn fields_and_words_survive_their_separators() {
        assert_eq!(tsv_field("a\tb"), "\"a\tb\"");
        assert_eq!(tsv_field("say \"x\""), "\"say \"\"x\"\"\"");
        assert_eq!(tsv_field("0.3"), "0.3");
        assert_eq!(shell_quote("name=s--1"), "name=s--1");
        assert_eq!(
            shell_quote("bar.angle=\"60 deg\""),
            "'bar.angle=\"60 deg\"'"
        );
        assert_eq!(shell_quote("it's"), "'it'\\''s'");
    }
}
