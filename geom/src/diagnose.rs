//! Naming what gmsh could not mesh, in the specimen's terms.
//!
//! gmsh reports a failure by entity tag ("Impossible to mesh periodic
//! surface 75", "Invalid boundary mesh (overlapping facets) on surface 12
//! surface 13"). Those tags mean nothing to the user, so
//! [`entities_in_gmsh_output`] picks them out of gmsh's error lines,
//! [`query_entities`] rebuilds the model from the same `.geo` (tags are
//! deterministic) and measures each entity through gmsh's Python API, and
//! [`diagnose`] says where it is on the bar (which transverse rib, the core
//! between which ribs, which cut plane), what is wrong with it (a sliver
//! narrower than the mesh size, a boundary that does not close in gmsh's
//! parameter space) and what to change.

use crate::gmsh::{Gmsh, GmshError};
use crate::layout::Layout;
use serde::Deserialize;
use std::f64::consts::PI;
use std::fmt;
use std::path::Path;
use std::time::Duration;

/// Time allowed for rebuilding the model and measuring the entities.
const QUERY_TIMEOUT: Duration = Duration::from_secs(600);

/// A face narrower than this fraction of the mesh size is a sliver for the mesher.
const SLIVER_FRACTION_OF_H: f64 = 0.2;

/// A gmsh model entity: dimension (1 curve, 2 surface, 3 volume) and tag.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EntityRef {
    pub dim: i32,
    pub tag: i32,
}

impl fmt::Display for EntityRef {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let kind = match self.dim {
            0 => "point",
            1 => "curve",
            2 => "surface",
            _ => "volume",
        };
        write!(f, "{kind} {}", self.tag)
    }
}

/// The entities named on gmsh's `Error` lines, in order of first mention.
/// "No elements in …" warnings and the error summary are consequences, not
/// causes, and are not read.
pub fn entities_in_gmsh_output(text: &str) -> Vec<EntityRef> {
    let mut out: Vec<EntityRef> = vec![];
    for line in text.lines().flat_map(|l| l.split('\r')) {
        let Some(msg) = line.strip_prefix("Error") else {
            continue;
        };
        let words: Vec<&str> = msg
            .split(|c: char| c.is_whitespace() || c == ',' || c == ':' || c == '(' || c == ')')
            .filter(|w| !w.is_empty())
            .collect();
        for (i, w) in words.iter().enumerate() {
            let dim = match w.to_ascii_lowercase().as_str() {
                "curve" | "curves" => 1,
                "surface" | "surfaces" => 2,
                "volume" | "volumes" => 3,
                _ => continue,
            };
            // "surface 75", and lists such as "surface 75 113".
            for t in words[i + 1..].iter().map_while(|t| t.parse::<i32>().ok()) {
                let e = EntityRef { dim, tag: t };
                if !out.contains(&e) {
                    out.push(e);
                }
            }
        }
    }
    out
}

/// The worst gap, in a periodic face's parameter space, between the ends of
/// two boundary curves that meet at one point of the model.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct ParametricGap {
    /// The model point (gmsh tag) where the curve ends disagree.
    pub point: i32,
    /// Distance between the two parameter-space ends (angle in rad, height in model units).
    pub gap: f64,
    /// gmsh's first tolerance for chaining the boundary: 1e-6 of the
    /// diagonal of the face's parameter range.
    pub tolerance: f64,
}

/// What gmsh's Python API says of one entity, lengths in m.
#[derive(Debug, Clone, PartialEq, Deserialize)]
pub struct EntityFacts {
    pub dim: i32,
    pub tag: i32,
    /// gmsh's type name: "Cylinder", "Plane", "BSpline surface", "Line", …
    pub kind: String,
    /// Bounding box x0, y0, z0, x1, y1, z1, m.
    pub bbox: [f64; 6],
    /// Area (surface), length (curve) or volume, SI.
    pub measure: f64,
    /// A point on the entity near its centre of mass, m.
    pub centre: [f64; 3],
    /// Surfaces: boundary length, m.
    #[serde(default)]
    pub perimeter: f64,
    /// Surfaces: the shortest boundary curve, m.
    #[serde(default)]
    pub shortest_curve: f64,
    /// Physical groups of the volumes the entity bounds ("steel", "concrete").
    #[serde(default)]
    pub materials: Vec<String>,
    /// Periodic surfaces (cylinders): the worst boundary gap.
    #[serde(default)]
    pub parametric_gap: Option<ParametricGap>,
}

