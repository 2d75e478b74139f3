//! The `loading` and `solver` sections as written, and their resolution.
//!
//! A scene sets a few main keys: the loading's end and step bounds, the
//! curve tolerance, the residual tolerance, the integrations, the path
//! control and a named `profile` that fills in the settings a kind of run
//! needs. Everything else a run can be tuned by is under `solver.expert`,
//! each key with its unit and the reason a user would touch it
//! (specs/README.md). A value is taken from the key written, else from the
//! profile, else from the default; only the resolved values are hashed, so
//! a scene that writes out what a profile sets has the same cache keys.
//!
//! Keys of an earlier layout are refused with their new place
//! ([`moved_key`]), so an old scene file says what to change.

use super::settings::{
    ConcreteIntegration, CurveError, Forcing, InterfaceHolds, InterfaceIntegration,
    LinearSolverKind, Loading, MultigridRebuild, PathFollowing, Precision, PreconditionerKind,
    Predictor, SolverSettings, SolverSpecError, DEFAULT_IMPL_EX_REJECT,
};
use crate::laws::TangentKind;
use crate::linalg::Ordering;
use geom::units::{Dim, RawQuantity};
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// `loading` as written: how far the bar is pulled and the bounds of the
/// steps.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawLoading {
    /// Final imposed displacement of the bar's loaded end (length; default
    /// 1 mm; > 0).
    pub u_final: Option<RawQuantity>,
    /// Stop once the free-end displacement (FED) reaches this value
    /// (length; default none; > 0).
    pub fed_stop: Option<RawQuantity>,
    /// Size of the first step (length; default 5 µm; ≥ `min_step`, ≤
    /// `max_step`).
    pub initial_step: Option<RawQuantity>,
    /// Smallest step: a step that fails at this size ends the run, and the
    /// IMPL-EX step control keeps a step at this size whatever its error
    /// (length; default 1 nm; ≤ `initial_step`).
    pub min_step: Option<RawQuantity>,
    /// Largest step; a dissipation-controlled step releases at most ½|F|
    /// times it (length; default 20 µm; ≥ `initial_step`).
    pub max_step: Option<RawQuantity>,
    /// How closely displacement-controlled steps follow the bond
    /// stress–slip curve: the distance of each curve point from the chord
    /// of its neighbours, on axes scaled to the FED's range and the largest
    /// |σ_mb| so far, is held near this; a step more than twice above it is
    /// redone shorter (pure number; default 3e-3; ≥ 0, 0 switches it off).
    pub curve_tolerance: Option<f64>,
}

/// A named set of solver settings for a kind of run (`solver.profile`).
/// The keys a scene writes override the profile's.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Profile {
    /// Implicit integration of every law, Newton on the energy and force
    /// criteria: the default, for meshes up to about 0.6 mm at the
    /// interface.
    #[default]
    Implicit,
    /// IMPL-EX concrete damage for meshes at the paper's resolution (R1):
    /// `concrete_integration: impl_ex`, the force criterion deciding
    /// (`expert.energy_tolerance: 0.5`) and each GMRES solve aimed at it
    /// (`expert.forcing: tolerance`).
    ImplEx,
    /// `impl_ex` with the interface damage IMPL-EX too, for interfaces that
    /// soften along their whole length at once (R2):
    /// `interface_integration: impl_ex` and `expert.krylov_max_iterations:
    /// 120` for the snap-back, where many interface points slide at once.
    ImplExInterface,
}

impl Profile {
    /// The settings the profile stands for where a scene writes nothing.
    pub fn settings(self) -> SolverSettings {
        let d = SolverSettings::default();
        match self {
            Profile::Implicit => d,
            Profile::ImplEx => SolverSettings {
                concrete_integration: ConcreteIntegration::ImplEx,
                energy_tolerance: 0.5,
                forcing: Forcing::Tolerance,
                ..d
            },
            Profile::ImplExInterface => SolverSettings {
                interface_integration: InterfaceIntegration::ImplEx,
                krylov_max_iterations: 120,
                ..Profile::ImplEx.settings()
            },
        }
    }
}

