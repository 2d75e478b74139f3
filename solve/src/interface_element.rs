//! 6-node zero-thickness interface element (SPEC §4–§6), in three pieces:
//! 1. the displacement jump `[[u]] = u_concrete − u_steel` at an integration
//!    point, rotated into the local frame `R = [n; t; h]` (rows), so that
//!    `u_n > 0` is opening (n points from steel into concrete);
//! 2. the interface law (local traction and d traction / d jump), called by
//!    the caller;
//! 3. rotation back (`Rᵀ t`, `Rᵀ C R`) and integration over the triangle.
//!
//! Element DOFs are node-major over `[s0, s1, s2, c0, c1, c2]` (18 values).
//!
//! Integration rule: nodal (Newton–Cotes, vertex) quadrature, 3 points at the
//! node pairs `(s_i, c_i)` with weight A/3 each. It integrates the linear
//! jump field's stiffness only approximately (it lumps it), but it decouples
//! the node pairs: each pair carries its own traction, so a stiff cohesive
//! interface (K_n = f_t/λ_0 ≈ 4e10 N/m³ against the bulk's E/h) does not show
//! the spurious traction oscillations that Gauss integration produces
//! (Schellekens & de Borst 1993), and damage initiates node pair by node pair
//! rather than at interior points whose state mixes neighbours. The
//! integration point `i` of an element is therefore the node pair `i`.

use mesh::InterfaceElement;
use nalgebra::{Matrix3, Vector3};

/// Number of integration points (node pairs) of an interface element.
pub const INTERFACE_POINTS: usize = 3;

/// Precomputed frame and weight of one interface element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InterfaceKernel {
    /// Rotation global → local, rows `n, t, h`.
    pub rotation: Matrix3<f64>,
    /// Integration weight A/3 of each node pair, m².
    pub weight: f64,
}

impl InterfaceKernel {
    pub fn new(element: &InterfaceElement) -> Self {
        let f = &element.frame;
        let rotation = Matrix3::new(
            f.n[0], f.n[1], f.n[2], f.t[0], f.t[1], f.t[2], f.h[0], f.h[1], f.h[2],
        );
        Self {
            rotation,
            weight: element.area / INTERFACE_POINTS as f64,
        }
    }

    /// Local jump `(u_n, u_t, u_h)` (m) at integration point `point` from the
    /// 18 element displacements (m).
    pub fn local_jump(&self, u: &[f64; 18], point: usize) -> Vector3<f64> {
        let s = 3 * point;
        let c = 3 * (point + 3);
        let jump = Vector3::new(u[c] - u[s], u[c + 1] - u[s + 1], u[c + 2] - u[s + 2]);
        self.rotation * jump
    }

    /// Adds the nodal forces (N) of the local traction (Pa) at `point` into `out`.
    pub fn add_force(&self, point: usize, traction: &Vector3<f64>, out: &mut [f64; 18]) {
        let g = self.rotation.transpose() * traction * self.weight;
        for k in 0..3 {
            out[3 * point + k] -= g[k];
            out[3 * (point + 3) + k] += g[k];
        }
    }

    /// Adds the stiffness (N/m) of the local tangent (N/m³) at `point` into
    /// `out` (18×18 row-major).
    pub fn add_stiffness(&self, point: usize, tangent: &Matrix3<f64>, out: &mut [f64; 324]) {
        let k = self.rotation.transpose() * tangent * self.rotation * self.weight;
        let (s, c) = (3 * point, 3 * (point + 3));
        for i in 0..3 {
            for j in 0..3 {
                let v = k[(i, j)];
                out[18 * (s + i) + s + j] += v;
                out[18 * (c + i) + c + j] += v;
                out[18 * (s + i) + c + j] -= v;
                out[18 * (c + i) + s + j] -= v;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::laws::{elastic::ElasticInterface, InterfaceLaw, InterfaceState, TangentKind};
    use mesh::{Frame, InterfaceZone};

    fn element() -> InterfaceElement {
        // A tilted frame so that rotation errors would show.
        let (c, s) = (0.6f64, 0.8f64);
        InterfaceElement {
            nodes: [0, 1, 2, 3, 4, 5],
            zone: InterfaceZone::Adhesive,
            frame: Frame {
                n: [c, s, 0.0],
                t: [0.0, 0.0, 1.0],
                h: [s, -c, 0.0],
            },
            area: 2.5e-6,
        }
    }

    /// Under a uniform jump the element's nodal forces per unit area are the
    /// law's traction rotated to the global frame (SPEC §6 patch requirement).
    #[test]
    fn uniform_jump_gives_law_traction() {
        let el = element();
        let k = InterfaceKernel::new(&el);
        let law = ElasticInterface {
            normal_stiffness: 4e10,
            shear_stiffness: 1e10,
        };
        let jump_local = Vector3::new(1e-6, -2e-6, 0.5e-6);
        let jump_global = k.rotation.transpose() * jump_local;
        let mut u = [0.0; 18];
        for p in 0..3 {
            for d in 0..3 {
                u[3 * (p + 3) + d] = jump_global[d] + 0.3e-6;
                u[3 * p + d] = 0.3e-6;
            }
        }
        let mut f = [0.0; 18];
        let mut kk = [0.0; 324];
        for p in 0..3 {
            let j = k.local_jump(&u, p);
            assert!((j - jump_local).norm() < 1e-18);
            let r = law
                .step(&InterfaceState::default(), &j, TangentKind::Consistent)
                .unwrap();
            k.add_force(p, &r.traction, &mut f);
            k.add_stiffness(p, &r.tangent, &mut kk);
        }
        let t_global = k.rotation.transpose() * (law.elastic_stiffness() * jump_local);
        let mut total = [0.0; 3];
        for p in 0..3 {
            for d in 0..3 {
                total[d] += f[3 * (p + 3) + d];
                assert!((f[3 * p + d] + f[3 * (p + 3) + d]).abs() < 1e-12);
            }
        }
        for d in 0..3 {
            assert!((total[d] / el.area - t_global[d]).abs() < 1e-9 * t_global.norm());
        }
        // K u reproduces f for a linear law.
        for i in 0..18 {
            let ku: f64 = (0..18).map(|j| kk[18 * i + j] * u[j]).sum();
            assert!((ku - f[i]).abs() < 1e-9 * t_global.norm() * el.area);
        }
    }
}
