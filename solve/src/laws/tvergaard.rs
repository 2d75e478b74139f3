//! Tvergaard's cohesive zone model as modified in the paper's Appendix A
//! (eqs. A.1–A.11).
//!
//! * Equivalent opening λ = √(⟨u_n⟩₊² + (u_t² + u_h²)/δ_s) (A.2).
//! * Damage indicator λ̃ = max(λ̃_p, λ − λ_0, 0) (A.4), kept in
//!   `InterfaceState::lambda_max`; damage D = 1 − exp(−f_t λ̃ / G_f) (A.9).
//! * Stiffnesses K_n = f_t/λ_0 (A.7), K_s = K_n/δ_s (A.3).
//! * With S = λ_0/(λ̃ + λ_0) · exp(−f_t λ̃/G_f), the four printed cases
//!   (A.5, A.6, A.8, A.10, A.11) are one formula:
//!   σ_n = S K_n u_n if u_n ≥ 0, K_n u_n otherwise; σ_s = S K_s u_s.
//!   While damage grows λ̃ + λ_0 = λ (A.10–A.11); otherwise the history value
//!   makes unloading secant toward the origin (A.6, A.8).
//!
//! Tangents: `Elastic` → diag(K_n, K_s, K_s); `Secant` → diag(S K_n or K_n,
//! S K_s, S K_s) (exactly σ = T u); `Consistent` → the secant when λ̃ does not
//! grow, plus v ⊗ (dS/dλ) ∂λ/∂u when it does (v = σ/S on the damaged
//! components). In pure tension the area under σ_n(u_n) is f_t λ_0/2 + G_f.
//!
//! Reference: V. Tvergaard, "Effect of fibre debonding in a whisker-reinforced
//! metal", Mater. Sci. Eng. A 125 (1990); Abbas, Bary, Jason (2023) App. A.

use super::contract::{
    check_finite, check_result, extrapolated_lambda, lambda_step, InterfaceLaw, InterfaceResponse,
    InterfaceState, LawError, TangentKind,
};
use nalgebra::{Matrix3, Vector3};
use serde::{Deserialize, Serialize};

/// Modified Tvergaard cohesive law.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Tvergaard {
    /// Tensile strength f_t, Pa.
    pub tensile_strength: f64,
    /// Fracture energy G_f, N/m.
    pub fracture_energy: f64,
    /// Damage threshold λ_0, m.
    pub lambda0: f64,
    /// Stiffness ratio δ_s = K_n/K_s (dimensionless).
    pub delta_s: f64,
}

/// Equivalent opening λ (A.2) and ∂λ/∂u (zero where λ = 0).
pub(crate) fn opening(jump: &Vector3<f64>, delta_s: f64) -> (f64, Vector3<f64>) {
    let un = jump[0].max(0.0);
    let lam = (un * un + (jump[1] * jump[1] + jump[2] * jump[2]) / delta_s).sqrt();
    if lam > 0.0 {
        (
            lam,
            Vector3::new(un, jump[1] / delta_s, jump[2] / delta_s) / lam,
        )
    } else {
        (0.0, Vector3::zeros())
    }
}

impl Tvergaard {
    /// K_n = f_t/λ_0 (A.7), N/m³.
    pub fn normal_stiffness(&self) -> f64 {
        self.tensile_strength / self.lambda0
    }
    /// K_s = K_n/δ_s (A.3), N/m³.
    pub fn shear_stiffness(&self) -> f64 {
        self.normal_stiffness() / self.delta_s
    }
}

impl InterfaceLaw for Tvergaard {
    fn respond(
        &self,
        committed: &InterfaceState,
        jump: &Vector3<f64>,
        kind: TangentKind,
        evolve: bool,
    ) -> Result<InterfaceResponse, LawError> {
        const LAW: &str = "tvergaard";
        check_finite(LAW, "jump", jump.as_slice())?;
        let (kn, ks) = (self.normal_stiffness(), self.shear_stiffness());
        let c = self.tensile_strength / self.fracture_energy;
        let (lam, dlam) = opening(jump, self.delta_s);
        // Under IMPL-EX the traction takes the extrapolated λ̃, fixed in
        // the step; the state follows the implicit one.
        let step = lambda_step(committed, lam, self.lambda0, evolve);
        let (lt, loading, implicit) = (step.traction, step.loading, step.implicit);
        let big = lt + self.lambda0;
        let s = self.lambda0 / big * (-c * lt).exp();
        let open = jump[0] >= 0.0;
        let diag = Vector3::new(if open { s * kn } else { kn }, s * ks, s * ks);
        let traction = diag.component_mul(jump);
        let tangent = match kind {
            TangentKind::Elastic => self.elastic_stiffness(),
            TangentKind::Secant => Matrix3::from_diagonal(&diag),
            TangentKind::Consistent => {
                let mut t = Matrix3::from_diagonal(&diag);
                if loading {
                    let ds = -s * (1.0 / big + c);
                    let v = Vector3::new(
                        if open { kn * jump[0] } else { 0.0 },
                        ks * jump[1],
                        ks * jump[2],
                    );
                    t += v * dlam.transpose() * ds;
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
                lambda_max: implicit,
                damage: (1.0 - (-c * implicit).exp()).max(committed.damage),
                slip: committed.slip,
                held: None,
                explicit_lambda: committed.explicit_lambda,
                lambda_increment: step.increment,
            },
        })
    }

    fn extrapolate(&self, committed: &InterfaceState, ratio: f64) -> InterfaceState {
        extrapolated_lambda(committed, ratio)
    }

    /// Secant law (the traction unloads to the origin): ½ t·u.
    fn stored_energy(
        &self,
        _state: &InterfaceState,
        jump: &Vector3<f64>,
        traction: &Vector3<f64>,
    ) -> f64 {
        0.5 * traction.dot(jump)
    }

    fn elastic_stiffness(&self) -> Matrix3<f64> {
        Matrix3::from_diagonal(&Vector3::new(
            self.normal_stiffness(),
            self.shear_stiffness(),
            self.shear_stiffness(),
        ))
    }
}
