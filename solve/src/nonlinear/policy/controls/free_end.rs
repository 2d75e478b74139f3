//! Free-end control (`solver.path_following: fed`): after the first
//! converged step each step prescribes the free-end displacement, and λ is
//! an unknown (indirect displacement control).

use super::super::state::{PathView, Rules, Steps};
use super::displacement;
use super::plan::Plan;
use crate::nonlinear::control::ControlMode;
use crate::spec::solver::{Loading, PathFollowing};

/// FED control takes over after the first converged step, when both λ and
/// the FED grew in it; their ratio converts the step's size.
pub fn take_over(steps: &mut Steps, view: &PathView, rules: &Rules) {
    let (dl, df) = (view.lambda_increment, view.fed_increment);
    if steps.mode == ControlMode::Displacement
        && rules.settings.path_following == PathFollowing::Fed
        && dl > 0.0
        && df > 0.0
    {
        steps.mode = ControlMode::FreeEnd;
        steps.next *= df / dl;
    }
}

/// A FED-controlled step of the planned size, handed to displacement
/// control where the extrapolated λ would pass `u_final`.
pub fn plan(steps: &Steps, view: &PathView, rules: &Rules) -> Plan {
    let plan = by_fed(view, steps.next, rules.loading);
    if view.lambda + plan.scale * view.lambda_increment >= rules.loading.u_final {
        return displacement::by_lambda(view, rules.loading.u_final - view.lambda, rules.loading);
    }
    plan
}

/// A step prescribing the FED `size` further (at most to `fed_stop`, at
/// least `min_step`).
pub fn by_fed(view: &PathView, size: f64, loading: &Loading) -> Plan {
    let fed = view.fed;
    let mut size = size;
    if let Some(stop) = loading.fed_stop {
        size = size.min(stop - fed).max(loading.min_step);
    }
    let df = view.fed_increment;
    Plan {
        mode: ControlMode::FreeEnd,
        size,
        target: fed + size,
        scale: if df > 0.0 { size / df } else { 0.0 },
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::test_support::*;
    use super::*;
    use crate::spec::solver::SolverSettings;

    /// Under `fed`, the first step with λ and the FED both growing hands
    /// over to FED control with the step converted by their ratio; under
    /// the other settings, or with the FED not growing, nothing changes.
    #[test]
    fn fed_control_takes_over_once_both_grew() {
        let loading = loading();
        let settings = SolverSettings {
            path_following: PathFollowing::Fed,
            ..SolverSettings::default()
        };
        let rules = Rules {
            loading: &loading,
            settings: &settings,
        };
        let rows = [row(1, 4e-6, 10.0)];
        let v = view(&rows, [0.0, 0.0], [4e-6, 10.0]);
        let mut steps = Steps::start(&loading);
        take_over(&mut steps, &v, &rules);
        assert_eq!(steps.mode, ControlMode::FreeEnd);
        assert!((steps.next - 0.5 * loading.initial_step).abs() < 1e-18);
        let standing = PathView {
            fed_increment: 0.0,
            ..v
        };
        let mut steps = Steps::start(&loading);
        take_over(&mut steps, &standing, &rules);
        assert_eq!(steps.mode, ControlMode::Displacement);
        let auto = SolverSettings::default();
        let rules = Rules {
            loading: &loading,
            settings: &auto,
        };
        take_over(&mut steps, &v, &rules);
        assert_eq!(steps.mode, ControlMode::Displacement);
    }

    /// A FED step lands on `fed_stop` (never below `min_step`), and is
    /// handed to displacement control where λ would pass `u_final`.
    #[test]
    fn fed_steps_stop_at_fed_stop_and_hand_back_near_u_final() {
        let loading = Loading {
            fed_stop: Some(1.01e-5),
            ..loading()
        };
        let rows = [row(1, 2e-5, 10.0)];
        let v = view(&rows, [1e-5, 0.0], [2e-5, 10.0]);
        let fed = by_fed(&v, 4e-6, &loading);
        assert_eq!(fed.mode, ControlMode::FreeEnd);
        assert!((fed.size - 1e-7).abs() < 1e-15, "{}", fed.size);
        let settings = SolverSettings::default();
        let near_end = Loading {
            u_final: 2.5e-5,
            fed_stop: None,
            ..loading
        };
        let rules = Rules {
            loading: &near_end,
            settings: &settings,
        };
        let steps = Steps {
            mode: ControlMode::FreeEnd,
            next: 5e-6,
            ..Steps::start(&near_end)
        };
        let landed = plan(&steps, &v, &rules);
        assert_eq!(landed.mode, ControlMode::Displacement);
        assert!((landed.target - 2.5e-5).abs() < 1e-18);
    }
}
