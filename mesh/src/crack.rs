//! Whether a set of concrete tets cuts the cover: a band of them, joined
//! through shared nodes, that reaches from the bar's surface to a lateral
//! face of the cube. A splitting crack of a pull-out specimen is such a
//! band of fully damaged tets; damage in front of the ribs that does not
//! reach the faces is not.

use crate::model::{Model, Region, Symmetry};

impl Model {
    /// The tets of `marked` (one flag per tet; steel tets are ignored) in
    /// bands that join the concrete side of the interface to a lateral face
    /// of the cube (|x| or |y| at the cube's half side), connected through
    /// shared nodes and, in a half-turn half, through the twins of the cut
    /// plane (a band that meets the cut at (−x, 0, z) goes on as the image
    /// of the region at (x, 0, z)). 0 where no band crosses the cover.
    pub fn cover_crossing_tets(&self, marked: &[bool]) -> usize {
        let n = self.nodes.len();
        let counts = |t: usize| {
            marked.get(t).copied().unwrap_or(false) && self.tet_region[t] == Region::Concrete
        };
        let mut sets = DisjointSets::new(n);
        let mut any = false;
        for (t, tet) in self.tets.iter().enumerate() {
            if !counts(t) {
                continue;
            }
            any = true;
            for &m in &tet[1..] {
                sets.union(tet[0] as usize, m as usize);
            }
        }
        if !any {
            return 0;
        }
        if self.symmetry == Symmetry::HalfTurn {
            if let Ok(twins) = self.half_turn_twins() {
                for (a, b) in twins.pairs {
                    sets.union(a as usize, b as usize);
                }
            }
        }
        let mut at_bar = vec![false; n];
        for e in &self.interfaces {
            for &c in &e.nodes[3..] {
                at_bar[sets.find(c as usize)] = true;
            }
        }
        let half_side = self
            .nodes
            .iter()
            .zip(&self.node_region)
            .filter(|(_, r)| **r == Region::Concrete)
            .fold(0.0f64, |a, (x, _)| a.max(x[0].abs()).max(x[1].abs()));
        let tol = 1e-9 * half_side;
        let mut at_face = vec![false; n];
        for (i, x) in self.nodes.iter().enumerate() {
            let on_face =
                (x[0].abs() - half_side).abs() <= tol || (x[1].abs() - half_side).abs() <= tol;
            if on_face && self.node_region[i] == Region::Concrete {
                at_face[sets.find(i)] = true;
            }
        }
        self.tets
            .iter()
            .enumerate()
            .filter(|&(t, tet)| {
                counts(t) && {
                    let root = sets.find(tet[0] as usize);
                    at_bar[root] && at_face[root]
                }
            })
            .count()
    }
}

/// Union–find over node indices, with path halving.
struct DisjointSets {
    parent: Vec<usize>,
}

impl DisjointSets {
    fn new(n: usize) -> Self {
        Self {
            parent: (0..n).collect(),
        }
    }
    fn find(&mut self, mut i: usize) -> usize {
        while self.parent[i] != i {
            self.parent[i] = self.parent[self.parent[i]];
            i = self.parent[i];
        }
        i
    }
    fn union(&mut self, a: usize, b: usize) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            self.parent[ra] = rb;
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::model::{Frame, InterfaceElement, InterfaceZone, Model, Region};

    /// A row of `cells` concrete cubes (6 tets each) from the bar's
    /// surface x = r to the cube's face x = s, 1 mm across, with an
    /// interface triangle on x = r and a steel tet beyond it.
    fn strip(cells: usize) -> Model {
        let (r, s) = (4e-3, 12e-3);
        let dx = (s - r) / cells as f64;
        let mut m = Model::default();
        for i in 0..=cells {
            for k in 0..2 {
                for j in 0..2 {
                    m.nodes
                        .push([r + i as f64 * dx, j as f64 * 1e-3, k as f64 * 1e-3]);
                    m.node_region.push(Region::Concrete);
                }
            }
        }
        let node = |i: usize, j: usize, k: usize| (4 * i + 2 * k + j) as u32;
        for i in 0..cells {
            let c = |b: usize| node(i + (b & 1), (b >> 1) & 1, (b >> 2) & 1);
            // Kuhn's six tets of the cube along its diagonal 0–7.
            for p in [[1, 3], [3, 2], [2, 6], [6, 4], [4, 5], [5, 1]] {
                m.tets.push([c(0), c(p[0]), c(p[1]), c(7)]);
                m.tet_region.push(Region::Concrete);
                m.tet_size.push(1e-3);
            }
        }
        // The steel side of the interface and one steel tet.
        let steel: Vec<u32> = (0..4)
            .map(|q| {
                m.nodes
                    .push([r, (q & 1) as f64 * 1e-3, (q >> 1) as f64 * 1e-3]);
                m.node_region.push(Region::Steel);
                (m.nodes.len() - 1) as u32
            })
            .collect();
        m.nodes.push([r - 1e-3, 0.0, 0.0]);
        m.node_region.push(Region::Steel);
        m.tets
            .push([steel[0], steel[1], steel[2], (m.nodes.len() - 1) as u32]);
        m.tet_region.push(Region::Steel);
        m.tet_size.push(1e-3);
        m.interfaces.push(InterfaceElement {
            nodes: [
                steel[0],
                steel[1],
                steel[2],
                node(0, 0, 0),
                node(0, 1, 0),
                node(0, 0, 1),
            ],
            zone: InterfaceZone::Adhesive,
            frame: Frame {
                n: [1.0, 0.0, 0.0],
                t: [0.0, 0.0, 1.0],
                h: [0.0, -1.0, 0.0],
            },
            area: 0.5e-6,
        });
        // The cube's half side is set by a concrete node at y = s.
        m.nodes.push([r, s, 0.0]);
        m.node_region.push(Region::Concrete);
        m
    }

    #[test]
    fn a_band_from_the_bar_to_the_face_crosses_the_cover() {
        let m = strip(4);
        let concrete = 6 * 4;
        let mut marked = vec![true; m.tets.len()];
        // Every concrete tet: all of them cross; the steel tet never counts.
        assert_eq!(m.cover_crossing_tets(&marked), concrete);
        // One cell left whole near the face: no band reaches it.
        for flag in &mut marked[18..24] {
            *flag = false;
        }
        assert_eq!(m.cover_crossing_tets(&marked), 0);
        // One tet of that cell cracked joins the band to the face.
        marked[18] = true;
        let crossing = m.cover_crossing_tets(&marked);
        assert!(crossing == 19, "{crossing}");
        // Nothing marked, or a band that starts away from the bar.
        assert_eq!(m.cover_crossing_tets(&vec![false; m.tets.len()]), 0);
        let mut outer = vec![false; m.tets.len()];
        outer[6..24].iter_mut().for_each(|f| *f = true);
        assert_eq!(m.cover_crossing_tets(&outer), 0);
    }
}
