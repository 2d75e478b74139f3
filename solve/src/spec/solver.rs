//! The scene's `loading` and `solver` sections: raw (as written, with units)
//! and resolved (SI, validated, defaults filled).
//!
//! ```
//! use solve::spec::solver::{RawLoading, RawSolver};
//! let l: RawLoading = serde_yaml::from_str("u_final: 0.5 mm\ninitial_step: 2 um").unwrap();
//! let l = l.resolve().unwrap();
//! assert!((l.u_final - 0.5e-3).abs() < 1e-15);
//! let s: RawSolver = serde_yaml::from_str("linear_solver: pcg").unwrap();
//! assert_eq!(s.resolve().unwrap().max_iterations, 25);
//! ```

use crate::laws::TangentKind;
use crate::linalg::Ordering;
use geom::units::{Dim, RawQuantity, UnitError};
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
}

/// `loading` as written.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawLoading {
    pub u_final: Option<RawQuantity>,
    pub fed_stop: Option<RawQuantity>,
    pub initial_step: Option<RawQuantity>,
    pub min_step: Option<RawQuantity>,
    pub max_step: Option<RawQuantity>,
    pub growth: Option<f64>,
    pub cutback: Option<f64>,
    pub easy_iterations: Option<usize>,
    pub max_steps: Option<usize>,
    pub curve_tolerance: Option<f64>,
    pub curve_error: Option<CurveError>,
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

/// What `loading.curve_tolerance` bounds (docs/solver.md, "Resolving the
/// curve").
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CurveError {
    /// The shortest distance of a curve point from its neighbours' chord.
    #[default]
    Distance,
    /// Where the FED grows, the σ_mb distance of the point from the chord
    /// at its FED: the error of σ_mb read along FED, which on a steep rise
    /// or drop is many times the shortest distance. Elsewhere as
    /// `Distance`.
    Stress,
}

impl CurveError {
    fn is_distance(&self) -> bool {
        *self == CurveError::Distance
    }
}

/// `loading.curve_tolerance` unless a scene sets it (docs/solver.md,
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

fn positive(key: &str, v: f64) -> Result<f64, SolverSpecError> {
    if v > 0.0 {
        Ok(v)
    } else {
        Err(SolverSpecError::OutOfRange {
            key: key.into(),
            value: v,
            bound: "must be > 0",
        })
    }
}

fn length(q: &Option<RawQuantity>, key: &str, default: f64) -> Result<f64, SolverSpecError> {
    match q {
        Some(q) => positive(key, q.to_si(Dim::Length, key)?),
        None => Ok(default),
    }
}

impl RawLoading {
    pub fn resolve(&self) -> Result<Loading, SolverSpecError> {
        let d = Loading::default();
        let l = Loading {
            u_final: length(&self.u_final, "loading.u_final", d.u_final)?,
            fed_stop: match &self.fed_stop {
                Some(q) => Some(positive(
                    "loading.fed_stop",
                    q.to_si(Dim::Length, "loading.fed_stop")?,
                )?),
                None => None,
            },
            initial_step: length(&self.initial_step, "loading.initial_step", d.initial_step)?,
            min_step: length(&self.min_step, "loading.min_step", d.min_step)?,
            max_step: length(&self.max_step, "loading.max_step", d.max_step)?,
            growth: self.growth.unwrap_or(d.growth),
            cutback: self.cutback.unwrap_or(d.cutback),
            easy_iterations: self.easy_iterations.unwrap_or(d.easy_iterations),
            max_steps: self.max_steps,
            curve_tolerance: self.curve_tolerance.unwrap_or(d.curve_tolerance),
            curve_error: self.curve_error.unwrap_or(d.curve_error),
        };
        let bad = |key: &str, value: f64, bound| {
            Err(SolverSpecError::OutOfRange {
                key: key.into(),
                value,
                bound,
            })
        };
        if !(l.curve_tolerance >= 0.0 && l.curve_tolerance.is_finite()) {
            return bad(
                "loading.curve_tolerance",
                l.curve_tolerance,
                "must be ≥ 0 (0: off)",
            );
        }
        if l.max_steps == Some(0) {
            return bad("loading.max_steps", 0.0, "must be ≥ 1");
        }
        if !(l.growth >= 1.0 && l.growth.is_finite()) {
            return bad("loading.growth", l.growth, "must be ≥ 1");
        }
        if !(l.cutback > 0.0 && l.cutback < 1.0) {
            return bad("loading.cutback", l.cutback, "must be in (0, 1)");
        }
        if l.min_step > l.initial_step {
            return bad(
                "loading.min_step",
                l.min_step,
                "must be ≤ loading.initial_step",
            );
        }
        if l.initial_step > l.max_step {
            return bad(
                "loading.initial_step",
                l.initial_step,
                "must be ≤ loading.max_step",
            );
        }
        Ok(l)
    }
}

