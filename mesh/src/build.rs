//! From a [`RawMesh`] to the solver's [`Model`]: oriented tets with size and
//! quality, interface nodes duplicated, 6-node interface elements with
//! their frames, node sets.
//!
//! Duplication rule: a node is an interface node when it belongs to at least
//! one steel tet and at least one concrete tet. In a conforming mesh these
//! are exactly the nodes of the triangles shared by a steel and a concrete
//! tet, including the nodes on the circles where the bar enters and leaves
//! the cube (z = 0 and z = L) and on the curve where the adhesive and free
//! zones meet (z = l_adh). Each interface node gets exactly one concrete
//! twin (same coordinates, new id); every concrete tet and every triangle of
//! a concrete boundary group uses the twin, every steel tet and steel group
//! keeps the original. So an adhesive and a free element meeting on
//! z = l_adh share the same twin, and the concrete face triangles touching
//! the circles z = 0, L use the twins: no concrete tet touches a steel node.

use crate::model::*;
use crate::MeshError;
use crate::RawMesh;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Physical volume names the model needs.
pub const VOLUME_GROUPS: [&str; 2] = ["steel", "concrete"];
/// Physical surfaces that must be present.
pub const REQUIRED_SURFACES: [&str; 5] = [
    "interface_adhesive",
    "bar_loaded_end",
    "bar_free_end",
    "concrete_bearing_face",
    "concrete_free_face",
];
/// Physical surface that may be absent (no free zone when l_adh = L).
pub const OPTIONAL_SURFACES: [&str; 1] = ["interface_free"];
/// Physical surfaces of the mirror planes x = 0 and y = 0 (steel and
/// concrete faces). Both present: [`Symmetry::Quarter`]; y = 0 alone:
/// [`Symmetry::Half`]; none: [`Symmetry::Full`]; x = 0 alone is an error.
pub const SYMMETRY_SURFACES: [&str; 2] = ["symmetry_x", "symmetry_y"];
/// Physical surface of the cut plane y = 0 of a half-turn half model
/// ([`Symmetry::HalfTurn`]), its side x < 0 meshed as the image of x > 0.
pub const HALF_TURN_SURFACE: &str = "half_turn_y";

/// Counts and measures of a built model, written as `mesh.json`.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct MeshReport {
    /// Version printed by the gmsh that made the mesh (empty when unknown).
    pub gmsh_version: String,
    /// Nodes of the model, twins included.
    pub nodes: usize,
    pub tets_steel: usize,
    pub tets_concrete: usize,
    pub interface_elements_adhesive: usize,
    pub interface_elements_free: usize,
    /// Interface nodes that received a concrete twin.
    pub duplicated_nodes: usize,
    /// Tets whose node order was reversed to make their volume positive.
    pub reoriented_tets: usize,
    /// Minimum of the normalised radius ratio 3 r_in / R_circ (1 = regular tet).
    pub min_quality: f64,
    pub mean_quality: f64,
    /// Tets with quality below 0.1.
    pub tets_quality_below_0_1: usize,
    /// Smallest / largest characteristic size l (eq. 11), m.
    pub min_size_m: f64,
    pub max_size_m: f64,
    /// Sum of the adhesive interface triangles' areas, m².
    pub interface_area_adhesive_m2: f64,
    /// Sum of the free-zone interface triangles' areas, m².
    pub interface_area_free_m2: f64,
    /// Steel and concrete volumes, m³.
    pub volume_steel_m3: f64,
    pub volume_concrete_m3: f64,
    /// The modelled part, `"full"` or `"quarter"` (x ≥ 0, y ≥ 0): the
    /// counts, areas and volumes above are the modelled part's.
    #[serde(default, with = "symmetry_name")]
    pub symmetry: Symmetry,
    /// Nodes held on the mirror planes x = 0 and y = 0 (both sides, twins included).
    #[serde(default)]
    pub symmetry_nodes_x: usize,
    #[serde(default)]
    pub symmetry_nodes_y: usize,
    /// The 3D algorithm that made the mesh, and why it is not the one the
    /// spec asked for (gmsh's HXT aborts on some rib designs; the mesh
    /// stage then meshes with Delaunay).
    #[serde(default)]
    pub algorithm_3d: Option<crate::spec::Algorithm3d>,
    #[serde(default)]
    pub algorithm_fallback: Option<String>,
    /// The meshed part the whole model is made of (`mesh.unfold`); `None`:
    /// the model is the meshed part itself.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub unfolded_from: Option<String>,
    /// gmsh's OpenCASCADE model measured against the geometry (specimens
    /// the geometry stage built; `None` for other `.geo` files).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub occ: Option<geom::occ::OccReport>,
    pub timings_s: Timings,
}

