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
}
