//! The solver's model: what `ribbar mesh` builds from gmsh's `.msh` and the
//! solver loads. All coordinates in metres.
//!
//! Node numbering: 0-based, dense. After interface duplication every node
//! belongs to exactly one side (steel or concrete); interface element nodes
//! are `[s0, s1, s2, c0, c1, c2]` with `c_i` the concrete-side twin of `s_i`
//! (same coordinates).

use serde::{Deserialize, Serialize};

/// Which material a tetrahedron (or a node) belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Region {
    Steel,
    Concrete,
}

/// Interface zone of SPEC §2: bonded, or the non-adhesive pre-length.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum InterfaceZone {
    Adhesive,
    Free,
}

/// Orthonormal local frame of an interface element.
/// `n`: normal from steel into concrete; `t`: bar axis (z) projected on the
/// surface, normalised; `h = n × t`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    pub n: [f64; 3],
    pub t: [f64; 3],
    pub h: [f64; 3],
}

/// A 6-node zero-thickness interface element.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct InterfaceElement {
    /// `[s0, s1, s2, c0, c1, c2]`: steel-side triangle then concrete-side twins.
    pub nodes: [u32; 6],
    pub zone: InterfaceZone,
    pub frame: Frame,
    /// Area of the triangle, m².
    pub area: f64,
}

/// Node sets for boundary conditions and measurements (SPEC §2).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct NodeSets {
    /// Steel nodes on the bar's loaded end face (z = L + e_load): imposed u_z.
    pub bar_loaded_end: Vec<u32>,
    /// Steel nodes on the bar's free end face (z = -e_free): FED.
    pub bar_free_end: Vec<u32>,
    /// Concrete nodes on the bearing face z = L: u_z = 0.
    pub concrete_bearing_face: Vec<u32>,
    /// Concrete nodes on the free face z = 0 (the ring around the bar): FED.
    pub concrete_free_face: Vec<u32>,
    /// Nodes (both sides) on the symmetry plane x = 0 of a reduced model: u_x = 0.
    #[serde(default)]
    pub symmetry_x: Vec<u32>,
    /// Nodes (both sides) on the symmetry plane y = 0 of a reduced model:
    /// u_y = 0 on a mirror plane; tied in pairs by the half-turn
    /// ([`Model::half_turn_twins`]) in a [`Symmetry::HalfTurn`] model.
    #[serde(default)]
    pub symmetry_y: Vec<u32>,
}

/// Which part of the specimen the model holds. A smooth bar in the cube has
/// the mirror planes x = 0 and y = 0; the quarter x ≥ 0, y ≥ 0 with those
/// planes held normal gives the whole specimen's response at a quarter of
/// the cost. A herringbone bar has the plane y = 0 alone: the half y ≥ 0.
/// A spiral bar has the half-turn about its axis: the half y ≥ 0 whose cut
/// face's side x < 0 moves as the half-turn image of its side x > 0.
/// Forces measured on the model are multiplied by
/// [`Symmetry::force_factor`].
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub enum Symmetry {
    #[default]
    Full,
    // After Quarter: model files store the variant's index.
    Quarter,
    Half,
    HalfTurn,
}

impl Symmetry {
    /// Whole-specimen force per force measured on the model.
    pub fn force_factor(self) -> f64 {
        match self {
            Symmetry::Full => 1.0,
            Symmetry::Half | Symmetry::HalfTurn => 2.0,
            Symmetry::Quarter => 4.0,
        }
    }
}

/// The meshed specimen ready for the solver.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Model {
    /// Node coordinates, m.
    pub nodes: Vec<[f64; 3]>,
    /// Side of each node after duplication.
    pub node_region: Vec<Region>,
    /// Linear tetrahedra, positively oriented (positive signed volume).
    pub tets: Vec<[u32; 4]>,
    pub tet_region: Vec<Region>,
    /// Characteristic size l = (12 V / √2)^(1/3) (paper eq. 11), m.
    pub tet_size: Vec<f64>,
    pub interfaces: Vec<InterfaceElement>,
    pub node_sets: NodeSets,
    /// Bar diameter d, m (for σ_mb = F / (π d l_adh)).
    pub bar_diameter: f64,
    /// Adhesive (bonded) length l_adh, m.
    pub adhesive_length: f64,
    /// Full specimen or a symmetric part of it.
    #[serde(default)]
    pub symmetry: Symmetry,
}

/// First bytes of a model file: names the format and its version, so a
/// stale or foreign file is rejected instead of misread.
const MODEL_MAGIC: &[u8; 16] = b"ribbar-model-v2\n";

impl Model {
    /// Writes the model (bincode after a magic header) atomically: a
    /// temporary file in the same directory renamed over `path`.
    pub fn save(&self, path: &std::path::Path) -> Result<(), crate::MeshError> {
        let mut bytes = MODEL_MAGIC.to_vec();
        bincode::serialize_into(&mut bytes, self).map_err(|e| crate::MeshError::ModelFile {
            path: path.to_path_buf(),
            detail: e.to_string(),
        })?;
        crate::write_atomic(path, &bytes)
    }

    /// Reads a model written by [`Model::save`].
    pub fn load(path: &std::path::Path) -> Result<Model, crate::MeshError> {
        let bytes = std::fs::read(path).map_err(|e| crate::MeshError::io(path, e))?;
        let bad = |detail: String| crate::MeshError::ModelFile {
            path: path.to_path_buf(),
            detail,
        };
        let body = bytes
            .strip_prefix(MODEL_MAGIC.as_slice())
            .ok_or_else(|| bad("not a ribbar model file (or an older format)".into()))?;
        let model: Model = bincode::DefaultOptions::new()
            .with_fixint_encoding()
            .allow_trailing_bytes()
            .with_limit(body.len() as u64 * 2 + 1024)
            .deserialize(body)
            .map_err(|e| bad(format!("corrupt or truncated: {e}")))?;
        model.check().map_err(bad)?;
        Ok(model)
    }

    /// Checks that every array has a consistent length and every node id exists.
    pub fn check(&self) -> Result<(), String> {
        let n = self.nodes.len();
        if self.node_region.len() != n {
            return Err(format!(
                "{} node regions for {} nodes",
                self.node_region.len(),
                n
            ));
        }
        let m = self.tets.len();
        if self.tet_region.len() != m || self.tet_size.len() != m {
            return Err(format!("tet arrays of different lengths ({m} tets)"));
        }
        let ok = |i: &u32| (*i as usize) < n;
        if !self.tets.iter().all(|t| t.iter().all(ok))
            || !self.interfaces.iter().all(|e| e.nodes.iter().all(ok))
        {
            return Err(format!("an element references a node id ≥ {n}"));
        }
        let s = &self.node_sets;
        for (name, v) in [
            ("bar_loaded_end", &s.bar_loaded_end),
            ("bar_free_end", &s.bar_free_end),
            ("concrete_bearing_face", &s.concrete_bearing_face),
            ("concrete_free_face", &s.concrete_free_face),
            ("symmetry_x", &s.symmetry_x),
            ("symmetry_y", &s.symmetry_y),
        ] {
            if !v.iter().all(ok) {
                return Err(format!("node set {name} references a node id ≥ {n}"));
            }
        }
        Ok(())
    }
}

use bincode::Options as _;
