//! Displacement control: each step prescribes the imposed displacement λ
//! of the bar's loaded end.

use super::super::state::PathView;
use super::plan::Plan;
use crate::nonlinear::control::ControlMode;
use crate::spec::solver::Loading;

/// A step prescribing λ `h` further, at most to `u_final`; its predictor
/// repeats the last increment scaled to it.
pub fn by_lambda(view: &PathView, h: f64, loading: &Loading) -> Plan {
    let dl = view.lambda_increment;
    let size = h.min(loading.u_final - view.lambda);
    Plan {
        mode: ControlMode::Displacement,
        size,
        target: view.lambda + size,
        scale: if dl > 0.0 { size / dl } else { 0.0 },
    }
}

/// The size of a displacement-controlled step that takes over from an
/// indirect control: the last step's |Δλ| within the loading's bounds.
pub fn lambda_step(view: &PathView, loading: &Loading) -> f64 {
    view.lambda_increment
        .abs()
        .clamp(loading.min_step, loading.max_step)
}

#[cfg(test)]
mod tests {
    use super::super::super::test_support::*;
    use super::*;

    /// A displacement step stops at `u_final`, and its predictor scales
    /// the last increment to its size (none before a first increment).
    #[test]
    fn a_displacement_step_ends_at_u_final_and_scales_the_last_increment() {
        let loading = loading();
        let rows = [row(1, 4e-6, 10.0)];
        let v = view(&rows, [0.0, 0.0], [4e-6, 10.0]);
        let plan = by_lambda(&v, 8e-6, &loading);
        assert_eq!((plan.size, plan.scale), (8e-6, 2.0));
        assert_eq!(plan.target, 4e-6 + 8e-6);
        let v = view(&rows, [0.0, 0.0], [0.995e-3, 10.0]);
        let plan = by_lambda(&v, 2e-5, &loading);
        assert!((plan.target - 1e-3).abs() < 1e-18);
        let first = view(&[], [0.0, 0.0], [0.0, 0.0]);
        assert_eq!(by_lambda(&first, 5e-6, &loading).scale, 0.0);
    }

    /// Taking over from an indirect control, λ steps as far as the last
    /// step moved it, within `min_step` and `max_step`, whichever way it
    /// moved.
    #[test]
    fn the_step_after_an_indirect_one_is_its_lambda_increment_bounded() {
        let loading = loading();
        let v = view(&[], [3e-5, 0.0], [2e-5, 0.0]);
        assert!((lambda_step(&v, &loading) - 1e-5).abs() < 1e-18);
        let v = view(&[], [0.0, 0.0], [1.0, 0.0]);
        assert_eq!(lambda_step(&v, &loading), loading.max_step);
        let v = view(&[], [0.0, 0.0], [0.0, 0.0]);
        assert_eq!(lambda_step(&v, &loading), loading.min_step);
    }
}
