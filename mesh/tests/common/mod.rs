//! Shared helpers of the mesh tests: meshing the test geometries once per
//! test binary with the real gmsh, and topology checks on a built model.
#![allow(dead_code)]

use mesh::{Gmsh, InterfaceZone, MeshSpec, Model, Region};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Test specimens (see the `.geo` files): d = 8 mm, L = 16 mm, l_adh = 8 mm.
pub const D: f64 = 0.008;
pub const L: f64 = 0.016;
pub const L_ADH: f64 = 0.008;
/// Ring ribs: height and axial width, m.
pub const RIB_A: f64 = 0.0008;
pub const RIB_B: f64 = 0.0012;

pub fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// A fresh scratch directory under cargo's test tmp dir.
pub fn scratch(name: &str) -> PathBuf {
    let base = option_env!("CARGO_TARGET_TMPDIR")
        .map(PathBuf::from)
        .unwrap_or_else(std::env::temp_dir);
    let dir = base.join("mesh-tests").join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The gmsh of the test machine (set up by `scripts/setup.sh`), located once.
pub fn gmsh() -> &'static Gmsh {
    static G: std::sync::OnceLock<Gmsh> = std::sync::OnceLock::new();
    G.get_or_init(|| Gmsh::locate().expect("the mesh tests need gmsh (scripts/setup.sh)"))
}

/// Small sizes: each mesh takes well under a second.
pub fn small_spec(h_interface: f64) -> MeshSpec {
    MeshSpec {
        h_interface,
        h_outer: 0.004,
        algorithm_3d: mesh::spec::Algorithm3d::Delaunay,
        timeout: 60.0,
        ..MeshSpec::default()
    }
}