impl EntityFacts {
    pub fn entity(&self) -> EntityRef {
        EntityRef {
            dim: self.dim,
            tag: self.tag,
        }
    }

    /// Typical width of a surface, m: 2 area / perimeter (the width of a
    /// long strip, the radius of a disc).
    pub fn width(&self) -> f64 {
        if self.dim == 2 && self.perimeter > 0.0 {
            2.0 * self.measure / self.perimeter
        } else {
            self.measure
        }
    }
}

/// Python (gmsh API) shared by the measurement of the built model (`crate::occ`) and the
/// failure diagnosis: `parametric_gap(tag)` is the worst gap, in the
/// parameter space of periodic surface `tag`, between the ends of two of its
/// boundary curves at one model point (a [`ParametricGap`] as a dict), and
/// `PERIODIC` the gmsh type names of surfaces meshed as periodic.
pub(crate) const PARAMETRIC_GAP_PY: &str = r#"
import math
import gmsh
PERIODIC = ("Cylinder", "Cone", "Sphere", "Torus", "SurfaceOfRevolution")
def parametric_gap(tag):
    # gmsh chains a periodic face's boundary in its (u, v) space with the
    # tolerance 1e-6 * diagonal of the face's parameter range (meshGFace.cpp).
    lo, hi = gmsh.model.getParametrizationBounds(2, tag)
    tol = 1e-6 * math.hypot(hi[0] - lo[0], hi[1] - lo[1])
    ends = {}
    for t in (int(c) for c in gmsh.model.getAdjacencies(2, tag)[1]):
        clo, chi = gmsh.model.getParametrizationBounds(1, t)
        pts = gmsh.model.getAdjacencies(1, t)[1]
        if len(pts) != 2:
            continue
        for p, u in zip(pts, (clo[0], chi[0])):
            ends.setdefault(int(p), []).append(gmsh.model.reparametrizeOnSurface(1, t, [u], tag))
    worst = {"point": 0, "gap": 0.0, "tolerance": tol}
    for p, uvs in ends.items():
        for i in range(len(uvs)):
            for j in range(i + 1, len(uvs)):
                du = abs(uvs[i][0] - uvs[j][0])
                du = min(du, abs(du - 2 * math.pi))  # a seam point sits at u and u + 2 pi
                g = math.hypot(du, uvs[i][1] - uvs[j][1])
                if g > worst["gap"]:
                    worst = {"point": p, "gap": g, "tolerance": tol}
    return worst
"#;

const QUERY_PY: &str = r#"
import json, math, sys
import gmsh
geo, out = sys.argv[1], sys.argv[2]
wanted = [(int(a), int(b)) for a, b in (s.split(":") for s in sys.argv[3:])]
gmsh.initialize(["-noenv"], interruptible=False)
gmsh.option.setNumber("General.Terminal", 0)
gmsh.open(geo)
try:
    per_m = gmsh.parser.getNumber("model_per_m")[0]
except Exception:
    per_m = 1.0
names = {}
for dim, tag in gmsh.model.getPhysicalGroups(3):
    for e in gmsh.model.getEntitiesForPhysicalGroup(dim, tag):
        names[int(e)] = gmsh.model.getPhysicalName(dim, tag)
def volumes_of(dim, tag):
    if dim == 3:
        return [tag]
    up = list(gmsh.model.getAdjacencies(dim, tag)[0])
    return sorted(set(v for s in up for v in volumes_of(dim + 1, int(s)))) if dim < 2 else [int(v) for v in up]
