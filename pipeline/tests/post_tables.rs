//! Study and convergence tables in CSV and Markdown (SPEC §7 "Studies",
//! "a table"; issue 6 study outputs).

use pipeline::post::{
    convergence_order_table, convergence_study, study_table, summarize, write_convergence_tables,
    write_study_tables, Cell, CurveRow, GridResult, StudyCase, SummaryOptions,
};
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join("post_tables")
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn curve(peak_mpa: f64) -> Vec<CurveRow> {
    [(0.2, 0.5), (0.5, 1.0), (1.0, 0.6), (2.0, 0.4)]
        .iter()
        .enumerate()
        .map(|(i, &(fed, k))| CurveRow::new(i + 1, 0.0, 0.0, fed * 1e-3, k * peak_mpa * 1e6, 2))
        .collect()
}

fn cases() -> Vec<StudyCase> {
    let opts = SummaryOptions::default();
    vec![
        StudyCase {
            label: "beta=40".into(),
            params: vec![
                ("bar.ribs.angle".into(), Cell::Text("40 deg".into())),
                ("mu".into(), 0.3.into()),
            ],
            summary: summarize(&curve(10.0), &opts).unwrap().table_entries(),
        },
        StudyCase {
            label: "beta=90, rough|x".into(),
            params: vec![
                ("bar.ribs.angle".into(), Cell::Text("90 deg".into())),
                ("mu".into(), 0.001.into()),
                (
                    "mesh.h_interface".into(),
                    (&serde_json::json!(0.0008)).into(),
                ),
            ],
            summary: vec![
                ("peak_bond_stress_MPa".into(), 12.5.into()),
                ("note".into(), "stopped at step 3".into()),
            ],
        },
    ]
}

/// Columns are `case`, then parameters, then summary quantities, each in
/// order of first appearance; missing values are empty cells.
#[test]
fn study_table_column_order() {
    let t = study_table(&cases());
    assert_eq!(
        t.columns,
        [
            "case",
            "bar.ribs.angle",
            "mu",
            "mesh.h_interface",
            "peak_bond_stress_MPa",
            "fed_at_peak_mm",
            "first_peak_bond_stress_MPa",
            "fed_at_first_peak_mm",
            "energy_to_1mm_J_per_m2",
            "residual_bond_stress_MPa",
            "final_fed_mm",
            "steps",
            "iterations",
            "note",
        ]
    );
    assert_eq!(t.rows[0][3], Cell::Empty);
    assert_eq!(t.rows[1][3], Cell::Num(0.0008));
    assert_eq!(t.rows[0][4], Cell::Num(10.0));
    assert_eq!(t.rows[1][5], Cell::Empty);
    assert_eq!(t.rows[0][11], Cell::Int(4));
}

/// CSV is written with full precision and RFC 4180 quoting, Markdown with
/// escaped pipes and right-aligned numeric columns; both files are written.
#[test]
fn study_tables_written() {
    let dir = scratch("study");
    let (csv, md) = (dir.join("out/study.csv"), dir.join("out/study.md"));
    write_study_tables(&cases(), &csv, &md).unwrap();
    let csv_text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = csv_text.lines().collect();
    assert_eq!(lines.len(), 3);
    assert!(lines[0].starts_with("case,bar.ribs.angle,mu,mesh.h_interface,peak_bond_stress_MPa,"));
    assert!(
        lines[1].starts_with("beta=40,40 deg,0.3,,10,"),
        "{}",
        lines[1]
    );
    assert!(
        lines[2].starts_with("\"beta=90, rough|x\",90 deg,0.001,0.0008,12.5,"),
        "{}",
        lines[2]
    );
    assert!(lines[2].ends_with(",stopped at step 3"), "{}", lines[2]);

    let md_text = std::fs::read_to_string(&md).unwrap();
    let md_lines: Vec<&str> = md_text.lines().collect();
    assert_eq!(md_lines.len(), 4);
    assert!(md_lines[0].starts_with("| case | bar.ribs.angle | mu |"));
    assert!(
        md_lines[1].starts_with("| --- | --- | ---: | ---: | ---: |"),
        "{}",
        md_lines[1]
    );
    assert!(
        md_lines[3].starts_with("| beta=90, rough\\|x | 90 deg | 0.001 | 8e-4 | 12.5 |"),
        "{}",
        md_lines[3]
    );
    // Every Markdown row has as many cells as the header.
    let bars = |l: &str| l.replace("\\|", "").matches('|').count();
    assert!(md_lines.iter().all(|l| bars(l) == bars(md_lines[0])));
}