/// `solver` as written: the main keys, the profile, and the expert section.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawSolver {
    /// Named settings for a kind of run: `implicit`, `impl_ex` (IMPL-EX
    /// concrete, for the paper's mesh) or `impl_ex_interface` (IMPL-EX
    /// concrete and interface, for interfaces that unzip at once); the keys
    /// a scene writes override the profile's (choice; default implicit).
    pub profile: Option<Profile>,
    /// Newton's force criterion: ‖residual‖ ≤ this × ‖reactions‖ (pure
    /// number; default 1e-4; in (0, 1)).
    pub residual_tolerance: Option<f64>,
    /// Time integration of the Mazars damage: `implicit` (backward Euler)
    /// or `impl_ex` (the stress of a step uses the damage extrapolated from
    /// the last two steps; first order in the step) (choice; default
    /// implicit, impl_ex under the IMPL-EX profiles).
    pub concrete_integration: Option<ConcreteIntegration>,
    /// Time integration of the interface damage: `implicit` or `impl_ex`
    /// (choice; default implicit, impl_ex under `impl_ex_interface`).
    pub interface_integration: Option<InterfaceIntegration>,
    /// IMPL-EX step control: a step whose displacement is out of balance
    /// under the implicit damage by more than this share of the reaction
    /// shrinks the next one (pure number; default 1e-2; > 0).
    pub impl_ex_tolerance: Option<f64>,
    /// What a step prescribes: `auto` (the imposed displacement, handing
    /// over to dissipation control where it stalls after a dissipating
    /// step), `off`, `fed`, `energy` or `process_zone` (choice; default
    /// auto).
    pub path_following: Option<PathFollowing>,
    /// Settings a user rarely needs: step growth and cut-back, Newton's
    /// other criteria, the linear solver, and the stepping policy's
    /// remedies.
    pub expert: Option<RawExpert>,
}

/// `solver.expert` as written: each key's unit and why a user would set
/// it are in specs/README.md.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RawExpert {
    /// Step growth factor after an easy step (pure number; default 1.5;
    /// ≥ 1).
    pub growth: Option<f64>,
    /// Step reduction factor after a failed attempt (pure number; default
    /// 0.5; in (0, 1)).
    pub cutback: Option<f64>,
    /// Stop after this many converged steps, the converged part kept and
    /// the run reported as stopped: a bound on run time that gives the same
    /// result on every machine (count; default none; ≥ 1).
    pub max_steps: Option<usize>,
    /// What `loading.curve_tolerance` bounds: `distance` (the shortest
    /// distance of a point from its neighbours' chord) or `stress` (where
    /// the FED grows, the σ_mb distance at the point's FED) (choice;
    /// default distance).
    pub curve_error: Option<CurveError>,
    /// Newton's energy criterion: |Δu·r| ≤ this × the step's largest
    /// (pure number; default 1e-8, 0.5 under the IMPL-EX profiles; in (0, 1)).
    pub energy_tolerance: Option<f64>,
    /// Newton iterations per attempt before a cut-back (count; default 25;
    /// ≥ 1).
    pub max_iterations: Option<usize>,
    /// Newton matrix: `consistent`, `secant` or `elastic` (choice; default
    /// consistent).
    pub tangent: Option<TangentKind>,
    /// Secant line search on the energy along each correction (bool;
    /// default true).
    pub line_search: Option<bool>,
    /// First iterate of a step: `extrapolate` (the last increment scaled
    /// to the new step) or `constant` (choice; default extrapolate).
    pub predictor: Option<Predictor>,
    /// A stagnating attempt ends on its best iterate if its relative
    /// residual is at most this multiple of `residual_tolerance` (pure
    /// number; default 1; ≥ 1).
    pub stagnation_acceptance: Option<f64>,
    /// Linear solver of the corrections: `gmres`, `cholesky` or `pcg`
    /// (choice; default gmres).
    pub linear_solver: Option<LinearSolverKind>,
    /// Fill-reducing ordering of Cholesky factors: `metis` or `amd`
    /// (choice; default metis).
    pub ordering: Option<Ordering>,
    /// GMRES relative residual of a correction, the tightest one used
    /// (pure number; default 1e-3; in (0, 1)).
    pub krylov_tolerance: Option<f64>,
    /// GMRES iterations per solve; past half of them the preconditioner is
    /// rebuilt (count; default 40, 120 under `impl_ex_interface`; ≥ 1).
    pub krylov_max_iterations: Option<usize>,
    /// GMRES tolerance per correction: `eisenstat_walker`, `tolerance` or
    /// `fixed` (choice; default eisenstat_walker, tolerance under the
    /// IMPL-EX profiles).
    pub forcing: Option<Forcing>,
    /// What preconditions GMRES: `auto` (multigrid from 100 000 free DOFs,
    /// else Cholesky), `cholesky` or `multigrid` (choice; default auto).
    pub preconditioner: Option<PreconditionerKind>,
    /// Precision of the Cholesky preconditioner's triangular solves:
    /// `single` or `double` (choice; default single).
    pub preconditioner_precision: Option<Precision>,
    /// When a kept multigrid hierarchy is rebuilt: `half_limit` or
    /// `amortised` (choice; default half_limit).
    pub multigrid_rebuild: Option<MultigridRebuild>,
    /// A converged IMPL-EX step whose error is above this multiple of
    /// `impl_ex_tolerance` is redone shorter (pure number; default 2 with
    /// the IMPL-EX interface, else unset; ≥ 1).
    pub impl_ex_reject: Option<f64>,
    /// Tets of quality below this take their damage from the IMPL-EX
    /// extrapolation for the whole run (pure number; default 0: none; in
    /// [0, 1)).
    pub sliver_quality: Option<f64>,
    /// When interface points whose regime keeps switching are held for a
    /// retry: `on_stall`, `always` or `off` (choice; default on_stall).
    pub interface_holds: Option<InterfaceHolds>,
    /// A converged step that gives back dissipated energy, or leaves forces
    /// out of balance whose work is, more than this share of its own work is
    /// refused (pure number; default 0.15; in [0, 1), 0 switches it off).
    pub dissipation_tolerance: Option<f64>,
}