impl MeshReport {
    /// The report of `whole`, the model unfolded from the part this report
    /// describes: counts and measures of the whole specimen.
    pub fn of_unfolded(&self, whole: &Model) -> MeshReport {
        let copies = self.symmetry.force_factor();
        let scale = |n: usize| (n as f64 * copies).round() as usize;
        let interfaces = InterfaceTally::of(&whole.interfaces);
        let steel = whole
            .tet_region
            .iter()
            .filter(|r| **r == crate::model::Region::Steel)
            .count();
        let twins: std::collections::BTreeSet<u32> = whole
            .interfaces
            .iter()
            .flat_map(|e| e.nodes[3..].iter().copied())
            .collect();
        MeshReport {
            nodes: whole.nodes.len(),
            tets_steel: steel,
            tets_concrete: whole.tets.len() - steel,
            interface_elements_adhesive: interfaces.elements_adhesive,
            interface_elements_free: interfaces.elements_free,
            duplicated_nodes: twins.len(),
            reoriented_tets: scale(self.reoriented_tets),
            tets_quality_below_0_1: scale(self.tets_quality_below_0_1),
            interface_area_adhesive_m2: interfaces.area_adhesive_m2,
            interface_area_free_m2: interfaces.area_free_m2,
            volume_steel_m3: copies * self.volume_steel_m3,
            volume_concrete_m3: copies * self.volume_concrete_m3,
            symmetry: Symmetry::Full,
            symmetry_nodes_x: 0,
            symmetry_nodes_y: 0,
            unfolded_from: Some(symmetry_name::name(self.symmetry).to_string()),
            ..self.clone()
        }
    }
}

/// Interface elements and their area per zone, as the report gives them.
struct InterfaceTally {
    elements_adhesive: usize,
    elements_free: usize,
    area_adhesive_m2: f64,
    area_free_m2: f64,
}

impl InterfaceTally {
    fn of(interfaces: &[InterfaceElement]) -> Self {
        let mut tally = InterfaceTally {
            elements_adhesive: 0,
            elements_free: 0,
            area_adhesive_m2: 0.0,
            area_free_m2: 0.0,
        };
        for e in interfaces {
            match e.zone {
                InterfaceZone::Adhesive => {
                    tally.elements_adhesive += 1;
                    tally.area_adhesive_m2 += e.area;
                }
                InterfaceZone::Free => {
                    tally.elements_free += 1;
                    tally.area_free_m2 += e.area;
                }
            }
        }
        tally
    }
}

/// `Symmetry` as the lower-case name `geometry.json` also uses.
mod symmetry_name {
    use crate::model::Symmetry;
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn name(s: Symmetry) -> &'static str {
        match s {
            Symmetry::Full => "full",
            Symmetry::Half => "half",
            Symmetry::Quarter => "quarter",
            Symmetry::HalfTurn => "half_turn",
        }
    }

    pub fn serialize<S: Serializer>(s: &Symmetry, ser: S) -> Result<S::Ok, S::Error> {
        ser.serialize_str(name(*s))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(de: D) -> Result<Symmetry, D::Error> {
        match String::deserialize(de)?.as_str() {
            "full" => Ok(Symmetry::Full),
            "half" => Ok(Symmetry::Half),
            "quarter" => Ok(Symmetry::Quarter),
            "half_turn" => Ok(Symmetry::HalfTurn),
            other => Err(serde::de::Error::custom(format!(
                "symmetry {other:?}: expected \"full\", \"half\", \"half_turn\" or \"quarter\""
            ))),
        }
    }
}

/// Wall-clock times of the mesh stage's steps, s.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Timings {
    pub gmsh: f64,
    pub read: f64,
    pub build: f64,
    pub write: f64,
}

type V3 = [f64; 3];

#[inline]
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
#[inline]
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
#[inline]
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
#[inline]
fn norm(a: V3) -> f64 {
    dot(a, a).sqrt()
}
fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

