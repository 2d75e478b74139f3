//! A step's plan (what it prescribes, how far) and the bounds of a step
//! of each control.

use super::super::state::{PathView, Rules};
use crate::nonlinear::control::ControlMode;

/// One step's plan: what it prescribes, how far, and the predictor's
/// scale of the last increment.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plan {
    pub mode: ControlMode,
    /// The step's size in the mode's unit (m, or J under dissipation
    /// control).
    pub size: f64,
    /// λ (displacement control), the FED or the zone's quantity (m), or
    /// the energy to release (J) at the end of the step.
    pub target: f64,
    /// The predictor's multiple of the last increment (0: none).
    pub scale: f64,
}

/// The process zone as the plan reads it: its quantity's value now (m)
/// and how far the last step moved it (m).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Zone {
    pub value: f64,
    pub moved: f64,
}

/// The smallest step of `mode`: under dissipation control the work of the
/// load over `loading.min_step`.
pub fn min_step(mode: ControlMode, view: &PathView, rules: &Rules) -> f64 {
    match mode {
        ControlMode::Energy => view.load_work(rules.loading.min_step),
        _ => rules.loading.min_step,
    }
}

/// The largest step of `mode`: under dissipation control the work of the
/// load over `loading.max_step` (as the floor is over `min_step`), not the
/// length itself read as joules.
pub fn max_step(mode: ControlMode, view: &PathView, rules: &Rules) -> f64 {
    match mode {
        ControlMode::Energy => view.load_work(rules.loading.max_step),
        _ => rules.loading.max_step,
    }
}

/// Whether `plan` is a step of the smallest size of its kind, which
/// cannot be shortened.
pub fn at_min_step(plan: &Plan, view: &PathView, rules: &Rules) -> bool {
    plan.size <= min_step(plan.mode, view, rules) * (1.0 + 1e-12)
}

#[cfg(test)]
mod tests {
    use super::super::super::test_support::*;
    use super::*;
    use crate::spec::solver::SolverSettings;

    /// Under dissipation control the step bounds are the load's work over
    /// `min_step` and `max_step`; elsewhere those lengths themselves, and a
    /// plan at the smallest size is recognised as such.
    #[test]
    fn step_bounds_are_energies_under_dissipation_control() {
        let rows = [row(1, 1e-5, 200.0)];
        let v = view(&rows, [0.0, 0.0], [1e-5, 200.0]);
        let settings = SolverSettings::default();
        let loading = loading();
        let rules = Rules {
            loading: &loading,
            settings: &settings,
        };
        assert_eq!(min_step(ControlMode::Energy, &v, &rules), 100.0 * 1e-9);
        assert_eq!(max_step(ControlMode::Energy, &v, &rules), 100.0 * 2e-5);
        assert_eq!(max_step(ControlMode::FreeEnd, &v, &rules), 2e-5);
        let at = |mode, size| {
            at_min_step(
                &Plan {
                    mode,
                    size,
                    target: 0.0,
                    scale: 0.0,
                },
                &v,
                &rules,
            )
        };
        assert!(at(ControlMode::Displacement, 1e-9));
        assert!(!at(ControlMode::Displacement, 2e-9));
        assert!(at(ControlMode::Energy, 1e-7));
        assert!(!at(ControlMode::Energy, 1e-9 * 1000.0));
    }
}
