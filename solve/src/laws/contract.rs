//! The step contract every law keeps: its states, responses, tangent
//! kinds and errors, and the traits [`BulkLaw`] and [`InterfaceLaw`].

use nalgebra::{Matrix3, Matrix6, Vector3, Vector6};

/// Which tangent the caller wants (MFront's elastic / secant / consistent).
#[derive(
    Debug,
    Clone,
    Copy,
    PartialEq,
    Eq,
    Hash,
    serde::Serialize,
    serde::Deserialize,
    schemars::JsonSchema,
)]
#[serde(rename_all = "snake_case")]
pub enum TangentKind {
    /// Undamaged elastic stiffness.
    Elastic,
    /// Secant stiffness (e.g. (1 − D) C): always positive semi-definite.
    Secant,
    /// Consistent (algorithmic) tangent dσ/dε of the step.
    Consistent,
}

/// A law could not produce a finite answer for this input; the solver cuts the step.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LawError {
    #[error("{law}: non-finite input {what}")]
    NonFiniteInput {
        law: &'static str,
        what: &'static str,
    },
    #[error("{law}: return mapping did not converge ({detail})")]
    ReturnMapping { law: &'static str, detail: String },
    #[error("{law}: non-finite result ({what})")]
    NonFiniteResult {
        law: &'static str,
        what: &'static str,
    },
}

/// Committed history of one bulk integration point. Each law uses its part.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct BulkState {
    /// Mazars: largest equivalent strain reached, κ.
    pub kappa: f64,
    /// Mazars: damage D ∈ [0, 1], never decreasing.
    pub damage: f64,
    /// J2: plastic strain (Voigt, engineering shear).
    pub plastic_strain: [f64; 6],
    /// Mazars, IMPL-EX integration (`solver.concrete_integration: impl_ex`):
    /// the damage the stress uses in this step, extrapolated by the solver
    /// from the implicit history before the step; `None`: implicit
    /// integration (the stress uses `damage`).
    pub explicit_damage: Option<f64>,
    /// Mazars, IMPL-EX: increment of κ in the step that produced this
    /// state (the rate the next extrapolation uses).
    pub kappa_increment: f64,
    /// Mazars, IMPL-EX: α_t of the strain of this state (the tension weight
    /// of the next extrapolated damage).
    pub alpha_t: f64,
}

/// Result of a bulk step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BulkResponse {
    pub stress: Vector6<f64>,
    pub tangent: Matrix6<f64>,
    pub state: BulkState,
    /// `Some(s)` when `tangent` is exactly s × [`BulkLaw::elastic_stiffness`]
    /// with s fixed by the committed state and the tangent kind, not by this
    /// strain (an elastic point, an unloading or IMPL-EX Mazars point): the
    /// element matrix then holds for every iterate of the step while the
    /// point stays so, and the assembly keeps it instead of rebuilding it.
    pub fixed_scale: Option<f64>,
}

/// Committed history of one interface integration point.
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct InterfaceState {
    /// Largest effective jump reached beyond λ_0 (Tvergaard/FCZM λ̃), m.
    pub lambda_max: f64,
    /// Interface damage D ∈ [0, 1], never decreasing.
    pub damage: f64,
    /// Plastic (frictional) slip in the local tangential plane (t, h), m.
    pub slip: [f64; 2],
    /// The history this point's traction is held at in the step being
    /// attempted (the solver's retry of a step in which the point kept
    /// switching regime between Newton iterates); `None`: the traction
    /// follows the law. The state itself still evolves by the law.
    #[serde(default)]
    pub held: Option<HeldHistory>,
    /// IMPL-EX integration of the interface damage
    /// (`solver.interface_integration: impl_ex`): the λ̃ the traction uses
    /// in this step, extrapolated by the solver from the implicit history
    /// before the step; `None`: implicit (the traction uses the step's own
    /// λ̃). `lambda_max` and `damage` stay implicit either way.
    #[serde(default)]
    pub explicit_lambda: Option<f64>,
    /// Increment of λ̃ in the step that produced this state (the rate the
    /// next extrapolation uses), m.
    #[serde(default)]
    pub lambda_increment: f64,
}

