//! Mazars' scalar damage model for concrete (paper §2.3, eqs. 1–13), with
//! Hillerborg regularisation in tension and size-dependent compression
//! parameters.
//!
//! * Stress: σ = (1 − D) C : ε (eq. 1), C isotropic (E, ν).
//! * Equivalent strain: ε_eq = √(Σ ⟨ε_i⟩₊²) over the principal strains (eq. 3);
//!   history κ = max(ε_D0, max over time of ε_eq).
//! * Damage: D = α_t^β D_t(κ) + α_c^β D_c(κ) (eq. 4), α_c = 1 − α_t, with
//!   α_t = Σ ⟨ε_ti⟩₊ ⟨ε_i⟩₊ / ε_eq² (eq. 6) and ε_t the strain of the positive
//!   part of the *effective* stress C:ε (eqs. 7–8), clipped to [0, 1].
//! * D_c (and D_t in the classic form) from eq. (5):
//!   D = 1 − ε_D0 (1 − A)/κ − A exp(−B (κ − ε_D0)).
//! * Regularised tension (eq. 9): D_t = 1 − (ε_D0/κ) exp(B_t (ε_D0 − κ)), with
//!   B_t = l E ε_D0 / (G_f − l E ε_D0²/2), the intended form of the misprinted
//!   eq. (10): it makes the energy per unit crack area l ∫σ dε equal G_f.
//! * Compression from the element size (eqs. 12–13, l in metres), with the
//!   sign of the l² term of eq. (12) corrected (SPEC §5):
//!   A_c = 335.9133 l² + 16.2746 l − 0.0002, B_c = 140984.5429 l² + 29701.4423 l − 0.0996.
//! * Damage never decreases: D = max(D_committed, D(κ, α_t)).
//!
//! Tangents: `Elastic` → C; `Secant` → (1 − D) C; `Consistent` → (1 − D) C
//! when D does not grow in the step (elastic, unloading, reloading below κ),
//! and (1 − D) C − (C:ε) ⊗ ∂D/∂ε when it grows, where ∂D/∂ε contains the
//! exact derivative through κ = ε_eq and the derivative through α_t, the
//! latter evaluated by central differences of the closed-form α_t (it is a
//! piecewise-smooth function of the principal values).
//!
//! State: `BulkState::kappa` (largest ε_eq reached) and `BulkState::damage`.
//!
//! Reference: J. Mazars, "A description of micro- and macroscale damage of
//! concrete structures", Eng. Fract. Mech. 25 (1986); Abbas, Bary, Jason,
//! IJMS 237 (2023), §2.3.

use super::contract::{
    check_finite, check_result, BulkLaw, BulkResponse, BulkState, LawError, TangentKind,
};
use super::elastic::isotropic_stiffness;
use nalgebra::{Matrix3, Matrix6, SymmetricEigen, Vector3, Vector6};
use serde::{Deserialize, Serialize};

/// Default initial damage threshold ε_D0 (paper §2.3).
pub const DEFAULT_EPS_D0: f64 = 1e-4;
/// Default shear correction exponent β (paper §2.3).
pub const DEFAULT_SHEAR_EXPONENT: f64 = 1.06;

/// How tension softening is given.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TensionSoftening {
    /// Hillerborg-regularised exponential softening (eq. 9), B_t from the
    /// fracture energy `fracture_energy` (G_f, N/m) and the element size.
    Regularised { fracture_energy: f64 },
    /// Classical eq. (5) with fixed A_t (dimensionless) and B_t (dimensionless,
    /// multiplies a strain); mesh dependent.
    Classic { a_t: f64, b_t: f64 },
}

/// How compression softening is given.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum CompressionSoftening {
    /// A_c, B_c from the element size by eqs. (12)–(13) (SPEC §5 reading).
    SizeFit,
    /// Fixed A_c, B_c (dimensionless) in eq. (5).
    Classic { a_c: f64, b_c: f64 },
}

