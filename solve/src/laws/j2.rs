//! Von Mises (J2) perfectly plastic steel (paper §2.3: E = 200 GPa, ν = 0.3,
//! σ_y = 365 MPa), integrated by radial return.
//!
//! * Elastic trial: s* = 2G dev(ε − ε_p), with ‖s*‖ the Frobenius norm.
//! * Yield: f = ‖s*‖ − R, R = √(2/3) σ_y (i.e. von Mises stress ≤ σ_y).
//! * If f > 0: s = R n, n = s*/‖s*‖, Δε_p = (‖s*‖ − R)/(2G) n.
//! * σ = K tr(ε) 1 + s.
//!
//! Tangents: `Elastic` and `Secant` → C (there is no useful secant for perfect
//! plasticity; C is positive definite); `Consistent` → C when elastic, and the
//! algorithmic tangent K 1⊗1 + 2G θ (P_dev − n⊗n), θ = R/‖s*‖, when yielding.
//!
//! State: `BulkState::plastic_strain` (Voigt, engineering shear).
//!
//! Reference: J.C. Simo, T.J.R. Hughes, *Computational Inelasticity*,
//! Springer 1998, §3.3 (radial return), with zero hardening.

use super::contract::{
    check_finite, check_result, BulkLaw, BulkResponse, BulkState, LawError, TangentKind,
};
use super::elastic::isotropic_stiffness;
use nalgebra::{Matrix6, Vector6};
use serde::{Deserialize, Serialize};

/// Perfectly plastic von Mises steel.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct J2 {
    /// Young's modulus E, Pa.
    pub young_modulus: f64,
    /// Poisson's ratio ν.
    pub poisson_ratio: f64,
    /// Uniaxial yield stress σ_y, Pa.
    pub yield_stress: f64,
}

impl Default for J2 {
    /// The paper's steel: 200 GPa, 0.3, 365 MPa.
    fn default() -> Self {
        J2 {
            young_modulus: 200e9,
            poisson_ratio: 0.3,
            yield_stress: 365e6,
        }
    }
}

/// Von Mises equivalent stress of a Voigt stress vector, Pa.
pub fn von_mises(s: &Vector6<f64>) -> f64 {
    let p = (s[0] + s[1] + s[2]) / 3.0;
    let d = [s[0] - p, s[1] - p, s[2] - p];
    let n2 =
        d[0] * d[0] + d[1] * d[1] + d[2] * d[2] + 2.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]);
    (1.5 * n2).sqrt()
}

impl J2 {
    pub fn stiffness(&self) -> Matrix6<f64> {
        isotropic_stiffness(self.young_modulus, self.poisson_ratio)
    }
}

impl BulkLaw for J2 {
    fn elastic_stiffness(&self) -> Matrix6<f64> {
        self.stiffness()
    }

    fn yield_stress(&self) -> Option<f64> {
        Some(self.yield_stress)
    }

    fn step(
        &self,
        committed: &BulkState,
        strain: &Vector6<f64>,
        kind: TangentKind,
    ) -> Result<BulkResponse, LawError> {
        const LAW: &str = "j2";
        check_finite(LAW, "strain", strain.as_slice())?;
        let (e, nu) = (self.young_modulus, self.poisson_ratio);
        let g = e / (2.0 * (1.0 + nu));
        let k = e / (3.0 * (1.0 - 2.0 * nu));
        let c = self.stiffness();
        let ee = strain - Vector6::from_column_slice(&committed.plastic_strain);
        let tr = ee[0] + ee[1] + ee[2];
        // Deviatoric trial stress, tensor components (shear = G γ = 2G ε_xy).
        let mut s = Vector6::new(
            2.0 * g * (ee[0] - tr / 3.0),
            2.0 * g * (ee[1] - tr / 3.0),
            2.0 * g * (ee[2] - tr / 3.0),
            g * ee[3],
            g * ee[4],
            g * ee[5],
        );
        let norm = (s[0] * s[0]
            + s[1] * s[1]
            + s[2] * s[2]
            + 2.0 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]))
            .sqrt();
        let radius = (2.0f64 / 3.0).sqrt() * self.yield_stress;
        let mut plastic = committed.plastic_strain;
        let mut tangent = c;
        let mut fixed_scale = Some(1.0);
        if norm > radius {
            let n = s / norm;
            let dgamma = (norm - radius) / (2.0 * g);
            for i in 0..3 {
                plastic[i] += dgamma * n[i];
                plastic[i + 3] += 2.0 * dgamma * n[i + 3];
            }
            s = n * radius;
            if kind == TangentKind::Consistent {
                let theta = radius / norm;
                let mut t = Matrix6::zeros();
                for i in 0..3 {
                    for j in 0..3 {
                        t[(i, j)] = k - 2.0 * g * theta / 3.0;
                    }
                    t[(i, i)] += 2.0 * g * theta;
                    t[(i + 3, i + 3)] = g * theta;
                }
                tangent = t - n * n.transpose() * (2.0 * g * theta);
                fixed_scale = None;
            }
        }
        let p = k * tr;
        let stress = Vector6::new(s[0] + p, s[1] + p, s[2] + p, s[3], s[4], s[5]);
        check_result(LAW, "stress", stress.as_slice())?;
        check_result(LAW, "tangent", tangent.as_slice())?;
        Ok(BulkResponse {
            stress,
            tangent,
            state: BulkState {
                plastic_strain: plastic,
                ..*committed
            },
            fixed_scale,
        })
    }
}