/// Signed volume of the tet (a, b, c, d), m³: positive when (b−a, c−a, d−a) is right-handed.
pub fn tet_volume(p: [V3; 4]) -> f64 {
    dot(cross(sub(p[1], p[0]), sub(p[2], p[0])), sub(p[3], p[0])) / 6.0
}

/// Characteristic size of a tet, m (paper eq. 11): the edge of the regular
/// tet of the same volume, l = (12 V / √2)^(1/3).
pub fn characteristic_size(volume: f64) -> f64 {
    (12.0 * volume.abs() / std::f64::consts::SQRT_2).cbrt()
}

/// Normalised radius ratio q = 3 r_in / R_circ of a tet: 1 for the regular
/// tet, → 0 for degenerate ones (gmsh's "gamma"-like quality measures rank
/// elements the same way).
pub fn tet_quality(p: [V3; 4]) -> f64 {
    let v = tet_volume(p).abs();
    if v == 0.0 {
        return 0.0;
    }
    let faces = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];
    let area: f64 = faces
        .iter()
        .map(|f| 0.5 * norm(cross(sub(p[f[1]], p[f[0]]), sub(p[f[2]], p[f[0]]))))
        .sum();
    let r_in = 3.0 * v / area;
    let (a, b, c) = (sub(p[1], p[0]), sub(p[2], p[0]), sub(p[3], p[0]));
    let num = [
        scale(cross(b, c), dot(a, a)),
        scale(cross(c, a), dot(b, b)),
        scale(cross(a, b), dot(c, c)),
    ];
    let s = [
        num[0][0] + num[1][0] + num[2][0],
        num[0][1] + num[1][1] + num[2][1],
        num[0][2] + num[1][2] + num[2][2],
    ];
    let r_circ = norm(s) / (12.0 * v);
    3.0 * r_in / r_circ
}

fn sorted3(mut k: [u32; 3]) -> [u32; 3] {
    k.sort_unstable();
    k
}

/// Local faces of a tet; the remaining node of face i is node i.
const TET_FACES: [[usize; 3]; 4] = [[1, 2, 3], [0, 2, 3], [0, 1, 3], [0, 1, 2]];

/// Builds the solver model from a read mesh. `bar_diameter` (m) and
/// `adhesive_length` (m) are stored in the model for σ_mb (eq. 14).
pub fn build_model(
    raw: &RawMesh,
    bar_diameter: f64,
    adhesive_length: f64,
) -> Result<(Model, MeshReport), MeshError> {
    check_groups(raw)?;
    let numbering = Numbering::new(raw);
    let (steel, reoriented_steel) = oriented(raw, &raw.volumes["steel"], "steel")?;
    let (concrete, reoriented_concrete) = oriented(raw, &raw.volumes["concrete"], "concrete")?;
    let interfaces = interface_elements(raw, &numbering, &steel, &concrete)?;
    let tets = Tets::renumbered(raw, &numbering, &steel, &concrete);
    let (node_sets, symmetry) = node_sets(raw, &numbering)?;

    let n_tets = tets.tets.len() as f64;
    let tally = InterfaceTally::of(&interfaces);
    let report = MeshReport {
        nodes: numbering.nodes.len(),
        tets_steel: steel.len(),
        tets_concrete: concrete.len(),
        interface_elements_adhesive: tally.elements_adhesive,
        interface_elements_free: tally.elements_free,
        duplicated_nodes: numbering.duplicated,
        reoriented_tets: reoriented_steel + reoriented_concrete,
        min_quality: tets.quality.iter().copied().fold(f64::INFINITY, f64::min),
        mean_quality: tets.quality.iter().sum::<f64>() / n_tets,
        tets_quality_below_0_1: tets.quality.iter().filter(|&&q| q < 0.1).count(),
        min_size_m: tets.size.iter().copied().fold(f64::INFINITY, f64::min),
        max_size_m: tets.size.iter().copied().fold(0.0, f64::max),
        interface_area_adhesive_m2: tally.area_adhesive_m2,
        interface_area_free_m2: tally.area_free_m2,
        volume_steel_m3: tets.volume_steel,
        volume_concrete_m3: tets.volume_concrete,
        symmetry,
        symmetry_nodes_x: node_sets.symmetry_x.len(),
        symmetry_nodes_y: node_sets.symmetry_y.len(),
        ..Default::default()
    };
    let model = Model {
        nodes: numbering.nodes,
        node_region: numbering.node_region,
        tets: tets.tets,
        tet_region: tets.region,
        tet_size: tets.size,
        interfaces,
        node_sets,
        bar_diameter,
        adhesive_length,
        symmetry,
    };
    if symmetry == Symmetry::HalfTurn {
        // A cut face gmsh did not mesh as its own half-turn image cannot be
        // tied node to node: stop here, naming the first unpaired node.
        model
            .half_turn_twins()
            .map_err(|detail| topology_error(raw, detail))?;
    }
    Ok((model, report))
}

