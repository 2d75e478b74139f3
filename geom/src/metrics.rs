//! Rib metrics: relative rib area f_R, rib and bar volumes, bonded surface
//! areas, computed two ways:
//!
//! * **analytic**: exact integrals over the radial graph ρ(θ, z) of
//!   [`crate::layout`]. At fixed θ the profile along z is piecewise linear
//!   (core, longitudinal rib, trapezoid ribs), so the z-integrals are done in
//!   closed form; the θ-integral uses composite Gauss–Legendre quadrature with
//!   panel ends at every kink of the longitudinal rib profile.
//!   Surface element of the radial graph: dA = √(ρ²(1 + ρ_z²) + ρ_θ²) dθ dz;
//!   on a transverse rib flank, parametrised by its height h,
//!   dA = √((R + h)²(1 + m²) + K² sin²θ) dθ dh with m = |dz/dh| and
//!   K = R cot β, whose h-integral is closed form.
//! * **parry3d**: a triangle mesh of the same bar (columns in θ, rows that
//!   follow the rib edges), clipped exactly at the bar ends and cut planes,
//!   closed by end caps; volume from `MassProperties::from_trimesh`, areas as
//!   sums of `Triangle::area`.
//!
//! Relative rib area (EN 10080, ISO 15630-1): f_R = (1 / (π d)) Σ_i F_R,i sin β_i / c_i,
//! the sum running over the rib rows around the circumference; F_R sin β is
//! the area of the rib's projection on the cross-section plane. We evaluate
//! that projection exactly: for one rib of one side it is
//! ∫ ((R + a)² − max(R, ρ_l(θ))²)₊ / 2 dθ, i.e. the annular sector the rib
//! covers minus the part hidden inside the longitudinal ribs, so
//! f_R = (A_A + A_B) / (π d c).

use crate::layout::{Layout, RibLayout};
use parry3d_f64::mass_properties::MassProperties;
use parry3d_f64::math::Point;
use parry3d_f64::shape::Triangle;
use serde::Serialize;
use std::f64::consts::PI;

/// The metrics of one bar in one specimen (SI).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Metrics {
    /// Relative rib area f_R (0 for a smooth bar).
    pub f_r: f64,
    /// Volume of the bar minus its core cylinder, m³.
    pub rib_volume_m3: f64,
    /// Volume of the whole bar z ∈ [−e_free, L + e_load], m³.
    pub bar_volume_m3: f64,
    /// Steel surface area in z ∈ [0, l_adh], m².
    pub interface_area_adhesive_m2: f64,
    /// Steel surface area in z ∈ [l_adh, L], m².
    pub interface_area_free_m2: f64,
    /// Number of transverse ribs in the model (both sides).
    pub rib_count: usize,
}

/// Panel width of the θ quadrature, rad.
const PANEL: f64 = 0.004;
/// Gauss–Legendre nodes and weights on [−1, 1].
const GL4: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_9),
];

/// ∫ over h of √((R + h)² A + B) dh, as a function of u = R + h.
fn flank_primitive(u: f64, a: f64, b: f64) -> f64 {
    let sa = a.sqrt();
    let root = (a * u * u + b).sqrt();
    if b <= 0.0 {
        return sa * u * u / 2.0;
    }
    u / 2.0 * root + b / (2.0 * sa) * (sa * u + root).ln()
}

