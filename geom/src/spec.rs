//! The `bar` and `specimen` sections of a scene spec: raw (as written, units
//! unresolved) and resolved (SI, defaults filled in, every bound checked).
//!
//! ```
//! use geom::spec::{resolve, RawBar, RawSpecimen};
//! let bar: RawBar = serde_yaml::from_str("kind: ribbed\ndiameter: 8 mm\nribs: {angle: 55 deg}").unwrap();
//! let specimen: RawSpecimen = serde_yaml::from_str("{}").unwrap();
//! let (bar, specimen) = resolve(&bar, &specimen).unwrap();
//! assert!((specimen.cube_side - 0.08).abs() < 1e-12); // default 10 d
//! assert!((bar.ribs.unwrap().transverse.height - 0.52e-3).abs() < 1e-12); // default 0.065 d
//! ```

use crate::units::{Dim, RawQuantity, UnitError};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};
use std::f64::consts::FRAC_PI_2;

/// Smooth or spiral-ribbed bar.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum BarKind {
    /// A plain cylinder of the diameter d.
    Smooth,
    /// A core of the diameter d with transverse and longitudinal ribs.
    Ribbed,
}

/// How the ribs of side B (π < θ < 2π) derive from those of side A.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum SideB {
    /// Image of side A by the 180° rotation about the bar axis (spiral bar).
    #[default]
    Rotated,
    /// Mirror image of side A in the plane of the longitudinal ribs (herringbone).
    Mirrored,
}

/// `specimen.symmetry` as written: which part of the specimen is modelled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum RawSymmetry {
    /// The smallest exact part: the quarter of a smooth bar's specimen, the
    /// half of a herringbone bar's (side B mirrored, no phase), the
    /// half-turn half of a spiral one's (side B rotated, no phase), the
    /// whole of a bar with a phase between its sides.
    #[default]
    Auto,
    /// The whole specimen.
    Full,
    /// The half y ≥ 0: a smooth bar or a herringbone bar without phase (its
    /// mirror plane), a spiral bar without phase (the half-turn about the
    /// axis).
    Half,
    /// The quarter x ≥ 0, y ≥ 0 of a smooth bar's specimen.
    Quarter,
}

/// The modelled part of the specimen, resolved. The smooth bar in the cube
/// has the mirror planes x = 0 and y = 0 (loading, supports and the FED/force
/// measurements are symmetric in both), so the quarter x ≥ 0, y ≥ 0 with
/// those planes held normal gives the whole specimen's response. A
/// herringbone bar whose side B is the mirror image of side A in the plane
/// of the longitudinal ribs (y = 0) with no axial phase between the sides is
/// mirror-symmetric in that plane alone: the half y ≥ 0. A spiral bar
/// (side B rotated) without phase has no mirror plane through its axis, but
/// the half-turn about the axis maps it onto itself: its half y ≥ 0 with
/// the cut face's two sides tied by u(−x, 0, z) = R u(x, 0, z),
/// R = diag(−1, −1, 1) (`HalfTurn`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Symmetry {
    #[default]
    Full,
    /// The half y ≥ 0, the plane y = 0 held normal.
    Half,
    Quarter,
    /// The half y ≥ 0 of a specimen symmetric under the half-turn about the
    /// bar axis: each point (x, 0, z) of the cut face, x < 0, moves as the
    /// half-turn image of (−x, 0, z).
    #[serde(rename = "half_turn")]
    HalfTurn,
}

impl Symmetry {
    /// Modelled volume (or area, or force) per whole-specimen one.
    pub fn fraction(self) -> f64 {
        match self {
            Symmetry::Full => 1.0,
            Symmetry::Half | Symmetry::HalfTurn => 0.5,
            Symmetry::Quarter => 0.25,
        }
    }
}

// Every field of the raw types below documents itself for the scene
// reference and the JSON Schema (`ribbar schema scene`): its meaning, then
// `(unit; default …; bounds)` as the last parenthesis of its doc comment.

/// `bar` as written in the spec.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawBar {
    /// Whether the bar is smooth or ribbed (choice; required).
    pub kind: BarKind,
    /// Core (nominal) diameter d (length; required; > 0).
    pub diameter: RawQuantity,
    /// The transverse ribs of a ribbed bar; an error for `kind: smooth`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ribs: Option<RawRibs>,
    /// The two longitudinal ribs (θ = 0, π) of a ribbed bar; an error for
    /// `kind: smooth`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub longitudinal_ribs: Option<RawLongitudinalRibs>,
}

