//! The `mesh` section of a scene spec: parsed raw ([`RawMeshSpec`]), then
//! resolved to SI with defaults and bounds ([`MeshSpec`]).
//!
//! ```
//! let raw: mesh::spec::RawMeshSpec =
//!     serde_yaml::from_str("h_interface: 0.8 mm\nalgorithm_3d: delaunay").unwrap();
//! let spec = raw.resolve().unwrap();
//! assert!((spec.h_interface - 0.8e-3).abs() < 1e-15);
//! assert!((spec.h_outer - 5e-3).abs() < 1e-15);
//! ```

use crate::MeshError;
use geom::units::{Dim, RawQuantity};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// Default interface mesh size (paper §3.3): 0.4 mm.
pub const DEFAULT_H_INTERFACE: f64 = 0.4e-3;
/// Default mesh size at the cube's outer faces (paper §3.3): 5 mm.
pub const DEFAULT_H_OUTER: f64 = 5e-3;
/// Default wall-clock limit for one gmsh run: 600 s.
pub const DEFAULT_TIMEOUT: f64 = 600.0;
/// The default of `mesh.max_elements` (`crate::estimate`): ten million
/// tetrahedra, past what the solver's direct factorisation holds in memory
/// on a workstation (R2's paper mesh, the largest shipped, has 2.3 million).
pub const DEFAULT_MAX_ELEMENTS: f64 = 1e7;

/// gmsh's 3D meshing algorithm (`Mesh.Algorithm3D`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Algorithm3d {
    /// Delaunay (`Mesh.Algorithm3D = 1`): robust; faster on coarse meshes.
    Delaunay,
    /// Frontal (`Mesh.Algorithm3D = 4`).
    Frontal,
    /// MMG3D (`Mesh.Algorithm3D = 7`).
    Mmg3d,
    /// HXT (`Mesh.Algorithm3D = 10`): ~10× faster than Delaunay at
    /// h_interface = 0.4 mm; output depends on the thread count.
    Hxt,
}

impl Algorithm3d {
    /// The value of gmsh's `Mesh.Algorithm3D` option.
    pub fn gmsh_id(self) -> u32 {
        match self {
            Algorithm3d::Delaunay => 1,
            Algorithm3d::Frontal => 4,
            Algorithm3d::Mmg3d => 7,
            Algorithm3d::Hxt => 10,
        }
    }
}

/// Mesh optimisation after 3D meshing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Optimize {
    /// No optimisation (`Mesh.Optimize = 0`): thousands of poor tets remain.
    None,
    /// gmsh's tet optimiser (`Mesh.Optimize = 1`).
    Gmsh,
    /// gmsh's then Netgen's optimiser (`Mesh.OptimizeNetgen = 1`; absent from Debian's gmsh 4.8.4).
    Netgen,
}

/// `optimize` accepts `true`/`false` or a named optimiser.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum RawOptimize {
    Flag(bool),
    Named(Optimize),
}