fn topology_error(raw: &RawMesh, detail: String) -> MeshError {
    MeshError::Topology {
        path: raw.source.clone(),
        detail,
    }
}

fn missing_group(raw: &RawMesh, group: &str, what: &str) -> MeshError {
    MeshError::MissingGroup {
        path: raw.source.clone(),
        group: group.to_string(),
        what: what.to_string(),
    }
}

/// Refuses a mesh without the physical groups the model needs.
fn check_groups(raw: &RawMesh) -> Result<(), MeshError> {
    for g in VOLUME_GROUPS {
        if raw.volumes.get(g).is_none_or(|v| v.is_empty()) {
            return Err(missing_group(raw, g, "a physical volume of linear tets"));
        }
    }
    for g in REQUIRED_SURFACES {
        if raw.surfaces.get(g).is_none_or(|v| v.is_empty()) {
            return Err(missing_group(raw, g, "a physical surface of triangles"));
        }
    }
    Ok(())
}

/// The model's node numbering: nodes of tets in file order, then the
/// concrete twins of the interface nodes (see the module doc).
struct Numbering {
    in_steel: Vec<bool>,
    in_concrete: Vec<bool>,
    /// Raw index → model id (steel side for interface nodes).
    new_id: Vec<u32>,
    /// Raw index → concrete twin's model id (`u32::MAX`: no twin).
    twin: Vec<u32>,
    nodes: Vec<V3>,
    node_region: Vec<Region>,
    duplicated: usize,
}

impl Numbering {
    fn new(raw: &RawMesh) -> Self {
        let n_raw = raw.nodes.len();
        let touched = |tets: &[[u32; 4]]| {
            let mut v = vec![false; n_raw];
            for t in tets {
                for &i in t {
                    v[i as usize] = true;
                }
            }
            v
        };
        let in_steel = touched(&raw.volumes["steel"]);
        let in_concrete = touched(&raw.volumes["concrete"]);
        let mut new_id = vec![u32::MAX; n_raw];
        let mut nodes: Vec<V3> = Vec::with_capacity(n_raw);
        let mut node_region = Vec::with_capacity(n_raw);
        for i in 0..n_raw {
            if in_steel[i] || in_concrete[i] {
                new_id[i] = nodes.len() as u32;
                nodes.push(raw.nodes[i]);
                node_region.push(if in_steel[i] {
                    Region::Steel
                } else {
                    Region::Concrete
                });
            }
        }
        let mut twin = vec![u32::MAX; n_raw];
        let mut duplicated = 0;
        for i in 0..n_raw {
            if in_steel[i] && in_concrete[i] {
                twin[i] = nodes.len() as u32;
                nodes.push(raw.nodes[i]);
                node_region.push(Region::Concrete);
                duplicated += 1;
            }
        }
        Numbering {
            in_steel,
            in_concrete,
            new_id,
            twin,
            nodes,
            node_region,
            duplicated,
        }
    }

    fn is_interface(&self, i: u32) -> bool {
        self.twin[i as usize] != u32::MAX
    }

    /// The id a concrete element uses for raw node `i`.
    fn concrete_id(&self, i: u32) -> u32 {
        let t = self.twin[i as usize];
        if t != u32::MAX {
            t
        } else {
            self.new_id[i as usize]
        }
    }
}

/// `tets` (raw ids) with positive volume (two nodes swapped where needed),
/// and how many were swapped; a flat tet is an error naming `name`.
fn oriented(
    raw: &RawMesh,
    tets: &[[u32; 4]],
    name: &str,
) -> Result<(Vec<[u32; 4]>, usize), MeshError> {
    let mut reoriented = 0;
    let mut out = Vec::with_capacity(tets.len());
    for (k, t) in tets.iter().enumerate() {
        let p = t.map(|i| raw.nodes[i as usize]);
        let v = tet_volume(p);
        if v == 0.0 || !v.is_finite() {
            return Err(topology_error(
                raw,
                format!(
                    "{name} tet {k} (nodes {:?}) has zero volume",
                    t.map(|i| raw.node_tags[i as usize])
                ),
            ));
        }
        if v < 0.0 {
            reoriented += 1;
            out.push([t[0], t[1], t[3], t[2]]);
        } else {
            out.push(*t);
        }
    }
    Ok((out, reoriented))
}

