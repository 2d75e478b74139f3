//! The geometry stage: `specimen.geo` + `geometry.json`, with the solid built
//! by gmsh and measured three ways (analytic, parry3d, gmsh OCC).

use crate::geo::{groups, write_geo};
use crate::gmsh::{Gmsh, GmshError};
use crate::layout::Layout;
use crate::metrics::{analytic, tessellated, Metrics};
use crate::spec::{Bar, Specimen, Symmetry};
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Relative agreement required between the three measurements.
pub const CHECK_TOLERANCE: f64 = 0.01;
/// Time allowed for gmsh to build and measure the solid.
pub const GMSH_TIMEOUT: Duration = Duration::from_secs(600);

/// One quantity measured three ways.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Check {
    pub analytic: f64,
    pub parry3d: f64,
    pub gmsh_occ: f64,
    /// Largest |x − analytic| / |analytic| over the two numerical values.
    pub max_rel_diff: f64,
    /// `max_rel_diff` ≤ 1 %.
    pub agree: bool,
}

impl Check {
    fn new(analytic: f64, parry3d: f64, gmsh_occ: f64) -> Check {
        let scale = analytic.abs().max(f64::MIN_POSITIVE);
        let max_rel_diff =
            ((parry3d - analytic).abs() / scale).max((gmsh_occ - analytic).abs() / scale);
        Check {
            analytic,
            parry3d,
            gmsh_occ,
            max_rel_diff,
            agree: max_rel_diff <= CHECK_TOLERANCE,
        }
    }
}

/// Everything `geometry.json` holds. The metrics describe the whole
/// specimen even when only a part of it is modelled, so reports of full and
/// quarter runs compare.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GeometryReport {
    /// The modelled part: `"full"`, `"half"` (y ≥ 0) or `"quarter"` (x ≥ 0, y ≥ 0).
    pub symmetry: Symmetry,
    /// Modelled volume per whole-specimen volume (1, 0.5 or 0.25).
    pub modelled_fraction: f64,
    #[serde(rename = "f_R")]
    pub f_r: f64,
    pub rib_volume_m3: f64,
    pub bar_volume_m3: f64,
    pub interface_area_adhesive_m2: f64,
    pub interface_area_free_m2: f64,
    pub rib_count: usize,
    /// rib_volume_m3 (ribbed bars only), bar_volume_m3, interface areas;
    /// `gmsh_occ` is the modelled part's measure divided by
    /// `modelled_fraction` (whole-specimen equivalent).
    pub checks: BTreeMap<String, Check>,
    /// Smallest axial distance from the planes z = 0, l_adh, L to a rib edge feature, m.
    pub plane_clearance_m: Option<f64>,
    /// Smallest axial distance from the bar end planes to a rib edge feature, m.
    pub end_clearance_m: Option<f64>,
    /// Entities per physical group in the built model.
    pub group_entities: BTreeMap<String, usize>,
    /// The worst-closing periodic face (None for a model without one).
    pub periodic_face_gap: Option<PeriodicFaceGap>,
    /// Triangles of the parry3d tessellation.
    pub tessellation_triangles: usize,
    pub gmsh_version: String,
    /// Wall time gmsh took to build and measure the solid, s.
    pub gmsh_build_seconds: f64,
    pub bar: Bar,
    pub specimen: Specimen,
}

