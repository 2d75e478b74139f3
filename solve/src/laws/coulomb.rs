//! Coulomb interface (paper Appendix B): elastic springs K_n, K_s (A.5), a
//! Mohr–Coulomb shear limit and a tension cut-off.
//!
//! * σ_n = K_n u_n; trial shear τ* = K_s (u_s − s_p) (s_p: plastic slip).
//! * Shear limit τ_y = C − σ_n tan φ (B.1 read as the Mohr–Coulomb line of
//!   Fig. B.1, SPEC §5), with 0 ≤ f_t ≤ C / tan φ (B.2) so that τ_y ≥ 0.
//! * |τ*| ≤ τ_y: stick (τ = τ*); otherwise slide: τ = τ_y τ*/|τ*|, slip grows
//!   along τ* only (non-associated: no dilatancy), perfectly plastic.
//! * Tension cut-off: when the normal stress would exceed f_t the interface
//!   separates for good ("the normal stress flips to null instantly", App. B);
//!   it is then a frictional contact: σ_n = K_n ⟨u_n⟩₋, τ_y = −σ_n tan φ.
//!   Separation is stored as `damage = 1`.
//!
//! Tangents: `Elastic` → diag(K_n, K_s, K_s); `Secant` → diag(∂σ_n/∂u_n,
//! K_s r, K_s r), r = 1 sticking, τ_y/|τ*| sliding; `Consistent` → the exact
//! derivative of the return map (sliding: τ_y/|τ*| K_s (I − n⊗n) on the
//! slip block and n ∂τ_y/∂u_n in the normal column).
//!
//! Reference: Abbas, Bary, Jason (2023), Appendix B.

use super::contract::{
    check_finite, check_result, InterfaceLaw, InterfaceResponse, InterfaceState, LawError,
    TangentKind,
};
use nalgebra::{Matrix2, Matrix3, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// Mohr–Coulomb interface with tension cut-off.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Coulomb {
    /// Normal stiffness K_n, N/m³.
    pub normal_stiffness: f64,
    /// Shear stiffness K_s, N/m³.
    pub shear_stiffness: f64,
    /// Tensile strength f_t, Pa (0 ≤ f_t ≤ C / tan φ).
    pub tensile_strength: f64,
    /// Cohesion C, Pa.
    pub cohesion: f64,
    /// Friction angle φ, rad, in [0, π/2).
    pub friction_angle: f64,
}

/// Outcome of a 2-D radial return of the slip for a friction limit `ty`.
pub(crate) struct SlipReturn {
    pub tau: Vector2<f64>,
    pub slip: Vector2<f64>,
    /// ∂τ/∂u_s.
    pub d_tau_d_us: Matrix2<f64>,
    /// ∂τ/∂τ_y (zero when sticking).
    pub d_tau_d_ty: Vector2<f64>,
    /// Secant ratio τ/τ* (1 when sticking).
    pub ratio: f64,
}

/// Radial return of the tangential traction onto |τ| ≤ τ_y (τ_y ≥ 0).
pub(crate) fn slip_return(us: Vector2<f64>, slip: Vector2<f64>, ks: f64, ty: f64) -> SlipReturn {
    let trial = (us - slip) * ks;
    let norm = trial.norm();
    if norm <= ty {
        return SlipReturn {
            tau: trial,
            slip,
            d_tau_d_us: Matrix2::identity() * ks,
            d_tau_d_ty: Vector2::zeros(),
            ratio: 1.0,
        };
    }
    // norm > ty ≥ 0, so the direction is defined.
    let n = trial / norm;
    let ratio = ty / norm;
    SlipReturn {
        tau: n * ty,
        slip: slip + n * ((norm - ty) / ks),
        d_tau_d_us: (Matrix2::identity() - n * n.transpose()) * (ks * ratio),
        d_tau_d_ty: n,
        ratio,
    }
}

impl InterfaceLaw for Coulomb {
    fn respond(
        &self,
        committed: &InterfaceState,
        jump: &Vector3<f64>,
        kind: TangentKind,
        evolve: bool,
    ) -> Result<InterfaceResponse, LawError> {
        const LAW: &str = "coulomb";
        check_finite(LAW, "jump", jump.as_slice())?;
        let (kn, ks) = (self.normal_stiffness, self.shear_stiffness);
        let tan_phi = self.friction_angle.tan();
        let separated = committed.damage >= 1.0 || (evolve && kn * jump[0] > self.tensile_strength);
        let (sn, dsn, ty) = if separated {
            let sn = kn * jump[0].min(0.0);
            (sn, if jump[0] < 0.0 { kn } else { 0.0 }, -sn * tan_phi)
        } else {
            let sn = kn * jump[0];
            (sn, kn, self.cohesion - sn * tan_phi)
        };
        let ty = if evolve { ty.max(0.0) } else { f64::INFINITY };
        let ret = slip_return(
            Vector2::new(jump[1], jump[2]),
            Vector2::new(committed.slip[0], committed.slip[1]),
            ks,
            ty,
        );
        let traction = Vector3::new(sn, ret.tau[0], ret.tau[1]);
        let tangent = match kind {
            TangentKind::Elastic => self.elastic_stiffness(),
            TangentKind::Secant => {
                Matrix3::from_diagonal(&Vector3::new(dsn, ks * ret.ratio, ks * ret.ratio))
            }
            TangentKind::Consistent => {
                let mut t = Matrix3::zeros();
                t[(0, 0)] = dsn;
                let dty_dun = -tan_phi * dsn;
                for i in 0..2 {
                    t[(i + 1, 0)] = ret.d_tau_d_ty[i] * dty_dun;
                    for j in 0..2 {
                        t[(i + 1, j + 1)] = ret.d_tau_d_us[(i, j)];
                    }
                }
                t
            }
        };
        check_result(LAW, "traction", traction.as_slice())?;
        check_result(LAW, "tangent", tangent.as_slice())?;
        Ok(InterfaceResponse {
            traction,
            tangent,
            state: InterfaceState {
                lambda_max: committed.lambda_max,
                damage: if separated { 1.0 } else { committed.damage },
                slip: [ret.slip[0], ret.slip[1]],
                ..InterfaceState::default()
            },
        })
    }

    /// Elastic springs with plastic slip: ½ t_n u_n + ½ |t_s|²/K_s.
    fn stored_energy(
        &self,
        _state: &InterfaceState,
        jump: &Vector3<f64>,
        traction: &Vector3<f64>,
    ) -> f64 {
        let ks = self.elastic_stiffness()[(1, 1)];
        0.5 * traction[0] * jump[0]
            + 0.5 * (traction[1] * traction[1] + traction[2] * traction[2]) / ks
    }

    fn elastic_stiffness(&self) -> Matrix3<f64> {
        Matrix3::from_diagonal(&Vector3::new(
            self.normal_stiffness,
            self.shear_stiffness,
            self.shear_stiffness,
        ))
    }
}