/// Linear solver of the Newton corrections.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
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

/// `solver` as written.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RawSolver {
    pub residual_tolerance: Option<f64>,
    pub energy_tolerance: Option<f64>,
    pub max_iterations: Option<usize>,
    pub tangent: Option<TangentKind>,
    pub line_search: Option<bool>,
    pub linear_solver: Option<LinearSolverKind>,
    pub ordering: Option<Ordering>,
    pub pcg_tolerance: Option<f64>,
    pub pcg_max_iterations: Option<usize>,
    pub krylov_tolerance: Option<f64>,
    pub krylov_max_iterations: Option<usize>,
    pub forcing: Option<Forcing>,
    pub predictor: Option<Predictor>,
    pub preconditioner_precision: Option<Precision>,
    pub stagnation_acceptance: Option<f64>,
    pub concrete_integration: Option<ConcreteIntegration>,
    pub interface_integration: Option<InterfaceIntegration>,
    pub impl_ex_tolerance: Option<f64>,
    pub impl_ex_reject: Option<f64>,
    pub path_following: Option<PathFollowing>,
    pub sliver_quality: Option<f64>,
    pub interface_holds: Option<InterfaceHolds>,
    pub preconditioner: Option<PreconditionerKind>,
    pub multigrid_rebuild: Option<MultigridRebuild>,
    pub dissipation_tolerance: Option<f64>,
}

/// What preconditions GMRES in the Newton–Krylov solver.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum PreconditionerKind {
    /// `multigrid` from [`MULTIGRID_MIN_DOFS`] free DOFs on, else `cholesky`.
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum MultigridRebuild {
    /// After a solve that needed more than half of `krylov_max_iterations`.
    #[default]
    HalfLimit,
    /// Also once the solves since the last build have needed, beyond the
    /// iterations of the first of them, more GMRES iterations in all than
    /// a build costs ([`REBUILD_COST_ITERATIONS`]), so that a hierarchy
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
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
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
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
    /// the implicit one (docs/solver.md).
    ImplEx,
}

/// Time integration of the interface damage (FCZM and Tvergaard λ̃).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
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
    /// `impl_ex_tolerance` bounds its error (docs/solver.md).
    ImplEx,
}

/// What a load step prescribes (docs/solver.md, Path-following).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
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
/// switching between Newton iterates (docs/solver.md, "Law switches").
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

/// `solver.interface_holds` as written: a mode, or the bool of the first
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
                    "solver.interface_holds: `{m}` is not one of off, on_stall, always"
                )),
            },
        }
    }
}

/// First iterate of a load step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize, Default)]
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
    /// 0.9 √(tol/e) (at least by `loading.cutback`). Left out of the
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
    /// then switches on and off between Newton iterates (docs/solver.md,
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
    /// last one: it is refused like a failed attempt (docs/solver.md,
    /// "Steps that create energy"). 0 disables.
    /// Always serialised, so that a change of it (or of its default)
    /// re-runs the solve.
    #[serde(default = "default_dissipation_tolerance")]
    pub dissipation_tolerance: f64,
}

