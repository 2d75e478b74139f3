//! The `loading` and `solver` sections resolved: SI values, defaults
//! filled in, bounds checked; and the choices they hold.

use crate::laws::TangentKind;
use crate::linalg::Ordering;
use geom::units::UnitError;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A `loading` or `solver` value that cannot be used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolverSpecError {
    #[error(transparent)]
    Unit(#[from] UnitError),
    #[error("{key}: {value} is out of range ({bound})")]
    OutOfRange {
        key: String,
        value: f64,
        bound: &'static str,
    },
    #[error("{key}: {problem}")]
    Combination { key: String, problem: &'static str },
    /// A key of an earlier layout of the sections.
    #[error("{key}: {place}")]
    Moved { key: String, place: String },
}

/// Displacement-controlled loading, SI.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Loading {
    /// Final imposed displacement of the bar's loaded end, m.
    pub u_final: f64,
    /// Stop once the free-end displacement reaches this value, m.
    pub fed_stop: Option<f64>,
    /// First step size, m.
    pub initial_step: f64,
    /// Smallest step size; a step failing at this size ends the run, m.
    pub min_step: f64,
    /// Largest step size, m.
    pub max_step: f64,
    /// Step growth factor after an easy step (> 1).
    pub growth: f64,
    /// Step reduction factor on non-convergence (in (0, 1)).
    pub cutback: f64,
    /// A converged step with at most this many iterations is easy.
    pub easy_iterations: usize,
    /// Stop (with the converged part kept) after this many converged
    /// steps: a bound on run time that, unlike a wall-clock limit, gives
    /// the same result on every machine. Left out of the serialised form
    /// when unset, so that specs without it keep their cache keys.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_steps: Option<usize>,
    /// How closely the steps follow the bond stress–slip curve: after a
    /// displacement-controlled step, the distance of the previous curve
    /// point from the chord of its neighbours, on axes scaled to the FED's
    /// range (`fed_stop`, else `u_final`) and to the largest |σ_mb| so
    /// far, is held near this (the next step is sized by it, a step more
    /// than twice above it is redone shorter, never below
    /// `initial_step`). 0 switches it off; a record written before it
    /// existed reads as 0.
    #[serde(default)]
    pub curve_tolerance: f64,
    /// What `curve_tolerance` bounds. Left out of the serialised form when
    /// it is the default, so that specs without it keep their cache keys.
    #[serde(default, skip_serializing_if = "CurveError::is_distance")]
    pub curve_error: CurveError,
}

/// What `loading.curve_tolerance` bounds (docs/src/validation/solver.md, "Resolving the
/// curve").
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum CurveError {
    /// The shortest distance of a curve point from its neighbours' chord.
    #[default]
    Distance,
    /// Where the FED grows, the σ_mb distance of the point from the chord
    /// at its FED: the error of σ_mb read along FED, which on a steep rise
    /// or drop is many times the shortest distance. Elsewhere as
    /// `distance`.
    Stress,
}

impl CurveError {
    fn is_distance(&self) -> bool {
        *self == CurveError::Distance
    }
}

/// `loading.curve_tolerance` unless a scene sets it (docs/src/validation/solver.md,
/// "Resolving the curve").
pub const DEFAULT_CURVE_TOLERANCE: f64 = 3e-3;

impl Default for Loading {
    fn default() -> Self {
        Self {
            u_final: 1e-3,
            fed_stop: None,
            initial_step: 5e-6,
            min_step: 1e-9,
            max_step: 2e-5,
            growth: 1.5,
            cutback: 0.5,
            easy_iterations: 5,
            max_steps: None,
            curve_tolerance: DEFAULT_CURVE_TOLERANCE,
            curve_error: CurveError::Distance,
        }
    }
}

/// Linear solver of the Newton corrections.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LinearSolverKind {
    /// Sparse Cholesky of every new matrix (of the symmetric part of an
    /// unsymmetric consistent tangent).
    Cholesky,
    /// Conjugate gradients preconditioned by a reused Cholesky factor.
    Pcg,
    /// Newton–Krylov: GMRES on the exact (unsymmetric) consistent tangent,
    /// right-preconditioned by a reused Cholesky factor (or multigrid
    /// hierarchy, `preconditioner`) of its symmetric part (or of the secant
    /// matrix when that part is indefinite).
    #[default]
    Gmres,
}

