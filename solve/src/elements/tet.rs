//! Linear (4-node, constant-strain) tetrahedron kernels.
//!
//! With shape functions N_a linear in x, the strain ε = B u is constant over
//! the element, so one integration point (the centroid, weight V) is exact
//! for the stiffness `K_e = V Bᵀ D B` and the internal force `f_e = V Bᵀ σ`.
//! Voigt order `[xx, yy, zz, xy, yz, xz]` with engineering shear strains,
//! as in [`crate::laws`]. Element DOFs are node-major: `[u0x, u0y, u0z, u1x, …]`.
//!
//! The kernels know nothing global: they read the 4 nodal coordinates (m)
//! and write into caller buffers.

use nalgebra::{Matrix6, Vector6};

/// A tetrahedron that cannot be integrated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ElementError {
    #[error(
        "tetrahedron has non-positive or non-finite volume {volume:e} m^3 (inverted or degenerate)"
    )]
    BadVolume { volume: f64 },
}

/// Geometry of one tetrahedron: volume and shape-function gradients.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TetGeometry {
    /// Volume V, m³.
    pub volume: f64,
    /// ∇N_a for the 4 nodes, 1/m.
    pub grad: [[f64; 3]; 4],
}

impl TetGeometry {
    /// Volume and gradients from the nodal coordinates (m); the node order
    /// must give a positive signed volume.
    pub fn new(x: &[[f64; 3]; 4]) -> Result<Self, ElementError> {
        let d = |a: usize| [x[a][0] - x[0][0], x[a][1] - x[0][1], x[a][2] - x[0][2]];
        let (e1, e2, e3) = (d(1), d(2), d(3));
        let cross = |a: [f64; 3], b: [f64; 3]| {
            [
                a[1] * b[2] - a[2] * b[1],
                a[2] * b[0] - a[0] * b[2],
                a[0] * b[1] - a[1] * b[0],
            ]
        };
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let det = dot(e1, cross(e2, e3));
        let volume = det / 6.0;
        if !(volume > 0.0 && volume.is_finite()) {
            return Err(ElementError::BadVolume { volume });
        }
        // Rows of the inverse Jacobian are the gradients of N_1..N_3.
        let g1 = cross(e2, e3).map(|v| v / det);
        let g2 = cross(e3, e1).map(|v| v / det);
        let g3 = cross(e1, e2).map(|v| v / det);
        let g0 = [
            -g1[0] - g2[0] - g3[0],
            -g1[1] - g2[1] - g3[1],
            -g1[2] - g2[2] - g3[2],
        ];
        Ok(Self {
            volume,
            grad: [g0, g1, g2, g3],
        })
    }

    /// Strain ε = B u (Voigt, engineering shear) from the 12 nodal displacements (m).
    pub fn strain(&self, u: &[f64; 12]) -> Vector6<f64> {
        let mut e = Vector6::zeros();
        for (a, g) in self.grad.iter().enumerate() {
            let (ux, uy, uz) = (u[3 * a], u[3 * a + 1], u[3 * a + 2]);
            e[0] += g[0] * ux;
            e[1] += g[1] * uy;
            e[2] += g[2] * uz;
            e[3] += g[1] * ux + g[0] * uy;
            e[4] += g[2] * uy + g[1] * uz;
            e[5] += g[2] * ux + g[0] * uz;
        }
        e
    }

    /// Internal force f = V Bᵀ σ (N) for the stress σ (Pa), written into `out`.
    pub fn internal_force(&self, stress: &Vector6<f64>, out: &mut [f64; 12]) {
        let s = stress * self.volume;
        for (a, g) in self.grad.iter().enumerate() {
            out[3 * a] = g[0] * s[0] + g[1] * s[3] + g[2] * s[5];
            out[3 * a + 1] = g[1] * s[1] + g[0] * s[3] + g[2] * s[4];
            out[3 * a + 2] = g[2] * s[2] + g[1] * s[4] + g[0] * s[5];
        }
    }

    /// Stiffness K = V Bᵀ D B (N/m) for the 6×6 tangent D (Pa), row-major into `out`.
    pub fn stiffness(&self, tangent: &Matrix6<f64>, out: &mut [f64; 144]) {
        // Column (a, i) of B has three non-zeros: Voigt rows VOIGT_ROW[i][k]
        // holding ∇N_a[GRAD_COMPONENT[i][k]]. Using that structure instead of
        // the dense 6×12 B halves the products and removes every branch
        // (this kernel runs for every tet at every Newton iteration).
        const VOIGT_ROW: [[usize; 3]; 3] = [[0, 3, 5], [1, 3, 4], [2, 4, 5]];
        const GRAD_COMPONENT: [[usize; 3]; 3] = [[0, 1, 2], [1, 0, 2], [2, 1, 0]];
        // V D B, one Voigt column per element DOF.
        let mut db = [[0.0f64; 6]; 12];
        for (b, g) in self.grad.iter().enumerate() {
            for j in 0..3 {
                let w = GRAD_COMPONENT[j].map(|c| g[c] * self.volume);
                for (r, dbr) in db[3 * b + j].iter_mut().enumerate() {
                    *dbr = tangent[(r, VOIGT_ROW[j][0])] * w[0]
                        + tangent[(r, VOIGT_ROW[j][1])] * w[1]
                        + tangent[(r, VOIGT_ROW[j][2])] * w[2];
                }
            }
        }
        for (a, g) in self.grad.iter().enumerate() {
            for i in 0..3 {
                let w = GRAD_COMPONENT[i].map(|c| g[c]);
                let rows = VOIGT_ROW[i];
                let row = &mut out[12 * (3 * a + i)..12 * (3 * a + i + 1)];
                for (k, dbc) in row.iter_mut().zip(&db) {
                    *k = w[0] * dbc[rows[0]] + w[1] * dbc[rows[1]] + w[2] * dbc[rows[2]];
                }
            }
        }
    }
}

