//! The bar's outer surface as a radial graph ρ(θ, z), and where the ribs go.
//!
//! The ribbed bar is star-shaped about its axis, so its surface is
//! ρ(θ, z) = max(R, ρ_l(θ), R + f(z − z_c(θ))) where ρ_l is the longitudinal
//! ribs' radial extent and f the transverse ribs' trapezoid profile centred
//! on z_c(θ) = ζ_k + σ K cos θ (K = R cot β). Each side (A: θ ∈ (0, π),
//! B: θ ∈ (π, 2π)) is described with a local angle t ∈ [0, π]; side B's
//! global angle is t + π, its sign σ is +1 when rotated, −1 when mirrored.
//!
//! The transverse ribs are built between t_s and π − t_s (t_s inside the
//! longitudinal rib's crest) so that their ends lie strictly inside the
//! longitudinal ribs: no face of a rib end is tangent to a longitudinal rib
//! face, which keeps the OpenCASCADE union robust.

use crate::spec::{Bar, SideB, Specimen, Symmetry};
use std::f64::consts::PI;

/// Ribs of one side: mid-rib axial positions and the sign of the cos θ shift.
#[derive(Debug, Clone, PartialEq)]
pub struct SideRibs {
    /// ζ_k of each rib (z of the rib centre at t = π/2), m.
    pub zeta: Vec<f64>,
    /// +1 or −1: centre z_c(t) = ζ_k + sign K cos t.
    pub sign: f64,
}

/// Resolved rib geometry in the form the metrics and the `.geo` use.
#[derive(Debug, Clone, PartialEq)]
pub struct RibLayout {
    /// Transverse rib height a, m.
    pub a: f64,
    /// Axial spacing c, m.
    pub c: f64,
    /// K = R cot β, m: axial amplitude of the rib centreline.
    pub k: f64,
    /// Axial width of the transverse rib section at the core surface, m.
    pub wb: f64,
    /// Axial width of the transverse rib section at its crest, m.
    pub wt: f64,
    /// Longitudinal rib height a_l, m.
    pub a_l: f64,
    /// Longitudinal rib crest width, m.
    pub bl_top: f64,
    /// Longitudinal rib width where its flanks meet the core circle, m.
    pub bl_base: f64,
    /// x of the longitudinal rib flank foot on the core circle, m.
    pub x_foot: f64,
    /// Angle from a longitudinal rib's centre to its crest corner, rad.
    pub phi_top: f64,
    /// Angle from a longitudinal rib's centre to its flank foot, rad.
    pub phi_base: f64,
    /// Angle where the longitudinal rib's extent drops to R + a, rad.
    pub phi_a: f64,
    /// Transverse ribs span t ∈ [t_s, π − t_s], rad.
    pub t_s: f64,
    /// Side A (t ∈ [0, π] is global θ) and side B (global θ = t + π).
    pub sides: [SideRibs; 2],
    /// Smallest axial distance from a cut plane (z = 0, l_adh, L) to a rib edge feature, m.
    pub clearance_cube: f64,
    /// Smallest axial distance from a bar end plane to a rib edge feature, m.
    pub clearance_ends: f64,
}

/// Everything needed to describe the specimen's bar in SI units.
#[derive(Debug, Clone, PartialEq)]
pub struct Layout {
    /// Core radius R = d/2, m.
    pub r: f64,
    /// Bar free end z, m.
    pub z_lo: f64,
    /// Bar loaded end z, m.
    pub z_hi: f64,
    /// Cube side L, m.
    pub l: f64,
    /// Adhesive length l_adh, m.
    pub l_adh: f64,
    pub ribs: Option<RibLayout>,
    /// Modelled part: whole specimen or the quarter x ≥ 0, y ≥ 0. The
    /// metrics always describe the whole specimen.
    pub symmetry: Symmetry,
}

/// Sections in a ThruSections rib (SPEC §9: ~13 gave exact volumes).
pub const RIB_SECTIONS: usize = 13;