/// Meshes `geo` into `dir/out.msh` and returns the path.
pub fn mesh_file(geo: &Path, spec: &MeshSpec, dir: &Path) -> PathBuf {
    let out = dir.join("out.msh");
    mesh::run_gmsh(gmsh(), geo, spec, &out).unwrap();
    out
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn sorted(mut k: [u32; 3]) -> [u32; 3] {
    k.sort_unstable();
    k
}

/// Every topological requirement of SPEC §4 / §9 on a built model; panics
/// with the violated requirement.
pub fn check_topology(m: &Model) {
    m.check().unwrap();
    // Tets: positive volume, and only nodes of their own side.
    let mut node_tet_region: Vec<Option<Region>> = vec![None; m.nodes.len()];
    for (k, t) in m.tets.iter().enumerate() {
        let p = t.map(|i| m.nodes[i as usize]);
        let v = dot(cross(sub(p[1], p[0]), sub(p[2], p[0])), sub(p[3], p[0]));
        assert!(v > 0.0, "tet {k} is not positively oriented");
        for &i in t {
            assert_eq!(
                m.node_region[i as usize], m.tet_region[k],
                "tet {k} references a node of the other side"
            );
            match node_tet_region[i as usize] {
                None => node_tet_region[i as usize] = Some(m.tet_region[k]),
                Some(r) => assert_eq!(
                    r, m.tet_region[k],
                    "node {i} is shared by steel and concrete tets"
                ),
            }
        }
    }
    // Faces → (tet, opposite node).
    let mut faces: HashMap<[u32; 3], Vec<(usize, u32)>> = HashMap::new();
    for (k, t) in m.tets.iter().enumerate() {
        for f in [[1, 2, 3, 0], [0, 2, 3, 1], [0, 1, 3, 2], [0, 1, 2, 3]] {
            faces
                .entry(sorted([t[f[0]], t[f[1]], t[f[2]]]))
                .or_default()
                .push((k, t[f[3]]));
        }
    }
    let mut twin_of: HashMap<u32, u32> = HashMap::new();
    for (e, el) in m.interfaces.iter().enumerate() {
        let s = [el.nodes[0], el.nodes[1], el.nodes[2]];
        let c = [el.nodes[3], el.nodes[4], el.nodes[5]];
        for i in 0..3 {
            assert_eq!(
                m.node_region[s[i] as usize],
                Region::Steel,
                "element {e}: s{i} not steel"
            );
            assert_eq!(
                m.node_region[c[i] as usize],
                Region::Concrete,
                "element {e}: c{i} not concrete"
            );
            assert_eq!(
                m.nodes[s[i] as usize], m.nodes[c[i] as usize],
                "element {e}: triangles do not coincide"
            );
            // One twin per steel node, whatever element (adhesive or free) refers to it.
            let prev = *twin_of.entry(s[i]).or_insert(c[i]);
            assert_eq!(prev, c[i], "steel node {} has two concrete twins", s[i]);
        }
        let f = el.frame;
        let n = f.n;
        for (a, b, want) in [
            (n, n, 1.0),
            (f.t, f.t, 1.0),
            (f.h, f.h, 1.0),
            (n, f.t, 0.0),
            (n, f.h, 0.0),
            (f.t, f.h, 0.0),
        ] {
            assert!(
                (dot(a, b) - want).abs() < 1e-9,
                "element {e}: frame not orthonormal"
            );
        }
        let nh = cross(n, f.t);
        assert!(dot(nh, f.h) > 1.0 - 1e-9, "element {e}: h ≠ n × t");
        let p = s.map(|i| m.nodes[i as usize]);
        let rn = cross(sub(p[1], p[0]), sub(p[2], p[0]));
        assert!(
            (0.5 * dot(rn, rn).sqrt() - el.area).abs() <= 1e-9 * el.area,
            "element {e}: area"
        );
        // The steel triangle's right-hand normal is n; seen from its concrete tet the
        // same face is traversed the other way (outward normal −n).
        assert!(
            dot(rn, n) > 0.0,
            "element {e}: steel triangle not oriented along n"
        );
        let st = &faces[&sorted(s)];
        let ct = &faces[&sorted(c)];
        assert_eq!(
            st.len(),
            1,
            "element {e}: steel face not a boundary face of one steel tet"
        );
        assert_eq!(
            ct.len(),
            1,
            "element {e}: concrete face not a boundary face of one concrete tet"
        );
        let (ks, qs) = st[0];
        let (kc, qc) = ct[0];
        assert_eq!(m.tet_region[ks], Region::Steel);
        assert_eq!(m.tet_region[kc], Region::Concrete);
        assert!(
            dot(sub(m.nodes[qs as usize], p[0]), n) < 0.0,
            "element {e}: steel tet on the +n side"
        );
        assert!(
            dot(sub(m.nodes[qc as usize], p[0]), n) > 0.0,
            "element {e}: n does not point into concrete"
        );
        let centroid = |k: usize| {
            let t = m.tets[k];
            let mut c = [0.0; 3];
            for &i in &t {
                for (cd, x) in c.iter_mut().zip(m.nodes[i as usize]) {
                    *cd += x / 4.0;
                }
            }
            c
        };
        assert!(
            dot(sub(centroid(kc), centroid(ks)), n) > 0.0,
            "element {e}: n not from steel to concrete"
        );
        assert!(
            f.t[2] >= -1e-12,
            "element {e}: t points against the bar axis"
        );
    }
    // Every concrete node at the position of a steel node is that node's twin:
    // no concrete tet is left attached to a steel interface node anywhere,
    // including the circles z = 0, L and the curve z = l_adh.
    let duplicated = m
        .node_region
        .iter()
        .filter(|r| **r == Region::Concrete)
        .count()
        - m.tets
            .iter()
            .zip(&m.tet_region)
            .filter(|(_, r)| **r == Region::Concrete)
            .flat_map(|(t, _)| t.iter().copied())
            .filter(|i| !twin_of.values().any(|c| c == i))
            .collect::<std::collections::HashSet<_>>()
            .len();
    assert_eq!(
        duplicated,
        twin_of.len(),
        "a concrete node duplicates nothing or a twin is unused"
    );
    let mut by_pos: HashMap<[u64; 3], Vec<u32>> = HashMap::new();
    for (i, p) in m.nodes.iter().enumerate() {
        by_pos
            .entry(p.map(f64::to_bits))
            .or_default()
            .push(i as u32);
    }
    for (_, ids) in by_pos {
        if ids.len() > 1 {
            assert_eq!(ids.len(), 2, "more than two nodes at one position");
            let (a, b) = (ids[0], ids[1]);
            let (s, c) = if m.node_region[a as usize] == Region::Steel {
                (a, b)
            } else {
                (b, a)
            };
            assert_eq!(m.node_region[s as usize], Region::Steel);
            assert_eq!(m.node_region[c as usize], Region::Concrete);
            assert_eq!(
                twin_of.get(&s),
                Some(&c),
                "coincident nodes not joined by an interface element"
            );
        }
    }
    // Node sets: on their side.
    for &i in m
        .node_sets
        .bar_loaded_end
        .iter()
        .chain(&m.node_sets.bar_free_end)
    {
        assert_eq!(m.node_region[i as usize], Region::Steel);
    }
    for &i in m
        .node_sets
        .concrete_bearing_face
        .iter()
        .chain(&m.node_sets.concrete_free_face)
    {
        assert_eq!(m.node_region[i as usize], Region::Concrete);
    }
}

/// Sum of interface element areas of a zone, m².
pub fn zone_area(m: &Model, zone: InterfaceZone) -> f64 {
    m.interfaces
        .iter()
        .filter(|e| e.zone == zone)
        .map(|e| e.area)
        .sum()
}

/// A smooth bar of diameter `d` (m) in a 40 mm cube bonded over
/// `l_adh` (m), built and meshed with real gmsh once per spec of `specs`
/// (at h_interface 1 mm and h_outer 6 mm, each spec's lean-mesh options
/// set): each mesh's report and topology-checked model.
pub fn smooth_meshes(
    name: &str,
    d: f64,
    l_adh: f64,
    specs: &[MeshSpec],
) -> Vec<(mesh::MeshReport, Model)> {
    let bar: geom::spec::RawBar =
        serde_yaml::from_str(&format!("{{kind: smooth, diameter: {} mm}}", d * 1e3)).unwrap();
    let specimen: geom::spec::RawSpecimen = serde_yaml::from_str(&format!(
        "{{cube_side: 40 mm, adhesive_length: {} mm, free_overhang: 2 mm, loaded_overhang: 4 mm}}",
        l_adh * 1e3
    ))
    .unwrap();
    let (bar, specimen) = geom::spec::resolve(&bar, &specimen).unwrap();
    specs
        .iter()
        .enumerate()
        .map(|(i, lean)| {
            let dir = scratch(&format!("{name}-{i}"));
            geom::build_geometry(&bar, &specimen, &dir).unwrap();
            let spec = MeshSpec {
                h_interface: 1e-3,
                h_outer: 6e-3,
                ..lean.clone()
            };
            let report =
                mesh::mesh_specimen(gmsh(), &dir.join("specimen.geo"), &spec, d, l_adh, &dir)
                    .unwrap();
            let model = Model::load(&dir.join(mesh::MODEL_FILE)).unwrap();
            check_topology(&model);
            (report, model)
        })
        .collect()
}

/// |a − b| / b.
pub fn relative_difference(a: f64, b: f64) -> f64 {
    (a - b).abs() / b
}

/// A lean mesh (coarser somewhere away from the bond) keeps the bonded
/// interface: its area to 1e-3 of the uniform mesh's.
pub fn assert_bonded_interface_kept(uniform: &mesh::MeshReport, lean: &mesh::MeshReport) {
    let (a, b) = (
        lean.interface_area_adhesive_m2,
        uniform.interface_area_adhesive_m2,
    );
    assert!(
        relative_difference(a, b) < 1e-3,
        "bonded interface area {b} → {a} m²"
    );
}
