//! The lean bar core (`mesh.h_bar_core`, issue 14): the bar's interior
//! coarsens toward the axis while a band under its surface, and so the
//! interface, keeps h_interface.

use crate::common;
use common::*;
use mesh::{MeshSpec, Model, Region};

/// d = 16 mm smooth bar in a 40 mm cube at h_interface = 1 mm: a 4 mm core
/// takes out over 30 % of the steel tets; the interface (element count and area), the
/// steel volume and the concrete mesh stay; tets in the 2 mm band under
/// the surface keep the interface's size, the core's grow toward the axis.
#[test]
fn bar_core_coarsens_the_interior_only() {
    let d = 0.016;
    let meshes = smooth_meshes(
        "bar-core",
        d,
        0.02,
        &[
            MeshSpec::default(),
            MeshSpec {
                h_bar_core: Some(4e-3),
                ..MeshSpec::default()
            },
        ],
    );
    let (uniform, lean) = (&meshes[0], &meshes[1]);
    let steel = |m: &Model| m.tet_region.iter().filter(|r| **r == Region::Steel).count();
    assert!(
        (steel(&lean.1) as f64) < 0.7 * steel(&uniform.1) as f64,
        "steel tets {} → {}",
        steel(&uniform.1),
        steel(&lean.1)
    );
    assert_bonded_interface_kept(&uniform.0, &lean.0);
    let rel = relative_difference;
    assert!(rel(lean.0.volume_steel_m3, uniform.0.volume_steel_m3) < 1e-3);
    let interfaces = |m: &Model| m.interfaces.len() as f64;
    assert!(rel(interfaces(&lean.1), interfaces(&uniform.1)) < 0.05);
    // Sizes by depth below the surface.
    let radius = |m: &Model, t: &[u32; 4]| {
        t.iter()
            .map(|&n| m.nodes[n as usize][0].hypot(m.nodes[n as usize][1]))
            .fold(f64::INFINITY, f64::min)
    };
    let r_bar = d / 2.0;
    let sizes = |m: &Model| {
        let (mut band_max, mut core_max) = (0.0f64, 0.0f64);
        for (i, t) in m.tets.iter().enumerate() {
            if m.tet_region[i] != Region::Steel {
                continue;
            }
            let r = radius(m, t);
            if r > r_bar - 1.5e-3 {
                band_max = band_max.max(m.tet_size[i]);
            } else if r < 1e-3 {
                core_max = core_max.max(m.tet_size[i]);
            }
        }
        (band_max, core_max)
    };
    let (band_uniform, core_uniform) = sizes(&uniform.1);
    let (band_lean, core_lean) = sizes(&lean.1);
    assert!(
        band_lean < 1.15 * band_uniform,
        "largest tet in the band {band_uniform} → {band_lean}"
    );
    assert!(
        core_lean > 2.0 * core_uniform,
        "largest tet at the axis {core_uniform} → {core_lean}"
    );
}