/// What preconditions GMRES in the Newton–Krylov solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PreconditionerKind {
    /// `multigrid` from 100 000 free DOFs on (`MULTIGRID_MIN_DOFS`), else
    /// `cholesky`.
    #[default]
    Auto,
    /// A kept sparse Cholesky factor of the symmetric part (or the secant
    /// matrix): few GMRES iterations, memory of the factor's fill.
    Cholesky,
    /// A kept smoothed-aggregation multigrid hierarchy of the same matrix
    /// (one V-cycle per GMRES iteration): memory about twice the matrix,
    /// more GMRES iterations.
    Multigrid,
}

/// When the kept multigrid hierarchy is built anew between GMRES solves
/// (besides when there is none and when GMRES fails with it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum MultigridRebuild {
    /// After a solve that needed more than half of `krylov_max_iterations`.
    #[default]
    HalfLimit,
    /// Also once the solves since the last build have needed, beyond the
    /// iterations of the first of them, more GMRES iterations in all than
    /// a build costs (40, `REBUILD_COST_ITERATIONS`), so that a hierarchy
    /// built before the damage grew is renewed even when no single solve
    /// passes the half limit. A rebuild whose first solve needs no fewer
    /// iterations per decade of residual than the worn hierarchy's solves
    /// did not pay: the wear the next rebuild waits for doubles.
    Amortised,
}

/// What a multigrid build costs in GMRES iterations of the same system:
/// 11.4 s against 0.30 s an iteration on R2's paper mesh (1.25 M DOFs),
/// 1.55 s against 0.029 s on its 0.8 mm reproducer.
pub const REBUILD_COST_ITERATIONS: usize = 40;

/// How the GMRES tolerance of each Newton correction (the forcing term η)
/// is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Forcing {
    /// η = `krylov_tolerance` for every correction.
    Fixed,
    /// Eisenstat–Walker (1996) choice 2: η_k = 0.9 (‖r_k‖/‖r_{k−1}‖)², kept
    /// ≥ 0.9 η_{k−1}² when that is > 0.1, capped at 0.1, and floored at
    /// `krylov_tolerance`; the first correction of a step uses 0.1. Loose
    /// solves far from the solution, tight ones near it.
    #[default]
    EisenstatWalker,
    /// η_k = ½ `residual_tolerance` · (force scale) / ‖r_k‖, clipped to
    /// [`krylov_tolerance`, 0.1]: each correction aims at the force
    /// criterion itself. For steps that are nearly linear (IMPL-EX
    /// concrete), where Eisenstat–Walker's loose first correction costs a
    /// second correction and its tight second one oversolves; a strongly
    /// nonlinear step would oversolve its first correction instead.
    Tolerance,
}

/// Floating-point precision of the kept Cholesky factor when it is applied
/// as the GMRES preconditioner (the factorisation itself is always double).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Precision {
    /// L and the triangular solves in f64.
    Double,
    /// L rounded to f32 after the factorisation, triangular solves in f32:
    /// half the memory traffic per application. Only the preconditioner
    /// changes; GMRES still converges on the f64 tangent.
    #[default]
    Single,
}

/// Time integration of the Mazars concrete damage.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ConcreteIntegration {
    /// Backward Euler: the stress of a step uses the damage of the step's
    /// own strain (consistent tangent; Newton meets the loading/unloading
    /// threshold of every point).
    #[default]
    Implicit,
    /// IMPL-EX (Oliver, Huespe & Cante, CMAME 197, 2008): the stress of a
    /// step uses the damage extrapolated linearly from the last two
    /// converged steps (never below the last one), so the concrete is linear
    /// within a step; the damage history is still integrated implicitly.
    /// First-order in the step size: its curve error is measured against
    /// the implicit one (docs/src/validation/solver.md).
    ImplEx,
}