res = []
for dim, tag in wanted:
    if (dim, tag) not in gmsh.model.getEntities(dim):
        continue
    f = {"dim": dim, "tag": tag, "kind": gmsh.model.getType(dim, tag)}
    f["bbox"] = [v / per_m for v in gmsh.model.getBoundingBox(dim, tag)]
    f["measure"] = gmsh.model.occ.getMass(dim, tag) / per_m ** dim
    c = gmsh.model.occ.getCenterOfMass(dim, tag)
    if dim < 3:
        c = gmsh.model.getClosestPoint(dim, tag, c)[0]
    f["centre"] = [v / per_m for v in c]
    f["materials"] = sorted(set(names.get(v, "?") for v in volumes_of(dim, tag)))
    if dim == 2:
        curves = [int(t) for t in gmsh.model.getAdjacencies(2, tag)[1]]
        lengths = [gmsh.model.occ.getMass(1, t) / per_m for t in curves]
        f["perimeter"] = sum(lengths)
        f["shortest_curve"] = min(lengths) if lengths else 0.0
        if f["kind"] in PERIODIC:
            f["parametric_gap"] = parametric_gap(tag)
    res.append(f)
with open(out, "w") as fh:
    json.dump(res, fh)
gmsh.finalize()
"#;

/// Rebuilds the model of `geo` in gmsh and measures `entities` (those
/// that exist in it), in SI units whatever the script's model units.
pub fn query_entities(
    gmsh: &Gmsh,
    geo: &Path,
    entities: &[EntityRef],
) -> Result<Vec<EntityFacts>, GmshError> {
    let geo = std::path::absolute(geo).map_err(|source| GmshError::Io {
        path: geo.to_path_buf(),
        source,
    })?;
    let dir = geo.parent().unwrap_or(Path::new(".")).to_path_buf();
    let out = dir.join(format!(".gmsh-diagnosis-{}.json", std::process::id()));
    let mut args = vec![geo.display().to_string(), out.display().to_string()];
    args.extend(entities.iter().map(|e| format!("{}:{}", e.dim, e.tag)));
    let script = format!("{PARAMETRIC_GAP_PY}{QUERY_PY}");
    let run = gmsh.run_python(&script, &args, &dir, QUERY_TIMEOUT);
    let text = run.and_then(|_| {
        std::fs::read_to_string(&out).map_err(|source| GmshError::Io {
            path: out.clone(),
            source,
        })
    });
    let _ = std::fs::remove_file(&out);
    let text = text?;
    serde_json::from_str(&text).map_err(|e| GmshError::Io {
        path: out,
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, e),
    })
}

/// One entity gmsh could not mesh, in the specimen's terms.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnosis {
    pub entity: EntityRef,
    /// Where it is: "core surface between transverse ribs 3 and 4 of side A (z 0.0–8.5 mm, θ 13–120°)".
    pub location: String,
    /// What is wrong with it, or what was measured when nothing stands out.
    pub problem: String,
    /// What to change in the spec.
    pub remedy: String,
}

impl fmt::Display for Diagnosis {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{}: {}; {}; likely remedy: {}",
            self.entity, self.location, self.problem, self.remedy
        )
    }
}

fn mm(v: f64) -> String {
    let v = v * 1e3;
    if v.abs() >= 0.1 {
        format!("{v:.2} mm")
    } else {
        format!("{v:.3} mm")
    }
}

/// Where a point of the bar's surface lies with respect to the ribs.
enum RibSite {
    /// On the longitudinal rib at θ = 0 (side 0) or π (side 1).
    Longitudinal(usize),
    /// On transverse rib `rib` (0-based from the free end) of `side`.
    Rib { side: usize, rib: usize },
    /// On the core between ribs `below` and `below + 1` of `side`
    /// (`below` = None: before the first rib).
    Between { side: usize, below: Option<usize> },
}