impl Layout {
    /// Places the ribs of `bar` in `specimen` (choosing the axial phase that
    /// keeps rib edges away from the cut planes).
    pub fn new(bar: &Bar, specimen: &Specimen) -> Layout {
        let r = bar.diameter / 2.0;
        let z_lo = specimen.bar_z_min();
        let z_hi = specimen.bar_z_max();
        let l = specimen.cube_side;
        let l_adh = specimen.adhesive_length;
        let ribs = bar.ribs.as_ref().map(|ribs| {
            let t = &ribs.transverse;
            let lr = &ribs.longitudinal;
            let sin_b = t.angle.sin();
            let k = r * t.angle.cos() / sin_b;
            let wb = t.base_width / sin_b;
            let wt = t.top_width / sin_b;
            let x_foot = (r * r - (lr.base_width / 2.0).powi(2)).sqrt();
            let phi_top = (lr.top_width / 2.0).atan2(r + lr.height);
            let phi_base = (lr.base_width / 2.0).atan2(x_foot);
            let mut rl = RibLayout {
                a: t.height,
                c: t.spacing,
                k,
                wb,
                wt,
                a_l: lr.height,
                bl_top: lr.top_width,
                bl_base: lr.base_width,
                x_foot,
                phi_top,
                phi_base,
                phi_a: 0.0,
                t_s: 0.5 * phi_top,
                sides: [
                    SideRibs {
                        zeta: vec![],
                        sign: 1.0,
                    },
                    SideRibs {
                        zeta: vec![],
                        sign: match t.side_b {
                            SideB::Rotated => 1.0,
                            SideB::Mirrored => -1.0,
                        },
                    },
                ],
                clearance_cube: f64::INFINITY,
                clearance_ends: f64::INFINITY,
            };
            rl.phi_a = rl.angle_where_long_rib_drops_to(r, r + rl.a);
            rl.place(z_lo, z_hi, l, l_adh, t.phase);
            rl
        });
        Layout {
            r,
            z_lo,
            z_hi,
            l,
            l_adh,
            ribs,
            symmetry: specimen.symmetry,
        }
    }

    /// Outer radius of the bar, m.
    pub fn outer_radius(&self) -> f64 {
        self.r + self.ribs.as_ref().map_or(0.0, |rl| rl.a.max(rl.a_l))
    }
}

impl RibLayout {
    /// Radial extent of the bar's floor (core or longitudinal rib) and its
    /// derivative dρ/dt at local angle t ∈ [0, π].
    pub fn floor(&self, r: f64, t: f64) -> (f64, f64) {
        let (phi, s) = if t <= PI / 2.0 {
            (t, 1.0)
        } else {
            (PI - t, -1.0)
        };
        if phi >= self.phi_base {
            return (r, 0.0);
        }
        let u = (phi.cos(), phi.sin());
        let du = (-phi.sin(), phi.cos());
        // The crest line x = R + a_l, or the flank line through the foot
        // (x_foot, b_base/2) and the crest corner (R + a_l, b_top/2).
        let (n, q) = if phi <= self.phi_top {
            ((1.0, 0.0), r + self.a_l)
        } else {
            let p1 = (self.x_foot, self.bl_base / 2.0);
            let p2 = (r + self.a_l, self.bl_top / 2.0);
            let dir = (p2.0 - p1.0, p2.1 - p1.1);
            let norm = (dir.0 * dir.0 + dir.1 * dir.1).sqrt();
            let n = (dir.1 / norm, -dir.0 / norm);
            (n, n.0 * p1.0 + n.1 * p1.1)
        };
        let nu = n.0 * u.0 + n.1 * u.1;
        let rho = q / nu;
        let drho = -q * (n.0 * du.0 + n.1 * du.1) / (nu * nu);
        if rho <= r {
            (r, 0.0)
        } else {
            (rho, s * drho)
        }
    }