/// Time integration of the interface damage (FCZM and Tvergaard λ̃).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum InterfaceIntegration {
    /// Backward Euler: the traction of a step uses the damage of the
    /// step's own jump (consistent tangent, softening where λ̃ grows).
    #[default]
    Implicit,
    /// IMPL-EX, as `concrete_integration: impl_ex` for the concrete: the
    /// traction uses λ̃ extrapolated linearly from the last converged step
    /// (never below the last one), so the interface's damage does not
    /// switch between Newton iterates and its tangent does not soften;
    /// friction and contact stay implicit. The step control of
    /// `impl_ex_tolerance` bounds its error (docs/src/validation/solver.md).
    ImplEx,
}

/// What a load step prescribes (docs/src/validation/solver.md, Path-following).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum PathFollowing {
    /// Every step prescribes the imposed displacement λ.
    Off,
    /// After the first step, each step prescribes the free-end
    /// displacement (FED) and λ is an unknown (indirect displacement
    /// control): the path is followed through local snap-backs where λ
    /// must decrease. Steps are then measured in FED (`loading.*_step`
    /// apply to it); the last step lands on `loading.fed_stop`.
    Fed,
    /// Displacement control while the steps are elastic; a step that
    /// dissipates (its released energy ½(F_0 λ − F λ_0) above a tenth of
    /// its external work), or that displacement control cannot converge,
    /// hands over to dissipation control: each step prescribes the energy
    /// it releases and λ is an unknown, which follows local and global
    /// snap-backs. Back to displacement control when the steps turn
    /// elastic again.
    Energy,
    /// Displacement control until a step softens interface points; from
    /// then each step prescribes how far the jumps of those points (the
    /// process zone: the points whose λ̃ grew in the last step) move on
    /// along their last increments, their r.m.s. over the zone in metres,
    /// and λ is an unknown: a local arc-length (Geers, IJNME 46, 1999)
    /// that follows snap-backs in λ and in the FED. Its constraint is
    /// linear in the step's displacement and bounds the zone's jump
    /// increments, on which the IMPL-EX interface's error depends. Back to
    /// displacement control after a step in which no point softened, and
    /// for a step in which the zone would move λ by more than
    /// `loading.max_step`.
    ProcessZone,
    /// Displacement control until it fails at the minimum step after a
    /// step that dissipated (a snap-back: no equilibrium at a larger λ);
    /// from there dissipation control as in `energy`, back to displacement
    /// control when the steps turn elastic. Runs that displacement control
    /// carries to the end keep their curves.
    #[default]
    Auto,
}

/// When the solver holds the interface points whose regime keeps
/// switching between Newton iterates (docs/src/validation/solver.md, "Law switches").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case", try_from = "RawInterfaceHolds")]
pub enum InterfaceHolds {
    /// Never: a step whose interface chatters is cut back, and stalls at
    /// the minimum step.
    Off,
    /// From the first step that would otherwise stall at its minimum
    /// size to the end of the run. Every run that gets through without
    /// them keeps its curve: holding the points in every step carries the
    /// stress sweep's stiff-interface case 21 to its end but moves
    /// splitting cubes onto other branches, where they stall.
    #[default]
    OnStall,
    /// In the retries of every step.
    Always,
}

/// `solver.expert.interface_holds` as written: a mode, or the bool of the first
/// version of the option (`true`: in every step, `false`: never).
#[derive(Deserialize)]
#[serde(untagged)]
enum RawInterfaceHolds {
    Flag(bool),
    Mode(String),
}