/// Mazars concrete as a material (size independent); [`MazarsMaterial::at_size`]
/// gives the law of an element of characteristic size l.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MazarsMaterial {
    /// Young's modulus E, Pa.
    pub young_modulus: f64,
    /// Poisson's ratio ν (dimensionless).
    pub poisson_ratio: f64,
    /// Initial damage threshold ε_D0 (dimensionless strain); f_t = E ε_D0.
    pub eps_d0: f64,
    /// Shear correction exponent β of eq. (4) (dimensionless).
    pub shear_exponent: f64,
    pub tension: TensionSoftening,
    pub compression: CompressionSoftening,
    /// The length l that eqs. (11)–(13) regularise with, m. `None` (the
    /// paper): each element's own size, the crack band of a damage band one
    /// element wide. A fixed length gives every element the same law, with
    /// G_f / l per unit volume whatever the mesh: for damage zones spread
    /// over many elements (in front of the ribs), whose energy per volume
    /// the element-size law changes with the mesh.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub regularisation_length: Option<f64>,
    /// Internal length ℓ of a gradient-enhanced damage, m: κ follows the
    /// equivalent strain averaged by ε̄ − ℓ²∇²ε̄ = ε_eq over the concrete
    /// (Peerlings et al. 1996; `crate::nonlocal`), so a damage zone has a
    /// width of its own instead of one set by the mesh. `None` (the paper):
    /// each point's own ε_eq.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nonlocal_length: Option<f64>,
}

/// Why no law exists for an element of the given size.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MazarsSizeError {
    #[error("Mazars: element size l = {l} m must be positive and finite")]
    BadSize { l: f64 },
    #[error(
        "Mazars: element size l = {l} m is too large for the regularised tension: \
         G_f = {fracture_energy} N/m must exceed l E ε_D0²/2 = {elastic_energy} N/m \
         (snap-back), so l must be below {l_max} m; refine the mesh"
    )]
    TooLarge {
        l: f64,
        fracture_energy: f64,
        elastic_energy: f64,
        l_max: f64,
    },
    #[error(
        "Mazars: element size l = {l} m gives A_c = {a_c}, B_c = {b_c} by eqs. (12)-(13), \
         outside their range (A_c >= 0, B_c > 0 needed); give A_c and B_c explicitly"
    )]
    OutsideFit { l: f64, a_c: f64, b_c: f64 },
}

/// A_c and B_c of eqs. (12)–(13) for an element size `l` in metres (SPEC §5 sign reading).
pub fn compression_fit(l: f64) -> (f64, f64) {
    let a_c = 335.9133 * l * l + 16.2746 * l - 0.0002;
    let b_c = 140984.5429 * l * l + 29701.4423 * l - 0.0996;
    (a_c, b_c)
}

impl MazarsMaterial {
    /// Tensile strength f_t = E ε_D0, Pa.
    pub fn tensile_strength(&self) -> f64 {
        self.young_modulus * self.eps_d0
    }

    /// The law of an element of characteristic size `l` (m, eq. 11).
    /// With a `regularisation_length` every size gets the law of that length.
    pub fn at_size(&self, l: f64) -> Result<Mazars, MazarsSizeError> {
        if !(l.is_finite() && l > 0.0) {
            return Err(MazarsSizeError::BadSize { l });
        }
        let l = self.regularisation_length.unwrap_or(l);
        let (e, e0) = (self.young_modulus, self.eps_d0);
        let tension = match self.tension {
            TensionSoftening::Regularised { fracture_energy } => {
                let elastic_energy = l * e * e0 * e0 / 2.0;
                let denom = fracture_energy - elastic_energy;
                if denom <= 0.0 {
                    return Err(MazarsSizeError::TooLarge {
                        l,
                        fracture_energy,
                        elastic_energy,
                        l_max: 2.0 * fracture_energy / (e * e0 * e0),
                    });
                }
                TensionBranch::Exponential {
                    b_t: l * e * e0 / denom,
                }
            }
            TensionSoftening::Classic { a_t, b_t } => TensionBranch::Classic { a_t, b_t },
        };
        let (a_c, b_c) = match self.compression {
            CompressionSoftening::SizeFit => {
                let (a_c, b_c) = compression_fit(l);
                if !(a_c >= 0.0 && b_c > 0.0) {
                    return Err(MazarsSizeError::OutsideFit { l, a_c, b_c });
                }
                (a_c, b_c)
            }
            CompressionSoftening::Classic { a_c, b_c } => (a_c, b_c),
        };
        Ok(Mazars {
            young_modulus: e,
            poisson_ratio: self.poisson_ratio,
            eps_d0: e0,
            shear_exponent: self.shear_exponent,
            tension,
            a_c,
            b_c,
        })
    }
}

/// Tension branch of one element's law.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TensionBranch {
    /// Eq. (9) with B_t (dimensionless).
    Exponential { b_t: f64 },
    /// Eq. (5) with A_t, B_t (dimensionless).
    Classic { a_t: f64, b_t: f64 },
}