/// `bar.ribs` (transverse ribs) as written; every key is optional. In every
/// plane through the bar axis a rib's section is an isosceles trapezoid
/// whose axial widths are the widths below divided by sin β.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawRibs {
    /// Transverse rib height a above the core (length; default 0.065 d;
    /// 0 < a < d/2).
    pub height: Option<RawQuantity>,
    /// Axial spacing c of the ribs of one side (length; default 0.625 d; > 0).
    pub spacing: Option<RawQuantity>,
    /// Inclination β of the ribs to the bar axis, 90° giving rings; a plain
    /// number is radians (angle; default 55 deg; in (0, 90] deg).
    pub angle: Option<RawQuantity>,
    /// Crest width b_top, measured perpendicular to the rib at mid-rib
    /// (length; default 0.1 d; > 0).
    pub top_width: Option<RawQuantity>,
    /// Width b_base at the core surface; give it or `flank_angle`, not both
    /// (length; default b_top + 2a, 45° flanks; b_top ≤ b_base < 0.98 c sin β,
    /// so that neighbouring ribs do not touch).
    pub base_width: Option<RawQuantity>,
    /// Flank inclination α to the core surface; sets the base width
    /// b_base = b_top + 2a / tan α instead of `base_width` (angle; default
    /// 45 deg; in (0, 90] deg).
    pub flank_angle: Option<RawQuantity>,
    /// How side B's ribs derive from side A's: `rotated` for a spiral bar,
    /// `mirrored` for a herringbone bar (choice; default rotated).
    pub side_b: Option<SideB>,
    /// Axial offset of side B's ribs from the rotated or mirrored image of
    /// side A's (length; default 0; in [0, c)).
    pub phase: Option<RawQuantity>,
}

/// `bar.longitudinal_ribs` as written; every key is optional.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawLongitudinalRibs {
    /// Height a_l of the two longitudinal ribs above the core; the
    /// transverse ribs end inside them (length; default a, the transverse
    /// rib height; a ≤ a_l < d/2).
    pub height: Option<RawQuantity>,
    /// Crest width (length; default b_top of the transverse ribs; > 0).
    pub top_width: Option<RawQuantity>,
    /// Width where the flanks meet the core (length; default the top width
    /// + 2 a_l; top width ≤ it ≤ d/2).
    pub base_width: Option<RawQuantity>,
}

/// `specimen` as written; every key is optional.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawSpecimen {
    /// Side L of the concrete cube; the cube spans x, y ∈ [−L/2, L/2],
    /// z ∈ [0, L], z = 0 the free face and z = L the loaded (bearing) face
    /// (length; default 10 d; wider than the bar's outer diameter).
    pub cube_side: Option<RawQuantity>,
    /// Bonded length l_adh, z ∈ [0, l_adh] (length; default L/2;
    /// 0 < l_adh ≤ L).
    pub adhesive_length: Option<RawQuantity>,
    /// Bar length beyond the free face z = 0 (length; default 0.25 d; ≥ 0).
    pub free_overhang: Option<RawQuantity>,
    /// Bar length beyond the loaded face z = L (length; default 0.5 d; ≥ 0).
    pub loaded_overhang: Option<RawQuantity>,
    /// The modelled part of the specimen: `half` models y ≥ 0 (a smooth or
    /// herringbone bar's mirror half, or a spiral bar's half-turn half, both
    /// without phase), `quarter` x, y ≥ 0 (smooth bars only); forces, σ_mb,
    /// FED and energies are always the whole specimen's. `half` with a
    /// phase, or `quarter` on a ribbed bar, is an error naming the reason
    /// (choice; default auto).
    pub symmetry: Option<RawSymmetry>,
}

/// The resolved bar (SI units).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Bar {
    pub kind: BarKind,
    /// Nominal (core) diameter d, m.
    pub diameter: f64,
    /// Present exactly when `kind` is `Ribbed`.
    pub ribs: Option<Ribs>,
}

/// The rib pattern of a ribbed bar.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Ribs {
    pub transverse: TransverseRibs,
    pub longitudinal: LongitudinalRibs,
}

/// Transverse ribs (paper §3.4.1, SPEC §3). Widths are measured
/// perpendicular to the rib at mid-rib (θ = π/2); in every plane through the
/// bar axis the rib section is an isosceles trapezoid whose axial widths are
/// these widths divided by sin β.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TransverseRibs {
    /// Rib height a above the core, m.
    pub height: f64,
    /// Axial spacing c between consecutive ribs of one side, m.
    pub spacing: f64,
    /// Rib inclination β to the bar axis, rad (π/2 gives rings).
    pub angle: f64,
    /// Width b_top at the rib crest, m.
    pub top_width: f64,
    /// Width b_base at the core surface, m.
    pub base_width: f64,
    pub side_b: SideB,
    /// Axial offset of side B's ribs from the rotated/mirrored image of side A, m.
    pub phase: f64,
}

/// The two longitudinal ribs at θ = 0 and θ = π (isosceles trapezoid section
/// in the cross-section plane, along the whole bar).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LongitudinalRibs {
    /// Height a_l above the core surface, m.
    pub height: f64,
    /// Width at the crest, m.
    pub top_width: f64,
    /// Width where the flanks meet the core surface, m.
    pub base_width: f64,
}

