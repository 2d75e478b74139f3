//! Bad input to the mesh stage: each a typed error naming what and where,
//! never a panic, earlier artifacts intact (SPEC §8).

use crate::common;
use common::*;
use mesh::{build_model, mesh_specimen, read_msh, MeshError, MeshSpec, Model};
use std::path::Path;

fn smooth_msh(dir: &Path) -> Vec<u8> {
    let msh = mesh_file(&data("smooth.geo"), &small_spec(0.0016), dir);
    std::fs::read(msh).unwrap()
}

fn read_bytes(dir: &Path, name: &str, bytes: &[u8]) -> Result<mesh::RawMesh, MeshError> {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    read_msh(&p)
}

/// gmsh failing on a broken .geo is an error showing gmsh's own message (SPEC §4).
#[test]
fn broken_geo_shows_gmsh_error() {
    let dir = scratch("broken_geo");
    let geo = dir.join("broken.geo");
    std::fs::write(
        &geo,
        "SetFactory(\"OpenCASCADE\");\nBox(1) = {0, 0, 0, 1, 1;\n",
    )
    .unwrap();
    let err = mesh::run_gmsh(gmsh(), &geo, &small_spec(0.001), &dir.join("x.msh")).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, MeshError::GmshFailed { .. }), "{err:?}");
    assert!(msg.contains("broken.geo") && msg.contains("Error"), "{msg}");
}

/// A missing .geo is an I/O error naming the file.
#[test]
fn missing_geo_is_named() {
    let dir = scratch("missing_geo");
    let err = mesh::run_gmsh(
        gmsh(),
        &dir.join("nope.geo"),
        &small_spec(0.001),
        &dir.join("x.msh"),
    )
    .unwrap_err();
    assert!(
        matches!(err, MeshError::Io { .. }) && err.to_string().contains("nope.geo"),
        "{err}"
    );
}

/// gmsh exceeding mesh.timeout is killed and reported (SPEC §4).
#[test]
fn timeout_is_reported() {
    let dir = scratch("timeout");
    let spec = MeshSpec {
        timeout: 0.01,
        ..small_spec(0.0004)
    };
    let err = mesh::run_gmsh(gmsh(), &data("smooth.geo"), &spec, &dir.join("x.msh")).unwrap_err();
    assert!(matches!(err, MeshError::GmshTimeout { .. }), "{err:?}");
    assert!(err.to_string().contains("mesh.timeout"));
}

/// A .msh cut anywhere is a corrupt-file error naming the file, never a panic (SPEC §8).
#[test]
fn truncated_msh_is_an_error() {
    let dir = scratch("truncated");
    let bytes = smooth_msh(&dir);
    for k in 1..40 {
        let cut = bytes.len() * k / 40;
        let err = read_bytes(&dir, "cut.msh", &bytes[..cut]).unwrap_err();
        assert!(
            matches!(err, MeshError::MshCorrupt { .. }),
            "cut at {cut}: {err:?}"
        );
        assert!(err.to_string().contains("cut.msh"), "{err}");
    }
    assert!(read_bytes(&dir, "empty.msh", b"").is_err());
}

