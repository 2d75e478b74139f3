//! Dissipation control (`solver.path_following: energy`, and `auto` past a
//! stall): each step prescribes the energy it releases,
//! G = ½(F₀λ − Fλ₀) (Gutiérrez, IJNME 59, 2004), and λ is an unknown, so
//! the path is followed through snap-backs in λ. Its steps are energies:
//! bounded by the load's work over `loading.min_step` and `max_step`.

use super::super::state::{PathView, Rules, Steps};
use super::landing::landing;
use super::plan::{at_min_step, min_step, Plan};
use crate::nonlinear::control::ControlMode;
use crate::spec::solver::PathFollowing;

/// A step dissipates when the energy it releases exceeds this fraction of
/// the external work it takes; under `energy` dissipation control starts
/// there.
pub const DISSIPATIVE: f64 = 0.1;
/// Dissipation control hands back to displacement control when a step
/// releases less than this fraction of its external work.
pub const ELASTIC: f64 = 0.05;
/// After a failed displacement-controlled step, dissipation control takes
/// over if the last converged step released at least this fraction of its
/// work.
pub const STARTS_DISSIPATING: f64 = 1e-3;

/// A dissipation-controlled step of the planned energy, its predictor the
/// last increment scaled by the ratio of the energies.
pub fn plan(steps: &Steps, view: &PathView, rules: &Rules) -> Plan {
    let (released, _) = view.last_energies();
    let size = steps.next;
    let scale = if released > 0.0 { size / released } else { 0.0 };
    landing(view, scale, rules).unwrap_or(Plan {
        mode: ControlMode::Energy,
        size,
        target: size,
        scale,
    })
}

/// The energy step (J) that follows a failed displacement-controlled
/// attempt, if dissipation control takes over there: displacement control
/// found no equilibrium just after a step that dissipated, a snap-back,
/// which dissipation control follows, its step releasing what the last one
/// did. After an elastic step the energy constraint would not respond to
/// λ: that step is cut back first, nearer to where dissipation starts.
/// `auto` hands over only where displacement control would stop (at the
/// minimum step), so that every run it carries to the end keeps its curve;
/// `energy` at the first failure.
pub fn hand_over(steps: &Steps, plan: &Plan, view: &PathView, rules: &Rules) -> Option<f64> {
    let allowed = match rules.settings.path_following {
        PathFollowing::Energy => true,
        PathFollowing::Auto => at_min_step(plan, view, rules),
        _ => false,
    };
    let (released, work) = view.last_energies();
    (allowed
        && plan.mode == ControlMode::Displacement
        && steps.mode == ControlMode::Displacement
        && released > STARTS_DISSIPATING * work.abs()
        && !view.unloaded())
    .then(|| released.max(min_step(ControlMode::Energy, view, rules)))
}