/// Default of `solver.dissipation_tolerance`: above what the FCZM's
/// non-potential exchange gives back in the kept steps of the sweeps and
/// holdouts (at most 0.082 of a step's work), below the force jumps it
/// refuses (0.21 to 3.9 of their step's work; docs/solver.md).
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
/// (docs/performance.md, "The multigrid as the Newton–Krylov
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

/// `v` if it lies in [0, 1), else the error naming `key`.
fn in_unit_interval(key: &str, v: f64) -> Result<f64, SolverSpecError> {
    if (0.0..1.0).contains(&v) {
        Ok(v)
    } else {
        Err(SolverSpecError::OutOfRange {
            key: key.into(),
            value: v,
            bound: "must be in [0, 1)",
        })
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

/// Default of `solver.impl_ex_reject` under `interface_integration:
/// impl_ex` (docs/solver.md, "IMPL-EX interface").
pub const DEFAULT_IMPL_EX_REJECT: f64 = 2.0;

/// Default of `solver.impl_ex_tolerance` (docs/solver.md, IMPL-EX).
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

impl RawSolver {
    pub fn resolve(&self) -> Result<SolverSettings, SolverSpecError> {
        let d = SolverSettings::default();
        let unit = |key: &str, v: Option<f64>, dv: f64| -> Result<f64, SolverSpecError> {
            let v = v.unwrap_or(dv);
            if v > 0.0 && v < 1.0 {
                Ok(v)
            } else {
                Err(SolverSpecError::OutOfRange {
                    key: key.into(),
                    value: v,
                    bound: "must be in (0, 1)",
                })
            }
        };
        let count = |key: &str, v: Option<usize>, dv: usize| -> Result<usize, SolverSpecError> {
            let v = v.unwrap_or(dv);
            if v >= 1 {
                Ok(v)
            } else {
                Err(SolverSpecError::OutOfRange {
                    key: key.into(),
                    value: v as f64,
                    bound: "must be ≥ 1",
                })
            }
        };
        Ok(SolverSettings {
            residual_tolerance: unit(
                "solver.residual_tolerance",
                self.residual_tolerance,
                d.residual_tolerance,
            )?,
            energy_tolerance: unit(
                "solver.energy_tolerance",
                self.energy_tolerance,
                d.energy_tolerance,
            )?,
            max_iterations: count(
                "solver.max_iterations",
                self.max_iterations,
                d.max_iterations,
            )?,
            tangent: self.tangent.unwrap_or(d.tangent),
            line_search: self.line_search.unwrap_or(d.line_search),
            linear_solver: self.linear_solver.unwrap_or(d.linear_solver),
            ordering: self.ordering.unwrap_or(d.ordering),
            pcg_tolerance: unit("solver.pcg_tolerance", self.pcg_tolerance, d.pcg_tolerance)?,
            pcg_max_iterations: count(
                "solver.pcg_max_iterations",
                self.pcg_max_iterations,
                d.pcg_max_iterations,
            )?,
            krylov_tolerance: unit(
                "solver.krylov_tolerance",
                self.krylov_tolerance,
                d.krylov_tolerance,
            )?,
            krylov_max_iterations: count(
                "solver.krylov_max_iterations",
                self.krylov_max_iterations,
                d.krylov_max_iterations,
            )?,
            forcing: self.forcing.unwrap_or(d.forcing),
            predictor: self.predictor.unwrap_or(d.predictor),
            preconditioner_precision: self
                .preconditioner_precision
                .unwrap_or(d.preconditioner_precision),
            stagnation_acceptance: {
                let v = self
                    .stagnation_acceptance
                    .unwrap_or(d.stagnation_acceptance);
                if v.is_finite() && v >= 1.0 {
                    v
                } else {
                    return Err(SolverSpecError::OutOfRange {
                        key: "solver.stagnation_acceptance".into(),
                        value: v,
                        bound: "must be ≥ 1 (a multiple of residual_tolerance)",
                    });
                }
            },
            concrete_integration: self.concrete_integration.unwrap_or(d.concrete_integration),
            interface_integration: self
                .interface_integration
                .unwrap_or(d.interface_integration),
            impl_ex_tolerance: {
                let v = self.impl_ex_tolerance.unwrap_or(d.impl_ex_tolerance);
                if v.is_finite() && v > 0.0 {
                    v
                } else {
                    return Err(SolverSpecError::OutOfRange {
                        key: "solver.impl_ex_tolerance".into(),
                        value: v,
                        bound: "must be > 0",
                    });
                }
            },
            impl_ex_reject: self.impl_ex_reject()?,
            path_following: self.path_following.unwrap_or(d.path_following),
            sliver_quality: in_unit_interval(
                "solver.sliver_quality",
                self.sliver_quality.unwrap_or(d.sliver_quality),
            )?,
            interface_holds: self.interface_holds.unwrap_or(d.interface_holds),
            preconditioner: self.preconditioner(&d)?,
            multigrid_rebuild: self.multigrid_rebuild.unwrap_or(d.multigrid_rebuild),
            dissipation_tolerance: in_unit_interval(
                "solver.dissipation_tolerance",
                self.dissipation_tolerance
                    .unwrap_or(d.dissipation_tolerance),
            )?,
        })
    }
}

impl RawSolver {
    /// `preconditioner` as given, else its default; the multigrid only
    /// with GMRES.
    fn preconditioner(&self, d: &SolverSettings) -> Result<PreconditionerKind, SolverSpecError> {
        let p = self.preconditioner.unwrap_or(d.preconditioner);
        let linear = self.linear_solver.unwrap_or(d.linear_solver);
        if p == PreconditionerKind::Multigrid && linear != LinearSolverKind::Gmres {
            return Err(SolverSpecError::Combination {
                key: "solver.preconditioner".into(),
                problem: "multigrid preconditions GMRES only: set linear_solver: gmres (the default) or leave preconditioner out",
            });
        }
        Ok(p)
    }

    /// `impl_ex_reject` as given (≥ 1), else its default: on with the
    /// interface IMPL-EX, off otherwise.
    fn impl_ex_reject(&self) -> Result<Option<f64>, SolverSpecError> {
        match self.impl_ex_reject {
            Some(v) if v.is_nan() || v < 1.0 => Err(SolverSpecError::OutOfRange {
                key: "solver.impl_ex_reject".into(),
                value: v,
                bound: "must be ≥ 1 (a multiple of impl_ex_tolerance)",
            }),
            Some(v) => Ok(Some(v)),
            None => Ok(
                (self.interface_integration == Some(InterfaceIntegration::ImplEx))
                    .then_some(DEFAULT_IMPL_EX_REJECT),
            ),
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
            e.contains("solver.interface_holds") && e.contains("on_stall"),
            "{e}"
        );
        assert_eq!(
            serde_json::to_string(&InterfaceHolds::OnStall).unwrap(),
            "\"on_stall\""
        );
    }

    /// IMPL-EX rejection: on by default only with the interface IMPL-EX
    /// (concrete-only IMPL-EX runs keep every converged step, as before),
    /// settable, and a bound below the tolerance itself is refused.
    #[test]
    fn impl_ex_reject_defaults_with_the_interface_integration() {
        let resolve = |y: &str| serde_yaml::from_str::<RawSolver>(y).unwrap().resolve();
        assert_eq!(resolve("{}").unwrap().impl_ex_reject, None);
        let concrete = resolve("concrete_integration: impl_ex").unwrap();
        assert_eq!(concrete.impl_ex_reject, None);
        let interface = resolve("interface_integration: impl_ex").unwrap();
        assert_eq!(
            interface.interface_integration,
            InterfaceIntegration::ImplEx
        );
        assert_eq!(interface.impl_ex_reject, Some(DEFAULT_IMPL_EX_REJECT));
        let set = resolve("concrete_integration: impl_ex\nimpl_ex_reject: 4").unwrap();
        assert_eq!(set.impl_ex_reject, Some(4.0));
        for bad in ["0.5", ".nan"] {
            let e = resolve(&format!("impl_ex_reject: {bad}"))
                .unwrap_err()
                .to_string();
            assert!(e.contains("solver.impl_ex_reject"), "{e}");
        }
        let e = serde_yaml::from_str::<RawSolver>("interface_integration: explicit")
            .unwrap_err()
            .to_string();
        assert!(e.contains("impl_ex"), "{e}");
    }

    #[test]
    fn unknown_key_and_bad_values_are_named() {
        let e = serde_yaml::from_str::<RawLoading>("u_finall: 1 mm").unwrap_err();
        assert!(e.to_string().contains("u_finall"), "{e}");
        let l: RawLoading = serde_yaml::from_str("u_final: 1 MPa").unwrap();
        assert!(l
            .resolve()
            .unwrap_err()
            .to_string()
            .contains("loading.u_final"));
        let l: RawLoading = serde_yaml::from_str("cutback: 1.5").unwrap();
        assert!(l
            .resolve()
            .unwrap_err()
            .to_string()
            .contains("loading.cutback"));
        let s: RawSolver = serde_yaml::from_str("residual_tolerance: 0").unwrap();
        assert!(s
            .resolve()
            .unwrap_err()
            .to_string()
            .contains("solver.residual_tolerance"));
        for bad in ["0.5", ".nan"] {
            let s: RawSolver =
                serde_yaml::from_str(&format!("stagnation_acceptance: {bad}")).unwrap();
            assert!(s
                .resolve()
                .unwrap_err()
                .to_string()
                .contains("solver.stagnation_acceptance"));
        }
        let s: RawSolver =
            serde_yaml::from_str("stagnation_acceptance: 1\npreconditioner_precision: double")
                .unwrap();
        let s = s.resolve().unwrap();
        assert_eq!(
            (s.stagnation_acceptance, s.preconditioner_precision),
            (1.0, Precision::Double)
        );
        let s: RawSolver = serde_yaml::from_str("tangent: secant\nordering: amd").unwrap();
        let s = s.resolve().unwrap();
        assert_eq!(
            (s.tangent, s.ordering),
            (TangentKind::Secant, Ordering::Amd)
        );
    }

    #[test]
    fn defaults_are_documented_values() {
        let l = RawLoading::default().resolve().unwrap();
        assert_eq!(l, Loading::default());
        assert_eq!(l.u_final, 1e-3);
    }

    #[test]
    fn auto_preconditioner_takes_the_multigrid_on_large_gmres_systems_only() {
        let auto: SolverSettings = RawSolver::default().resolve().unwrap();
        assert_eq!(
            auto.preconditioner_for(MULTIGRID_MIN_DOFS - 1),
            PreconditionerKind::Cholesky
        );
        assert_eq!(
            auto.preconditioner_for(MULTIGRID_MIN_DOFS),
            PreconditionerKind::Multigrid
        );
        let pcg: RawSolver = serde_yaml::from_str("linear_solver: pcg").unwrap();
        let pcg = pcg.resolve().unwrap();
        assert_eq!(
            pcg.preconditioner_for(10 * MULTIGRID_MIN_DOFS),
            PreconditionerKind::Cholesky
        );
        let chosen: RawSolver = serde_yaml::from_str("preconditioner: cholesky").unwrap();
        let chosen = chosen.resolve().unwrap();
        assert_eq!(
            chosen.preconditioner_for(10 * MULTIGRID_MIN_DOFS),
            PreconditionerKind::Cholesky
        );
        let bad: RawSolver =
            serde_yaml::from_str("preconditioner: multigrid\nlinear_solver: cholesky").unwrap();
        let e = bad.resolve().unwrap_err().to_string();
        assert!(
            e.contains("solver.preconditioner") && e.contains("gmres"),
            "{e}"
        );
        // The default stays out of the serialised settings (cache keys).
        let yaml = serde_yaml::to_string(&auto).unwrap();
        assert!(!yaml.contains("preconditioner:"), "{yaml}");
    }
}