fn rib_site(layout: &Layout, p: [f64; 3]) -> Option<RibSite> {
    let rl = layout.ribs.as_ref()?;
    let theta = p[1].atan2(p[0]).rem_euclid(2.0 * PI);
    let (side, t) = if theta < PI {
        (0, theta)
    } else {
        (1, theta - PI)
    };
    if t < rl.phi_base || t > PI - rl.phi_base {
        let at_pi = (theta - PI).abs() < PI / 2.0;
        return Some(RibSite::Longitudinal(usize::from(at_pi)));
    }
    let zs = &rl.sides[side].zeta;
    let zeta = p[2] - rl.sides[side].sign * rl.k * t.cos();
    let first = *zs.first()?;
    let pos = (zeta - first) / rl.c;
    let nearest = pos.round();
    if nearest >= 0.0 && (nearest as usize) < zs.len() {
        let rib = nearest as usize;
        if (zeta - zs[rib]).abs() <= 0.5 * rl.wb * (1.0 + 1e-6) {
            return Some(RibSite::Rib { side, rib });
        }
    }
    let below = pos.floor();
    Some(RibSite::Between {
        side,
        below: (below >= 0.0).then_some(below as usize),
    })
}

fn side_name(side: usize) -> &'static str {
    if side == 0 {
        "side A (θ 0–180°, ribs counted from the free end)"
    } else {
        "side B (θ 180–360°, ribs counted from the free end)"
    }
}

/// The cut planes of the specimen (z = 0, l_adh, L) and the bar ends.
fn planes(layout: &Layout) -> Vec<(f64, &'static str)> {
    let mut p = vec![
        (layout.z_lo, "the bar's free end"),
        (0.0, "the free face z = 0"),
        (layout.l, "the loaded face z = L"),
        (layout.z_hi, "the bar's loaded end"),
    ];
    if layout.l_adh < layout.l {
        p.push((layout.l_adh, "the plane z = l_adh (adhesive/free boundary)"));
    }
    p
}

/// Where the entity is, in words.
fn locate(layout: &Layout, f: &EntityFacts) -> String {
    let b = f.bbox;
    // + 0.0 turns −0 into 0 for display.
    let span = format!("z {:.2}–{:.2} mm", b[2] * 1e3 + 0.0, b[5] * 1e3 + 0.0);
    let r_bar = layout.outer_radius() * 1.05;
    let on_bar = b[0] >= -r_bar && b[3] <= r_bar && b[1] >= -r_bar && b[4] <= r_bar;
    if !on_bar {
        return format!("{} face of the concrete cube, {span}", f.kind);
    }
    let flat_z = b[5] - b[2] < 1e-9;
    if flat_z && f.dim == 2 {
        let name = planes(layout)
            .into_iter()
            .min_by(|p, q| (p.0 - b[2]).abs().total_cmp(&(q.0 - b[2]).abs()))
            .map_or("a cross-section", |p| p.1);
        return format!("bar cross-section in {name} (z {:.2} mm)", b[2] * 1e3);
    }
    let what = match (f.dim, f.kind.as_str()) {
        (2, "Cylinder") => "core surface",
        (2, "Plane") => "longitudinal-rib face",
        (2, k) if k.contains("BSpline") || k.contains("Bezier") => "transverse-rib face",
        (2, _) => "bar surface",
        (1, _) => "curve of the bar surface",
        _ => "steel volume",
    };
    let site = match rib_site(layout, f.centre) {
        None => String::new(),
        Some(RibSite::Longitudinal(s)) => {
            format!(
                " on the longitudinal rib at θ = {}°",
                if s == 0 { 0 } else { 180 }
            )
        }
        Some(RibSite::Rib { side, rib }) => {
            format!(" of transverse rib {} of {}", rib + 1, side_name(side))
        }
        Some(RibSite::Between { side, below }) => match below {
            Some(k) => format!(
                " between transverse ribs {} and {} of {}",
                k + 1,
                k + 2,
                side_name(side)
            ),
            None => format!(" before the first transverse rib of {}", side_name(side)),
        },
    };
    format!("{what}{site}, {span}")
}