/// The convergence table lists every grid (h, DOFs, value, error against
/// the extrapolated value, GCI, wall time); CSV numbers read back exactly.
#[test]
fn convergence_tables_written() {
    let f = |h: f64| 9.0 + 2.0e6 * h * h;
    let h = [0.4e-3, 0.8e-3, 1.2e-3, 1.6e-3];
    let grids: Vec<GridResult> = h
        .iter()
        .enumerate()
        .map(|(i, &h)| GridResult {
            h,
            value: f(h),
            dofs: Some(1000 * (4 - i) as u64),
            wall_time: Some(10.0 / (i + 1) as f64),
        })
        .collect();
    let studies = vec![
        convergence_study("peak_bond_stress_MPa", &grids).unwrap(),
        convergence_study(
            "fed_at_peak_mm",
            &grids
                .iter()
                .map(|g| GridResult { value: 0.3, ..*g })
                .collect::<Vec<_>>(),
        )
        .unwrap(),
    ];
    let dir = scratch("conv");
    let (csv, md) = (dir.join("convergence.csv"), dir.join("convergence.md"));
    write_convergence_tables(&studies, &csv, &md).unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(
        lines[0],
        "quantity,h_mm,dofs,value,rel_error_vs_extrapolated,gci,uncertainty,wall_time_s"
    );
    assert_eq!(lines.len(), 1 + 8);
    let first: Vec<&str> = lines[1].split(',').collect();
    assert_eq!(first[0], "peak_bond_stress_MPa");
    assert_eq!(first[1].parse::<f64>().unwrap(), 0.4);
    assert_eq!(first[2], "4000");
    assert_eq!(first[3].parse::<f64>().unwrap(), f(0.4e-3));
    let err: f64 = first[4].parse().unwrap();
    assert!((err - (f(0.4e-3) - 9.0) / 9.0).abs() < 1e-9, "{err}");
    assert_eq!(
        first[5].parse::<f64>().unwrap(),
        studies[0].triplets[0].gci_fine.unwrap()
    );
    // An exact second-order series: the least-squares uncertainty is
    // 1.25 × the finest grid's error relative to its value.
    let u: f64 = first[6].parse().unwrap();
    let exact = 1.25 * (f(0.4e-3) - 9.0) / f(0.4e-3);
    assert!((u - exact).abs() < 1e-6 * exact, "{u} against {exact}");
    assert_eq!(first[7], "10");
    // Coarsest grid: no GCI.
    assert_eq!(lines[4].split(',').nth(5), Some(""));

    let md_text = std::fs::read_to_string(&md).unwrap();
    assert!(md_text.contains(
        "| quantity | h_mm | dofs | value | rel_error_vs_extrapolated | gci | uncertainty | wall_time_s |"
    ));
    assert!(
        md_text.contains("| peak_bond_stress_MPa | a h^p") && md_text.contains("Eça & Hoekstra"),
        "{md_text}"
    );
    assert!(
        md_text.contains("| peak_bond_stress_MPa | 0.4 / 0.8 / 1.2 | monotonic | 2 | 9 |"),
        "{md_text}"
    );
    assert!(
        md_text.contains("| fed_at_peak_mm | 0.4 / 0.8 / 1.2 | grid-independent |"),
        "{md_text}"
    );

    let order = convergence_order_table(&studies);
    assert_eq!(order.rows.len(), 4);
}

/// A study case built from its study-file parameters and its summary.json
/// gets the curve summary's columns (in named units) and the solver's DOFs
/// and wall time.
#[test]
fn study_case_from_summary_json() {
    let curve = summarize(&curve(10.0), &SummaryOptions::default()).unwrap();
    let summary = serde_json::json!({
        "scene": "r1",
        "curve": curve,
        "solver": {"summary": {"dofs": 12345, "wall_time_s": {"total": 61.5}}},
    });
    let params: Vec<(String, serde_yaml::Value)> = vec![
        (
            "bar.ribs.angle".into(),
            serde_yaml::from_str("60 deg").unwrap(),
        ),
        (
            "materials.interface.mu".into(),
            serde_yaml::from_str("0.3").unwrap(),
        ),
        ("mesh.refine".into(), serde_yaml::from_str("2").unwrap()),
    ];
    let case = StudyCase::from_summary("case-3", &params, &summary);
    assert_eq!(case.label, "case-3");
    assert_eq!(
        case.params,
        vec![
            ("bar.ribs.angle".to_string(), Cell::Text("60 deg".into())),
            ("materials.interface.mu".to_string(), Cell::Num(0.3)),
            ("mesh.refine".to_string(), Cell::Int(2)),
        ]
    );
    let names: Vec<&str> = case.summary.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(&names[..2], ["peak_bond_stress_MPa", "fed_at_peak_mm"]);
    assert_eq!(&names[names.len() - 2..], ["dofs", "solve_wall_time_s"]);
    assert_eq!(case.summary[0].1, Cell::Num(10.0));
    assert_eq!(case.summary[names.len() - 2].1, Cell::Int(12345));
    assert_eq!(case.summary[names.len() - 1].1, Cell::Num(61.5));
    // No curve object: only what is there.
    let bare = StudyCase::from_summary("x", &[], &serde_json::json!({}));
    assert!(bare.summary.is_empty());
}
