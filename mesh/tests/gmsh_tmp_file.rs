//! gmsh runs at once (a study meshing two cases at a time, parallel tests)
//! mesh as they do alone.

mod common;
use common::*;
use mesh::MeshSpec;

/// The mesh stage's options reach gmsh without its per-user temporary file
/// `~/.gmsh-tmp`, through which gmsh parses a `-string`: runs started
/// together overwrite and remove each other's, and a run that lost it
/// meshed with gmsh's defaults (docs/src/explanation/mesh.md). With that file made
/// unwritable (a directory in its place), `run_gmsh` still meshes with the
/// spec's options, byte for byte as with a usable home, while the same
/// options given as a `-string` are lost and the mesh changes.
#[test]
fn options_do_not_go_through_gmsh_temporary_file() {
    let dir = scratch("gmsh-tmp-file");
    let geo = data("smooth.geo");
    let spec = MeshSpec {
        h_interface: 0.0016,
        h_outer: 0.004,
        timeout: 120.0,
        ..MeshSpec::default()
    };
    let normal = dir.join("normal.msh");
    mesh::run_gmsh(gmsh(), &geo, &spec, &normal).unwrap();
    let home = dir.join("home");
    std::fs::create_dir_all(home.join(".gmsh-tmp")).unwrap();
    // This test binary holds this test alone: no other thread reads HOME.
    std::env::set_var("HOME", &home);
    let blocked = dir.join("blocked.msh");
    mesh::run_gmsh(gmsh(), &geo, &spec, &blocked).unwrap();
    let with_string = dir.join("string.msh");
    let mut args = mesh::gmsh_args(&std::path::absolute(&geo).unwrap(), &spec, &with_string);
    if let Some(at) = args.iter().position(|a| a == "Mesh.Algorithm3D") {
        args.drain(at - 1..at + 2);
    }
    args.extend([
        "-string".into(),
        format!("Mesh.Algorithm3D={};", spec.algorithm_3d.gmsh_id()),
    ]);
    gmsh()
        .run(&args, Some(&dir), std::time::Duration::from_secs(120))
        .unwrap();
    let read = |p: &std::path::Path| std::fs::read(p).unwrap();
    assert!(read(&blocked) == read(&normal), "the options were lost");
    assert!(
        read(&with_string) != read(&normal),
        "a -string with an unwritable ~/.gmsh-tmp should lose its option"
    );
}
