//! Reading `.msh` 4.1: node tags, physical names, ASCII and binary (SPEC §4, §9).

use crate::common;
use common::*;
use mesh::read_msh;

/// Node tags in an order other than the file order (dense, so mshio drops
/// them) are mapped by tag, not by position (SPEC §9: "node order must be
/// checked against the tags gmsh wrote").
#[test]
fn permuted_dense_node_tags_map_by_tag() {
    let dir = scratch("permuted_tags");
    let text = "\
$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
3
2 3 \"interface_adhesive\"
3 1 \"steel\"
3 2 \"concrete\"
$EndPhysicalNames
$Entities
0 0 1 2
1 0 0 0 1 1 0 1 3 0
1 0 0 -1 1 1 0 1 1 0
2 0 0 0 1 1 1 1 2 0
$EndEntities
$Nodes
2 5 1 5
3 1 0 3
3
1
2
0 1 0
0 0 0
1 0 0
3 2 0 2
5
4
0 0 1
0 0 -1
$EndNodes
$Elements
3 3 1 3
2 1 2 1
1 1 2 3
3 1 4 1
2 1 2 3 4
3 2 4 1
3 1 2 3 5
$EndElements
";
    let p = dir.join("permuted.msh");
    std::fs::write(&p, text).unwrap();
    let raw = read_msh(&p).unwrap();
    let coord_of_tag = |t: u64| match t {
        1 => [0.0, 0.0, 0.0],
        2 => [1.0, 0.0, 0.0],
        3 => [0.0, 1.0, 0.0],
        4 => [0.0, 0.0, -1.0],
        5 => [0.0, 0.0, 1.0],
        _ => unreachable!(),
    };
    for (i, &tag) in raw.node_tags.iter().enumerate() {
        assert_eq!(raw.nodes[i], coord_of_tag(tag), "node tag {tag}");
    }
    let steel = &raw.volumes["steel"];
    assert_eq!(steel.len(), 1);
    let got: Vec<[f64; 3]> = steel[0].iter().map(|&i| raw.nodes[i as usize]).collect();
    assert_eq!(got, [1, 2, 3, 4].map(coord_of_tag).to_vec());
    let concrete = &raw.volumes["concrete"][0];
    assert_eq!(raw.nodes[concrete[3] as usize], coord_of_tag(5));
    assert_eq!(raw.surfaces["interface_adhesive"].len(), 1);
    // A missing node tag in an element is named.
    let bad = text.replace("3 1 2 3 5", "3 1 2 3 7");
    std::fs::write(&p, bad).unwrap();
    let err = read_msh(&p).unwrap_err();
    assert!(
        matches!(err, mesh::MeshError::BadNodeRef { tag: 7, .. }),
        "{err:?}"
    );
}

/// The ASCII and the binary .msh of one gmsh mesh read to the same mesh.
#[test]
fn ascii_and_binary_agree() {
    let dir = scratch("ascii_binary");
    let geo = data("smooth.geo");
    let bin = dir.join("bin.msh");
    let asc = dir.join("ascii.msh");
    let spec = small_spec(0.0016);
    mesh::run_gmsh(gmsh(), &geo, &spec, &bin).unwrap();
    // Same options without -bin.
    let args: Vec<String> = mesh::gmsh_args(&std::path::absolute(&geo).unwrap(), &spec, &asc)
        .into_iter()
        .filter(|a| a != "-bin")
        .collect();
    gmsh()
        .run(&args, Some(&dir), std::time::Duration::from_secs(60))
        .unwrap();
    let mut a = read_msh(&asc).unwrap();
    let b = read_msh(&bin).unwrap();
    a.source = b.source.clone();
    assert_eq!(a.node_tags, b.node_tags);
    assert_eq!(a.volumes, b.volumes);
    assert_eq!(a.surfaces, b.surfaces);
    for (x, y) in a.nodes.iter().zip(&b.nodes) {
        for k in 0..3 {
            assert!((x[k] - y[k]).abs() <= 1e-15 + 1e-12 * y[k].abs());
        }
    }
    assert_eq!(a.volumes.len(), 2);
    assert_eq!(a.surfaces.len(), 6);
}

/// Damaged ASCII .msh files (bytes overwritten, cut short) give errors or a
/// checked mesh, never a panic (SPEC §8).
#[test]
fn damaged_ascii_msh_never_panics() {
    let dir = scratch("ascii_damage");
    let geo = data("smooth.geo");
    let asc = dir.join("ascii.msh");
    let args: Vec<String> = mesh::gmsh_args(
        &std::path::absolute(&geo).unwrap(),
        &small_spec(0.0016),
        &asc,
    )
    .into_iter()
    .filter(|a| a != "-bin")
    .collect();
    gmsh()
        .run(&args, Some(&dir), std::time::Duration::from_secs(60))
        .unwrap();
    let bytes = std::fs::read(&asc).unwrap();
    let mut errors = 0;
    for k in 0..200usize {
        let mut b = bytes.clone();
        let at = b.len() * k / 200;
        b[at] = b"9-x $\n."[k % 7];
        if k % 3 == 0 {
            b.truncate(b.len() - k * 7);
        }
        match mesh::read::parse_msh(&b, &asc) {
            Ok(raw) => {
                let _ = mesh::build_model(&raw, D, L_ADH);
            }
            Err(e) => {
                assert!(e.to_string().contains("ascii.msh"), "{e}");
                errors += 1;
            }
        }
    }
    assert!(errors > 50, "{errors}");
}