/// Why the geometry stage failed.
#[derive(Debug, thiserror::Error)]
pub enum GeomError {
    #[error(transparent)]
    Gmsh(#[from] GmshError),
    #[error("{path}: {source}", path = .path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("gmsh could not build the specimen from {path}:\n{message}", path = .path.display())]
    Build { path: PathBuf, message: String },
    #[error("gmsh's measurement output is unreadable ({problem}): {text}")]
    Measure { problem: String, text: String },
    #[error("physical group {group:?} is empty in the built model{hint}")]
    EmptyGroup { group: String, hint: String },
    #[error("the built model has {curves} curve(s) and {surfaces} surface(s) not bounding anything (leftover construction entities)")]
    Leftovers { curves: usize, surfaces: usize },
    #[error("{quantity}: analytic {analytic:.6e}, parry3d {parry3d:.6e}, gmsh OCC {gmsh_occ:.6e} differ by {pct:.2} % (> 1 %)")]
    Disagree {
        quantity: String,
        analytic: f64,
        parry3d: f64,
        gmsh_occ: f64,
        pct: f64,
    },
}

const MEASURE_PY: &str = r#"
import json, sys
import gmsh
geo, out, model_per_m = sys.argv[1], sys.argv[2], float(sys.argv[3])
gmsh.initialize(["-noenv"], interruptible=False)
gmsh.option.setNumber("General.Terminal", 0)
gmsh.logger.start()
res = {"errors": [], "groups": {}}
try:
    gmsh.open(geo)
except Exception as e:
    res["errors"].append(str(e))
res["errors"] += [m for m in gmsh.logger.get() if m.startswith("Error")]
if not res["errors"]:
    for dim, tag in gmsh.model.getPhysicalGroups():
        name = gmsh.model.getPhysicalName(dim, tag)
        ents = gmsh.model.getEntitiesForPhysicalGroup(dim, tag)
        # getMass is in model units: back to SI (m^dim).
        res["groups"][name] = {"count": len(ents),
                               "mass": sum(gmsh.model.occ.getMass(dim, int(e)) for e in ents)
                                       / model_per_m ** dim}
    bounded = set(abs(t) for _, t in gmsh.model.getBoundary(gmsh.model.getEntities(2), combined=False, oriented=False))
    res["free_curves"] = len([t for _, t in gmsh.model.getEntities(1) if t not in bounded])
    bounded = set(abs(t) for _, t in gmsh.model.getBoundary(gmsh.model.getEntities(3), combined=False, oriented=False))
    res["free_surfaces"] = len([t for _, t in gmsh.model.getEntities(2) if t not in bounded])
    worst = None
    for _, t in gmsh.model.getEntities(2):
        if gmsh.model.getType(2, t) in PERIODIC:
            g = parametric_gap(t)
            if worst is None or g["gap"] / g["tolerance"] > worst["gap"] / worst["tolerance"]:
                worst = dict(g, surface=t)
    res["periodic_gap"] = worst
with open(out, "w") as f:
    json.dump(res, f)
gmsh.finalize()
"#;

#[derive(serde::Deserialize)]
struct Measured {
    errors: Vec<String>,
    groups: BTreeMap<String, Group>,
    #[serde(default)]
    free_curves: usize,
    #[serde(default)]
    free_surfaces: usize,
    #[serde(default)]
    periodic_gap: Option<PeriodicFaceGap>,
}

/// The periodic (cylindrical) face of the built model whose boundary comes
/// closest to not closing in gmsh's parameter space: gmsh's periodic-face
/// mesher chains the boundary curves with a tolerance of 1e-6 of the face's
/// parameter diagonal, and fails on a face whose curves meet farther apart
/// (the 35° failure before the model was built in millimetres;
/// docs/geometry.md).
#[derive(Debug, Clone, PartialEq, Serialize, serde::Deserialize)]
pub struct PeriodicFaceGap {
    /// gmsh tag of the surface (in the model `specimen.geo` builds).
    pub surface: i32,
    /// gmsh tag of the point where two boundary curves' ends disagree most.
    pub point: i32,
    /// Their distance in the face's parameter space (rad, model units).
    pub gap: f64,
    /// gmsh's first chaining tolerance for the face.
    pub tolerance: f64,
}

impl PeriodicFaceGap {
    /// gap / tolerance: below 1 gmsh chains the boundary at its first try.
    pub fn ratio(&self) -> f64 {
        self.gap / self.tolerance
    }
}

#[derive(serde::Deserialize)]
struct Group {
    count: usize,
    mass: f64,
}

/// Writes `path` atomically: a temporary file in the same directory, renamed.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), GeomError> {
    crate::fsutil::write_atomic(path, bytes).map_err(|source| GeomError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// Analytic and parry3d metrics, no gmsh: what a parameter sweep can afford
/// for every combination.
pub fn offline_metrics(bar: &Bar, specimen: &Specimen) -> (Metrics, crate::metrics::Tessellated) {
    let layout = Layout::new(bar, specimen);
    let m = analytic(&layout);
    let t = tessellated(&layout, &[(0.0, layout.l_adh), (layout.l_adh, layout.l)]);
    (m, t)
}

/// Runs the geometry stage into `out_dir` (created if needed): writes
/// `specimen.geo`, has gmsh build and measure it, then writes
/// `geometry.json`. Fails if gmsh fails or the checks disagree by > 1 %;
/// `geometry.json` is then not written.
pub fn build_geometry(
    bar: &Bar,
    specimen: &Specimen,
    gmsh: &Gmsh,
    out_dir: &Path,
) -> Result<GeometryReport, GeomError> {
    std::fs::create_dir_all(out_dir).map_err(|source| GeomError::Io {
        path: out_dir.to_path_buf(),
        source,
    })?;
    let layout = Layout::new(bar, specimen);
    // An old report beside a new script would look like a finished stage.
    let json_path = out_dir.join("geometry.json");
    if json_path.exists() {
        std::fs::remove_file(&json_path).map_err(|source| GeomError::Io {
            path: json_path.clone(),
            source,
        })?;
    }
    let geo_path = out_dir.join("specimen.geo");
    write_atomic(&geo_path, write_geo(&layout).as_bytes())?;

    let m = analytic(&layout);
    let tess = tessellated(&layout, &[(0.0, layout.l_adh), (layout.l_adh, layout.l)]);

    let (measured, build_seconds) = measure(gmsh, &layout, &geo_path, out_dir)?;
    // OCC measures the modelled part; the checks compare whole-specimen values.
    let fraction = specimen.symmetry.fraction();
    let group_mass = |name: &str| measured.groups.get(name).map_or(0.0, |g| g.mass) / fraction;
    let group_entities = group_counts(&measured, &layout, specimen.symmetry, &geo_path)?;
    let checks = three_way_checks(&layout, &m, &tess, &group_mass);
    for (name, c) in &checks {
        if !c.agree {
            return Err(GeomError::Disagree {
                quantity: name.clone(),
                analytic: c.analytic,
                parry3d: c.parry3d,
                gmsh_occ: c.gmsh_occ,
                pct: 100.0 * c.max_rel_diff,
            });
        }
    }
    let report = GeometryReport {
        symmetry: specimen.symmetry,
        modelled_fraction: fraction,
        f_r: m.f_r,
        rib_volume_m3: m.rib_volume_m3,
        bar_volume_m3: m.bar_volume_m3,
        interface_area_adhesive_m2: m.interface_area_adhesive_m2,
        interface_area_free_m2: m.interface_area_free_m2,
        rib_count: m.rib_count,
        checks,
        plane_clearance_m: layout.ribs.as_ref().map(|r| r.clearance_cube),
        end_clearance_m: layout.ribs.as_ref().map(|r| r.clearance_ends),
        group_entities,
        periodic_face_gap: measured.periodic_gap,
        tessellation_triangles: tess.triangles,
        gmsh_version: gmsh.version().to_string(),
        gmsh_build_seconds: build_seconds,
        bar: bar.clone(),
        specimen: specimen.clone(),
    };
    let json = serde_json::to_vec_pretty(&report).map_err(|e| GeomError::Measure {
        problem: e.to_string(),
        text: String::new(),
    })?;
    write_atomic(&json_path, &json)?;
    Ok(report)
}

/// Has gmsh build the `.geo` and measure its physical groups, free
/// entities and periodic faces; returns the measurements and the build's
/// wall time (s).
fn measure(
    gmsh: &Gmsh,
    layout: &Layout,
    geo_path: &Path,
    out_dir: &Path,
) -> Result<(Measured, f64), GeomError> {
    let measure_out = out_dir.join(format!(".occ-measure-{}.json", std::process::id()));
    let model_per_m = crate::geo::model_units_per_m(layout).to_string();
    let script = format!("{}{MEASURE_PY}", crate::diagnose::PARAMETRIC_GAP_PY);
    let run = gmsh.run_python(
        &script,
        &[
            geo_path.as_os_str(),
            measure_out.as_os_str(),
            std::ffi::OsStr::new(&model_per_m),
        ],
        out_dir,
        GMSH_TIMEOUT,
    );
    let run = match run {
        Ok(o) => o,
        Err(GmshError::Failed { stderr, .. }) => {
            let _ = std::fs::remove_file(&measure_out);
            return Err(GeomError::Build {
                path: geo_path.to_path_buf(),
                message: stderr,
            });
        }
        Err(e) => return Err(e.into()),
    };
    let text = std::fs::read_to_string(&measure_out).map_err(|source| GeomError::Io {
        path: measure_out.clone(),
        source,
    })?;
    let _ = std::fs::remove_file(&measure_out);
    let measured: Measured = serde_json::from_str(&text).map_err(|e| GeomError::Measure {
        problem: e.to_string(),
        text: crate::gmsh::tail(&text, 5),
    })?;
    if !measured.errors.is_empty() {
        return Err(GeomError::Build {
            path: geo_path.to_path_buf(),
            message: measured.errors.join("\n"),
        });
    }
    Ok((measured, run.elapsed.as_secs_f64()))
}

/// Entities per physical group; an empty group (other than a free zone the
/// specimen does not have) or a leftover curve or surface is an error.
fn group_counts(
    measured: &Measured,
    layout: &Layout,
    symmetry: Symmetry,
    geo_path: &Path,
) -> Result<BTreeMap<String, usize>, GeomError> {
    let mut group_entities = BTreeMap::new();
    let mirror_groups: &[&str] = match symmetry {
        Symmetry::Full => &[],
        Symmetry::Half => &[groups::SYMMETRY_Y],
        Symmetry::Quarter => &[groups::SYMMETRY_X, groups::SYMMETRY_Y],
        Symmetry::HalfTurn => &[groups::HALF_TURN_Y],
    };
    for &name in [
        groups::STEEL,
        groups::CONCRETE,
        groups::INTERFACE_ADHESIVE,
        groups::INTERFACE_FREE,
        groups::BAR_LOADED_END,
        groups::BAR_FREE_END,
        groups::CONCRETE_BEARING_FACE,
        groups::CONCRETE_FREE_FACE,
    ]
    .iter()
    .chain(mirror_groups)
    {
        let count = measured.groups.get(name).map_or(0, |g| g.count);
        let may_be_empty = name == groups::INTERFACE_FREE && layout.l_adh >= layout.l;
        if count == 0 && !may_be_empty {
            return Err(GeomError::EmptyGroup {
                group: name.into(),
                hint: format!(" (see {})", geo_path.display()),
            });
        }
        group_entities.insert(name.to_string(), count);
    }
    if measured.free_curves > 0 || measured.free_surfaces > 0 {
        return Err(GeomError::Leftovers {
            curves: measured.free_curves,
            surfaces: measured.free_surfaces,
        });
    }

    Ok(group_entities)
}

/// The bar volume, rib volume and interface areas three ways: analytic,
/// the parry3d tessellation, gmsh's OCC model (`group_mass`, whole specimen).
fn three_way_checks(
    layout: &Layout,
    m: &crate::metrics::Metrics,
    tess: &crate::metrics::Tessellated,
    group_mass: &dyn Fn(&str) -> f64,
) -> BTreeMap<String, Check> {
    let core = std::f64::consts::PI * layout.r * layout.r * (layout.z_hi - layout.z_lo);
    let steel = group_mass(groups::STEEL);
    let mut checks = BTreeMap::new();
    checks.insert(
        "bar_volume_m3".to_string(),
        Check::new(m.bar_volume_m3, tess.bar_volume_m3, steel),
    );
    if layout.ribs.is_some() {
        checks.insert(
            "rib_volume_m3".to_string(),
            Check::new(m.rib_volume_m3, tess.bar_volume_m3 - core, steel - core),
        );
    }
    checks.insert(
        "interface_area_adhesive_m2".to_string(),
        Check::new(
            m.interface_area_adhesive_m2,
            tess.slab_areas_m2[0],
            group_mass(groups::INTERFACE_ADHESIVE),
        ),
    );
    if layout.l_adh < layout.l {
        checks.insert(
            "interface_area_free_m2".to_string(),
            Check::new(
                m.interface_area_free_m2,
                tess.slab_areas_m2[1],
                group_mass(groups::INTERFACE_FREE),
            ),
        );
    }
    checks
}
