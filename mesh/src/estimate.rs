//! How many tetrahedra gmsh will make of a specimen, estimated from the
//! size field alone before any work: a mesh far finer than meant (a µm for
//! mm slip in `mesh.h_interface` gives ~10^11 elements) is refused with its
//! estimate and the key that raises the limit, instead of gmsh running out
//! of memory after minutes.
//!
//! The estimate integrates the density of a mesh of local size h over the
//! meshed part, N ≈ C ∫ dV / h(x)³, with the size field the `.geo` sets
//! (`geom::geo`, SPEC §9): h_interface in the bar and at the interface,
//! growing linearly with the distance from the bar to h_outer at the cube's
//! side faces, with the lean bar core and unbonded parts where the spec
//! sets them. The field depends only on the distance r to the axis and on
//! z, so the cube's square section is integrated as ∫ f(r) ℓ(r) dr with
//! ℓ(r) the length of the circle of radius r inside the square. C is
//! measured on gmsh's meshes of the shipped scenes (docs:
//! validation/trusted-results.md gives each scene's estimate against its
//! real count).

use crate::spec::MeshSpec;
use crate::MeshError;
use geom::spec::{Bar, Specimen, Symmetry};

/// Tetrahedra per h³ of volume in gmsh's meshes of the shipped scenes
/// (HXT with optimisation; a regular tetrahedron of edge h would give
/// 6√2 ≈ 8.5): with it the real counts of the scenes at h_interface 0.4 mm
/// are 0.93–1.02 times the estimate, r1-coarse's (1 mm) 1.22 times, the
/// 2 mm test meshes', where the bar's surface holds most elements, 2.4–2.7
/// times.
pub const TETS_PER_H3: f64 = 4.2;

/// The size field of the `.geo` at distance `r` from the axis and height
/// `z`, m.
struct SizeField {
    h_in: f64,
    h_out: f64,
    k_grow: f64,
    r_out: f64,
    /// (h_bar_core − h_in, r_band) of a lean core.
    core: Option<(f64, f64)>,
    /// (h_unbonded − h_in, z from which it grows, the bearing face z = L).
    unbonded: Option<(f64, f64, f64)>,
}

impl SizeField {
    fn new(bar: &Bar, specimen: &Specimen, spec: &MeshSpec) -> SizeField {
        let l = specimen.cube_side;
        let r = bar.diameter / 2.0;
        let r_out = bar.outer_radius();
        let h_in = spec.h_interface;
        let core = spec
            .h_bar_core
            .filter(|&h| h > h_in)
            .map(|h| (h - h_in, r - (2.0 * (r_out - r)).max(2.0 * h_in)));
        let unbonded = spec.h_unbonded.filter(|&h| h > h_in).map(|h| {
            let band = (2.0 * r).max((2.0 * (r_out - r)).max(2.0 * h_in));
            (h - h_in, specimen.adhesive_length + band, l)
        });
        SizeField {
            h_in,
            h_out: spec.h_outer,
            k_grow: (spec.h_outer - h_in) / (l / 2.0 - r_out),
            r_out,
            core,
            unbonded,
        }
    }

    fn at(&self, r: f64, z: f64) -> f64 {
        let mut inc = self.k_grow * (r - self.r_out).max(0.0);
        if let Some((dh, r_band)) = self.core {
            inc = inc.max(dh.min(0.5 * (r_band - r).max(0.0)));
        }
        if let Some((dh, z0, z1)) = self.unbonded {
            inc = inc.max(dh.min(0.5 * (z - z0).min(z1 - z).max(0.0)));
        }
        self.h_out.min(self.h_in + inc)
    }
}

/// Length of the circle of radius `r` inside the square [−a, a]², m.
fn circle_in_square(r: f64, a: f64) -> f64 {
    if r <= a {
        2.0 * std::f64::consts::PI * r
    } else if r < a * std::f64::consts::SQRT_2 {
        r * (2.0 * std::f64::consts::PI - 8.0 * (a / r).acos())
    } else {
        0.0
    }
}

/// ∫ g(x) dx over [a, b] by the midpoint rule on `n` cells.
fn integrate(a: f64, b: f64, n: usize, g: impl Fn(f64) -> f64) -> f64 {
    let dx = (b - a) / n as f64;
    (0..n).map(|i| g(a + (i as f64 + 0.5) * dx)).sum::<f64>() * dx
}

