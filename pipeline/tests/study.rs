//! Studies end to end with real gmsh: sweeps share upstream stages, tables
//! and plots are written, convergence studies report GCI (the Snakemake
//! export under a real `snakemake`: tests/cluster.rs).

use crate::common::{repo, text};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn work_dir(name: &str) -> PathBuf {
    crate::common::scratch("study", name)
}

/// Runs `cmd` in the repository; its status and its stdout and stderr as one text.
fn output(cmd: &mut Command) -> (Output, String) {
    let o: Output = cmd
        .current_dir(repo())
        .stdin(Stdio::null())
        .output()
        .expect("command runs");
    let t = text(&o);
    (o, t)
}

fn ok(cmd: &mut Command) -> String {
    let (o, t) = output(cmd);
    assert!(o.status.success(), "{cmd:?} failed:\n{t}");
    t
}

fn ribbar() -> Command {
    Command::new(env!("CARGO_BIN_EXE_ribbar"))
}

fn entries(dir: &Path) -> usize {
    std::fs::read_dir(dir)
        .map(|d| {
            d.filter_map(|e| e.ok())
                .filter(|e| !e.file_name().to_string_lossy().contains('.'))
                .count()
        })
        .unwrap_or(0)
}

/// Issue 6: a sweep runs its cases in parallel, cases that agree on the
/// geometry and mesh share those stages, and the study writes one table row
/// per case and one plot with every curve.
#[test]
fn sweep_shares_upstream_stages_and_tabulates() {
    let work = work_dir("sweep");
    let w = work.to_str().unwrap();
    ok(ribbar().args([
        "study",
        "tests/data/tiny-friction.yaml",
        "--work",
        w,
        "--jobs",
        "2",
    ]));
    assert_eq!(entries(&work.join(".store/geometry")), 1);
    assert_eq!(entries(&work.join(".store/mesh")), 1);
    assert_eq!(entries(&work.join(".store/solve")), 2);
    let table = std::fs::read_to_string(work.join("tiny-friction/table.csv")).unwrap();
    let lines: Vec<&str> = table.lines().collect();
    assert_eq!(lines.len(), 3, "{table}");
    assert!(
        lines[0].starts_with("case,materials.interface.mu"),
        "{table}"
    );
    assert!(work.join("tiny-friction/table.md").is_file());
    assert!(work.join("tiny-friction/bond_slip.png").is_file());
    // Friction only adds shear: without it the post-peak bond stress is
    // lower (on a smooth bar with little confinement, only slightly).
    let residual = |case: &str| -> f64 {
        let s: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(work.join(case).join("summary.json")).unwrap(),
        )
        .unwrap();
        s.pointer("/curve/residual_bond_stress")
            .and_then(|v| v.as_f64())
            .unwrap()
    };
    assert!(residual("tiny-friction--1") < residual("tiny-friction--0"));
    std::fs::remove_dir_all(&work).unwrap();
}

/// Issue 6: a convergence study over four mesh sizes writes the observed
/// order / Richardson / GCI tables and the least-squares uncertainty of
/// every grid.
#[test]
fn convergence_study_writes_gci_tables() {
    let work = work_dir("convergence");
    let w = work.to_str().unwrap();
    let printed = ok(ribbar().args([
        "study",
        "tests/data/tiny-convergence.yaml",
        "--work",
        w,
        "--jobs",
        "2",
    ]));
    let md = std::fs::read_to_string(work.join("tiny-convergence/convergence.md")).unwrap();
    assert!(
        md.contains("peak_bond_stress") && md.contains("GCI") || md.contains("gci"),
        "{md}"
    );
    assert!(md.contains("Uncertainty from all grids"), "{md}");
    // The run says each plotted quantity's error on the finest grid.
    assert!(
        printed.contains("convergence: first_peak_bond_stress on h = 1.75 mm: GCI")
            && printed.contains("uncertainty U"),
        "{printed}"
    );
    let csv = std::fs::read_to_string(work.join("tiny-convergence/convergence.csv")).unwrap();
    assert!(csv.lines().count() >= 5, "{csv}");
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let column = header.iter().position(|c| *c == "uncertainty").unwrap();
    // The finest grid's first-peak line carries a finite, non-negative
    // uncertainty.
    let finest = csv
        .lines()
        .find(|l| l.starts_with("first_peak_bond_stress,1.75,"))
        .unwrap_or_else(|| panic!("{csv}"));
    let u: f64 = finest.split(',').nth(column).unwrap().parse().unwrap();
    assert!(u.is_finite() && u >= 0.0, "{finest}");
    std::fs::remove_dir_all(&work).unwrap();
}

/// A case the spec checks refuse fails alone: the study names the case and
/// the refusal itself (not only the log that holds it), exits non-zero, and
/// the other case's results are published.
#[test]
fn a_refused_case_says_why_and_the_others_are_kept() {
    let work = work_dir("refused");
    std::fs::create_dir_all(&work).unwrap();
    let study = work.join("refused.yaml");
    let base = repo().join("tests/data/tiny-smooth.yaml");
    std::fs::write(
        &study,
        format!(
            "name: refused\nbase: {}\nparameters:\n  materials.interface.mu: [0.3, -0.5]\n",
            base.display()
        ),
    )
    .unwrap();
    let (o, text) = output(
        ribbar()
            .args(["study", study.to_str().unwrap(), "--work"])
            .arg(&work),
    );
    assert!(!o.status.success(), "{text}");
    let line = text
        .lines()
        .find(|l| l.starts_with("[refused--1]") && l.contains("failed"))
        .unwrap_or_else(|| panic!("no failure line for the refused case:\n{text}"));
    assert!(
        line.contains("materials.interface.mu") && line.contains("refused--1.mesh.log"),
        "{line}"
    );
    assert!(text.contains("1 of 2 cases failed"), "{text}");
    assert!(work.join("refused--0/summary.json").is_file(), "{text}");
    std::fs::remove_dir_all(&work).unwrap();
}