/// The interface group (zone) of each interface triangle (sorted raw ids).
fn interface_zones(raw: &RawMesh) -> Result<HashMap<[u32; 3], InterfaceZone>, MeshError> {
    let mut zone_of: HashMap<[u32; 3], InterfaceZone> = HashMap::new();
    for (g, zone) in [
        ("interface_adhesive", InterfaceZone::Adhesive),
        ("interface_free", InterfaceZone::Free),
    ] {
        for tri in raw.surfaces.get(g).map_or(&[][..], |v| v.as_slice()) {
            if zone_of
                .insert(sorted3(*tri), zone)
                .is_some_and(|z| z != zone)
            {
                return Err(topology_error(raw, format!("an interface triangle is in both interface_adhesive and interface_free (nodes {:?})", tri.map(|i| raw.node_tags[i as usize]))));
            }
        }
    }
    Ok(zone_of)
}

/// One interface element per triangle shared by a steel and a concrete
/// tet: steel nodes first, ordered so that n points from steel into
/// concrete, then their twins.
fn interface_elements(
    raw: &RawMesh,
    numbering: &Numbering,
    steel: &[[u32; 4]],
    concrete: &[[u32; 4]],
) -> Result<Vec<InterfaceElement>, MeshError> {
    // Faces of a steel tet all of whose nodes are interface nodes.
    let mut steel_faces: HashMap<[u32; 3], (u32, u8)> = HashMap::new();
    for (k, t) in steel.iter().enumerate() {
        for (f, face) in TET_FACES.iter().enumerate() {
            let tri = face.map(|j| t[j]);
            if tri.iter().all(|&i| numbering.is_interface(i)) {
                steel_faces.insert(sorted3(tri), (k as u32, f as u8));
            }
        }
    }
    let zone_of = interface_zones(raw)?;
    let mut interfaces = Vec::new();
    let mut matched = 0usize;
    for t in concrete {
        for face in TET_FACES.iter() {
            let tri = face.map(|j| t[j]);
            let key = sorted3(tri);
            let Some(&(ks, fs)) = steel_faces.get(&key) else {
                continue;
            };
            let zone = *zone_of.get(&key).ok_or_else(|| {
                let c = centroid(&raw.nodes, &tri);
                topology_error(raw, format!(
                    "the triangle shared by a steel and a concrete tet at ({:.6}, {:.6}, {:.6}) m is in neither interface_adhesive nor interface_free",
                    c[0], c[1], c[2]
                ))
            })?;
            matched += 1;
            let st = steel[ks as usize];
            let fl = TET_FACES[fs as usize];
            let mut s = fl.map(|j| st[j]);
            let q = raw.nodes[st[fs as usize] as usize];
            let p = s.map(|i| raw.nodes[i as usize]);
            let mut nrm = cross(sub(p[1], p[0]), sub(p[2], p[0]));
            // The steel tet's fourth node lies on the steel side: n must point away from it.
            if dot(nrm, sub(q, p[0])) > 0.0 {
                s.swap(1, 2);
                nrm = scale(nrm, -1.0);
            }
            let a2 = norm(nrm);
            let n = scale(nrm, 1.0 / a2);
            let frame = make_frame(n, centroid(&raw.nodes, &s));
            let (id, twin) = (&numbering.new_id, &numbering.twin);
            interfaces.push(InterfaceElement {
                nodes: [
                    id[s[0] as usize],
                    id[s[1] as usize],
                    id[s[2] as usize],
                    twin[s[0] as usize],
                    twin[s[1] as usize],
                    twin[s[2] as usize],
                ],
                zone,
                frame,
                area: 0.5 * a2,
            });
        }
    }
    if matched != zone_of.len() {
        return Err(topology_error(raw, format!(
            "{} triangles of interface_adhesive/interface_free are not shared by a steel and a concrete tet ({} are)",
            zone_of.len() - matched.min(zone_of.len()),
            matched
        )));
    }
    Ok(interfaces)
}