    fn angle_where_long_rib_drops_to(&self, r: f64, level: f64) -> f64 {
        // The floor decreases monotonically from the rib centre to its foot.
        let (mut lo, mut hi) = (0.0, self.phi_base);
        if self.floor(r, hi * (1.0 - 1e-12)).0 >= level {
            return hi;
        }
        for _ in 0..100 {
            let mid = 0.5 * (lo + hi);
            if self.floor(r, mid).0 >= level {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        0.5 * (lo + hi)
    }

    /// Axial offsets (from ζ_k) of the rib features a plane should not graze:
    /// the four section corners at the angles where ribs end or emerge.
    fn critical_offsets(&self) -> Vec<f64> {
        let mut out = vec![];
        for e in [-self.wb / 2.0, -self.wt / 2.0, self.wt / 2.0, self.wb / 2.0] {
            for t in [self.t_s, self.phi_base, self.phi_a, PI / 2.0] {
                for s in [-1.0, 1.0] {
                    out.push(e + s * self.k * t.cos());
                }
            }
        }
        out
    }

    fn place(&mut self, z_lo: f64, z_hi: f64, l: f64, l_adh: f64, phase: f64) {
        let c = self.c;
        let base = self.critical_offsets();
        let mut offsets = base.clone();
        offsets.extend(base.iter().map(|o| o + phase));
        let dist = |planes: &[f64], z0: f64| -> f64 {
            let mut best = f64::INFINITY;
            for &p in planes {
                for &o in &offsets {
                    let x = (p - z0 - o).rem_euclid(c);
                    best = best.min(x.min(c - x));
                }
            }
            best
        };
        let cube = [0.0, l_adh, l];
        let ends = [z_lo, z_hi];
        let n = 2000;
        let (mut best_z0, mut best_score) = (0.0, f64::NEG_INFINITY);
        for i in 0..n {
            let z0 = c * i as f64 / n as f64;
            let score = dist(&cube, z0).min(2.0 * dist(&ends, z0));
            if score > best_score {
                best_score = score;
                best_z0 = z0;
            }
        }
        self.clearance_cube = dist(&cube, best_z0);
        self.clearance_ends = dist(&ends, best_z0);
        let reach = self.k.abs() + self.wb / 2.0;
        for (side, shift) in [(0usize, 0.0), (1usize, phase)] {
            let first = ((z_lo - reach - best_z0 - shift) / c).floor() as i64;
            let last = ((z_hi + reach - best_z0 - shift) / c).ceil() as i64;
            self.sides[side].zeta = (first..=last)
                .map(|k| best_z0 + shift + k as f64 * c)
                .filter(|&z| z + reach > z_lo && z - reach < z_hi)
                .collect();
        }
    }

    /// Transverse rib height above the core at local angle t and axial
    /// position z on `side` (0 when no rib is there), m.
    pub fn rib_height(&self, side: usize, t: f64, z: f64) -> f64 {
        if t < self.t_s || t > PI - self.t_s {
            return 0.0;
        }
        let shift = self.sides[side].sign * self.k * t.cos();
        let c = self.c;
        // Ribs of one side are spaced by c and never overlap: only the
        // nearest rib centre matters.
        let zs = &self.sides[side].zeta;
        if zs.is_empty() {
            return 0.0;
        }
        let rel = z - shift - zs[0];
        let idx = (rel / c).round().clamp(0.0, (zs.len() - 1) as f64) as usize;
        let mut h: f64 = 0.0;
        for zk in &zs[idx.saturating_sub(1)..(idx + 2).min(zs.len())] {
            h = h.max(self.profile((z - shift - zk).abs()));
        }
        h
    }

    /// Trapezoid profile at axial distance `x` from a rib centre, m.
    pub fn profile(&self, x: f64) -> f64 {
        // The tolerance keeps a vertical flank's crest row on the crest
        // despite rounding of x.
        if x <= self.wt / 2.0 + 1e-9 * self.c {
            self.a
        } else if x >= self.wb / 2.0 {
            0.0
        } else {
            self.a * (self.wb / 2.0 - x) / ((self.wb - self.wt) / 2.0)
        }
    }

    /// Total number of transverse ribs built (both sides).
    pub fn rib_count(&self) -> usize {
        self.sides[0].zeta.len() + self.sides[1].zeta.len()
    }
}