/// Corrupt counts, corrupt node references and arbitrary byte damage give
/// errors or a checked mesh, never a panic or a huge allocation (SPEC §8).
#[test]
fn corrupt_msh_is_an_error() {
    let dir = scratch("corrupt");
    let bytes = smooth_msh(&dir);
    let find = |pat: &[u8]| bytes.windows(pat.len()).position(|w| w == pat).unwrap();
    // Node count of the $Nodes header: an absurd value.
    let mut b = bytes.clone();
    let at = find(b"$Nodes\n") + 7 + 8;
    b[at..at + 8].copy_from_slice(&u64::MAX.to_le_bytes());
    let err = read_bytes(&dir, "count.msh", &b).unwrap_err();
    assert!(matches!(err, MeshError::MshCorrupt { .. }), "{err:?}");
    // The first element's first node tag of the last block (the tets): undefined tag.
    let mut b = bytes.clone();
    let end = find(b"$EndElements");
    let raw = read_msh(&{
        let p = dir.join("ok.msh");
        std::fs::write(&p, &bytes).unwrap();
        p
    })
    .unwrap();
    let n_tets = raw.volumes.values().map(Vec::len).sum::<usize>();
    assert!(n_tets > 0);
    // Last element of the file: [tag, n0, n1, n2, n3] as u64, just before "\n$EndElements".
    let last_node = end - 1 - 8;
    b[last_node..last_node + 8].copy_from_slice(&9_999_999u64.to_le_bytes());
    let err = read_bytes(&dir, "noderef.msh", &b).unwrap_err();
    assert!(
        matches!(err, MeshError::BadNodeRef { tag: 9_999_999, .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("noderef.msh"));
    // Not a mesh at all.
    let err = read_bytes(&dir, "text.msh", b"hello\n").unwrap_err();
    assert!(matches!(err, MeshError::MshCorrupt { .. }));
    let err = read_bytes(&dir, "v2.msh", b"$MeshFormat\n2.2 0 8\n$EndMeshFormat\n").unwrap_err();
    assert!(err.to_string().contains("2.2"), "{err}");
    // Damage every ~1/300 of the file in turn: whatever happens, no panic.
    for k in 0..300 {
        let mut b = bytes.clone();
        let at = b.len() * k / 300;
        b[at] ^= 0xA5;
        let p = dir.join("damaged.msh");
        std::fs::write(&p, &b).unwrap();
        if let Ok(raw) = read_msh(&p) {
            let _ = build_model(&raw, D, L_ADH);
        }
    }
}

/// A .msh without a required physical group names the file and the group (SPEC §4).
#[test]
fn missing_physical_group_is_named() {
    let dir = scratch("missing_group");
    let geo = std::fs::read_to_string(data("smooth.geo")).unwrap();
    let geo = geo.replace("Physical Surface(\"concrete_free_face\") = cf();", "");
    let path = dir.join("no_free_face.geo");
    std::fs::write(&path, geo).unwrap();
    let msh = mesh_file(&path, &small_spec(0.0016), &dir);
    let err = build_model(&read_msh(&msh).unwrap(), D, L_ADH).unwrap_err();
    assert!(matches!(err, MeshError::MissingGroup { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("concrete_free_face") && msg.contains("out.msh"),
        "{msg}"
    );
}

/// A failed re-run leaves the previous artifacts byte-identical and no
/// temporary file behind (SPEC §1, §8); a good run writes all four.
#[test]
fn failure_keeps_earlier_artifacts() {
    let dir = scratch("artifacts");
    let spec = small_spec(0.0016);
    let r = mesh_specimen(gmsh(), &data("smooth.geo"), &spec, D, L_ADH, &dir).unwrap();
    let names = [
        mesh::MSH_FILE,
        mesh::MODEL_FILE,
        mesh::VTU_FILE,
        mesh::REPORT_FILE,
    ];
    let before: Vec<Vec<u8>> = names
        .iter()
        .map(|n| std::fs::read(dir.join(n)).unwrap())
        .collect();
    let json: serde_json::Value = serde_json::from_slice(&before[3]).unwrap();
    for key in [
        "gmsh_version",
        "nodes",
        "tets_steel",
        "tets_concrete",
        "interface_elements_adhesive",
        "interface_elements_free",
        "duplicated_nodes",
        "min_quality",
        "mean_quality",
        "interface_area_adhesive_m2",
    ] {
        assert!(json.get(key).is_some(), "mesh.json lacks {key}");
    }
    for key in ["gmsh", "read", "build"] {
        assert!(json["timings_s"][key].as_f64().unwrap() >= 0.0);
    }
    assert_eq!(json["tets_steel"].as_u64().unwrap() as usize, r.tets_steel);
    let model = Model::load(&dir.join(mesh::MODEL_FILE)).unwrap();
    assert_eq!(model.tets.len(), r.tets_steel + r.tets_concrete);
    check_topology(&model);

    let broken = dir.join("broken.geo");
    std::fs::write(&broken, "Box(1) = {0, 0;\n").unwrap();
    assert!(mesh_specimen(gmsh(), &broken, &spec, D, L_ADH, &dir).is_err());
    let missing_group = dir.join("nogroup.geo");
    let geo = std::fs::read_to_string(data("smooth.geo"))
        .unwrap()
        .replace("Physical Volume(\"steel\") = steel();", "");
    std::fs::write(&missing_group, geo).unwrap();
    let err = mesh_specimen(gmsh(), &missing_group, &spec, D, L_ADH, &dir).unwrap_err();
    assert!(err.to_string().contains("\"steel\""), "{err}");
    for (n, b) in names.iter().zip(&before) {
        assert_eq!(
            &std::fs::read(dir.join(n)).unwrap(),
            b,
            "{n} changed by a failed run"
        );
    }
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
}

/// A damaged model file is rejected with an error naming it (SPEC §8).
#[test]
fn corrupt_model_file_is_an_error() {
    let dir = scratch("model_file");
    let msh = mesh_file(&data("smooth.geo"), &small_spec(0.0016), &dir);
    let (model, _) = build_model(&read_msh(&msh).unwrap(), D, L_ADH).unwrap();
    let p = dir.join("model.bin");
    model.save(&p).unwrap();
    assert_eq!(Model::load(&p).unwrap(), model);
    let bytes = std::fs::read(&p).unwrap();
    std::fs::write(&p, &bytes[..bytes.len() / 2]).unwrap();
    let err = Model::load(&p).unwrap_err();
    assert!(
        matches!(err, MeshError::ModelFile { .. }) && err.to_string().contains("model.bin"),
        "{err}"
    );
    std::fs::write(&p, b"something else").unwrap();
    assert!(Model::load(&p).is_err());
}
