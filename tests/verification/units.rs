use geom::units::{Dim, RawQuantity};

/// SPEC §2: a spec quantity written with a unit resolves to SI base units.
#[test]
fn scene_quantities_resolve_to_si() {
    let q: RawQuantity = serde_yaml::from_str("\"0.4 mm\"").unwrap();
    assert!((q.to_si(Dim::Length, "mesh.h_interface").unwrap() - 4e-4).abs() < 1e-18);
}
