//! The whole specimen from a symmetric part: a half or quarter model
//! mirrored in its symmetry planes, or a half-turn half joined to its image
//! under the half-turn about the axis. Nodes on a mirror plane (its node
//! set, both sides of the interface) are shared by the part and its image;
//! a half-turn half's cut-plane nodes map onto their twins. Every other
//! node, tet and interface element is copied with the map, and the copies
//! keep their orientation (positive tets, interface triangles numbered the
//! same way round their normal). Used to write fields of the
//! whole specimen and to compare a part with the whole.

use crate::model::{Frame, InterfaceElement, Model, NodeSets, Symmetry};

/// A whole model and where each of its nodes and tets comes from in the part.
#[derive(Debug, Clone)]
pub struct Unfolded {
    pub model: Model,
    /// Node of the part each node of the whole is the image of.
    pub node_source: Vec<u32>,
    /// Tet of the part each tet of the whole is the image of.
    pub tet_source: Vec<u32>,
    /// Per node of the whole, the signs (±1) of x, y, z of the map (a
    /// reflection or the half-turn) from its source: a vector field is
    /// `sign ∘ v(source)`.
    pub node_reflection: Vec<[f64; 3]>,
    /// Interface element of the part each element of the whole is the image of.
    pub interface_source: Vec<u32>,
    /// Per interface element of the whole, +1 or −1: the sign of its frame's
    /// h against its source's (a reflection turns h over to keep h = n × t;
    /// the half-turn does not), so local h components (traction t_h, slip
    /// s_h) take this sign.
    pub interface_h_sign: Vec<f64>,
}

impl Model {
    /// The whole specimen this model is a part of (the model itself, with
    /// identity maps, when it is whole).
    ///
    /// # Panics
    /// On a half-turn half whose cut plane does not pair
    /// ([`Model::half_turn_twins`]): the mesh stage refuses such models.
    pub fn unfold(&self) -> Unfolded {
        let mut u = identity(self);
        match self.symmetry {
            Symmetry::Full => {}
            Symmetry::Half => u = mirror(u, 1),
            Symmetry::Quarter => u = mirror(mirror(u, 0), 1),
            Symmetry::HalfTurn => {
                let twins = self
                    .half_turn_twins()
                    .expect("a half-turn model's cut plane pairs (checked when meshed)");
                let mut twin: Vec<u32> = (0..self.nodes.len() as u32).collect();
                for &(a, b) in &twins.pairs {
                    twin[a as usize] = b;
                    twin[b as usize] = a;
                }
                u = join_image(u, [-1.0, -1.0, 1.0], 1, &twin);
            }
        }
        u.model.symmetry = Symmetry::Full;
        u
    }

    /// A quarter model mirrored in x = 0: the half y ≥ 0 (`None` for a
    /// model that is not a quarter).
    pub fn half_of_quarter(&self) -> Option<Unfolded> {
        (self.symmetry == Symmetry::Quarter).then(|| mirror(identity(self), 0))
    }
}

fn identity(m: &Model) -> Unfolded {
    Unfolded {
        model: m.clone(),
        node_source: (0..m.nodes.len() as u32).collect(),
        tet_source: (0..m.tets.len() as u32).collect(),
        node_reflection: vec![[1.0; 3]; m.nodes.len()],
        interface_source: (0..m.interfaces.len() as u32).collect(),
        interface_h_sign: vec![1.0; m.interfaces.len()],
    }
}

/// Joins `part` and its image in the plane x_axis = 0 (axis 0: x, 1: y),
/// whose nodes are `part`'s symmetry set of that axis.
fn mirror(part: Unfolded, axis: usize) -> Unfolded {
    let mut signs = [1.0; 3];
    signs[axis] = -1.0;
    let identity: Vec<u32> = (0..part.model.nodes.len() as u32).collect();
    join_image(part, signs, axis, &identity)
}

