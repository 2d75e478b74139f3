//! Topology of the model built from real gmsh meshes (SPEC §4, §9).

use crate::common;
use common::*;
use mesh::{build_model, read_msh, InterfaceZone, Model, Region};
use std::f64::consts::PI;

fn build(geo: &str, h: f64, dir: &str) -> (Model, mesh::MeshReport) {
    let dir = scratch(dir);
    let msh = mesh_file(&data(geo), &small_spec(h), &dir);
    let raw = read_msh(&msh).unwrap();
    build_model(&raw, D, L_ADH).unwrap()
}

/// Smooth bar: every tet on its own side, interface elements coincident,
/// oppositely oriented, n into concrete, one twin per node (SPEC §4, §9).
#[test]
fn smooth_bar_topology() {
    let (m, r) = build("smooth.geo", 0.0008, "smooth_topology");
    check_topology(&m);
    assert!(r.tets_steel > 1000 && r.tets_concrete > 1000, "{r:?}");
    assert!(r.interface_elements_adhesive > 100 && r.interface_elements_free > 100);
    assert_eq!(r.nodes, m.nodes.len());
    // Twins on the circles z = 0 and z = L: concrete face sets there use them.
    let on_circle = |z: f64| {
        m.node_sets
            .concrete_free_face
            .iter()
            .chain(&m.node_sets.concrete_bearing_face)
            .filter(|&&i| {
                let p = m.nodes[i as usize];
                (p[2] - z).abs() < 1e-9 && ((p[0].hypot(p[1])) - D / 2.0).abs() < 1e-7
            })
            .count()
    };
    assert!(on_circle(0.0) > 10 && on_circle(L) > 10);
    // Adhesive and free elements meet on z = l_adh and share the twins there.
    let at_ladh = |zone: InterfaceZone| -> std::collections::BTreeSet<u32> {
        m.interfaces
            .iter()
            .filter(|e| e.zone == zone)
            .flat_map(|e| e.nodes[3..].to_vec())
            .filter(|&i| (m.nodes[i as usize][2] - L_ADH).abs() < 1e-9)
            .collect()
    };
    let a = at_ladh(InterfaceZone::Adhesive);
    assert!(a.len() > 10);
    assert_eq!(a, at_ladh(InterfaceZone::Free));
    // Adhesive elements lie in z ∈ [0, l_adh], free ones in [l_adh, L].
    for e in &m.interfaces {
        let z: Vec<f64> = e.nodes[..3]
            .iter()
            .map(|&i| m.nodes[i as usize][2])
            .collect();
        let (lo, hi) = match e.zone {
            InterfaceZone::Adhesive => (0.0, L_ADH),
            InterfaceZone::Free => (L_ADH, L),
        };
        assert!(z.iter().all(|&z| z >= lo - 1e-9 && z <= hi + 1e-9));
        // On a cylinder n is nearly radial (a flat facet tilts by O(h/d)) and t nearly axial.
        assert!(
            e.frame.t[2] > 0.99 && e.frame.n[2].abs() < 0.1,
            "{:?}",
            e.frame
        );
    }
    // Bar end sets sit on their planes.
    for &i in &m.node_sets.bar_loaded_end {
        assert!((m.nodes[i as usize][2] - (L + 0.003)).abs() < 1e-9);
    }
    for &i in &m.node_sets.bar_free_end {
        assert!((m.nodes[i as usize][2] + 0.002).abs() < 1e-9);
    }
}

/// The mesh's interface areas equal the analytic π d l_adh and π d (L − l_adh)
/// within 1 % at h_interface = 0.4 mm (SPEC §4, issue 3).
#[test]
fn smooth_interface_area_matches_analytic() {
    let (m, r) = build("smooth.geo", 0.0004, "smooth_area");
    let exact = PI * D * L_ADH;
    let rel = (r.interface_area_adhesive_m2 - exact).abs() / exact;
    assert!(
        rel < 0.01,
        "adhesive area {} vs {exact}: {rel}",
        r.interface_area_adhesive_m2
    );
    let free = zone_area(&m, InterfaceZone::Free);
    let exact_free = PI * D * (L - L_ADH);
    assert!((free - exact_free).abs() / exact_free < 0.01);
    // Volumes: steel bar, concrete cube minus the embedded bar (within mesh error).
    let v_bar = PI * D * D / 4.0 * (L + 0.005);
    assert!((r.volume_steel_m3 - v_bar).abs() / v_bar < 0.01);
    let v_con = L * L * L - PI * D * D / 4.0 * L;
    assert!((r.volume_concrete_m3 - v_con).abs() / v_con < 0.01);
    assert!(
        r.min_quality > 0.05 && r.mean_quality > 0.5 && r.mean_quality <= 1.0,
        "{r:?}"
    );
}

/// Ring ribs (flanks normal to the axis, rib corners on the interface): the
/// same topology requirements hold and the rib's area is in the interface
/// (SPEC §4, §9: duplication must not leave nodes shared at rib corners).
#[test]
fn ring_rib_topology_and_area() {
    let (m, r) = build("ring_rib.geo", 0.0004, "ring_rib");
    check_topology(&m);
    let (rc, rr) = (D / 2.0, D / 2.0 + RIB_A);
    let flanks = 2.0 * PI * (rr * rr - rc * rc);
    let exact = 2.0 * PI * rc * (L_ADH - RIB_B) + 2.0 * PI * rr * RIB_B + flanks;
    let rel = (r.interface_area_adhesive_m2 - exact).abs() / exact;
    assert!(
        rel < 0.01,
        "adhesive area {} vs {exact}: {rel}",
        r.interface_area_adhesive_m2
    );
    // Flank elements (n ∥ z) get a radial t.
    let flank: Vec<_> = m
        .interfaces
        .iter()
        .filter(|e| e.frame.n[2].abs() > 0.999)
        .collect();
    assert!(!flank.is_empty());
    for e in flank {
        let c = m.nodes[e.nodes[0] as usize];
        let radial = (e.frame.t[0] * c[0] + e.frame.t[1] * c[1]) / c[0].hypot(c[1]);
        assert!(radial > 0.9, "flank t not radial: {:?}", e.frame);
    }
    assert!(
        m.node_region
            .iter()
            .filter(|r| **r == Region::Concrete)
            .count()
            > r.duplicated_nodes
    );
}
