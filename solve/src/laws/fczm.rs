//! The frictional cohesive zone model (FCZM) of the paper, §3.1, eqs. 15–26.
//!
//! A representative interface area splits into a damaged part (fraction D),
//! in frictional contact, and an undamaged part following a modified
//! Tvergaard law:
//!
//! * σ = D σ^d + (1 − D) σ^u (15).
//! * Damaged part (16–18): σ_dn = K_n ⟨u_n⟩₋ (no tension), σ_ds = K_s (u_s − u_s^di);
//!   Coulomb friction |σ_ds| + μ σ_dn ≤ 0 (19) with slip along σ_ds (20),
//!   Kuhn–Tucker (21): solved by a closed-form radial return.
//! * Damage (22): D = 1 − exp(−f_t λ̃ / (ζ G_f)), λ̃ as in Tvergaard (A.2–A.4),
//!   with K_n = f_t/λ_0 (A.7), K_s = K_n/δ_s (A.3).
//! * Undamaged part (23–24): σ_un = β K_n u_n, σ_us = α K_s u_s, with β (25)
//!   and α (26): both 1 while D = 0; λ_0/λ when σ_dn ≥ 0 (u_n ≥ 0); when
//!   σ_dn < 0: β = exp(f_t λ̃/(ζ G_f)) = 1/(1 − D), and α = 1 − D for
//!   σ_dn ≤ γ, and in between (γ < σ_dn < 0) the linear interpolation in σ_dn
//!   from λ_0/λ (σ_dn = 0) to 1 − D (σ_dn = γ).
//!
//! Readings of the printed equations (SPEC §5): λ in (25)–(26) is the history
//! value λ̃ + λ_0 (equal to λ while damage grows), so unloading is secant and
//! nothing divides by zero; the third case of (26) is the interpolation above.
//! With ζ = 1 and u_n ≥ 0, (1 − D) σ^u is exactly Tvergaard's (A.6–A.11); in
//! compression (1 − D) σ_un = K_n u_n, so the total normal stress is
//! (1 + D) K_n u_n (the damaged part adds D K_n u_n): that is what (15)–(25)
//! say, and it is why the paper's shear-under-compression cases hold u_n at
//! σ_N/K_n rather than the total normal stress.
//!
//! `min_damage` (normally 0) raises D to at least that value: with 1 and μ = 0
//! it is the no-tension frictionless contact of SPEC §2.
//!
//! Tangents: `Elastic` → diag(K_n, K_s, K_s); `Secant` → D·diag(∂σ_dn/∂u_n,
//! K_s r, K_s r) + (1 − D)·diag(β K_n, α K_s, α K_s), r = 1 sticking,
//! |σ_ds|/|σ_ds*| sliding (drops all history derivatives: positive
//! semi-definite); `Consistent` → the exact derivative of the step: return
//! map, dD/du and dα/du, dβ/du while λ̃ grows, and the dependence of α on σ_dn.
//! It is not symmetric when sliding or when damage grows.
//!
//! Reference: Abbas, Bary, Jason, IJMS 237 (2023) §3.1; G. Alfano, E. Sacco,
//! IJNME 68 (2006) for the damage/friction decomposition.

