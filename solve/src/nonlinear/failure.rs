//! Why a step's attempt was not committed: Newton did not converge
//! ([`NotConverged`]), or a check refused the converged state ([`Refusal`]).

use crate::assembly::{AssemblyError, States};
use crate::linalg::LinearError;

/// How many integration points changed regime between the committed state
/// and the last iterate of a failed attempt: the hint of a likely cause.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct RegimeChanges {
    /// Interface node pairs whose damage grew.
    pub interface_damage: usize,
    /// Interface node pairs whose frictional slip changed.
    pub slip: usize,
    /// Concrete tets whose damage grew.
    pub concrete_damage: usize,
    /// Steel tets whose plastic strain changed.
    pub steel_yield: usize,
}

impl RegimeChanges {
    /// Counts the changes from `committed` to `trial`.
    pub fn between(committed: &States, trial: &States) -> Self {
        fn count<T>(a: &[T], b: &[T], changed: impl Fn(&T, &T) -> bool) -> usize {
            a.iter().zip(b).filter(|(c, t)| changed(c, t)).count()
        }
        let grew = |a: f64, b: f64| b > a + 1e-12;
        Self {
            interface_damage: count(&committed.interface, &trial.interface, |c, t| {
                grew(c.damage, t.damage)
            }),
            slip: count(&committed.interface, &trial.interface, |c, t| {
                c.slip != t.slip
            }),
            concrete_damage: count(&committed.bulk, &trial.bulk, |c, t| {
                grew(c.damage, t.damage)
            }),
            steel_yield: count(&committed.bulk, &trial.bulk, |c, t| {
                c.plastic_strain != t.plastic_strain
            }),
        }
    }
}

impl std::fmt::Display for RegimeChanges {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "in the last iterate, interface damage grew at {} node pairs and frictional slip changed at {}; \
             concrete damage grew in {} tets; steel yielded in {} tets (softening or sticking/sliding switches)",
            self.interface_damage, self.slip, self.concrete_damage, self.steel_yield
        )
    }
}

/// Why a Newton attempt did not reach an equilibrium: the step is cut back
/// or retried.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum NotConverged {
    /// A law or element could not evaluate an iterate.
    #[error("constitutive failure{}: {source}", if *.in_line_search { " in line search" } else { "" })]
    Constitutive {
        in_line_search: bool,
        source: AssemblyError,
    },
    #[error("non-finite residual")]
    NonFiniteResidual,
    #[error("non-finite correction")]
    NonFiniteCorrection,
    /// The residual stopped decreasing (points switching between law
    /// branches) with the best iterate above the acceptance.
    #[error("stagnating at relative residual {relative_residual:e}. {regimes}")]
    Stagnating {
        relative_residual: f64,
        regimes: RegimeChanges,
    },
    /// The residual grew beyond 1e8 times its start.
    #[error("diverging: residual {residual:e} N. {regimes}")]
    Diverging {
        /// ‖r‖, N.
        residual: f64,
        regimes: RegimeChanges,
    },
    #[error("linear solve: {source}. {regimes}")]
    LinearSolve {
        source: LinearError,
        regimes: RegimeChanges,
    },
    /// The interface points held for a retried step did not come to
    /// rest: held at the history their laws reach at the converged jumps,
    /// the displacement is still out of balance after every pass.
    #[error("{points} held interface points did not settle in {passes} passes (relative residual under their laws {relative_residual:e}). {regimes}")]
    Unsettled {
        points: usize,
        passes: usize,
        relative_residual: f64,
        regimes: RegimeChanges,
    },
    #[error("no convergence in {iterations} iterations (last relative residual {relative_residual:e}). {regimes}")]
    IterationLimit {
        iterations: usize,
        relative_residual: f64,
        regimes: RegimeChanges,
    },
}

