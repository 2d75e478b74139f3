//! The node ties of a half-turn half model ([`Symmetry::HalfTurn`]): on the
//! cut plane y = 0, each node (x, 0, z) with x < 0 moves as the half-turn
//! image of its twin (−x, 0, z): u = R u_twin, R = diag(−1, −1, 1). Nodes
//! on the axis are their own images, so u_x = u_y = 0 there. gmsh meshes
//! the side x < 0 as the image of the side x > 0 (`Periodic Surface …
//! Rotate`), so the twins' coordinates agree to rounding; the pairing
//! demands it to 1e-9 of the specimen's size and one twin per node on the
//! same side of the interface.

use crate::model::{Model, Region, Symmetry};

/// The cut plane's nodes of a half-turn half model, paired.
#[derive(Debug, Clone, PartialEq)]
pub struct HalfTurnTwins {
    /// (node at x < 0, its twin at x > 0), sorted by the first.
    pub pairs: Vec<(u32, u32)>,
    /// Nodes on the axis x = y = 0.
    pub axis: Vec<u32>,
}

/// The half-turn about the z axis applied to a vector.
pub fn half_turn(v: [f64; 3]) -> [f64; 3] {
    [-v[0], -v[1], v[2]]
}

impl Model {
    /// Pairs the nodes of the cut plane (`node_sets.symmetry_y`) of a
    /// half-turn half model. Fails, naming the first node without a twin, if
    /// the plane was not meshed as its own image.
    pub fn half_turn_twins(&self) -> Result<HalfTurnTwins, String> {
        if self.symmetry != Symmetry::HalfTurn {
            return Err(format!(
                "the model is {:?}, not a half-turn half",
                self.symmetry
            ));
        }
        let plane = &self.node_sets.symmetry_y;
        let scale = plane
            .iter()
            .flat_map(|&n| self.nodes[n as usize])
            .fold(0.0f64, |a, c| a.max(c.abs()));
        let tol = 1e-9 * scale.max(f64::MIN_POSITIVE);
        let side = |n: u32| u8::from(self.node_region[n as usize] == Region::Concrete);
        let (mut positive, mut negative, mut axis) = (Vec::new(), Vec::new(), Vec::new());
        for &n in plane {
            let [x, y, _] = self.nodes[n as usize];
            if y.abs() > tol {
                return Err(format!(
                    "node {n} of the cut plane lies at y = {y:e} m, off the plane y = 0"
                ));
            }
            if x > tol {
                positive.push(n);
            } else if x < -tol {
                negative.push(n);
            } else {
                axis.push(n);
            }
        }
        // Twins sorted by (side, z): each node's candidates are a short run.
        let key = |n: u32| (side(n), self.nodes[n as usize][2]);
        positive.sort_by(|&a, &b| key(a).partial_cmp(&key(b)).unwrap());
        let mut taken = vec![false; positive.len()];
        let mut pairs = Vec::with_capacity(negative.len());
        for &n in &negative {
            let [x, _, z] = self.nodes[n as usize];
            let s = side(n);
            let start = positive.partition_point(|&m| key(m) < (s, z - tol));
            let twins: Vec<usize> = (start..positive.len())
                .take_while(|&i| key(positive[i]) <= (s, z + tol))
                .filter(|&i| (self.nodes[positive[i] as usize][0] + x).abs() <= tol)
                .collect();
            match twins[..] {
                [i] if !taken[i] => {
                    taken[i] = true;
                    pairs.push((n, positive[i]));
                }
                [i] => {
                    return Err(format!(
                        "node {n} at ({x:e}, 0, {z:e}) m shares its twin {} with another node",
                        positive[i]
                    ))
                }
                [] => {
                    return Err(format!(
                        "node {n} at ({x:e}, 0, {z:e}) m of the cut plane has no node at its \
                         half-turn image ({:e}, 0, {z:e}) m on the same side of the interface: \
                         the plane was not meshed as its own image",
                        -x
                    ))
                }
                _ => {
                    return Err(format!(
                        "node {n} at ({x:e}, 0, {z:e}) m has {} nodes at its half-turn image",
                        twins.len()
                    ))
                }
            }
        }
        if let Some(i) = taken.iter().position(|t| !t) {
            let m = positive[i];
            let [x, _, z] = self.nodes[m as usize];
            return Err(format!(
                "node {m} at ({x:e}, 0, {z:e}) m of the cut plane has no node at its \
                 half-turn image ({:e}, 0, {z:e}) m on the same side of the interface",
                -x
            ));
        }
        pairs.sort_unstable();
        axis.sort_unstable();
        Ok(HalfTurnTwins { pairs, axis })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::NodeSets;

    fn model(nodes: Vec<[f64; 3]>, regions: Vec<Region>) -> Model {
        let n = nodes.len() as u32;
        Model {
            nodes,
            node_region: regions,
            node_sets: NodeSets {
                symmetry_y: (0..n).collect(),
                ..NodeSets::default()
            },
            symmetry: Symmetry::HalfTurn,
            ..Model::default()
        }
    }

    /// (−1, 0, 2) pairs with (1, 0, 2) and the axis node stands alone; a
    /// node whose image is on the other side, or off by more than rounding,
    /// is refused and named.
    #[test]
    fn twins_pair_by_image_and_side() {
        let steel = Region::Steel;
        let m = model(
            vec![[1.0, 0.0, 2.0], [0.0, 0.0, 2.0], [-1.0, 0.0, 2.0]],
            vec![steel; 3],
        );
        let t = m.half_turn_twins().unwrap();
        assert_eq!((t.pairs, t.axis), (vec![(2, 0)], vec![1]));
        // The image exists, but on the other side of the interface.
        let m = model(
            vec![[1.0, 0.0, 2.0], [-1.0, 0.0, 2.0]],
            vec![steel, Region::Concrete],
        );
        let e = m.half_turn_twins().unwrap_err();
        assert!(e.contains("node 1") && e.contains("half-turn image"), "{e}");
        // An image off by more than rounding.
        let m = model(
            vec![[1.0, 0.0, 2.0], [-1.0 - 1e-6, 0.0, 2.0]],
            vec![steel; 2],
        );
        assert!(m.half_turn_twins().is_err());
        let m = Model {
            symmetry: Symmetry::Half,
            ..m
        };
        assert!(m.half_turn_twins().unwrap_err().contains("not a half-turn"));
    }
}
