//! Writes the `.geo` of a scene spec's specimen, optionally overriding its
//! symmetry, without running gmsh (for benchmarks of the mesh stage):
//! `cargo run -p geom --example write_geo -- SPEC.yaml OUT.geo [auto|full|half|quarter]`

use geom::spec::{resolve, RawBar, RawSpecimen, RawSymmetry};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let usage = "usage: write_geo SPEC.yaml OUT.geo [auto|full|half|quarter]";
    let spec = args.get(1).ok_or(usage)?;
    let out = args.get(2).ok_or(usage)?;
    let doc: serde_yaml::Value = serde_yaml::from_str(&std::fs::read_to_string(spec)?)?;
    let bar: RawBar = serde_yaml::from_value(doc["bar"].clone())?;
    // The solver's key of the specimen section is not the geometry's.
    let mut raw_specimen = doc["specimen"].clone();
    if let Some(m) = raw_specimen.as_mapping_mut() {
        m.remove("non_adhesive");
    }
    let mut specimen: RawSpecimen = serde_yaml::from_value(raw_specimen)?;
    if let Some(s) = args.get(3) {
        specimen.symmetry = Some(serde_yaml::from_str::<RawSymmetry>(s)?);
    }
    let (bar, specimen) = resolve(&bar, &specimen)?;
    let layout = geom::layout::Layout::new(&bar, &specimen);
    std::fs::write(out, geom::geo::write_geo(&layout))?;
    eprintln!("{out}: symmetry {:?}", specimen.symmetry);
    Ok(())
}