/// The keys of an earlier layout of `loading` and `solver`, each with its
/// place now (`None`: removed, its value fixed).
const MOVED: &[(&str, Option<&str>)] = &[
    ("loading.growth", Some("solver.expert.growth")),
    ("loading.cutback", Some("solver.expert.cutback")),
    ("loading.max_steps", Some("solver.expert.max_steps")),
    ("loading.curve_error", Some("solver.expert.curve_error")),
    ("loading.easy_iterations", None),
    (
        "solver.energy_tolerance",
        Some("solver.expert.energy_tolerance"),
    ),
    (
        "solver.max_iterations",
        Some("solver.expert.max_iterations"),
    ),
    ("solver.tangent", Some("solver.expert.tangent")),
    ("solver.line_search", Some("solver.expert.line_search")),
    ("solver.predictor", Some("solver.expert.predictor")),
    (
        "solver.stagnation_acceptance",
        Some("solver.expert.stagnation_acceptance"),
    ),
    ("solver.linear_solver", Some("solver.expert.linear_solver")),
    ("solver.ordering", Some("solver.expert.ordering")),
    (
        "solver.krylov_tolerance",
        Some("solver.expert.krylov_tolerance"),
    ),
    (
        "solver.krylov_max_iterations",
        Some("solver.expert.krylov_max_iterations"),
    ),
    ("solver.forcing", Some("solver.expert.forcing")),
    (
        "solver.preconditioner",
        Some("solver.expert.preconditioner"),
    ),
    (
        "solver.preconditioner_precision",
        Some("solver.expert.preconditioner_precision"),
    ),
    (
        "solver.multigrid_rebuild",
        Some("solver.expert.multigrid_rebuild"),
    ),
    (
        "solver.impl_ex_reject",
        Some("solver.expert.impl_ex_reject"),
    ),
    (
        "solver.sliver_quality",
        Some("solver.expert.sliver_quality"),
    ),
    (
        "solver.interface_holds",
        Some("solver.expert.interface_holds"),
    ),
    (
        "solver.dissipation_tolerance",
        Some("solver.expert.dissipation_tolerance"),
    ),
    ("solver.pcg_tolerance", None),
    ("solver.pcg_max_iterations", None),
];

