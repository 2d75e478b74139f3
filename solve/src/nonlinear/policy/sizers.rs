//! The sizers: the size of the next step after a committed one. Three
//! pieces, each bounding the step by what it measures, and the next
//! displacement step is the smallest of them:
//!
//! - [`effort`]: Newton's effort: grown by `expert.growth` after an easy
//!   step (up to `loading.max_step`), kept after a hard one;
//! - [`impl_ex_error`]: shrunk where the IMPL-EX error passed its
//!   tolerance (`solver.impl_ex_tolerance`);
//! - [`curve_limit`]: the curve's bend (`loading.curve_tolerance`), kept
//!   apart in `Steps::curve_limit` so that a step shortened for the curve
//!   does not slow the steps after the bend.
//!
//! Dissipation control's switches after a commit (`controls::dissipation`)
//! run between the effort and the curve, as they read the effort's size.

use super::controls::{dissipation, max_step, Plan};
use super::state::{PathView, Rules, Steps};
use crate::nonlinear::control::ControlMode;

/// What a committed step tells the sizers.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Committed {
    /// Newton iterations of the converged attempt.
    pub iterations: usize,
    /// It ended on its best iterate of a stagnating iteration.
    pub force_only: bool,
    /// The interface's damage is integrated explicitly
    /// (`interface_integration: impl_ex`).
    pub explicit_interface: bool,
    /// The curve's bend and the step it asks for (`checks::curve_bend`).
    pub curve: Option<(f64, f64)>,
    /// The step's IMPL-EX error, where points are integrated explicitly.
    pub impl_ex_error: Option<f64>,
}

/// Sizes the step after `step`, planned as `plan`; `view` is the path with
/// the step committed. Returns whether the step was easy (at most
/// `easy_iterations`), after which a stall no longer goes back before it.
pub fn after_commit(
    steps: &mut Steps,
    plan: &Plan,
    step: &Committed,
    view: &PathView,
    rules: &Rules,
) -> bool {
    let easy = effort(steps, plan, step, view, rules);
    dissipation::switch_after(steps, plan, view, rules);
    curve_limit(steps, plan, step.curve, rules);
    if let Some(e) = step.impl_ex_error {
        impl_ex_error(steps, plan, e, rules);
    }
    easy
}

/// Newton's effort: after an easy step the next grows by `growth` (up to
/// the mode's largest step, never below the size already planned), after
/// a hard one it keeps the step's size. A step the curve's bend shortened
/// says nothing of the size Newton could take, nor does the last step of
/// an indirect run taken under displacement control: those keep the size
/// as it was. Under the IMPL-EX interface a step that ended on its best
/// iterate grows as after an easy one: there the chatter of friction
/// points, not the step, sets the residual, so keeping the size would
/// crawl. Returns whether the step was easy.
pub fn effort(
    steps: &mut Steps,
    plan: &Plan,
    step: &Committed,
    view: &PathView,
    rules: &Rules,
) -> bool {
    let loading = rules.loading;
    let for_curve = plan.mode == ControlMode::Displacement && steps.curve_limit < steps.next;
    if plan.mode != steps.mode || for_curve {
        false
    } else if step.iterations <= loading.easy_iterations {
        steps.next = (plan.size * loading.growth)
            .min(max_step(plan.mode, view, rules))
            .max(steps.next);
        true
    } else if step.force_only && step.explicit_interface {
        steps.next = (plan.size * loading.growth).min(max_step(plan.mode, view, rules));
        false
    } else {
        steps.next = plan.size;
        false
    }
}

/// The curve's bend limits the next displacement step (never below
/// `initial_step`) when the step was planned in the mode the steps are in.
pub fn curve_limit(steps: &mut Steps, plan: &Plan, curve: Option<(f64, f64)>, rules: &Rules) {
    steps.curve_limit = f64::INFINITY;
    if let Some((_, next)) = curve {
        if plan.mode == steps.mode {
            steps.curve_limit = next.max(rules.loading.initial_step);
        }
    }
}

/// A step whose IMPL-EX error `e` passed the tolerance shrinks the next by
/// 0.9 √(tol/e), at least by `cutback`, not below `min_step`. A linear
/// extrapolation's error grows like h² on a smooth history; near an
/// adhesion peak it grows closer to h, and the steps then shrink over
/// several steps instead of one.
pub fn impl_ex_error(steps: &mut Steps, plan: &Plan, e: f64, rules: &Rules) {
    let (loading, tolerance) = (rules.loading, rules.settings.impl_ex_tolerance);
    if e > tolerance {
        let shrink = (tolerance / e).sqrt() * 0.9;
        steps.next = (plan.size * shrink.max(loading.cutback))
            .max(loading.min_step)
            .min(steps.next);
    }
}

#[cfg(test)]
mod tests {
    use super::super::test_support::*;
    use super::*;
    use crate::spec::solver::SolverSettings;

