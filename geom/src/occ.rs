//! gmsh's OpenCASCADE model of a specimen measured against the geometry:
//! the physical groups' volumes and areas beside the analytic and parry3d
//! values (the third of the three ways of SPEC §2's check), the entity
//! count of each group, leftover entities and the worst-closing periodic
//! face.
//!
//! The measurement is Python for gmsh's API ([`measure_py`]) that runs on
//! the model a script has just built. The mesh stage runs it between
//! building and meshing, in the same gmsh process, so a scene's
//! OpenCASCADE booleans run once; [`measure`] runs it on its own.

use crate::build::{checks_of, GeomError};
use crate::geo::groups;
use crate::gmsh::{Gmsh, GmshError};
use crate::layout::Layout;
use crate::metrics::{analytic, tessellated};
use crate::spec::{Bar, Specimen, Symmetry};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;
use std::time::Duration;

/// Time allowed for gmsh to build and measure the solid on its own.
pub const GMSH_TIMEOUT: Duration = Duration::from_secs(600);

/// Python defining `measure()`: the dict [`Measured`] reads, of the model
/// gmsh holds, in SI units (the script's `model_per_m` converts).
pub fn measure_py() -> String {
    format!("{}{MEASURE_FN_PY}", crate::diagnose::PARAMETRIC_GAP_PY)
}

const MEASURE_FN_PY: &str = r#"
def measure():
    try:
        model_per_m = gmsh.parser.getNumber("model_per_m")[0]
    except Exception:
        model_per_m = 1.0
    res = {"groups": {}}
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
    return res
"#;

const STANDALONE_PY: &str = r#"
import json, sys, time
geo, out = sys.argv[1], sys.argv[2]
gmsh.initialize(["-noenv"], interruptible=False)
gmsh.option.setNumber("General.Terminal", 0)
gmsh.logger.start()
errors = []
start = time.time()
try:
    gmsh.open(geo)
except Exception as e:
    errors.append(str(e))
errors += [m for m in gmsh.logger.get() if m.startswith("Error")]
res = {"errors": errors, "groups": {}}
if not errors:
    built = time.time()
    res = measure()
    res["build_seconds"] = built - start
    res["errors"] = []
with open(out, "w") as f:
    json.dump(res, f)
gmsh.finalize()
"#;

/// What [`measure_py`]'s `measure()` returns.
#[derive(Debug, Clone, Deserialize)]
pub struct Measured {
    #[serde(default)]
    pub errors: Vec<String>,
    pub groups: BTreeMap<String, Group>,
    #[serde(default)]
    pub free_curves: usize,
    #[serde(default)]
    pub free_surfaces: usize,
    #[serde(default)]
    pub periodic_gap: Option<PeriodicFaceGap>,
    /// Wall time gmsh took to build the model from its script, s.
    #[serde(default)]
    pub build_seconds: f64,
}

/// One physical group of the built model.
#[derive(Debug, Clone, Deserialize)]
pub struct Group {
    /// Its entities.
    pub count: usize,
    /// Their total volume, area or length, SI.
    pub mass: f64,
}

/// The periodic (cylindrical) face of the built model whose boundary comes
/// closest to not closing in gmsh's parameter space: gmsh's periodic-face
/// mesher chains the boundary curves with a tolerance of 1e-6 of the face's
/// parameter diagonal, and fails on a face whose curves meet farther apart
/// (the 35° failure before the model was built in millimetres;
/// docs/src/explanation/geometry.md).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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

/// The built model checked against the geometry.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OccReport {
    /// bar_volume_m3, rib_volume_m3 (ribbed bars), interface areas three
    /// ways; `gmsh_occ` is the modelled part's measure divided by the
    /// modelled fraction (whole-specimen equivalent).
    pub checks: BTreeMap<String, crate::build::Check>,
    /// Entities per physical group in the built model.
    pub group_entities: BTreeMap<String, usize>,
    /// The worst-closing periodic face (None for a model without one).
    pub periodic_face_gap: Option<PeriodicFaceGap>,
    /// Wall time gmsh took to build the model from its script, s.
    pub build_seconds: f64,
}

impl OccReport {
    /// Reads `measure()`'s JSON `text` for the specimen of `bar` and
    /// `specimen` built from `geo_path`, and checks it: an error gmsh
    /// reported, an empty physical group, leftover entities or a measure
    /// more than 1 % from the analytic one is an error.
    pub fn check(
        text: &str,
        bar: &Bar,
        specimen: &Specimen,
        geo_path: &Path,
    ) -> Result<OccReport, GeomError> {
        let measured: Measured = serde_json::from_str(text).map_err(|e| GeomError::Measure {
            problem: e.to_string(),
            text: crate::gmsh::tail(text, 5),
        })?;
        if !measured.errors.is_empty() {
            return Err(GeomError::Build {
                path: geo_path.to_path_buf(),
                message: measured.errors.join("\n"),
            });
        }
        let layout = Layout::new(bar, specimen);
        let group_entities = group_counts(&measured, &layout, specimen.symmetry, geo_path)?;
        // OCC measures the modelled part; the checks compare whole-specimen values.
        let fraction = specimen.symmetry.fraction();
        let group_mass = |name: &str| measured.groups.get(name).map_or(0.0, |g| g.mass) / fraction;
        let m = analytic(&layout);
        let tess = tessellated(&layout, &[(0.0, layout.l_adh), (layout.l_adh, layout.l)]);
        let checks = checks_of(&layout, &m, &tess, Some(&group_mass));
        if let Some((quantity, check)) = checks.iter().find(|(_, c)| !c.agree) {
            return Err(GeomError::Disagree {
                quantity: quantity.clone(),
                check: check.clone(),
            });
        }
        Ok(OccReport {
            checks,
            group_entities,
            periodic_face_gap: measured.periodic_gap,
            build_seconds: measured.build_seconds,
        })
    }
}

/// Has gmsh build `geo_path` (the script the geometry stage wrote for `bar`
/// and `specimen`) on its own and checks the built model ([`OccReport::check`]);
/// `work_dir` takes a scratch file. The mesh stage does the same in its own
/// gmsh run.
pub fn measure(
    gmsh: &Gmsh,
    bar: &Bar,
    specimen: &Specimen,
    geo_path: &Path,
    work_dir: &Path,
) -> Result<OccReport, GeomError> {
    let out = crate::fsutil::scratch_name(work_dir, "occ-measure", "json");
    let script = format!("import gmsh\n{}{STANDALONE_PY}", measure_py());
    let run = gmsh.run_python(
        &script,
        &[geo_path.as_os_str(), out.as_os_str()],
        work_dir,
        GMSH_TIMEOUT,
    );
    match run {
        Ok(_) => {}
        Err(GmshError::Failed { stderr, .. }) => {
            let _ = std::fs::remove_file(&out);
            return Err(GeomError::Build {
                path: geo_path.to_path_buf(),
                message: stderr,
            });
        }
        Err(e) => return Err(e.into()),
    }
    let text = std::fs::read_to_string(&out).map_err(|source| GeomError::Io {
        path: out.clone(),
        source,
    })?;
    let _ = std::fs::remove_file(&out);
    OccReport::check(&text, bar, specimen, geo_path)
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