impl TryFrom<RawInterfaceHolds> for InterfaceHolds {
    type Error = String;
    fn try_from(raw: RawInterfaceHolds) -> Result<Self, String> {
        match raw {
            RawInterfaceHolds::Flag(true) => Ok(Self::Always),
            RawInterfaceHolds::Flag(false) => Ok(Self::Off),
            RawInterfaceHolds::Mode(m) => match m.as_str() {
                "off" => Ok(Self::Off),
                "on_stall" => Ok(Self::OnStall),
                "always" => Ok(Self::Always),
                _ => Err(format!(
                    "solver.expert.interface_holds: `{m}` is not one of off, on_stall, always"
                )),
            },
        }
    }
}

/// The schema of what the parser reads (`RawInterfaceHolds`): a mode's
/// name, or the first version's bool. Written out because the derive would
/// take the schema of the untagged `RawInterfaceHolds`, whose mode is any
/// string.
impl JsonSchema for InterfaceHolds {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "InterfaceHolds".into()
    }

    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "oneOf": [
                {"const": "off", "description": "Never: a step whose interface chatters is cut back, and stalls at the minimum step."},
                {"const": "on_stall", "description": "From the first step that would otherwise stall at its minimum size to the end of the run; a run that gets through without them keeps its curve."},
                {"const": "always", "description": "In the retries of every step."},
                {"type": "boolean", "description": "The first form of the option: true is always, false is off."}
            ]
        })
    }
}

/// First iterate of a load step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Predictor {
    /// The last converged displacement with the new Dirichlet values.
    Constant,
    /// The last converged displacement plus the last step's increment scaled
    /// to the new step size (linear extrapolation along the path), with the
    /// new Dirichlet values.
    #[default]
    Extrapolate,
}