/// Why a converged attempt was not kept: a check of the stepping policy
/// refused its state (`docs/architecture.md`, "The stepping policy").
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Refusal {
    /// A process-zone step converged with λ moved further than
    /// `loading.max_step`: the zone's jumps hardly respond to λ there, so
    /// the start state's own imbalance (IMPL-EX's error of the last step)
    /// sends λ far; or a dissipation-controlled step carried λ forward by
    /// more than that, or past `u_final` (along the secant through the
    /// origin a step releases nearly nothing). The step is taken under
    /// displacement control.
    #[error("the step under indirect control moved the imposed displacement by {increment:e} m, more than {limit:e} m (loading.max_step, or what is left to u_final): the step is taken under displacement control")]
    LoadJump { increment: f64, limit: f64 },
    /// The step converged, but its IMPL-EX extrapolation error (the
    /// relative residual of its displacement under the implicit damage) is
    /// above `impl_ex_reject` × `impl_ex_tolerance`: redone shorter.
    #[error(
        "IMPL-EX extrapolation error {indicator:e} above {limit:e}: the step is redone shorter"
    )]
    ExtrapolationError { indicator: f64, limit: f64 },
    /// A converged displacement-controlled step left its previous curve
    /// point further off the chord of its neighbours than the curve
    /// tolerance allows (`loading.curve_tolerance`).
    #[error(
        "the curve bends: its last point lies {deviation:e} off the chord (scaled axes), above {limit:e}; the step is redone shorter"
    )]
    CurveResolution {
        deviation: f64,
        limit: f64,
        /// λ increment of the redone step, m.
        next_step: f64,
    },
    /// A converged step that gave back from the dissipated energy more
    /// than `solver.expert.dissipation_tolerance` of its own external work (and
    /// more than a floor of W_ext): the laws cannot reach its state from
    /// the last one (each of them only dissipates, but for the FCZM's
    /// non-potential exchange, a small part of a step's work), so Newton
    /// found another solution of the equilibrium equations than the
    /// path's, typically a force jump after explicit retries or holds.
    #[error("the converged state gives back {} ({of_total_work:e} of W_ext), more than solver.expert.dissipation_tolerance {limit}: it is not on the path of the laws. {regimes}", ShareOfStepWork { share: *.of_step_work, what: "from the dissipated energy", none: "dissipated energy" })]
    CreatesEnergy {
        /// −ΔW_diss / |ΔW_ext| of the step.
        of_step_work: f64,
        /// −ΔW_diss / W_ext.
        of_total_work: f64,
        limit: f64,
        regimes: RegimeChanges,
    },
    /// A converged step (a retry whose tets' damage passes did not settle)
    /// in which the forces left out of balance did more work than
    /// `solver.expert.dissipation_tolerance` of the step's external work (and a
    /// floor of W_ext): W_ext and W_int part by that much.
    #[error("the converged state is out of balance: the residual forces did {} ({of_total_work:e} of W_ext), more than solver.expert.dissipation_tolerance {limit}. {regimes}", ShareOfStepWork { share: *.of_step_work, what: "", none: "work" })]
    OutOfBalance {
        /// |Δ(W_ext − W_int)| / |ΔW_ext| of the step.
        of_step_work: f64,
        /// |Δ(W_ext − W_int)| / W_ext.
        of_total_work: f64,
        limit: f64,
        regimes: RegimeChanges,
    },
    /// A converged step that would take the run's energy record outside
    /// the energy check of solve.json (`crate::energy::check`): W_ext and
    /// W_int part, or the dissipated energy falls, by more than its
    /// tolerance of W_ext, each step within `solver.expert.dissipation_tolerance`
    /// but their sum not.
    #[error("the converged state would fail the run's energy check: W_ext and W_int part by {imbalance:e} of W_ext, the dissipated energy changes by {dissipation_increment:e} of it in the step, the check allows {limit}. {regimes}")]
    FailsEnergyCheck {
        /// |W_ext − W_int| / W_ext after the step.
        imbalance: f64,
        /// ΔW_diss / W_ext of the step.
        dissipation_increment: f64,
        limit: f64,
        regimes: RegimeChanges,
    },
}

/// Why a step's attempt was not committed: it did not converge, or it
/// converged and a check refused it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum StepFailure {
    #[error(transparent)]
    NotConverged(#[from] NotConverged),
    #[error(transparent)]
    Refused(#[from] Refusal),
}

impl NotConverged {
    /// The regime changes of the last iterate, where the failure records
    /// them.
    pub fn regimes(&self) -> Option<&RegimeChanges> {
        match self {
            NotConverged::Stagnating { regimes, .. }
            | NotConverged::Diverging { regimes, .. }
            | NotConverged::LinearSolve { regimes, .. }
            | NotConverged::Unsettled { regimes, .. }
            | NotConverged::IterationLimit { regimes, .. } => Some(regimes),
            _ => None,
        }
    }

    /// [`NotConverged::regimes`], to be recounted.
    pub(crate) fn regimes_mut(&mut self) -> Option<&mut RegimeChanges> {
        match self {
            NotConverged::Stagnating { regimes, .. }
            | NotConverged::Diverging { regimes, .. }
            | NotConverged::LinearSolve { regimes, .. }
            | NotConverged::Unsettled { regimes, .. }
            | NotConverged::IterationLimit { regimes, .. } => Some(regimes),
            _ => None,
        }
    }
}

impl Refusal {
    /// The regime changes from the committed state to the refused one,
    /// where the check records them.
    pub fn regimes(&self) -> Option<&RegimeChanges> {
        match self {
            Refusal::CreatesEnergy { regimes, .. }
            | Refusal::OutOfBalance { regimes, .. }
            | Refusal::FailsEnergyCheck { regimes, .. } => Some(regimes),
            _ => None,
        }
    }
}

/// A share of a step's external work as the energy rules report it; a
/// step back along a snap-back receives none, and its share is infinite.
struct ShareOfStepWork {
    share: f64,
    /// What the share is taken from, after "of its step's external work".
    what: &'static str,
    /// What is named where the step received no work.
    none: &'static str,
}

impl std::fmt::Display for ShareOfStepWork {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.share.is_finite() {
            write!(f, "{:.3} of its step's external work", self.share)?;
            if !self.what.is_empty() {
                write!(f, " {}", self.what)?;
            }
            Ok(())
        } else {
            write!(f, "{} in a step that received no external work", self.none)
        }
    }
}

