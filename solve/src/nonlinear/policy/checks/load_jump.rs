//! The load-jump check: a converged process-zone step that moved λ by more
//! than `loading.max_step`, or a converged dissipation-controlled step
//! that carried λ forward by more than that or past `u_final`, is taken
//! under displacement control instead. The zone's jumps hardly respond to
//! λ where the zone is small, so the start state's own imbalance sends λ
//! far; and where the path turns forward again after a snap-back, a step's
//! released energy ½(F₀λ − Fλ₀) nearly vanishes along the secant through
//! the origin, so a step of a few millijoules may land anywhere on it.
//! Backward jumps of dissipation control (a split's snap-back) stay.

use super::super::controls::Plan;
use crate::nonlinear::control::ControlMode;
use crate::nonlinear::failure::Refusal;
use crate::spec::solver::Loading;

/// The verdict on a converged step from λ = `before` to `after`.
pub fn check(plan: &Plan, before: f64, after: f64, loading: &Loading) -> Option<Refusal> {
    let increment = after - before;
    let (max_step, u_final) = (loading.max_step, loading.u_final);
    let (jumped, limit) = match plan.mode {
        ControlMode::ProcessZone => (increment.abs() > max_step, max_step),
        ControlMode::Energy => (
            increment > max_step || after > u_final * (1.0 + 1e-12),
            max_step.min(u_final - before),
        ),
        _ => return None,
    };
    jumped.then_some(Refusal::LoadJump { increment, limit })
}

#[cfg(test)]
mod tests {
    use super::super::super::test_support::loading;
    use super::*;

    fn plan(mode: ControlMode) -> Plan {
        Plan {
            mode,
            size: 1.0,
            target: 0.0,
            scale: 0.0,
        }
    }

    /// A process-zone step may move λ at most `max_step` either way; a
    /// dissipation-controlled one forward at most `max_step` and not past
    /// `u_final`, backward as far as it goes; displacement steps are not
    /// checked.
    #[test]
    fn indirect_steps_that_move_lambda_too_far_are_refused() {
        let l = loading();
        let zone = plan(ControlMode::ProcessZone);
        assert!(check(&zone, 1e-4, 1e-4 + 3e-5, &l).is_some());
        assert!(check(&zone, 1e-4, 1e-4 - 3e-5, &l).is_some());
        assert!(check(&zone, 1e-4, 1e-4 + 1e-5, &l).is_none());
        let energy = plan(ControlMode::Energy);
        assert!(check(&energy, 1e-4, 1e-4 + 3e-5, &l).is_some());
        assert!(
            check(&energy, 1e-4, 1e-5, &l).is_none(),
            "back along a snap-back"
        );
        let refusal = check(&energy, 0.995e-3, 1.001e-3, &l).unwrap();
        let Refusal::LoadJump { limit, .. } = refusal else {
            panic!("{refusal:?}")
        };
        assert!((limit - 5e-6).abs() < 1e-15, "what is left to u_final");
        assert!(check(&plan(ControlMode::Displacement), 0.0, 1.0, &l).is_none());
    }
}