/// Joins `part` and its image under the map x ↦ signs ∘ x (a reflection or
/// the half-turn). The nodes of `part`'s plane set of `axis` (0: x = 0,
/// 1: y = 0) are not copied: their image is the node `plane_image` names.
fn join_image(part: Unfolded, signs: [f64; 3], axis: usize, plane_image: &[u32]) -> Unfolded {
    let Unfolded {
        model: m,
        mut node_source,
        mut tet_source,
        mut node_reflection,
        mut interface_source,
        mut interface_h_sign,
    } = part;
    let plane = match axis {
        0 => &m.node_sets.symmetry_x,
        _ => &m.node_sets.symmetry_y,
    };
    let mut on_plane = vec![false; m.nodes.len()];
    for &n in plane {
        on_plane[n as usize] = true;
    }
    let reflect = |v: [f64; 3]| [signs[0] * v[0], signs[1] * v[1], signs[2] * v[2]];
    // A reflection turns tets inside out and h = n × t over; a rotation not.
    let proper = signs[0] * signs[1] * signs[2] > 0.0;
    let h_turn = if proper { 1.0 } else { -1.0 };
    let mut nodes = m.nodes.clone();
    let mut node_region = m.node_region.clone();
    let image: Vec<u32> = (0..m.nodes.len())
        .map(|i| {
            if on_plane[i] {
                return plane_image[i];
            }
            nodes.push(reflect(m.nodes[i]));
            node_region.push(m.node_region[i]);
            node_source.push(node_source[i]);
            node_reflection.push(reflect(node_reflection[i]));
            (nodes.len() - 1) as u32
        })
        .collect();
    let map = |n: u32| image[n as usize];
    let mut tets = m.tets.clone();
    for (i, t) in m.tets.iter().enumerate() {
        // Swapping two nodes restores a reflected tet.
        let mut t = t.map(map);
        if !proper {
            t.swap(1, 2);
        }
        tets.push(t);
        tet_source.push(tet_source[i]);
    }
    let mut interfaces = m.interfaces.clone();
    for (k, e) in m.interfaces.iter().enumerate() {
        interface_source.push(interface_source[k]);
        interface_h_sign.push(h_turn * interface_h_sign[k]);
        let mut nodes = e.nodes.map(map);
        if !proper {
            nodes.swap(1, 2);
            nodes.swap(4, 5);
        }
        interfaces.push(InterfaceElement {
            nodes,
            // h = n × t stays right-handed: the reflected h turns over.
            frame: Frame {
                n: reflect(e.frame.n),
                t: reflect(e.frame.t),
                h: reflect(e.frame.h).map(|c| h_turn * c),
            },
            ..*e
        });
    }
    let both = |set: &Vec<u32>| {
        let mut v: Vec<u32> = set
            .iter()
            .copied()
            .chain(set.iter().map(|&n| map(n)))
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let s = &m.node_sets;
    let node_sets = NodeSets {
        bar_loaded_end: both(&s.bar_loaded_end),
        bar_free_end: both(&s.bar_free_end),
        concrete_bearing_face: both(&s.concrete_bearing_face),
        concrete_free_face: both(&s.concrete_free_face),
        symmetry_x: if axis == 0 {
            vec![]
        } else {
            both(&s.symmetry_x)
        },
        symmetry_y: if axis == 1 {
            vec![]
        } else {
            both(&s.symmetry_y)
        },
    };
    let symmetry = if axis == 0 && m.symmetry == Symmetry::Quarter {
        Symmetry::Half
    } else {
        Symmetry::Full
    };
    Unfolded {
        model: Model {
            nodes,
            node_region,
            tet_region: [m.tet_region.clone(), m.tet_region.clone()].concat(),
            tet_size: [m.tet_size.clone(), m.tet_size.clone()].concat(),
            tets,
            interfaces,
            node_sets,
            symmetry,
            ..m
        },
        node_source,
        tet_source,
        node_reflection,
        interface_source,
        interface_h_sign,
    }
}
