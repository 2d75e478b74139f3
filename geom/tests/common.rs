//! Helpers shared by the geometry integration tests.
#![allow(dead_code)]

use geom::spec::{resolve, Bar, RawBar, RawSpecimen, Specimen};
use std::path::{Path, PathBuf};

/// The workspace root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .unwrap()
        .to_path_buf()
}

/// Reads the `bar` and `specimen` sections of a shipped scene spec.
pub fn load_spec(name: &str) -> (Bar, Specimen) {
    let path = root().join("specs").join(format!("{name}.yaml"));
    let text = std::fs::read_to_string(&path).unwrap();
    let doc: serde_yaml::Value = serde_yaml::from_str(&text).unwrap();
    let bar: RawBar = serde_yaml::from_value(doc["bar"].clone()).unwrap();
    // `specimen.non_adhesive` is the solve's (the scene takes it out before
    // geom reads the section).
    let mut specimen = doc["specimen"].clone();
    if let Some(map) = specimen.as_mapping_mut() {
        map.remove("non_adhesive");
    }
    let specimen: RawSpecimen = serde_yaml::from_value(specimen).unwrap();
    resolve(&bar, &specimen).unwrap()
}

/// A fresh scratch directory under the target directory.
pub fn scratch(name: &str) -> PathBuf {
    let dir = root().join("target").join("geom-tests").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The geometry stage's report and gmsh's OpenCASCADE model of its script
/// measured against it (as the mesh stage measures it before meshing).
#[allow(dead_code)]
pub fn build_and_measure(
    bar: &Bar,
    specimen: &Specimen,
    dir: &std::path::Path,
) -> (geom::GeometryReport, geom::occ::OccReport) {
    let gmsh = geom::gmsh::Gmsh::locate().expect("gmsh (run scripts/setup.sh)");
    let report = geom::build_geometry(bar, specimen, dir).unwrap_or_else(|e| panic!("{e}"));
    let occ = geom::occ::measure(&gmsh, bar, specimen, &dir.join("specimen.geo"), dir)
        .unwrap_or_else(|e| panic!("{e}"));
    (report, occ)
}