/// Mazars law of one element (all parameters fixed).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Mazars {
    /// Young's modulus E, Pa.
    pub young_modulus: f64,
    /// Poisson's ratio ν.
    pub poisson_ratio: f64,
    /// Initial damage threshold ε_D0.
    pub eps_d0: f64,
    /// Shear correction exponent β.
    pub shear_exponent: f64,
    pub tension: TensionBranch,
    /// A_c of eq. (5), dimensionless.
    pub a_c: f64,
    /// B_c of eq. (5), dimensionless.
    pub b_c: f64,
}

/// Eq. (5): damage and its derivative in κ.
fn classic(e0: f64, a: f64, b: f64, kappa: f64) -> (f64, f64) {
    let ex = (-b * (kappa - e0)).exp();
    (
        1.0 - e0 * (1.0 - a) / kappa - a * ex,
        e0 * (1.0 - a) / (kappa * kappa) + a * b * ex,
    )
}

/// Σ_i w_i n_i ⊗ n_i over the eigenvectors n_i (columns), as the Voigt
/// gradient of a scalar of the strain: with engineering shear the
/// off-diagonal entry is taken once (dγ_xy = 2 dε_xy).
fn spectral_gradient(eigenvectors: &Matrix3<f64>, weights: [f64; 3]) -> Vector6<f64> {
    let mut m = Matrix3::zeros();
    for (i, w) in weights.into_iter().enumerate() {
        let n = eigenvectors.column(i);
        m += n * n.transpose() * w;
    }
    Vector6::new(
        m[(0, 0)],
        m[(1, 1)],
        m[(2, 2)],
        m[(0, 1)],
        m[(1, 2)],
        m[(0, 2)],
    )
}

/// ε_eq = √(Σ ⟨ε_i⟩₊²) over the principal strains (eq. 3).
fn equivalent_strain(principal: &Vector3<f64>) -> f64 {
    principal
        .iter()
        .map(|v| v.max(0.0).powi(2))
        .sum::<f64>()
        .sqrt()
}

fn voigt_to_tensor(e: &Vector6<f64>) -> Matrix3<f64> {
    Matrix3::new(
        e[0],
        e[3] / 2.0,
        e[5] / 2.0,
        e[3] / 2.0,
        e[1],
        e[4] / 2.0,
        e[5] / 2.0,
        e[4] / 2.0,
        e[2],
    )
}

impl Mazars {
    /// A virgin point whose strain norm stays below ε_D0 is elastic:
    /// ε_eq = ‖⟨ε⟩₊‖ ≤ ‖ε‖ (Frobenius), so κ cannot reach ε_D0. Most of a
    /// specimen is in this state; it skips the eigen-decomposition.
    fn stays_elastic(&self, committed: &BulkState, strain: &Vector6<f64>) -> bool {
        if !(committed.damage == 0.0 && committed.kappa <= self.eps_d0) {
            return false;
        }
        let shear = strain[3] * strain[3] + strain[4] * strain[4] + strain[5] * strain[5];
        let norm2 =
            strain[0] * strain[0] + strain[1] * strain[1] + strain[2] * strain[2] + 0.5 * shear;
        norm2 <= self.eps_d0 * self.eps_d0
    }

    pub fn stiffness(&self) -> Matrix6<f64> {
        isotropic_stiffness(self.young_modulus, self.poisson_ratio)
    }

    /// Tension damage D_t(κ) and dD_t/dκ.
    fn tension_damage(&self, kappa: f64) -> (f64, f64) {
        let e0 = self.eps_d0;
        match self.tension {
            TensionBranch::Exponential { b_t } => {
                let g = (e0 / kappa) * (b_t * (e0 - kappa)).exp();
                (1.0 - g, g * (1.0 / kappa + b_t))
            }
            TensionBranch::Classic { a_t, b_t } => classic(e0, a_t, b_t, kappa),
        }
    }

    /// α_t of eq. (6) from principal strains (effective stress, eq. 7).
    fn alpha_t(&self, principal: &Vector3<f64>) -> f64 {
        let (e, nu) = (self.young_modulus, self.poisson_ratio);
        let lam = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        let tr = principal.sum();
        let s_pos = principal.map(|ei| (lam * tr + 2.0 * mu * ei).max(0.0));
        let tr_pos = s_pos.sum();
        let eq2: f64 = principal.iter().map(|v| v.max(0.0).powi(2)).sum();
        if eq2 <= 0.0 {
            return 0.0;
        }
        let mut a = 0.0;
        for i in 0..3 {
            let eti = ((1.0 + nu) * s_pos[i] - nu * tr_pos) / e;
            a += eti.max(0.0) * principal[i].max(0.0);
        }
        (a / eq2).clamp(0.0, 1.0)
    }