/// (∫ρ² dz, ∫ dA/dθ dz) over z ∈ [z1, z2] at local angle t of `side`.
fn column_integrals(r: f64, rl: &RibLayout, side: usize, t: f64, z1: f64, z2: f64) -> (f64, f64) {
    let (rho_f, drho_f) = rl.floor(r, t);
    let dens_f = (rho_f * rho_f + drho_f * drho_f).sqrt();
    let len = z2 - z1;
    let mut vol2 = rho_f * rho_f * len;
    let mut area = dens_f * len;
    if t < rl.t_s || t > PI - rl.t_s || r + rl.a <= rho_f {
        return (vol2, area);
    }
    let h_f = rho_f - r;
    let half_run = (rl.wb - rl.wt) / 2.0;
    let m = half_run / rl.a;
    let sin_t = t.sin();
    let big_a = 1.0 + m * m;
    let big_b = (rl.k * sin_t).powi(2);
    let shift = rl.sides[side].sign * rl.k * t.cos();
    // One flank: z-range [zs, ze] where h rises from 0 to a (or falls, mirrored).
    let flank = |zs: f64, ze: f64, rising: bool| -> (f64, f64) {
        let (lo, hi) = (zs.max(z1), ze.min(z2));
        let (mut h1, mut h2);
        if half_run > 0.0 {
            if hi <= lo {
                return (0.0, 0.0);
            }
            let h = |z: f64| {
                let f = (z - zs) / half_run;
                rl.a * if rising { f } else { 1.0 - f }
            };
            h1 = h(lo);
            h2 = h(hi);
            if h1 > h2 {
                std::mem::swap(&mut h1, &mut h2);
            }
        } else {
            // Vertical flank: counted in the slab holding its z.
            if !(zs >= z1 && zs < z2) {
                return (0.0, 0.0);
            }
            h1 = 0.0;
            h2 = rl.a;
        }
        let (v1, v2) = (h1.max(h_f), h2.max(h_f));
        if v2 <= v1 {
            return (0.0, 0.0);
        }
        let dz = (v2 - v1) * m;
        (
            m * ((r + v2).powi(3) - (r + v1).powi(3)) / 3.0 - rho_f * rho_f * dz,
            flank_primitive(r + v2, big_a, big_b)
                - flank_primitive(r + v1, big_a, big_b)
                - dens_f * dz,
        )
    };
    for &zeta in &rl.sides[side].zeta {
        let zc = zeta + shift;
        if zc + rl.wb / 2.0 < z1 || zc - rl.wb / 2.0 > z2 {
            continue;
        }
        for (dv, da) in [
            flank(zc - rl.wb / 2.0, zc - rl.wt / 2.0, true),
            flank(zc + rl.wt / 2.0, zc + rl.wb / 2.0, false),
        ] {
            vol2 += dv;
            area += da;
        }
        let top = (zc + rl.wt / 2.0).min(z2) - (zc - rl.wt / 2.0).max(z1);
        if top > 0.0 {
            let rt = r + rl.a;
            area += (rt - dens_f) * top;
            vol2 += (rt * rt - rho_f * rho_f) * top;
        }
    }
    (vol2, area)
}

/// Quadrature nodes (t, weight) on [0, π] with panel ends at the kinks.
fn theta_nodes(rl: &RibLayout) -> Vec<(f64, f64)> {
    let mut breaks = vec![0.0, PI];
    for phi in [rl.phi_top, rl.phi_base, rl.phi_a, rl.t_s] {
        breaks.push(phi);
        breaks.push(PI - phi);
    }
    breaks.sort_by(f64::total_cmp);
    breaks.dedup_by(|a, b| (*a - *b).abs() < 1e-14);
    let mut nodes = vec![];
    for w in breaks.windows(2) {
        let (a, b) = (w[0], w[1]);
        let n = ((b - a) / PANEL).ceil().max(1.0) as usize;
        let h = (b - a) / n as f64;
        for i in 0..n {
            let mid = a + (i as f64 + 0.5) * h;
            for (x, wt) in GL4 {
                nodes.push((mid + x * h / 2.0, wt * h / 2.0));
            }
        }
    }
    nodes
}

/// (volume, lateral area) of the bar within z ∈ [z1, z2], analytic.
pub fn slab_analytic(layout: &Layout, z1: f64, z2: f64) -> (f64, f64) {
    let r = layout.r;
    if z2 <= z1 {
        return (0.0, 0.0);
    }
    match &layout.ribs {
        None => (PI * r * r * (z2 - z1), 2.0 * PI * r * (z2 - z1)),
        Some(rl) => {
            let (mut vol, mut area) = (0.0, 0.0);
            for (t, w) in theta_nodes(rl) {
                for side in 0..2 {
                    let (v2, a) = column_integrals(r, rl, side, t, z1, z2);
                    vol += w * v2 / 2.0;
                    area += w * a;
                }
            }
            (vol, area)
        }
    }
}

