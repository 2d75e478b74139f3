//! Times the mesh stage (gmsh, read, build, write) on a `.geo`:
//! `cargo run --release -p mesh --example mesh_bench -- GEO H_INTERFACE_M [hxt|delaunay] [OUT_DIR]`
//! Prints `mesh.json`.

use mesh::{mesh_specimen, Gmsh, MeshSpec};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let geo = PathBuf::from(
        args.get(1)
            .ok_or("usage: mesh_bench GEO H_INTERFACE_M [ALGO] [OUT_DIR]")?,
    );
    let h: f64 = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(4e-4);
    let algorithm_3d = match args.get(3).map(String::as_str) {
        Some("delaunay") => mesh::spec::Algorithm3d::Delaunay,
        _ => mesh::spec::Algorithm3d::Hxt,
    };
    let out = PathBuf::from(
        args.get(4)
            .cloned()
            .unwrap_or_else(|| "target/mesh_bench".into()),
    );
    let spec = MeshSpec {
        h_interface: h,
        h_outer: 5e-3,
        algorithm_3d,
        ..MeshSpec::default()
    };
    let report = mesh_specimen(&Gmsh::locate()?, &geo, &spec, 0.008, 0.040, &out)?;
    println!("{}", serde_json::to_string_pretty(&report)?);
    Ok(())
}