/// The model's tets (steel, then concrete) in model ids, with their
/// region, characteristic size and quality, and the regions' volumes.
struct Tets {
    tets: Vec<[u32; 4]>,
    region: Vec<Region>,
    size: Vec<f64>,
    quality: Vec<f64>,
    volume_steel: f64,
    volume_concrete: f64,
}

impl Tets {
    fn renumbered(
        raw: &RawMesh,
        numbering: &Numbering,
        steel: &[[u32; 4]],
        concrete: &[[u32; 4]],
    ) -> Self {
        let n = steel.len() + concrete.len();
        let mut out = Tets {
            tets: Vec::with_capacity(n),
            region: Vec::with_capacity(n),
            size: Vec::with_capacity(n),
            quality: Vec::with_capacity(n),
            volume_steel: 0.0,
            volume_concrete: 0.0,
        };
        for (list, region) in [(steel, Region::Steel), (concrete, Region::Concrete)] {
            for t in list.iter() {
                let p = t.map(|i| raw.nodes[i as usize]);
                let v = tet_volume(p);
                match region {
                    Region::Steel => out.volume_steel += v,
                    Region::Concrete => out.volume_concrete += v,
                }
                out.size.push(characteristic_size(v));
                out.quality.push(tet_quality(p));
                out.region.push(region);
                out.tets.push(match region {
                    Region::Steel => t.map(|i| numbering.new_id[i as usize]),
                    Region::Concrete => t.map(|i| numbering.concrete_id(i)),
                });
            }
        }
        out
    }
}

/// The model ids of the nodes of physical surface `group` on `side`:
/// steel faces keep original ids, concrete faces use twins.
fn side_set(
    raw: &RawMesh,
    numbering: &Numbering,
    group: &str,
    side: Region,
) -> Result<Vec<u32>, MeshError> {
    let mut v = Vec::new();
    for tri in raw.surfaces.get(group).map_or(&[][..], |v| v.as_slice()) {
        for &i in tri {
            let id = match side {
                Region::Steel if numbering.in_steel[i as usize] => numbering.new_id[i as usize],
                Region::Concrete if numbering.in_concrete[i as usize] => numbering.concrete_id(i),
                _ => {
                    return Err(topology_error(
                        raw,
                        format!(
                            "node {} of physical surface \"{group}\" belongs to no {} tet",
                            raw.node_tags[i as usize],
                            if side == Region::Steel {
                                "steel"
                            } else {
                                "concrete"
                            }
                        ),
                    ))
                }
            };
            v.push(id);
        }
    }
    v.sort_unstable();
    v.dedup();
    Ok(v)
}

/// The model ids of the nodes of mirror plane `group`. Mirror-plane faces
/// belong to either side; a node on the plane gets the id of every side
/// whose tets it touches, so an interface node lying in the plane is held
/// through its steel original and its concrete twin.
fn mirror_set(raw: &RawMesh, numbering: &Numbering, group: &str) -> Result<Vec<u32>, MeshError> {
    let mut v = Vec::new();
    for tri in raw.surfaces.get(group).map_or(&[][..], |v| v.as_slice()) {
        for &i in tri {
            let (steel, concrete) = (
                numbering.in_steel[i as usize],
                numbering.in_concrete[i as usize],
            );
            if !steel && !concrete {
                return Err(topology_error(
                    raw,
                    format!(
                        "node {} of physical surface \"{group}\" belongs to no tet",
                        raw.node_tags[i as usize]
                    ),
                ));
            }
            if steel {
                v.push(numbering.new_id[i as usize]);
            }
            if concrete {
                v.push(numbering.concrete_id(i));
            }
        }
    }
    v.sort_unstable();
    v.dedup();
    Ok(v)
}