/// Newton settings, resolved.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SolverSettings {
    /// ‖residual‖ ≤ tol · ‖reaction‖ (relative force criterion).
    pub residual_tolerance: f64,
    /// |Δu_k · r_{k−1}| ≤ tol · max(largest |Δu_j · r_{j−1}| of the step,
    /// ‖reactions‖ · step size) (energy criterion, dimensionless).
    pub energy_tolerance: f64,
    /// Newton iterations per attempt before a cut-back.
    pub max_iterations: usize,
    /// Tangent used in the Newton matrix.
    pub tangent: TangentKind,
    /// Backtracking line search on the energy along the correction.
    pub line_search: bool,
    pub linear_solver: LinearSolverKind,
    pub ordering: Ordering,
    /// PCG relative residual tolerance.
    pub pcg_tolerance: f64,
    /// PCG iterations before the preconditioner is refactorised.
    pub pcg_max_iterations: usize,
    /// GMRES relative residual tolerance of a Newton correction (the
    /// inexact-Newton forcing term).
    pub krylov_tolerance: f64,
    /// GMRES iterations before the preconditioner is refactorised; a solve
    /// that needed more than half of them refactorises at the next iteration.
    pub krylov_max_iterations: usize,
    /// Choice of the GMRES tolerance per correction.
    pub forcing: Forcing,
    /// First iterate of a load step.
    pub predictor: Predictor,
    /// Precision of the GMRES preconditioner's triangular solves.
    pub preconditioner_precision: Precision,
    /// A stagnating attempt (points flipping between law branches) ends on
    /// its best iterate if that one's relative residual is at most this
    /// multiple of `residual_tolerance` (≥ 1; 1 = the force criterion
    /// itself), counted in `force_only_steps`; otherwise it is cut back.
    pub stagnation_acceptance: f64,
    /// Time integration of the Mazars damage. Left out of the serialised
    /// form when implicit, so that specs without it keep their cache keys.
    #[serde(default, skip_serializing_if = "is_implicit")]
    pub concrete_integration: ConcreteIntegration,
    /// Time integration of the interface damage. Left out of the
    /// serialised form when implicit.
    #[serde(default, skip_serializing_if = "is_implicit_interface")]
    pub interface_integration: InterfaceIntegration,
    /// IMPL-EX step control: after a converged step, the residual of its
    /// displacement under the implicit damage, relative to the reaction,
    /// is compared with this; above it the next step shrinks by
    /// 0.9 √(tol/e) (at least by `solver.expert.cutback`). Left out of the
    /// serialised form at its default.
    #[serde(
        default = "default_impl_ex_tolerance",
        skip_serializing_if = "is_default_impl_ex_tolerance"
    )]
    pub impl_ex_tolerance: f64,
    /// IMPL-EX: a converged step whose extrapolation error is above this
    /// multiple of `impl_ex_tolerance` is redone shorter (a step in which
    /// points start to damage has no increment to extrapolate from, and
    /// its error is not bounded by the next step's size). `None`: every
    /// converged step is kept. Default 2 under `interface_integration:
    /// impl_ex`, else `None`; left out of the serialised form when `None`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub impl_ex_reject: Option<f64>,
    /// Which quantity a step prescribes after the first one. Left out of
    /// the serialised form at its default.
    #[serde(default, skip_serializing_if = "is_auto")]
    pub path_following: PathFollowing,
    /// Tets whose quality (3 r_in / R_circ, 1 for the regular tet) is below
    /// this take their damage from an extrapolation of their history
    /// (IMPL-EX) instead of the step's own: a degenerate tet's strain
    /// swings with displacements far below the tolerance, and its damage
    /// then switches on and off between Newton iterates (docs/src/validation/solver.md,
    /// "Law switches"). 0 disables; left out of the serialised form then.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub sliver_quality: f64,
    /// When the interface points whose regime (stick/slip, slip
    /// direction, damage growth) keeps switching between Newton iterates
    /// are held at a history for a retry of the step and then settled
    /// (after the tets' explicit retry). Left out of the serialised form at
    /// its default.
    #[serde(default, skip_serializing_if = "is_on_stall")]
    pub interface_holds: InterfaceHolds,
    /// The GMRES preconditioner (`linear_solver: gmres` only). Left out of
    /// the serialised form at its default.
    #[serde(default, skip_serializing_if = "is_auto_preconditioner")]
    pub preconditioner: PreconditionerKind,
    /// When a kept multigrid hierarchy is rebuilt. Left out of the
    /// serialised form at its default.
    #[serde(default, skip_serializing_if = "is_half_limit")]
    pub multigrid_rebuild: MultigridRebuild,
    /// A converged step that gives back from the dissipated energy (W_int
    /// − stored, over the whole specimen), or leaves forces out of balance
    /// whose work is, more than this fraction of its own external work
    /// plus 2e-3 of W_ext, reached a state the laws cannot reach from the
    /// last one: it is refused like a failed attempt (docs/src/validation/solver.md,
    /// "Steps that create energy"). 0 disables.
    /// Always serialised, so that a change of it (or of its default)
    /// re-runs the solve.
    #[serde(default = "default_dissipation_tolerance")]
    pub dissipation_tolerance: f64,
}

/// Default of `solver.expert.dissipation_tolerance`: above what the FCZM's
/// non-potential exchange gives back in the kept steps of the sweeps and
/// holdouts (at most 0.082 of a step's work), below the force jumps it
/// refuses (0.21 to 3.9 of their step's work; docs/src/validation/solver.md).
pub const DEFAULT_DISSIPATION_TOLERANCE: f64 = 0.15;

fn default_dissipation_tolerance() -> f64 {
    DEFAULT_DISSIPATION_TOLERANCE
}

fn is_on_stall(h: &InterfaceHolds) -> bool {
    *h == InterfaceHolds::OnStall
}

fn is_auto_preconditioner(p: &PreconditionerKind) -> bool {
    *p == PreconditionerKind::Auto
}

fn is_half_limit(r: &MultigridRebuild) -> bool {
    *r == MultigridRebuild::HalfLimit
}

/// Free DOFs from which `preconditioner: auto` takes the multigrid. Measured
/// (docs/src/validation/performance.md, "The multigrid as the Newton–Krylov
/// preconditioner"): on R1 at the paper's mesh (412 k DOFs) the multigrid
/// solve took 641 s and 2.06 GiB against 743 s and 7.6 GiB for the Cholesky
/// route (that one on the earlier metre-built mesh), the same curve; on r1-coarse (54 k) both
/// took the same time; on tiny-ribbed (7 k) the Cholesky route was 2.8×
/// faster.
pub const MULTIGRID_MIN_DOFS: usize = 100_000;