/// Characteristic size l = (12 V / √2)^(1/3) of a tetrahedron of volume V
/// (m³), paper eq. (11); the edge of the regular tetrahedron of that volume, m.
pub fn characteristic_size(volume: f64) -> f64 {
    (12.0 * volume / std::f64::consts::SQRT_2).cbrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::laws::elastic::isotropic_stiffness;

    fn tet() -> [[f64; 3]; 4] {
        [
            [0.1, 0.0, 0.05],
            [1.2, 0.1, 0.0],
            [0.2, 0.9, 0.1],
            [0.3, 0.2, 1.1],
        ]
    }

    /// Rigid-body translations and rotations produce no strain and no force
    /// (consistency of the B matrix; standard FE requirement).
    #[test]
    fn rigid_modes_are_strain_free() {
        let g = TetGeometry::new(&tet()).unwrap();
        let x = tet();
        let mut u = [0.0; 12];
        for a in 0..4 {
            // small rotation about an arbitrary axis plus translation
            let w = [0.3, -0.2, 0.5];
            let p = x[a];
            u[3 * a] = 1.0 + w[1] * p[2] - w[2] * p[1];
            u[3 * a + 1] = -2.0 + w[2] * p[0] - w[0] * p[2];
            u[3 * a + 2] = 0.5 + w[0] * p[1] - w[1] * p[0];
        }
        let e = g.strain(&u);
        assert!(e.norm() < 1e-14, "{e}");
        let k = {
            let mut k = [0.0; 144];
            g.stiffness(&isotropic_stiffness(30e9, 0.2), &mut k);
            k
        };
        for i in 0..12 {
            let f: f64 = (0..12).map(|j| k[12 * i + j] * u[j]).sum();
            assert!(f.abs() < 1e-3, "row {i}: {f}");
        }
    }

    /// The stiffness is symmetric and consistent with the internal force
    /// (K u = V Bᵀ D B u) for a linear law.
    #[test]
    fn stiffness_matches_internal_force() {
        let g = TetGeometry::new(&tet()).unwrap();
        let d = isotropic_stiffness(30e9, 0.2);
        let mut k = [0.0; 144];
        g.stiffness(&d, &mut k);
        let u: [f64; 12] = std::array::from_fn(|i| ((i * 7 + 3) % 5) as f64 * 1e-4 - 2e-4);
        let mut f = [0.0; 12];
        g.internal_force(&(d * g.strain(&u)), &mut f);
        for i in 0..12 {
            let ku: f64 = (0..12).map(|j| k[12 * i + j] * u[j]).sum();
            assert!((ku - f[i]).abs() < 1e-9 * f.iter().map(|v| v.abs()).fold(0.0, f64::max));
            for j in 0..12 {
                assert!((k[12 * i + j] - k[12 * j + i]).abs() < 1e-6 * k[12 * i + i].abs());
            }
        }
    }

    #[test]
    fn stiffness_equals_dense_bt_d_b_for_an_unsymmetric_tangent() {
        let g = TetGeometry::new(&tet()).unwrap();
        let d = Matrix6::from_fn(|r, c| {
            ((r * 5 + c * 3) % 7) as f64 * 1e9 - 2e9 + if r == c { 3e10 } else { 0.0 }
        });
        let mut k = [0.0; 144];
        g.stiffness(&d, &mut k);
        // Dense B (6×12) column by column from strain(e_j).
        let b: Vec<Vector6<f64>> = (0..12)
            .map(|j| {
                let mut u = [0.0; 12];
                u[j] = 1.0;
                g.strain(&u)
            })
            .collect();
        for i in 0..12 {
            for j in 0..12 {
                let dense = g.volume * b[i].dot(&(d * b[j]));
                assert!(
                    (k[12 * i + j] - dense).abs() <= 1e-12 * dense.abs().max(1e9 * g.volume),
                    "K[{i}][{j}] = {} against {dense}",
                    k[12 * i + j]
                );
            }
        }
    }

    #[test]
    fn inverted_tet_is_an_error() {
        let mut x = tet();
        x.swap(1, 2);
        assert!(matches!(
            TetGeometry::new(&x),
            Err(ElementError::BadVolume { .. })
        ));
    }
}