/// The resolved pull-out specimen (SI units; SPEC §2 frame).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Specimen {
    /// Cube side L, m; the cube spans x, y ∈ [−L/2, L/2], z ∈ [0, L].
    pub cube_side: f64,
    /// Adhesive (bonded) length l_adh, m: z ∈ [0, l_adh].
    pub adhesive_length: f64,
    /// Bar length e_free beyond the free face z = 0, m.
    pub free_overhang: f64,
    /// Bar length e_load beyond the loaded face z = L, m.
    pub loaded_overhang: f64,
    /// The modelled part (whole specimen or the quarter x ≥ 0, y ≥ 0).
    pub symmetry: Symmetry,
}

impl Bar {
    /// Outer radius of the bar (core plus the tallest rib), m.
    pub fn outer_radius(&self) -> f64 {
        let r = self.diameter / 2.0;
        match &self.ribs {
            None => r,
            Some(ribs) => r + ribs.transverse.height.max(ribs.longitudinal.height),
        }
    }
}

impl Specimen {
    /// Lowest z of the bar (its free end), m.
    pub fn bar_z_min(&self) -> f64 {
        -self.free_overhang
    }
    /// Highest z of the bar (its loaded end), m.
    pub fn bar_z_max(&self) -> f64 {
        self.cube_side + self.loaded_overhang
    }
}

/// A spec value that violates a bound or cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpecError {
    #[error(transparent)]
    Unit(#[from] UnitError),
    #[error("{key} = {value}: must be {bound}")]
    OutOfBounds {
        key: String,
        value: String,
        bound: String,
    },
    #[error("{key} = {value} rad is above 90°; plain numbers are radians: did you mean \"{value} deg\"?")]
    AngleInRadians { key: String, value: f64 },
    #[error("{key}: {problem}")]
    Inconsistent { key: String, problem: String },
}

/// Defaults derived from the diameter (SPEC §3, EN 10080 / ISO 6935-2 orders
/// of magnitude): a = 0.065 d, c = 0.625 d, β = 55°, b_top = 0.1 d,
/// b_base = b_top + 2a (45° flanks); longitudinal ribs as tall as the
/// transverse ones with the same widths.
pub mod defaults {
    /// Transverse rib height / d.
    pub const RIB_HEIGHT_PER_D: f64 = 0.065;
    /// Rib spacing / d.
    pub const RIB_SPACING_PER_D: f64 = 0.625;
    /// Rib angle, degrees.
    pub const RIB_ANGLE_DEG: f64 = 55.0;
    /// Rib crest width / d.
    pub const RIB_TOP_WIDTH_PER_D: f64 = 0.1;
    /// Cube side / d (RILEM).
    pub const CUBE_SIDE_PER_D: f64 = 10.0;
    /// Free-end overhang / d.
    pub const FREE_OVERHANG_PER_D: f64 = 0.25;
    /// Loaded-end overhang / d.
    pub const LOADED_OVERHANG_PER_D: f64 = 0.5;
}

fn mm(v: f64) -> String {
    show(v, Dim::Length)
}

fn show(v: f64, dim: Dim) -> String {
    match dim {
        Dim::Length => {
            let s = format!("{}", v * 1e3);
            format!("{s} mm")
        }
        Dim::Angle => format!("{} deg", v.to_degrees()),
        _ => format!("{v} {}", dim.si_unit()),
    }
}

fn bound(key: &str, v: f64, dim: Dim, ok: bool, bound: impl Into<String>) -> Result<(), SpecError> {
    if ok {
        Ok(())
    } else {
        Err(SpecError::OutOfBounds {
            key: key.to_string(),
            value: show(v, dim),
            bound: bound.into(),
        })
    }
}

fn positive(key: &str, v: f64) -> Result<(), SpecError> {
    bound(key, v, Dim::Length, v > 0.0, "> 0")
}

fn len(q: &Option<RawQuantity>, key: &str, default: f64) -> Result<f64, SpecError> {
    match q {
        Some(q) => Ok(q.to_si(Dim::Length, key)?),
        None => Ok(default),
    }
}

/// An angle (rad); a plain number above π/2 is taken for degrees written
/// without unit and rejected with a hint.
fn angle(q: &RawQuantity, key: &str) -> Result<f64, SpecError> {
    let v = q.to_si(Dim::Angle, key)?;
    if let RawQuantity::Number(n) = q {
        if *n > FRAC_PI_2 {
            return Err(SpecError::AngleInRadians {
                key: key.into(),
                value: *n,
            });
        }
    }
    Ok(v)
}