/// After a committed step, under dissipation control's policy (`energy`,
/// or `auto` once it handed over): a dissipative displacement-controlled
/// step hands over to dissipation control (its released energy sizes the
/// next step), an elastic dissipation-controlled step hands back (its Δλ
/// sizes the next step). `view` is the path with the step committed.
pub fn switch_after(steps: &mut Steps, plan: &Plan, view: &PathView, rules: &Rules) {
    let following = rules.settings.path_following;
    if !(following == PathFollowing::Energy
        || (following == PathFollowing::Auto && steps.mode == ControlMode::Energy))
    {
        return;
    }
    let (released, work) = view.last_energies();
    // The size the next step would have (the curve may bound it) over
    // this one's.
    let ratio = steps.next.min(steps.curve_limit) / plan.size;
    match plan.mode {
        ControlMode::Displacement
            if steps.mode == ControlMode::Displacement
                && released > DISSIPATIVE * work.abs()
                && !view.unloaded() =>
        {
            steps.mode = ControlMode::Energy;
            steps.next = released * ratio;
        }
        ControlMode::Energy
            if view.lambda_increment > 0.0 && (released < ELASTIC * work || view.unloaded()) =>
        {
            steps.mode = ControlMode::Displacement;
            let loading = rules.loading;
            steps.next = (view.lambda_increment * ratio).clamp(loading.min_step, loading.max_step);
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::test_support::*;
    use super::*;
    use crate::spec::solver::SolverSettings;

    fn plan_of(mode: ControlMode, size: f64) -> Plan {
        Plan {
            mode,
            size,
            target: 0.0,
            scale: 0.0,
        }
    }

    /// An energy step repeats the last step's increment scaled by the
    /// ratio of the energy to release to the energy the last step released.
    #[test]
    fn an_energy_step_scales_the_last_increment_by_the_energies() {
        let loading = loading();
        let settings = SolverSettings::default();
        let rules = Rules {
            loading: &loading,
            settings: &settings,
        };
        let rows = [row(1, 1e-5, 100.0), row(2, 2e-5, 50.0)];
        let v = view(&rows, [1e-5, 100.0], [2e-5, 50.0]);
        let released = v.last_energies().0;
        let steps = Steps {
            mode: ControlMode::Energy,
            next: 0.5 * released,
            ..Steps::start(&loading)
        };
        let p = plan(&steps, &v, &rules);
        assert_eq!(p.mode, ControlMode::Energy);
        assert!((p.scale - 0.5).abs() < 1e-12 && p.target == p.size);
    }

    /// Under `auto` a failed displacement step after a dissipating one hands
    /// over only at the minimum step, releasing what the last step did;
    /// under `energy` at once; never after an elastic step, when unloaded,
    /// or under `off`.
    #[test]
    fn dissipation_control_takes_over_a_stalled_dissipating_step() {
        let loading = loading();
        let rows = [row(1, 1e-5, 100.0), row(2, 2e-5, 50.0)];
        let dissipating = view(&rows, [1e-5, 100.0], [2e-5, 50.0]);
        let released = dissipating.last_energies().0;
        let steps = Steps::start(&loading);
        let tried = |following, size, v: &PathView| {
            let settings = SolverSettings {
                path_following: following,
                ..SolverSettings::default()
            };
            let rules = Rules {
                loading: &loading,
                settings: &settings,
            };
            hand_over(&steps, &plan_of(ControlMode::Displacement, size), v, &rules)
        };
        assert_eq!(
            tried(PathFollowing::Auto, 1e-9, &dissipating),
            Some(released)
        );
        assert_eq!(tried(PathFollowing::Auto, 1e-6, &dissipating), None);
        assert_eq!(
            tried(PathFollowing::Energy, 1e-6, &dissipating),
            Some(released)
        );
        assert_eq!(tried(PathFollowing::Off, 1e-9, &dissipating), None);
        let elastic = view(&rows, [1e-5, 25.0], [2e-5, 50.0]);
        assert_eq!(tried(PathFollowing::Auto, 1e-9, &elastic), None);
        let lost = [row(1, 1e-5, 100.0), row(2, 2e-5, 0.05)];
        let unloaded = view(&lost, [1e-5, 100.0], [2e-5, 0.05]);
        assert_eq!(tried(PathFollowing::Energy, 1e-6, &unloaded), None);
    }

    /// Under `energy`, a committed displacement step that released more
    /// than a tenth of its work hands over, the next energy step its
    /// release; a committed energy step that released less than 5 % hands
    /// back with its Δλ; under `auto` only the hand-back applies.
    #[test]
    fn dissipation_control_switches_by_the_share_released() {
        let loading = loading();
        let energy = SolverSettings {
            path_following: PathFollowing::Energy,
            ..SolverSettings::default()
        };
        let rules = Rules {
            loading: &loading,
            settings: &energy,
        };
        let rows = [row(1, 1e-5, 100.0), row(2, 2e-5, 50.0)];
        let v = view(&rows, [1e-5, 100.0], [2e-5, 50.0]);
        let mut steps = Steps {
            next: 1e-5,
            ..Steps::start(&loading)
        };
        switch_after(
            &mut steps,
            &plan_of(ControlMode::Displacement, 1e-5),
            &v,
            &rules,
        );
        assert_eq!(steps.mode, ControlMode::Energy);
        assert!((steps.next - v.last_energies().0).abs() < 1e-15);
        let rising = view(&rows, [1e-5, 49.0], [2e-5, 100.0]);
        let mut steps = Steps {
            mode: ControlMode::Energy,
            next: 1e-4,
            ..Steps::start(&loading)
        };
        switch_after(
            &mut steps,
            &plan_of(ControlMode::Energy, 1e-4),
            &rising,
            &rules,
        );
        assert_eq!(steps.mode, ControlMode::Displacement);
        assert!((steps.next - 1e-5).abs() < 1e-18);
        let auto = SolverSettings::default();
        let rules = Rules {
            loading: &loading,
            settings: &auto,
        };
        let mut steps = Steps::start(&loading);
        switch_after(
            &mut steps,
            &plan_of(ControlMode::Displacement, 1e-5),
            &v,
            &rules,
        );
        assert_eq!(steps.mode, ControlMode::Displacement);
    }
}
