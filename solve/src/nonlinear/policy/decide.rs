//! What follows an attempt that was not committed (a failure of Newton or
//! a check's refusal): one [`Action`], chosen by [`decide`] from the
//! policy state, the failure and the path, in this order:
//!
//! 1. a load jump is taken under displacement control at the last |Δλ|;
//! 2. a curve refusal redoes the step at the size the bend asks for;
//! 3. dissipation control takes over a failed displacement step after a
//!    dissipating one (`controls::dissipation::hand_over`);
//! 4. above the minimum step, the step is cut back by `expert.cutback`;
//! 5. at the minimum step: the limit load; else the rewind point, from
//!    where interface points may be held; else a brittle failure; else a
//!    restart from step 1 with the points held; else the run stalls.

use super::controls::{at_min_step, displacement, dissipation, min_step, Plan};
use super::state::{PathView, PolicyState, Rules};
use crate::nonlinear::control::ControlMode;
use crate::nonlinear::failure::{Refusal, StepFailure};
use crate::nonlinear::summary::Ending;
use crate::spec::solver::InterfaceHolds;

/// What the driver does after an attempt that was not committed.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Take the step under displacement control at `size` (m), the process
    /// zone's control paused for it.
    Displacement { size: f64 },
    /// Redo the step with the curve's limit at `size` (m).
    ForCurve { size: f64 },
    /// Hand over to dissipation control, the next step releasing `energy`
    /// (J).
    HandOver { energy: f64 },
    /// Cut back: the next step of the same control is `size`, at least the
    /// mode's minimum (a mode the control changed keeps its size).
    CutBack { size: f64 },
    /// The run ends here.
    End(Ending),
    /// Go back to the rewind point, from where interface points may be
    /// held.
    Rewind,
    /// Start again from step 1 with interface points held from there.
    RestartWithHolds,
    /// No rule continues the run: it stops with its converged steps.
    Stall,
}

impl Action {
    /// The control and size of the next attempt as a cut-back report
    /// states them (a stall reports the halved size it did not take).
    pub fn next_attempt(&self, plan: &Plan, cutback: f64) -> (ControlMode, f64) {
        match *self {
            Action::Displacement { size } => (ControlMode::Displacement, size),
            Action::ForCurve { size } => (plan.mode, size),
            Action::HandOver { energy } => (ControlMode::Energy, energy),
            _ => (plan.mode, plan.size * cutback),
        }
    }
}

/// The endings a stall at the minimum step may reach, evaluated only when
/// the rule asks (they count damaged tets).
pub trait StallEndings {
    fn limit_load(&self) -> Option<Ending>;
    fn brittle_failure(&self) -> Option<Ending>;
}

/// Whether a failure counts among the run's cut-backs (a curve refusal
/// redoes a converged step and does not).
pub fn counts_as_cutback(failure: &StepFailure) -> bool {
    !matches!(
        failure,
        StepFailure::Refused(Refusal::CurveResolution { .. })
    )
}

/// Whether the converged path before this failure becomes the rewind
/// point: under `on_stall`, before the holds started, at the first failure
/// since the last easy step (a curve refusal is not a failure).
pub fn keeps_rewind_point(policy: &PolicyState, failure: &StepFailure, rules: &Rules) -> bool {
    policy.rewind.is_none()
        && counts_as_cutback(failure)
        && rules.settings.interface_holds == InterfaceHolds::OnStall
        && policy.holds_from_step.is_none()
}