/// λ̃ (m) of a damage interface law's step at the equivalent opening
/// `lam` (A.2) from `committed`.
pub(crate) struct LambdaStep {
    /// The step's own λ̃ (the state's).
    pub implicit: f64,
    /// The λ̃ the traction uses: the implicit one, or under IMPL-EX the
    /// solver's extrapolation (never below the committed λ̃).
    pub traction: f64,
    /// Whether the traction's λ̃ grows with the jump (its tangent then
    /// carries ∂λ/∂u).
    pub loading: bool,
    /// Increment of the implicit λ̃ over the committed one (the state's
    /// `lambda_increment`).
    pub increment: f64,
}

/// See [`LambdaStep`]; `evolve`: whether λ̃ may grow (false: held).
pub(crate) fn lambda_step(
    committed: &InterfaceState,
    lam: f64,
    lambda0: f64,
    evolve: bool,
) -> LambdaStep {
    let start = committed.lambda_max.max(0.0);
    let growing = evolve && lam - lambda0 > committed.lambda_max;
    let implicit = if growing { lam - lambda0 } else { start };
    let explicit = committed
        .explicit_lambda
        .filter(|_| evolve)
        .map(|l| l.max(start));
    LambdaStep {
        implicit,
        traction: explicit.unwrap_or(implicit),
        loading: growing && explicit.is_none(),
        increment: implicit - start,
    }
}

/// The committed state with λ̃ extrapolated linearly over a step `ratio`
/// times as long as the one that produced it (IMPL-EX, Oliver et al.
/// 2008): what damage interface laws return from
/// [`InterfaceLaw::extrapolate`].
pub(crate) fn extrapolated_lambda(committed: &InterfaceState, ratio: f64) -> InterfaceState {
    let start = committed.lambda_max.max(0.0);
    InterfaceState {
        explicit_lambda: Some(start + ratio.max(0.0) * committed.lambda_increment.max(0.0)),
        ..*committed
    }
}

/// An interface point's history as the solver holds it for one step: the
/// traction is the law's at this λ̃, D and slip, with no damage growth and
/// no slip (see [`InterfaceLaw::held_step`]).
#[derive(Debug, Clone, Copy, PartialEq, Default, serde::Serialize, serde::Deserialize)]
pub struct HeldHistory {
    pub lambda_max: f64,
    pub damage: f64,
    pub slip: [f64; 2],
}

impl HeldHistory {
    /// The history of `state`.
    pub fn of(state: &InterfaceState) -> Self {
        Self {
            lambda_max: state.lambda_max,
            damage: state.damage,
            slip: state.slip,
        }
    }
    /// The state with this history and no hold.
    pub fn state(&self) -> InterfaceState {
        InterfaceState {
            lambda_max: self.lambda_max,
            damage: self.damage,
            slip: self.slip,
            ..InterfaceState::default()
        }
    }
}

/// Result of an interface step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InterfaceResponse {
    pub traction: Vector3<f64>,
    pub tangent: Matrix3<f64>,
    pub state: InterfaceState,
}

/// A bulk constitutive law.
pub trait BulkLaw: Sync {
    fn step(
        &self,
        committed: &BulkState,
        strain: &Vector6<f64>,
        kind: TangentKind,
    ) -> Result<BulkResponse, LawError>;

    /// Whether the stress and tangent of [`BulkLaw::step`] from
    /// `committed` do not depend on its history update (IMPL-EX: the
    /// extrapolated damage fixes both, and only the next extrapolation
    /// reads the implicit κ). Newton's iterates may then skip the update
    /// ([`BulkLaw::step_without_history`]) and make it once, at the
    /// converged strain.
    fn history_deferrable(&self, _committed: &BulkState) -> bool {
        false
    }

    /// [`BulkLaw::step`]'s stress, tangent and fixed scale, bit for bit;
    /// where [`BulkLaw::history_deferrable`], without the history update,
    /// the state returned being `committed`. Elsewhere it is the step.
    fn step_without_history(
        &self,
        committed: &BulkState,
        strain: &Vector6<f64>,
        kind: TangentKind,
    ) -> Result<BulkResponse, LawError> {
        self.step(committed, strain, kind)
    }

    /// The stress of [`BulkLaw::step`] (secant kind) at `strain` from
    /// `committed`, bit for bit, where the history update is not wanted
    /// (the IMPL-EX error indicator, the energy balance).
    fn stress(
        &self,
        committed: &BulkState,
        strain: &Vector6<f64>,
    ) -> Result<Vector6<f64>, LawError> {
        Ok(self
            .step_without_history(committed, strain, TangentKind::Secant)?
            .stress)
    }

