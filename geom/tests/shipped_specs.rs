//! The shipped scene specs build in real gmsh with agreeing metrics.

use crate::common;

use geom::gmsh::Gmsh;

fn build(name: &str) -> (geom::GeometryReport, geom::occ::OccReport) {
    let (bar, specimen) = common::load_spec(name);
    let dir = common::scratch(name);
    let (report, occ) = common::build_and_measure(&bar, &specimen, &dir);
    assert!(dir.join("specimen.geo").is_file() && dir.join("geometry.json").is_file());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("geometry.json")).unwrap()).unwrap();
    for key in [
        "f_R",
        "rib_volume_m3",
        "bar_volume_m3",
        "interface_area_adhesive_m2",
        "interface_area_free_m2",
        "rib_count",
        "checks",
    ] {
        assert!(json.get(key).is_some(), "{name}: geometry.json lacks {key}");
    }
    for (q, c) in report.checks.iter().chain(&occ.checks) {
        assert!(c.agree && c.max_rel_diff <= 0.01, "{name}: {q} {c:?}");
    }
    // The stage's two ways and gmsh's are the same quantities.
    assert_eq!(
        report.checks.keys().collect::<Vec<_>>(),
        occ.checks.keys().collect::<Vec<_>>()
    );
    assert!(occ.checks.values().all(|c| c.gmsh_occ.is_some()));
    eprintln!(
        "{name}: f_R {:.4}, ribs {}, gmsh {:.1} s, checks {:?}",
        report.f_r, report.rib_count, occ.build_seconds, occ.checks
    );
    (report, occ)
}

/// R1 builds; f_R meets EN 1992-1-1's minimum for 6.5–12 mm bars and the three-way checks agree within 1 % (SPEC §3, issue 2).
#[test]
fn r1_builds() {
    let (r, _) = build("r1");
    assert!(r.f_r >= 0.040 && r.f_r < 0.2, "{}", r.f_r);
    assert!(r.checks.contains_key("rib_volume_m3"));
}

/// R1-coarse has R1's bar and specimen (SPEC §2).
#[test]
fn r1_coarse_builds_like_r1() {
    let (r, _) = build("r1-coarse");
    let (b1, s1) = common::load_spec("r1");
    assert_eq!((r.bar, r.specimen), (b1, s1));
}

/// R2 builds; f_R meets EN 1992-1-1's minimum 0.056 for bars above 12 mm (SPEC §3).
#[test]
fn r2_builds() {
    let (r, _) = build("r2");
    assert!(r.f_r >= 0.056 && r.f_r < 0.2, "{}", r.f_r);
}

/// The smooth scenes build; their interface is a cylinder of area π d l (SPEC §2).
#[test]
fn smooth_scenes_build() {
    for (name, d, l, l_adh) in [
        ("smooth-80", 8e-3, 80e-3, 40e-3),
        ("smooth-125", 10e-3, 125e-3, 62.5e-3),
    ] {
        let (r, occ) = build(name);
        assert_eq!(r.rib_count, 0);
        let expect = std::f64::consts::PI * d * l_adh;
        assert!(
            (r.interface_area_adhesive_m2 - expect).abs() < 1e-9 * expect.max(1.0),
            "{name}"
        );
        let free = std::f64::consts::PI * d * (l - l_adh);
        assert!(
            (occ.checks["interface_area_free_m2"].gmsh_occ.unwrap() - free).abs() < 1e-6 * free,
            "{name}"
        );
    }
}

/// l_adh = L (the paper's caption reading of smooth-125) builds with no free zone (SPEC §2: l_adh ≤ L).
#[test]
fn full_adhesive_length_builds() {
    let (bar, mut specimen) = common::load_spec("smooth-125");
    specimen.adhesive_length = specimen.cube_side;
    let dir = common::scratch("smooth-125-full");
    let (r, occ) = common::build_and_measure(&bar, &specimen, &dir);
    assert_eq!(occ.group_entities["interface_free"], 0);
    assert!(r.interface_area_free_m2.abs() < 1e-12);
    let expect = std::f64::consts::PI * 10e-3 * 125e-3;
    let occ_area = occ.checks["interface_area_adhesive_m2"].gmsh_occ.unwrap();
    assert!((occ_area - expect).abs() < 1e-6 * expect);
}

/// A rib design OCC is asked to build goes through gmsh, and a broken script fails with gmsh's message, not a panic (SPEC §8).
#[test]
fn gmsh_errors_surface_with_the_message() {
    let gmsh = Gmsh::locate().expect("gmsh (run scripts/setup.sh)");
    let dir = common::scratch("broken");
    std::fs::write(
        dir.join("bad.geo"),
        "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 1};\n",
    )
    .unwrap();
    let out = gmsh.run(
        &["bad.geo", "-0"],
        Some(&dir),
        std::time::Duration::from_secs(60),
    );
    let text = match out {
        Ok(o) => format!("{}{}", o.stdout, o.stderr),
        Err(e) => e.to_string(),
    };
    assert!(text.contains("Error"), "{text}");
}