    /// D(κ, α_t) before the max with the committed damage, and the partial
    /// derivatives (∂D/∂κ, ∂D/∂α_t).
    fn damage(&self, kappa: f64, alpha_t: f64) -> (f64, f64, f64) {
        if kappa <= self.eps_d0 {
            return (0.0, 0.0, 0.0);
        }
        let (dt, ddt) = self.tension_damage(kappa);
        let (dc, ddc) = classic(self.eps_d0, self.a_c, self.b_c, kappa);
        let b = self.shear_exponent;
        let ac = 1.0 - alpha_t;
        let wt = alpha_t.powf(b);
        let wc = ac.powf(b);
        let d = wt * dt + wc * dc;
        let dwt = if alpha_t > 0.0 {
            b * alpha_t.powf(b - 1.0)
        } else {
            0.0
        };
        let dwc = if ac > 0.0 { b * ac.powf(b - 1.0) } else { 0.0 };
        (d, wt * ddt + wc * ddc, dwt * dt - dwc * dc)
    }

    /// The point's own equivalent strain ε_eq (eq. 3) and α_t (eq. 6) at
    /// `strain`: what a gradient-enhanced damage averages, and the split
    /// between tension and compression it keeps local.
    pub fn local_measures(&self, strain: &Vector6<f64>) -> (f64, f64) {
        let principal = SymmetricEigen::new(voigt_to_tensor(strain)).eigenvalues;
        (equivalent_strain(&principal), self.alpha_t(&principal))
    }

    /// The implicit history of a step whose κ follows the averaged
    /// equivalent strain `averaged` (ε̄) instead of the point's own:
    /// κ = max(κ_committed, ε̄), D = max(D_committed, D(κ, α_t)); the
    /// stress of the step (IMPL-EX) is left as `trial` has it.
    pub fn averaged_state(
        &self,
        committed: &BulkState,
        trial: &BulkState,
        averaged: f64,
        alpha_t: f64,
    ) -> BulkState {
        let kappa_c = committed.kappa.max(self.eps_d0);
        let kappa = kappa_c.max(averaged);
        let (d, _, _) = self.damage(kappa, alpha_t);
        BulkState {
            kappa,
            damage: d.clamp(0.0, 1.0).max(committed.damage),
            kappa_increment: kappa - kappa_c,
            alpha_t,
            ..*trial
        }
    }
}

impl BulkLaw for Mazars {
    fn elastic_stiffness(&self) -> Matrix6<f64> {
        self.stiffness()
    }

    /// κ̃ = κ + ratio·Δκ and D̃ = max(D, D(κ̃, α_t)) with the last α_t:
    /// extrapolating κ rather than D follows the shape of the softening
    /// law (D jumps at the threshold and saturates towards 1).
    fn extrapolate(&self, committed: &BulkState, ratio: f64) -> BulkState {
        let kappa = committed.kappa.max(self.eps_d0) + ratio * committed.kappa_increment;
        let (d, _, _) = self.damage(kappa, committed.alpha_t);
        BulkState {
            explicit_damage: Some(d.clamp(0.0, 1.0).max(committed.damage)),
            ..*committed
        }
    }

    fn history_deferrable(&self, committed: &BulkState) -> bool {
        committed.explicit_damage.is_some()
    }

    /// Under IMPL-EX the stress is (1 − D̃) C ε with the extrapolated D̃
    /// and the tangent its secant: no eigen-decomposition, which only the
    /// implicit history needs.
    fn step_without_history(
        &self,
        committed: &BulkState,
        strain: &Vector6<f64>,
        kind: TangentKind,
    ) -> Result<BulkResponse, LawError> {
        const LAW: &str = "mazars";
        let Some(d_stress) = committed.explicit_damage else {
            return self.step(committed, strain, kind);
        };
        check_finite(LAW, "strain", strain.as_slice())?;
        let c = self.stiffness();
        let (stress, tangent, scale) = if self.stays_elastic(committed, strain) {
            (c * strain, c, 1.0)
        } else if kind == TangentKind::Elastic {
            ((c * strain) * (1.0 - d_stress), c, 1.0)
        } else {
            let scale = 1.0 - d_stress;
            ((c * strain) * scale, c * scale, scale)
        };
        check_result(LAW, "stress", stress.as_slice())?;
        check_result(LAW, "tangent", tangent.as_slice())?;
        Ok(BulkResponse {
            stress,
            tangent,
            state: *committed,
            fixed_scale: Some(scale),
        })
    }