/// The `mesh` section as written in the spec (all keys optional). Every
/// field's doc comment ends with `(unit; default …; bounds)`: the scene
/// reference and `ribbar schema scene` are generated from them.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawMeshSpec {
    /// Element size on the steel/concrete interface and in the whole bar,
    /// passed to the `.geo` as `-setnumber h_interface` (length; default
    /// 0.4 mm; > 0).
    pub h_interface: Option<RawQuantity>,
    /// Element size at the cube's outer faces, `-setnumber h_outer` (length;
    /// default 5 mm; ≥ h_interface).
    pub h_outer: Option<RawQuantity>,
    /// Largest element size in the bar's core: h_interface in a band of two
    /// rib heights (at least 2 h_interface) under the surface, then growing
    /// by half the depth toward the axis up to this size (length; default
    /// none: the whole bar at h_interface; ≥ h_interface).
    pub h_bar_core: Option<RawQuantity>,
    /// Largest element size along the bar's unbonded part: from a band of one
    /// diameter (at least two rib heights and 2 h_interface) past the bonded
    /// zone to the bearing face z = L the size grows by half the distance to
    /// the nearer of the two, up to this size; the bearing face and the
    /// loaded overhang keep their sizes, their reactions being the solver's
    /// force scale (length; default none: sized as the bonded zone;
    /// ≥ h_interface).
    pub h_unbonded: Option<RawQuantity>,
    /// gmsh's `Mesh.Algorithm3D`; HXT is about ten times faster than
    /// Delaunay at the paper's mesh, and its mesh changes with `threads`
    /// (choice; default hxt).
    pub algorithm_3d: Option<Algorithm3d>,
    /// Mesh optimisation: `true` is gmsh's optimiser (`Mesh.Optimize`),
    /// `netgen` adds `Mesh.OptimizeNetgen` (absent from some gmsh builds);
    /// without it thousands of tets stay below quality 0.1 (choice; default
    /// true).
    pub optimize: Option<RawOptimize>,
    /// gmsh threads, `General.NumThreads`; 1 keeps the mesh reproducible
    /// (count; default 1; ≥ 1).
    pub threads: Option<u32>,
    /// Wall-clock limit of one gmsh run, after which gmsh is stopped (time;
    /// default 600 s; > 0).
    pub timeout: Option<RawQuantity>,
    /// The model is the whole specimen made of the meshed part
    /// (`specimen.symmetry`) and its images, so that the whole's mesh has the
    /// part's symmetry exactly: a whole-specimen run that differs from the
    /// part's only in the symmetry it does not impose. `mesh.json` reports
    /// the whole, with `unfolded_from`; no effect on a whole part (bool;
    /// default false).
    pub unfold: Option<bool>,
    /// The most tetrahedra the size field may give (estimated before
    /// meshing; default 1e7).
    pub max_elements: Option<f64>,
}

/// The resolved `mesh` section, SI units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MeshSpec {
    /// Mesh size at the interface, m.
    pub h_interface: f64,
    /// Mesh size at the cube's outer faces, m.
    pub h_outer: f64,
    /// Largest mesh size in the bar's core, m; `None`: h_interface in the
    /// whole bar. Left out of the serialised spec when unset, so that meshes
    /// without it keep their cache keys.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub h_bar_core: Option<f64>,
    /// Largest mesh size along the bar's unbonded part (the non-adhesive
    /// zone between a band of one diameter past the bonded zone and the
    /// bearing face, whose reactions set the solver's force scale and keep
    /// their mesh), m; `None`: sized as the bonded zone. Left out of the serialised spec
    /// when unset, so that meshes without it keep their cache keys.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub h_unbonded: Option<f64>,
    pub algorithm_3d: Algorithm3d,
    pub optimize: Optimize,
    /// Number of gmsh threads (≥ 1).
    pub threads: u32,
    /// Wall-clock limit for gmsh, s.
    pub timeout: f64,
    /// The model written is the whole specimen made of the meshed part
    /// (`specimen.symmetry`) and its images under the part's symmetry, so
    /// the whole's mesh has that symmetry exactly: a whole-specimen run
    /// that differs from the part's only by the symmetry it does not
    /// impose. Left out of the serialised spec when false, so other
    /// meshes keep their cache keys.
    #[serde(default, skip_serializing_if = "is_false")]
    pub unfold: bool,
    /// The most tetrahedra the size field may give
    /// (`crate::estimate::check_size`). A bound, not an input of the mesh:
    /// left out of the serialised spec, so that it is in no key.
    #[serde(skip_serializing, default = "default_max_elements")]
    pub max_elements: f64,
}

fn default_max_elements() -> f64 {
    DEFAULT_MAX_ELEMENTS
}

fn is_false(v: &bool) -> bool {
    !*v
}