/// Resolves and validates `bar` and `specimen` (SPEC §2, §3). Errors name the
/// dotted key, its value with unit and the violated bound.
pub fn resolve(bar: &RawBar, specimen: &RawSpecimen) -> Result<(Bar, Specimen), SpecError> {
    let d = bar.diameter.to_si(Dim::Length, "bar.diameter")?;
    positive("bar.diameter", d)?;

    let ribs = match bar.kind {
        BarKind::Smooth => {
            for (present, key) in [
                (bar.ribs.is_some(), "bar.ribs"),
                (bar.longitudinal_ribs.is_some(), "bar.longitudinal_ribs"),
            ] {
                if present {
                    return Err(SpecError::Inconsistent {
                        key: key.into(),
                        problem: "given for a smooth bar (bar.kind = smooth); remove it or set bar.kind: ribbed"
                            .into(),
                    });
                }
            }
            None
        }
        BarKind::Ribbed => Some(resolve_ribs(
            bar.ribs.as_ref().cloned().unwrap_or_default(),
            bar.longitudinal_ribs.as_ref().cloned().unwrap_or_default(),
            d,
        )?),
    };
    let bar = Bar {
        kind: bar.kind,
        diameter: d,
        ribs,
    };

    let l = len(
        &specimen.cube_side,
        "specimen.cube_side",
        defaults::CUBE_SIDE_PER_D * d,
    )?;
    positive("specimen.cube_side", l)?;
    let outer = 2.0 * bar.outer_radius();
    bound(
        "specimen.cube_side",
        l,
        Dim::Length,
        l > outer * (1.0 + 1e-6),
        format!(
            "> {} (the ribbed bar's outer diameter): the cube must be wider than the bar",
            mm(outer)
        ),
    )?;
    let l_adh = len(
        &specimen.adhesive_length,
        "specimen.adhesive_length",
        l / 2.0,
    )?;
    positive("specimen.adhesive_length", l_adh)?;
    bound(
        "specimen.adhesive_length",
        l_adh,
        Dim::Length,
        l_adh <= l * (1.0 + 1e-12),
        format!("<= specimen.cube_side = {}", mm(l)),
    )?;
    let l_adh = l_adh.min(l);
    let e_free = len(
        &specimen.free_overhang,
        "specimen.free_overhang",
        defaults::FREE_OVERHANG_PER_D * d,
    )?;
    bound(
        "specimen.free_overhang",
        e_free,
        Dim::Length,
        e_free >= 0.0,
        ">= 0",
    )?;
    let e_load = len(
        &specimen.loaded_overhang,
        "specimen.loaded_overhang",
        defaults::LOADED_OVERHANG_PER_D * d,
    )?;
    bound(
        "specimen.loaded_overhang",
        e_load,
        Dim::Length,
        e_load >= 0.0,
        ">= 0",
    )?;

    let symmetry = resolve_symmetry(specimen.symmetry.unwrap_or_default(), &bar)?;

    Ok((
        bar,
        Specimen {
            cube_side: l,
            adhesive_length: l_adh,
            free_overhang: e_free,
            loaded_overhang: e_load,
            symmetry,
        },
    ))
}

/// The modelled part `raw` asks for, checked against the bar's symmetry.
fn resolve_symmetry(raw: RawSymmetry, bar: &Bar) -> Result<Symmetry, SpecError> {
    // The half y ≥ 0 a bar admits: a mirror half for a smooth or herringbone
    // bar, a half-turn half for a spiral one; with a phase between the
    // sides, none.
    let half = match &bar.ribs {
        None => Ok(Symmetry::Half),
        Some(ribs) if ribs.transverse.phase != 0.0 => Err(match ribs.transverse.side_b {
            SideB::Rotated => {
                "side B's ribs are shifted by bar.ribs.phase, so they are not the \
                 half-turn images of side A's"
            }
            SideB::Mirrored => {
                "side B's ribs are shifted by bar.ribs.phase, so they are not the \
                 mirror images of side A's"
            }
        }),
        Some(ribs) => Ok(match ribs.transverse.side_b {
            SideB::Rotated => Symmetry::HalfTurn,
            SideB::Mirrored => Symmetry::Half,
        }),
    };
    match (raw, bar.kind) {
        (RawSymmetry::Full, _) => Ok(Symmetry::Full),
        (RawSymmetry::Auto | RawSymmetry::Quarter, BarKind::Smooth) => Ok(Symmetry::Quarter),
        (RawSymmetry::Half, _) => half.map_err(|why| SpecError::Inconsistent {
            key: "specimen.symmetry".into(),
            problem: format!("half needs a symmetric half: {why}; use full or auto"),
        }),
        (RawSymmetry::Auto, BarKind::Ribbed) => Ok(half.unwrap_or(Symmetry::Full)),
        (RawSymmetry::Quarter, BarKind::Ribbed) => Err(SpecError::Inconsistent {
            key: "specimen.symmetry".into(),
            problem: "quarter needs a smooth bar: a ribbed bar has at most one mirror \
                      plane through its axis (herringbone) or the half-turn about it \
                      (spiral), so a quarter model would not be the specimen; use half, \
                      full or auto"
                .into(),
        }),
    }
}

