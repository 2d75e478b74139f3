//! The last step of an indirectly controlled run: onto `fed_stop` under
//! FED control, or onto `u_final` under displacement control.

use super::super::state::{PathView, Rules};
use super::plan::Plan;
use super::{displacement, free_end};

/// The last step of an indirectly controlled run: where a step repeating
/// `scale` times the last increment would pass `fed_stop`, a step to it
/// under FED control; where it would pass `u_final`, a step to it under
/// displacement control.
pub fn landing(view: &PathView, scale: f64, rules: &Rules) -> Option<Plan> {
    let loading = rules.loading;
    let df = view.fed_increment;
    if let Some(stop) = loading.fed_stop {
        let fed = view.fed;
        if fed + scale * df >= stop {
            return Some(free_end::by_fed(view, stop - fed, loading));
        }
    }
    let u_final = loading.u_final;
    (view.lambda + scale * view.lambda_increment >= u_final)
        .then(|| displacement::by_lambda(view, u_final - view.lambda, loading))
}

#[cfg(test)]
mod tests {
    use super::super::super::test_support::*;
    use super::*;
    use crate::nonlinear::control::ControlMode;
    use crate::spec::solver::{Loading, SolverSettings};

    /// An indirect step that would pass `fed_stop` lands on it under FED
    /// control; one that would pass `u_final`, on it under displacement
    /// control; otherwise it needs no landing.
    #[test]
    fn indirect_steps_land_on_the_end_of_the_loading() {
        let rows = [row(1, 1e-5, 100.0), row(2, 2e-5, 120.0)];
        let v = view(&rows, [1e-5, 100.0], [2e-5, 120.0]);
        let settings = SolverSettings::default();
        let loading = Loading {
            u_final: 3e-5,
            fed_stop: Some(1.2e-5),
            ..loading()
        };
        let rules = Rules {
            loading: &loading,
            settings: &settings,
        };
        // FED now 1e-5, grows 5e-6 a unit of scale: passes 1.2e-5 at 0.4.
        let plan = landing(&v, 1.0, &rules).unwrap();
        assert_eq!(plan.mode, ControlMode::FreeEnd);
        assert!((plan.target - 1.2e-5).abs() < 1e-18);
        let loading = Loading {
            fed_stop: None,
            ..loading
        };
        let rules = Rules {
            loading: &loading,
            settings: &settings,
        };
        let plan = landing(&v, 1.0, &rules).unwrap();
        assert_eq!(plan.mode, ControlMode::Displacement);
        assert!((plan.target - 3e-5).abs() < 1e-18);
        assert!(landing(&v, 0.5, &rules).is_none());
    }
}