/// The boundary-condition node sets and the symmetry the mirror-plane
/// groups declare (both: quarter; y = 0 alone: half; none: full; x = 0
/// alone is an error; the half-turn cut plane alone: half-turn).
fn node_sets(raw: &RawMesh, numbering: &Numbering) -> Result<(NodeSets, Symmetry), MeshError> {
    let has = |g: &str| raw.surfaces.get(g).is_some_and(|v| !v.is_empty());
    let present = SYMMETRY_SURFACES.map(has);
    let symmetry = match (present, has(HALF_TURN_SURFACE)) {
        ([false, false], true) => Symmetry::HalfTurn,
        (_, true) => {
            return Err(topology_error(
                raw,
                format!(
                    "physical surface \"{HALF_TURN_SURFACE}\" (a half-turn half model) beside \
                     mirror-plane groups: a model has one kind of symmetry"
                ),
            ));
        }
        ([true, true], false) => Symmetry::Quarter,
        ([false, true], false) => Symmetry::Half,
        ([false, false], false) => Symmetry::Full,
        ([true, false], false) => {
            return Err(missing_group(
                raw,
                SYMMETRY_SURFACES[1],
                &format!(
                    "a physical surface of triangles: \"{}\" is present, and a quarter model \
                     needs both mirror planes (a half model has y = 0 alone)",
                    SYMMETRY_SURFACES[0]
                ),
            ));
        }
    };
    let set = |group: &str, side: Region| side_set(raw, numbering, group, side);
    let plane_y = if symmetry == Symmetry::HalfTurn {
        HALF_TURN_SURFACE
    } else {
        SYMMETRY_SURFACES[1]
    };
    let node_sets = NodeSets {
        bar_loaded_end: set("bar_loaded_end", Region::Steel)?,
        bar_free_end: set("bar_free_end", Region::Steel)?,
        concrete_bearing_face: set("concrete_bearing_face", Region::Concrete)?,
        concrete_free_face: set("concrete_free_face", Region::Concrete)?,
        symmetry_x: mirror_set(raw, numbering, SYMMETRY_SURFACES[0])?,
        symmetry_y: mirror_set(raw, numbering, plane_y)?,
    };
    Ok((node_sets, symmetry))
}

fn centroid(nodes: &[V3], tri: &[u32; 3]) -> V3 {
    let mut c = [0.0; 3];
    for &i in tri {
        for k in 0..3 {
            c[k] += nodes[i as usize][k] / 3.0;
        }
    }
    c
}

/// The frame of an interface element with unit normal `n` at `centre`:
/// t = e_z projected on the plane ⟂ n. Where the surface is normal to the
/// axis (a rib flank at 90°) that projection vanishes and t is the radial
/// direction e_r (from the axis through `centre`) projected instead.
pub fn make_frame(n: V3, centre: V3) -> Frame {
    let project = |v: V3| sub(v, scale(n, dot(v, n)));
    let mut t = project([0.0, 0.0, 1.0]);
    if norm(t) < 1e-6 {
        t = project([centre[0], centre[1], 0.0]);
        if norm(t) < 1e-12 * (1.0 + norm(centre)) {
            // On the axis itself: any direction in the plane.
            t = project(if n[0].abs() < 0.9 {
                [1.0, 0.0, 0.0]
            } else {
                [0.0, 1.0, 0.0]
            });
        }
    }
    let t = scale(t, 1.0 / norm(t));
    Frame {
        n,
        t,
        h: cross(n, t),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eq. 11: the characteristic size of a regular tet is its edge length.
    #[test]
    fn size_of_regular_tet_is_its_edge() {
        let a = 2e-3;
        let p = [
            [0.0, 0.0, 0.0],
            [a, 0.0, 0.0],
            [a / 2.0, a * 3f64.sqrt() / 2.0, 0.0],
            [a / 2.0, a * 3f64.sqrt() / 6.0, a * (2.0f64 / 3.0).sqrt()],
        ];
        assert!((characteristic_size(tet_volume(p)) - a).abs() < 1e-15);
        assert!((tet_quality(p) - 1.0).abs() < 1e-12);
        // A flattened tet has a low quality.
        let mut flat = p;
        flat[3][2] = 1e-3 * a;
        assert!(tet_quality(flat) < 0.01);
    }

    /// The frame is orthonormal and right-handed, t along z where possible (SPEC §4).
    #[test]
    fn frame_is_orthonormal() {
        let n = [0.6, 0.0, 0.8];
        let f = make_frame(n, [1.0, 0.0, 0.0]);
        assert!(f.t[2] > 0.0 && dot(f.t, n).abs() < 1e-14 && (norm(f.t) - 1.0).abs() < 1e-14);
        let h = cross(f.n, f.t);
        assert!(norm(sub(h, f.h)) < 1e-14);
        // A flank normal to the axis: t radial.
        let f = make_frame([0.0, 0.0, -1.0], [0.0, 2.0, 0.5]);
        assert!((f.t[1] - 1.0).abs() < 1e-14);
    }
}