fn resolve_ribs(raw: RawRibs, raw_l: RawLongitudinalRibs, d: f64) -> Result<Ribs, SpecError> {
    let r = d / 2.0;
    let a = len(
        &raw.height,
        "bar.ribs.height",
        defaults::RIB_HEIGHT_PER_D * d,
    )?;
    positive("bar.ribs.height", a)?;
    bound(
        "bar.ribs.height",
        a,
        Dim::Length,
        a < r,
        format!("< d/2 = {} (ribs taller than the core radius)", mm(r)),
    )?;
    let c = len(
        &raw.spacing,
        "bar.ribs.spacing",
        defaults::RIB_SPACING_PER_D * d,
    )?;
    positive("bar.ribs.spacing", c)?;

    let beta = match &raw.angle {
        None => defaults::RIB_ANGLE_DEG.to_radians(),
        Some(q) => angle(q, "bar.ribs.angle")?,
    };
    bound(
        "bar.ribs.angle",
        beta,
        Dim::Angle,
        beta > 0.0 && beta <= FRAC_PI_2 * (1.0 + 1e-12),
        "in (0, 90] deg",
    )?;
    let beta = beta.min(FRAC_PI_2);

    let b_top = len(
        &raw.top_width,
        "bar.ribs.top_width",
        defaults::RIB_TOP_WIDTH_PER_D * d,
    )?;
    positive("bar.ribs.top_width", b_top)?;
    let b_base = rib_base_width(&raw, a, c, beta, b_top)?;
    let phase = len(&raw.phase, "bar.ribs.phase", 0.0)?;
    bound(
        "bar.ribs.phase",
        phase,
        Dim::Length,
        (0.0..c).contains(&phase),
        format!("in [0, bar.ribs.spacing = {})", mm(c)),
    )?;

    let longitudinal = resolve_longitudinal_ribs(&raw_l, r, a, b_top)?;
    Ok(Ribs {
        transverse: TransverseRibs {
            height: a,
            spacing: c,
            angle: beta,
            top_width: b_top,
            base_width: b_base,
            side_b: raw.side_b.unwrap_or_default(),
            phase,
        },
        longitudinal,
    })
}

/// The transverse ribs' base width (from `base_width` or `flank_angle`),
/// checked against the crest (`b_top`) and the neighbouring ribs (spacing
/// `c`, angle `beta`), m.
fn rib_base_width(raw: &RawRibs, a: f64, c: f64, beta: f64, b_top: f64) -> Result<f64, SpecError> {
    let b_base = match (&raw.base_width, &raw.flank_angle) {
        (Some(_), Some(_)) => {
            return Err(SpecError::Inconsistent {
                key: "bar.ribs.flank_angle".into(),
                problem: "given together with bar.ribs.base_width; the flank angle sets the \
                          base width (b_top + 2 a / tan(flank_angle)): give one of them"
                    .into(),
            })
        }
        (_, Some(q)) => {
            let alpha = angle(q, "bar.ribs.flank_angle")?;
            bound(
                "bar.ribs.flank_angle",
                alpha,
                Dim::Angle,
                alpha > 0.0 && alpha <= FRAC_PI_2 * (1.0 + 1e-12),
                "in (0, 90] deg (90 = flanks perpendicular to the core)",
            )?;
            // cos/sin rather than 1/tan: exactly b_top at 90°.
            let alpha = alpha.min(FRAC_PI_2);
            b_top + 2.0 * a * alpha.cos() / alpha.sin()
        }
        (raw_base, None) => len(raw_base, "bar.ribs.base_width", b_top + 2.0 * a)?,
    };
    // A base width derived from the flank angle is reported as such.
    let base_key = if raw.flank_angle.is_some() {
        "bar.ribs.base_width (b_top + 2a / tan(bar.ribs.flank_angle))"
    } else {
        "bar.ribs.base_width"
    };
    positive(base_key, b_base)?;
    bound(
        base_key,
        b_base,
        Dim::Length,
        b_base >= b_top,
        format!(
            ">= bar.ribs.top_width = {} (isosceles trapezoid, crest not wider than base)",
            mm(b_top)
        ),
    )?;
    let gap_limit = c * beta.sin();
    bound(
        base_key,
        b_base,
        Dim::Length,
        b_base < 0.98 * gap_limit,
        format!(
            "< 0.98 c sin(beta) = {} (neighbouring ribs would overlap: c = {}, beta = {} deg; \
             narrow the ribs or raise bar.ribs.spacing or bar.ribs.angle)",
            mm(0.98 * gap_limit),
            mm(c),
            beta.to_degrees()
        ),
    )?;
    Ok(b_base)
}