    /// The stiffness that [`BulkResponse::fixed_scale`] scales, Pa.
    fn elastic_stiffness(&self) -> Matrix6<f64>;

    /// IMPL-EX: the committed state prepared for a step `ratio` times as
    /// long as the one that produced it (`explicit_damage` set); laws
    /// without damage return it unchanged.
    fn extrapolate(&self, committed: &BulkState, _ratio: f64) -> BulkState {
        *committed
    }

    /// The uniaxial stress beyond which the law cannot carry more (a
    /// perfectly plastic yield stress), Pa; `None` for hardening or
    /// softening laws.
    fn yield_stress(&self) -> Option<f64> {
        None
    }

    /// Recoverable energy density (J/m³) at `strain` with `stress`, the
    /// state `state` being committed there: ½ σ·(ε − ε_p), which is every
    /// law here (Mazars σ = (1 − D) C ε: ½ ε·C_sec·ε; J2 σ = C (ε − ε_p);
    /// elastic ½ σ·ε). A law whose unloading is not secant to ε_p says so
    /// by overriding it.
    fn stored_energy(
        &self,
        state: &BulkState,
        strain: &Vector6<f64>,
        stress: &Vector6<f64>,
    ) -> f64 {
        let elastic = strain - Vector6::from_column_slice(&state.plastic_strain);
        0.5 * stress.dot(&elastic)
    }
}

/// An interface constitutive law in the local frame.
pub trait InterfaceLaw: Sync {
    /// The response at `jump` from `committed`. With `evolve` the history
    /// follows the law (damage growth, slip); without, it is held as it
    /// is: the law's traction with no damage growth and no slip, its exact
    /// tangent for `Consistent` (a smooth function of the jump but for the
    /// open/closed switch). A point Newton cannot settle is held so for
    /// one attempt, then released to its implicit history (docs/src/validation/solver.md,
    /// "Law switches").
    fn respond(
        &self,
        committed: &InterfaceState,
        jump: &Vector3<f64>,
        kind: TangentKind,
        evolve: bool,
    ) -> Result<InterfaceResponse, LawError>;
    /// The law's step from `committed` at `jump`.
    fn step(
        &self,
        committed: &InterfaceState,
        jump: &Vector3<f64>,
        kind: TangentKind,
    ) -> Result<InterfaceResponse, LawError> {
        self.respond(committed, jump, kind, true)
    }
    /// The response with the history of `history` held; the state returned
    /// is `history`.
    fn held_step(
        &self,
        history: &InterfaceState,
        jump: &Vector3<f64>,
        kind: TangentKind,
    ) -> Result<InterfaceResponse, LawError> {
        let mut response = self.respond(history, jump, kind, false)?;
        response.state = *history;
        Ok(response)
    }
    /// IMPL-EX: the committed state prepared for a step `ratio` times as
    /// long as the one that produced it (`explicit_lambda` set); laws
    /// without a damage history return it unchanged.
    fn extrapolate(&self, committed: &InterfaceState, _ratio: f64) -> InterfaceState {
        *committed
    }
    /// The initial (undamaged) stiffness diag(K_n, K_s, K_s), N/m³.
    fn elastic_stiffness(&self) -> Matrix3<f64>;
    /// Recoverable energy per area (J/m²) at `jump` with `traction`, the
    /// state `state` being committed there: what unloading to zero traction
    /// would give back (the rest of the work is dissipated).
    fn stored_energy(
        &self,
        state: &InterfaceState,
        jump: &Vector3<f64>,
        traction: &Vector3<f64>,
    ) -> f64;
}

/// `Err(NonFiniteInput)` unless every component is finite.
pub(crate) fn check_finite(
    law: &'static str,
    what: &'static str,
    v: &[f64],
) -> Result<(), LawError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(LawError::NonFiniteInput { law, what })
    }
}

/// `Err(NonFiniteResult)` unless every component is finite.
pub(crate) fn check_result(
    law: &'static str,
    what: &'static str,
    v: &[f64],
) -> Result<(), LawError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(LawError::NonFiniteResult { law, what })
    }
}
