//! The geometry stage: `specimen.geo` + `geometry.json`, the solid measured
//! analytically and on its parry3d tessellation. gmsh's OpenCASCADE model
//! of the script is measured by the mesh stage, in the gmsh run that
//! meshes it ([`crate::occ`]): the booleans that build a ribbed bar are
//! nearly all of gmsh's time, and run once a scene that way.

use crate::geo::{groups, write_geo};
use crate::gmsh::GmshError;
use crate::layout::Layout;
use crate::metrics::{analytic, tessellated, Metrics};
use crate::spec::{Bar, Specimen, Symmetry};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Relative agreement required between the measurements.
pub const CHECK_TOLERANCE: f64 = 0.01;

/// One quantity measured two or three ways.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Check {
    pub analytic: f64,
    pub parry3d: f64,
    /// gmsh's OpenCASCADE measure, where the model was built.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gmsh_occ: Option<f64>,
    /// Largest |x − analytic| / |analytic| over the numerical values.
    pub max_rel_diff: f64,
    /// `max_rel_diff` ≤ 1 %.
    pub agree: bool,
}

impl Check {
    pub(crate) fn new(analytic: f64, parry3d: f64, gmsh_occ: Option<f64>) -> Check {
        let scale = analytic.abs().max(f64::MIN_POSITIVE);
        let max_rel_diff = std::iter::once(parry3d)
            .chain(gmsh_occ)
            .map(|x| (x - analytic).abs() / scale)
            .fold(0.0, f64::max);
        Check {
            analytic,
            parry3d,
            gmsh_occ,
            max_rel_diff,
            agree: max_rel_diff <= CHECK_TOLERANCE,
        }
    }

    /// "analytic a, parry3d p[, gmsh OCC g]" for messages.
    pub fn values(&self) -> String {
        let occ = self
            .gmsh_occ
            .map_or(String::new(), |g| format!(", gmsh OCC {g:.6e}"));
        format!(
            "analytic {:.6e}, parry3d {:.6e}{occ}",
            self.analytic, self.parry3d
        )
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
    /// rib_volume_m3 (ribbed bars only), bar_volume_m3, interface areas:
    /// analytic and parry3d (the mesh stage adds gmsh OCC's, `mesh.json`).
    pub checks: BTreeMap<String, Check>,
    /// Smallest axial distance from the planes z = 0, l_adh, L to a rib edge feature, m.
    pub plane_clearance_m: Option<f64>,
    /// Smallest axial distance from the bar end planes to a rib edge feature, m.
    pub end_clearance_m: Option<f64>,
    /// Triangles of the parry3d tessellation.
    pub tessellation_triangles: usize,
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
    #[error("{quantity}: {} differ by {:.2} % (> 1 %)", .check.values(), 100.0 * .check.max_rel_diff)]
    Disagree { quantity: String, check: Check },
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
/// `specimen.geo` and `geometry.json` with the analytic and parry3d
/// measures. Fails if they disagree by > 1 %; `geometry.json` is then not
/// written.
pub fn build_geometry(
    bar: &Bar,
    specimen: &Specimen,
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
    let checks = checks_of(&layout, &m, &tess, None);
    if let Some((quantity, check)) = checks.iter().find(|(_, c)| !c.agree) {
        return Err(GeomError::Disagree {
            quantity: quantity.clone(),
            check: check.clone(),
        });
    }
    let report = GeometryReport {
        symmetry: specimen.symmetry,
        modelled_fraction: specimen.symmetry.fraction(),
        f_r: m.f_r,
        rib_volume_m3: m.rib_volume_m3,
        bar_volume_m3: m.bar_volume_m3,
        interface_area_adhesive_m2: m.interface_area_adhesive_m2,
        interface_area_free_m2: m.interface_area_free_m2,
        rib_count: m.rib_count,
        checks,
        plane_clearance_m: layout.ribs.as_ref().map(|r| r.clearance_cube),
        end_clearance_m: layout.ribs.as_ref().map(|r| r.clearance_ends),
        tessellation_triangles: tess.triangles,
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

/// The bar volume, rib volume and interface areas: analytic, the parry3d
/// tessellation and, when the model was built, gmsh's OCC measure
/// (`group_mass`, whole specimen).
pub(crate) fn checks_of(
    layout: &Layout,
    m: &Metrics,
    tess: &crate::metrics::Tessellated,
    group_mass: Option<&dyn Fn(&str) -> f64>,
) -> BTreeMap<String, Check> {
    let occ = |name: &str| group_mass.map(|f| f(name));
    let core = std::f64::consts::PI * layout.r * layout.r * (layout.z_hi - layout.z_lo);
    let steel = occ(groups::STEEL);
    let mut checks = BTreeMap::new();
    checks.insert(
        "bar_volume_m3".to_string(),
        Check::new(m.bar_volume_m3, tess.bar_volume_m3, steel),
    );
    if layout.ribs.is_some() {
        checks.insert(
            "rib_volume_m3".to_string(),
            Check::new(
                m.rib_volume_m3,
                tess.bar_volume_m3 - core,
                steel.map(|s| s - core),
            ),
        );
    }
    checks.insert(
        "interface_area_adhesive_m2".to_string(),
        Check::new(
            m.interface_area_adhesive_m2,
            tess.slab_areas_m2[0],
            occ(groups::INTERFACE_ADHESIVE),
        ),
    );
    if layout.l_adh < layout.l {
        checks.insert(
            "interface_area_free_m2".to_string(),
            Check::new(
                m.interface_area_free_m2,
                tess.slab_areas_m2[1],
                occ(groups::INTERFACE_FREE),
            ),
        );
    }
    checks
}
