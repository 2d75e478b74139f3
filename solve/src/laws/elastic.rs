//! Linear elasticity: isotropic bulk (Hooke) and a linear interface
//! t = diag(K_n, K_s, K_s) u. Used for perfect-bond and linear reference
//! runs, and as the undamaged part of the other laws.

use super::contract::{
    BulkLaw, BulkResponse, BulkState, InterfaceLaw, InterfaceResponse, InterfaceState, LawError,
    TangentKind,
};
use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

/// Isotropic stiffness in Voigt form (engineering shear strains).
/// `young_modulus` in Pa; `poisson_ratio` dimensionless, in (-1, 0.5).
pub fn isotropic_stiffness(young_modulus: f64, poisson_ratio: f64) -> Matrix6<f64> {
    let lambda =
        young_modulus * poisson_ratio / ((1.0 + poisson_ratio) * (1.0 - 2.0 * poisson_ratio));
    let mu = young_modulus / (2.0 * (1.0 + poisson_ratio));
    let mut c = Matrix6::zeros();
    for i in 0..3 {
        for j in 0..3 {
            c[(i, j)] = lambda;
        }
        c[(i, i)] += 2.0 * mu;
        c[(i + 3, i + 3)] = mu;
    }
    c
}

/// Isotropic linear elastic bulk law.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LinearElastic {
    /// Young's modulus E, Pa.
    pub young_modulus: f64,
    /// Poisson's ratio ν.
    pub poisson_ratio: f64,
}

impl LinearElastic {
    pub fn stiffness(&self) -> Matrix6<f64> {
        isotropic_stiffness(self.young_modulus, self.poisson_ratio)
    }
}

impl BulkLaw for LinearElastic {
    fn elastic_stiffness(&self) -> Matrix6<f64> {
        self.stiffness()
    }

    fn step(
        &self,
        committed: &BulkState,
        strain: &Vector6<f64>,
        _kind: TangentKind,
    ) -> Result<BulkResponse, LawError> {
        if !strain.iter().all(|v| v.is_finite()) {
            return Err(LawError::NonFiniteInput {
                law: "elastic",
                what: "strain",
            });
        }
        let tangent = self.stiffness();
        Ok(BulkResponse {
            stress: tangent * strain,
            tangent,
            state: *committed,
            fixed_scale: Some(1.0),
        })
    }
}

/// Linear interface: t_n = K_n u_n, t_s = K_s u_s (no damage, no friction).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ElasticInterface {
    /// Normal stiffness K_n, N/m³.
    pub normal_stiffness: f64,
    /// Shear stiffness K_s, N/m³.
    pub shear_stiffness: f64,
}

impl InterfaceLaw for ElasticInterface {
    /// No history to evolve or hold.
    fn respond(
        &self,
        committed: &InterfaceState,
        jump: &Vector3<f64>,
        _kind: TangentKind,
        _evolve: bool,
    ) -> Result<InterfaceResponse, LawError> {
        if !jump.iter().all(|v| v.is_finite()) {
            return Err(LawError::NonFiniteInput {
                law: "elastic interface",
                what: "jump",
            });
        }
        let tangent = self.elastic_stiffness();
        Ok(InterfaceResponse {
            traction: tangent * jump,
            tangent,
            state: *committed,
        })
    }

    /// Elastic: ½ t·u.
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
            self.normal_stiffness,
            self.shear_stiffness,
            self.shear_stiffness,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uniaxial_stress_recovers_young_modulus() {
        // ε = σ/E (1, −ν, −ν) must give σ_xx = σ and zero lateral stress.
        let (e, nu) = (30e9, 0.2);
        let strain = Vector6::new(1e-4, -nu * 1e-4, -nu * 1e-4, 0.0, 0.0, 0.0);
        let s = isotropic_stiffness(e, nu) * strain;
        assert!((s[0] - e * 1e-4).abs() < 1e-6 * e * 1e-4);
        assert!(s[1].abs() < 1e-9 * e * 1e-4 && s[2].abs() < 1e-9 * e * 1e-4);
    }

    #[test]
    fn engineering_shear_gives_shear_modulus() {
        let (e, nu) = (200e9, 0.3);
        let gamma = 1e-4;
        let s = isotropic_stiffness(e, nu) * Vector6::new(0.0, 0.0, 0.0, gamma, 0.0, 0.0);
        assert!((s[3] - e / (2.0 * (1.0 + nu)) * gamma).abs() < 1e-3);
    }
}