impl StepFailure {
    /// The regime changes the failure records, if it does.
    pub fn regimes(&self) -> Option<&RegimeChanges> {
        match self {
            StepFailure::NotConverged(n) => n.regimes(),
            StepFailure::Refused(r) => r.regimes(),
        }
    }
}

/// The user guide's page on the messages of a run that stops.
pub const WHEN_A_RUN_STOPS: &str = "docs/src/howto/when-a-run-stops.md";

impl NotConverged {
    /// The scene keys whose change most likely takes a step past this
    /// failure, the first the likeliest.
    pub fn keys_to_change(&self) -> &'static [&'static str] {
        match self {
            NotConverged::Constitutive {
                in_line_search: true,
                ..
            } => &["solver.expert.line_search"],
            // An iterate no law can evaluate, or a non-finite one: a
            // shorter step is the only remedy.
            NotConverged::Constitutive { .. }
            | NotConverged::NonFiniteResidual
            | NotConverged::NonFiniteCorrection => &["loading.min_step"],
            NotConverged::Stagnating { .. } => &[
                "solver.expert.stagnation_acceptance",
                "solver.expert.interface_holds",
            ],
            NotConverged::Diverging { .. } => {
                &["solver.expert.tangent", "solver.expert.line_search"]
            }
            NotConverged::LinearSolve { .. } => &[
                "solver.expert.linear_solver",
                "solver.expert.preconditioner",
            ],
            NotConverged::Unsettled { .. } => &["solver.expert.interface_holds"],
            NotConverged::IterationLimit { .. } => &["solver.expert.max_iterations"],
        }
    }
}

impl Refusal {
    /// The scene keys that set the check which refused the step.
    pub fn keys_to_change(&self) -> &'static [&'static str] {
        match self {
            Refusal::LoadJump { .. } => &["loading.max_step"],
            Refusal::ExtrapolationError { .. } => {
                &["solver.impl_ex_tolerance", "solver.expert.impl_ex_reject"]
            }
            Refusal::CurveResolution { .. } => &["loading.curve_tolerance"],
            Refusal::CreatesEnergy { .. }
            | Refusal::OutOfBalance { .. }
            | Refusal::FailsEnergyCheck { .. } => &["solver.expert.dissipation_tolerance"],
        }
    }
}

impl StepFailure {
    /// [`NotConverged::keys_to_change`] or [`Refusal::keys_to_change`].
    pub fn keys_to_change(&self) -> &'static [&'static str] {
        match self {
            StepFailure::NotConverged(n) => n.keys_to_change(),
            StepFailure::Refused(r) => r.keys_to_change(),
        }
    }

    /// What a user may change after a stall with this failure at the
    /// minimum step: a smaller `loading.min_step`, then the keys of the
    /// cause, and where the user guide explains them.
    pub fn stall_advice(&self) -> String {
        let mut keys = vec!["loading.min_step"];
        keys.extend(
            self.keys_to_change()
                .iter()
                .filter(|k| **k != "loading.min_step"),
        );
        format!(
            "to get past it, change {} ({WHEN_A_RUN_STOPS})",
            keys.join(", then ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The energy rules' reasons read as sentences whether or not the step
    /// received work: a step back along a snap-back receives none, and its
    /// share of it is not a number to print.
    #[test]
    fn energy_reasons_name_a_step_without_work() {
        let creates = |of_step_work| Refusal::CreatesEnergy {
            of_step_work,
            of_total_work: 0.5,
            limit: 0.15,
            regimes: RegimeChanges::default(),
        };
        let unbalanced = |of_step_work| Refusal::OutOfBalance {
            of_step_work,
            of_total_work: 0.01,
            limit: 0.15,
            regimes: RegimeChanges::default(),
        };
        let text = creates(0.25).to_string();
        assert!(
            text.contains(
                "gives back 0.250 of its step's external work from the dissipated energy"
            ),
            "{text}"
        );
        let text = creates(f64::INFINITY).to_string();
        assert!(
            text.contains("gives back dissipated energy in a step that received no external work")
                && !text.contains("inf"),
            "{text}"
        );
        let text = unbalanced(20.784).to_string();
        assert!(
            text.contains("the residual forces did 20.784 of its step's external work ("),
            "{text}"
        );
        let text = unbalanced(f64::INFINITY).to_string();
        assert!(
            text.contains("the residual forces did work in a step that received no external work")
                && !text.contains("inf"),
            "{text}"
        );
    }
}