/// The cut plane or bar end the entity touches, if any.
fn touched_plane(layout: &Layout, f: &EntityFacts) -> Option<(f64, &'static str)> {
    let tol = 1e-6 * layout.l;
    planes(layout)
        .into_iter()
        .find(|(z, _)| (f.bbox[2] - z).abs() < tol || (f.bbox[5] - z).abs() < tol)
}

/// Explains each entity of `facts` for the specimen of `layout` meshed at
/// `h_interface` (m).
pub fn diagnose(layout: &Layout, facts: &[EntityFacts], h_interface: f64) -> Vec<Diagnosis> {
    facts
        .iter()
        .map(|f| {
            let location = locate(layout, f);
            let width = f.width();
            // Gap between neighbouring ribs at mid-rib, c sin β − b_base
            // (K = R cot β, axial widths are the widths over sin β).
            let rib_gap = layout.ribs.as_ref().map(|rl| {
                let sin_beta = (layout.r / rl.k.hypot(layout.r)).min(1.0);
                (rl.c - rl.wb) * sin_beta
            });
            if let Some(g) = f.parametric_gap.as_ref().filter(|g| g.gap > g.tolerance) {
                return Diagnosis {
                    entity: f.entity(),
                    location,
                    problem: format!(
                        "its boundary does not close in gmsh's parameter space: the curves meeting \
                         at point {} end {:.2e} apart, {:.1} times gmsh's tolerance ({:.2e}), so \
                         the periodic-surface mesher cannot chain them",
                        g.point,
                        g.gap,
                        g.gap / g.tolerance,
                        g.tolerance
                    ),
                    remedy: "shift the rib pattern slightly (bar.ribs.phase, or bar.ribs.spacing \
                             by a few %): the gap comes from OpenCASCADE's approximation of where \
                             a rib meets the core, which depends on the rib's exact position"
                        .into(),
                };
            }
            let problem;
            let remedy;
            if f.dim == 2 && width < SLIVER_FRACTION_OF_H * h_interface {
                problem = format!(
                    "a sliver about {} wide (2 area / perimeter; shortest edge {}) against \
                     mesh.h_interface = {}",
                    mm(width),
                    mm(f.shortest_curve),
                    mm(h_interface)
                );
                remedy = match (touched_plane(layout, f), rib_gap) {
                    (Some((z, name)), _) => format!(
                        "move the rib pattern off {name} (z = {}): change bar.ribs.phase or \
                         bar.ribs.spacing slightly, or the specimen length that puts the plane \
                         there; or lower mesh.h_interface towards {}",
                        mm(z),
                        mm(width / SLIVER_FRACTION_OF_H)
                    ),
                    (None, Some(gap)) if gap < SLIVER_FRACTION_OF_H * h_interface => {
                        format!(
                            "neighbouring ribs nearly touch (gap c sin β − b_base = {} at \
                             mid-rib): raise bar.ribs.spacing or narrow the ribs \
                             (bar.ribs.base_width / flank_angle), or lower mesh.h_interface \
                             towards {}",
                            mm(gap),
                            mm(width / SLIVER_FRACTION_OF_H)
                        )
                    }
                    _ => format!(
                        "lower mesh.h_interface towards {}",
                        mm(width / SLIVER_FRACTION_OF_H)
                    ),
                };
            } else {
                problem = format!(
                    "no thin feature found (width about {}, shortest edge {}, mesh.h_interface = {})",
                    mm(width),
                    mm(f.shortest_curve),
                    mm(h_interface)
                );
                remedy = "retry with mesh.algorithm_3d: delaunay, or a slightly different \
                          mesh.h_interface; report the design if it persists"
                    .into();
            }
            Diagnosis {
                entity: f.entity(),
                location,
                problem,
                remedy,
            }
        })
        .collect()
}