impl Default for MeshSpec {
    fn default() -> Self {
        MeshSpec {
            h_interface: DEFAULT_H_INTERFACE,
            h_outer: DEFAULT_H_OUTER,
            h_bar_core: None,
            h_unbonded: None,
            algorithm_3d: Algorithm3d::Hxt,
            optimize: Optimize::Gmsh,
            threads: 1,
            timeout: DEFAULT_TIMEOUT,
            unfold: false,
            max_elements: default_max_elements(),
        }
    }
}

fn bad(key: &str, message: String) -> MeshError {
    MeshError::Spec {
        key: key.to_string(),
        message,
    }
}

impl RawMeshSpec {
    /// Resolves units, fills defaults and checks bounds; errors name the key.
    pub fn resolve(&self) -> Result<MeshSpec, MeshError> {
        let d = MeshSpec::default();
        let h_interface = match &self.h_interface {
            Some(q) => q.to_si(Dim::Length, "mesh.h_interface")?,
            None => d.h_interface,
        };
        let h_outer = match &self.h_outer {
            Some(q) => q.to_si(Dim::Length, "mesh.h_outer")?,
            None => d.h_outer,
        };
        let h_bar_core = self
            .h_bar_core
            .as_ref()
            .map(|q| q.to_si(Dim::Length, "mesh.h_bar_core"))
            .transpose()?;
        let h_unbonded = self
            .h_unbonded
            .as_ref()
            .map(|q| q.to_si(Dim::Length, "mesh.h_unbonded"))
            .transpose()?;
        let timeout = match &self.timeout {
            Some(q) => q.to_si(Dim::Time, "mesh.timeout")?,
            None => d.timeout,
        };
        if h_interface <= 0.0 {
            return Err(bad(
                "h_interface",
                format!("must be > 0 m, got {h_interface} m"),
            ));
        }
        if h_outer <= 0.0 {
            return Err(bad("h_outer", format!("must be > 0 m, got {h_outer} m")));
        }
        if h_outer < h_interface {
            return Err(bad(
                "h_outer",
                format!("must be ≥ h_interface ({h_interface} m), got {h_outer} m"),
            ));
        }
        for (key, h) in [("h_bar_core", h_bar_core), ("h_unbonded", h_unbonded)] {
            if let Some(h) = h.filter(|&h| h < h_interface || h.is_nan()) {
                return Err(bad(
                    key,
                    format!("must be ≥ h_interface ({h_interface} m), got {h} m"),
                ));
            }
        }
        if timeout <= 0.0 {
            return Err(bad("timeout", format!("must be > 0 s, got {timeout} s")));
        }
        let max_elements = self.max_elements.unwrap_or(d.max_elements);
        if max_elements.is_nan() || max_elements < 1.0 {
            return Err(bad(
                "max_elements",
                format!("must be ≥ 1, got {max_elements}"),
            ));
        }
        let threads = self.threads.unwrap_or(d.threads);
        if threads == 0 {
            return Err(bad("threads", "must be ≥ 1".to_string()));
        }
        let optimize = match &self.optimize {
            None => d.optimize,
            Some(RawOptimize::Flag(true)) => Optimize::Gmsh,
            Some(RawOptimize::Flag(false)) => Optimize::None,
            Some(RawOptimize::Named(o)) => *o,
        };
        Ok(MeshSpec {
            h_interface,
            h_outer,
            h_bar_core,
            h_unbonded,
            algorithm_3d: self.algorithm_3d.unwrap_or(d.algorithm_3d),
            optimize,
            threads,
            timeout,
            unfold: self.unfold.unwrap_or(d.unfold),
            max_elements,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Defaults are the paper's sizes (§3.3: 0.4 mm / 5 mm) and a documented gmsh set-up.
    #[test]
    fn defaults() {
        let spec = RawMeshSpec::default().resolve().unwrap();
        assert_eq!(spec, MeshSpec::default());
        assert_eq!(spec.h_interface, 0.4e-3);
        assert_eq!(spec.h_outer, 5e-3);
    }

    /// The bar core's size is at least h_interface; unset, it leaves the
    /// serialised spec (and so every mesh key) as it was.
    #[test]
    fn bar_core_is_checked_and_absent_when_unset() {
        let raw: RawMeshSpec = serde_yaml::from_str("h_bar_core: 0.1 mm").unwrap();
        let e = raw.resolve().unwrap_err().to_string();
        assert!(
            e.contains("mesh.h_bar_core") && e.contains("h_interface"),
            "{e}"
        );
        let raw: RawMeshSpec = serde_yaml::from_str("h_bar_core: 3 mm").unwrap();
        assert_eq!(raw.resolve().unwrap().h_bar_core, Some(3e-3));
        // Unset, it is not part of the resolved spec that mesh keys hash.
        let json = serde_json::to_value(MeshSpec::default()).unwrap();
        assert!(json.get("h_bar_core").is_none(), "{json}");
    }

    /// So is the unbonded parts' size.
    #[test]
    fn unbonded_size_is_checked_and_absent_when_unset() {
        let raw: RawMeshSpec = serde_yaml::from_str("h_unbonded: 0.2 mm").unwrap();
        let e = raw.resolve().unwrap_err().to_string();
        assert!(
            e.contains("mesh.h_unbonded") && e.contains("h_interface"),
            "{e}"
        );
        let raw: RawMeshSpec = serde_yaml::from_str("h_unbonded: 1 s").unwrap();
        let e = raw.resolve().unwrap_err().to_string();
        assert!(e.contains("mesh.h_unbonded"), "{e}");
        let raw: RawMeshSpec = serde_yaml::from_str("h_unbonded: 3 mm").unwrap();
        assert_eq!(raw.resolve().unwrap().h_unbonded, Some(3e-3));
        let json = serde_json::to_value(MeshSpec::default()).unwrap();
        assert!(json.get("h_unbonded").is_none(), "{json}");
    }

    /// Unknown keys and out-of-range values are errors naming the key (SPEC §8).
    #[test]
    fn bad_keys_are_named() {
        let e = serde_yaml::from_str::<RawMeshSpec>("h_inter: 1 mm").unwrap_err();
        assert!(e.to_string().contains("h_inter"), "{e}");
        let raw: RawMeshSpec = serde_yaml::from_str("h_interface: -1 mm").unwrap();
        let e = raw.resolve().unwrap_err().to_string();
        assert!(e.contains("mesh.h_interface"), "{e}");
        let raw: RawMeshSpec = serde_yaml::from_str("h_outer: 3 GPa").unwrap();
        let e = raw.resolve().unwrap_err().to_string();
        assert!(e.contains("mesh.h_outer"), "{e}");
        let raw: RawMeshSpec = serde_yaml::from_str("h_interface: 2 mm\nh_outer: 1 mm").unwrap();
        assert!(raw
            .resolve()
            .unwrap_err()
            .to_string()
            .contains("mesh.h_outer"));
        let raw: RawMeshSpec = serde_yaml::from_str("threads: 0").unwrap();
        assert!(raw
            .resolve()
            .unwrap_err()
            .to_string()
            .contains("mesh.threads"));
        assert!(serde_yaml::from_str::<RawMeshSpec>("algorithm_3d: fast").is_err());
    }

    /// `optimize` accepts booleans and names; `timeout` takes time units.
    #[test]
    fn optimize_and_timeout() {
        let raw: RawMeshSpec =
            serde_yaml::from_str("optimize: false\ntimeout: 2 min\nalgorithm_3d: delaunay")
                .unwrap();
        let s = raw.resolve().unwrap();
        assert_eq!(s.optimize, Optimize::None);
        assert_eq!(s.timeout, 120.0);
        assert_eq!(s.algorithm_3d, Algorithm3d::Delaunay);
        let raw: RawMeshSpec = serde_yaml::from_str("optimize: netgen").unwrap();
        assert_eq!(raw.resolve().unwrap().optimize, Optimize::Netgen);
    }
}