/// The first key of an earlier layout in a scene tree, and what became of
/// it: `Err` with the message a user reads ("loading.growth: moved to
/// solver.expert.growth").
pub fn moved_key(tree: &serde_yaml::Value) -> Result<(), SolverSpecError> {
    for (old, new) in MOVED {
        let (section, key) = old.split_once('.').expect("dotted");
        if tree.get(section).and_then(|s| s.get(key)).is_some() {
            return Err(SolverSpecError::Moved {
                key: (*old).to_string(),
                place: match new {
                    Some(new) => format!("moved to {new}"),
                    None => "removed: its value is fixed (specs/README.md)".to_string(),
                },
            });
        }
    }
    Ok(())
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

fn out_of_range<T>(key: &str, value: f64, bound: &'static str) -> Result<T, SolverSpecError> {
    Err(SolverSpecError::OutOfRange {
        key: key.into(),
        value,
        bound,
    })
}

impl RawLoading {
    /// The loading in SI, with the step policy's keys of `solver.expert`.
    pub fn resolve(&self, solver: &RawSolver) -> Result<Loading, SolverSpecError> {
        let d = Loading::default();
        let expert = solver.expert.clone().unwrap_or_default();
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
            growth: expert.growth.unwrap_or(d.growth),
            cutback: expert.cutback.unwrap_or(d.cutback),
            easy_iterations: d.easy_iterations,
            max_steps: expert.max_steps,
            curve_tolerance: self.curve_tolerance.unwrap_or(d.curve_tolerance),
            curve_error: expert.curve_error.unwrap_or(d.curve_error),
        };
        if !(l.curve_tolerance >= 0.0 && l.curve_tolerance.is_finite()) {
            return out_of_range(
                "loading.curve_tolerance",
                l.curve_tolerance,
                "must be ≥ 0 (0: off)",
            );
        }
        if l.max_steps == Some(0) {
            return out_of_range("solver.expert.max_steps", 0.0, "must be ≥ 1");
        }
        if !(l.growth >= 1.0 && l.growth.is_finite()) {
            return out_of_range("solver.expert.growth", l.growth, "must be ≥ 1");
        }
        if !(l.cutback > 0.0 && l.cutback < 1.0) {
            return out_of_range("solver.expert.cutback", l.cutback, "must be in (0, 1)");
        }
        if l.min_step > l.initial_step {
            return out_of_range(
                "loading.min_step",
                l.min_step,
                "must be ≤ loading.initial_step",
            );
        }
        if l.initial_step > l.max_step {
            return out_of_range(
                "loading.initial_step",
                l.initial_step,
                "must be ≤ loading.max_step",
            );
        }
        Ok(l)
    }
}

/// `v` if it lies in (0, 1), else the error naming `key`.
fn open_unit(key: &str, v: f64) -> Result<f64, SolverSpecError> {
    if v > 0.0 && v < 1.0 {
        Ok(v)
    } else {
        out_of_range(key, v, "must be in (0, 1)")
    }
}

/// `v` if it lies in [0, 1), else the error naming `key`.
fn in_unit_interval(key: &str, v: f64) -> Result<f64, SolverSpecError> {
    if (0.0..1.0).contains(&v) {
        Ok(v)
    } else {
        out_of_range(key, v, "must be in [0, 1)")
    }
}

/// `v` if it is at least 1, else the error naming `key`.
fn count(key: &str, v: usize) -> Result<usize, SolverSpecError> {
    if v >= 1 {
        Ok(v)
    } else {
        out_of_range(key, v as f64, "must be ≥ 1")
    }
}