/// What follows the failure of the attempt planned as `plan` (see the
/// module's list).
pub fn decide(
    policy: &PolicyState,
    failure: &StepFailure,
    plan: &Plan,
    view: &PathView,
    rules: &Rules,
    endings: &dyn StallEndings,
) -> Action {
    match failure {
        StepFailure::Refused(Refusal::LoadJump { .. }) => {
            return Action::Displacement {
                size: displacement::lambda_step(view, rules.loading),
            };
        }
        StepFailure::Refused(Refusal::CurveResolution { next_step, .. }) => {
            return Action::ForCurve { size: *next_step };
        }
        _ => {}
    }
    if let Some(energy) = dissipation::hand_over(&policy.steps, plan, view, rules) {
        return Action::HandOver { energy };
    }
    if !at_min_step(plan, view, rules) {
        return Action::CutBack {
            size: (plan.size * rules.loading.cutback).max(min_step(plan.mode, view, rules)),
        };
    }
    if let Some(limit) = endings.limit_load() {
        return Action::End(limit);
    }
    // The held points first: a stalled attempt's iterates can wander to
    // λ < 0 with damage everywhere without a split, so a split is
    // diagnosed only once they were tried.
    if policy.rewind.is_some() {
        return Action::Rewind;
    }
    if let Some(failure) = endings.brittle_failure() {
        return Action::End(failure);
    }
    if policy.may_hold_from_start(rules.settings) {
        // Held from the step before the stall, the points did not settle
        // either: the run starts again with them held from step 1, as
        // under `always`.
        return Action::RestartWithHolds;
    }
    Action::Stall
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;
    use super::super::{RewindPoint, Steps};
    use super::*;
    use crate::nonlinear::failure::{NotConverged, RegimeChanges};
    use crate::nonlinear::summary::Summary;
    use crate::spec::solver::{PathFollowing, SolverSettings};

    struct Endings(Option<Ending>, Option<Ending>);
    impl StallEndings for Endings {
        fn limit_load(&self) -> Option<Ending> {
            self.0.clone()
        }
        fn brittle_failure(&self) -> Option<Ending> {
            self.1.clone()
        }
    }
    const NONE: Endings = Endings(None, None);

    fn stagnating() -> StepFailure {
        NotConverged::Stagnating {
            relative_residual: 1e-2,
            regimes: RegimeChanges::default(),
        }
        .into()
    }

    fn displacement(size: f64) -> Plan {
        Plan {
            mode: ControlMode::Displacement,
            size,
            target: 0.0,
            scale: 0.0,
        }
    }

    fn limit() -> Ending {
        Ending::LimitLoad {
            force: 1.0,
            yield_force: 1.0,
        }
    }

    struct Case {
        loading: crate::spec::solver::Loading,
        settings: SolverSettings,
        policy: PolicyState,
        rows: Vec<crate::curve::CurveRow>,
    }

    impl Case {
        fn new() -> Self {
            let loading = loading();
            Self {
                policy: PolicyState::start(&loading),
                loading,
                settings: SolverSettings::default(),
                // An elastic last step: nothing for dissipation control.
                rows: vec![row(1, 1e-5, 50.0), row(2, 2e-5, 100.0)],
            }
        }
        fn decide(&self, failure: &StepFailure, plan: &Plan, endings: &Endings) -> Action {
            let v = view(&self.rows, [1e-5, 50.0], [2e-5, 100.0]);
            let rules = Rules {
                loading: &self.loading,
                settings: &self.settings,
            };
            decide(&self.policy, failure, plan, &v, &rules, endings)
        }
    }

    /// A load jump is taken under displacement control at the last |Δλ|,
    /// and a curve refusal redoes the step at the size the bend asks.
    #[test]
    fn refusals_of_converged_steps_redo_them() {
        let c = Case::new();
        let jump = Refusal::LoadJump {
            increment: 1e-3,
            limit: 2e-5,
        }
        .into();
        let zone = Plan {
            mode: ControlMode::ProcessZone,
            ..displacement(1e-6)
        };
        assert_eq!(
            c.decide(&jump, &zone, &NONE),
            Action::Displacement { size: 1e-5 }
        );
        let curve = Refusal::CurveResolution {
            deviation: 1.0,
            limit: 0.006,
            next_step: 3e-6,
        }
        .into();
        assert_eq!(
            c.decide(&curve, &displacement(1e-5), &NONE),
            Action::ForCurve { size: 3e-6 }
        );
        assert!(!counts_as_cutback(&curve));
        assert!(counts_as_cutback(&jump));
    }

    /// Above the minimum step a failure cuts back by `cutback`, never below
    /// the minimum.
    #[test]
    fn a_failure_above_the_minimum_cuts_back() {
        let c = Case::new();
        let a = c.decide(&stagnating(), &displacement(1e-5), &NONE);
        assert_eq!(a, Action::CutBack { size: 5e-6 });
        let a = c.decide(&stagnating(), &displacement(1.5e-9), &NONE);
        assert_eq!(a, Action::CutBack { size: 1e-9 });
    }

    /// A failed displacement step after a dissipating one hands over to
    /// dissipation control (under `auto` at the minimum step).
    #[test]
    fn a_stalled_dissipating_step_hands_over() {
        let mut c = Case::new();
        c.rows = vec![row(1, 1e-5, 100.0), row(2, 2e-5, 50.0)];
        let v = view(&c.rows, [1e-5, 100.0], [2e-5, 50.0]);
        let rules = Rules {
            loading: &c.loading,
            settings: &c.settings,
        };
        let a = decide(
            &c.policy,
            &stagnating(),
            &displacement(1e-9),
            &v,
            &rules,
            &NONE,
        );
        assert_eq!(
            a,
            Action::HandOver {
                energy: v.last_energies().0
            }
        );
        let a = decide(
            &c.policy,
            &stagnating(),
            &displacement(1e-5),
            &v,
            &rules,
            &NONE,
        );
        assert!(matches!(a, Action::CutBack { .. }), "{a:?}");
    }

    /// At the minimum step the rules apply in order: the limit load, the
    /// rewind point, a brittle failure, the restart with holds, the stall.
    #[test]
    fn a_stall_at_the_minimum_step_takes_the_first_rule_that_applies() {
        let mut c = Case::new();
        let at_min = displacement(1e-9);
        let brittle = Ending::Unloaded {
            force: 0.0,
            peak_force: 1.0,
            broken_concrete_tets: 0,
        };
        let both = Endings(Some(limit()), Some(brittle.clone()));
        assert_eq!(
            c.decide(&stagnating(), &at_min, &both),
            Action::End(limit())
        );
        c.policy.rewind = Some(Box::new(RewindPoint {
            path: super::super::ConvergedPath::start(0, Default::default()),
            steps: Steps::start(&c.loading),
            summary: Summary::default(),
        }));
        let split = Endings(None, Some(brittle.clone()));
        assert_eq!(c.decide(&stagnating(), &at_min, &split), Action::Rewind);
        c.policy.rewind = None;
        assert_eq!(
            c.decide(&stagnating(), &at_min, &split),
            Action::End(brittle)
        );
        c.policy.holds_from_step = Some(5);
        assert_eq!(
            c.decide(&stagnating(), &at_min, &NONE),
            Action::RestartWithHolds
        );
        c.policy.holds_from_step = Some(1);
        assert_eq!(c.decide(&stagnating(), &at_min, &NONE), Action::Stall);
        c.settings.path_following = PathFollowing::Off;
        c.policy.holds_from_step = None;
        assert_eq!(c.decide(&stagnating(), &at_min, &NONE), Action::Stall);
    }

    /// The rewind point is kept at the first failure under `on_stall`
    /// before any hold, not for a curve refusal, not once one is kept, not
    /// under the other settings.
    #[test]
    fn the_rewind_point_is_the_path_before_the_first_failure() {
        let mut c = Case::new();
        let rules = |c: &Case| -> bool {
            let r = Rules {
                loading: &c.loading,
                settings: &c.settings,
            };
            keeps_rewind_point(&c.policy, &stagnating(), &r)
        };
        assert!(rules(&c));
        c.policy.holds_from_step = Some(3);
        assert!(!rules(&c));
        c.policy.holds_from_step = None;
        c.settings.interface_holds = InterfaceHolds::Always;
        assert!(!rules(&c));
        c.settings.interface_holds = InterfaceHolds::OnStall;
        let curve: StepFailure = Refusal::CurveResolution {
            deviation: 1.0,
            limit: 0.006,
            next_step: 3e-6,
        }
        .into();
        let r = Rules {
            loading: &c.loading,
            settings: &c.settings,
        };
        assert!(!keeps_rewind_point(&c.policy, &curve, &r));
    }
}
