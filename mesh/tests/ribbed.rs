//! The spiral-ribbed bar of the geometry stage, meshed at the paper's
//! interface size: topology and interface area (SPEC §3, §4, issue 3).

use crate::common;
use common::*;
use mesh::{mesh_specimen, MeshSpec, Model};

/// On geom's ribbed specimen (R1 bar in a short 20 mm cube) at h_interface =
/// 0.4 mm, every topology requirement holds and the mesh's interface areas
/// (its half-turn half's, doubled) equal geometry.json's within 1 % (SPEC
/// §4, issue 3).
#[test]
fn ribbed_specimen_topology_and_area() {
    let dir = scratch("ribbed");
    let bar: geom::spec::RawBar = serde_yaml::from_str(
        "kind: ribbed\ndiameter: 8 mm\nribs: {height: 0.52 mm, spacing: 5 mm, angle: 55 deg, top_width: 0.8 mm, base_width: 1.84 mm, side_b: rotated, phase: 0 mm}\nlongitudinal_ribs: {height: 0.6 mm, top_width: 0.8 mm, base_width: 2.0 mm}",
    )
    .unwrap();
    let specimen: geom::spec::RawSpecimen = serde_yaml::from_str(
        "cube_side: 20 mm\nadhesive_length: 10 mm\nfree_overhang: 2 mm\nloaded_overhang: 4 mm",
    )
    .unwrap();
    let (bar, specimen) = geom::spec::resolve(&bar, &specimen).unwrap();
    let geo_report = geom::build_geometry(&bar, &specimen, &dir).unwrap();
    let spec = MeshSpec {
        h_interface: 0.4e-3,
        h_outer: 4e-3,
        ..MeshSpec::default()
    };
    let r = mesh_specimen(
        gmsh(),
        &dir.join("specimen.geo"),
        &spec,
        bar.diameter,
        specimen.adhesive_length,
        &dir,
    )
    .unwrap();
    let model = Model::load(&dir.join(mesh::MODEL_FILE)).unwrap();
    check_topology(&model);
    // A spiral bar is modelled as its half-turn half; the geometry reports
    // the whole specimen.
    assert_eq!(model.symmetry, mesh::Symmetry::HalfTurn);
    let fraction = geo_report.modelled_fraction;
    for (mesh_area, geo_area) in [
        (
            r.interface_area_adhesive_m2,
            geo_report.interface_area_adhesive_m2,
        ),
        (r.interface_area_free_m2, geo_report.interface_area_free_m2),
    ] {
        let rel = (mesh_area / fraction - geo_area).abs() / geo_area;
        assert!(
            rel < 0.01,
            "mesh {mesh_area} / {fraction} vs geometry {geo_area}: {rel}"
        );
    }
    assert_eq!(model.bar_diameter, 0.008);
    assert_eq!(model.adhesive_length, 0.010);
    assert!(r.min_quality > 0.02, "{r:?}");
}