/// Relative rib area f_R (module doc); 0 for a smooth bar.
pub fn relative_rib_area(layout: &Layout) -> f64 {
    let Some(rl) = &layout.ribs else { return 0.0 };
    let r = layout.r;
    let rt = r + rl.a;
    let per_side: f64 = theta_nodes(rl)
        .into_iter()
        .filter(|(t, _)| *t >= rl.t_s && *t <= PI - rl.t_s)
        .map(|(t, w)| {
            let f = rl.floor(r, t).0;
            w * ((rt * rt - f * f).max(0.0)) / 2.0
        })
        .sum();
    2.0 * per_side / (PI * 2.0 * r * rl.c)
}

/// Analytic metrics of the bar in its specimen.
pub fn analytic(layout: &Layout) -> Metrics {
    let (bar_volume, _) = slab_analytic(layout, layout.z_lo, layout.z_hi);
    let (_, adh) = slab_analytic(layout, 0.0, layout.l_adh);
    let (_, free) = slab_analytic(layout, layout.l_adh, layout.l);
    let core = PI * layout.r * layout.r * (layout.z_hi - layout.z_lo);
    Metrics {
        f_r: relative_rib_area(layout),
        rib_volume_m3: if layout.ribs.is_some() {
            bar_volume - core
        } else {
            0.0
        },
        bar_volume_m3: bar_volume,
        interface_area_adhesive_m2: adh,
        interface_area_free_m2: free,
        rib_count: layout.ribs.as_ref().map_or(0, |rl| rl.rib_count()),
    }
}

/// Closed-form volume of one transverse rib spanning the angle `span` with no
/// longitudinal ribs: span ∫_R^{R+a} r w(r) dr, w the axial width at radius r.
pub fn single_rib_volume(r: f64, a: f64, wb: f64, wt: f64, span: f64) -> f64 {
    span * (wb * (r * a + a * a / 2.0) + (wt - wb) * (r * a / 2.0 + a * a / 3.0))
}

/// A triangulated lateral surface of the bar (outward orientation).
struct Lateral {
    tris: Vec<[Point<f64>; 3]>,
}

const COLUMNS: usize = 720;
/// Extra rows per flank in the longitudinal-rib band.
const BAND_SUBDIVISIONS: usize = 16;