use super::contract::{
    check_finite, check_result, extrapolated_lambda, lambda_step, InterfaceLaw, InterfaceResponse,
    InterfaceState, LambdaStep, LawError, TangentKind,
};
use super::coulomb::slip_return;
use super::tvergaard::opening;
use nalgebra::{Matrix3, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// Default γ of eq. (26), Pa.
pub const DEFAULT_GAMMA: f64 = -1e6;

/// Frictional cohesive zone model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Fczm {
    /// Tensile strength f_t, Pa.
    pub tensile_strength: f64,
    /// Fracture energy G_f, N/m.
    pub fracture_energy: f64,
    /// Damage threshold λ_0, m.
    pub lambda0: f64,
    /// Stiffness ratio δ_s = K_n/K_s (dimensionless).
    pub delta_s: f64,
    /// Friction coefficient μ (dimensionless).
    pub friction: f64,
    /// Damage energy coefficient ζ of eq. (22) (dimensionless, > 0).
    pub zeta: f64,
    /// Stress γ of eq. (26), Pa, negative.
    pub gamma: f64,
    /// Lower bound of D (dimensionless, [0, 1]); 1 for contact.
    #[serde(default)]
    pub min_damage: f64,
    /// Half-width δ (m) of the band |u_n| < δ over which the switch
    /// between open and closed contact is smoothed; 0: the sharp switch of
    /// eqs. (16)–(18), (25)–(26). See [`contact_ramp`]. Left out of the
    /// serialised form when 0.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub contact_smoothing: f64,
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

/// The compressive part ⟨u⟩₋ = min(u, 0) of a normal jump and its
/// derivative, smoothed over |u| < δ by the quadratic −(u − δ)²/(4δ)
/// (continuous slope; exact outside the band, −δ/4 at u = 0).
///
/// Every open/closed switch of the FCZM goes through this one function:
/// the damaged part's contact stress K_n⟨u_n⟩₋ (16), the undamaged part's
/// normal stiffness, λ_0/λ open and (1 − D)β closed (25), and through
/// σ_dn the shear weight α (26). With δ = 0 the switch is a kink in all
/// three: at a rib edge pressed by nearly zero normal traction Newton then
/// alternates between the open and the closed branch (docs/src/validation/solver.md,
/// "Law switches").
pub fn contact_ramp(u: f64, delta: f64) -> (f64, f64) {
    if u < 0.0 && u <= -delta {
        (u, 1.0)
    } else if u >= 0.0 && u >= delta {
        (0.0, 0.0)
    } else {
        (
            -(u - delta) * (u - delta) / (4.0 * delta),
            (delta - u) / (2.0 * delta),
        )
    }
}

impl Fczm {
    /// The no-tension frictionless contact with normal stiffness `kn` (N/m³).
    pub fn contact(kn: f64) -> Self {
        // Only K_n = f_t/λ_0 matters once D = 1 and μ = 0.
        Fczm {
            tensile_strength: kn * 1e-5,
            fracture_energy: 1.0,
            lambda0: 1e-5,
            delta_s: 1.0,
            friction: 0.0,
            zeta: 1.0,
            gamma: DEFAULT_GAMMA,
            min_damage: 1.0,
            contact_smoothing: 0.0,
        }
    }
    /// K_n = f_t/λ_0, N/m³.
    pub fn normal_stiffness(&self) -> f64 {
        self.tensile_strength / self.lambda0
    }
    /// K_s = K_n/δ_s, N/m³.
    pub fn shear_stiffness(&self) -> f64 {
        self.normal_stiffness() / self.delta_s
    }
}

/// The damage of a step (A.2–A.4, 22) and its derivatives in the jump.
#[derive(Debug, Clone, Copy)]
struct Damage {
    /// λ̃ of the step, m.
    lt: f64,
    /// ∂(λ̃ + λ_0)/∂u (zero unless damage grows).
    dbig: Vector3<f64>,
    /// 1 − D and its derivative.
    q: f64,
    dq: Vector3<f64>,
    d: f64,
    dd: Vector3<f64>,
    /// λ_0/λ and its derivative.
    r: f64,
    dr: Vector3<f64>,
    /// Whether D sits at its floor `min_damage` (then q = `floor_q`).
    floored: bool,
    floor_q: f64,
    /// f_t / (ζ G_f), 1/m.
    c: f64,
}

/// The undamaged part's normal traction N = K_n (P_o u_n + (P_c − P_o)⟨u_n⟩₋)
/// with P_o = (1 − D)λ_0/λ (open) and P_c = (1 − D)β (closed), and the
/// shear weight P_s = (1 − D)α (23–26). `normal_slope` is ∂N/∂u_n at fixed
/// history, `normal_history` the rest of ∂N/∂u (through λ̃ while damage grows).
struct Undamaged {
    normal: f64,
    normal_slope: f64,
    normal_history: Vector3<f64>,
    ps: f64,
    dps: Vector3<f64>,
}

impl Fczm {
    /// The damage the traction uses and the step's λ̃ (the state's is
    /// the implicit one). `evolve`: whether λ̃ may grow (false: held, see
    /// `held_step`). Under IMPL-EX the traction's damage is that of the
    /// extrapolated λ̃, fixed within the step (no derivative).
    fn damage(
        &self,
        committed: &InterfaceState,
        jump: &Vector3<f64>,
        evolve: bool,
    ) -> (Damage, LambdaStep) {
        let c = self.tensile_strength / (self.zeta * self.fracture_energy);
        let (lam, dlam) = opening(jump, self.delta_s);
        let step = lambda_step(committed, lam, self.lambda0, evolve);
        let (lt, loading) = (step.traction, step.loading);
        let big = lt + self.lambda0;
        let dbig = if loading { dlam } else { Vector3::zeros() };
        let q_nat = (-c * lt).exp();
        let floor_q = 1.0 - self.min_damage;
        let floored = floor_q <= q_nat;
        let q = if floored { floor_q } else { q_nat };
        let d = 1.0 - q;
        let dq = if floored {
            Vector3::zeros()
        } else {
            dbig * (-c * q)
        };
        let dd = -dq;
        let r = self.lambda0 / big;
        let dr = dbig * (-self.lambda0 / (big * big));
        let damage = Damage {
            lt,
            dbig,
            q,
            dq,
            d,
            dd,
            r,
            dr,
            floored,
            floor_q,
            c,
        };
        (damage, step)
    }

    /// D (22) at λ̃ = `lt` (m), never below `min_damage`.
    fn damage_at(&self, lt: f64) -> f64 {
        let c = self.tensile_strength / (self.zeta * self.fracture_energy);
        1.0 - (-c * lt).exp().min(1.0 - self.min_damage)
    }

    fn undamaged(
        &self,
        dmg: &Damage,
        un: f64,
        (closed, dclosed): (f64, f64),
        (sdn, dsdn): (f64, f64),
    ) -> Undamaged {
        let kn = self.normal_stiffness();
        let e_n = Vector3::new(1.0, 0.0, 0.0);
        let Damage {
            lt,
            q,
            dq,
            r,
            dr,
            dbig,
            floored,
            floor_q,
            c,
            ..
        } = *dmg;
        let (normal, normal_slope, normal_history, ps, dps);
        if q >= 1.0 {
            (normal, normal_slope, normal_history) = (kn * un, kn, Vector3::zeros());
            (ps, dps) = (1.0, Vector3::zeros());
        } else {
            let (p_o, dp_o) = (q * r, dq * r + dr * q);
            // (1 − D)/(1 − D(λ̃)) in logarithms: no overflow of exp(c λ̃).
            let (p_c, dp_c) = if floored {
                let p = (floor_q.ln() + c * lt).exp();
                (p, dbig * (c * p))
            } else {
                (1.0, Vector3::zeros())
            };
            if closed == 0.0 || closed == un {
                // Outside the smoothing band: one branch of (25).
                let (p, dp) = if closed == 0.0 {
                    (p_o, dp_o)
                } else {
                    (p_c, dp_c)
                };
                (normal, normal_slope, normal_history) = (p * kn * un, p * kn, dp * (kn * un));
            } else {
                normal = kn * (p_o * un + (p_c - p_o) * closed);
                normal_slope = kn * (p_o + (p_c - p_o) * dclosed);
                normal_history = (dp_o * un + (dp_c - dp_o) * closed) * kn;
            }
            if sdn >= 0.0 {
                (ps, dps) = (p_o, dp_o);
            } else if sdn <= self.gamma {
                ps = q * q;
                dps = dq * (2.0 * q);
            } else {
                let s = sdn / self.gamma;
                let ds = e_n * (dsdn / self.gamma);
                let a = r * (1.0 - s) + s * q;
                let da = dr * (1.0 - s) - ds * r + ds * q + dq * s;
                ps = q * a;
                dps = dq * a + da * q;
            }
        }

        Undamaged {
            normal,
            normal_slope,
            normal_history,
            ps,
            dps,
        }
    }
}

impl InterfaceLaw for Fczm {
    fn respond(
        &self,
        committed: &InterfaceState,
        jump: &Vector3<f64>,
        kind: TangentKind,
        evolve: bool,
    ) -> Result<InterfaceResponse, LawError> {
        const LAW: &str = "fczm";
        check_finite(LAW, "jump", jump.as_slice())?;
        let (kn, ks) = (self.normal_stiffness(), self.shear_stiffness());
        let un = jump[0];
        let us = Vector2::new(jump[1], jump[2]);

        let (dmg, step) = self.damage(committed, jump, evolve);
        let implicit = step.implicit;
        let Damage { lt, d, dd, .. } = dmg;

        // Damaged part: no tension, Coulomb friction (16–21).
        let (closed, dclosed) = contact_ramp(un, self.contact_smoothing);
        let sdn = kn * closed;
        let dsdn = kn * dclosed;
        let ret = slip_return(
            us,
            Vector2::new(committed.slip[0], committed.slip[1]),
            ks,
            if evolve {
                -self.friction * sdn
            } else {
                f64::INFINITY
            },
        );

        let Undamaged {
            normal,
            normal_slope,
            normal_history,
            ps,
            dps,
        } = self.undamaged(&dmg, un, (closed, dclosed), (sdn, dsdn));
        let e_n = Vector3::new(1.0, 0.0, 0.0);

        let traction = Vector3::new(
            d * sdn + normal,
            d * ret.tau[0] + ps * ks * us[0],
            d * ret.tau[1] + ps * ks * us[1],
        );
        let tangent = match kind {
            TangentKind::Elastic => self.elastic_stiffness(),
            TangentKind::Secant => Matrix3::from_diagonal(&Vector3::new(
                d * dsdn + normal_slope,
                d * ks * ret.ratio + ps * ks,
                d * ks * ret.ratio + ps * ks,
            )),
            TangentKind::Consistent => {
                let mut t = Matrix3::zeros();
                // Normal row.
                let row_n = e_n * (d * dsdn + normal_slope) + dd * sdn + normal_history;
                t.set_row(0, &row_n.transpose());
                // Tangential rows.
                let dty_dun = -self.friction * dsdn;
                for i in 0..2 {
                    let mut row = dd * ret.tau[i] + dps * (ks * us[i]);
                    row[0] += d * ret.d_tau_d_ty[i] * dty_dun;
                    row[1] += d * ret.d_tau_d_us[(i, 0)];
                    row[2] += d * ret.d_tau_d_us[(i, 1)];
                    row[i + 1] += ps * ks;
                    t.set_row(i + 1, &row.transpose());
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
                damage: if implicit == lt {
                    d
                } else {
                    self.damage_at(implicit)
                }
                .max(committed.damage),
                slip: [ret.slip[0], ret.slip[1]],
                held: None,
                explicit_lambda: committed.explicit_lambda,
                lambda_increment: step.increment,
            },
        })
    }

    fn extrapolate(&self, committed: &InterfaceState, ratio: f64) -> InterfaceState {
        extrapolated_lambda(committed, ratio)
    }

    /// Undamaged part ½ [P_n K_n u_n² + P_s K_s |u_s|²] plus damaged part
    /// D [½ K_n ⟨u_n⟩₋² + ½ |τ|²/K_s] with τ = K_s (u_s − s), which is
    /// ½ t·u − ½ D τ·s (solve::energy).
    fn stored_energy(
        &self,
        state: &InterfaceState,
        jump: &Vector3<f64>,
        traction: &Vector3<f64>,
    ) -> f64 {
        let ks = self.elastic_stiffness()[(1, 1)];
        let s = [state.slip[0], state.slip[1]];
        let tau = [ks * (jump[1] - s[0]), ks * (jump[2] - s[1])];
        0.5 * traction.dot(jump) - 0.5 * state.damage * (tau[0] * s[0] + tau[1] * s[1])
    }

    fn elastic_stiffness(&self) -> Matrix3<f64> {
        Matrix3::from_diagonal(&Vector3::new(
            self.normal_stiffness(),
            self.shear_stiffness(),
            self.shear_stiffness(),
        ))
    }
}