impl SolverSettings {
    /// The preconditioner `auto` stands for on a system of `free_dofs`.
    pub fn preconditioner_for(&self, free_dofs: usize) -> PreconditionerKind {
        match self.preconditioner {
            PreconditionerKind::Auto
                if self.linear_solver == LinearSolverKind::Gmres
                    && free_dofs >= MULTIGRID_MIN_DOFS =>
            {
                PreconditionerKind::Multigrid
            }
            PreconditionerKind::Auto => PreconditionerKind::Cholesky,
            p => p,
        }
    }
}

fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

fn is_auto(p: &PathFollowing) -> bool {
    *p == PathFollowing::Auto
}

fn is_implicit(c: &ConcreteIntegration) -> bool {
    *c == ConcreteIntegration::Implicit
}

fn is_implicit_interface(c: &InterfaceIntegration) -> bool {
    *c == InterfaceIntegration::Implicit
}

/// Default of `solver.expert.impl_ex_reject` under `interface_integration:
/// impl_ex` (docs/src/validation/solver.md, "IMPL-EX interface").
pub const DEFAULT_IMPL_EX_REJECT: f64 = 2.0;

/// Default of `solver.impl_ex_tolerance` (docs/src/validation/solver.md, IMPL-EX).
pub const DEFAULT_IMPL_EX_TOLERANCE: f64 = 1e-2;

fn default_impl_ex_tolerance() -> f64 {
    DEFAULT_IMPL_EX_TOLERANCE
}

fn is_default_impl_ex_tolerance(v: &f64) -> bool {
    *v == DEFAULT_IMPL_EX_TOLERANCE
}

impl Default for SolverSettings {
    fn default() -> Self {
        Self {
            residual_tolerance: 1e-4,
            energy_tolerance: 1e-8,
            max_iterations: 25,
            tangent: TangentKind::Consistent,
            line_search: true,
            linear_solver: LinearSolverKind::Gmres,
            ordering: Ordering::Metis,
            pcg_tolerance: 1e-8,
            pcg_max_iterations: 20,
            krylov_tolerance: 1e-3,
            krylov_max_iterations: 40,
            forcing: Forcing::EisenstatWalker,
            predictor: Predictor::Extrapolate,
            preconditioner_precision: Precision::Single,
            stagnation_acceptance: 1.0,
            concrete_integration: ConcreteIntegration::Implicit,
            interface_integration: InterfaceIntegration::Implicit,
            impl_ex_tolerance: DEFAULT_IMPL_EX_TOLERANCE,
            impl_ex_reject: None,
            path_following: PathFollowing::Auto,
            sliver_quality: 0.0,
            interface_holds: InterfaceHolds::OnStall,
            preconditioner: PreconditionerKind::Auto,
            multigrid_rebuild: MultigridRebuild::HalfLimit,
            dissipation_tolerance: DEFAULT_DISSIPATION_TOLERANCE,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `interface_holds` takes its modes, and the first version's bools.
    #[test]
    fn interface_holds_modes_and_bools() {
        let parse = |v: &str| serde_yaml::from_str::<InterfaceHolds>(v);
        assert_eq!(parse("on_stall").unwrap(), InterfaceHolds::OnStall);
        assert_eq!(parse("always").unwrap(), InterfaceHolds::Always);
        assert_eq!(parse("off").unwrap(), InterfaceHolds::Off);
        assert_eq!(parse("true").unwrap(), InterfaceHolds::Always);
        assert_eq!(parse("false").unwrap(), InterfaceHolds::Off);
        let e = parse("sometimes").unwrap_err().to_string();
        assert!(
            e.contains("solver.expert.interface_holds") && e.contains("on_stall"),
            "{e}"
        );
        assert_eq!(
            serde_json::to_string(&InterfaceHolds::OnStall).unwrap(),
            "\"on_stall\""
        );
    }
}