    fn step(
        &self,
        committed: &BulkState,
        strain: &Vector6<f64>,
        kind: TangentKind,
    ) -> Result<BulkResponse, LawError> {
        const LAW: &str = "mazars";
        check_finite(LAW, "strain", strain.as_slice())?;
        let c = self.stiffness();
        if self.stays_elastic(committed, strain) {
            let stress = c * strain;
            check_result(LAW, "stress", stress.as_slice())?;
            return Ok(BulkResponse {
                stress,
                tangent: c,
                state: BulkState {
                    kappa: self.eps_d0,
                    damage: 0.0,
                    kappa_increment: 0.0,
                    ..*committed
                },
                fixed_scale: Some(1.0),
            });
        }
        let eig = SymmetricEigen::new(voigt_to_tensor(strain));
        let principal = eig.eigenvalues;
        let eps_eq = equivalent_strain(&principal);
        let kappa_c = committed.kappa.max(self.eps_d0);
        let loading = eps_eq > kappa_c;
        let kappa = kappa_c.max(eps_eq);
        let alpha_t = self.alpha_t(&principal);
        let (d_trial, dd_dkappa, dd_dalpha) = self.damage(kappa, alpha_t);
        let d_trial = d_trial.clamp(0.0, 1.0);
        let grows = d_trial > committed.damage;
        let d = if grows { d_trial } else { committed.damage };
        let effective = c * strain;
        // IMPL-EX (Oliver, Huespe & Cante 2008): the stress uses the damage
        // extrapolated before the step, so it is linear in the strain and
        // the secant (1 − D̃) C is its exact tangent; κ and D are still
        // integrated implicitly, for the next extrapolation.
        let d_stress = committed.explicit_damage.unwrap_or(d);
        let stress = effective * (1.0 - d_stress);
        // The secant of the committed or extrapolated damage does not move
        // with the strain; a growing implicit damage does.
        let fixed_scale = match kind {
            TangentKind::Elastic => Some(1.0),
            _ if committed.explicit_damage.is_some() || !grows => Some(1.0 - d_stress),
            _ => None,
        };
        let tangent = match kind {
            TangentKind::Elastic => c,
            TangentKind::Secant => c * (1.0 - d_stress),
            TangentKind::Consistent => {
                let mut t = c * (1.0 - d_stress);
                if committed.explicit_damage.is_none() && grows && d_trial < 1.0 {
                    let mut grad = Vector6::zeros();
                    if loading {
                        // dε_eq/dε = ⟨ε⟩₊/ε_eq, in Voigt with engineering shear.
                        let pos = principal.map(|e| e.max(0.0));
                        let dk =
                            spectral_gradient(&eig.eigenvectors, [pos[0], pos[1], pos[2]]) / eps_eq;
                        grad += dk * dd_dkappa;
                    }
                    if dd_dalpha != 0.0 {
                        // α_t is a symmetric function of the principal
                        // strains, so dα_t/dε = Σ_i ∂α_t/∂ε_i n_i ⊗ n_i; the
                        // partials by central differences in the principal
                        // values (6 cheap evaluations instead of 12
                        // eigen-decompositions of perturbed tensors).
                        let h = 1e-7 * principal.amax().max(self.eps_d0);
                        let da = [0, 1, 2].map(|i| {
                            let mut p = principal;
                            let mut q = principal;
                            p[i] += h;
                            q[i] -= h;
                            (self.alpha_t(&p) - self.alpha_t(&q)) / (2.0 * h)
                        });
                        grad += spectral_gradient(&eig.eigenvectors, da) * dd_dalpha;
                    }
                    t -= effective * grad.transpose();
                }
                t
            }
        };
        check_result(LAW, "stress", stress.as_slice())?;
        check_result(LAW, "tangent", tangent.as_slice())?;
        Ok(BulkResponse {
            stress,
            tangent,
            state: BulkState {
                kappa,
                damage: d,
                kappa_increment: kappa - kappa_c,
                alpha_t,
                ..*committed
            },
            fixed_scale,
        })
    }
}
