//! `ribbar bench linear` end to end on a coarse mesh, with real gmsh and,
//! when installed, real CalculiX.

use crate::common::repo;
use std::process::{Command, Stdio};

fn ccx_installed() -> bool {
    std::env::var_os("PATH")
        .map(|p| std::env::split_paths(&p).any(|d| d.join("ccx").is_file()))
        .unwrap_or(false)
}

/// Issue 7: the perfect-bond benchmark writes its table with every ribbar
/// solver, and when `ccx` is installed the reaction forces agree with
/// CalculiX's within 0.5 %; with petsc4py, PETSc's GAMG gives ribbar's AMG
/// reaction within 1e-6.
#[test]
fn bench_linear_table_and_agreement_with_calculix() {
    let tmp = std::env::temp_dir().join(format!("ribbar-bench-linear-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    let (work, out) = (tmp.join("work"), tmp.join("out"));
    let o = Command::new(env!("CARGO_BIN_EXE_ribbar"))
        .args([
            "bench",
            "linear",
            "--set",
            "mesh.h_interface=3 mm",
            "--set",
            "mesh.h_outer=8 mm",
        ])
        .arg("--work")
        .arg(&work)
        .arg("--out")
        .arg(&out)
        .current_dir(repo())
        .stdin(Stdio::null())
        .output()
        .expect("ribbar runs");
    let log = crate::common::text(&o);
    assert!(o.status.success(), "bench failed:\n{log}");
    let table = std::fs::read_to_string(out.join("linear.md")).expect("linear.md written");
    let rows: Vec<Vec<&str>> = table
        .lines()
        .filter(|l| l.starts_with("| full") || l.starts_with("| quarter"))
        .map(|l| l.split('|').map(str::trim).collect())
        .collect();
    let solvers: Vec<&str> = rows.iter().map(|r| r[4]).collect();
    assert!(solvers.iter().any(|s| s.contains("Cholesky")), "{table}");
    assert!(solvers.iter().any(|s| s.contains("AMG")), "{table}");
    assert!(rows.iter().any(|r| r[1] == "quarter"), "{table}");
    let force = |r: &Vec<&str>| r[9].parse::<f64>().unwrap();
    for r in &rows {
        assert!(force(r) > 0.0, "reaction of {r:?}");
    }
    let full: Vec<&Vec<&str>> = rows.iter().filter(|r| r[1] == "full").collect();
    if ccx_installed() {
        let ccx = full
            .iter()
            .find(|r| r[4].contains("CalculiX"))
            .expect("a CalculiX row");
        for r in full.iter().filter(|r| r[4].starts_with("ribbar")) {
            let rel = (force(r) - force(ccx)).abs() / force(ccx);
            assert!(rel < 5e-3, "{} vs ccx: {rel:e}\n{table}", r[4]);
            let printed: f64 = r[10].parse().unwrap();
            assert!(printed.abs() < 5e-3, "printed difference {r:?}");
        }
    } else {
        assert!(table.contains("not installed"), "{table}");
    }
    // PETSc's CG + GAMG solves the system ribbar's AMG solves: the same
    // reaction to the CG tolerance, when petsc4py is there at all.
    match full.iter().find(|r| r[4].starts_with("PETSc")) {
        Some(petsc) => {
            let amg = full
                .iter()
                .find(|r| r[4].contains("AMG"))
                .expect("an AMG row");
            let rel = (force(petsc) - force(amg)).abs() / force(amg);
            assert!(rel < 1e-6, "PETSc vs ribbar's AMG: {rel:e}\n{table}");
            assert!(
                table.contains("PETSc's reaction against ribbar's AMG"),
                "{table}"
            );
        }
        None => assert!(
            table.contains("petsc4py is not installed"),
            "no PETSc row and no reason:\n{table}"
        ),
    }
    let _ = std::fs::remove_dir_all(&tmp);
}