impl RawSolver {
    /// The settings in SI: each key as written, else the profile's, else
    /// the default.
    pub fn resolve(&self) -> Result<SolverSettings, SolverSpecError> {
        let p = self.profile.unwrap_or_default().settings();
        let x = self.expert.clone().unwrap_or_default();
        let interface_integration = self
            .interface_integration
            .unwrap_or(p.interface_integration);
        let linear_solver = x.linear_solver.unwrap_or(p.linear_solver);
        Ok(SolverSettings {
            residual_tolerance: open_unit(
                "solver.residual_tolerance",
                self.residual_tolerance.unwrap_or(p.residual_tolerance),
            )?,
            energy_tolerance: open_unit(
                "solver.expert.energy_tolerance",
                x.energy_tolerance.unwrap_or(p.energy_tolerance),
            )?,
            max_iterations: count(
                "solver.expert.max_iterations",
                x.max_iterations.unwrap_or(p.max_iterations),
            )?,
            tangent: x.tangent.unwrap_or(p.tangent),
            line_search: x.line_search.unwrap_or(p.line_search),
            linear_solver,
            ordering: x.ordering.unwrap_or(p.ordering),
            pcg_tolerance: p.pcg_tolerance,
            pcg_max_iterations: p.pcg_max_iterations,
            krylov_tolerance: open_unit(
                "solver.expert.krylov_tolerance",
                x.krylov_tolerance.unwrap_or(p.krylov_tolerance),
            )?,
            krylov_max_iterations: count(
                "solver.expert.krylov_max_iterations",
                x.krylov_max_iterations.unwrap_or(p.krylov_max_iterations),
            )?,
            forcing: x.forcing.unwrap_or(p.forcing),
            predictor: x.predictor.unwrap_or(p.predictor),
            preconditioner_precision: x
                .preconditioner_precision
                .unwrap_or(p.preconditioner_precision),
            stagnation_acceptance: stagnation_acceptance(
                x.stagnation_acceptance.unwrap_or(p.stagnation_acceptance),
            )?,
            concrete_integration: self.concrete_integration.unwrap_or(p.concrete_integration),
            interface_integration,
            impl_ex_tolerance: impl_ex_tolerance(
                self.impl_ex_tolerance.unwrap_or(p.impl_ex_tolerance),
            )?,
            impl_ex_reject: impl_ex_reject(x.impl_ex_reject, interface_integration)?,
            path_following: self.path_following.unwrap_or(p.path_following),
            sliver_quality: in_unit_interval(
                "solver.expert.sliver_quality",
                x.sliver_quality.unwrap_or(p.sliver_quality),
            )?,
            interface_holds: x.interface_holds.unwrap_or(p.interface_holds),
            preconditioner: preconditioner(
                x.preconditioner.unwrap_or(p.preconditioner),
                linear_solver,
            )?,
            multigrid_rebuild: x.multigrid_rebuild.unwrap_or(p.multigrid_rebuild),
            dissipation_tolerance: in_unit_interval(
                "solver.expert.dissipation_tolerance",
                x.dissipation_tolerance.unwrap_or(p.dissipation_tolerance),
            )?,
        })
    }
}

fn stagnation_acceptance(v: f64) -> Result<f64, SolverSpecError> {
    if v.is_finite() && v >= 1.0 {
        Ok(v)
    } else {
        out_of_range(
            "solver.expert.stagnation_acceptance",
            v,
            "must be ≥ 1 (a multiple of residual_tolerance)",
        )
    }
}

fn impl_ex_tolerance(v: f64) -> Result<f64, SolverSpecError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        out_of_range("solver.impl_ex_tolerance", v, "must be > 0")
    }
}

/// `impl_ex_reject` as given (≥ 1), else its default: on with the
/// interface IMPL-EX, off otherwise.
fn impl_ex_reject(
    written: Option<f64>,
    interface: InterfaceIntegration,
) -> Result<Option<f64>, SolverSpecError> {
    match written {
        Some(v) if v.is_nan() || v < 1.0 => out_of_range(
            "solver.expert.impl_ex_reject",
            v,
            "must be ≥ 1 (a multiple of impl_ex_tolerance)",
        ),
        Some(v) => Ok(Some(v)),
        None => Ok((interface == InterfaceIntegration::ImplEx).then_some(DEFAULT_IMPL_EX_REJECT)),
    }
}