fn lateral_surface(layout: &Layout) -> Lateral {
    let r = layout.r;
    let z_lo = layout.z_lo;
    let z_hi = layout.z_hi;
    let mut tris = vec![];
    let mut cols: Vec<f64> = (0..=COLUMNS / 2)
        .map(|i| PI * i as f64 / (COLUMNS / 2) as f64)
        .collect();
    let margin =
        layout.ribs.as_ref().map_or(0.0, |rl| rl.k.abs() + rl.c) + (z_hi - z_lo) * 0.01 + 1e-3;
    for side in 0..2 {
        let mut rows = vec![z_lo - margin, z_hi + margin];
        // Rows inside the flanks, used only in the longitudinal-rib band where
        // the flank meets the rib floor at a level between foot and crest.
        let mut fine = vec![];
        let mut sign = 0.0;
        let mut band = 0.0;
        if let Some(rl) = &layout.ribs {
            for phi in [rl.phi_top, rl.phi_base, rl.phi_a, rl.t_s] {
                cols.push(phi);
                cols.push(PI - phi);
            }
            band = rl.phi_base;
            sign = rl.sides[side].sign * rl.k;
            for &zeta in &rl.sides[side].zeta {
                // Foot rows sit a hair outside the base so a vertical flank
                // (b_top = b_base) still gets its wall between two rows.
                let foot = rl.wb / 2.0 + 2e-9 * rl.c;
                for e in [-foot, -rl.wt / 2.0, rl.wt / 2.0, foot] {
                    rows.push(zeta + e);
                }
                if rl.wb > rl.wt {
                    for i in 1..BAND_SUBDIVISIONS {
                        let e = rl.wt / 2.0
                            + (rl.wb - rl.wt) / 2.0 * i as f64 / BAND_SUBDIVISIONS as f64;
                        fine.push(zeta - e);
                        fine.push(zeta + e);
                    }
                }
            }
        }
        cols.sort_by(f64::total_cmp);
        cols.dedup_by(|a, b| (*a - *b).abs() < 1e-13);
        rows.sort_by(f64::total_cmp);
        let mut rows_band = rows.clone();
        rows_band.extend(fine);
        rows_band.sort_by(f64::total_cmp);
        let point = |t: f64, zeta: f64| -> Point<f64> {
            let z = zeta + sign * t.cos();
            let rho = match &layout.ribs {
                None => r,
                Some(rl) => {
                    let h = rl.rib_height(side, t, z);
                    rl.floor(r, t).0.max(r + h)
                }
            };
            let th = t + side as f64 * PI;
            Point::new(rho * th.cos(), rho * th.sin(), z)
        };
        let in_band = |t: f64| t <= band * (1.0 + 1e-9) || t >= PI - band * (1.0 + 1e-9);
        let grid: Vec<(Vec<f64>, Vec<Point<f64>>)> = cols
            .iter()
            .map(|&t| {
                let rs = if in_band(t) { &rows_band } else { &rows };
                (rs.clone(), rs.iter().map(|&zeta| point(t, zeta)).collect())
            })
            .collect();
        // Zipper between neighbouring columns: both share the coarse rows, so
        // the strips are watertight even where one column has extra rows.
        for w in grid.windows(2) {
            let ((za, pa), (zb, pb)) = (&w[0], &w[1]);
            let (mut i, mut j) = (0, 0);
            while i + 1 < za.len() || j + 1 < zb.len() {
                let advance_a = j + 1 == zb.len() || (i + 1 < za.len() && za[i + 1] <= zb[j + 1]);
                if advance_a {
                    tris.push([pa[i], pb[j], pa[i + 1]]);
                    i += 1;
                } else {
                    tris.push([pa[i], pb[j], pb[j + 1]]);
                    j += 1;
                }
            }
        }
    }
    Lateral { tris }
}

/// Clips polygon `poly` to the half-space `keep_above ? z >= z0 : z <= z0`.
fn clip(poly: &[Point<f64>], z0: f64, keep_above: bool) -> Vec<Point<f64>> {
    let inside = |p: &Point<f64>| if keep_above { p.z >= z0 } else { p.z <= z0 };
    let mut out = Vec::with_capacity(poly.len() + 2);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let (ip, iq) = (inside(&p), inside(&q));
        if ip {
            out.push(p);
        }
        if ip != iq {
            let s = (z0 - p.z) / (q.z - p.z);
            let mut x = p + (q - p) * s;
            x.z = z0;
            out.push(x);
        }
    }
    out
}

fn clip_slab(tri: &[Point<f64>; 3], z1: f64, z2: f64) -> Vec<Point<f64>> {
    let p = clip(tri, z1, true);
    if p.len() < 3 {
        return vec![];
    }
    let p = clip(&p, z2, false);
    if p.len() < 3 {
        return vec![];
    }
    p
}

/// (volume, lateral areas per slab) from the parry3d tessellation.
pub struct Tessellated {
    /// Volume of the closed bar, m³ (parry3d mass properties, unit density).
    pub bar_volume_m3: f64,
    /// Lateral surface area in each requested slab, m².
    pub slab_areas_m2: Vec<f64>,
    /// Triangles in the closed bar mesh.
    pub triangles: usize,
}