    fn displacement(size: f64) -> Plan {
        Plan {
            mode: ControlMode::Displacement,
            size,
            target: 0.0,
            scale: 0.0,
        }
    }

    fn rules<'a>(
        loading: &'a crate::spec::solver::Loading,
        settings: &'a SolverSettings,
    ) -> Rules<'a> {
        Rules { loading, settings }
    }

    /// After an easy step the next grows by `growth` up to `max_step`;
    /// after a hard one it keeps the step's size; a step shortened for the
    /// curve leaves it alone.
    #[test]
    fn effort_grows_after_easy_steps_and_keeps_after_hard_ones() {
        let (loading, settings) = (loading(), SolverSettings::default());
        let r = rules(&loading, &settings);
        let v = view(&[], [0.0, 0.0], [1e-5, 1.0]);
        let mut steps = Steps {
            next: 4e-6,
            ..Steps::start(&loading)
        };
        let easy = Committed {
            iterations: 3,
            ..Committed::default()
        };
        assert!(effort(&mut steps, &displacement(4e-6), &easy, &v, &r));
        assert!((steps.next - 6e-6).abs() < 1e-18);
        let mut big = Steps {
            next: 1.8e-5,
            ..steps
        };
        effort(&mut big, &displacement(1.8e-5), &easy, &v, &r);
        assert_eq!(big.next, loading.max_step);
        let hard = Committed {
            iterations: 9,
            ..Committed::default()
        };
        let mut steps = Steps {
            next: 8e-6,
            ..steps
        };
        assert!(!effort(&mut steps, &displacement(4e-6), &hard, &v, &r));
        assert_eq!(steps.next, 4e-6);
        let mut curved = Steps {
            next: 8e-6,
            curve_limit: 2e-6,
            ..steps
        };
        assert!(!effort(&mut curved, &displacement(2e-6), &easy, &v, &r));
        assert_eq!(curved.next, 8e-6);
    }

    /// Under the IMPL-EX interface a step that ended on its best iterate
    /// grows as an easy one; under the implicit interface it keeps its
    /// size.
    #[test]
    fn a_best_iterate_step_grows_under_the_impl_ex_interface() {
        let (loading, settings) = (loading(), SolverSettings::default());
        let r = rules(&loading, &settings);
        let v = view(&[], [0.0, 0.0], [1e-5, 1.0]);
        let chattering = Committed {
            iterations: 25,
            force_only: true,
            explicit_interface: true,
            ..Committed::default()
        };
        let mut steps = Steps {
            next: 4e-6,
            ..Steps::start(&loading)
        };
        effort(&mut steps, &displacement(4e-6), &chattering, &v, &r);
        assert!((steps.next - 6e-6).abs() < 1e-18);
        let implicit = Committed {
            explicit_interface: false,
            ..chattering
        };
        effort(&mut steps, &displacement(4e-6), &implicit, &v, &r);
        assert_eq!(steps.next, 4e-6);
    }

    /// The curve's bend limits the next step when its mode stays, never
    /// below `initial_step`; without a bend the limit is lifted.
    #[test]
    fn the_curve_limit_follows_the_bend() {
        let (loading, settings) = (loading(), SolverSettings::default());
        let r = rules(&loading, &settings);
        let mut steps = Steps::start(&loading);
        curve_limit(&mut steps, &displacement(1e-5), Some((1e-3, 1e-7)), &r);
        assert_eq!(steps.curve_limit, loading.initial_step);
        curve_limit(&mut steps, &displacement(1e-5), Some((1e-3, 8e-6)), &r);
        assert_eq!(steps.curve_limit, 8e-6);
        curve_limit(&mut steps, &displacement(1e-5), None, &r);
        assert!(steps.curve_limit.is_infinite());
    }

    /// An IMPL-EX error above the tolerance shrinks the next step by
    /// 0.9 √(tol/e), at most by `cutback`, never below `min_step`; below the
    /// tolerance nothing changes.
    #[test]
    fn the_impl_ex_error_shrinks_the_next_step() {
        let (loading, settings) = (loading(), SolverSettings::default());
        let r = rules(&loading, &settings);
        let tol = settings.impl_ex_tolerance;
        let mut steps = Steps {
            next: 1e-5,
            ..Steps::start(&loading)
        };
        impl_ex_error(&mut steps, &displacement(1e-5), 1.21 * tol, &r);
        assert!((steps.next - 1e-5 * 0.9 / 1.1).abs() < 1e-18);
        let mut steps = Steps {
            next: 1e-5,
            ..steps
        };
        impl_ex_error(&mut steps, &displacement(1e-5), 100.0 * tol, &r);
        assert!((steps.next - 1e-5 * loading.cutback).abs() < 1e-18);
        let mut steps = Steps {
            next: 1e-5,
            ..steps
        };
        impl_ex_error(&mut steps, &displacement(1e-5), 0.5 * tol, &r);
        assert_eq!(steps.next, 1e-5);
    }
}