/// `bar.longitudinal_ribs` on a core of radius `r` whose transverse ribs
/// are `a` high with crests `b_top` wide (the defaults follow them).
fn resolve_longitudinal_ribs(
    raw_l: &RawLongitudinalRibs,
    r: f64,
    a: f64,
    b_top: f64,
) -> Result<LongitudinalRibs, SpecError> {
    let a_l = len(&raw_l.height, "bar.longitudinal_ribs.height", a)?;
    positive("bar.longitudinal_ribs.height", a_l)?;
    bound(
        "bar.longitudinal_ribs.height",
        a_l,
        Dim::Length,
        a_l < r,
        format!("< d/2 = {} (ribs taller than the core radius)", mm(r)),
    )?;
    bound(
        "bar.longitudinal_ribs.height",
        a_l,
        Dim::Length,
        a_l >= a,
        format!(
            ">= bar.ribs.height = {} (transverse ribs end inside the longitudinal ribs)",
            mm(a)
        ),
    )?;
    let bl_top = len(&raw_l.top_width, "bar.longitudinal_ribs.top_width", b_top)?;
    positive("bar.longitudinal_ribs.top_width", bl_top)?;
    let bl_base = len(
        &raw_l.base_width,
        "bar.longitudinal_ribs.base_width",
        bl_top + 2.0 * a_l,
    )?;
    positive("bar.longitudinal_ribs.base_width", bl_base)?;
    bound(
        "bar.longitudinal_ribs.base_width",
        bl_base,
        Dim::Length,
        bl_base >= bl_top,
        format!(">= bar.longitudinal_ribs.top_width = {}", mm(bl_top)),
    )?;
    bound(
        "bar.longitudinal_ribs.base_width",
        bl_base,
        Dim::Length,
        bl_base <= r,
        format!("<= d/2 = {} (leaves room for the transverse ribs)", mm(r)),
    )?;
    Ok(LongitudinalRibs {
        height: a_l,
        top_width: bl_top,
        base_width: bl_base,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn try_resolve(bar: &str, specimen: &str) -> Result<(Bar, Specimen), SpecError> {
        let bar: RawBar = serde_yaml::from_str(bar).unwrap();
        let sp: RawSpecimen = serde_yaml::from_str(specimen).unwrap();
        resolve(&bar, &sp)
    }

    fn err(bar: &str, specimen: &str) -> String {
        try_resolve(bar, specimen).unwrap_err().to_string()
    }

    /// Defaults follow SPEC §2 (L = 10 d, l_adh = L/2) and SPEC §3 (a = 0.065 d, β = 55°).
    #[test]
    fn defaults_follow_the_spec() {
        let (bar, sp) = try_resolve("{kind: ribbed, diameter: 16 mm}", "{}").unwrap();
        assert!((sp.cube_side - 0.16).abs() < 1e-15 && (sp.adhesive_length - 0.08).abs() < 1e-15);
        let t = bar.ribs.unwrap().transverse;
        assert!((t.height - 1.04e-3).abs() < 1e-15 && (t.angle - 55f64.to_radians()).abs() < 1e-15);
        assert_eq!(t.side_b, SideB::Rotated);
    }

    /// Every out-of-range parameter names its dotted key, its value and the bound (SPEC §3, §8).
    #[test]
    fn violations_name_the_key_value_and_bound() {
        let ribbed = |ribs: &str| format!("{{kind: ribbed, diameter: 8 mm, ribs: {ribs}}}");
        let cases = [
            (ribbed("{height: 5 mm}"), "{}", "bar.ribs.height", "< d/2"),
            (ribbed("{height: -1 mm}"), "{}", "bar.ribs.height", "> 0"),
            (ribbed("{spacing: 0}"), "{}", "bar.ribs.spacing", "> 0"),
            (
                ribbed("{spacing: 2 mm}"),
                "{}",
                "bar.ribs.base_width",
                "overlap",
            ),
            (ribbed("{angle: 0 deg}"), "{}", "bar.ribs.angle", "(0, 90]"),
            (ribbed("{angle: 95 deg}"), "{}", "bar.ribs.angle", "(0, 90]"),
            (
                ribbed("{top_width: 2 mm, base_width: 1 mm}"),
                "{}",
                "bar.ribs.base_width",
                ">= bar.ribs.top_width",
            ),
            (
                ribbed("{phase: 9 mm}"),
                "{}",
                "bar.ribs.phase",
                "[0, bar.ribs.spacing",
            ),
            (
                "{kind: ribbed, diameter: 8 mm, longitudinal_ribs: {height: 0.3 mm}}".into(),
                "{}",
                "bar.longitudinal_ribs.height",
                ">= bar.ribs.height",
            ),
            (
                "{kind: ribbed, diameter: 8 mm, longitudinal_ribs: {base_width: 5 mm}}".into(),
                "{}",
                "bar.longitudinal_ribs.base_width",
                "<= d/2",
            ),
            (
                "{kind: smooth, diameter: -8 mm}".into(),
                "{}",
                "bar.diameter",
                "> 0",
            ),
            (
                "{kind: smooth, diameter: 8 mm}".into(),
                "{adhesive_length: 90 mm}",
                "specimen.adhesive_length",
                "<= specimen.cube_side",
            ),
            (
                "{kind: smooth, diameter: 8 mm}".into(),
                "{free_overhang: -1 mm}",
                "specimen.free_overhang",
                ">= 0",
            ),
            (
                "{kind: smooth, diameter: 8 mm}".into(),
                "{loaded_overhang: -1 mm}",
                "specimen.loaded_overhang",
                ">= 0",
            ),
            (
                "{kind: ribbed, diameter: 8 mm}".into(),
                "{cube_side: 9 mm}",
                "specimen.cube_side",
                "wider than the bar",
            ),
            (
                "{kind: smooth, diameter: 8 mm, ribs: {}}".into(),
                "{}",
                "bar.ribs",
                "smooth bar",
            ),
            (
                "{kind: smooth, diameter: 8 MPa}".into(),
                "{}",
                "bar.diameter",
                "MPa",
            ),
        ];
        for (bar, sp, key, bound) in cases {
            let msg = err(&bar, sp);
            assert!(
                msg.contains(key) && msg.contains(bound),
                "{bar} {sp}: {msg}"
            );
        }
        // The value is shown with its unit.
        let msg = err(&ribbed("{height: 5 mm}"), "{}");
        assert!(msg.contains("5 mm"), "{msg}");
    }

    /// A plain number above π/2 for an angle is taken for degrees given without unit: the error suggests "deg" (SPEC §2 units).
    #[test]
    fn plain_angle_above_right_angle_suggests_degrees() {
        let msg = err("{kind: ribbed, diameter: 8 mm, ribs: {angle: 55}}", "{}");
        assert!(
            msg.contains("bar.ribs.angle") && msg.contains("\"55 deg\""),
            "{msg}"
        );
        assert!(try_resolve("{kind: ribbed, diameter: 8 mm, ribs: {angle: 1.0}}", "{}").is_ok());
    }

    /// Unknown keys are rejected at parse time (SPEC §8).
    #[test]
    fn unknown_keys_are_rejected() {
        assert!(
            serde_yaml::from_str::<RawBar>("{kind: smooth, diameter: 8 mm, colour: red}").is_err()
        );
        assert!(serde_yaml::from_str::<RawRibs>("{hieght: 1 mm}").is_err());
        assert!(serde_yaml::from_str::<RawSpecimen>("{cube: 1}").is_err());
    }

    /// `specimen.symmetry: auto` models a quarter of a smooth bar's
    /// specimen and the half-turn half of a (default: spiral, no phase)
    /// ribbed one's; `full` is honoured for both (issue 7: symmetry on by
    /// default for smooth bars; issue 14: for ribbed bars).
    #[test]
    fn symmetry_auto_is_quarter_for_smooth_half_for_ribbed() {
        let smooth = "{kind: smooth, diameter: 8 mm}";
        let ribbed = "{kind: ribbed, diameter: 8 mm}";
        assert_eq!(
            try_resolve(smooth, "{}").unwrap().1.symmetry,
            Symmetry::Quarter
        );
        assert_eq!(
            try_resolve(ribbed, "{}").unwrap().1.symmetry,
            Symmetry::HalfTurn
        );
        let full = try_resolve(smooth, "{symmetry: full}").unwrap().1;
        assert_eq!(full.symmetry, Symmetry::Full);
        assert_eq!(full.symmetry.fraction(), 1.0);
        let q = try_resolve(smooth, "{symmetry: quarter}").unwrap().1;
        assert_eq!(q.symmetry.fraction(), 0.25);
        assert_eq!(
            try_resolve(ribbed, "{symmetry: full}").unwrap().1.symmetry,
            Symmetry::Full
        );
        // The resolved choice is what gets hashed: it serialises by name.
        let json = serde_json::to_value(&q).unwrap();
        assert_eq!(json["symmetry"], "quarter");
    }

    /// `auto` and `half` model the half y ≥ 0 of a herringbone bar without
    /// phase (its one mirror plane is that of the longitudinal ribs) and
    /// the half-turn half of a spiral one; `auto` models a bar with a phase
    /// whole, and `half` there is refused naming the key and the reason
    /// (issue 14).
    #[test]
    fn symmetry_half_only_for_a_symmetric_half() {
        let hb = "{kind: ribbed, diameter: 8 mm, ribs: {side_b: mirrored}}";
        let hb_phase = "{kind: ribbed, diameter: 8 mm, ribs: {side_b: mirrored, phase: 1 mm}}";
        let spiral = "{kind: ribbed, diameter: 8 mm, ribs: {side_b: rotated}}";
        let spiral_phase = "{kind: ribbed, diameter: 8 mm, ribs: {side_b: rotated, phase: 1 mm}}";
        let smooth = "{kind: smooth, diameter: 8 mm}";
        let sym = |bar: &str, sp: &str| try_resolve(bar, sp).unwrap().1.symmetry;
        assert_eq!(sym(hb, "{}"), Symmetry::Half);
        assert_eq!(sym(hb, "{symmetry: half}"), Symmetry::Half);
        assert_eq!(sym(hb, "{symmetry: full}"), Symmetry::Full);
        assert_eq!(sym(hb_phase, "{}"), Symmetry::Full);
        assert_eq!(sym(spiral_phase, "{}"), Symmetry::Full);
        assert_eq!(sym(spiral, "{}"), Symmetry::HalfTurn);
        assert_eq!(sym(spiral, "{symmetry: half}"), Symmetry::HalfTurn);
        assert_eq!(sym(smooth, "{symmetry: half}"), Symmetry::Half);
        assert_eq!(Symmetry::Half.fraction(), 0.5);
        assert_eq!(Symmetry::HalfTurn.fraction(), 0.5);
        for (bar, why) in [
            (spiral_phase, "half-turn images"),
            (hb_phase, "mirror images"),
        ] {
            let msg = err(bar, "{symmetry: half}");
            assert!(
                msg.contains("specimen.symmetry")
                    && msg.contains(why)
                    && msg.contains("bar.ribs.phase"),
                "{msg}"
            );
        }
        let msg = err(hb, "{symmetry: quarter}");
        assert!(
            msg.contains("specimen.symmetry") && msg.contains("use half"),
            "{msg}"
        );
    }

    /// A quarter model of a ribbed bar is rejected naming `specimen.symmetry` and why (spiral ribs have no mirror planes; SPEC §8).
    #[test]
    fn quarter_ribbed_bar_is_rejected() {
        let msg = err("{kind: ribbed, diameter: 8 mm}", "{symmetry: quarter}");
        assert!(
            msg.contains("specimen.symmetry")
                && msg.contains("smooth bar")
                && msg.contains("mirror"),
            "{msg}"
        );
        assert!(serde_yaml::from_str::<RawSpecimen>("{symmetry: eighth}").is_err());
    }

    /// `bar.ribs.flank_angle` sets b_base = b_top + 2a / tan α (90° gives b_top); it excludes `base_width`, and
    /// out-of-range or overlapping results name the flank angle (issue 15: flank angle 30–60°).
    #[test]
    fn flank_angle_sets_the_base_width() {
        let ribs = |r: &str| {
            try_resolve(
                &format!("{{kind: ribbed, diameter: 10 mm, ribs: {r}}}"),
                "{}",
            )
        };
        let base = |r: &str| ribs(r).unwrap().0.ribs.unwrap().transverse.base_width;
        // a = 0.65 mm, b_top = 1 mm by default.
        let at30 = base("{flank_angle: 30 deg}");
        assert!(
            (at30 - (1e-3 + 2.0 * 0.65e-3 * 3f64.sqrt())).abs() < 1e-12,
            "{at30}"
        );
        assert!((base("{flank_angle: 45 deg}") - base("{}")).abs() < 1e-12);
        assert_eq!(base("{flank_angle: 90 deg}"), 1e-3);
        let msg = ribs("{flank_angle: 40 deg, base_width: 2 mm}")
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("bar.ribs.flank_angle") && msg.contains("base_width"),
            "{msg}"
        );
        for bad in ["0 deg", "100 deg"] {
            let msg = ribs(&format!("{{flank_angle: {bad}}}"))
                .unwrap_err()
                .to_string();
            assert!(
                msg.contains("bar.ribs.flank_angle") && msg.contains("(0, 90]"),
                "{msg}"
            );
        }
        let msg = ribs("{flank_angle: 30 deg, height: 1.5 mm, spacing: 4 mm, angle: 35 deg}")
            .unwrap_err()
            .to_string();
        assert!(
            msg.contains("flank_angle") && msg.contains("overlap"),
            "{msg}"
        );
    }

    /// l_adh = L is allowed (SPEC §2: l_adh ≤ L).
    #[test]
    fn adhesive_length_may_equal_the_cube_side() {
        let (_, sp) = try_resolve(
            "{kind: smooth, diameter: 10 mm}",
            "{cube_side: 125 mm, adhesive_length: 125 mm}",
        )
        .unwrap();
        assert_eq!(sp.adhesive_length, sp.cube_side);
    }
}
