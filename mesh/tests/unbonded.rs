//! Lean unbonded parts (`mesh.h_unbonded`, issue 14): between a band past
//! the bonded zone and the bearing face the mesh coarsens along the bar,
//! while the bonded zone, and so its interface, keeps h_interface.

use crate::common;
use common::*;
use mesh::{MeshSpec, Model, Region};

/// d = 8 mm smooth bar in a 40 mm cube bonded over z in [0, 10 mm] at
/// h_interface = 1 mm: a 4 mm unbonded size takes out over a quarter of
/// the tets; the bonded interface (area, element count), the specimen's
/// volume and the sizes in the bonded zone and its band (one diameter)
/// stay; the tets around the bar between the band and the bearing face
/// grow. (The coarse bar's
/// polygonal section gives some of its volume to the concrete.)
#[test]
fn unbonded_size_coarsens_past_the_bonded_zone_only() {
    let d = 0.008;
    let l_adh = 0.01;
    let meshes = smooth_meshes(
        "unbonded",
        d,
        l_adh,
        &[
            MeshSpec::default(),
            MeshSpec {
                h_unbonded: Some(4e-3),
                ..MeshSpec::default()
            },
        ],
    );
    let (uniform, lean) = (&meshes[0], &meshes[1]);
    let tets = |m: &Model| m.tets.len() as f64;
    assert!(
        tets(&lean.1) < 0.75 * tets(&uniform.1),
        "tets {} → {}",
        tets(&uniform.1),
        tets(&lean.1)
    );
    assert_bonded_interface_kept(&uniform.0, &lean.0);
    let rel = relative_difference;
    let volume = |r: &mesh::MeshReport| r.volume_steel_m3 + r.volume_concrete_m3;
    assert!(rel(volume(&lean.0), volume(&uniform.0)) < 1e-3);
    let adhesive = |r: &mesh::MeshReport| r.interface_elements_adhesive as f64;
    assert!(rel(adhesive(&lean.0), adhesive(&uniform.0)) < 0.05);
    // The largest tet whose centroid lies within 1 mm of the bar's
    // surface, in the bonded zone and its band, and past the band (8 mm)
    // by over 8 mm.
    let sizes = |m: &Model| {
        let (mut bonded_max, mut unbonded_max) = (0.0f64, 0.0f64);
        for (i, t) in m.tets.iter().enumerate() {
            let at = |n: u32| m.nodes[n as usize];
            let c = t
                .iter()
                .fold([0.0; 3], |c, &n| [0, 1, 2].map(|k| c[k] + 0.25 * at(n)[k]));
            if (c[0].hypot(c[1]) - d / 2.0).abs() > 1e-3 {
                continue;
            }
            if t.iter().all(|&n| (0.0..=l_adh + d).contains(&at(n)[2])) {
                bonded_max = bonded_max.max(m.tet_size[i]);
            } else if c[2] > l_adh + d + 8e-3 {
                unbonded_max = unbonded_max.max(m.tet_size[i]);
            }
        }
        assert!(m.tet_region.contains(&Region::Steel));
        (bonded_max, unbonded_max)
    };
    let (bonded_uniform, unbonded_uniform) = sizes(&uniform.1);
    let (bonded_lean, unbonded_lean) = sizes(&lean.1);
    assert!(
        bonded_lean < 1.15 * bonded_uniform,
        "largest tet in the bonded zone and band {bonded_uniform} → {bonded_lean}"
    );
    assert!(
        unbonded_lean > 1.5 * unbonded_uniform,
        "largest tet past the band {unbonded_uniform} → {unbonded_lean}"
    );
}