/// The preconditioner, the multigrid only with GMRES.
fn preconditioner(
    p: PreconditionerKind,
    linear: LinearSolverKind,
) -> Result<PreconditionerKind, SolverSpecError> {
    if p == PreconditionerKind::Multigrid && linear != LinearSolverKind::Gmres {
        return Err(SolverSpecError::Combination {
            key: "solver.expert.preconditioner".into(),
            problem: "multigrid preconditions GMRES only: set expert.linear_solver: gmres (the default) or leave preconditioner out",
        });
    }
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::super::MULTIGRID_MIN_DOFS;
    use super::*;

    fn solver(yaml: &str) -> Result<SolverSettings, SolverSpecError> {
        serde_yaml::from_str::<RawSolver>(yaml).unwrap().resolve()
    }

    fn loading(yaml: &str, solver: &str) -> Result<Loading, SolverSpecError> {
        let solver: RawSolver = serde_yaml::from_str(solver).unwrap();
        serde_yaml::from_str::<RawLoading>(yaml)
            .unwrap()
            .resolve(&solver)
    }

    /// IMPL-EX rejection: on by default only with the interface IMPL-EX
    /// (concrete-only IMPL-EX runs keep every converged step), settable,
    /// and a bound below the tolerance itself is refused.
    #[test]
    fn impl_ex_reject_defaults_with_the_interface_integration() {
        assert_eq!(solver("{}").unwrap().impl_ex_reject, None);
        let concrete = solver("concrete_integration: impl_ex").unwrap();
        assert_eq!(concrete.impl_ex_reject, None);
        let interface = solver("interface_integration: impl_ex").unwrap();
        assert_eq!(interface.impl_ex_reject, Some(DEFAULT_IMPL_EX_REJECT));
        let profile = solver("profile: impl_ex_interface").unwrap();
        assert_eq!(profile.impl_ex_reject, Some(DEFAULT_IMPL_EX_REJECT));
        let set = solver("concrete_integration: impl_ex\nexpert: {impl_ex_reject: 4}").unwrap();
        assert_eq!(set.impl_ex_reject, Some(4.0));
        for bad in ["0.5", ".nan"] {
            let e = solver(&format!("expert: {{impl_ex_reject: {bad}}}"))
                .unwrap_err()
                .to_string();
            assert!(e.contains("solver.expert.impl_ex_reject"), "{e}");
        }
        let e = serde_yaml::from_str::<RawSolver>("interface_integration: explicit")
            .unwrap_err()
            .to_string();
        assert!(e.contains("impl_ex"), "{e}");
    }

    /// Every key that does not resolve is named by its dotted place, the
    /// expert keys with `expert` in it.
    #[test]
    fn unknown_key_and_bad_values_are_named() {
        let e = serde_yaml::from_str::<RawLoading>("u_finall: 1 mm").unwrap_err();
        assert!(e.to_string().contains("u_finall"), "{e}");
        let e = loading("u_final: 1 MPa", "{}").unwrap_err().to_string();
        assert!(e.contains("loading.u_final"), "{e}");
        let e = loading("{}", "expert: {cutback: 1.5}").unwrap_err();
        assert!(e.to_string().contains("solver.expert.cutback"), "{e}");
        let e = solver("residual_tolerance: 0").unwrap_err().to_string();
        assert!(e.contains("solver.residual_tolerance"), "{e}");
        for bad in ["0.5", ".nan"] {
            let e = solver(&format!("expert: {{stagnation_acceptance: {bad}}}"))
                .unwrap_err()
                .to_string();
            assert!(e.contains("solver.expert.stagnation_acceptance"), "{e}");
        }
        let s =
            solver("expert: {stagnation_acceptance: 1, preconditioner_precision: double}").unwrap();
        assert_eq!(
            (s.stagnation_acceptance, s.preconditioner_precision),
            (1.0, Precision::Double)
        );
        let s = solver("expert: {tangent: secant, ordering: amd}").unwrap();
        assert_eq!(
            (s.tangent, s.ordering),
            (TangentKind::Secant, Ordering::Amd)
        );
    }

    /// With nothing written the loading is the documented default.
    #[test]
    fn defaults_are_documented_values() {
        let l = loading("{}", "{}").unwrap();
        assert_eq!(l, Loading::default());
        assert_eq!(l.u_final, 1e-3);
        assert_eq!(solver("{}").unwrap(), SolverSettings::default());
    }

    /// `preconditioner: auto` takes the multigrid on large GMRES systems
    /// only, and the multigrid without GMRES is refused.
    #[test]
    fn auto_preconditioner_takes_the_multigrid_on_large_gmres_systems_only() {
        let auto = solver("{}").unwrap();
        assert_eq!(
            auto.preconditioner_for(MULTIGRID_MIN_DOFS - 1),
            PreconditionerKind::Cholesky
        );
        assert_eq!(
            auto.preconditioner_for(MULTIGRID_MIN_DOFS),
            PreconditionerKind::Multigrid
        );
        let pcg = solver("expert: {linear_solver: pcg}").unwrap();
        assert_eq!(
            pcg.preconditioner_for(10 * MULTIGRID_MIN_DOFS),
            PreconditionerKind::Cholesky
        );
        let chosen = solver("expert: {preconditioner: cholesky}").unwrap();
        assert_eq!(
            chosen.preconditioner_for(10 * MULTIGRID_MIN_DOFS),
            PreconditionerKind::Cholesky
        );
        let e = solver("expert: {preconditioner: multigrid, linear_solver: cholesky}")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("solver.expert.preconditioner") && e.contains("gmres"),
            "{e}"
        );
        // The default stays out of the serialised settings (cache keys).
        let yaml = serde_yaml::to_string(&auto).unwrap();
        assert!(!yaml.contains("preconditioner:"), "{yaml}");
    }

    /// A profile resolves to exactly the settings its scenes wrote out key
    /// by key, so their cache keys and curves stay; a key written beside
    /// it wins.
    #[test]
    fn profiles_are_the_settings_the_shipped_scenes_wrote() {
        let r1 = solver(
            "concrete_integration: impl_ex\nexpert: {energy_tolerance: 0.5, forcing: tolerance}",
        )
        .unwrap();
        assert_eq!(solver("profile: impl_ex").unwrap(), r1);
        let r2 = solver(
            "concrete_integration: impl_ex\ninterface_integration: impl_ex\n\
             expert: {energy_tolerance: 0.5, forcing: tolerance, krylov_max_iterations: 120}",
        )
        .unwrap();
        assert_eq!(solver("profile: impl_ex_interface").unwrap(), r2);
        let overridden = solver("profile: impl_ex\nconcrete_integration: implicit").unwrap();
        assert_eq!(
            overridden.concrete_integration,
            ConcreteIntegration::Implicit
        );
        assert_eq!(overridden.energy_tolerance, 0.5);
        let e = serde_yaml::from_str::<RawSolver>("profile: fast")
            .unwrap_err()
            .to_string();
        assert!(e.contains("impl_ex"), "{e}");
    }

    /// A key of the earlier layout is refused with its new place, or with
    /// the word that it was removed.
    #[test]
    fn keys_of_the_earlier_layout_name_their_new_place() {
        let tree = |y: &str| serde_yaml::from_str::<serde_yaml::Value>(y).unwrap();
        let e = moved_key(&tree("loading: {growth: 2}"))
            .unwrap_err()
            .to_string();
        assert_eq!(e, "loading.growth: moved to solver.expert.growth");
        let e = moved_key(&tree("solver: {forcing: tolerance}"))
            .unwrap_err()
            .to_string();
        assert_eq!(e, "solver.forcing: moved to solver.expert.forcing");
        let e = moved_key(&tree("solver: {pcg_tolerance: 1e-6}"))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("solver.pcg_tolerance: removed"), "{e}");
        assert!(moved_key(&tree("solver: {expert: {forcing: tolerance}}")).is_ok());
        // Every moved key's new place is a key that reads.
        for (old, new) in MOVED {
            let Some(new) = new else { continue };
            let key = new.rsplit('.').next().unwrap();
            let field = format!("{key}: ~");
            assert!(
                serde_yaml::from_str::<RawExpert>(&field).is_ok(),
                "{old} → {new}"
            );
        }
    }
}
