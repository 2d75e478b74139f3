//! A sensitivity study end to end with real gmsh: Saltelli's design on a
//! tiny ribbed scene, its cases' bond laws, the indices, their bar plot and
//! the trends, from the `ribbar` binary.

use crate::common::repo;
use std::path::Path;
use std::process::{Command, Stdio};

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// A Sobol' sensitivity study of two rib parameters writes its design,
/// every case's bond law, sensitivity.csv with S1, ST and their intervals
/// for each parameter and response, the estimators and what has no
/// indices in sensitivity.md, the bar plot and the trend plots; the table
/// holds the sampled values in SI beside the fitted law.
#[test]
fn a_sobol_study_writes_indices_bond_laws_and_trends() {
    let work = std::env::temp_dir().join(format!("ribbar-sobol-study-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&work);
    std::fs::create_dir_all(&work).unwrap();
    let study = work.join("s.yaml");
    std::fs::write(
        &study,
        format!(
            "name: tiny-sobol\nbase: {}\nkind: sensitivity\nmethod: sobol\n\
             sampler: {{n: 2, seed: 5}}\nset: {{loading.u_final: 0.05 mm}}\n\
             responses: [first_peak_bond_stress, energy, mc2010_tau_max]\nparameters:\n  \
             bar.ribs.height: {{range: [0.35 mm, 0.65 mm]}}\n  bar.ribs.angle: {{range: [50 deg, 90 deg]}}\n",
            repo().join("tests/data/tiny-ribbed.yaml").display()
        ),
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_ribbar"))
        .args([
            "study",
            study.to_str().unwrap(),
            "--work",
            work.to_str().unwrap(),
            "-j",
            "2",
        ])
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "{text}");
    let dir = work.join("tiny-sobol");
    let designs = read(&dir.join("designs.csv"));
    assert_eq!(designs.lines().count(), 1 + 2 * 4, "{designs}");
    assert!(
        designs.contains(",row 0 A,") && designs.contains(",row 1 AB(bar.ribs.angle),"),
        "{designs}"
    );
    let csv = read(&dir.join("sensitivity.csv"));
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "parameter,response,S1,S1_conf,ST,ST_conf,rows");
    for response in ["first_peak_bond_stress", "mc2010_tau_max"] {
        for key in ["bar.ribs.height", "bar.ribs.angle"] {
            let row = lines
                .iter()
                .find(|l| l.starts_with(&format!("{key},{response},")))
                .unwrap_or_else(|| panic!("{key} {response}: {csv}"));
            let cells: Vec<&str> = row.split(',').collect();
            assert!(
                cells[2..6]
                    .iter()
                    .all(|c| c.parse::<f64>().unwrap().is_finite()),
                "{row}"
            );
            assert_eq!(cells[6], "2", "{row}");
        }
    }
    // The curves stop at 0.05 mm: no energy to 1 mm, and the file says so.
    assert!(!csv.contains(",energy,"), "{csv}");
    let md = read(&dir.join("sensitivity.md"));
    assert!(
        md.contains("Saltelli") && md.contains("Jansen") && md.contains("energy: no indices"),
        "{md}"
    );
    for plot in [
        "sensitivity.png",
        "sensitivity.svg",
        "trend_first_peak_bond_stress.png",
    ] {
        assert!(dir.join("plots").join(plot).is_file(), "{plot}");
    }
    let table = read(&dir.join("table.csv"));
    let header: Vec<&str> = table.lines().next().unwrap().split(',').collect();
    let height = header.iter().position(|c| *c == "bar.ribs.height").unwrap();
    assert!(
        header.contains(&"mc2010_tau_max_MPa") && header.contains(&"f_R"),
        "{table}"
    );
    for row in table.lines().skip(1) {
        let h: f64 = row.split(',').nth(height).unwrap().parse().unwrap();
        assert!((0.35e-3..=0.65e-3).contains(&h), "{row}");
    }
    let laws = read(&dir.join("bond_laws.csv"));
    assert_eq!(laws.lines().count(), 9, "{laws}");
    for case in 0..8 {
        let law: serde_json::Value = serde_json::from_str(&read(
            &work.join(format!("tiny-sobol--{case}/bond_law.json")),
        ))
        .unwrap();
        assert!(law["mc2010"]["tau_max"].as_f64().unwrap() > 0.0, "{law}");
        assert!(
            law["design_code"]["tau_max"].as_f64().unwrap() > 0.0,
            "{law}"
        );
    }
    std::fs::remove_dir_all(&work).ok();
}