/// The estimated number of tetrahedra of the meshed part (the whole
/// specimen for `mesh.unfold`).
pub fn estimated_tets(bar: &Bar, specimen: &Specimen, spec: &MeshSpec) -> f64 {
    let field = SizeField::new(bar, specimen, spec);
    let l = specimen.cube_side;
    let a = l / 2.0;
    let density = |r: f64, z: f64| TETS_PER_H3 / field.at(r, z).powi(3);
    // Cells of at most a tenth of the finest size along r, a quarter along
    // z: the field is piecewise linear, so this is exact to a few per cent.
    let nr =
        ((a * std::f64::consts::SQRT_2 / (0.1 * field.h_in)).ceil() as usize).clamp(200, 5_000);
    let nz = ((l / (0.25 * field.h_in)).ceil() as usize).clamp(50, 2_000);
    let cube = integrate(0.0, l, nz, |z| {
        integrate(0.0, a * std::f64::consts::SQRT_2, nr, |r| {
            density(r, z) * circle_in_square(r, a)
        })
    });
    let r = bar.diameter / 2.0;
    let overhangs = (specimen.free_overhang + specimen.loaded_overhang)
        * std::f64::consts::PI
        * r
        * r
        * TETS_PER_H3
        / field.h_in.powi(3);
    let share = match specimen.symmetry {
        _ if spec.unfold => 1.0,
        Symmetry::Full => 1.0,
        Symmetry::Half | Symmetry::HalfTurn => 0.5,
        Symmetry::Quarter => 0.25,
    };
    share * (cube + overhangs)
}

/// Refuses a mesh whose estimate is above `mesh.max_elements`, with the
/// estimate, the sizes that make it and the key that raises the limit.
pub fn check_size(bar: &Bar, specimen: &Specimen, spec: &MeshSpec) -> Result<f64, MeshError> {
    let estimate = estimated_tets(bar, specimen, spec);
    if estimate > spec.max_elements {
        return Err(MeshError::Spec {
            key: "max_elements".into(),
            message: format!(
                "the size field gives an estimated {estimate:.2e} tetrahedra \
                 (mesh.h_interface = {} mm, mesh.h_outer = {} mm), more than mesh.max_elements = \
                 {:.3e}; coarsen the mesh (was a size meant in mm rather than µm?), or raise \
                 mesh.max_elements if a mesh that large is meant",
                spec.h_interface * 1e3,
                spec.h_outer * 1e3,
                spec.max_elements
            ),
        });
    }
    Ok(estimate)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The circle's length inside the square goes from the whole circle
    /// to none at the corner; its integral is the square's area.
    #[test]
    fn the_circle_lengths_integrate_to_the_square() {
        let a = 0.012;
        assert_eq!(circle_in_square(0.5 * a, a), std::f64::consts::PI * a);
        assert_eq!(circle_in_square(1.5 * a, a), 0.0);
        let area = integrate(0.0, a * std::f64::consts::SQRT_2, 100_000, |r| {
            circle_in_square(r, a)
        });
        assert!((area / (4.0 * a * a) - 1.0).abs() < 1e-6, "{area}");
    }

    /// A uniform field gives C V / h³ exactly; halving h multiplies the
    /// estimate by eight.
    #[test]
    fn a_uniform_field_gives_the_volume_over_h_cubed() {
        let raw: geom::spec::RawBar =
            serde_yaml::from_str("{kind: smooth, diameter: 8 mm}").unwrap();
        let spec: geom::spec::RawSpecimen = serde_yaml::from_str(
            "{cube_side: 24 mm, adhesive_length: 12 mm, free_overhang: 0 mm, loaded_overhang: 0 mm, symmetry: full}",
        )
        .unwrap();
        let (bar, specimen) = geom::spec::resolve(&raw, &spec).unwrap();
        let mesh = |h: &str| {
            let raw: crate::spec::RawMeshSpec =
                serde_yaml::from_str(&format!("{{h_interface: {h}, h_outer: {h}}}")).unwrap();
            raw.resolve().unwrap()
        };
        let n = estimated_tets(&bar, &specimen, &mesh("2 mm"));
        let exact = TETS_PER_H3 * 0.024f64.powi(3) / 0.002f64.powi(3);
        assert!((n / exact - 1.0).abs() < 1e-3, "{n} vs {exact}");
        let fine = estimated_tets(&bar, &specimen, &mesh("1 mm"));
        assert!((fine / n - 8.0).abs() < 1e-2, "{fine} vs {n}");
    }
}
