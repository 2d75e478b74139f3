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

use crate::laws::{InterfaceLaw, InterfaceResponse, InterfaceState, LawError, TangentKind};
use mesh::InterfaceElement;
use nalgebra::{Matrix3, Vector3};

/// Number of integration points (node pairs) of an interface element.
pub const INTERFACE_POINTS: usize = 3;

/// Precomputed nodes, frame and weight of one interface element.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InterfaceKernel {
    /// Global node indices `[s0, s1, s2, c0, c1, c2]`.
    pub nodes: [u32; 6],
    /// Rotation global → local, rows `n, t, h`.
    pub rotation: Matrix3<f64>,
    /// Integration weight A/3 of each node pair, m².
    pub weight: f64,
}

/// The law's answer at one node pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointResponse {
    /// Local jump `(u_n, u_t, u_h)`, m.
    pub jump: Vector3<f64>,
    /// Traction, tangent and trial state.
    pub law: InterfaceResponse,
}

/// The law failed at one node pair.
#[derive(Debug, Clone, PartialEq)]
pub struct PointError {
    pub point: usize,
    pub source: LawError,
}

impl InterfaceKernel {
    pub fn new(element: &InterfaceElement) -> Self {
        let f = &element.frame;
        let rotation = Matrix3::new(
            f.n[0], f.n[1], f.n[2], f.t[0], f.t[1], f.t[2], f.h[0], f.h[1], f.h[2],
        );
        Self {
            nodes: element.nodes,
            rotation,
            weight: element.area / INTERFACE_POINTS as f64,
        }
    }

    /// The 18 element values of the global node-major vector `v`.
    pub fn gather(&self, v: &[f64]) -> [f64; 18] {
        std::array::from_fn(|i| v[3 * self.nodes[i / 3] as usize + i % 3])
    }

    /// Local jump `(u_n, u_t, u_h)` (m) at integration point `point` from the
    /// 18 element displacements (m).
    pub fn local_jump(&self, u: &[f64; 18], point: usize) -> Vector3<f64> {
        let s = 3 * point;
        let c = 3 * (point + 3);
        let jump = Vector3::new(u[c] - u[s], u[c + 1] - u[s + 1], u[c + 2] - u[s + 2]);
        self.rotation * jump
    }

    /// Steps `law` at every node pair from the pairs' `committed` states at
    /// the global displacement `u` (m): the one place where an interface
    /// element meets its law (assembly, fields, energy and profiles all
    /// read tractions through it).
    pub fn tractions(
        &self,
        law: &dyn InterfaceLaw,
        u: &[f64],
        committed: &[InterfaceState],
        kind: TangentKind,
    ) -> Result<[PointResponse; INTERFACE_POINTS], PointError> {
        let ue = self.gather(u);
        let mut out = [PointResponse {
            jump: Vector3::zeros(),
            law: InterfaceResponse {
                traction: Vector3::zeros(),
                tangent: Matrix3::zeros(),
                state: InterfaceState::default(),
            },
        }; INTERFACE_POINTS];
        for (point, (o, state)) in out.iter_mut().zip(committed).enumerate() {
            let jump = self.local_jump(&ue, point);
            let law = match state.held {
                None => law.step(state, &jump, kind),
                // Held by the solver: the traction at the held history,
                // the state the law's own update (what settles the hold).
                Some(held) => law
                    .step(
                        &InterfaceState {
                            held: None,
                            ..*state
                        },
                        &jump,
                        kind,
                    )
                    .and_then(|implicit| {
                        let at_held = law.held_step(&held.state(), &jump, kind)?;
                        Ok(InterfaceResponse {
                            state: InterfaceState {
                                held: Some(held),
                                ..implicit.state
                            },
                            ..at_held
                        })
                    }),
            }
            .map_err(|source| PointError { point, source })?;
            *o = PointResponse { jump, law };
        }
        Ok(out)
    }

    /// Adds the nodal forces (N) of the local traction (Pa) at `point` into `out`.
    pub fn add_force(&self, point: usize, traction: &Vector3<f64>, out: &mut [f64; 18]) {
        let g = self.rotation.transpose() * traction * self.weight;
        for k in 0..3 {
            out[3 * point + k] -= g[k];
            out[3 * (point + 3) + k] += g[k];
        }
    }

    /// Stiffness (N/m) of the local tangent (N/m³) at a node pair, over the
    /// pair's DOFs `[s_p (3), c_p (3)]` (6×6 row-major): the nodal rule
    /// couples a pair to nothing else.
    pub fn pair_stiffness(&self, tangent: &Matrix3<f64>) -> [f64; 36] {
        let k = self.rotation.transpose() * tangent * self.rotation * self.weight;
        let mut out = [0.0; 36];
        for i in 0..3 {
            for j in 0..3 {
                let v = k[(i, j)];
                out[6 * i + j] = v;
                out[6 * (i + 3) + j + 3] = v;
                out[6 * i + j + 3] = -v;
                out[6 * (i + 3) + j] = -v;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::laws::{elastic::ElasticInterface, InterfaceLaw};
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
        let committed = [InterfaceState::default(); INTERFACE_POINTS];
        let points = k
            .tractions(&law, &u, &committed, TangentKind::Consistent)
            .unwrap();
        for (p, r) in points.iter().enumerate() {
            assert!((r.jump - jump_local).norm() < 1e-18);
            k.add_force(p, &r.law.traction, &mut f);
            let pair = k.pair_stiffness(&r.law.tangent);
            let d: [usize; 6] = std::array::from_fn(|i| 3 * (p + 3 * (i / 3)) + i % 3);
            for a in 0..6 {
                for b in 0..6 {
                    kk[18 * d[a] + d[b]] += pair[6 * a + b];
                }
            }
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