/// Checks the parry3d measures against the analytic ones: the rib volume
/// (the tessellated bar less its core cylinder of volume `core_m3`) and
/// the adhesive and free interface areas (`t`'s first two slabs), each
/// within `tolerance` (relative). Names the first that is not.
pub fn check_offline(
    m: &Metrics,
    t: &Tessellated,
    core_m3: f64,
    tolerance: f64,
) -> Result<(), String> {
    let pairs = [
        ("rib volume", t.bar_volume_m3 - core_m3, m.rib_volume_m3),
        (
            "adhesive area",
            t.slab_areas_m2[0],
            m.interface_area_adhesive_m2,
        ),
        ("free area", t.slab_areas_m2[1], m.interface_area_free_m2),
    ];
    for (what, tessellated, analytic) in pairs {
        let rel = (tessellated - analytic).abs() / analytic.abs();
        if rel.is_nan() || rel >= tolerance {
            return Err(format!(
                "{what}: parry3d {tessellated:e}, analytic {analytic:e} ({:.3} % apart)",
                100.0 * rel
            ));
        }
    }
    Ok(())
}

/// Tessellates the bar and measures it with parry3d; `slabs` are z-ranges
/// whose lateral area is wanted.
pub fn tessellated(layout: &Layout, slabs: &[(f64, f64)]) -> Tessellated {
    let lat = lateral_surface(layout);
    let (z_lo, z_hi) = (layout.z_lo, layout.z_hi);
    let mut vertices: Vec<Point<f64>> = vec![];
    let mut indices: Vec<[u32; 3]> = vec![];
    let mut push = |a: Point<f64>, b: Point<f64>, c: Point<f64>, v: &mut Vec<Point<f64>>| {
        let n = v.len() as u32;
        v.extend([a, b, c]);
        indices.push([n, n + 1, n + 2]);
    };
    let lo_c = Point::new(0.0, 0.0, z_lo);
    let hi_c = Point::new(0.0, 0.0, z_hi);
    let mut slab_areas = vec![0.0; slabs.len()];
    for tri in &lat.tris {
        for (k, &(z1, z2)) in slabs.iter().enumerate() {
            let p = clip_slab(tri, z1, z2);
            for i in 1..p.len().saturating_sub(1) {
                slab_areas[k] += Triangle::new(p[0], p[i], p[i + 1]).area();
            }
        }
        let p = clip_slab(tri, z_lo, z_hi);
        if p.is_empty() {
            continue;
        }
        for i in 1..p.len() - 1 {
            push(p[0], p[i], p[i + 1], &mut vertices);
        }
        // Caps: the lateral polygon runs a→b along an end plane; the cap
        // triangle runs b→a so the closed surface is consistently oriented.
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            for (zc, c) in [(z_lo, lo_c), (z_hi, hi_c)] {
                if a.z == zc && b.z == zc {
                    push(c, b, a, &mut vertices);
                }
            }
        }
    }
    let mp = MassProperties::from_trimesh(1.0, &vertices, &indices);
    Tessellated {
        bar_volume_m3: mp.mass(),
        slab_areas_m2: slab_areas,
        triangles: indices.len(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spec::{resolve, RawBar, RawSpecimen};

    fn layout(bar: &str, specimen: &str) -> Layout {
        let bar: RawBar = serde_yaml::from_str(bar).unwrap();
        let sp: RawSpecimen = serde_yaml::from_str(specimen).unwrap();
        let (bar, sp) = resolve(&bar, &sp).unwrap();
        Layout::new(&bar, &sp)
    }

    fn rel(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    /// A smooth bar's volume and interface areas are those of a cylinder (SPEC §3).
    #[test]
    fn smooth_bar_is_a_cylinder() {
        let l = layout("{kind: smooth, diameter: 8 mm}", "{}");
        let m = analytic(&l);
        let r = 4e-3;
        assert!(rel(m.bar_volume_m3, PI * r * r * (0.08 + 0.002 + 0.004)) < 1e-12);
        assert!(rel(m.interface_area_adhesive_m2, 2.0 * PI * r * 0.04) < 1e-12);
        assert_eq!(m.f_r, 0.0);
        let t = tessellated(&l, &[(0.0, 0.04)]);
        assert!(
            rel(t.bar_volume_m3, m.bar_volume_m3) < 1e-4,
            "{}",
            t.bar_volume_m3
        );
        assert!(rel(t.slab_areas_m2[0], m.interface_area_adhesive_m2) < 1e-4);
    }

    /// Nearly vanishing longitudinal ribs leave transverse rings whose volume,
    /// crest area and flank (conical frustum) area match closed forms (SPEC §3 rib section).
    #[test]
    fn rings_match_closed_forms() {
        let bar = "{kind: ribbed, diameter: 8 mm, ribs: {height: 0.5 mm, spacing: 5 mm, angle: 90 deg, \
                   top_width: 0.8 mm, base_width: 1.8 mm}, longitudinal_ribs: {height: 0.5 mm, top_width: 0.000001 mm, base_width: 0.000001 mm}}";
        let l = layout(
            bar,
            "{cube_side: 80 mm, free_overhang: 20 mm, loaded_overhang: 20 mm}",
        );
        let rl = l.ribs.as_ref().unwrap();
        let (r, a, wb, wt) = (4e-3, 0.5e-3, 1.8e-3, 0.8e-3);
        let span = PI - 2.0 * rl.t_s;
        let m = analytic(&l);
        // A window from just before ring 2 to just after ring 10 of side A
        // (side B's rings coincide with them: β = 90°, phase 0).
        let (z1, z2) = (rl.sides[0].zeta[2] - 2.4e-3, rl.sides[0].zeta[10] + 2.4e-3);
        let per_side = rl.sides[0]
            .zeta
            .iter()
            .filter(|z| **z > z1 && **z < z2)
            .count() as f64;
        assert_eq!(per_side, 9.0);
        let (vol, area) = slab_analytic(&l, z1, z2);
        let core_vol = PI * r * r * (z2 - z1);
        let expect_vol = 2.0 * per_side * single_rib_volume(r, a, wb, wt, span);
        assert!(
            rel(vol - core_vol, expect_vol) < 1e-4,
            "{} vs {}",
            vol - core_vol,
            expect_vol
        );
        let slant = (a * a + ((wb - wt) / 2.0).powi(2)).sqrt();
        let per_rib_area = span * ((r + a) * wt + 2.0 * (r + r + a) / 2.0 * slant) - span * r * wb;
        // The 1 nm longitudinal ribs are fins: 4 walls of height a_l = a,
        // partly hidden under each ring (∫ h dz = a (wb + wt) / 2 per ring).
        let fins = 4.0 * (a * (z2 - z1) - per_side * a * (wb + wt) / 2.0);
        let expect_area = 2.0 * PI * r * (z2 - z1) + 2.0 * per_side * per_rib_area + fins;
        assert!(rel(area, expect_area) < 1e-4, "{area} vs {expect_area}");
        // f_R of rings: two half-annuli per spacing over π d c.
        let fr = 2.0 * span * ((r + a).powi(2) - r * r) / 2.0 / (PI * 2.0 * r * 5e-3);
        assert!(rel(m.f_r, fr) < 1e-4, "{} vs {fr}", m.f_r);
    }

    /// The parry3d tessellation agrees with the analytic metrics within 1 % for
    /// spiral, herringbone and steep ribs (SPEC §3 cross-check).
    #[test]
    fn tessellation_agrees_with_analytic() {
        for ribs in [
            "{angle: 55 deg}",
            "{angle: 35 deg, side_b: mirrored, phase: 1 mm}",
            "{angle: 90 deg, height: 0.8 mm, top_width: 1 mm, base_width: 1 mm}",
        ] {
            let l = layout(
                &format!("{{kind: ribbed, diameter: 8 mm, ribs: {ribs}}}"),
                "{}",
            );
            let m = analytic(&l);
            let t = tessellated(&l, &[(0.0, l.l_adh), (l.l_adh, l.l)]);
            let core = PI * l.r * l.r * (l.z_hi - l.z_lo);
            if let Err(e) = check_offline(&m, &t, core, 0.01) {
                panic!("{ribs}: {e}");
            }
        }
    }

    /// Default ribs of SPEC §3 proportions give f_R above EN 1992-1-1's minimum 0.040.
    #[test]
    fn default_ribs_meet_the_minimum_relative_rib_area() {
        let l = layout("{kind: ribbed, diameter: 8 mm}", "{}");
        let fr = relative_rib_area(&l);
        assert!(fr > 0.040 && fr < 0.2, "{fr}");
    }
}
