//! `ribbar bench mesh-series --quick` and `ribbar bench solver-settings
//! --quick` end to end (real gmsh, tiny smooth scene).

use crate::common::repo;
use std::process::Command;

fn bench(kind: &str, work: &std::path::Path, sets: &[&str]) -> String {
    let out = work.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_ribbar"))
        .args([
            "bench",
            kind,
            "--quick",
            "-q",
            "--work",
            work.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .args(sets.iter().flat_map(|s| ["--set", s]))
        .current_dir(repo())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::read_to_string(out.join(format!("{kind}.md"))).unwrap()
}

/// Issue 7 mesh series: per grid DOFs, stage times, peak σ_mb and energy
/// with errors against the Richardson extrapolation and the GCI (Celik et
/// al. 2008), a triplet table, the error-against-time plot, and an energy
/// balance within its 1 % tolerance.
#[test]
fn mesh_series_writes_table_gci_and_plot() {
    let work = std::env::temp_dir().join(format!("ribbar-bench-mesh-{}", std::process::id()));
    let md = bench("mesh-series", &work, &[]);
    let rows: Vec<&str> = md
        .lines()
        .filter(|l| l.starts_with("| 3 |") || l.starts_with("| 2.5 |") || l.starts_with("| 2 |"))
        .collect();
    assert_eq!(rows.len(), 3, "{md}");
    for r in &rows {
        let cells: Vec<&str> = r.split('|').map(str::trim).collect();
        assert!(cells[2].parse::<u64>().unwrap() > 100, "DOFs in {r}");
        assert_eq!(cells[4], "yes", "{r}");
        let imbalance: f64 = cells[15].parse().unwrap();
        assert!(imbalance < 1e-2, "{r}");
    }
    assert!(md.contains("| energy | 2 / 2.5 / 3 |"), "{md}");
    assert!(
        work.join("out/mesh-series-error-vs-time.png").is_file() || md.contains("no extrapolation")
    );
    std::fs::remove_dir_all(&work).unwrap();
}

/// Issue 7 solver settings: every variant is timed and compared with the
/// reference run (its own distance is 0, the others' finite).
#[test]
fn solver_settings_compares_against_the_reference() {
    let work = std::env::temp_dir().join(format!("ribbar-bench-settings-{}", std::process::id()));
    let md = bench("solver-settings", &work, &["loading.u_final=\"0.15 mm\""]);
    let rows: Vec<Vec<String>> = md
        .lines()
        .filter(|l| l.starts_with("| ") && !l.starts_with("| setting"))
        .map(|l| l.split('|').map(|c| c.trim().to_string()).collect())
        .collect();
    assert_eq!(
        rows.len(),
        pipeline::bench_series::solver_variants().len(),
        "{md}"
    );
    assert!(
        rows[0][1].starts_with("reference") && rows[0][9] == "0.00e0",
        "{:?}",
        rows[0]
    );
    let compared = rows
        .iter()
        .skip(1)
        .filter(|r| r[9].parse::<f64>().is_ok_and(|d| d.is_finite() && d > 0.0))
        .count();
    assert!(compared >= rows.len() / 2, "{md}");
    std::fs::remove_dir_all(&work).unwrap();
}
